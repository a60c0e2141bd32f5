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

/// Mergeable max-heaps whose entries arrive in *runs*, one per initial
/// heap, each sorted once from its top (what the painting's T(c) are: a
/// colour's touched vertices, all known before the first meld). A heap is a
/// [`PairingHeaps`] of runs keyed by each run's head, not of entries:
/// delete-max pops the top run, advances its head and melds it back (one
/// comparison more), and meld melds the run heaps. The answers are those
/// of one pairing heap of all entries (the top is the highest entry of the
/// heap, ties by name); what changes is where the pointers lie: a run
/// heap has one node per initial heap (per colour, 16 bytes each, a few
/// hundred kilobytes on the noisy volumes) where an entry heap had one per
/// entry, so that a pop chases pointers inside the second-level cache, and
/// the entries themselves are read in order, run by run. (With one node
/// per entry, tooth's painting spent most of its time in pops' sibling
/// walks, each a cache miss.) Comparisons: sorting the runs, Σ k log2 k for
/// runs of k entries, then per delete-max O(log r) amortised for a heap of
/// r runs, plus one per meld; a binomial or pairing heap of entries makes
/// O(k) to build and O(log size) per delete-max.
pub struct RunHeaps<K> {
    /// Every run's entries (key, name), each run sorted from its top.
    entries: Vec<(K, u32)>,
    /// Per run, the index of its head in `entries`, and the run's end.
    head: Vec<u32>,
    end: Vec<u32>,
    /// The heaps of runs: node r is run r, keyed by its head.
    nodes: PairingHeaps<K>,
}

impl<K: Copy + Send + Sync> RunHeaps<K> {
    /// The heaps of `entries` (key, name), in runs `start[r]..start[r + 1]`
    /// (in any order within a run; names distinct but for copies of one
    /// vertex, numbered in the order of their vertices' ids): each run is
    /// sorted from its top, on all cores.
    pub fn new<O: CountingOrder<Key = K> + ?Sized>(
        mut entries: Vec<(K, u32)>,
        start: &[u32],
        order: &O,
    ) -> Self {
        use rayon::prelude::*;
        let runs = start.len().saturating_sub(1);
        let mut slices: Vec<&mut [(K, u32)]> = Vec::with_capacity(runs);
        let mut rest = entries.as_mut_slice();
        for r in 0..runs {
            let (s, tail) = rest.split_at_mut((start[r + 1] - start[r]) as usize);
            slices.push(s);
            rest = tail;
        }
        slices.into_par_iter().for_each(|s| {
            s.sort_unstable_by(|a, b| {
                if a.1 == b.1 {
                    std::cmp::Ordering::Equal
                } else if order.above_keys(a.0, a.1, b.0, b.1) {
                    std::cmp::Ordering::Less
                } else {
                    std::cmp::Ordering::Greater
                }
            })
        });
        let blank = entries.first().map(|e| e.0);
        let mut nodes = match blank {
            Some(b) => PairingHeaps::with_len(runs, b),
            None => PairingHeaps::with_capacity(0),
        };
        for r in 0..runs {
            if start[r] < start[r + 1] {
                let (k, item) = entries[start[r] as usize];
                nodes.set(r as u32, k, item);
            }
        }
        Self {
            entries,
            head: start[..runs].to_vec(),
            end: start[1..].to_vec(),
            nodes,
        }
    }

    /// The heap of run `r` alone (`NONE` when the run is empty).
    pub fn run(&self, r: u32) -> u32 {
        if self.head[r as usize] < self.end[r as usize] {
            r
        } else {
            NONE
        }
    }

    /// The name of a heap's highest entry, or `None` when empty.
    #[inline]
    pub fn top(&self, heap: u32) -> Option<u32> {
        self.nodes.top(heap)
    }

