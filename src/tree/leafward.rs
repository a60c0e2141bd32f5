//! The sweeps' per-vertex words (each vertex's link code until the sweep
//! visits it, then its leafward candidate or its own candidate number:
//! [`super::sweep::CANDIDATE`]) held in 3 bytes per vertex instead of 4
//! from the link pass to the finished tree, when there are fewer than
//! 2^23 candidates (every scan but the noisiest of a billion vertices).
//!
//! Both sweeps run at once and each holds one word per vertex beside the
//! vertex order, so the two records are the largest thing the engine holds
//! while it sweeps and merges: in 3 bytes each they are 6 bytes per vertex
//! instead of 8 (a smooth float field sweeps in 10 bytes per vertex with
//! its 4-byte order, not 12). The sweeps read and write the entries in
//! place ([`Word`] for `[u8; 3]`: a candidate flag in bit 23 instead of
//! bit 31, the same 32-bit word to the sweep). The placement writes each
//! vertex's place (its superarc, or its supernode with the flag) over its
//! entry of the first record, in place and in the same 3 bytes, and gives
//! the second back ([`combine`]): a tree has fewer supernodes and
//! superarcs than candidates, so the places pack wherever the records
//! did, and the finished tree keeps them so (`ContourTree::place` reads
//! them): 3 bytes per vertex, not 4.
//!
//! The candidates' own tables (each sweep's union-find, the merge's
//! tables) are packed alike on noisy scans, where they weigh on the peak
//! ([`packs_tables`]).
//!
//! The link pass counts the candidates while it writes the codes, so a
//! record starts packed and is widened in place ([`Leafward::widen`]) if
//! the candidates (or, in blocks, a block's nodes) turn out too many.

use super::sweep::CANDIDATE;
use rayon::prelude::*;
use std::mem::MaybeUninit;

/// The flag of a candidate's own entry in a packed record.
const PACKED_CANDIDATE: u32 = 1 << 23;
/// The low 24 bits.
const ENTRY: u32 = (1 << 24) - 1;
/// Groups of four entries unpacked one after another at the record's
/// start (where the waves would be too small to share out), as a number
/// of groups.
const SERIAL_GROUPS: usize = 1 << 12;

/// The most groups [`combine`] writes in one wave (a MiB of words).
const WAVE_GROUPS: usize = 1 << 16;

/// A sweep's per-vertex word as it is stored: a whole word, or a 3-byte
/// entry (little end first) whose bit 23 stands for [`CANDIDATE`].
pub trait Word: Copy + Send + Sync {
    /// The word.
    fn get(self) -> u32;
    /// Stores `w` (below 2^23 but for the [`CANDIDATE`] flag, if packed).
    fn of(w: u32) -> Self;
}

impl Word for u32 {
    #[inline(always)]
    fn get(self) -> u32 {
        self
    }

    #[inline(always)]
    fn of(w: u32) -> Self {
        w
    }
}

impl Word for [u8; 3] {
    #[inline(always)]
    fn get(self) -> u32 {
        let e = u32::from_le_bytes([self[0], self[1], self[2], 0]);
        (e & !PACKED_CANDIDATE) | (e >> 23) << 31
    }

    #[inline(always)]
    fn of(w: u32) -> Self {
        debug_assert!(w & !CANDIDATE < PACKED_CANDIDATE);
        let e = (w & !CANDIDATE) | (w >> 31) << 23;
        let b = e.to_le_bytes();
        [b[0], b[1], b[2]]
    }
}

/// A sweep's per-vertex record: its words, or the same entries packed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Leafward {
    /// One word per vertex.
    Words(Vec<u32>),
    /// Three words per four vertices (3-byte entries, little end first;
    /// the last group's unused bytes are 0); `len` vertices. The allocation
    /// has room for a word per vertex, untouched, to unpack into.
    Packed {
        /// The entries, in `3 * len.div_ceil(4)` words.
        words: Vec<u32>,
        /// The number of vertices.
        len: usize,
    },
}

