//! Contour tree simplification (Carr, Snoeyink, van de Panne, §3.3): the
//! whole pruning sequence, computed once, then any level on demand.
//!
//! The sequence starts from the [`CollapsedTree`] (zero-height arcs
//! contracted, §5) and follows the paper's three rules with a priority
//! queue and lazy deletion (`PruningQueue`: the starting leaves sorted once
//! in parallel and read in order, a 4-ary heap only for the leaves made
//! later, so a tree of millions of arcs does not pay a chain of cache
//! misses per pop; the steps are `Pruning::leaf_prune` and
//! `Pruning::vertex_reduction`):
//!
//! 1. always perform vertex reduction where possible;
//! 2. always prune the least important leaf: a lower leaf `e` costs up(e),
//!    an upper leaf down(e) ([`Measure`]);
//! 3. never prune the last up- or down-arc of an interior node (it is
//!    discarded from the queue and comes back after a vertex reduction).
//!
//! Reducing a node merges its arcs `e1` (above) and `e2` (below) into a new
//! arc `d` with up(d) = up(e1), down(d) = down(e2). One *step* is one leaf
//! prune with the reduction it may allow. Arcs are never changed once
//! made, only created, so the sequence is a list of small diffs and a
//! [`SimplifiedTree`] moves between levels in time proportional to the
//! number of steps between them, not to the tree.
//!
//! **Chains.** Every arc, at any level, stands for a monotone path of
//! original superarcs. Reductions form a forest over arc ids (d's children
//! are e2 and e1); laying its leaves out in order puts the chain of *every*
//! arc in one contiguous range of a single array, ascending in value:
//! [`Simplification::chain`] is a slice, and a contour at isovalue `h` on
//! any arc is found by binary search on it. No arc owns a heap allocation.
//!
//! **Cost:** O(t log t) for t collapsed arcs: one parallel sort of the
//! starting leaves, then O(1) per pop and step plus O(log) per leaf made.
//! On millions of arcs the constant is cache misses, since pops come in
//! cost order, i.e. at arcs and nodes all over memory. So an arc's ends
//! are one 8-byte record (its costs lie apart: only a reduction reads
//! them, and the level view streams the ends alone), a node's live
//! adjacency one aligned 16-byte record (`NodeLinks`), liveness a bitset
//! that stays in cache, and the loop prefetches the records of the
//! starting leaves it will pop next: a step costs about three misses,
//! overlapped, instead of nine in a row.
//! The arrays derived from the sequence afterwards (curve, diffs, chains,
//! ends) are built side by side with rayon. On synthetic-noisy-256 (3.9 M
//! arcs, 2 M steps) this is about a second on the 2-core reference box.
//!
//! **Memory:** per arc id (at most twice the collapsed arcs) 40 bytes; per
//! step 52 bytes (the step and its diff); per original superarc 4 bytes (the chain array); a
//! [`SimplifiedTree`] adds 8 bytes per arc id and 8 per node; the
//! steps are also kept as 28-byte diffs for the level view.

mod adjacency;
pub mod branches;
pub mod collapse;
pub mod json;
pub mod layout;
mod level_set;
pub mod memory;
pub mod overview;

pub use crate::measure::geometric::Measure;
pub use collapse::CollapsedTree;

use crate::field::ScalarField;
use crate::tree::{ArcId, ContourTree};
use std::cmp::Ordering;
use std::sync::{Arc, OnceLock};

/// An arc of the simplification: an arc of the collapsed tree (ids below
/// [`Simplification::base_arcs`]) or one made by vertex reduction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SimplifiedArcId(pub u32);

/// A node of the collapsed tree (nodes are never created by simplification).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SimplifiedNodeId(pub u32);

/// One step of the pruning sequence: a leaf prune, and the vertex
/// reduction it allowed, if any.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// The leaf arc pruned.
    pub pruned: SimplifiedArcId,
    /// True when the leaf was a lower leaf (a minimum levelled up to the
    /// arc's upper node), false for an upper leaf.
    pub lower_leaf: bool,
    /// Its cost: up(e) for a lower leaf, down(e) for an upper one.
    pub cost: f64,
    /// The arc made by the reduction that followed (its parts are
    /// [`Simplification::reduced_from`]), if any.
    pub reduced: Option<SimplifiedArcId>,
}

/// One point of the simplification curve (paper §5): after some steps, the
/// tree has `arcs` arcs, and `feature_size` is the highest cost pruned so
/// far. Plotted log-log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvePoint {
    /// Arcs in the tree.
    pub arcs: usize,
    /// Highest cost of any arc pruned to get here (0 for the full tree).
    pub feature_size: f64,
}

/// Priority queue entry, ordered by cost then arc id (deterministic ties).
#[derive(Clone, Copy, Debug)]
struct Entry {
    cost: f64,
    arc: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    /// Reversed, so that `BinaryHeap` pops the cheapest.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .cost
            .total_cmp(&self.cost)
            .then(other.arc.cmp(&self.arc))
    }
}

const NONE: u32 = u32::MAX;

/// How many starting leaves ahead the pruning loop prefetches an arc's
/// record, and its nodes ([`Pruning::prefetch`]).
const PREFETCH_FAR: usize = 16;
const PREFETCH_NEAR: usize = 8;

/// A step as the level view replays it: every id it touches, in one
/// record, so moving the slider reads the steps sequentially.
#[derive(Clone, Copy, Debug)]
struct StepDiff {
    pruned: u32,
    /// Ends of the pruned arc.
    upper: u32,
    lower: u32,
    /// The arc made by reduction (`NONE` if none), its parts above and
    /// below, and the node reduced.
    made: u32,
    e1: u32,
    e2: u32,
    reduced: u32,
}

