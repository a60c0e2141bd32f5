//! The contour tree: join and split trees, their merge, and the augmented
//! tree (Carr, Snoeyink, Axen: "Computing contour trees in all dimensions").
//!
//! Pipeline: vertex order (sorted by value, ties by id, in parallel) ->
//! link codes (parallel) -> [`sweep::JoinTree`] and [`sweep::SplitTree`] on
//! the *candidate nodes* (§4.4: vertices whose upper or lower link is not
//! one piece), both sweeps at once -> merge by leaf cutting on the
//! candidates (Fig. 9) -> every other vertex placed on its superarc from
//! its two leafward candidates in one parallel pass -> regular vertices of
//! each superarc in value order. [`merge`] explains the placement rule and
//! why it replaced the per-vertex merge (kept as the tests' oracle). On more
//! than two cores the sweeps run in blocks of the volume, both directions
//! of every block at once, glued into the same two trees ([`blocks`]: the
//! divide and conquer of Pascucci and Cole-McLaughlin).
//!
//! **Memory per vertex** (n vertices, beyond the field's own values): the
//! vertex order (4 bytes, 3 for at most 2^24 vertices, whose ids narrow
//! to 3 bytes: [`crate::field::Order::Narrow`], or 0.6-1.2 for 8-bit
//! values, whose order is packed: [`crate::field::PackedOrder`]) plus 6
//! to 8, plus the
//! candidates' share below. The float sort holds 8 ((value, id) pairs, the
//! ids then read off in place); the sweeps the order and 6 (each sweep's
//! one word per vertex, which holds the vertex's link code until the sweep
//! visits it: the union-find lives on the candidates); merge and
//! placement the order and the two leafward records, the first of which
//! becomes `vertex_arc`; the grouping the order, `vertex_arc` and the
//! arcs' vertex lists (3 bytes per id for at most 2^24 vertices, else 4:
//! [`ArcVertices`]; an order of ids given back as it is read, so 7 in
//! all). The records are held in 3 bytes per vertex each from the link
//! pass on when there are fewer than 2^23 candidates ([`leafward`]): 6
//! bytes per vertex through the sweeps, the merge and the placement,
//! which writes each vertex's place over its entry of the first record,
//! in the same 3 bytes, and gives the second back (8 otherwise, and 8 at
//! the grouping).
//! Candidates add 16 bytes each during the sweeps and about 37 at the
//! merge's peak ([`peak_bytes`]): little on smooth fields (a few per cent
//! of the vertices), but much on noisy scans (tooth 31 %) and white noise,
//! where half the vertices are candidates. There about half the
//! candidates are regular in both trees and are reduced before the merge
//! ([`merge::reduce_regular_candidates`]): the merge then holds about 45
//! bytes per supernode, and the reduction 10 per candidate and 9 per
//! supernode. Where at least one vertex in 8 is a candidate and the
//! records pack, the candidates' own tables are packed too
//! ([`leafward::packs_tables`]): 14 bytes per candidate in the sweeps and
//! about 30 at the merge (37.5 per supernode where it is reduced). Where
//! the records cannot pack (2^23 candidates or more: a noisy scan of a
//! billion vertices, white noise), the sweeps write each candidate's
//! parent into its record ([`sweep::sweep_parents_in_words`]): 8 bytes per
//! candidate while sweeping and 10 once the parents are read off, not 16.
//! So when the order is cheap to
//! make again (8- and 16-bit values: a counting sort in O(n), most scans)
//! and the candidates are many, [`ContourTree::from_field`] lets the order
//! go before the merge and sorts again after the placement, once the
//! second leafward record and the candidates' tables are gone
//! ([`order_at_merge`]); the order goes again before the tree's node
//! adjacency is made. A float order, which costs a sort of (value, id)
//! pairs to make again, is let go likewise where that takes at least a
//! byte per vertex off the peak: noisy float fields, not smooth ones. Measured peaks (`flexiso bench`, session 26): about
//! 10 bytes per vertex on the 8-bit brains (7 % candidates; the grouping),
//! 10.5 on a smooth float field (12.1 before the float sort, the placement
//! and the grouping gave memory back as they went). With the reduction
//! (session 29): tooth 14.9 sampled (31 %; the grouping, beside the sweeps
//! at 14.4 and the finished tree at 13.5, where the merge held 17.5
//! before), a noisy 1024³ scan
//! 13.8 (28 %, too many candidates to pack; the sweeps, where the merge
//! held 16.5), white noise 22.3 (29.5). [`check_memory`] refuses a
//! build that would not fit as soon as the candidates are counted, with
//! as many supernodes as the extrema allow (at most twice as many:
//! [`sweep::Census::supernodes_at_most`], 0.1-2 % above the real number on
//! the shared scans; half the candidates before session 42), and
//! [`check_merge_memory`] again with their real number once the sweeps are
//! done. The finished tree keeps 6 bytes per vertex (`vertex_arc` in 3, and
//! `arc_vertices` 3 per regular vertex; 4 each where the records did not
//! pack or the vertices are more than 2^24) plus about 28 per supernode:
//! 10.3 on tooth (11.15 with 4-byte lists, before session 45). Keeping the places in 3 bytes
//! (session 38) took the peaks of `flexiso bench` about a byte per vertex
//! lower on every scan whose peak was the placement or the grouping
//! (colin27_ch2 9.7-9.8 → 8.5-8.8, colin27_ch2better 8.8-8.9 → 7.5),
//! 10.4 → 10.0 on `synthetic:256` (its sweeps now). Making the supernodes
//! after the placement and packing a noisy scan's tables (session 39)
//! took tooth from 12.1-12.4 to 11.1-11.9 (its sweeps at 11.5 are the
//! peak, the finished tree's 11.15 just below) and engine from 9.7 to
//! 9.5-9.6. The parents in the records and the reduction over the old
//! parents (session 40) took the noisy 1024³ scan from 13.2 to 11.6 (its
//! sweeps and its reduction now at 11.6-11.7, the merge 11.0) and white
//! noise from 21.3-21.6 to 20.5-20.7 (its merge on the supernodes, in
//! words, is its peak). Letting white noise's float order go during the
//! merge and sorting it again (session 41) took it to 17.6 (its sweeps,
//! 4 bytes of order, 8 of records and 10 per candidate, are the peak now,
//! the grouping 17.2 just below it), for a second float sort: 0.26 s of
//! 6.3-7.2 on this machine. The ids of an order of at most 2^24 vertices
//! (a 256³ volume, float or 16-bit) held in 3 bytes each took it to
//! 16.4-16.5 and `synthetic:256` from 10.3 to 9.3.

mod arc_vertices;
pub mod blocks;
pub mod json;
pub mod leafward;
mod merge;
pub mod raichel_seshadhri;
pub mod sweep;
#[cfg(test)]
mod vertex_merge;

use crate::field::{Order, OrderView, ScalarField, VertexOrder};
use crate::mesh::Mesh;
use crate::progress::{Cancelled, Progress};
use arc_vertices::VertexLists;
pub use arc_vertices::{ArcVertices, Iter as ArcVerticesIter};
use leafward::{Leafward, Word};
use merge::NODE_FLAG;
use std::time::{Duration, Instant};
use sweep::Census;

/// Index of a supernode in [`ContourTree::nodes`]. Nodes are sorted by the
/// vertex order, so comparing ids compares heights.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(pub u32);

/// Index of a superarc in [`ContourTree::arcs`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ArcId(pub u32);

/// A supernode: a critical vertex of the contour tree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Node {
    /// The mesh vertex.
    pub vertex: u32,
    /// Number of superarcs going up (0 at a maximum, >= 2 at a join; at
    /// most the pieces of a vertex's upper link, 7 in a Freudenthal grid).
    pub up: u16,
    /// Number of superarcs going down (0 at a minimum, >= 2 at a split).
    pub down: u16,
}

/// What kind of critical point a node is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NodeKind {
    /// Local maximum: no arc up.
    Maximum,
    /// Local minimum: no arc down.
    Minimum,
    /// Several arcs up, one down: contours join going down.
    JoinSaddle,
    /// One arc up, several down: a contour splits going down.
    SplitSaddle,
    /// Several arcs up and down (a multi-saddle that is both).
    JoinSplitSaddle,
    /// One up, one down: only the global min/max of a one-vertex tree, or
    /// never otherwise.
    Regular,
}

