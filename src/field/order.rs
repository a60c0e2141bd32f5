//! The vertex order: all vertices sorted by (value, id).
//!
//! Ties broken by id are what simulation of simplicity means on a grid, and
//! every sort here is *stable over ids*, so ties come out in id order without
//! comparing ids: counting sort for 8- and 16-bit values (O(n), one pass to
//! count, one to place, both in parallel chunks), a parallel radix sort on
//! 32-bit keys ((key, id) pairs bucketed by the high 16 bits, then each
//! bucket on its own thread by the low 16 bits, least significant byte
//! first), and a parallel comparison sort only for f64.
//!
//! The tree engine holds the order of 8-bit values packed
//! ([`compact_vertex_order`], [`PackedOrder`]): 2 bytes per vertex instead
//! of 4, read back 64 Ki ids at a time ([`OrderView`]).

use super::Values;
use rayon::prelude::*;

/// The vertices sorted ascending by (value, id).
pub fn vertex_order(values: &Values) -> Vec<u32> {
    match values {
        Values::U8(v) => counting_sort(v.len(), |i| v[i] as usize, 1 << 8),
        Values::I8(v) => counting_sort(v.len(), |i| (v[i] as i16 + 128) as usize, 1 << 8),
        Values::U16(v) => counting_sort(v.len(), |i| v[i] as usize, 1 << 16),
        Values::I16(v) => counting_sort(v.len(), |i| (v[i] as i32 + 32768) as usize, 1 << 16),
        Values::U32(v) => radix_sort_u32_keys(v.len(), |i| v[i]),
        Values::I32(v) => radix_sort_u32_keys(v.len(), |i| (v[i] as u32) ^ 0x8000_0000),
        Values::F32(v) => radix_sort_u32_keys(v.len(), |i| f32_key(v[i])),
        Values::F64(v) => {
            let mut ids: Vec<u32> = (0..v.len() as u32).collect();
            ids.par_sort_unstable_by(|&a, &b| {
                v[a as usize].total_cmp(&v[b as usize]).then(a.cmp(&b))
            });
            // total_cmp orders -0.0 before 0.0; fix ties between them to id order.
            fix_signed_zero_ties(v, &mut ids);
            ids
        }
    }
}

/// The vertex order as the engine holds it while it builds a tree: the
/// ids, or for 8-bit values the same ids packed in 2 bytes each
/// ([`PackedOrder`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Order {
    /// One id per position, 4 bytes each.
    Ids(Vec<u32>),
    /// The ids' low halves and the runs of their high halves.
    Packed(PackedOrder),
}

/// [`vertex_order`] in the form that takes least memory: packed for 8-bit
/// values (2 bytes per vertex and one run per value and 64 Ki ids), the
/// ids otherwise.
pub fn compact_vertex_order(values: &Values) -> Order {
    match values {
        Values::U8(v) => Order::Packed(PackedOrder::sort(v.len(), |i| v[i] as usize)),
        Values::I8(v) => {
            Order::Packed(PackedOrder::sort(v.len(), |i| (v[i] as i16 + 128) as usize))
        }
        _ => Order::Ids(vertex_order(values)),
    }
}

/// Bytes per vertex that [`compact_vertex_order`] takes for these values:
/// 2 where it packs them (the types it matches), else 4.
pub fn order_bytes(values: &Values) -> u64 {
    match values {
        Values::U8(_) | Values::I8(_) => 2,
        _ => 4,
    }
}

impl Order {
    /// A view to read the order through.
    pub fn view(&self) -> OrderView<'_> {
        match self {
            Order::Ids(ids) => OrderView::Ids(ids),
            Order::Packed(p) => OrderView::Packed(p),
        }
    }
}

/// The vertex order of 8-bit values in 2 bytes per vertex. A counting sort
/// by value is stable over ids, so within one value the ids ascend, and
/// their high 16 bits stay the same over long runs: at most one run per
/// value and block of 64 Ki ids (the sort counts each such block on its
/// own, and a run is one block's ids of one value). Each position keeps
/// its id's low 16 bits; the runs say what the high bits are.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PackedOrder {
    /// Per position: the id's low 16 bits.
    low: Vec<u16>,
    /// Ascending: where each run starts (the first is 0).
    run_start: Vec<u32>,
    /// Per run: its ids' high 16 bits.
    run_high: Vec<u16>,
}

