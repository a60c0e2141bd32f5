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
//! ([`compact_vertex_order`], [`PackedOrder`]): about one byte per vertex
//! instead of 4, read back 64 Ki ids at a time ([`OrderView`]); the order
//! of any other values, where there are at most 2^24 vertices (a 256³
//! volume), in 3 bytes per id ([`Order::Narrow`]).

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
/// ids, in 3 bytes each where there are at most 2^24 vertices, or for
/// 8-bit values the same ids packed in about a byte each
/// ([`PackedOrder`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Order {
    /// One id per position, 4 bytes each.
    Ids(Vec<u32>),
    /// One id per position in 3 bytes, little end first: at most
    /// [`NARROW_VERTICES`] vertices.
    Narrow(Vec<[u8; 3]>),
    /// The ids' low halves and the runs of their high halves.
    Packed(PackedOrder),
}

/// The most vertices whose ids fit [`Order::Narrow`]'s 3 bytes.
pub const NARROW_VERTICES: usize = 1 << 24;

/// [`vertex_order`] in the form that takes least memory: packed for 8-bit
/// values (about a byte per vertex, [`PackedOrder`]), the
/// ids in 3 bytes each for at most [`NARROW_VERTICES`] vertices, else in 4.
/// Narrowing holds the ids beside their 3-byte copy (7 bytes per vertex),
/// below the float sort's 8.
pub fn compact_vertex_order(values: &Values) -> Order {
    match values {
        Values::U8(v) => Order::Packed(PackedOrder::sort(v.len(), &|i| v[i] as usize)),
        Values::I8(v) => Order::Packed(PackedOrder::sort(v.len(), &|i| {
            (v[i] as i16 + 128) as usize
        })),
        _ => narrowed(vertex_order(values)),
    }
}

/// The ids as an [`Order`]: in 3 bytes each where they fit.
fn narrowed(ids: Vec<u32>) -> Order {
    if ids.len() > NARROW_VERTICES {
        return Order::Ids(ids);
    }
    let mut narrow = vec![[0u8; 3]; ids.len()];
    narrow
        .par_chunks_mut(1 << 16)
        .zip(ids.par_chunks(1 << 16))
        .for_each(|(out, ids)| {
            for (o, &id) in out.iter_mut().zip(ids) {
                *o = narrow_id(id);
            }
        });
    Order::Narrow(narrow)
}

/// An id below 2^24 in 3 bytes, little end first.
pub fn narrow_id(id: u32) -> [u8; 3] {
    let b = id.to_le_bytes();
    [b[0], b[1], b[2]]
}

/// The id [`narrow_id`] wrote.
#[inline(always)]
pub fn wide_id(b: [u8; 3]) -> u32 {
    u32::from_le_bytes([b[0], b[1], b[2], 0])
}

/// The bytes an order of ids takes for `n` vertices: 3 per vertex where
/// they narrow ([`Order::Narrow`]), else 4.
pub fn ids_bytes(n: usize) -> u64 {
    if n <= NARROW_VERTICES { 3 } else { 4 }
}

/// The bytes [`compact_vertex_order`] takes for these values: what the
/// packed order will hold where it packs them (its runs sized by a
/// counting pass, in parallel), else 3 or 4 per vertex ([`ids_bytes`]).
pub fn order_bytes(values: &Values) -> u64 {
    match values {
        Values::U8(v) => packed_bytes(v.len(), &|i| v[i] as usize),
        Values::I8(v) => packed_bytes(v.len(), &|i| (v[i] as i16 + 128) as usize),
        _ => ids_bytes(values.len()) * values.len() as u64,
    }
}