/// Why a node's degree fits [`Node`]'s 16 bits: it is at most the pieces
/// of a vertex's link.
pub(crate) const DEGREE_FITS: &str = "a node's degree is at most its link's pieces";

impl Node {
    /// Number of superarcs at the node.
    pub fn degree(&self) -> u32 {
        u32::from(self.up) + u32::from(self.down)
    }

    /// The kind of critical point.
    pub fn kind(&self) -> NodeKind {
        match (self.up, self.down) {
            (0, _) => NodeKind::Maximum,
            (_, 0) => NodeKind::Minimum,
            (1, 1) => NodeKind::Regular,
            (1, _) => NodeKind::SplitSaddle,
            (_, 1) => NodeKind::JoinSaddle,
            _ => NodeKind::JoinSplitSaddle,
        }
    }
}

/// A superarc: a monotone path between two supernodes through regular
/// vertices; every point on it stands for one contour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Superarc {
    /// The higher end in the vertex order.
    pub upper: NodeId,
    /// The lower end.
    pub lower: NodeId,
}

/// What lies at a vertex in the augmented tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexPlace {
    /// The vertex is a supernode.
    Node(NodeId),
    /// The vertex is regular, inside this superarc.
    Arc(ArcId),
}

/// The augmented contour tree of a scalar field on a mesh.
#[derive(Clone, Debug)]
pub struct ContourTree {
    nodes: Vec<Node>,
    arcs: Vec<Superarc>,
    /// Per vertex: its superarc, or `NODE_FLAG | node`; in 3 bytes per
    /// vertex where the sweeps' records were packed ([`leafward`]: it is
    /// the first of them, written over by the placement).
    vertex_arc: Leafward,
    /// Regular vertices of arc `a`: `arc_vertices[arc_offsets[a]..arc_offsets[a+1]]`,
    /// ascending in the vertex order (in 3 bytes each for at most 2^24
    /// vertices: [`ArcVertices`]).
    arc_offsets: Vec<u32>,
    arc_vertices: VertexLists,
    /// Arcs at node `v`: `node_arcs[node_offsets[v]..]`, the up arcs first.
    node_offsets: Vec<u32>,
    node_arcs: Vec<ArcId>,
}

/// Seconds spent in each stage of [`ContourTree::from_field`].
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildTimes {
    /// Sorting the vertices.
    pub sort: Duration,
    /// Classifying every vertex's link (part of `sweeps`).
    pub links: Duration,
    /// Join tree sweep (in parallel with the split sweep).
    pub join: Duration,
    /// Split tree sweep.
    pub split: Duration,
    /// Link classification and both sweeps, wall clock.
    pub sweeps: Duration,
    /// Merging into the contour tree.
    pub merge: Duration,
    /// Grouping regular vertices into superarcs.
    pub augment: Duration,
    /// The blocks the join and split trees were swept in (1: the whole
    /// mesh; [`blocks`]).
    pub blocks: usize,
}

impl BuildTimes {
    /// Wall-clock total.
    pub fn total(&self) -> Duration {
        self.sort + self.sweeps + self.merge + self.augment
    }
}

/// Why the tree was not built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum BuildError {
    /// The user (or a newer job) cancelled it.
    #[error("cancelled")]
    Cancelled,
    /// The engine's arrays would not fit in the memory left.
    #[error(
        "the contour tree of these {vertices} vertices needs about {} MiB at its peak beyond the values \
         ({candidates} candidate nodes, {}% of the vertices: each costs {} bytes in the sweeps and \
         about {} at the merge), but only {} MiB are left",
        needed >> 20,
        (*candidates as f64 * 100.0 / (*vertices).max(1) as f64).round(),
        sweep_bytes_per_candidate(*vertices, *candidates),
        merge_bytes_per_candidate(*vertices, *candidates),
        available >> 20
    )]
    OutOfMemory {
        /// Vertices of the mesh.
        vertices: usize,
        /// Its candidate nodes (§4.4), known once the links are classified.
        candidates: usize,
        /// Peak bytes of the engine beyond the values ([`peak_bytes`]).
        needed: u64,
        /// Bytes available when the check ran, plus what the engine already
        /// held then (vertex order and link codes).
        available: u64,
    },
}

impl From<Cancelled> for BuildError {
    fn from(_: Cancelled) -> Self {
        BuildError::Cancelled
    }
}

/// Peak bytes the engine holds beyond the values for `n` vertices whose
/// link classification counted `census` (its candidate nodes, the module
/// doc's account, and extrema), with an order of `order_bytes` (about 1
/// per vertex packed for 8-bit values, else 4:
/// [`crate::field::order_bytes`]), before the sweeps tell how many of the
/// candidates are supernodes: at most twice the extrema
/// ([`sweep::Census::supernodes_at_most`]; [`check_merge_memory`] checks
/// again with the real number). The order, the two sweeps' records and
/// 16 per candidate while sweeping; then the order unless it is let go (`order`, see
/// [`order_at_merge`]) and, at the merge, the records and the candidates'
/// tables ([`merge_table_bytes`]); at the grouping the order (made again if
/// it was let go), `vertex_arc` and the arcs' vertex lists
/// ([`tree_bytes`]). The records take 8 bytes per vertex, or 6 with fewer
/// than 2^23 candidates ([`leafward`]: 3 bytes each from the link pass
/// on; the placement writes `vertex_arc` over the first in its 3 bytes
/// and gives the second back). Where the order is made again, the sort
/// ([`remake_bytes`]: the float sort's (value, id) pairs, 8 bytes per
/// vertex) beside the first record's places and the placed tree's
/// supernodes ([`PLACED_BYTES_PER_SUPERNODE`]).
pub fn peak_bytes(n: usize, census: Census, order_bytes: u64, order: OrderAtMerge) -> u64 {
    let supernodes = census.supernodes_at_most();
    peak_bytes_of(n, census.candidates, supernodes, order_bytes, order)
}

/// [`peak_bytes`] for a build whose join and split trees are swept in
/// blocks with `band` band vertices in all ([`blocks::band_vertices`]; 0
/// for one block), and whether it keeps them: while the blocks are glued
/// the build holds the order, the records and [`GLUE_BYTES_PER_NODE`] per
/// node (candidate or band vertex), [`GLUE_BYTES_PER_BAND_VERTEX`] more
/// per band vertex. Where that would not fit in
/// `available` the build sweeps in one block ([`cuts_that_fit`]), and
/// this is [`peak_bytes`] and false.
pub fn peak_bytes_in_blocks(
    n: usize,
    census: Census,
    order_bytes: u64,
    order: OrderAtMerge,
    band: usize,
    available: Option<u64>,
) -> (u64, bool) {
    let whole = peak_bytes(n, census, order_bytes, order);
    let candidates = census.candidates;
    let held = order_bytes + records_bytes(candidates) * n as u64;
    if band > 0 && glue_fits(candidates, band, held, available) {
        let glue = held.saturating_add(glue_bytes(candidates, band));
        (whole.max(glue), true)
    } else {
        (whole, false)
    }
}

/// [`peak_bytes`] with the number of supernodes known.
fn peak_bytes_of(
    n: usize,
    candidates: usize,
    supernodes: usize,
    order_bytes: u64,
    order: OrderAtMerge,
) -> u64 {
    let records = records_bytes(candidates) * n as u64;
    let sweeps =
        order_bytes + records + sweep_bytes_per_candidate(n, candidates) * candidates as u64;
    sweeps.max(after_sweeps_bytes(
        n,
        candidates,
        supernodes,
        order_bytes,
        order,
    ))
}