/// The complete pruning sequence of a collapsed contour tree under one
/// measure. Immutable once made; share it between threads with `Arc`.
#[derive(Clone, Debug)]
pub struct Simplification {
    measure: Measure,
    /// Per node: representative vertex and value.
    node_vertex: Vec<u32>,
    node_value: Vec<f64>,
    /// Per arc id: its ends, apart from its costs: the pruning loop reads
    /// mostly ends, the level view only ends, so more of them share a
    /// cache line.
    ends: Vec<ArcEnds>,
    /// Per arc id: (up, down) costs.
    costs: Vec<(f64, f64)>,
    /// Per arc id made by reduction (index `id - base_arcs`): (e1, e2), the
    /// arcs above and below the reduced node.
    parts: Vec<(u32, u32)>,
    /// Per arc id: its chain, `chain[chain_start[a]..][..chain_len[a]]`.
    chain_start: Vec<u32>,
    chain_len: Vec<u32>,
    chain: Vec<ArcId>,
    steps: Vec<Step>,
    diffs: Vec<StepDiff>,
    curve: Vec<CurvePoint>,
    base_arcs: usize,
    perturbed_arcs: usize,
    /// Per original superarc: the collapsed-tree arc whose chain holds it
    /// (`NONE` for the zero-height ones collapsed into nodes).
    superarc_base: Vec<u32>,
    /// Per arc id: the arc made by the reduction that ends it (`NONE` when
    /// it is pruned or never ends).
    merged_into: Vec<u32>,
    /// Per arc id: the step that ends it, pruning it or reducing it into
    /// a made arc (`NONE` when none does).
    ends_at: Vec<u32>,
    /// Per arc id made by reduction (index `id - base_arcs`): the step that
    /// made it.
    made_at: Vec<u32>,
}

impl Simplification {
    /// Collapses `tree`, measures it and computes the whole pruning
    /// sequence. The field is read once, for the measures.
    pub fn new(tree: &ContourTree, field: &ScalarField, measure: Measure) -> Self {
        Self::from_collapsed(&CollapsedTree::new(tree, field), measure)
    }

    /// The pruning sequence of an already collapsed tree (switching the
    /// measure does not need the field again).
    pub fn from_collapsed(base: &CollapsedTree, measure: Measure) -> Self {
        let m = base.num_arcs();
        let n = base.num_nodes();
        let node_value: Vec<f64> = (0..n as u32).map(|v| base.node_value(v)).collect();
        let node_vertex: Vec<u32> = (0..n as u32).map(|v| base.node_vertex(v)).collect();
        let mut tree = Pruning::new(base, measure, &node_value);
        let mut queue = {
            use rayon::prelude::*;
            let tree = &tree;
            PruningQueue::new(
                (0..m as u32)
                    .into_par_iter()
                    .filter_map(|a| tree.leaf_entry(a))
                    .collect(),
            )
        };
        let mut steps = Vec::new();
        loop {
            tree.prefetch(queue.ahead(PREFETCH_FAR), queue.ahead(PREFETCH_NEAR));
            let Some(Entry { cost, arc: a }) = queue.pop() else {
                break;
            };
            let Some((s, lower_leaf)) = tree.prunable(a) else {
                continue;
            };
            tree.leaf_prune(a);
            let mut reduced = None;
            let links = tree.nodes[s as usize];
            if links.n_up == 1 && links.n_down == 1 {
                // Rule 1: vertex reduction.
                let d = tree.vertex_reduction(s);
                queue.extend(tree.leaf_entry(d));
                reduced = Some(SimplifiedArcId(d));
            } else if links.degree() == 1 {
                // A node with arcs in one direction only (a collapsed
                // plateau) has become a leaf.
                queue.extend(tree.leaf_entry(links.x_up ^ links.x_down));
            }
            steps.push(Step {
                pruned: SimplifiedArcId(a),
                lower_leaf,
                cost,
                reduced,
            });
        }
        let Pruning {
            ends, costs, parts, ..
        } = tree;
        // What the level view and the queries read, in three independent
        // groups, side by side.
        let (
            (curve, diffs),
            ((chain_start, chain_len, chain, superarc_base), (merged_into, ends_at, made_at)),
        ) = rayon::join(
            || (curve_of(m, &steps), diffs_of(m, &steps, &ends, &parts)),
            || {
                rayon::join(
                    || {
                        let (start, len, chain) = layout_chains(base, ends.len(), &parts);
                        let mut superarc_base = vec![NONE; base.perturbed_arcs()];
                        for a in 0..m {
                            let s = start[a] as usize;
                            for e in &chain[s..s + len[a] as usize] {
                                superarc_base[e.0 as usize] = a as u32;
                            }
                        }
                        (start, len, chain, superarc_base)
                    },
                    || ends_of(m, ends.len(), &steps, &parts),
                )
            },
        );
        Self {
            measure,
            node_vertex,
            node_value,
            ends,
            costs,
            parts,
            chain_start,
            chain_len,
            chain,
            steps,
            diffs,
            curve,
            base_arcs: m,
            perturbed_arcs: base.perturbed_arcs(),
            superarc_base,
            merged_into,
            ends_at,
            made_at,
        }
    }

    /// The measure that ranked the leaves.
    pub fn measure(&self) -> Measure {
        self.measure
    }

    /// Arcs of the collapsed tree (level 0).
    pub fn base_arcs(&self) -> usize {
        self.base_arcs
    }

    /// Superarcs of the perturbed tree the collapsed tree was made from.
    pub fn perturbed_arcs(&self) -> usize {
        self.perturbed_arcs
    }

    /// Number of arc ids (collapsed arcs and arcs made by reduction).
    pub fn num_arc_ids(&self) -> usize {
        self.ends.len()
    }

    /// Number of nodes (of the collapsed tree).
    pub fn num_nodes(&self) -> usize {
        self.node_vertex.len()
    }

    /// The pruning sequence.
    pub fn steps(&self) -> &[Step] {
        &self.steps
    }

    /// The simplification curve: point `k` is the tree after `k` steps.
    pub fn curve(&self) -> &[CurvePoint] {
        &self.curve
    }

    /// Upper node of an arc.
    pub fn upper(&self, a: SimplifiedArcId) -> SimplifiedNodeId {
        SimplifiedNodeId(self.ends[a.0 as usize].upper)
    }

    /// Lower node of an arc.
    pub fn lower(&self, a: SimplifiedArcId) -> SimplifiedNodeId {
        SimplifiedNodeId(self.ends[a.0 as usize].lower)
    }

    /// up(e): the cost of pruning the arc as a lower leaf.
    pub fn up_cost(&self, a: SimplifiedArcId) -> f64 {
        self.costs[a.0 as usize].0
    }

    /// down(e): the cost of pruning the arc as an upper leaf.
    pub fn down_cost(&self, a: SimplifiedArcId) -> f64 {
        self.costs[a.0 as usize].1
    }