/// True when a record of a tree with this many candidates can be packed.
pub fn packs(candidates: usize) -> bool {
    candidates < PACKED_CANDIDATE as usize && cfg!(target_endian = "little")
}

/// True when the candidates' own tables are packed too, in 3 bytes per
/// number: the sweeps' union-finds ([`super::sweep`]) and the merge's
/// tables ([`super::merge`]). Where the records pack and at least one
/// vertex in `share` of the `n` is a candidate ([`PACKED_TABLES_SHARE`],
/// unless a test says otherwise): a noisy
/// scan, whose sweeps' 16 bytes per candidate (14 so) set its peak (tooth
/// 12.1 bytes per vertex, 11.4-11.5 so). Elsewhere the tables are not
/// what the peak is made of, and reading numbers of 3 bytes costs time
/// where they are read the most: with a packed union-find, a scan's or a
/// smooth field's sweeps took 20-30 % longer (aneurism 0.097 -> 0.129 s,
/// `synthetic:256` 0.097 -> 0.115, one sweep), with packed tables the
/// placement 25-40 % (colin27_ch2better 0.14 -> 0.20 s); tooth's sweeps
/// 3-6 %.
pub fn packs_tables(n: usize, candidates: usize, share: usize) -> bool {
    packs(candidates) && candidates.saturating_mul(share) >= n
}

/// See [`packs_tables`].
pub const PACKED_TABLES_SHARE: usize = 8;

/// Runs `$body` with `$w` bound to the record's entries as a mutable slice
/// of its [`Word`]s (`u32` or `[u8; 3]`).
macro_rules! with_words {
    ($record:expr, $w:ident => $body:expr) => {
        match $record {
            $crate::tree::leafward::Leafward::Words(words) => {
                let $w: &mut [u32] = words.as_mut_slice();
                $body
            }
            $crate::tree::leafward::Leafward::Packed { words, len } => {
                let $w: &mut [[u8; 3]] = $crate::tree::leafward::entries_mut(words, *len);
                $body
            }
        }
    };
}
pub(crate) use with_words;

/// [`with_words!`] for a shared record: `$w` bound to its entries as a
/// slice of its [`Word`]s.
macro_rules! with_entries {
    ($record:expr, $w:ident => $body:expr) => {
        match $record {
            $crate::tree::leafward::Leafward::Words(words) => {
                let $w: &[u32] = words.as_slice();
                $body
            }
            $crate::tree::leafward::Leafward::Packed { words, len } => {
                let $w: &[[u8; 3]] = $crate::tree::leafward::entries(words, *len);
                $body
            }
        }
    };
}
pub(crate) use with_entries;

/// [`with_words!`] for two records made alike (both packed or both not):
/// `$a` and `$b` bound to their entries, of one [`Word`] type.
macro_rules! with_both_words {
    ($first:expr, $second:expr, ($a:ident, $b:ident) => $body:expr) => {
        match ($first, $second) {
            (
                $crate::tree::leafward::Leafward::Words(a),
                $crate::tree::leafward::Leafward::Words(b),
            ) => {
                let ($a, $b): (&mut [u32], &mut [u32]) = (a.as_mut_slice(), b.as_mut_slice());
                $body
            }
            (
                $crate::tree::leafward::Leafward::Packed { words: a, len },
                $crate::tree::leafward::Leafward::Packed { words: b, .. },
            ) => {
                let ($a, $b) = (
                    $crate::tree::leafward::entries_mut(a, *len),
                    $crate::tree::leafward::entries_mut(b, *len),
                );
                $body
            }
            _ => unreachable!("both records are made alike"),
        }
    };
}
pub(crate) use with_both_words;

/// The `len` 3-byte entries of a packed record's words.
pub fn entries_mut(words: &mut [u32], len: usize) -> &mut [[u8; 3]] {
    assert!(3 * len <= 4 * words.len());
    // SAFETY: `[u8; 3]` has alignment 1 and no invalid values; the `len`
    // entries lie inside the words' bytes (asserted), which the returned
    // slice borrows mutably.
    unsafe { std::slice::from_raw_parts_mut(words.as_mut_ptr() as *mut [u8; 3], len) }
}