/// What the build holds at its peak after the sweeps: the merge (beside
/// the order where it is kept), the grouping, and the sort that makes
/// the order again where it was let go ([`remake_bytes`]).
fn after_sweeps_bytes(
    n: usize,
    candidates: usize,
    supernodes: usize,
    order_bytes: u64,
    order: OrderAtMerge,
) -> u64 {
    let records = records_bytes(candidates) * n as u64;
    let merge = records + merge_table_bytes(n, candidates, supernodes);
    let held = if order == OrderAtMerge::Kept {
        order_bytes
    } else {
        0
    };
    let grouping = order_bytes + tree_bytes(n, candidates) * n as u64;
    let sort = if order == OrderAtMerge::Kept {
        0
    } else {
        let places = records_bytes(candidates) / 2 * n as u64;
        let placed = PLACED_BYTES_PER_SUPERNODE * supernodes as u64;
        remake_bytes(n, order_bytes, order) + places + placed
    };
    (merge + held).max(grouping).max(sort)
}

/// What making the order again holds while it runs: the float sort its
/// (key, id) pairs, 8 bytes per vertex; a counting sort of 16-bit values
/// its ids, 4 bytes per vertex, and where they narrow their 3-byte copy
/// beside them ([`crate::field::Order::Narrow`]); the packed order of
/// 8-bit values about itself.
fn remake_bytes(n: usize, order_bytes: u64, order: OrderAtMerge) -> u64 {
    let n = n as u64;
    match order {
        OrderAtMerge::Kept => 0,
        OrderAtMerge::Sorted => 8 * n,
        OrderAtMerge::Counted if order_bytes == 3 * n => 7 * n,
        OrderAtMerge::Counted => order_bytes,
    }
}

/// What the placed tree holds per supernode while the order is made again
/// after the placement (its nodes, superarcs and their ends): 17.2
/// measured on white noise (`synthetic-noisy:256`, 3.9 M supernodes).
const PLACED_BYTES_PER_SUPERNODE: u64 = 18;

/// The two records' bytes per vertex: 6 packed, else 8 ([`leafward`]).
fn records_bytes(candidates: usize) -> u64 {
    if leafward::packs(candidates) { 6 } else { 8 }
}

/// The finished tree's bytes per vertex: its place (the first record's
/// entry, 3 bytes packed, else 4) and the arcs' vertex lists (3 for at
/// most 2^24 vertices, else 4: [`ArcVertices`]).
fn tree_bytes(n: usize, candidates: usize) -> u64 {
    records_bytes(candidates) / 2 + VertexLists::bytes_per_vertex(n)
}

/// What the candidates' tables hold at the merge's peak: the merge's
/// ([`merge_bytes`]) on every candidate, or, where the candidates regular
/// in both trees are reduced first ([`merge::reduce_regular_candidates`]),
/// the larger of the reduction's 10 per candidate and 9 per supernode and
/// the merge's on the supernodes alone.
fn merge_table_bytes(n: usize, candidates: usize, supernodes: usize) -> u64 {
    let (k, s) = (candidates as u64, supernodes as u64);
    let packed = packs_tables(n, candidates);
    if merge::reduces(n, candidates, supernodes, merge::REDUCED_SHARE) {
        (10 * k + 9 * s).max(merge_bytes(packed, supernodes, supernodes))
    } else {
        merge_bytes(packed, candidates, supernodes)
    }
}

/// What a merge on `merged` candidates, `supernodes` of them supernodes,
/// holds at its peak (the chains: [`merge`]): per candidate its parent,
/// the chains' pointers and answers and its subtree entry, six numbers
/// (18 bytes where they are `packed`, [`leafward::packs_tables`], else 24),
/// and per supernode its vertex and its superarc (12), with a quarter
/// more for the heap: measured within it on tooth (34.7 bytes per
/// supernode, packed, where it counts 30) and engine (29.5 per candidate,
/// in words, where it counts 29.7).
fn merge_bytes(packed: bool, merged: usize, supernodes: usize) -> u64 {
    let per = if packed { 18 } else { 24 };
    (per * merged as u64 + 12 * supernodes as u64) * 5 / 4
}

/// What a candidate node costs at the merge's peak, bytes, where half of
/// them are supernodes and none is reduced: 30 where the tables pack, 37
/// otherwise.
fn merge_bytes_per_candidate(n: usize, candidates: usize) -> u64 {
    let k = candidates.max(2);
    merge_bytes(packs_tables(n, k), k, k / 2) / k as u64
}

/// True where a build of `n` vertices and this many candidates holds the
/// candidates' tables in 3 bytes per number ([`leafward::packs_tables`]).
fn packs_tables(n: usize, candidates: usize) -> bool {
    leafward::packs_tables(n, candidates, leafward::PACKED_TABLES_SHARE)
}

/// What a candidate node costs while both sweeps run: per sweep its
/// union-find entry (3 bytes where the tables pack, else 4) and its
/// parent ([`sweep`]; the children counts come once the union-finds are
/// let go). Where the records are words, each candidate's parent is
/// written into its record ([`sweep::parents_in_words`]): the union-finds'
/// 8 while sweeping, then both trees' parents and children, 10.
fn sweep_bytes_per_candidate(n: usize, candidates: usize) -> u64 {
    if packs_tables(n, candidates) {
        14
    } else if sweep::parents_in_words(n, candidates, None) {
        10
    } else {
        16
    }
}

/// What a node of the blocks (a candidate or a band vertex) costs beyond
/// the order and the records while the blocks are glued, both directions
/// at once ([`blocks`]: the glue's lists, union-find, parents and lowest
/// candidates, beside the nodes' vertices and order, and the blocks'
/// trees and union-finds before it): 57 and 73 bytes measured on tooth in
/// 2 and 8 blocks.
const GLUE_BYTES_PER_NODE: u64 = 80;

/// What a band vertex costs beyond that: the mesh edges across its cut,
/// listed for both directions. `synthetic:256` in 8 blocks (918 K band
/// vertices, a thousand candidates) peaked at 113 bytes per node beyond
/// the order and the records.
const GLUE_BYTES_PER_BAND_VERTEX: u64 = 40;

/// What gluing blocks holds beyond the order and the records, with
/// `band` band vertices in all.
fn glue_bytes(candidates: usize, band: usize) -> u64 {
    GLUE_BYTES_PER_NODE.saturating_mul((candidates + band) as u64)
        + GLUE_BYTES_PER_BAND_VERTEX.saturating_mul(band as u64)
}

/// True where the glue fits in the memory `available` beside the `held`
/// bytes (none known: it fits).
fn glue_fits(candidates: usize, band: usize, held: u64, available: Option<u64>) -> bool {
    available.is_none_or(|a| held.saturating_add(glue_bytes(candidates, band)) <= a)
}

/// The cuts a build sweeps with: `cuts`, unless gluing their blocks would
/// not fit in the memory `available` beyond what the build holds already
/// (the order and the records), and then one block, the whole mesh, which
/// gives the same trees. Where candidates are many (a noisy scan) the
/// glue holds more than the whole sweep: tooth peaks at 29 bytes per
/// vertex in 2 blocks and 39 in 8, 13.6 in one.
fn cuts_that_fit<'a>(
    cuts: &'a [u32],
    whole: &'a [u32; 2],
    candidates: usize,
    band: usize,
    available: Option<u64>,
) -> &'a [u32] {
    // The memory left is read with the order and the records held.
    if cuts.len() > 2 && !glue_fits(candidates, band, 0, available) {
        whole
    } else {
        cuts
    }
}

/// What becomes of the vertex order while the tree is merged: neither
/// the reduction, the merge nor the placement reads it, so a build that
/// can make it again lets it go before them and sorts again before the
/// grouping ([`order_at_merge`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OrderAtMerge {
    /// Held from the sort to the grouping.
    Kept,
    /// Let go and made again by a counting sort (8- and 16-bit values,
    /// O(n)).
    Counted,
    /// Let go and made again by the float sort (32-bit keys: a radix sort
    /// of (key, id) pairs, 8 bytes per vertex while it runs; 64-bit: a
    /// comparison sort of the ids).
    Sorted,
}