    /// The two arcs (above, below) a reduced arc was made from, or `None`
    /// for an arc of the collapsed tree.
    pub fn reduced_from(&self, a: SimplifiedArcId) -> Option<(SimplifiedArcId, SimplifiedArcId)> {
        let i = (a.0 as usize).checked_sub(self.base_arcs)?;
        let (e1, e2) = self.parts[i];
        Some((SimplifiedArcId(e1), SimplifiedArcId(e2)))
    }

    /// The original superarcs (of the perturbed tree) an arc stands for: a
    /// monotone path, ascending in value, so the one holding isovalue `h`
    /// is found by binary search (`contour::seed` does).
    pub fn chain(&self, a: SimplifiedArcId) -> &[ArcId] {
        let s = self.chain_start[a.0 as usize] as usize;
        &self.chain[s..s + self.chain_len[a.0 as usize] as usize]
    }

    /// The representative mesh vertex of a node.
    pub fn node_vertex(&self, v: SimplifiedNodeId) -> u32 {
        self.node_vertex[v.0 as usize]
    }

    /// The value of a node.
    pub fn node_value(&self, v: SimplifiedNodeId) -> f64 {
        self.node_value[v.0 as usize]
    }

    /// The number of steps that leaves at most `arcs` arcs (all of them
    /// when even the last level has more).
    pub fn steps_for_arcs(&self, arcs: usize) -> usize {
        self.curve
            .partition_point(|p| p.arcs > arcs)
            .min(self.steps.len())
    }

    /// The number of steps that prunes every leaf up to `feature_size`: the
    /// last level whose feature size does not exceed it.
    pub fn steps_for_feature_size(&self, feature_size: f64) -> usize {
        self.curve
            .partition_point(|p| p.feature_size <= feature_size)
            .saturating_sub(1)
    }
}

/// An arc id's ends: 8 bytes, so that the pruning loop, which meets arcs
/// in cost order (all over memory), and the level view, which streams the
/// live ones, read no costs with them.
#[derive(Clone, Copy, Debug)]
struct ArcEnds {
    upper: u32,
    lower: u32,
}

/// A node's live adjacency: its number of live arcs up and down and the
/// XOR of their ids, so a node with one arc in a direction finds it in
/// O(1). One aligned 16-byte record, so the checks and updates at a node
/// cost one cache miss, not four.
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(16))]
struct NodeLinks {
    n_up: u32,
    n_down: u32,
    x_up: u32,
    x_down: u32,
}

impl NodeLinks {
    fn degree(&self) -> u32 {
        self.n_up + self.n_down
    }
}

/// The tree as the pruning sequence changes it (paper §3.3): arcs are only
/// created, never changed, and die when pruned or reduced.
struct Pruning {
    ends: Vec<ArcEnds>,
    /// Per arc id: (up, down) costs, read only when a reduction makes an
    /// arc.
    costs: Vec<(f64, f64)>,
    nodes: Vec<NodeLinks>,
    /// One bit per arc id, set while the arc is live (under a megabyte for
    /// millions of arcs: it stays in cache, unlike the records).
    alive: Vec<u64>,
    /// Per arc made by reduction: (e1, e2), the arcs above and below.
    parts: Vec<(u32, u32)>,
}

impl Pruning {
    fn new(base: &CollapsedTree, measure: Measure, node_value: &[f64]) -> Self {
        use rayon::prelude::*;
        let m = base.num_arcs();
        let n = base.num_nodes();
        // At most one arc is made per arc pruned.
        let (mut ends, mut costs) = (Vec::with_capacity(2 * m), Vec::with_capacity(2 * m));
        (0..m as u32)
            .into_par_iter()
            .map(|a| {
                let (u, l) = base.arc(a);
                (
                    ArcEnds { upper: u, lower: l },
                    (
                        measure.up_cost(base.below(a), node_value[u as usize]),
                        measure.down_cost(base.above(a), node_value[l as usize]),
                    ),
                )
            })
            .unzip_into_vecs(&mut ends, &mut costs);
        let mut nodes = vec![NodeLinks::default(); n];
        // The arcs come sorted by lower node: the lower ends stream, the
        // upper ones are scattered, so they are prefetched ahead.
        for (a, r) in ends.iter().enumerate() {
            if let Some(f) = ends.get(a + PREFETCH_FAR) {
                crate::tree::sweep::prefetch(&nodes, f.upper as usize);
            }
            let lo = &mut nodes[r.lower as usize];
            lo.n_up += 1;
            lo.x_up ^= a as u32;
            let hi = &mut nodes[r.upper as usize];
            hi.n_down += 1;
            hi.x_down ^= a as u32;
        }
        let mut alive = vec![0u64; (2 * m).div_ceil(64) + 1];
        alive[..m / 64].fill(u64::MAX);
        if !m.is_multiple_of(64) {
            alive[m / 64] = (1u64 << (m % 64)) - 1;
        }
        Self {
            ends,
            costs,
            nodes,
            alive,
            parts: Vec::new(),
        }
    }

    fn is_alive(&self, a: u32) -> bool {
        self.alive[a as usize / 64] & (1 << (a % 64)) != 0
    }

    fn set_alive(&mut self, a: u32, live: bool) {
        let w = a as usize / 64;
        if w >= self.alive.len() {
            self.alive.resize(w + 1, 0);
        }
        let bit = 1u64 << (a % 64);
        if live {
            self.alive[w] |= bit;
        } else {
            self.alive[w] &= !bit;
        }
    }

    fn degree(&self, v: u32) -> u32 {
        self.nodes[v as usize].degree()
    }

    /// The queue entry of arc `a` if it is a leaf: a lower leaf costs
    /// up(a), an upper leaf down(a) (rule 2).
    fn leaf_entry(&self, a: u32) -> Option<Entry> {
        let r = &self.ends[a as usize];
        match (self.degree(r.lower) == 1, self.degree(r.upper) == 1) {
            (true, false) => Some(Entry {
                cost: self.costs[a as usize].0,
                arc: a,
            }),
            (false, true) => Some(Entry {
                cost: self.costs[a as usize].1,
                arc: a,
            }),
            _ => None,
        }
    }

