//! Pairing heaps (Fredman, Sedgewick, Sleator, Tarjan) in one arena: the
//! mergeable max-heaps T(c) of §6.1. Raichel and Seshadhri use binomial
//! heaps; a pairing heap has the same interface (meld, find-max,
//! delete-max) with meld in one comparison and delete-max in amortised
//! O(log n) comparisons, which is all the bound of Lemma 33 needs.
//!
//! Entries are indices into the arena; a heap is named by its root entry
//! (`NONE` for the empty heap). Each entry holds its vertex's key (the value
//! the order compares, [`CountingOrder::key`]), the caller's name for it,
//! its first child and its next sibling: 16 bytes per entry for values of
//! up to 4 bytes, kept together so that touching an entry is one cache line
//! (four parallel arrays made every meld four misses: tooth's painting
//! spent a fifth of its time there), and a comparison reads no field value
//! (reading the value of both vertices was two more misses per meld on the
//! large volumes). Ties are broken by the names, so the names must be
//! numbered in the order of their vertices' ids: the painting names a
//! critical vertex by its index in id order.

use super::count::CountingOrder;

/// No entry.
pub const NONE: u32 = u32::MAX;

/// The arena of all heaps.
pub struct PairingHeaps<K> {
    entries: Vec<Entry<K>>,
    scratch: Vec<u32>,
}

/// One heap entry.
#[derive(Clone, Copy)]
#[repr(C, align(16))]
struct Entry<K> {
    key: K,
    item: u32,
    child: u32,
    sibling: u32,
}