impl PackedOrder {
    /// Sorts the ids `0..n` by `key` (below 256), ties by id.
    fn sort<K: Fn(usize) -> usize + Sync>(n: usize, key: K) -> Self {
        const BLOCK: usize = 1 << 16;
        let mut low = crate::pages::filled(n, 0u16);
        let ends = scatter_by_key(0..n, &key, 1 << 8, BLOCK, &mut low, |i| i as u16);
        // The (value, block) runs in position order, by value then block:
        // each starts where the one before it ends; skip the empty ones.
        let (mut run_start, mut run_high) = (Vec::new(), Vec::new());
        let mut start = 0u32;
        for k in 0..1 << 8 {
            for (b, e) in ends.iter().enumerate() {
                if start < e[k] {
                    run_start.push(start);
                    run_high.push(b as u16);
                }
                start = e[k];
            }
        }
        Self {
            low,
            run_start,
            run_high,
        }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.low.len()
    }

    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.low.is_empty()
    }

    /// The ids at the positions `range`, decoded into `buf`.
    pub fn read<'b>(&self, range: std::ops::Range<usize>, buf: &'b mut Vec<u32>) -> &'b [u32] {
        buf.clear();
        let n = self.len();
        let mut pos = range.start;
        let mut r = self.run_start.partition_point(|&s| s as usize <= pos);
        while pos < range.end {
            // The run holding `pos` is the last one starting at or before it.
            let high = (self.run_high[r - 1] as u32) << 16;
            let end = self
                .run_start
                .get(r)
                .map_or(n, |&s| s as usize)
                .min(range.end);
            buf.extend(self.low[pos..end].iter().map(|&l| high | l as u32));
            pos = end;
            r += 1;
        }
        buf
    }
}

/// A vertex order to read: borrowed ids or a [`PackedOrder`].
#[derive(Clone, Copy, Debug)]
pub enum OrderView<'a> {
    /// The ids.
    Ids(&'a [u32]),
    /// Packed ids.
    Packed(&'a PackedOrder),
}

impl<'a> From<&'a [u32]> for OrderView<'a> {
    fn from(ids: &'a [u32]) -> Self {
        OrderView::Ids(ids)
    }
}

impl<'a> OrderView<'a> {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        match self {
            OrderView::Ids(ids) => ids.len(),
            OrderView::Packed(p) => p.len(),
        }
    }

    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes it holds per vertex.
    pub fn bytes_per_vertex(&self) -> u64 {
        match self {
            OrderView::Ids(_) => 4,
            OrderView::Packed(_) => 2,
        }
    }

    /// The ids at the positions `range`: the order's own slice, or decoded
    /// into `buf`.
    pub fn read<'b>(&self, range: std::ops::Range<usize>, buf: &'b mut Vec<u32>) -> &'b [u32]
    where
        'a: 'b,
    {
        match *self {
            OrderView::Ids(ids) => &ids[range],
            OrderView::Packed(p) => p.read(range, buf),
        }
    }

    /// Calls `f` with the ids at the positions `range`, 64 Ki at a time.
    pub fn for_each_chunk(&self, range: std::ops::Range<usize>, mut f: impl FnMut(&[u32])) {
        let mut buf = Vec::new();
        let mut start = range.start;
        while start < range.end {
            let end = (start + (1 << 16)).min(range.end);
            f(self.read(start..end, &mut buf));
            start = end;
        }
    }
}

/// True when [`vertex_order`] is a counting sort for these values (8- and
/// 16-bit types): O(n), and no scratch beyond the order itself but one
/// count per value and chunk.
pub fn sorts_by_counting(values: &Values) -> bool {
    matches!(
        values,
        Values::U8(_) | Values::I8(_) | Values::U16(_) | Values::I16(_)
    )
}