impl Order {
    /// A view to read the order through.
    pub fn view(&self) -> OrderView<'_> {
        match self {
            Order::Ids(ids) => OrderView::Ids(ids),
            Order::Narrow(ids) => OrderView::Narrow(ids),
            Order::Packed(p) => OrderView::Packed(p),
        }
    }

    /// Keeps the first `len` positions of an order of ids, narrow or not,
    /// and gives the pages past them back ([`crate::pages::release_spare`]):
    /// what a grouping that consumes the order from its end lets go. A
    /// packed order is kept whole.
    pub fn truncate_releasing(&mut self, len: usize) {
        match self {
            Order::Ids(ids) => {
                ids.truncate(len);
                crate::pages::release_spare(ids);
            }
            Order::Narrow(ids) => {
                ids.truncate(len);
                crate::pages::release_spare(ids);
            }
            Order::Packed(_) => {}
        }
    }
}

/// The vertex order of 8-bit values in about one byte per vertex. A
/// counting sort by value is stable over ids, so within one value the ids
/// ascend, and their high 16 bits stay the same over long runs: the
/// positions fall into *runs*, one per value and block of 64 Ki ids (the
/// sort counts each block on its own), listed by value, then block. A run
/// keeps only its ids' low 16 bits, ascending, in whichever of three forms
/// is smallest for it:
///
/// * a list: 2 bytes per id (a value rare in its block);
/// * gaps: the first id, then one byte per gap below 256 and 3 bytes (a
///   zero, then the id) for a longer one (a value spread thinly);
/// * a bitmap of the block's ids between the run's first and last (a value
///   common in its block: the background of a scan, a tissue's range).
///
/// On the shared 8-bit scans this takes 0.8-1.1 bytes per vertex (2 as
/// lists alone; `tooth` 1.1, `colin27_ch2` 0.9, `engine` 0.8). Reading a
/// range decodes its runs, skipping into the first one from its start.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PackedOrder {
    len: usize,
    /// Ascending by start; the first starts at position 0.
    runs: Vec<Run>,
    /// The runs' encodings, one after another.
    bytes: Vec<u8>,
}

/// One run of a [`PackedOrder`]: its first position, its ids' high 16
/// bits (the block), its form and where its bytes start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Run {
    start: u32,
    block: u16,
    form: Form,
    offset: u64,
}

/// How a run's low halves are written (see [`PackedOrder`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Form {
    List,
    Gaps,
    Bitmap,
}

/// The ids of one 64 Ki block, each block's ids counted by key and
/// sorted by (key, id) on its own: the runs' contents.
const BLOCK: usize = 1 << 16;

impl Form {
    /// The smallest form for a run's ascending low halves, and its bytes.
    fn choose(ids: &[u16]) -> (Form, usize) {
        let list = 2 * ids.len();
        let gaps = 2 + ids
            .windows(2)
            .map(|w| if w[1] - w[0] < 256 { 1 } else { 3 })
            .sum::<usize>();
        let (first, last) = (ids[0] as usize / 64, ids[ids.len() - 1] as usize / 64);
        let bitmap = 2 + 8 * (last - first + 1);
        [
            (Form::List, list),
            (Form::Gaps, gaps),
            (Form::Bitmap, bitmap),
        ]
        .into_iter()
        .min_by_key(|&(_, b)| b)
        .expect("three forms")
    }

    /// Writes `ids` (ascending low halves) in this form to `out`, whose
    /// length is what [`Form::choose`] said.
    fn encode(self, ids: &[u16], out: &mut [u8]) {
        match self {
            Form::List => {
                for (o, &id) in out.chunks_exact_mut(2).zip(ids) {
                    o.copy_from_slice(&id.to_le_bytes());
                }
            }
            Form::Gaps => {
                out[..2].copy_from_slice(&ids[0].to_le_bytes());
                let mut at = 2;
                for w in ids.windows(2) {
                    let gap = w[1] - w[0];
                    if gap < 256 {
                        out[at] = gap as u8;
                        at += 1;
                    } else {
                        out[at] = 0;
                        out[at + 1..at + 3].copy_from_slice(&w[1].to_le_bytes());
                        at += 3;
                    }
                }
                debug_assert_eq!(at, out.len());
            }
            Form::Bitmap => {
                let first = ids[0] / 64;
                out[..2].copy_from_slice(&first.to_le_bytes());
                out[2..].fill(0);
                for &id in ids {
                    let bit = (id - first * 64) as usize;
                    out[2 + bit / 8] |= 1 << (bit % 8);
                }
            }
        }
    }