    /// Whether the popped arc `a` may be pruned now: alive (entries are
    /// deleted lazily), a leaf but not the last arc, and not the last arc
    /// down (up) of the node it hangs from (rule 3). Returns that node and
    /// whether `a` is a lower leaf.
    fn prunable(&self, a: u32) -> Option<(u32, bool)> {
        if !self.is_alive(a) {
            return None;
        }
        let r = &self.ends[a as usize];
        let (hi, lo) = (&self.nodes[r.upper as usize], &self.nodes[r.lower as usize]);
        let lower_leaf = lo.degree() == 1;
        let upper_leaf = hi.degree() == 1;
        if lower_leaf == upper_leaf {
            return None;
        }
        if (lower_leaf && hi.n_down == 1) || (upper_leaf && lo.n_up == 1) {
            return None;
        }
        Some((if lower_leaf { r.upper } else { r.lower }, lower_leaf))
    }

    /// Leaf pruning: arc `a` leaves the tree with its leaf node.
    fn leaf_prune(&mut self, a: u32) {
        let r = self.ends[a as usize];
        self.set_alive(a, false);
        let lo = &mut self.nodes[r.lower as usize];
        lo.n_up -= 1;
        lo.x_up ^= a;
        let hi = &mut self.nodes[r.upper as usize];
        hi.n_down -= 1;
        hi.x_down ^= a;
    }

    /// Vertex reduction of node `s`, left with one arc `e1` up and one
    /// `e2` down: they become one new arc `d` with up(d) = up(e1) and
    /// down(d) = down(e2). Returns `d`.
    fn vertex_reduction(&mut self, s: u32) -> u32 {
        let NodeLinks {
            x_up: e1,
            x_down: e2,
            ..
        } = self.nodes[s as usize];
        let (r1, r2) = (self.ends[e1 as usize], self.ends[e2 as usize]);
        let d = self.ends.len() as u32;
        self.ends.push(ArcEnds {
            upper: r1.upper,
            lower: r2.lower,
        });
        self.costs
            .push((self.costs[e1 as usize].0, self.costs[e2 as usize].1));
        self.parts.push((e1, e2));
        self.set_alive(e1, false);
        self.set_alive(e2, false);
        self.set_alive(d, true);
        self.nodes[s as usize] = NodeLinks::default();
        self.nodes[r1.upper as usize].x_down ^= e1 ^ d;
        self.nodes[r2.lower as usize].x_up ^= e2 ^ d;
        d
    }

    /// Hints the cache about the arc and the nodes the queue will pop
    /// next: `far` ahead its record, `near` ahead (record there by then)
    /// its two nodes. The pops are in cost order, so every one of these
    /// reads would otherwise be a miss to memory, one after another.
    fn prefetch(&self, far: Option<u32>, near: Option<u32>) {
        use crate::tree::sweep::prefetch;
        if let Some(a) = far {
            prefetch(&self.ends, a as usize);
        }
        if let Some(r) = near.and_then(|a| self.ends.get(a as usize)) {
            prefetch(&self.nodes, r.upper as usize);
            prefetch(&self.nodes, r.lower as usize);
        }
    }
}

/// The priority queue of leaves, cheapest first, ties by arc id. Most
/// entries are the leaves of the starting tree: they are sorted once (in
/// parallel) and read in order, so only the entries added during the
/// sequence (arcs made by reduction, plateau nodes turned leaves) go
/// through a heap ([`QuadHeap`]; about 0.7 M of them on
/// synthetic-noisy-256, at most 0.5 M at once). On trees of millions of arcs this replaces a
/// heap of millions of entries, whose every pop is a chain of cache misses,
/// by a sequential read; the entries popped, hence the sequence, are the
/// same as from one heap holding them all.
struct PruningQueue {
    sorted: Vec<Entry>,
    next: usize,
    heap: QuadHeap,
}

impl PruningQueue {
    fn new(mut initial: Vec<Entry>) -> Self {
        use rayon::prelude::*;
        // `Entry`'s order is reversed for `BinaryHeap`: sorting by it
        // descending gives the cheapest first.
        initial.par_sort_unstable_by(|a, b| b.cmp(a));
        Self {
            sorted: initial,
            next: 0,
            heap: QuadHeap::default(),
        }
    }

    /// The arc of the starting leaf `k` places ahead in the sorted run.
    fn ahead(&self, k: usize) -> Option<u32> {
        self.sorted.get(self.next + k).map(|e| e.arc)
    }

    fn pop(&mut self) -> Option<Entry> {
        match (self.sorted.get(self.next), self.heap.peek()) {
            (Some(s), Some(h)) if h > s => self.heap.pop(),
            (Some(&s), _) => {
                self.next += 1;
                Some(s)
            }
            (None, _) => self.heap.pop(),
        }
    }
}

impl Extend<Entry> for PruningQueue {
    fn extend<I: IntoIterator<Item = Entry>>(&mut self, entries: I) {
        for e in entries {
            self.heap.push(e);
        }
    }
}

/// A max-heap (by [`Entry`]'s order: the cheapest on top) with four
/// children per node: a pop walks half the levels of a binary heap, and
/// the four children it compares at each level lie in one or two cache
/// lines. With a million entries the lower levels are cache misses, so
/// this halves the misses per pop.
#[derive(Debug, Default)]
struct QuadHeap {
    v: Vec<Entry>,
}

impl QuadHeap {
    #[cfg(test)]
    fn len(&self) -> usize {
        self.v.len()
    }

    fn peek(&self) -> Option<&Entry> {
        self.v.first()
    }

    fn push(&mut self, e: Entry) {
        let mut i = self.v.len();
        self.v.push(e);
        while i > 0 {
            let p = (i - 1) / 4;
            if self.v[p] >= e {
                break;
            }
            self.v[i] = self.v[p];
            i = p;
        }
        self.v[i] = e;
    }

    fn pop(&mut self) -> Option<Entry> {
        let last = self.v.pop()?;
        let Some(&top) = self.v.first() else {
            return Some(last);
        };
        // Sift `last` down from the root.
        let n = self.v.len();
        let mut i = 0;
        loop {
            let c = 4 * i + 1;
            if c >= n {
                break;
            }
            let mut best = c;
            for j in c + 1..(c + 4).min(n) {
                if self.v[j] > self.v[best] {
                    best = j;
                }
            }
            if self.v[best] <= last {
                break;
            }
            self.v[i] = self.v[best];
            i = best;
        }
        self.v[i] = last;
        Some(top)
    }
}