    /// Melds two heaps (one comparison).
    #[inline]
    pub fn meld<O: CountingOrder<Key = K> + ?Sized>(&mut self, a: u32, b: u32, order: &O) -> u32 {
        self.nodes.meld(a, b, order)
    }

    /// Deletes a heap's highest entry and returns the heap.
    pub fn pop<O: CountingOrder<Key = K> + ?Sized>(&mut self, heap: u32, order: &O) -> u32 {
        let r = heap as usize;
        let rest = self.nodes.pop(heap, order);
        self.head[r] += 1;
        if self.head[r] == self.end[r] {
            return rest;
        }
        let (k, item) = self.entries[self.head[r] as usize];
        self.nodes.set(heap, k, item);
        self.nodes.meld(rest, heap, order)
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

    /// The same vertices in runs (one per heap, ids shuffled within a
    /// run), melded into one run heap in `k` steps, popped: the order's
    /// descending order, ties by id. Halfway, the popped vertices are
    /// checked against a plain sort of what the melded heaps hold.
    fn runs_pop_in_order<O: CountingOrder + ?Sized>(order: &O, n: u32, heap_of: &[u32], k: u32) {
        let mut start = vec![0u32; k as usize + 1];
        for &h in heap_of {
            start[h as usize + 1] += 1;
        }
        for h in 0..k as usize {
            start[h + 1] += start[h];
        }
        let mut fill = start.clone();
        let mut entries = vec![(order.key(0), 0u32); n as usize];
        // Reversed within each run, so that the sort has work to do.
        for v in (0..n).rev() {
            let h = heap_of[v as usize] as usize;
            entries[fill[h] as usize] = (order.key(v), v);
            fill[h] += 1;
        }
        let mut heaps = RunHeaps::new(entries, &start, order);
        // Pop the first heap for a while alone: its own descending order.
        let mut first = heaps.run(0);
        let mut own: Vec<u32> = (0..n).filter(|&v| heap_of[v as usize] == 0).collect();
        own.sort_by(|&a, &b| order.ordering(b, a));
        let half = own.len() / 2;
        for &v in &own[..half] {
            assert_eq!(heaps.top(first), Some(v));
            first = heaps.pop(first, order);
        }
        let mut all = first;
        for h in 1..k {
            let r = heaps.run(h);
            all = heaps.meld(all, r, order);
        }
        let mut popped = own[..half].to_vec();
        while let Some(v) = heaps.top(all) {
            popped.push(v);
            all = heaps.pop(all, order);
        }
        let mut rest: Vec<u32> = popped[half..].to_vec();
        let mut expected: Vec<u32> = (0..n).filter(|v| !own[..half].contains(v)).collect();
        expected.sort_by(|&a, &b| order.ordering(b, a));
        rest.truncate(expected.len());
        assert_eq!(rest, expected);
        assert_eq!(popped.len(), n as usize);
    }

    proptest! {
        #[test]
        fn grouped_and_run_heaps_pop_in_order_by_their_keys(
            (values, heap_of, k) in (1usize..300, 1u32..12).prop_flat_map(|(n, k)| (
                proptest::collection::vec(0u8..6, n),
                proptest::collection::vec(0..k, n),
                Just(k),
            ))
        ) {
            // Heaps of entries and heaps of sorted runs, each under the
            // order, its inverse, and the counter (the same answers, and
            // every comparison through above_keys counted).
            let n = values.len() as u32;
            let plain = values.as_slice();
            pops_in_order(plain, n, &heap_of, k);
            runs_pop_in_order(plain, n, &heap_of, k);
            let inverted = Inverted(plain);
            pops_in_order(&inverted, n, &heap_of, k);
            runs_pop_in_order(&inverted, n, &heap_of, k);
            let counted = Counted::new(plain);
            pops_in_order(&counted, n, &heap_of, k);
            runs_pop_in_order(&counted, n, &heap_of, k);
            prop_assert!(counted.comparisons() > 0 || n == 1);
        }
    }
}