impl<K: Copy> PairingHeaps<K> {
    /// An empty arena with room for `capacity` entries.
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            entries: Vec::with_capacity(capacity),
            scratch: Vec::new(),
        }
    }

    /// An arena of `len` entries to be filled by [`Self::set`], each its own
    /// one-entry heap once set (`blank` fills the keys meanwhile).
    pub fn with_len(len: usize, blank: K) -> Self {
        Self {
            entries: vec![
                Entry {
                    key: blank,
                    item: NONE,
                    child: NONE,
                    sibling: NONE,
                };
                len
            ],
            scratch: Vec::new(),
        }
    }

    /// Makes entry `e` (of [`Self::with_len`]) the one-entry heap holding a
    /// vertex of key `key` named `item`: the caller chooses where entries
    /// lie, so that those melded together early lie together in memory.
    pub fn set(&mut self, e: u32, key: K, item: u32) {
        self.entries[e as usize] = Entry {
            key,
            item,
            child: NONE,
            sibling: NONE,
        };
    }

    /// A new one-entry heap holding a vertex of key `key` (compared by the
    /// order, ties by the names) with a name `item` for the caller (what
    /// [`Self::top`] returns).
    pub fn singleton(&mut self, key: K, item: u32) -> u32 {
        let e = self.entries.len() as u32;
        self.entries.push(Entry {
            key,
            item,
            child: NONE,
            sibling: NONE,
        });
        e
    }

    /// The item at a heap's root (its highest vertex), or `None` when empty.
    #[inline]
    pub fn top(&self, root: u32) -> Option<u32> {
        (root != NONE).then(|| self.entries[root as usize].item)
    }

    /// Melds two heaps (one comparison) and returns the root.
    #[inline]
    pub fn meld<O: CountingOrder<Key = K> + ?Sized>(&mut self, a: u32, b: u32, order: &O) -> u32 {
        if a == NONE {
            return b;
        }
        if b == NONE {
            return a;
        }
        let (ea, eb) = (&self.entries[a as usize], &self.entries[b as usize]);
        let (a, b) = if order.above_keys(eb.key, eb.item, ea.key, ea.item) {
            (b, a)
        } else {
            (a, b)
        };
        // b becomes a's first child; a root's own sibling link is unused.
        self.entries[b as usize].sibling = self.entries[a as usize].child;
        self.entries[a as usize].child = b;
        a
    }

    /// Deletes the root and returns the new root: the children are melded in
    /// pairs left to right, then the pairs right to left (two-pass).
    pub fn pop<O: CountingOrder<Key = K> + ?Sized>(&mut self, root: u32, order: &O) -> u32 {
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.clear();
        let mut c = self.entries[root as usize].child;
        self.entries[root as usize].child = NONE;
        while c != NONE {
            let d = self.entries[c as usize].sibling;
            if d == NONE {
                scratch.push(c);
                break;
            }
            let next = self.entries[d as usize].sibling;
            let m = self.meld(c, d, order);
            scratch.push(m);
            c = next;
        }
        let mut acc = NONE;
        while let Some(h) = scratch.pop() {
            acc = self.meld(h, acc, order);
        }
        self.scratch = scratch;
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn melded_heaps_pop_in_descending_order() {
        let values: Vec<u32> = (0..200).map(|i| (i * 7919) % 211).collect();
        let order = values.as_slice();
        let mut heaps = PairingHeaps::with_capacity(200);
        // Ten heaps of twenty, melded together one by one.
        let mut roots = vec![NONE; 10];
        for v in 0..200u32 {
            let e = heaps.singleton(order.key(v), v);
            let r = &mut roots[v as usize % 10];
            *r = heaps.meld(*r, e, order);
        }
        let mut all = NONE;
        for r in roots {
            all = heaps.meld(all, r, order);
        }
        assert_pops_in_order(&mut heaps, all, order, 200);
    }

    /// Pops heap `all` empty: vertices `0..n` in the order's descending
    /// order, ties by id.
    fn assert_pops_in_order<O: CountingOrder + ?Sized>(
        heaps: &mut PairingHeaps<O::Key>,
        mut all: u32,
        order: &O,
        n: u32,
    ) {
        let mut popped = Vec::new();
        while let Some(v) = heaps.top(all) {
            popped.push(v);
            all = heaps.pop(all, order);
        }
        let mut expected: Vec<u32> = (0..n).collect();
        expected.sort_by(|&a, &b| order.ordering(b, a));
        assert_eq!(popped, expected);
    }

    use crate::tree::raichel_seshadhri::count::{Counted, CountingOrder, Inverted};
    use proptest::prelude::*;

    /// Vertices with many ties, spread over `k` heaps laid out by
    /// [`PairingHeaps::with_len`] and [`PairingHeaps::set`] (grouped per
    /// heap, as the painting lays them out), melded, then popped: the
    /// vertices come out in the order's descending order, ties by id, under
    /// the order and under its inverse, with one counted comparison per
    /// meld.
    fn pops_in_order<O: CountingOrder + ?Sized>(order: &O, n: u32, heap_of: &[u32], k: u32) {
        let mut start = vec![0u32; k as usize + 1];
        for &h in heap_of {
            start[h as usize + 1] += 1;
        }
        for h in 0..k as usize {
            start[h + 1] += start[h];
        }
        let mut heaps = PairingHeaps::with_len(n as usize, order.key(0));
        let mut fill = start.clone();
        for v in 0..n {
            let h = heap_of[v as usize] as usize;
            heaps.set(fill[h], order.key(v), v);
            fill[h] += 1;
        }
        let mut all = NONE;
        for h in 0..k as usize {
            let mut r = NONE;
            for e in start[h]..start[h + 1] {
                r = heaps.meld(r, e, order);
            }
            all = heaps.meld(all, r, order);
        }
        assert_pops_in_order(&mut heaps, all, order, n);
    }

    proptest! {
        #[test]
        fn grouped_heaps_pop_in_order_by_their_keys(
            (values, heap_of, k) in (1usize..300, 1u32..12).prop_flat_map(|(n, k)| (
                proptest::collection::vec(0u8..6, n),
                proptest::collection::vec(0..k, n),
                Just(k),
            ))
        ) {
            let n = values.len() as u32;
            let plain = values.as_slice();
            pops_in_order(plain, n, &heap_of, k);
            pops_in_order(&Inverted(plain), n, &heap_of, k);
            // Counted: the same answers, and every comparison through
            // above_keys is counted.
            let counted = Counted::new(plain);
            pops_in_order(&counted, n, &heap_of, k);
            prop_assert!(counted.comparisons() > 0 || n == 1);
        }
    }
}