/// The simplification curve of a sequence from a tree of `m` arcs.
fn curve_of(m: usize, steps: &[Step]) -> Vec<CurvePoint> {
    let mut curve = Vec::with_capacity(steps.len() + 1);
    let (mut arcs, mut feature) = (m, 0.0f64);
    curve.push(CurvePoint {
        arcs,
        feature_size: feature,
    });
    for s in steps {
        arcs -= 1 + s.reduced.is_some() as usize;
        feature = feature.max(s.cost);
        curve.push(CurvePoint {
            arcs,
            feature_size: feature,
        });
    }
    curve
}

/// Every step as the level view replays it.
fn diffs_of(m: usize, steps: &[Step], arcs: &[ArcEnds], parts: &[(u32, u32)]) -> Vec<StepDiff> {
    use rayon::prelude::*;
    steps
        .par_iter()
        .map(|s| {
            let p = s.pruned.0 as usize;
            let (made, e1, e2, reduced) = match s.reduced {
                Some(d) => {
                    let (e1, e2) = parts[d.0 as usize - m];
                    (d.0, e1, e2, arcs[e1 as usize].lower)
                }
                None => (NONE, NONE, NONE, NONE),
            };
            StepDiff {
                pruned: s.pruned.0,
                upper: arcs[p].upper,
                lower: arcs[p].lower,
                made,
                e1,
                e2,
                reduced,
            }
        })
        .collect()
}

/// Per arc id, the arc made by the reduction that ends it and the step
/// that ends it; per arc made, the step that made it (see the fields of
/// [`Simplification`]).
fn ends_of(
    m: usize,
    ids: usize,
    steps: &[Step],
    parts: &[(u32, u32)],
) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let mut merged_into = vec![NONE; ids];
    for (i, &(e1, e2)) in parts.iter().enumerate() {
        merged_into[e1 as usize] = (m + i) as u32;
        merged_into[e2 as usize] = (m + i) as u32;
    }
    let mut ends_at = vec![NONE; ids];
    let mut made_at = vec![NONE; parts.len()];
    for (i, st) in steps.iter().enumerate() {
        ends_at[st.pruned.0 as usize] = i as u32;
        if let Some(d) = st.reduced {
            let (e1, e2) = parts[d.0 as usize - m];
            ends_at[e1 as usize] = i as u32;
            ends_at[e2 as usize] = i as u32;
            made_at[d.0 as usize - m] = i as u32;
        }
    }
    (merged_into, ends_at, made_at)
}

/// Lays out the chains of all arc ids in one array so that each is a
/// contiguous ascending range (see the module documentation).
fn layout_chains(
    base: &CollapsedTree,
    total: usize,
    parts: &[(u32, u32)],
) -> (Vec<u32>, Vec<u32>, Vec<ArcId>) {
    let m = base.num_arcs();
    let mut len = vec![0u32; total];
    for (a, l) in len.iter_mut().enumerate().take(m) {
        *l = base.chain(a as u32).len() as u32;
    }
    let mut has_parent = vec![false; total];
    for (i, &(e1, e2)) in parts.iter().enumerate() {
        len[m + i] = len[e1 as usize] + len[e2 as usize];
        has_parent[e1 as usize] = true;
        has_parent[e2 as usize] = true;
    }
    let mut start = vec![NONE; total];
    let mut next = 0u32;
    for a in 0..total {
        if !has_parent[a] {
            start[a] = next;
            next += len[a];
        }
    }
    // Parents have higher ids than their parts: go down from the top.
    for i in (0..parts.len()).rev() {
        let (e1, e2) = parts[i];
        let s = start[m + i];
        start[e2 as usize] = s;
        start[e1 as usize] = s + len[e2 as usize];
    }
    let mut chain = vec![ArcId(0); next as usize];
    for (a, &s) in start.iter().enumerate().take(m) {
        let s = s as usize;
        let c = base.chain(a as u32);
        chain[s..s + c.len()].copy_from_slice(c);
    }
    (start, len, chain)
}

/// One level of a [`Simplification`], the view the explorer draws: the
/// live arcs after some number of steps. Moving to another level replays or
/// undoes the steps in between, a few array writes each (O(change));
/// reading costs nothing beyond the live arcs.
#[derive(Clone, Debug)]
pub struct SimplifiedTree {
    sim: Arc<Simplification>,
    step: usize,
    /// Live arcs, densely, in no particular order, and each arc id's
    /// position there (`NONE` when not live).
    live_arcs: Vec<u32>,
    arc_pos: Vec<u32>,
    /// Per node: live arcs (up, down).
    degree: Vec<(u32, u32)>,
    /// Per node: which arcs those are ([`SimplifiedTree::arcs_above`]),
    /// built on the first query after a level built afresh and kept up to
    /// date by every step walked from then on.
    adjacency: OnceLock<adjacency::LiveAdjacency>,
}

/// A live arc of a [`SimplifiedTree`], as the explorer reads it.
#[derive(Clone, Copy, Debug)]
pub struct LevelArc<'a> {
    /// The arc.
    pub id: SimplifiedArcId,
    /// Its upper node.
    pub upper: SimplifiedNodeId,
    /// Its lower node.
    pub lower: SimplifiedNodeId,
    /// Mesh vertex of the upper node.
    pub upper_vertex: u32,
    /// Mesh vertex of the lower node.
    pub lower_vertex: u32,
    /// up(e).
    pub up_cost: f64,
    /// down(e).
    pub down_cost: f64,
    /// The original superarcs it stands for, ascending.
    pub chain: &'a [ArcId],
}

impl SimplifiedTree {
    /// The unsimplified (collapsed) tree, level 0.
    pub fn new(sim: Arc<Simplification>) -> Self {
        let ids = sim.num_arc_ids();
        let n = sim.num_nodes();
        let m = sim.base_arcs;
        let mut degree = vec![(0, 0); n];
        for a in 0..m {
            degree[sim.ends[a].upper as usize].1 += 1;
            degree[sim.ends[a].lower as usize].0 += 1;
        }
        let mut arc_pos = vec![NONE; ids];
        for (a, p) in arc_pos.iter_mut().enumerate().take(m) {
            *p = a as u32;
        }
        Self {
            live_arcs: (0..m as u32).collect(),
            arc_pos,
            degree,
            step: 0,
            adjacency: OnceLock::new(),
            sim,
        }
    }

    /// The simplification this is a level of.
    pub fn simplification(&self) -> &Arc<Simplification> {
        &self.sim
    }