    /// Writes to `out` the ids of positions `skip..skip + out.len()` of a
    /// run written as `bytes` in this form, with `high` as their high bits.
    fn decode(self, bytes: &[u8], high: u32, skip: usize, out: &mut [u32]) {
        let u16_at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]) as u32;
        match self {
            Form::List => {
                for (o, b) in out.iter_mut().zip(bytes[2 * skip..].chunks_exact(2)) {
                    *o = high | u16::from_le_bytes([b[0], b[1]]) as u32;
                }
            }
            Form::Gaps => {
                // The next id after `id`, whose gap starts at `at`.
                let next = |id: u32, at: usize| match bytes[at] {
                    0 => (u16_at(at + 1), at + 3),
                    gap => (id + gap as u32, at + 1),
                };
                let (mut id, mut at) = (u16_at(0), 2);
                for _ in 0..skip {
                    (id, at) = next(id, at);
                }
                if let Some((first, rest)) = out.split_first_mut() {
                    *first = high | id;
                    for o in rest {
                        (id, at) = next(id, at);
                        *o = high | id;
                    }
                }
            }
            Form::Bitmap => {
                let mut base = high | (u16_at(0) * 64);
                let (mut skip, mut w) = (skip, 0);
                for word in bytes[2..].chunks_exact(8) {
                    if w == out.len() {
                        return;
                    }
                    let mut word = u64::from_le_bytes(word.try_into().expect("8 bytes"));
                    let ones = word.count_ones() as usize;
                    if skip >= ones {
                        skip -= ones;
                    } else {
                        for _ in 0..skip {
                            word &= word - 1;
                        }
                        skip = 0;
                        // The word's ids, or as many as `out` has room for.
                        let room = &mut out[w..];
                        let n = (word.count_ones() as usize).min(room.len());
                        for o in &mut room[..n] {
                            *o = base + word.trailing_zeros();
                            word &= word - 1;
                        }
                        w += n;
                    }
                    base += 64;
                }
            }
        }
    }
}

/// Block `b`'s ids (of `0..n`) sorted by (key, id) as low halves into
/// `sorted`, and where each key's ids start in it (`first[k]..first[k + 1]`).
fn sort_block<K: Fn(usize) -> usize>(
    n: usize,
    b: usize,
    key: &K,
    sorted: &mut Vec<u16>,
    first: &mut [u32; 257],
) {
    let ids = b * BLOCK..((b + 1) * BLOCK).min(n);
    first.fill(0);
    for i in ids.clone() {
        first[key(i) + 1] += 1;
    }
    for k in 0..256 {
        first[k + 1] += first[k];
    }
    let mut next = *first;
    sorted.resize(ids.len(), 0);
    for i in ids {
        let slot = &mut next[key(i)];
        sorted[*slot as usize] = i as u16;
        *slot += 1;
    }
}

/// Per block of 64 Ki ids and key: the run's ids, form and bytes (ids 0
/// where the block has no id of that key).
fn size_runs<K: Fn(usize) -> usize + Sync>(n: usize, key: &K) -> Vec<Vec<(u32, Form, u64)>> {
    (0..n.div_ceil(BLOCK))
        .into_par_iter()
        .map_init(
            || (Vec::new(), [0u32; 257]),
            |(sorted, first), b| {
                sort_block(n, b, key, sorted, first);
                (0..256)
                    .map(
                        |k| match &sorted[first[k] as usize..first[k + 1] as usize] {
                            [] => (0, Form::List, 0),
                            ids => {
                                let (form, bytes) = Form::choose(ids);
                                (ids.len() as u32, form, bytes as u64)
                            }
                        },
                    )
                    .collect()
            },
        )
        .collect()
}

/// The bytes a [`PackedOrder`] of the ids `0..n` sorted by `key` will
/// hold (its runs sized, nothing written).
fn packed_bytes<K: Fn(usize) -> usize + Sync>(n: usize, key: &K) -> u64 {
    size_runs(n, key)
        .iter()
        .flatten()
        .filter(|r| r.0 > 0)
        .map(|r| r.2 + size_of::<Run>() as u64)
        .sum()
}

