//! The sweeps' per-vertex records (each vertex's leafward candidate, or
//! its own candidate number: [`super::sweep::CANDIDATE`]) held in 3 bytes
//! per vertex instead of 4 while the candidates are merged, when there are
//! fewer than 2^23 candidates (every scan but the noisiest of a billion
//! vertices).
//!
//! The merge needs neither record; the placement after it needs both. So
//! between the sweeps and the placement the two records, 8 bytes per
//! vertex, are the largest thing the engine holds, beside the candidates'
//! tables: packed, the merge's peak drops by 2 bytes per vertex (on
//! `engine`, from 12.2 to about 10.3). Packing and unpacking happen in
//! place, in the record's own allocation, so neither ever holds a second
//! copy: four entries (four words) become three words, groups of entries
//! at a time on every core, each wave of groups writing only words that
//! no group of the same wave still has to read.

use super::sweep::CANDIDATE;
use rayon::prelude::*;

/// The flag of a candidate's own entry in a packed record.
const PACKED_CANDIDATE: u32 = 1 << 23;
/// The low 24 bits.
const ENTRY: u32 = (1 << 24) - 1;
/// Groups of four entries done one after another at the record's start
/// (where the waves would be too small to share out), as a number of
/// groups.
const SERIAL_GROUPS: usize = 1 << 12;

/// A sweep's per-vertex record: its words, or the same entries packed.
pub enum Leafward {
    /// One word per vertex.
    Words(Vec<u32>),
    /// Three words per four vertices; `len` vertices.
    Packed { words: Vec<u32>, len: usize },
}

/// True when a record of a tree with this many candidates can be packed
/// (by [`Leafward::pack`], which also keeps tiny records as they are).
pub fn packs(candidates: usize) -> bool {
    candidates < PACKED_CANDIDATE as usize
}

impl Leafward {
    /// The record `words` packed when the `candidates` allow it (and the
    /// record is not tiny), in place; otherwise as it is.
    pub fn pack(mut words: Vec<u32>, candidates: usize) -> Self {
        let len = words.len();
        if !packs(candidates) || len < 4 * SERIAL_GROUPS {
            return Leafward::Words(words);
        }
        // Whole groups in place, then the last, partial one (no growth:
        // growing could copy the whole record).
        let (groups, whole) = (len.div_ceil(4), len / 4);
        for g in 0..SERIAL_GROUPS {
            let four: [u32; 4] = std::array::from_fn(|k| words[4 * g + k]);
            words[3 * g..3 * g + 3].copy_from_slice(&pack4(four));
        }
        // Group g reads words 4g.. and writes 3g..: a wave of groups
        // [s, e) with 3e <= 4s writes below everything it reads.
        let mut s = SERIAL_GROUPS;
        while s < whole {
            let e = (s * 4 / 3).min(whole);
            let (low, high) = words.split_at_mut(4 * s);
            low[3 * s..3 * e]
                .par_chunks_mut(3 << 10)
                .zip(high[..4 * (e - s)].par_chunks(4 << 10))
                .for_each(|(out, four)| {
                    for (o, f) in out.chunks_exact_mut(3).zip(four.chunks_exact(4)) {
                        o.copy_from_slice(&pack4([f[0], f[1], f[2], f[3]]));
                    }
                });
            s = e;
        }
        if whole < groups {
            let mut four = [0; 4];
            four[..len - 4 * whole].copy_from_slice(&words[4 * whole..]);
            words[3 * whole..3 * groups].copy_from_slice(&pack4(four));
        }
        words.truncate(3 * groups);
        // The last quarter's pages go back; the capacity stays for
        // unpacking (a reallocation could copy).
        crate::pages::release_spare(&mut words);
        Leafward::Packed { words, len }
    }