    /// Steps applied (0 = the collapsed tree).
    pub fn step(&self) -> usize {
        self.step
    }

    /// Number of live arcs.
    pub fn num_arcs(&self) -> usize {
        self.live_arcs.len()
    }

    /// The feature size of this level: the highest cost pruned to reach it.
    pub fn feature_size(&self) -> f64 {
        self.sim.curve[self.step].feature_size
    }

    /// Moves to the level after `step` steps (clamped to the last), by
    /// whichever is cheaper: replaying or undoing the steps in between
    /// (O(change), but each step writes to scattered arcs and nodes), or
    /// building the level afresh from when each arc is made and ended (one
    /// streaming pass over the arc ids plus O(live arcs)). The two give the
    /// same live arcs, degrees and lists; only the order within
    /// [`Self::arc_ids`] and the lists may differ.
    pub fn set_step(&mut self, step: usize) {
        let step = step.min(self.sim.steps.len());
        // Measured on synthetic-noisy-256 (3.9 M arcs, 2 M steps, loaded
        // machine): a step walked costs about 800 ns, an arc id scanned
        // 4 ns and a live arc placed about 90 ns.
        let walk = step.abs_diff(self.step);
        let rebuild = self.sim.num_arc_ids() / 128 + self.sim.curve[step].arcs / 8;
        if walk > rebuild {
            self.rebuild(step);
        } else {
            self.walk(step);
        }
    }

    /// The level after `step` steps built afresh: arc `a` is live after
    /// `s` steps when the step that made it (none for the collapsed tree's
    /// arcs) is before `s` and the one that ends it is not.
    fn rebuild(&mut self, step: usize) {
        use crate::tree::sweep::prefetch;
        let sim = Arc::clone(&self.sim);
        let (m, s) = (sim.base_arcs, step as u32);
        self.adjacency = OnceLock::new();
        // First which arcs are live, without a branch per arc (at a middle
        // level liveness looks random, and a mispredicted branch per arc id
        // cost more than the rest of the scan): every id is written at the
        // end of the list, which grows only when the arc is live. No level
        // has more than the collapsed tree's m arcs, so m + 1 slots do.
        self.live_arcs.clear();
        self.live_arcs.resize(m + 1, 0);
        let mut len = 0;
        let (base_pos, made_pos) = self.arc_pos.split_at_mut(m);
        let (base_ends, made_ends) = sim.ends_at.split_at(m);
        for (a, (pos, &end)) in base_pos.iter_mut().zip(base_ends).enumerate() {
            let live = s <= end;
            self.live_arcs[len] = a as u32;
            *pos = if live { len as u32 } else { NONE };
            len += live as usize;
        }
        let made = made_pos.iter_mut().zip(made_ends).zip(&sim.made_at);
        for (i, ((pos, &end), &start)) in made.enumerate() {
            let live = (start < s) & (s <= end);
            self.live_arcs[len] = (m + i) as u32;
            *pos = if live { len as u32 } else { NONE };
            len += live as usize;
        }
        self.live_arcs.truncate(len);
        // Then the degrees: one scattered increment per end (the collapsed
        // tree's arcs come sorted by lower node, the rest in no order), so
        // both ends are prefetched this many live arcs ahead.
        const AHEAD: usize = 16;
        self.degree.fill((0, 0));
        let ends = &sim.ends;
        for (i, &a) in self.live_arcs.iter().enumerate() {
            if let Some(&b) = self.live_arcs.get(i + AHEAD) {
                let e = ends[b as usize];
                prefetch(&self.degree, e.upper as usize);
                prefetch(&self.degree, e.lower as usize);
            }
            let e = ends[a as usize];
            self.degree[e.upper as usize].1 += 1;
            self.degree[e.lower as usize].0 += 1;
        }
        self.step = step;
    }

    /// Moves to the level after `step` steps by replaying or undoing the
    /// steps in between.
    fn walk(&mut self, step: usize) {
        let sim = Arc::clone(&self.sim);
        while self.step < step {
            let d = sim.diffs[self.step];
            // Prune: the leaf and its node lose the arc.
            self.remove(d.pruned);
            self.degree[d.upper as usize].1 -= 1;
            self.degree[d.lower as usize].0 -= 1;
            if d.made != NONE {
                // Reduction: the made arc takes e1's place at the node
                // above and e2's below, so only the reduced node changes.
                self.replace(d.e1, d.made);
                self.remove(d.e2);
                self.degree[d.reduced as usize] = (0, 0);
            }
            self.step += 1;
        }
        while self.step > step {
            self.step -= 1;
            let d = sim.diffs[self.step];
            if d.made != NONE {
                self.replace(d.made, d.e1);
                self.insert(d.e2);
                self.degree[d.reduced as usize] = (1, 1);
            }
            self.insert(d.pruned);
            self.degree[d.upper as usize].1 += 1;
            self.degree[d.lower as usize].0 += 1;
        }
    }

    /// Moves to the simplest level with at most `arcs` arcs (the last level
    /// when none has so few).
    pub fn set_level(&mut self, arcs: usize) {
        let s = self.sim.steps_for_arcs(arcs);
        self.set_step(s);
    }

    /// Moves to the level that prunes every leaf whose cost is at most
    /// `feature_size` (the last level of the curve at or below it).
    pub fn set_feature_size(&mut self, feature_size: f64) {
        let s = self.sim.steps_for_feature_size(feature_size);
        self.set_step(s);
    }

    /// The live arcs, in no particular order (sort by id for determinism).
    pub fn arcs(&self) -> impl ExactSizeIterator<Item = LevelArc<'_>> + '_ {
        self.live_arcs.iter().map(|&a| self.arc(SimplifiedArcId(a)))
    }

    /// The live arc ids, in no particular order.
    pub fn arc_ids(&self) -> &[u32] {
        &self.live_arcs
    }

    /// The live nodes (the ends of live arcs), sorted; O(a log a) for a
    /// live arcs, computed on each call.
    pub fn nodes(&self) -> Vec<SimplifiedNodeId> {
        let mut v: Vec<u32> = self
            .live_arcs
            .iter()
            .flat_map(|&a| {
                let r = &self.sim.ends[a as usize];
                [r.upper, r.lower]
            })
            .collect();
        v.sort_unstable();
        v.dedup();
        v.into_iter().map(SimplifiedNodeId).collect()
    }