impl PackedOrder {
    /// Sorts the ids `0..n` by `key` (below 256), ties by id. Each block
    /// is sorted twice on its own, in parallel: once to choose its runs'
    /// forms and sizes, once to write them where the runs before them end.
    fn sort<K: Fn(usize) -> usize + Sync>(n: usize, key: &K) -> Self {
        let blocks = n.div_ceil(BLOCK);
        let mut sized = size_runs(n, &key);
        // The runs by key, then block; each block's sizes become offsets,
        // and `end_of` says where each one's bytes end.
        let (mut runs, mut start, mut offset) = (Vec::new(), 0u32, 0u64);
        let mut end_of = vec![[0u64; 256]; blocks];
        for k in 0..256 {
            for (b, per_key) in sized.iter_mut().enumerate() {
                let (count, form, bytes) = &mut per_key[k];
                if *count > 0 {
                    runs.push(Run {
                        start,
                        block: b as u16,
                        form: *form,
                        offset,
                    });
                    start += *count;
                    end_of[b][k] = offset + *bytes;
                    *bytes = offset;
                    offset = end_of[b][k];
                }
            }
        }
        debug_assert_eq!(start as usize, n);
        let mut bytes = crate::pages::filled(offset as usize, 0u8);
        let dst = crate::pages::DisjointSlots::new(&mut bytes);
        sized.par_iter().zip(&end_of).enumerate().for_each_init(
            || (Vec::new(), [0u32; 257]),
            |(sorted, first), (b, (per_key, ends))| {
                sort_block(n, b, key, sorted, first);
                for (k, &(count, form, at)) in per_key.iter().enumerate() {
                    if count > 0 {
                        let ids = &sorted[first[k] as usize..first[k + 1] as usize];
                        // SAFETY: the runs' byte ranges are disjoint (the
                        // offsets above), each written by its block only.
                        let out = unsafe { dst.slice(at as usize..ends[k] as usize) };
                        form.encode(ids, out);
                    }
                }
            },
        );
        Self {
            len: n,
            runs,
            bytes,
        }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The bytes it holds.
    pub fn bytes(&self) -> u64 {
        (self.bytes.len() + self.runs.len() * size_of::<Run>()) as u64
    }

    /// The ids at the positions `range`, decoded into `buf`.
    pub fn read<'b>(&self, range: std::ops::Range<usize>, buf: &'b mut Vec<u32>) -> &'b [u32] {
        buf.clear();
        buf.resize(range.len(), 0);
        let mut at = 0;
        self.for_each_run(range, |run, bytes, skip, len| {
            let out = &mut buf[at..at + len];
            run.form.decode(bytes, (run.block as u32) << 16, skip, out);
            at += len;
        });
        buf
    }

    /// The ids at the positions `range` that lie in `ids`, in the order's
    /// order, decoded into `buf`: a block of the divide and conquer reads
    /// only the runs of its own blocks of ids, skipping the others
    /// undecoded, so that B blocks do not decode the order B times.
    pub fn read_within<'b>(
        &self,
        range: std::ops::Range<usize>,
        ids: std::ops::Range<u32>,
        buf: &'b mut Vec<u32>,
    ) -> &'b [u32] {
        buf.clear();
        if ids.is_empty() {
            return buf;
        }
        let (first, last) = (ids.start >> 16, (ids.end - 1) >> 16);
        self.for_each_run(range, |run, bytes, skip, len| {
            let block = run.block as u32;
            if !(first..=last).contains(&block) {
                return;
            }
            let at = buf.len();
            buf.resize(at + len, 0);
            run.form.decode(bytes, block << 16, skip, &mut buf[at..]);
            // Only the blocks at the ends can hold ids outside.
            if block == first || block == last {
                keep_within(buf, at, &ids);
            }
        });
        buf
    }

    /// Calls `f(run, its bytes, positions to skip into it, positions to
    /// read)` for each run that holds positions of `range`, in order.
    fn for_each_run(
        &self,
        range: std::ops::Range<usize>,
        mut f: impl FnMut(Run, &[u8], usize, usize),
    ) {
        if range.is_empty() {
            return;
        }
        let mut pos = range.start;
        // The run holding `pos` is the last one starting at or before it.
        let mut r = self.runs.partition_point(|run| run.start as usize <= pos) - 1;
        while pos < range.end {
            let run = self.runs[r];
            let (end, bytes_end) = self
                .runs
                .get(r + 1)
                .map_or((self.len, self.bytes.len()), |next| {
                    (next.start as usize, next.offset as usize)
                });
            let end = end.min(range.end);
            let skip = pos - run.start as usize;
            f(
                run,
                &self.bytes[run.offset as usize..bytes_end],
                skip,
                end - pos,
            );
            pos = end;
            r += 1;
        }
    }
}