/// Whether a build lets the vertex order go during the merge, and how it
/// makes it again. Where the order is a counting sort (`counting`: 8- and
/// 16-bit values, O(n)), wherever the merge, without the order, would
/// still be above the grouping ([`peak_bytes`]), so that some of the
/// order's cost comes off the peak. With packed records ([`leafward`])
/// that takes the
/// merge's tables above a byte per vertex (the merge's 6 bytes per vertex
/// and its tables above the grouping's 7, whose lists now take 3 bytes per
/// id where the vertices are at most 2^24, so that the tables' whole
/// byte per vertex comes off, at least the packed 8-bit order's
/// cost): more than 1/37.5 of the
/// vertices as candidates, with half of them supernodes (at most twice
/// the extrema, [`sweep::Census::supernodes_at_most`]; [`merge_bytes`];
/// 1/44 before session 39, 1/22 while the grouping held 8, before session
/// 38). Otherwise (8 bytes per vertex in the records and
/// in the grouping) where they are above 2/3 of a byte per vertex: the
/// merge is then the peak by that much, worth a counting sort. A float
/// sort costs more (on white noise, `synthetic-noisy:256`, about as much
/// as the link pass): it is made again where that takes at least a byte
/// per vertex off the peak, the float sort's own pairs counted. That is
/// a noisy float field: white noise's merge held its 4-byte order beside
/// the records and about 45 bytes per supernode (23 % of the vertices).
/// Smooth fields keep it. Volumes of fewer than [`REMAKE_MIN_VERTICES`]
/// keep their order.
pub fn order_at_merge(n: usize, census: Census, counting: bool) -> OrderAtMerge {
    if n < REMAKE_MIN_VERTICES {
        return OrderAtMerge::Kept;
    }
    if !counting {
        let order_bytes = crate::field::ids_bytes(n) * n as u64;
        let kept = peak_bytes(n, census, order_bytes, OrderAtMerge::Kept);
        let sorted = peak_bytes(n, census, order_bytes, OrderAtMerge::Sorted);
        return if sorted + n as u64 <= kept {
            OrderAtMerge::Sorted
        } else {
            OrderAtMerge::Kept
        };
    }
    let (candidates, supernodes) = (census.candidates, census.supernodes_at_most());
    let tables = merge_bytes(packs_tables(n, candidates), candidates, supernodes);
    let above = if leafward::packs(candidates) {
        tables > n as u64
    } else {
        3 * tables > 2 * n as u64
    };
    if above {
        OrderAtMerge::Counted
    } else {
        OrderAtMerge::Kept
    }
}

/// Below this many vertices an order let go does not lower the peak: its
/// allocation (about a byte per vertex) is under the program's 1 MiB
/// `M_MMAP_THRESHOLD` ([`crate::pages`]), carved from the heap, whose
/// freed pages stay resident, and the order made again takes new ones.
/// `marschner_lobb` (69 K vertices, 3.4 % candidates) peaked at 16.2-16.5
/// bytes per vertex with its order remade, 11-13 without.
const REMAKE_MIN_VERTICES: usize = 1 << 20;

/// Refuses a build whose peak ([`peak_bytes`]) exceeds what is `available`
/// once the vertex order and the link codes in the sweeps' words
/// (`order_bytes` and 6 or 8 per vertex, already held) are counted back in: a
/// clear error instead of an allocation failure halfway through, on
/// volumes that are large *and* noisy.
pub fn check_memory(
    n: usize,
    census: Census,
    order_bytes: u64,
    order: OrderAtMerge,
    available: u64,
) -> Result<(), BuildError> {
    let candidates = census.candidates;
    let needed = peak_bytes(n, census, order_bytes, order);
    let held = order_bytes + records_bytes(candidates) * n as u64;
    refuse_beyond(n, candidates, needed, available.saturating_add(held))
}

/// [`check_memory`] again once the sweeps are done and the `supernodes`
/// are known: what is left to build (the merge and the grouping) against
/// what is `available` now plus what the build holds already (the order
/// unless it is let go, the records, and 10 bytes per candidate: both
/// trees' parents and child counts; the candidates' vertices are read off
/// the split tree's record later).
pub fn check_merge_memory(
    n: usize,
    candidates: usize,
    supernodes: usize,
    order_bytes: u64,
    order: OrderAtMerge,
    available: u64,
) -> Result<(), BuildError> {
    let records = records_bytes(candidates) * n as u64;
    let needed = after_sweeps_bytes(n, candidates, supernodes, order_bytes, order);
    let held = order_bytes + records + 10 * candidates as u64;
    refuse_beyond(n, candidates, needed, available.saturating_add(held))
}

fn refuse_beyond(
    vertices: usize,
    candidates: usize,
    needed: u64,
    available: u64,
) -> Result<(), BuildError> {
    if needed > available {
        return Err(BuildError::OutOfMemory {
            vertices,
            candidates,
            needed,
            available,
        });
    }
    Ok(())
}

/// The vertex order a build sweeps in.
enum OrderSource<'a> {
    /// The caller's, held for the whole build.
    Borrowed(&'a [u32]),
    /// The build's own, with a way to make it again if it may be let go
    /// during the merge ([`order_at_merge`]) and whether that way is a
    /// counting sort.
    Owned(Order, Option<(&'a (dyn Fn() -> Order + Sync), bool)>),
}

impl OrderSource<'_> {
    fn order(&self) -> OrderView<'_> {
        match self {
            OrderSource::Borrowed(order) => OrderView::Ids(order),
            OrderSource::Owned(order, _) => order.view(),
        }
    }

    /// Frees an owned order (until it is made again).
    fn let_go(&mut self) {
        if let OrderSource::Owned(order, _) = self {
            *order = Order::Ids(Vec::new());
        }
    }
}

impl ContourTree {
    /// Builds the tree of a grid field on its Freudenthal triangulation.
    pub fn from_field(
        field: &ScalarField,
        progress: &Progress,
    ) -> Result<(Self, BuildTimes), BuildError> {
        Self::from_field_cut(field, None, progress)
    }

    /// Builds the tree of a grid field with its join and split trees
    /// computed in `blocks` blocks ([`blocks`]); the same tree as
    /// [`Self::from_field`], which picks the number for the machine.
    pub fn from_field_in_blocks(
        field: &ScalarField,
        blocks: usize,
        progress: &Progress,
    ) -> Result<(Self, BuildTimes), BuildError> {
        Self::from_field_cut(field, Some(blocks), progress)
    }

    /// [`Self::from_field_in_blocks`] in `count` blocks, or with none given,
    /// in the blocks chosen for the machine ([`blocks::chosen_blocks`]).
    fn from_field_cut(
        field: &ScalarField,
        count: Option<usize>,
        progress: &Progress,
    ) -> Result<(Self, BuildTimes), BuildError> {
        let t = Instant::now();
        progress.stage("sort");
        let order = field.compact_vertex_order();
        let sort = t.elapsed();
        let mesh = field.mesh();
        let cuts = count.map(|b| blocks::even_cuts(field.len(), b));
        let remake = || field.compact_vertex_order();
        let counting = crate::field::sorts_by_counting(field.values());
        let source = OrderSource::Owned(order, Some((&remake, counting)));
        let (tree, mut times) = crate::with_values!(field.values(), v => Self::build_from(&mesh, v.as_slice(), source, cuts.as_deref(), merge::MERGING, progress))?;
        times.sort += sort;
        Ok((tree, times))
    }

    /// Builds the tree of any mesh given its vertex order: `values` compares
    /// two vertices, `order` lists them ascending. Blocks as
    /// [`blocks::chosen_blocks`] says.
    pub fn build<M: Mesh, O: VertexOrder + ?Sized>(
        mesh: &M,
        values: &O,
        order: &[u32],
        progress: &Progress,
    ) -> Result<(Self, BuildTimes), BuildError> {
        let order = OrderSource::Borrowed(order);
        Self::build_from(mesh, values, order, None, merge::MERGING, progress)
    }

    /// [`Self::build`] with the join and split trees computed in the blocks
    /// of consecutive ids that `cuts` bounds (`0 = cuts[0] < ... = n`),
    /// then glued ([`blocks`]): the same tree for any cuts.
    pub fn build_in_blocks<M: Mesh, O: VertexOrder + ?Sized>(
        mesh: &M,
        values: &O,
        order: &[u32],
        cuts: &[u32],
        progress: &Progress,
    ) -> Result<(Self, BuildTimes), BuildError> {
        Self::build_from(
            mesh,
            values,
            OrderSource::Borrowed(order),
            Some(cuts),
            merge::MERGING,
            progress,
        )
    }