    /// The live arc standing for original superarc `s` at this level (the
    /// one whose chain holds it): from its arc in the collapsed tree up
    /// through the reductions applied so far, O(those reductions), so
    /// markers follow their contours without a pass over the tree. None
    /// when `s` has zero height (collapsed into a node) or lies on a pruned
    /// branch.
    pub fn live_arc_of(&self, s: ArcId) -> Option<SimplifiedArcId> {
        let mut a = *self.sim.superarc_base.get(s.0 as usize)?;
        while a != NONE {
            if self.is_live(SimplifiedArcId(a)) {
                return Some(SimplifiedArcId(a));
            }
            // Dead: pruned (no successor), or reduced into an arc made at
            // an applied step (an arc ends at most once).
            a = self.sim.merged_into[a as usize];
        }
        None
    }

    /// The live arc that absorbed original superarc `s` at this level: the
    /// one holding it ([`Self::live_arc_of`]), else, when its branch was
    /// pruned, the arc that absorbed the pruned leaf: the arc made by the
    /// reduction of the node it was pruned to, or (no reduction there) the
    /// live arc at that node on the leaf's side (lowest id; the other side
    /// when none), followed on through later steps. None for a zero-height
    /// superarc, or when no live arc is left there. O(steps applied) at
    /// worst.
    pub fn absorbing_arc_of(&self, s: ArcId) -> Option<SimplifiedArcId> {
        let sim = &*self.sim;
        let mut a = *sim.superarc_base.get(s.0 as usize)?;
        // Each move goes to an arc made or pruned at a later step, so this
        // ends; bound it all the same.
        for _ in 0..=2 * sim.steps.len() + 1 {
            if a == NONE {
                return None;
            }
            if self.is_live(SimplifiedArcId(a)) {
                return Some(SimplifiedArcId(a));
            }
            if sim.merged_into[a as usize] != NONE {
                a = sim.merged_into[a as usize];
                continue;
            }
            // Not merged, so what ends it is a prune.
            let k = sim.ends_at[a as usize];
            if k == NONE || k as usize >= self.step {
                return None;
            }
            let d = sim.diffs[k as usize];
            if d.made != NONE {
                a = d.made;
                continue;
            }
            let lower_leaf = sim.steps[k as usize].lower_leaf;
            let node = if lower_leaf { d.upper } else { d.lower };
            let side = |want_down: bool| {
                self.live_arcs
                    .iter()
                    .copied()
                    .filter(|&e| {
                        let e = e as usize;
                        if want_down {
                            sim.ends[e].upper == node
                        } else {
                            sim.ends[e].lower == node
                        }
                    })
                    .min()
            };
            // A lower leaf hung below its node, an upper one above.
            return side(lower_leaf)
                .or_else(|| side(!lower_leaf))
                .map(SimplifiedArcId);
        }
        None
    }

    /// True when the arc is live at this level.
    pub fn is_live(&self, a: SimplifiedArcId) -> bool {
        self.arc_pos[a.0 as usize] != NONE
    }

