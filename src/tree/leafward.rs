//! The sweeps' per-vertex words (each vertex's link code until the sweep
//! visits it, then its leafward candidate or its own candidate number:
//! [`super::sweep::CANDIDATE`]) held in 3 bytes per vertex instead of 4
//! from the link pass to the placement, when there are fewer than 2^23
//! candidates (every scan but the noisiest of a billion vertices).
//!
//! Both sweeps run at once and each holds one word per vertex beside the
//! vertex order, so the two records are the largest thing the engine holds
//! while it sweeps and merges: in 3 bytes each they are 6 bytes per vertex
//! instead of 8 (a smooth float field sweeps in 10 bytes per vertex with
//! its 4-byte order, not 12). The sweeps read and write the entries in
//! place ([`Word`] for `[u8; 3]`: a candidate flag in bit 23 instead of
//! bit 31, the same 32-bit word to the sweep); only the placement unpacks
//! the first record, writing `vertex_arc` over it in its own allocation
//! while the second is given back as it is read ([`combine`]), so no
//! record is ever held twice: three words become four, groups of entries
//! at a time on every core, each wave of groups writing only words that
//! no group of the same wave still has to read.
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
fn entries(words: &[u32], len: usize) -> &[[u8; 3]] {
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
            Leafward::Packed { words, len } => entries(words, *len)[i].get(),
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
            Leafward::Packed { words, len } => unpack_in_place(words, len, None, |j, _| j),
        }
    }
}

/// One word per vertex, `f(join word, split word)`, from the two sweeps'
/// records: written in place over `join` (unpacked from the top down, as
/// [`Leafward::into_words`] does: [`unpack_in_place`]) while `split` is given back from the top
/// down as it is read. Packed, the two hold 6 bytes per vertex at most
/// throughout (3 + 1 for the part unpacked, 3 for the part of `split` not
/// yet read), where unpacking first and reading after held 7.
pub fn combine(join: Leafward, split: Leafward, f: impl Fn(u32, u32) -> u32 + Sync) -> Vec<u32> {
    match (join, split) {
        (Leafward::Packed { words, len }, Leafward::Packed { words: second, .. }) => {
            unpack_in_place(words, len, Some(second), f)
        }
        (Leafward::Words(mut words), Leafward::Words(second)) => {
            words
                .par_chunks_mut(1 << 14)
                .zip(second.par_chunks(1 << 14))
                .for_each(|(j, s)| j.iter_mut().zip(s).for_each(|(j, &s)| *j = f(*j, s)));
            words
        }
        _ => unreachable!("both records are made alike"),
    }
}

/// Group `g` of a packed record, if there is one.
fn group_of(record: &Option<Vec<u32>>, g: usize) -> Option<&[u32]> {
    record.as_ref().map(|r| &r[3 * g..3 * g + 3])
}

/// The packed record `words` of `len` entries unpacked in place, each
/// entry `j` written as `f(j, s)` with `s` the same vertex's entry of the
/// packed record `second` (0 without one). Group g reads words 3g.. and
/// writes 4g..: the last, partial group first, then waves from the top of
/// at most [`WAVE_GROUPS`] groups, each writing above everything it reads;
/// after each wave the groups of `second` it read are given back. The
/// words beyond the packed ones are not written before their wave
/// (zeroing them first would hold the whole fourth word from the start),
/// so the record is seen as possibly uninitialised words until the end.
fn unpack_in_place(
    mut words: Vec<u32>,
    len: usize,
    mut second: Option<Vec<u32>>,
    f: impl Fn(u32, u32) -> u32 + Sync,
) -> Vec<u32> {
    let group = |j: &[u32], s: Option<&[u32]>| -> [u32; 4] {
        let j = unpack4([j[0], j[1], j[2]]);
        let s = s.map_or([0; 4], |s| unpack4([s[0], s[1], s[2]]));
        std::array::from_fn(|k| f(j[k], s[k]))
    };
    let whole = len / 4;
    let last = (whole < len.div_ceil(4))
        .then(|| group(&words[3 * whole..3 * whole + 3], group_of(&second, whole)));
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
        [w[0].assume_init(), w[1].assume_init(), w[2].assume_init()]
    };
    let mut e = whole;
    while e > SERIAL_GROUPS {
        let s = (e * 3)
            .div_ceil(4)
            .max(e.saturating_sub(WAVE_GROUPS))
            .max(SERIAL_GROUPS);
        let (low, high) = all.split_at_mut(4 * s);
        let out = high[..4 * (e - s)].par_chunks_mut(4 << 10);
        let write = |(out, j): (&mut [MaybeUninit<u32>], &[MaybeUninit<u32>]),
                     t: Option<&[u32]>| {
            let groups = out.chunks_exact_mut(4).zip(j.chunks_exact(3)).enumerate();
            for (i, (o, j)) in groups {
                let four = group(&packed(j), t.map(|t| &t[3 * i..3 * i + 3]));
                o.iter_mut().zip(four).for_each(|(o, x)| _ = o.write(x));
            }
        };
        let low = low[3 * s..3 * e].par_chunks(3 << 10);
        match &second {
            Some(second) => out
                .zip(low)
                .zip(second[3 * s..3 * e].par_chunks(3 << 10))
                .for_each(|(oj, t)| write(oj, Some(t))),
            None => out.zip(low).for_each(|oj| write(oj, None)),
        }
        // The second record's groups from s up are read: their pages go.
        if let Some(second) = &mut second {
            second.truncate(3 * s);
            crate::pages::release_spare(second);
        }
        e = s;
    }
    for g in (0..e).rev() {
        let four = group(&packed(&all[3 * g..3 * g + 3]), group_of(&second, g));
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
        /// two words, packed or not.
        #[test]
        fn two_records_combine_vertex_by_vertex(
            n in 0usize..120_000,
            wide in any::<bool>(),
            seed in any::<u64>(),
        ) {
            let candidates = if wide { 1u32 << 23 } else { (1 << 23) - 1 };
            let (a, b) = (record(n, candidates, seed), record(n, candidates, !seed));
            let f = |x: u32, y: u32| x.rotate_left(7) ^ y.wrapping_mul(3);
            let combined = combine(pack(&a, candidates as usize), pack(&b, candidates as usize), f);
            let expect: Vec<u32> = a.iter().zip(&b).map(|(&x, &y)| f(x, y)).collect();
            prop_assert_eq!(combined, expect);
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