    /// [`Self::build_in_blocks`] with the order borrowed or owned: an owned
    /// order that can be made again may be let go during the merge. With
    /// no `cuts` given, the blocks are chosen for the machine once the
    /// candidates are counted ([`blocks::chosen_blocks`]). The candidates
    /// regular in both trees are reduced before the merge when at least
    /// one vertex in `merging.reduce_share` is one
    /// ([`merge::reduce_regular_candidates`]), and the merge's tables
    /// packed where `merging.packed` (the tests force each way).
    fn build_from<M: Mesh, O: VertexOrder + ?Sized>(
        mesh: &M,
        values: &O,
        mut source: OrderSource<'_>,
        cuts: Option<&[u32]>,
        merging: merge::Merging,
        progress: &Progress,
    ) -> Result<(Self, BuildTimes), BuildError> {
        let order = source.order();
        assert_eq!(mesh.num_vertices(), order.len(), "order covers the mesh");
        let order_bytes = order.bytes();
        let mut times = BuildTimes::default();
        if order.is_empty() {
            return Ok((
                Self::assemble(Vec::new(), Vec::new(), Vec::new(), vec![0], Vec::new()),
                times,
            ));
        }
        progress.stage("join and split trees");
        let t = Instant::now();
        let words = sweep::link_words(mesh, values);
        let census = words.census;
        let candidates = census.candidates;
        times.links = t.elapsed();
        let n = mesh.num_vertices();
        // An owned order comes with a way to make it again.
        let (remake, order_plan) = match &source {
            OrderSource::Owned(_, Some((remake, counting))) => {
                match order_at_merge(n, census, *counting) {
                    OrderAtMerge::Kept => (None, OrderAtMerge::Kept),
                    plan => (Some(*remake), plan),
                }
            }
            _ => (None, OrderAtMerge::Kept),
        };
        let available = crate::field::io::available_memory();
        if let Some(available) = available {
            check_memory(n, census, order_bytes, order_plan, available)?;
        }
        let whole = [0, n as u32];
        let span = mesh.edge_span();
        let chosen;
        let cuts = match cuts {
            Some(cuts) => cuts,
            None => {
                chosen = blocks::even_cuts(n, blocks::chosen_blocks(n, span, candidates));
                &chosen
            }
        };
        let band = blocks::band_vertices(cuts, n, span);
        let cuts = cuts_that_fit(cuts, &whole, candidates, band, available);
        let parents_in_words = sweep::parents_in_words(n, candidates, merging.parents_in_words);
        let ((mut join, tj), (mut split, ts)) =
            blocks::sweep_trees(mesh, values, words, order, cuts, parents_in_words, progress)?;
        progress.check(0, 1)?;
        times.join = tj;
        times.split = ts;
        times.blocks = cuts.len() - 1;
        times.sweeps = t.elapsed();
        let supernodes = merge::Supernodes::of_trees(&join, &split);
        if let Some(available) = crate::field::io::available_memory() {
            let s = supernodes.count();
            check_merge_memory(n, candidates, s, order_bytes, order_plan, available)?;
        }
        progress.stage("merge");
        let t = Instant::now();
        // Neither the reduction nor the merge reads the order.
        if remake.is_some() {
            source.let_go();
        }
        // Empty where the sweeps left them in the split tree's record
        // (one block): read off it, once the order is let go.
        let candidate_vertex = std::mem::take(&mut split.0.vertex);
        // Held through the merge in 3 bytes per vertex where they fit.
        let empty = || Leafward::Words(Vec::new());
        let mut join_leafward = std::mem::replace(&mut join.0.leafward, empty());
        let mut split_leafward = std::mem::replace(&mut split.0.leafward, empty());
        let (candidate_vertex, supernodes) = merge::reduce_regular_candidates(
            &mut join,
            &mut split,
            candidate_vertex,
            supernodes,
            &mut join_leafward,
            &mut split_leafward,
            merging.reduce_share,
        );
        let packed = leafward::packs_tables(n, candidates, merging.packed_share);
        let merged = merge::merge(join, split, candidate_vertex, supernodes, packed, progress)?;
        times.merge = t.elapsed();
        progress.stage("augment");
        let t = Instant::now();
        let placed = merge::place(merged, join_leafward, split_leafward);
        times.augment = t.elapsed();
        if let Some(remake) = remake {
            progress.stage("sort");
            let t = Instant::now();
            source = OrderSource::Owned(remake(), None);
            times.sort += t.elapsed();
            progress.stage("augment");
        }
        let t = Instant::now();
        // The order is not needed past the grouping: it goes before the
        // tree's node adjacency is made (an order of ids as it is read).
        let grouped = match source {
            OrderSource::Owned(order, _) => merge::group_owned(placed, order, values),
            source => merge::group(placed, source.order(), values),
        };
        let tree = grouped.into_tree();
        times.augment += t.elapsed();
        Ok((tree, times))
    }

    pub(crate) fn assemble(
        nodes: Vec<Node>,
        arcs: Vec<Superarc>,
        vertex_arc: Vec<u32>,
        arc_offsets: Vec<u32>,
        arc_vertices: Vec<u32>,
    ) -> Self {
        let arc_vertices = VertexLists::of_ids(arc_vertices, vertex_arc.len());
        let vertex_arc = Leafward::Words(vertex_arc);
        Self::assemble_places(nodes, arcs, vertex_arc, arc_offsets, arc_vertices)
    }

    /// [`Self::assemble`] with the places as the placement leaves them.
    pub(crate) fn assemble_places(
        nodes: Vec<Node>,
        arcs: Vec<Superarc>,
        mut vertex_arc: Leafward,
        arc_offsets: Vec<u32>,
        arc_vertices: VertexLists,
    ) -> Self {
        // Canonical arc order: by lower node, then upper node. Renumber.
        if arcs.is_sorted_by_key(|a| (a.lower, a.upper)) {
            // Already canonical (the candidate merge makes them so): no copy.
            return Self::with_adjacency(nodes, arcs, vertex_arc, arc_offsets, arc_vertices);
        }
        let mut perm: Vec<u32> = (0..arcs.len() as u32).collect();
        perm.sort_unstable_by_key(|&a| (arcs[a as usize].lower, arcs[a as usize].upper));
        let mut new_id = vec![0u32; arcs.len()];
        for (new, &old) in perm.iter().enumerate() {
            new_id[old as usize] = new as u32;
        }
        let sorted_arcs: Vec<Superarc> = perm.iter().map(|&a| arcs[a as usize]).collect();
        let mut offsets = vec![0u32; arcs.len() + 1];
        for (new, &old) in perm.iter().enumerate() {
            offsets[new + 1] =
                offsets[new] + arc_offsets[old as usize + 1] - arc_offsets[old as usize];
        }
        fn regroup<T: Copy>(ids: Vec<T>, perm: &[u32], old_offsets: &[u32]) -> Vec<T> {
            let mut out = Vec::with_capacity(ids.len());
            for &old in perm {
                let r = old_offsets[old as usize] as usize..old_offsets[old as usize + 1] as usize;
                out.extend_from_slice(&ids[r]);
            }
            out
        }
        let verts = match arc_vertices {
            VertexLists::Wide(ids) => VertexLists::Wide(regroup(ids, &perm, &arc_offsets)),
            VertexLists::Narrow(ids) => VertexLists::Narrow(regroup(ids, &perm, &arc_offsets)),
        };
        leafward::with_words!(&mut vertex_arc, places => for va in places.iter_mut() {
            let place = Word::get(*va);
            if place & NODE_FLAG == 0 {
                *va = Word::of(new_id[place as usize]);
            }
        });
        Self::with_adjacency(nodes, sorted_arcs, vertex_arc, offsets, verts)
    }