    /// Any arc (live or not) by id.
    pub fn arc(&self, a: SimplifiedArcId) -> LevelArc<'_> {
        let s = &self.sim;
        let (u, l) = (s.upper(a), s.lower(a));
        LevelArc {
            id: a,
            upper: u,
            lower: l,
            upper_vertex: s.node_vertex(u),
            lower_vertex: s.node_vertex(l),
            up_cost: s.up_cost(a),
            down_cost: s.down_cost(a),
            chain: s.chain(a),
        }
    }

    /// Live arcs (up, down) at a node; (0, 0) when the node is gone.
    pub fn degree(&self, v: SimplifiedNodeId) -> (u32, u32) {
        self.degree[v.0 as usize]
    }

    fn insert(&mut self, a: u32) {
        self.arc_pos[a as usize] = self.live_arcs.len() as u32;
        self.live_arcs.push(a);
        if let Some(adj) = self.adjacency.get_mut() {
            adj.link(&self.sim, a);
        }
    }

    fn remove(&mut self, a: u32) {
        let p = self.arc_pos[a as usize];
        debug_assert_ne!(p, NONE, "removing a dead arc");
        self.live_arcs.swap_remove(p as usize);
        if let Some(&moved) = self.live_arcs.get(p as usize) {
            self.arc_pos[moved as usize] = p;
        }
        self.arc_pos[a as usize] = NONE;
        if let Some(adj) = self.adjacency.get_mut() {
            adj.unlink(&self.sim, a);
        }
    }

    /// Puts arc `new` in the slot of live arc `old`.
    fn replace(&mut self, old: u32, new: u32) {
        let p = self.arc_pos[old as usize];
        debug_assert_ne!(p, NONE, "replacing a dead arc");
        self.live_arcs[p as usize] = new;
        self.arc_pos[new as usize] = p;
        self.arc_pos[old as usize] = NONE;
        if let Some(adj) = self.adjacency.get_mut() {
            adj.unlink(&self.sim, old);
            adj.link(&self.sim, new);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{ScalarField, Values};
    use crate::progress::Progress;
    use proptest::prelude::*;
    use std::collections::BinaryHeap;

    /// The pruning sequence as flexiso computed it before [`PruningQueue`]:
    /// every leaf in one binary heap.
    fn steps_with_one_heap(base: &CollapsedTree, measure: Measure) -> Vec<Step> {
        let m = base.num_arcs();
        let n = base.num_nodes();
        let cap = 2 * m;
        let mut upper = Vec::with_capacity(cap);
        let mut lower = Vec::with_capacity(cap);
        let mut up_cost = Vec::with_capacity(cap);
        let mut down_cost = Vec::with_capacity(cap);
        let node_value: Vec<f64> = (0..n as u32).map(|v| base.node_value(v)).collect();
        for a in 0..m as u32 {
            let (u, l) = base.arc(a);
            upper.push(u);
            lower.push(l);
            up_cost.push(measure.up_cost(base.below(a), node_value[u as usize]));
            down_cost.push(measure.down_cost(base.above(a), node_value[l as usize]));
        }
        // Live adjacency: counts and the XOR of the live arc ids up and
        // down; a node with one arc in a direction finds it in O(1).
        let mut n_up = vec![0u32; n];
        let mut n_down = vec![0u32; n];
        let mut x_up = vec![0u32; n];
        let mut x_down = vec![0u32; n];
        for a in 0..m {
            n_up[lower[a] as usize] += 1;
            x_up[lower[a] as usize] ^= a as u32;
            n_down[upper[a] as usize] += 1;
            x_down[upper[a] as usize] ^= a as u32;
        }
        let degree = |n_up: &[u32], n_down: &[u32], v: u32| n_up[v as usize] + n_down[v as usize];
        let mut alive = vec![true; m];
        let mut parts: Vec<(u32, u32)> = Vec::new();
        let mut heap = BinaryHeap::with_capacity(m);
        // The queue holds leaf arcs with the cost of their direction.
        let enqueue = |heap: &mut BinaryHeap<Entry>,
                       n_up: &[u32],
                       n_down: &[u32],
                       a: u32,
                       upper: &[u32],
                       lower: &[u32],
                       up_cost: &[f64],
                       down_cost: &[f64]| {
            let (lo, hi) = (lower[a as usize], upper[a as usize]);
            let (lo_leaf, hi_leaf) = (degree(n_up, n_down, lo) == 1, degree(n_up, n_down, hi) == 1);
            if lo_leaf && !hi_leaf {
                heap.push(Entry {
                    cost: up_cost[a as usize],
                    arc: a,
                });
            } else if hi_leaf && !lo_leaf {
                heap.push(Entry {
                    cost: down_cost[a as usize],
                    arc: a,
                });
            }
        };
        for a in 0..m as u32 {
            enqueue(
                &mut heap, &n_up, &n_down, a, &upper, &lower, &up_cost, &down_cost,
            );
        }
        let mut steps = Vec::new();
        while let Some(Entry { cost, arc: a }) = heap.pop() {
            if !alive[a as usize] {
                continue; // lazy deletion: reduced away since queued
            }
            let (hi, lo) = (upper[a as usize], lower[a as usize]);
            let lower_leaf = degree(&n_up, &n_down, lo) == 1;
            let upper_leaf = degree(&n_up, &n_down, hi) == 1;
            if lower_leaf == upper_leaf {
                continue; // the last arc of the tree
            }
            // Rule 3: never the last arc down (up) of the node it hangs from.
            let s = if lower_leaf { hi } else { lo };
            if (lower_leaf && n_down[s as usize] == 1) || (upper_leaf && n_up[s as usize] == 1) {
                continue;
            }
            // Prune.
            alive[a as usize] = false;
            n_up[lo as usize] -= 1;
            x_up[lo as usize] ^= a;
            n_down[hi as usize] -= 1;
            x_down[hi as usize] ^= a;
            let mut reduced = None;
            if n_up[s as usize] == 1 && n_down[s as usize] == 1 {
                // Rule 1: vertex reduction.
                let (e1, e2) = (x_up[s as usize], x_down[s as usize]);
                let d = upper.len() as u32;
                let (u, l) = (upper[e1 as usize], lower[e2 as usize]);
                upper.push(u);
                lower.push(l);
                up_cost.push(up_cost[e1 as usize]);
                down_cost.push(down_cost[e2 as usize]);
                parts.push((e1, e2));
                alive[e1 as usize] = false;
                alive[e2 as usize] = false;
                alive.push(true);
                n_up[s as usize] = 0;
                n_down[s as usize] = 0;
                x_up[s as usize] = 0;
                x_down[s as usize] = 0;
                x_down[u as usize] ^= e1 ^ d;
                x_up[l as usize] ^= e2 ^ d;
                enqueue(
                    &mut heap, &n_up, &n_down, d, &upper, &lower, &up_cost, &down_cost,
                );
                reduced = Some(SimplifiedArcId(d));
            } else if degree(&n_up, &n_down, s) == 1 {
                // A node with arcs in one direction only (a collapsed
                // plateau) has become a leaf.
                let r = x_up[s as usize] ^ x_down[s as usize];
                enqueue(
                    &mut heap, &n_up, &n_down, r, &upper, &lower, &up_cost, &down_cost,
                );
            }
            steps.push(Step {
                pruned: SimplifiedArcId(a),
                lower_leaf,
                cost,
                reduced,
            });
        }
        steps
    }

    fn grid(levels: u8, max: usize) -> impl Strategy<Value = ScalarField> {
        (1..=max, 1..=max, 1..=max, 1..=levels).prop_flat_map(|(x, y, z, l)| {
            proptest::collection::vec(0..l, x * y * z)
                .prop_map(move |v| ScalarField::new([x, y, z], Values::U8(v)).expect("field"))
        })
    }

    fn same_sequence(field: &ScalarField) {
        let (tree, _) = ContourTree::from_field(field, &Progress::new()).expect("tree");
        let base = CollapsedTree::new(&tree, field);
        for measure in Measure::ALL {
            let sim = Simplification::from_collapsed(&base, measure);
            assert_eq!(
                sim.steps(),
                steps_with_one_heap(&base, measure).as_slice(),
                "{measure}"
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// `QuadHeap` pops what `BinaryHeap` pops, under any interleaving
        /// of pushes and pops (costs from a few values, so ties by arc id
        /// and repeated entries occur).
        #[test]
        fn quad_heap_pops_what_a_binary_heap_pops(
            ops in proptest::collection::vec(proptest::option::of((0u8..6, 0u32..40)), 0..300)
        ) {
            let (mut quad, mut binary) = (QuadHeap::default(), BinaryHeap::new());
            for op in ops {
                match op {
                    Some((c, arc)) => {
                        let e = Entry { cost: c as f64 * 0.5, arc };
                        quad.push(e);
                        binary.push(e);
                    }
                    None => prop_assert_eq!(quad.pop(), binary.pop()),
                }
                prop_assert_eq!(quad.len(), binary.len());
            }
            while let Some(e) = binary.pop() {
                prop_assert_eq!(quad.pop(), Some(e));
            }
            prop_assert_eq!(quad.pop(), None);
        }

        #[test]
        fn pruning_queue_gives_the_one_heap_sequence_on_random_grids(field in grid(8, 7)) {
            same_sequence(&field);
        }
    }

    #[test]
    fn pruning_queue_gives_the_one_heap_sequence_on_a_noisy_scene() {
        same_sequence(
            &crate::field::synthetic::Synthetic::cube(24)
                .with_noise(0.05, 3)
                .generate(),
        );
    }
}