/// Maps an f32 to a u32 whose unsigned order is the float order, with -0.0
/// and 0.0 mapped to the same key (they are equal values).
#[inline]
fn f32_key(x: f32) -> u32 {
    let x = if x == 0.0 { 0.0 } else { x };
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// Sorts the ids `0..n` by a key below `buckets`, stably (ties in id
/// order): every chunk of ids counts its keys in parallel, then writes its
/// ids to the slots its counts reserve (each chunk's slots for a key follow
/// those of the chunks before it, which is what keeps the sort stable).
fn counting_sort<K>(n: usize, key: K, buckets: usize) -> Vec<u32>
where
    K: Fn(usize) -> usize + Sync,
{
    let mut out = crate::pages::filled(n, 0u32);
    scatter_by_key(0..n, &key, buckets, 1 << 20, &mut out, |i| i as u32);
    out
}

/// Writes `item(i)` for the ids `i` of `range` to `out`, stably sorted by
/// `key` (below `buckets`), counting and placing `chunk` ids at a time on
/// every core; returns per chunk one past the last slot of each key's ids
/// in it (`ends[c][k]`; the slots run by key, then chunk, so the last
/// chunk's end for a key is where its bucket ends).
fn scatter_by_key<K, T, F>(
    range: std::ops::Range<usize>,
    key: &K,
    buckets: usize,
    chunk: usize,
    out: &mut [T],
    item: F,
) -> Vec<Vec<u32>>
where
    K: Fn(usize) -> usize + Sync,
    T: Send,
    F: Fn(usize) -> T + Sync,
{
    let n = range.len();
    let chunks: Vec<std::ops::Range<usize>> = (0..n.div_ceil(chunk))
        .map(|c| range.start + c * chunk..range.start + ((c + 1) * chunk).min(n))
        .collect();
    let mut counts: Vec<Vec<u32>> = chunks
        .par_iter()
        .map(|r| {
            let mut c = vec![0u32; buckets];
            for i in r.clone() {
                c[key(i)] += 1;
            }
            c
        })
        .collect();
    // Exclusive prefix over (bucket, chunk): chunk c's first slot for key k.
    let mut total = 0usize;
    for k in 0..buckets {
        for c in counts.iter_mut() {
            let here = c[k] as usize;
            c[k] = total as u32;
            total += here;
        }
    }
    debug_assert_eq!(total, n);
    let dst = crate::pages::DisjointSlots::new(out);
    chunks
        .into_par_iter()
        .zip(counts.par_iter_mut())
        .for_each(|(r, next)| {
            let dst = &dst;
            for i in r {
                let slot = &mut next[key(i)];
                // SAFETY: the slots of different chunks and keys are
                // disjoint ranges of `out` (the prefix sums above), each
                // written once.
                unsafe { dst.write(*slot as usize, item(i)) };
                *slot += 1;
            }
        });
    // Each chunk's next slot per key is now one past its last.
    counts
}

/// Sorts ids by a 32-bit key: (key, id) pairs are first bucketed by the
/// key's high 16 bits (a stable parallel counting pass in id order), then
/// each bucket's pairs are sorted on their own thread, and the ids read
/// off. Needs 8 bytes per id beyond the output while sorting, so 12 in
/// all, as the sweeps.
fn radix_sort_u32_keys<K>(n: usize, key: K) -> Vec<u32>
where
    K: Fn(usize) -> u32 + Sync,
{
    // (key, id) pairs scattered by the key's high 16 bits, read in id order:
    // no key is read again, nor from random places.
    let mut pairs = crate::pages::filled(n, 0u64);
    let ends = scatter_by_key(
        0..n,
        &|i| (key(i) >> 16) as usize,
        1 << 16,
        1 << 20,
        &mut pairs,
        |i| ((key(i) as u64) << 32) | i as u64,
    );
    // The last chunk's ends are the buckets' ends; the other rows (4 bytes
    // per key and chunk: megabytes) go at once.
    let bucket_ends = ends.into_iter().last().unwrap_or_default();
    let mut buckets: Vec<&mut [u64]> = Vec::with_capacity(1 << 16);
    let mut rest = pairs.as_mut_slice();
    let mut start = 0;
    for end in bucket_ends {
        let (head, tail) = rest.split_at_mut(end as usize - start);
        buckets.push(head);
        rest = tail;
        start = end as usize;
    }
    // Each bucket's pairs are in id order: sorting them stably by the low
    // 16 bits of the key leaves them in (key, id) order. Each thread's
    // scratch holds at most n / (2 threads) pairs, so all of them together
    // stay within the 4 bytes per id that `out` takes later; a larger
    // bucket (one value filling much of a volume) is sorted in place
    // instead: (key, id) is unique, so an unstable sort gives the same
    // order.
    let limit = (n / (2 * rayon::current_num_threads())).max(1 << 16);
    buckets
        .into_par_iter()
        .for_each_init(Vec::new, |scratch, b| {
            if b.len() < 256 || b.len() > limit {
                b.sort_unstable();
            } else {
                sort_low_key_bits(b, scratch);
            }
        });
    let mut out = crate::pages::filled(n, 0u32);
    out.par_chunks_mut(1 << 16)
        .zip(pairs.par_chunks(1 << 16))
        .for_each(|(o, p)| {
            for (o, p) in o.iter_mut().zip(p) {
                *o = *p as u32;
            }
        });
    out
}

/// Sorts (key, id) pairs stably by bits 0..16 of the key (bits 32..48 of
/// the pair): two counting passes of 8 bits, least significant first,
/// through `scratch`.
fn sort_low_key_bits(pairs: &mut [u64], scratch: &mut Vec<u64>) {
    // Both digits' counts in one pass (a digit's counts do not depend on
    // the order the pairs are in).
    let mut counts = [[0usize; 256]; 2];
    for &p in pairs.iter() {
        counts[0][((p >> 32) & 0xff) as usize] += 1;
        counts[1][((p >> 40) & 0xff) as usize] += 1;
    }
    // A digit that all pairs share moves nothing: a bucket of one value
    // (a plateau) is already in order and needs no scratch at all.
    let moves = counts.map(|c| !c.contains(&pairs.len()));
    if moves == [false, false] {
        return;
    }
    scratch.clear();
    scratch.resize(pairs.len(), 0);
    let mut in_pairs = true;
    for (pass, shift) in [32, 40].into_iter().enumerate() {
        if !moves[pass] {
            continue;
        }
        let count = counts[pass];
        let digit = |p: u64| ((p >> shift) & 0xff) as usize;
        let (src, dst): (&[u64], &mut [u64]) = if in_pairs {
            (&*pairs, scratch.as_mut_slice())
        } else {
            (scratch.as_slice(), &mut *pairs)
        };
        let mut next = [0usize; 256];
        let mut total = 0;
        for (n, c) in next.iter_mut().zip(count) {
            *n = total;
            total += c;
        }
        for &p in src.iter() {
            let d = &mut next[digit(p)];
            dst[*d] = p;
            *d += 1;
        }
        in_pairs = !in_pairs;
    }
    if !in_pairs {
        pairs.copy_from_slice(scratch);
    }
}

fn fix_signed_zero_ties(v: &[f64], ids: &mut [u32]) {
    let mut i = 0;
    while i < ids.len() {
        if v[ids[i] as usize] == 0.0 {
            let mut j = i;
            while j < ids.len() && v[ids[j] as usize] == 0.0 {
                j += 1;
            }
            ids[i..j].sort_unstable();
            i = j;
        } else {
            i += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn by_comparison(values: &Values) -> Vec<u32> {
        let mut ids: Vec<u32> = (0..values.len() as u32).collect();
        ids.sort_by(|&a, &b| {
            values
                .get(a as usize)
                .partial_cmp(&values.get(b as usize))
                .expect("finite")
                .then(a.cmp(&b))
        });
        ids
    }

    #[test]
    fn every_type_sorts_by_value_then_id() {
        let raw: Vec<i64> = (0..500).map(|i| (i * 7919 % 23) - 11).collect();
        let all = [
            Values::U8(raw.iter().map(|&x| (x + 11) as u8).collect()),
            Values::I8(raw.iter().map(|&x| x as i8).collect()),
            Values::U16(raw.iter().map(|&x| (x * 1000 + 11000) as u16).collect()),
            Values::I16(raw.iter().map(|&x| (x * 1000) as i16).collect()),
            Values::U32(raw.iter().map(|&x| (x + 11) as u32 * 100_000).collect()),
            Values::I32(raw.iter().map(|&x| x as i32 * 100_000).collect()),
            Values::F32(raw.iter().map(|&x| x as f32 * 0.37).collect()),
            Values::F64(raw.iter().map(|&x| x as f64 * -1e-3).collect()),
        ];
        for values in &all {
            assert_eq!(
                vertex_order(values),
                by_comparison(values),
                "{}",
                values.type_name()
            );
        }
    }

    #[test]
    fn large_inputs_sort_across_chunks_and_big_buckets() {
        // Three million values: several counting chunks, and float buckets
        // (same high 16 bits) far above the small-bucket threshold.
        let n = 3_000_000u64;
        let mix = |i: u64| i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
        let all = [
            Values::U8((0..n).map(|i| mix(i) as u8).collect()),
            Values::I16((0..n).map(|i| mix(i) as i16).collect()),
            Values::F32(
                (0..n)
                    .map(|i| 1.0 + (mix(i) % 5000) as f32 * 1e-7)
                    .collect(),
            ),
            Values::I32((0..n).map(|i| (mix(i) % 100_000) as i32 - 50_000).collect()),
        ];
        for values in &all {
            assert_eq!(
                vertex_order(values),
                by_comparison(values),
                "{}",
                values.type_name()
            );
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// 32-bit keys through every path of the bucket sort: buckets below
        /// the radix threshold, buckets sorted by their low key bits (one
        /// digit or two), and a bucket larger than the scratch allows (most
        /// values within one high-16-bit bucket).
        #[test]
        fn thirty_two_bit_keys_sort_by_value_then_id(
            n in 1usize..300_000,
            spread in 0u32..24,
            seed in proptest::prelude::any::<u64>(),
        ) {
            let r = |i: usize| ((i as u64 ^ seed).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as u32;
            let narrow = |i: usize| r(i) & ((1u32 << spread) - 1);
            let all = [
                Values::F32((0..n).map(|i| 1.0 + narrow(i) as f32 * 1.2e-7).collect()),
                Values::F32((0..n).map(|i| f32::from_bits(r(i) >> 2) - 0.5).collect()),
                Values::U32((0..n).map(narrow).collect()),
                Values::I32((0..n).map(|i| narrow(i) as i32 - (1 << 10)).collect()),
            ];
            for values in &all {
                proptest::prop_assert_eq!(vertex_order(values), by_comparison(values));
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        /// The packed order reads back as the plain order over any range,
        /// for u8 and i8 values, few or many levels, on sizes that cross
        /// the 64 Ki blocks of ids (and the 1 Mi chunks of the plain sort).
        #[test]
        fn the_packed_order_reads_as_the_order(
            n in 0usize..400_000,
            levels in 1u32..=256,
            seed in proptest::prelude::any::<u64>(),
            cut in (0.0f64..1.0, 0.0f64..1.0),
        ) {
            let r = |i: usize| ((i as u64 ^ seed).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as u32 % levels;
            for values in [
                Values::U8((0..n).map(|i| r(i) as u8).collect()),
                Values::I8((0..n).map(|i| (r(i) as i32 - 128) as i8).collect()),
            ] {
                let plain = vertex_order(&values);
                let packed = compact_vertex_order(&values);
                proptest::prop_assert!(matches!(packed, Order::Packed(_)));
                let view = packed.view();
                proptest::prop_assert_eq!(view.len(), n);
                let (a, b) = ((cut.0 * n as f64) as usize, (cut.1 * n as f64) as usize);
                let range = a.min(b)..a.max(b);
                let mut buf = Vec::new();
                proptest::prop_assert_eq!(view.read(range.clone(), &mut buf), &plain[range.clone()]);
                let mut chunks = Vec::new();
                view.for_each_chunk(range.clone(), |ids| chunks.extend_from_slice(ids));
                proptest::prop_assert_eq!(&chunks[..], &plain[range]);
                proptest::prop_assert_eq!(view.read(0..n, &mut buf), &plain[..]);
            }
        }
    }

    #[test]
    fn negative_zero_ties_with_zero_by_id() {
        let v = Values::F32(vec![0.0, -0.0, 1.0, -0.0, 0.0]);
        assert_eq!(vertex_order(&v), vec![0, 1, 3, 4, 2]);
        let v = Values::F64(vec![0.0, -0.0, 1.0, -0.0, 0.0]);
        assert_eq!(vertex_order(&v), vec![0, 1, 3, 4, 2]);
    }
}