    /// The tree from arcs in canonical order, with each node's arcs listed.
    fn with_adjacency(
        nodes: Vec<Node>,
        sorted_arcs: Vec<Superarc>,
        vertex_arc: Leafward,
        offsets: Vec<u32>,
        verts: VertexLists,
    ) -> Self {
        // Node adjacency: up arcs (where the node is the lower end) first,
        // filled with no cursor array beside the offsets. Node `i`'s offset
        // slot `i + 1` starts as the cursor of its down arcs, after its up
        // arcs, and ends as the start of node `i + 1` once they are all in.
        let mut node_offsets = vec![0u32; nodes.len() + 1];
        for (i, n) in nodes.iter().enumerate() {
            node_offsets[i + 1] = node_offsets[i] + n.degree();
        }
        let mut node_arcs = vec![ArcId(0); node_offsets[nodes.len()] as usize];
        for (i, n) in nodes.iter().enumerate().rev() {
            node_offsets[i + 1] = node_offsets[i] + u32::from(n.up);
        }
        for (a, arc) in sorted_arcs.iter().enumerate() {
            let cursor = &mut node_offsets[arc.upper.0 as usize + 1];
            node_arcs[*cursor as usize] = ArcId(a as u32);
            *cursor += 1;
        }
        // Each node's up arcs are one run of the arcs (sorted by lower end),
        // in order.
        let mut run = (u32::MAX, 0u32);
        for (a, arc) in sorted_arcs.iter().enumerate() {
            let l = arc.lower.0;
            run = if run.0 == l { (l, run.1 + 1) } else { (l, 0) };
            node_arcs[(node_offsets[l as usize] + run.1) as usize] = ArcId(a as u32);
        }
        Self {
            nodes,
            arcs: sorted_arcs,
            vertex_arc,
            arc_offsets: offsets,
            arc_vertices: verts,
            node_offsets,
            node_arcs,
        }
    }

    /// The supernodes, ascending in the vertex order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// One supernode.
    pub fn node(&self, id: NodeId) -> &Node {
        &self.nodes[id.0 as usize]
    }

    /// The superarcs, sorted by (lower, upper).
    pub fn arcs(&self) -> &[Superarc] {
        &self.arcs
    }

    /// One superarc.
    pub fn arc(&self, id: ArcId) -> &Superarc {
        &self.arcs[id.0 as usize]
    }