/// [`entries_mut`], shared.
pub fn entries(words: &[u32], len: usize) -> &[[u8; 3]] {
    assert!(3 * len <= 4 * words.len());
    // SAFETY: as in `entries_mut`, borrowed shared.
    unsafe { std::slice::from_raw_parts(words.as_ptr() as *const [u8; 3], len) }
}

impl Leafward {
    /// A record of `n` vertices whose words are all 0, packed where
    /// `packed`; the pages are first touched on every core.
    pub fn zeroed(n: usize, packed: bool) -> Self {
        if packed {
            // Three words per group of four entries, the last group whole.
            let mut words = crate::pages::filled_within(3 * n.div_ceil(4), n, 0u32);
            // The room to unpack into is not held until it is used (a
            // huge page across the end would be, whole).
            crate::pages::release_spare(&mut words);
            Leafward::Packed { words, len: n }
        } else {
            Leafward::Words(crate::pages::filled(n, 0u32))
        }
    }

    /// A record holding the link `codes`, packed where `packed`.
    pub fn of_codes(codes: &[u8], packed: bool) -> Self {
        let mut record = Self::zeroed(codes.len(), packed);
        with_words!(&mut record, w => w
            .par_chunks_mut(1 << 16)
            .zip(codes.par_chunks(1 << 16))
            .for_each(|(w, c)| w.iter_mut().zip(c).for_each(|(w, &c)| *w = Word::of(c as u32))));
        record
    }

    /// The number of vertices.
    pub fn len(&self) -> usize {
        match self {
            Leafward::Words(words) => words.len(),
            Leafward::Packed { len, .. } => *len,
        }
    }

    /// True for a record of no vertex.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Vertex `i`'s word.
    #[inline]
    pub fn get(&self, i: usize) -> u32 {
        match self {
            Leafward::Words(words) => words[i],
            Leafward::Packed { words, len } => {
                debug_assert!(i < *len, "vertex {i} of {len}");
                // One bounds check, on the bytes (the words hold the
                // entries and at most 3 bytes of padding beyond them).
                let bytes: &[u8] = bytemuck::cast_slice(words);
                let entry: [u8; 3] = bytes[3 * i..3 * i + 3].try_into().expect("3 bytes");
                entry.get()
            }
        }
    }

    /// Heap bytes held by the record.
    pub fn heap_bytes(&self) -> usize {
        match self {
            Leafward::Words(words) | Leafward::Packed { words, .. } => 4 * words.capacity(),
        }
    }

    /// True if the record is packed.
    pub fn is_packed(&self) -> bool {
        matches!(self, Leafward::Packed { .. })
    }

    /// The record with a word per vertex, unpacked in place if packed.
    pub fn widen(self) -> Self {
        Leafward::Words(self.into_words())
    }

    /// The record as words, unpacked in place (the allocation grown to a
    /// word per vertex).
    pub fn into_words(self) -> Vec<u32> {
        match self {
            Leafward::Words(words) => words,
            Leafward::Packed { words, len } => unpack_in_place(words, len),
        }
    }
}

/// Each vertex's `f(join word, split word)` from the two sweeps' records,
/// written in place over `join`'s entry, in its packing: packed, `f` must
/// give words that pack (below 2^23 but for the [`CANDIDATE`] flag), as
/// the placement's do, since a tree has fewer supernodes and superarcs
/// than candidates. The two records hold 6 bytes per vertex throughout
/// (packed), and `join` 3 once `split` is given back: the tree's places
/// stay in 3 bytes per vertex.
pub fn combine(
    mut join: Leafward,
    mut split: Leafward,
    f: impl Fn(u32, u32) -> u32 + Sync,
) -> Leafward {
    with_both_words!(&mut join, &mut split, (j, s) => j
        .par_chunks_mut(1 << 14)
        .zip(s.par_chunks(1 << 14))
        .for_each(|(j, s)| j.iter_mut().zip(s).for_each(|(j, s)| *j = Word::of(f(j.get(), s.get())))));
    // Its pages go back even where it was carved from the heap (under the
    // program's 1 MiB `M_MMAP_THRESHOLD`), whose freed pages stay resident.
    let (Leafward::Words(words) | Leafward::Packed { words, .. }) = &mut split;
    words.clear();
    crate::pages::release_spare(words);
    drop(split);
    if let Leafward::Packed { words, .. } = &mut join {
        // The room to unpack into is not needed any more.
        words.shrink_to_fit();
    }
    join
}