    /// The record as words, unpacked in place (the allocation grown to a
    /// word per vertex).
    pub fn into_words(self) -> Vec<u32> {
        let (mut words, len) = match self {
            Leafward::Words(words) => return words,
            Leafward::Packed { words, len } => (words, len),
        };
        // The last, partial group first (its words are about to be
        // overwritten), then the whole ones; the record grows within its
        // capacity (a reallocation could copy it).
        let whole = len / 4;
        let last = (whole < len.div_ceil(4)).then(|| {
            let t = &words[3 * whole..3 * whole + 3];
            unpack4([t[0], t[1], t[2]])
        });
        words.resize(len, 0);
        // Group g reads words 3g.. and writes 4g..: from the top, a wave
        // [s, e) with 4s >= 3e writes above everything it reads.
        let mut e = whole;
        while e > SERIAL_GROUPS {
            let s = (e * 3).div_ceil(4).max(SERIAL_GROUPS);
            let (low, high) = words.split_at_mut(4 * s);
            high[..4 * (e - s)]
                .par_chunks_mut(4 << 10)
                .zip(low[3 * s..3 * e].par_chunks(3 << 10))
                .for_each(|(out, three)| {
                    for (o, t) in out.chunks_exact_mut(4).zip(three.chunks_exact(3)) {
                        o.copy_from_slice(&unpack4([t[0], t[1], t[2]]));
                    }
                });
            e = s;
        }
        for g in (0..e).rev() {
            let three: [u32; 3] = std::array::from_fn(|k| words[3 * g + k]);
            words[4 * g..4 * g + 4].copy_from_slice(&unpack4(three));
        }
        if let Some(last) = last {
            words[4 * whole..].copy_from_slice(&last[..len - 4 * whole]);
        }
        words
    }

    /// The words of vertices `start..start + out.len()` into `out`;
    /// `start` a multiple of 4.
    pub fn read(&self, start: usize, out: &mut [u32]) {
        match self {
            Leafward::Words(words) => out.copy_from_slice(&words[start..start + out.len()]),
            Leafward::Packed { words, .. } => {
                debug_assert_eq!(start % 4, 0);
                let (g, whole) = (start / 4, out.len() / 4);
                let mut four = out.chunks_exact_mut(4);
                for (o, t) in (&mut four).zip(words[3 * g..].chunks_exact(3)) {
                    o.copy_from_slice(&unpack4([t[0], t[1], t[2]]));
                }
                let rest = four.into_remainder();
                if !rest.is_empty() {
                    let t = &words[3 * (g + whole)..][..3];
                    rest.copy_from_slice(&unpack4([t[0], t[1], t[2]])[..rest.len()]);
                }
            }
        }
    }
}

/// Four words (candidate numbers below 2^23, `CANDIDATE` or not) as four
/// 3-byte entries in three words, little end first.
#[inline]
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
        /// Packed and unpacked in place, any record reads back as it was,
        /// whole and from any group; it is packed exactly when its
        /// candidates fit in 23 bits and it is not tiny.
        #[test]
        fn a_packed_record_reads_back(
            n in 0usize..200_000,
            wide in any::<bool>(),
            seed in any::<u64>(),
            at in 0.0f64..1.0,
        ) {
            let candidates = if wide { 1u32 << 23 } else { (1 << 23) - 1 };
            let words = record(n, candidates, seed);
            let leafward = Leafward::pack(words.clone(), candidates as usize);
            let packed = matches!(leafward, Leafward::Packed { .. });
            prop_assert_eq!(packed, !wide && n >= 4 * SERIAL_GROUPS);
            let start = ((at * n as f64) as usize) / 4 * 4;
            for len in [0, 1, 3, 4, 5, 4099] {
                let len = len.min(n - start);
                let mut out = vec![0; len];
                leafward.read(start, &mut out);
                prop_assert_eq!(&out[..], &words[start..start + len]);
            }
            prop_assert_eq!(leafward.into_words(), words);
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
        let leafward = Leafward::pack(words.clone(), 1 << 22);
        let Leafward::Packed {
            words: ref packed, ..
        } = leafward
        else {
            panic!("packed")
        };
        assert_eq!(packed.len(), 3 * n / 4);
        assert_eq!(leafward.into_words(), words);
    }
}