    /// Number of mesh vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertex_arc.len()
    }

    /// Where each superarc's regular vertices start in one list of all of
    /// them (one more entry than arcs, the last the total): for splitting
    /// work over the arcs by the vertices they hold.
    pub fn arc_vertex_offsets(&self) -> &[u32] {
        &self.arc_offsets
    }

    /// The regular vertices of a superarc, ascending in the vertex order
    /// (its ends, the supernodes, are not included).
    pub fn arc_vertices(&self, id: ArcId) -> ArcVertices<'_> {
        let a = id.0 as usize;
        self.arc_vertices
            .slice(self.arc_offsets[a] as usize..self.arc_offsets[a + 1] as usize)
    }

    /// Where vertex `v` lies: on a superarc or at a supernode.
    #[inline]
    pub fn place(&self, v: u32) -> VertexPlace {
        let va = self.vertex_arc.get(v as usize);
        if va & NODE_FLAG != 0 {
            VertexPlace::Node(NodeId(va & !NODE_FLAG))
        } else {
            VertexPlace::Arc(ArcId(va))
        }
    }

    /// The superarcs going up from a node (the node is their lower end).
    pub fn up_arcs(&self, id: NodeId) -> &[ArcId] {
        let i = id.0 as usize;
        let s = self.node_offsets[i] as usize;
        &self.node_arcs[s..s + self.nodes[i].up as usize]
    }

    /// The superarcs going down from a node (the node is their upper end).
    pub fn down_arcs(&self, id: NodeId) -> &[ArcId] {
        let i = id.0 as usize;
        let s = self.node_offsets[i] as usize + self.nodes[i].up as usize;
        &self.node_arcs[s..self.node_offsets[i + 1] as usize]
    }

    /// All superarcs at a node, the up arcs first: [`Self::up_arcs`]
    /// then [`Self::down_arcs`].
    pub fn node_arcs(&self, id: NodeId) -> &[ArcId] {
        let i = id.0 as usize;
        &self.node_arcs[self.node_offsets[i] as usize..self.node_offsets[i + 1] as usize]
    }

    /// Hints the cache that [`Self::node_arcs`] of this node will be read
    /// soon (its offsets; the list itself is a second, dependent read).
    pub(crate) fn prefetch_node_arcs(&self, id: NodeId) {
        sweep::prefetch(&self.node_offsets, id.0 as usize);
    }

    /// Count of nodes of each kind: (maxima, minima, join saddles, split
    /// saddles). A node that is both a join and a split counts as both.
    pub fn kind_counts(&self) -> (usize, usize, usize, usize) {
        let mut c = (0, 0, 0, 0);
        for n in &self.nodes {
            if n.up == 0 {
                c.0 += 1;
            }
            if n.down == 0 {
                c.1 += 1;
            }
            if n.up >= 2 {
                c.2 += 1;
            }
            if n.down >= 2 {
                c.3 += 1;
            }
        }
        c
    }

    /// Heap bytes held by the tree.
    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<Node>()
            + self.arcs.capacity() * size_of::<Superarc>()
            + self.vertex_arc.heap_bytes()
            + self.arc_vertices.heap_bytes()
            + (self.arc_offsets.capacity()
                + self.node_offsets.capacity()
                + self.node_arcs.capacity())
                * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `k` candidates of which at most half are supernodes (twice as many
    /// as a quarter of them extrema).
    fn half(k: usize) -> Census {
        Census {
            candidates: k,
            extrema: k / 4 + 1,
        }
    }

    #[test]
    fn supernodes_are_at_most_twice_the_extrema_and_never_more_than_the_candidates() {
        let census = |candidates, extrema| Census {
            candidates,
            extrema,
        };
        assert_eq!(census(100, 10).supernodes_at_most(), 18);
        assert_eq!(census(100, 60).supernodes_at_most(), 100);
        assert_eq!(census(2, 2).supernodes_at_most(), 2);
        // One vertex, and a mesh that reports no extrema: the candidates.
        assert_eq!(census(1, 1).supernodes_at_most(), 1);
        assert_eq!(census(50, 0).supernodes_at_most(), 50);
    }

    #[test]
    fn blocks_are_swept_only_where_their_glue_fits() {
        let whole = [0, 1000];
        let cuts = [0, 400, 700, 1000];
        // 300 candidates and 60 band vertices: 80 bytes each, and 40 more
        // a band vertex.
        let glue = 360 * GLUE_BYTES_PER_NODE + 60 * GLUE_BYTES_PER_BAND_VERTEX;
        assert_eq!(cuts_that_fit(&cuts, &whole, 300, 60, Some(glue)), cuts);
        assert_eq!(cuts_that_fit(&cuts, &whole, 300, 60, Some(glue - 1)), whole);
        assert_eq!(cuts_that_fit(&cuts, &whole, 300, 60, None), cuts);
        // One block stays one block.
        assert_eq!(cuts_that_fit(&whole, &whole, 300, 0, Some(0)), whole);
        // Bands: one plane, one row and one step on either side of a cut.
        assert_eq!(blocks::band_vertices(&cuts, 1000, 10), 4 * 10);
        assert_eq!(blocks::band_vertices(&whole, 1000, 10), 0);
        // A block thinner than two spans is all band.
        assert_eq!(blocks::band_vertices(&[0, 500, 505, 1000], 1000, 10), 25);
    }

    #[test]
    fn blocks_add_their_glue_to_the_peak_where_it_fits() {
        let (n, k, order) = (1_000_000, 300_000, 1_000_000);
        let whole = peak_bytes(n, half(k), order, OrderAtMerge::Kept);
        let peak = |k, band, available| {
            peak_bytes_in_blocks(n, half(k), order, OrderAtMerge::Kept, band, available)
        };
        assert_eq!(peak(k, 0, None), (whole, false));
        // A third of the vertices candidates: the glue is the peak.
        let glue = order + 6 * n as u64 + glue_bytes(k, 20_000);
        assert!(glue > whole);
        assert_eq!(peak(k, 20_000, None), (glue, true));
        assert_eq!(peak(k, 20_000, Some(glue)), (glue, true));
        // Where it does not fit, the build sweeps in one block.
        assert_eq!(peak(k, 20_000, Some(glue - 1)), (whole, false));
        // Few candidates (a smooth field): the glue's peak is just above
        // the whole build's (the grouping's order, places and lists in 3
        // bytes each: the sweeps' order and 6).
        let smooth = peak_bytes(n, half(100), order, OrderAtMerge::Kept);
        let glue = order + 6 * n as u64 + glue_bytes(100, 2_000);
        assert_eq!(peak(100, 2_000, None), (smooth.max(glue), true));
    }

    #[test]
    fn memory_check_follows_the_candidates() {
        let gib = 1u64 << 30;
        let n = 1usize << 30; // 1024^3 uint8: the order packed in at most 2 bytes
        let order = 2 * n as u64;
        // A scan or smooth field (2 % candidates): 10.9 bytes per vertex.
        assert!(check_memory(n, half(n / 50), order, OrderAtMerge::Kept, 12 * gib).is_ok());
        // The same volume noisy (28 % candidates, half of them supernodes,
        // so the other 14 % are reduced before the merge): the sweeps hold
        // 12.8 bytes per vertex (each candidate's parent in its record: 10
        // per candidate), the merge on the supernodes 14.3 with the order
        // let go and remade (4.3 GiB left beside the 10 already held), not
        // with 4.29; held through the merge, the merge's 16.3 (its tables
        // in 4 bytes per number: over 2^24 candidates) need 6.3.
        let noisy = n * 28 / 100;
        assert!(check_memory(n, half(noisy), order, OrderAtMerge::Counted, 12 * gib).is_ok());
        assert!(
            check_memory(
                n,
                half(noisy),
                order,
                OrderAtMerge::Counted,
                4310 * (gib / 1000)
            )
            .is_ok()
        );
        assert!(
            check_memory(
                n,
                half(noisy),
                order,
                OrderAtMerge::Counted,
                4290 * (gib / 1000)
            )
            .is_err()
        );
        assert!(
            check_memory(
                n,
                half(noisy),
                order,
                OrderAtMerge::Kept,
                6310 * (gib / 1000)
            )
            .is_ok()
        );
        assert!(
            check_memory(
                n,
                half(noisy),
                order,
                OrderAtMerge::Kept,
                6290 * (gib / 1000)
            )
            .is_err()
        );
        let e =
            check_memory(n, half(noisy), order, OrderAtMerge::Kept, 6 * gib).expect_err("refused");
        let BuildError::OutOfMemory {
            needed, available, ..
        } = e
        else {
            panic!("refused for memory")
        };
        assert_eq!(
            needed,
            peak_bytes(n, half(noisy), order, OrderAtMerge::Kept)
        );
        assert_eq!(available, 6 * gib + 10 * n as u64);
        assert_eq!(
            needed,
            peak_bytes_of(n, noisy, 2 * (noisy / 4), order, OrderAtMerge::Kept)
        );
        let message = e.to_string();
        assert!(message.contains("28%"), "{message}");
        assert!(message.contains("candidate nodes"), "{message}");
        assert!(message.contains("10 bytes in the sweeps"), "{message}");
        assert!(message.contains("about 37 at the merge"), "{message}");
        // Once the sweeps tell the supernodes: 8 % (the noisy 1024³ scan
        // of the README) are reduced to and the merge needs no more than
        // the sweeps held (11.6 bytes per vertex); 20 % are not, and the
        // merge on all candidates needs 19.4, 6.6 GiB beyond the 12.8 held.
        let (few, many) = (n * 8 / 100, n * 20 / 100);
        let (counted, kept) = (OrderAtMerge::Counted, OrderAtMerge::Kept);
        let merge_fits = |supernodes, plan, thousandths: u64| {
            let available = thousandths * (gib / 1000);
            check_merge_memory(n, noisy, supernodes, order, plan, available).is_ok()
        };
        assert!(merge_fits(few, counted, 0));
        assert!(merge_fits(many, counted, 6610));
        assert!(!merge_fits(many, counted, 6590));
        // Held through the merge, the order needs its 2 more.
        assert!(!merge_fits(many, kept, 8590));
        assert!(merge_fits(many, kept, 8610));
        // Fewer than 2^24 candidates: the tables in 3 bytes per number,
        // 30 bytes per candidate where half are supernodes.
        assert_eq!(merge_bytes_per_candidate(1 << 22, 1 << 20), 30);
        assert_eq!(merge_bytes_per_candidate(1 << 24, 1 << 20), 37);
        assert_eq!(merge_bytes_per_candidate(n, noisy), 37);
        // Exactly at the limit is allowed, a byte more is not.
        for per_vertex in [1, 2, 4] {
            let order_bytes = per_vertex * 1000;
            // The order and the packed records, 6 bytes per vertex.
            let held = order_bytes + 6 * 1000;
            let peak = peak_bytes(1000, half(10), order_bytes, OrderAtMerge::Kept);
            assert!(
                check_memory(1000, half(10), order_bytes, OrderAtMerge::Kept, peak - held).is_ok()
            );
            assert!(
                check_memory(
                    1000,
                    half(10),
                    order_bytes,
                    OrderAtMerge::Kept,
                    peak - held - 1
                )
                .is_err()
            );
        }
    }

    #[test]
    fn the_order_is_let_go_only_where_it_lowers_the_peak() {
        let n = REMAKE_MIN_VERTICES;
        let (kept, counted, sorted) = (
            OrderAtMerge::Kept,
            OrderAtMerge::Counted,
            OrderAtMerge::Sorted,
        );
        let remakes_order = |n, k, counting| order_at_merge(n, half(k), counting) != kept;
        assert!(
            !remakes_order(n - 1, n / 4, true),
            "a small volume keeps it"
        );
        assert!(!remakes_order(n - 1, n / 2, false));
        // Smooth fields keep it; counting sorts with many
        // candidates let it go, and the peak drops by up to the order's
        // bytes per vertex. With the records packed (fewer than 2^23
        // candidates, the tables in 4 bytes per number: fewer than 1/8),
        // below 1/37.5 of the vertices the grouping or the sweeps stay the
        // peak.
        assert!(!remakes_order(n, n / 100, true));
        assert_eq!(order_at_merge(n, half(n / 4), true), counted);
        assert!(!remakes_order(n, n / 40, true));
        assert!(remakes_order(n, n / 36, true));
        let huge = 1usize << 30;
        assert!(remakes_order(huge, huge / 50, true), "unpacked: 1/56");
        assert!(!remakes_order(huge, huge / 60, true), "unpacked: 1/56");
        // A float sort is made again only where it takes a byte per vertex
        // off the peak: white noise (half the vertices candidates), noisy
        // fields whose order is 4 bytes per vertex, not smooth ones.
        assert_eq!(order_at_merge(huge, half(huge / 4), false), sorted);
        assert_eq!(
            order_at_merge(n, half(n / 4), false),
            kept,
            "narrow: 3 bytes"
        );
        for n in [n, 1 << 24, huge] {
            assert_eq!(order_at_merge(n, half(n / 2), false), sorted, "{n}");
            assert_eq!(order_at_merge(n, half(n / 100), false), kept, "{n}");
            assert_eq!(order_at_merge(n, half(1000), false), kept, "{n}");
            for k in [n / 2, n / 4, n / 10, n / 20, n / 100] {
                let order_bytes = crate::field::ids_bytes(n) * n as u64;
                let peak = |order| peak_bytes(n, half(k), order_bytes, order);
                if order_at_merge(n, half(k), false) == sorted {
                    assert!(peak(sorted) + n as u64 <= peak(kept), "{n} {k}");
                } else {
                    assert!(peak(sorted) + n as u64 > peak(kept), "{n} {k}");
                }
                // The float sort's pairs are counted: never below the
                // order's own grouping.
                assert!(peak(sorted) >= peak(counted), "{n} {k}");
            }
        }
        for per_vertex in [1, 2, 4] {
            let order_bytes = per_vertex * n as u64;
            for k in [n / 36, n / 20, n / 16, n / 4, n / 2] {
                let held = peak_bytes(n, half(k), order_bytes, kept);
                let remade = peak_bytes(n, half(k), order_bytes, counted);
                assert!(remade < held, "{k}");
                assert!(held - remade <= order_bytes, "{k}");
            }
            // Below, less than a byte per vertex would come off (none
            // without candidates).
            for k in [0, n / 64, n / 50, n / 40] {
                let held = peak_bytes(n, half(k), order_bytes, kept);
                let remade = peak_bytes(n, half(k), order_bytes, counted);
                assert!(held - remade < n as u64, "{k}");
                assert_eq!(k == 0, held == remade, "{k}");
            }
            let (k, order_bytes) = (huge / 50, per_vertex * huge as u64);
            assert!(
                peak_bytes(huge, half(k), order_bytes, counted)
                    < peak_bytes(huge, half(k), order_bytes, kept)
            );
        }
        // A counting sort of 16-bit values holds its ids beside their
        // narrow copy: 7 bytes per vertex, then the 3 of the order.
        let (k, narrow) = (n / 2, 3 * n as u64);
        let placed = 3 * n as u64 + PLACED_BYTES_PER_SUPERNODE * (k / 2) as u64;
        assert!(peak_bytes(n, half(k), narrow, counted) >= 7 * n as u64 + placed);
        assert_eq!(remake_bytes(n, narrow, counted), 7 * n as u64);
        assert_eq!(remake_bytes(n, 4 * n as u64, counted), 4 * n as u64);
        assert_eq!(remake_bytes(n, n as u64, counted), n as u64);
    }

    /// White noise of 2 M vertices (more than [`REMAKE_MIN_VERTICES`]):
    /// its float order is let go during the merge and sorted again, and the
    /// tree is the one built with the order held throughout.
    #[test]
    fn an_order_sorted_again_gives_the_same_tree() {
        let noisy = crate::field::source::synthetic_spec("synthetic-noisy:128")
            .expect("spec")
            .expect("synthetic")
            .generate();
        let n = noisy.len();
        let census =
            crate::with_values!(noisy.values(), v => sweep::census_of(&noisy.mesh(), v.as_slice()));
        let counting = crate::field::sorts_by_counting(noisy.values());
        assert_eq!(order_at_merge(n, census, counting), OrderAtMerge::Sorted);
        let (sorted_again, _) = ContourTree::from_field(&noisy, &Progress::new()).expect("tree");
        let order = noisy.vertex_order();
        let (held, _) = crate::with_values!(noisy.values(), v => ContourTree::build(&noisy.mesh(), v.as_slice(), &order, &Progress::new()))
            .expect("tree");
        assert!(sorted_again.arcs().len() > n / 10, "white noise");
        assert_eq!(parts(&sorted_again), parts(&held));
    }

    use crate::field::Values;
    use proptest::prelude::*;

    /// Everything a tree holds, for comparing two trees vertex for vertex.
    fn parts(t: &ContourTree) -> (Vec<Node>, Vec<Superarc>, Vec<VertexPlace>, Vec<Vec<u32>>) {
        adjacency_lists_the_arcs(t);
        (
            t.nodes().to_vec(),
            t.arcs().to_vec(),
            (0..t.num_vertices() as u32).map(|v| t.place(v)).collect(),
            (0..t.arcs().len() as u32)
                .map(|a| t.arc_vertices(ArcId(a)).to_vec())
                .collect(),
        )
    }

    /// Each node's up and down arcs are the superarcs whose lower (upper)
    /// end it is, in the arcs' order: lists kept apart, one per node.
    fn adjacency_lists_the_arcs(t: &ContourTree) {
        let mut up = vec![Vec::new(); t.nodes().len()];
        let mut down = vec![Vec::new(); t.nodes().len()];
        for (a, arc) in t.arcs().iter().enumerate() {
            up[arc.lower.0 as usize].push(ArcId(a as u32));
            down[arc.upper.0 as usize].push(ArcId(a as u32));
        }
        for (i, node) in t.nodes().iter().enumerate() {
            let id = NodeId(i as u32);
            assert_eq!(t.up_arcs(id), up[i].as_slice(), "up arcs of node {i}");
            assert_eq!(t.down_arcs(id), down[i].as_slice(), "down arcs of node {i}");
            assert_eq!(t.node_arcs(id).len() as u32, node.degree());
        }
    }

    fn same_as_vertex_merge(dims: [usize; 3], values: Values) {
        let field = ScalarField::new(dims, values).expect("field");
        let (fast, _) = ContourTree::from_field(&field, &Progress::new()).expect("tree");
        let order = field.vertex_order();
        let oracle = crate::with_values!(field.values(), v => vertex_merge::build(&field.mesh(), v.as_slice(), &order));
        assert_eq!(parts(&fast), parts(&oracle), "dims {dims:?}");
        // The extrema the link classification counts are the tree's
        // leaves, and bound its supernodes, as the memory model takes them
        // before the sweeps.
        let census =
            crate::with_values!(field.values(), v => sweep::census_of(&field.mesh(), v.as_slice()));
        let (maxima, minima, _, _) = oracle.kind_counts();
        if field.len() > 1 {
            assert_eq!(census.extrema, maxima + minima, "dims {dims:?}");
        }
        assert!(
            oracle.nodes().len() <= census.supernodes_at_most(),
            "dims {dims:?}: {} supernodes, {census:?}",
            oracle.nodes().len()
        );
        // The candidates regular in both trees reduced before the merge
        // whenever there is one, and never: the same tree.
        let mesh = field.mesh();
        let cuts = blocks::even_cuts(field.len(), 1);
        // Its tables in 3 bytes per number and in 4.
        // Each candidate's parent written into its record while sweeping,
        // and in a table.
        for (reduce_share, packed_share, parents_in_words) in [
            (usize::MAX, usize::MAX, false),
            (0, usize::MAX, false),
            (usize::MAX, 0, false),
            (0, 0, false),
            (usize::MAX, usize::MAX, true),
            (0, usize::MAX, true),
            (usize::MAX, 0, true),
            (0, 0, true),
        ] {
            let merging = merge::Merging {
                reduce_share,
                packed_share,
                parents_in_words: Some(parents_in_words),
            };
            let (tree, _) = crate::with_values!(field.values(), v => ContourTree::build_from(
                &mesh,
                v.as_slice(),
                OrderSource::Borrowed(&order),
                Some(&cuts),
                merging,
                &Progress::new(),
            ))
            .expect("tree");
            assert_eq!(parts(&tree), parts(&oracle), "dims {dims:?}, {merging:?}");
        }
    }

    fn grid(levels: u8, max: usize) -> impl Strategy<Value = ([usize; 3], Vec<u8>)> {
        (1..=max, 1..=max, 1..=max, 1..=levels).prop_flat_map(|(x, y, z, l)| {
            proptest::collection::vec(0..l, x * y * z).prop_map(move |v| ([x, y, z], v))
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]

        #[test]
        fn candidate_merge_gives_the_vertex_merge_tree_on_random_grids_with_ties(
            (dims, v) in grid(6, 7)
        ) {
            same_as_vertex_merge(dims, Values::U8(v));
        }

        #[test]
        fn candidate_merge_gives_the_vertex_merge_tree_on_smooth_ish_grids(
            (dims, v) in grid(200, 10)
        ) {
            // Sorting the values along x makes long monotone runs, hence few
            // candidates and long superarcs with interleaved branches.
            let mut v = v;
            for row in v.chunks_mut(dims[0]) {
                row.sort_unstable();
            }
            same_as_vertex_merge(dims, Values::U8(v));
        }
    }

    #[test]
    fn candidate_merge_gives_the_vertex_merge_tree_on_the_synthetic_scene() {
        for f in [
            crate::field::synthetic::Synthetic::cube(24).generate(),
            crate::field::synthetic::Synthetic::cube(20)
                .with_noise(0.05, 3)
                .generate(),
        ] {
            same_as_vertex_merge(f.dims(), f.values().clone());
        }
    }
}