/// The packed record `words` of `len` entries unpacked in place. Group g
/// reads words 3g.. and writes 4g..: the last, partial group first, then
/// waves from the top of at most [`WAVE_GROUPS`] groups, each writing above
/// everything it reads. The words beyond the packed ones are not written
/// before their wave (zeroing them first would hold the whole fourth word
/// from the start), so the record is seen as possibly uninitialised words
/// until the end.
fn unpack_in_place(mut words: Vec<u32>, len: usize) -> Vec<u32> {
    let whole = len / 4;
    let last = (whole < len.div_ceil(4)).then(|| unpack4([0, 1, 2].map(|k| words[3 * whole + k])));
    words.reserve_exact(len.saturating_sub(words.len()));
    // SAFETY: the allocation holds `len` words (reserved just above);
    // `MaybeUninit` words may hold anything, and the first `3 *
    // len.div_ceil(4)` (or `len`, if fewer) are initialised.
    let all =
        unsafe { std::slice::from_raw_parts_mut(words.as_mut_ptr() as *mut MaybeUninit<u32>, len) };
    // SAFETY (for each `assume_init` below): a wave reads words below 3e
    // <= 4s of a group g < e, which are packed words no wave has written
    // yet, all initialised.
    let packed = |w: &[MaybeUninit<u32>]| unsafe {
        unpack4([w[0].assume_init(), w[1].assume_init(), w[2].assume_init()])
    };
    let mut e = whole;
    while e > SERIAL_GROUPS {
        let s = (e * 3)
            .div_ceil(4)
            .max(e.saturating_sub(WAVE_GROUPS))
            .max(SERIAL_GROUPS);
        let (low, high) = all.split_at_mut(4 * s);
        high[..4 * (e - s)]
            .par_chunks_mut(4 << 10)
            .zip(low[3 * s..3 * e].par_chunks(3 << 10))
            .for_each(|(out, j)| {
                for (o, j) in out.chunks_exact_mut(4).zip(j.chunks_exact(3)) {
                    o.iter_mut()
                        .zip(packed(j))
                        .for_each(|(o, x)| _ = o.write(x));
                }
            });
        e = s;
    }
    for g in (0..e).rev() {
        let four = packed(&all[3 * g..3 * g + 3]);
        all[4 * g..4 * g + 4]
            .iter_mut()
            .zip(four)
            .for_each(|(o, x)| _ = o.write(x));
    }
    if let Some(last) = last {
        all[4 * whole..]
            .iter_mut()
            .zip(last)
            .for_each(|(o, x)| _ = o.write(x));
    }
    // SAFETY: every one of the `len` words was written: the waves and the
    // serial groups cover groups 0..whole, the last group the rest.
    unsafe { words.set_len(len) };
    words
}

/// Four words (candidate numbers below 2^23, `CANDIDATE` or not) as four
/// 3-byte entries in three words, little end first: what [`Word`] for
/// `[u8; 3]` writes, four at a time.
#[cfg(test)]
fn pack4(w: [u32; 4]) -> [u32; 3] {
    let e = w.map(|w| (w & !CANDIDATE) | (w >> 31) << 23);
    debug_assert!(w.iter().all(|&w| w & !CANDIDATE < PACKED_CANDIDATE));
    [
        e[0] | e[1] << 24,
        e[1] >> 8 | e[2] << 16,
        e[2] >> 16 | e[3] << 8,
    ]
}