/// Keeps, of `buf[from..]`, the ids in `ids`, in place and in order,
/// without a branch per id (whether the next id of an order is in a block
/// is a coin toss for the predictor).
fn keep_within(buf: &mut Vec<u32>, from: usize, ids: &std::ops::Range<u32>) {
    let mut kept = from;
    for i in from..buf.len() {
        let id = buf[i];
        buf[kept] = id;
        kept += ids.contains(&id) as usize;
    }
    buf.truncate(kept);
}

/// A vertex order to read: borrowed ids, narrow or not, or a
/// [`PackedOrder`].
#[derive(Clone, Copy, Debug)]
pub enum OrderView<'a> {
    /// The ids.
    Ids(&'a [u32]),
    /// The ids in 3 bytes each ([`Order::Narrow`]).
    Narrow(&'a [[u8; 3]]),
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
            OrderView::Narrow(ids) => ids.len(),
            OrderView::Packed(p) => p.len(),
        }
    }

    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The bytes it holds.
    pub fn bytes(&self) -> u64 {
        match self {
            OrderView::Ids(ids) => 4 * ids.len() as u64,
            OrderView::Narrow(ids) => 3 * ids.len() as u64,
            OrderView::Packed(p) => p.bytes(),
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
            OrderView::Narrow(ids) => {
                buf.clear();
                buf.extend(ids[range].iter().map(|&b| wide_id(b)));
                buf
            }
            OrderView::Packed(p) => p.read(range, buf),
        }
    }

    /// The ids at the positions `range` that lie in `ids`, in the order's
    /// order, into `buf` ([`PackedOrder::read_within`] skips the runs of
    /// other ids; plain ids are all read and filtered).
    pub fn read_within<'b>(
        &self,
        range: std::ops::Range<usize>,
        ids: std::ops::Range<u32>,
        buf: &'b mut Vec<u32>,
    ) -> &'b [u32] {
        match *self {
            OrderView::Ids(all) => {
                buf.clear();
                buf.extend_from_slice(&all[range]);
                keep_within(buf, 0, &ids);
                buf
            }
            OrderView::Narrow(_) => {
                self.read(range, buf);
                keep_within(buf, 0, &ids);
                buf
            }
            OrderView::Packed(p) => p.read_within(range, ids, buf),
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
/// off into the first half of the pairs' own allocation. Holds 8 bytes
/// per id while sorting (and at most 1 more of scratch), then 4: less than
/// the sweeps after it.
fn radix_sort_u32_keys<K>(n: usize, key: K) -> Vec<u32>
where
    K: Fn(usize) -> u32 + Sync,
{
    // The pairs live in words, two per id, so that the ids can be read off
    // in place into a `Vec<u32>`; an allocation this large is 8-aligned on
    // every allocator the program meets, else the pairs get their own.
    let mut words = crate::pages::filled(2 * n, 0u32);
    // SAFETY: u64 has no invalid bit patterns; `align_to_mut` only takes
    // the aligned middle.
    match unsafe { words.align_to_mut::<u64>() } {
        ([], pairs, []) => sort_pairs(pairs, &key),
        _ => {
            let mut pairs = crate::pages::filled(n, 0u64);
            sort_pairs(&mut pairs, &key);
            return pairs.iter().map(|&p| p as u32).collect();
        }
    }
    // The id of pair i (its low half) is word 2i + at; it moves to word i.
    // Waves [s, 2s) write words s.. below 2s, whose pairs an earlier wave
    // read, and read words 2s.., which no write of theirs reaches.
    let at = usize::from(cfg!(target_endian = "big"));
    const SERIAL: usize = 1 << 16;
    for i in 0..n.min(SERIAL) {
        words[i] = words[2 * i + at];
    }
    let mut s = SERIAL;
    while s < n {
        let e = (2 * s).min(n);
        let (low, high) = words.split_at_mut(2 * s);
        low[s..e]
            .par_chunks_mut(1 << 16)
            .zip(high[..2 * (e - s)].par_chunks(2 << 16))
            .for_each(|(out, two)| {
                for (o, t) in out.iter_mut().zip(two.chunks_exact(2)) {
                    *o = t[at];
                }
            });
        s = e;
    }
    words.truncate(n);
    // The second half's pages go back at once.
    crate::pages::release_spare(&mut words);
    words
}

/// [`radix_sort_u32_keys`]' pairs, (key, id) for ids `0..pairs.len()`,
/// made and sorted.
fn sort_pairs<K>(pairs: &mut [u64], key: &K)
where
    K: Fn(usize) -> u32 + Sync,
{
    let n = pairs.len();
    // (key, id) pairs scattered by the key's high 16 bits, read in id order:
    // no key is read again, nor from random places.
    let ends = scatter_by_key(
        0..n,
        &|i| (key(i) >> 16) as usize,
        1 << 16,
        1 << 20,
        pairs,
        |i| ((key(i) as u64) << 32) | i as u64,
    );
    // The last chunk's ends are the buckets' ends; the other rows (4 bytes
    // per key and chunk: megabytes) go at once.
    let bucket_ends = ends.into_iter().last().unwrap_or_default();
    // Each bucket's pairs are in id order: sorting them stably by the low
    // 16 bits of the key leaves them in (key, id) order. Each thread's
    // scratch holds at most n / (8 threads) pairs, so all of them together
    // stay within a byte per id; a larger bucket (one value filling much
    // of a volume, or a narrow range of values) is sorted in place
    // instead: (key, id) is unique, so an unstable sort gives the same
    // order.
    let threads = rayon::current_num_threads();
    let limit = (n / (8 * threads)).max(1 << 16);
    // The buckets that hold pairs, in groups of about n / (16 threads)
    // pairs, one task and one scratch each. The values of a smooth field
    // fill a narrow range of keys (1,427 of the 65,536 buckets on
    // `synthetic:256`): rayon's halving of the bucket range left them all
    // to one thread (as slow on 2 threads as on 1), and a scratch made per
    // bucket was paged in afresh each time (a third slower).
    let share = (n / (16 * threads)).max(1);
    let mut groups: Vec<Vec<&mut [u64]>> = vec![Vec::new()];
    let (mut rest, mut start, mut in_group) = (pairs, 0, 0);
    for end in bucket_ends {
        let (bucket, tail) = rest.split_at_mut(end as usize - start);
        (rest, start) = (tail, end as usize);
        if bucket.is_empty() {
            continue;
        }
        if in_group >= share {
            groups.push(Vec::new());
            in_group = 0;
        }
        in_group += bucket.len();
        groups.last_mut().expect("a group").push(bucket);
    }
    groups.into_par_iter().with_max_len(1).for_each(|group| {
        let mut scratch = Vec::new();
        for b in group {
            if b.len() < 256 || b.len() > limit {
                b.sort_unstable();
            } else {
                sort_low_key_bits(b, &mut scratch);
            }
        }
    });
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
                proptest::prop_assert_eq!(&chunks[..], &plain[range.clone()]);
                proptest::prop_assert_eq!(view.read(0..n, &mut buf), &plain[..]);
                // Only the ids of a block: as the plain order filtered,
                // across the 64 Ki blocks of ids or inside one.
                let ids = (cut.0 * n as f64) as u32..(cut.1 * n as f64 + 70_000.0).min(n as f64) as u32;
                let within: Vec<u32> = plain[range.clone()].iter().copied().filter(|v| ids.contains(v)).collect();
                proptest::prop_assert_eq!(view.read_within(range.clone(), ids.clone(), &mut buf), &within[..]);
                let whole = OrderView::Ids(&plain);
                proptest::prop_assert_eq!(whole.read_within(range.clone(), ids.clone(), &mut buf), &within[..]);
                let Order::Narrow(narrow) = narrowed(plain.clone()) else {
                    panic!("narrow")
                };
                let narrow = OrderView::Narrow(&narrow);
                proptest::prop_assert_eq!(narrow.bytes(), 3 * n as u64);
                proptest::prop_assert_eq!(narrow.read(range.clone(), &mut buf), &plain[range.clone()]);
                chunks.clear();
                narrow.for_each_chunk(range.clone(), |ids| chunks.extend_from_slice(ids));
                proptest::prop_assert_eq!(&chunks[..], &plain[range.clone()]);
                proptest::prop_assert_eq!(narrow.read_within(range, ids, &mut buf), &within[..]);
            }
        }
    }

    /// Ids up to 2^24 - 1 narrow to 3 bytes and read back; an order of more
    /// vertices keeps 4 bytes per id.
    #[test]
    fn ids_narrow_to_three_bytes_up_to_2_to_the_24() {
        let top = NARROW_VERTICES as u32 - 1;
        let ids = vec![top, 0, 1 << 16, 255, 1 << 23, top - 1];
        let Order::Narrow(narrow) = narrowed(ids.clone()) else {
            panic!("narrow")
        };
        let mut buf = Vec::new();
        assert_eq!(OrderView::Narrow(&narrow).read(0..6, &mut buf), &ids[..]);
        assert_eq!(OrderView::Narrow(&narrow).read(2..5, &mut buf), &ids[2..5]);
        assert_eq!(
            (ids_bytes(NARROW_VERTICES), ids_bytes(NARROW_VERTICES + 1)),
            (3, 4)
        );
        assert!(matches!(
            narrowed(vec![0; NARROW_VERTICES + 1]),
            Order::Ids(_)
        ));
        let floats = Values::F32((0..1000).map(|i| ((i * 7919) % 1000) as f32).collect());
        assert_eq!(compact_vertex_order(&floats).view().bytes(), 3000);
        assert_eq!(order_bytes(&floats), 3000);
    }

    /// A value common in its block is a bitmap, one spread thinly gaps,
    /// a rare one a list; all read back as the plain order, from any
    /// position, and the packed order is smaller than 2 bytes per vertex.
    #[test]
    fn each_form_reads_as_the_order() {
        let n = 300_000;
        let values = Values::U8(
            (0..n)
                .map(|i| match i {
                    i if i % 5003 == 7 => 2,
                    i if i % 97 == 3 => 1,
                    i if i > 250_000 => 3,
                    _ => 0,
                })
                .collect(),
        );
        let Order::Packed(packed) = compact_vertex_order(&values) else {
            panic!("packed")
        };
        for form in [Form::List, Form::Gaps, Form::Bitmap] {
            assert!(packed.runs.iter().any(|r| r.form == form), "{form:?}");
        }
        assert_eq!(order_bytes(&values), packed.bytes());
        assert!(packed.bytes() < n as u64, "{} bytes", packed.bytes());
        let plain = vertex_order(&values);
        let mut buf = Vec::new();
        for start in [0, 1, 63, 64, 65, 1000, 65_535, 65_536, 131_073, 299_000] {
            for len in [0, 1, 2, 100, 70_000, n] {
                let end = (start + len).min(n);
                assert_eq!(
                    packed.read(start..end, &mut buf),
                    &plain[start..end],
                    "{start}+{len}"
                );
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