/// The inverse of [`pack4`].
#[inline]
fn unpack4(t: [u32; 3]) -> [u32; 4] {
    let e = [
        t[0] & ENTRY,
        (t[0] >> 24 | t[1] << 8) & ENTRY,
        (t[1] >> 16 | t[2] << 16) & ENTRY,
        t[2] >> 8,
    ];
    e.map(|e| (e & !PACKED_CANDIDATE) | (e >> 23) << 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `words` as a record, packed when the `candidates` allow it.
    fn pack(words: &[u32], candidates: usize) -> Leafward {
        let mut record = Leafward::zeroed(words.len(), packs(candidates));
        with_words!(&mut record, w => w.iter_mut().zip(words).for_each(|(w, &x)| *w = Word::of(x)));
        record
    }

    fn record(n: usize, candidates: u32, seed: u64) -> Vec<u32> {
        (0..n as u64)
            .map(|i| {
                let h = (i ^ seed).wrapping_mul(0x9E37_79B9_7F4A_7C15);
                let c = (h >> 33) as u32 % candidates;
                if h & 1 == 0 { c } else { CANDIDATE | c }
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]
        /// Packed entry by entry and unpacked in place, any record reads
        /// back as it was, whole, entry by entry and from any group; it is
        /// packed exactly when its candidates fit in 23 bits.
        #[test]
        fn a_packed_record_reads_back(
            n in 0usize..200_000,
            wide in any::<bool>(),
            seed in any::<u64>(),
            at in 0.0f64..1.0,
        ) {
            let candidates = if wide { 1u32 << 23 } else { (1 << 23) - 1 };
            let words = record(n, candidates, seed);
            let leafward = pack(&words, candidates as usize);
            prop_assert_eq!(leafward.is_packed(), !wide);
            prop_assert_eq!(leafward.len(), n);
            for i in [0, n / 3, n.saturating_sub(1)] {
                if i < n {
                    prop_assert_eq!(leafward.get(i), words[i]);
                }
            }
            let start = ((at * n as f64) as usize) / 4 * 4;
            for len in [0, 1, 3, 4, 5, 4099] {
                let len = len.min(n - start);
                let out: Vec<u32> = (start..start + len).map(|i| leafward.get(i)).collect();
                prop_assert_eq!(&out[..], &words[start..start + len]);
            }
            prop_assert_eq!(leafward.into_words(), words);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(30))]
        /// Combining two records in place gives each vertex `f` of its
        /// two words, in the first record's packing; packed, the room to
        /// unpack into is given back.
        #[test]
        fn two_records_combine_vertex_by_vertex(
            n in 0usize..120_000,
            wide in any::<bool>(),
            seed in any::<u64>(),
        ) {
            let candidates = if wide { 1u32 << 23 } else { (1 << 23) - 1 };
            let (a, b) = (record(n, candidates, seed), record(n, candidates, !seed));
            // A word that packs where the records do, as places are.
            let f = |x: u32, y: u32| (x & CANDIDATE) | ((x ^ y.wrapping_mul(3)) % candidates);
            let combined = combine(pack(&a, candidates as usize), pack(&b, candidates as usize), f);
            prop_assert_eq!(combined.is_packed(), !wide);
            let room = if wide { 4 * n } else { 12 * n.div_ceil(4) };
            prop_assert!(combined.heap_bytes() <= room);
            let expect: Vec<u32> = a.iter().zip(&b).map(|(&x, &y)| f(x, y)).collect();
            prop_assert_eq!(combined.into_words(), expect);
        }
    }

    #[test]
    fn the_extremes_round_trip() {
        let w = [0, CANDIDATE, (1 << 23) - 1, CANDIDATE | ((1 << 23) - 1)];
        assert_eq!(unpack4(pack4(w)), w);
        let n = 1 << 20;
        let words: Vec<u32> = (0..n as u32)
            .map(|i| (i % (1 << 23)) | ((i & 1) << 31))
            .collect();
        let leafward = pack(&words, 1 << 22);
        let Leafward::Packed {
            words: ref packed, ..
        } = leafward
        else {
            panic!("packed")
        };
        assert_eq!(packed.len(), 3 * n / 4);
        assert!(packed.capacity() >= n, "room to unpack in place");
        assert_eq!(leafward.into_words(), words);
    }
}
