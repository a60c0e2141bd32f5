//! Local geometric measures of superarcs (Carr, Snoeyink, van de Panne,
//! "Simplifying flexible isosurfaces using local geometric measures", §4).
//!
//! Cut a superarc `e` just below its upper node: the side holding its
//! lower node is the region swept *upwards* along `e` (the paper's region
//! behind up(e)); pruning `e` as a lower leaf levels this region off to the
//! height `h` of the upper node. Cut it just above its lower node: the side
//! holding the upper node is the region swept *downwards*, flattened when
//! `e` is pruned as an upper leaf. Both regions contain the regular
//! vertices of `e` itself. [`ArcRegions`] summarises both sides of every
//! superarc by vertex count, sum of values, and the extreme value; each
//! [`Measure`] turns a summary and `h` into a cost:
//!
//! | measure      | up(e) (lower leaf, region `R` below)  | down(e) (upper leaf, `R` above) |
//! |--------------|---------------------------------------|---------------------------------|
//! | height       | `h - min R`                           | `max R - h`                     |
//! | volume       | `|R|`                                 | `|R|`                           |
//! | hypervolume  | `|R| h - Σ_R f`                       | `Σ_R f - |R| h`                 |
//!
//! Hypervolume is the paper's "Σ f(x) - A h": it equals `Σ_R |f(x) - h|`
//! whenever `R` lies on one side of `h`, which holds for every leaf of the
//! unsimplified tree; once branches of the other direction have been pruned
//! inside `R`, their original values are still counted (the paper computes
//! the costs once, before simplification).
//!
//! **Algorithm 1, as implemented.** The paper peels leaves inwards: at each
//! vertex it *combines* the measures of the processed arcs, *updates* by the
//! vertex swept past, *removes* the arcs on the far side and *inverts*
//! (complements) to get the other direction. A leaf-peeling order is a
//! post-order of the tree rooted at the last vertex peeled; we root the
//! tree at the global minimum, so for every arc one side (the child side)
//! is combined exactly (Combine = add the children, Update = add the node
//! and the arc's regular vertices) and the other side is its inverse
//! against the whole field (count and sum subtract). The minimum of the
//! inverted side is the global minimum, since the root lies there; the
//! maximum is not invertible, but it is the global maximum unless the
//! child side holds it, which happens only along the path from the root to
//! the global maximum: walking down that path fixes those (see
//! `ArcRegions::new`). The cost is one O(n) parallel pass summing the
//! values of the regular vertices, then O(t) over the t superarcs: a
//! breadth-first order and one pass over it. On millions of superarcs the
//! constant is cache misses, so nodes are combined by breadth-first
//! *position* (children of a node are consecutive, so parents are met in
//! nearly descending order), the pass prefetches its arcs' records, and
//! the breadth-first search prefetches, in stages, the chain of reads that
//! leads from a queued node to its neighbours (`Rooted::prefetch`). The
//! nodes' values are read once, in parallel, and shared with the collapse
//! ([`node_values`]).
//!
//! A new measure (surface area, say) adds a field to [`RegionSummary`], its
//! Update for the regular vertices of an arc, and one match arm per cost.
//!
//! **Memory:** 48 bytes per superarc ([`ArcRegions`]); while computing,
//! 32 per superarc (the regular vertices' summary) and 57 per supernode
//! (the order, the sides being combined, the values); nothing per vertex.

use crate::field::{Scalar, ScalarField};
use crate::tree::sweep::prefetch;
use crate::tree::{ArcId, ContourTree, NodeId};
use rayon::prelude::*;

/// The local geometric measure that ranks leaves for pruning.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Measure {
    /// Persistence: the range of values levelled off.
    Height,
    /// The number of vertices levelled off.
    Volume,
    /// The sum over the levelled region of the height change, the paper's
    /// favourite for exploring data.
    #[default]
    Hypervolume,
}

impl Measure {
    /// Every measure, for menus.
    pub const ALL: [Measure; 3] = [Measure::Height, Measure::Volume, Measure::Hypervolume];

    /// Lower-case name, as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Measure::Height => "height",
            Measure::Volume => "volume",
            Measure::Hypervolume => "hypervolume",
        }
    }

    /// One line on what the measure ranks by (for help texts).
    pub fn summary(self) -> &'static str {
        match self {
            Measure::Height => "Persistence: the range of values levelled off",
            Measure::Volume => "The number of vertices levelled off",
            Measure::Hypervolume => {
                "The sum over the levelled region of the height change, the paper's favourite for exploring data"
            }
        }
    }

    /// up(e): the cost of pruning an arc as a lower leaf, levelling the
    /// region `below` (its lower side) up to the height `h` of its upper end.
    pub fn up_cost(self, below: &RegionSummary, h: f64) -> f64 {
        match self {
            Measure::Height => h - below.extreme,
            Measure::Volume => below.count as f64,
            Measure::Hypervolume => below.count as f64 * h - below.sum,
        }
    }

    /// down(e): the cost of pruning an arc as an upper leaf, levelling the
    /// region `above` (its upper side) down to the height `h` of its lower end.
    pub fn down_cost(self, above: &RegionSummary, h: f64) -> f64 {
        match self {
            Measure::Height => above.extreme - h,
            Measure::Volume => above.count as f64,
            Measure::Hypervolume => above.sum - above.count as f64 * h,
        }
    }
}

/// A name that is not a measure's.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{0}' is not a measure (height, volume, hypervolume)")]
pub struct UnknownMeasure(pub String);

impl std::str::FromStr for Measure {
    type Err = UnknownMeasure;

    /// The measure [`Measure::name`] spells `s` (any case).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Measure::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownMeasure(s.to_string()))
    }
}

impl std::fmt::Display for Measure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What the measures need to know of one side of a cut superarc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionSummary {
    /// Number of vertices (volume).
    pub count: u64,
    /// Sum of their values.
    pub sum: f64,
    /// The lowest value for a region below an arc, the highest for a
    /// region above.
    pub extreme: f64,
}

/// The value of every node of `tree`, by node id, read in parallel (the
/// nodes' vertices lie all over the field: one cache miss each).
pub fn node_values(tree: &ContourTree, field: &ScalarField) -> Vec<f64> {
    tree.nodes()
        .par_iter()
        .map(|n| field.value(n.vertex))
        .collect()
}

/// Both sides of every superarc of a tree, indexed by [`ArcId`].
#[derive(Clone, Debug, Default)]
pub struct ArcRegions {
    below: Vec<RegionSummary>,
    above: Vec<RegionSummary>,
}

impl ArcRegions {
    /// Algorithm 1: summaries of both sides of every superarc (see the
    /// module documentation). Reads each value of the field once.
    pub fn new(tree: &ContourTree, field: &ScalarField) -> Self {
        Self::with_node_values(tree, field, &node_values(tree, field))
    }

    /// As [`ArcRegions::new`], with the value of every node of `tree`
    /// already read ([`node_values`]; the collapse needs them too).
    pub fn with_node_values(tree: &ContourTree, field: &ScalarField, node_value: &[f64]) -> Self {
        let arcs = tree.arcs();
        let nodes = tree.nodes();
        let m = arcs.len();
        let mut below = vec![
            RegionSummary {
                count: 0,
                sum: 0.0,
                extreme: 0.0
            };
            m
        ];
        let mut above = below.clone();
        if nodes.is_empty() {
            return Self { below, above };
        }
        // Update for the regular vertices of each arc: count, sum, and their
        // extremes (the first and last, since they ascend). In parallel over
        // the arcs, on the values in their own type, so the pass over the
        // tree below reads one record per arc and no vertex.
        // Side by side with rooting the tree (a serial breadth-first
        // search): neither reads what the other makes.
        let (regular, rooted) = rayon::join(
            || -> Vec<Regular> {
                crate::with_values!(field.values(), values => {
                    balanced_arc_ranges(tree)
                        .into_par_iter()
                        .flat_map_iter(|arcs| arcs.map(|a| {
                            let vs = tree.arc_vertices(ArcId(a as u32));
                            let sum: f64 = vs.iter().map(|v| values[v as usize].to_f64()).sum();
                            let (first, last) = match (vs.first(), vs.last()) {
                                (Some(f), Some(l)) => (values[f as usize].to_f64(), values[l as usize].to_f64()),
                                _ => (f64::NAN, f64::NAN),
                            };
                            Regular { count: vs.len() as u64, sum, first, last }
                        }))
                        .collect()
                })
            },
            || Rooted::new(tree, NodeId(0)),
        );
        let (total_count, total_sum) = {
            let s: f64 =
                regular.iter().map(|r| r.sum).sum::<f64>() + node_value.iter().sum::<f64>();
            (field.len() as u64, s)
        };
        let global_min = node_value[0];
        let global_max = node_value[nodes.len() - 1];

        // Rooted at the global minimum: count, sum, min, max of every child
        // side, by position in breadth-first order (see `Rooted`).
        let mut sub: Vec<Side> = rooted
            .order
            .par_iter()
            .map(|&v| {
                let f = node_value[v as usize];
                Side {
                    count: 1,
                    sum: f,
                    min: f,
                    max: f,
                }
            })
            .collect();
        for i in (1..rooted.order.len()).rev() {
            if let Some(&p) = rooted.parent_arc.get(i.wrapping_sub(PREFETCH)) {
                prefetch(&regular, p as usize);
                prefetch(&below, p as usize);
                prefetch(&above, p as usize);
            }
            let p = rooted.parent_arc[i] as usize;
            let r = regular[p];
            let child = sub[i];
            // Combine the child side with the arc's own regular vertices.
            let count = child.count + r.count;
            let sum = child.sum + r.sum;
            let (mut lo, mut hi) = (child.min, child.max);
            if r.count > 0 {
                lo = lo.min(r.first);
                hi = hi.max(r.last);
            }
            // Invert: the parent side is the field minus the child side,
            // plus the arc's regular vertices, which both sides hold.
            let inv_count = total_count - count + r.count;
            let inv_sum = total_sum - sum + r.sum;
            if rooted.child_is_lower[i] {
                below[p] = RegionSummary {
                    count,
                    sum,
                    extreme: lo,
                };
                // The parent side holds the global maximum unless the
                // child side does (the path fixed below).
                above[p] = RegionSummary {
                    count: inv_count,
                    sum: inv_sum,
                    extreme: global_max,
                };
            } else {
                above[p] = RegionSummary {
                    count,
                    sum,
                    extreme: hi,
                };
                // The parent side holds the root, the global minimum.
                below[p] = RegionSummary {
                    count: inv_count,
                    sum: inv_sum,
                    extreme: global_min,
                };
            }
            // Combine into the parent node.
            let parent = &mut sub[rooted.parent_pos[i] as usize];
            parent.count += count;
            parent.sum += sum;
            parent.min = parent.min.min(lo);
            parent.max = parent.max.max(hi);
        }

        // The child sides holding the global maximum are those of the path
        // from the root to it. Going down it, the maximum outside the
        // child side of the next node is the maximum outside this one's,
        // this node, and the child sides of its other children (with their
        // arcs' regular vertices), and the regular vertices of the arc
        // followed: O(path and the degrees along it), not another pass.
        let top = nodes.len() - 1;
        let mut path = vec![top as u32];
        let mut at = rooted.pos[top] as usize;
        while at != 0 {
            at = rooted.parent_pos[at] as usize;
            path.push(rooted.order[at]);
        }
        path.reverse();
        let mut outside = f64::NEG_INFINITY;
        for w in path.windows(2) {
            let (q, next) = (NodeId(w[0]), w[1]);
            let via = rooted.parent_arc[rooted.pos[next as usize] as usize];
            let mut m = outside.max(node_value[q.0 as usize]);
            for &a in tree.up_arcs(q).iter().chain(tree.down_arcs(q)) {
                let arc = tree.arc(a);
                let u = if arc.lower == q { arc.upper } else { arc.lower };
                let pu = rooted.pos[u.0 as usize] as usize;
                if rooted.parent_arc[pu] != a.0 {
                    continue; // the arc to q's parent
                }
                let r = &regular[a.0 as usize];
                if r.count > 0 {
                    m = m.max(r.last);
                }
                if a.0 != via {
                    m = m.max(sub[pu].max);
                }
            }
            outside = m;
            if tree.arc(ArcId(via)).lower.0 == next {
                above[via as usize].extreme = outside;
            }
        }
        Self { below, above }
    }

    /// The region below a superarc (its lower side, regular vertices
    /// included): what pruning it as a lower leaf levels off.
    pub fn below(&self, arc: ArcId) -> &RegionSummary {
        &self.below[arc.0 as usize]
    }

    /// The region above a superarc: what pruning it as an upper leaf
    /// levels off.
    pub fn above(&self, arc: ArcId) -> &RegionSummary {
        &self.above[arc.0 as usize]
    }

    /// Number of superarcs summarised.
    pub fn len(&self) -> usize {
        self.below.len()
    }

    /// True when the tree had no arcs.
    pub fn is_empty(&self) -> bool {
        self.below.is_empty()
    }
}

const NO_ARC: u32 = u32::MAX;

/// How many nodes ahead the pass over the tree prefetches its arc's
/// records.
const PREFETCH: usize = 16;

/// What the regular vertices of one superarc add to a region: count, sum,
/// and the first and last values (their min and max, since they ascend;
/// NaN when there are none).
#[derive(Clone, Copy, Debug)]
struct Regular {
    count: u64,
    sum: f64,
    first: f64,
    last: f64,
}

/// The arcs `0..m` of `tree` cut into ranges of about equal work (a few
/// per thread), an arc's work its regular vertices and a few more for the
/// arc itself: on smooth fields a few arcs hold most vertices and get a
/// range each (an arc heavier than a range's share starts the only range
/// it is in), on white noise millions of arcs of a few vertices are shared
/// out in large ranges instead of one task each.
fn balanced_arc_ranges(tree: &ContourTree) -> Vec<std::ops::Range<usize>> {
    /// An arc's own work, in vertices.
    const ARC_WORK: u64 = 8;
    let offsets = tree.arc_vertex_offsets();
    let m = offsets.len() - 1;
    let work = |a: usize| offsets[a] as u64 + ARC_WORK * a as u64;
    let pieces = (rayon::current_num_threads() * 16).clamp(1, m.max(1)) as u64;
    let total = work(m);
    let mut starts: Vec<usize> = (0..pieces)
        .map(|i| {
            // The first arc whose work starts at or past piece i's share.
            let (mut lo, mut hi) = (0, m);
            while lo < hi {
                let mid = (lo + hi) / 2;
                if work(mid) * pieces < total * i {
                    lo = mid + 1;
                } else {
                    hi = mid;
                }
            }
            lo
        })
        .collect();
    starts.dedup();
    starts.push(m);
    starts.windows(2).map(|w| w[0]..w[1]).collect()
}

/// A region being combined: count, sum, min and max, one record so that
/// combining a child into its parent touches two records.
#[derive(Clone, Copy, Debug)]
struct Side {
    count: u64,
    sum: f64,
    min: f64,
    max: f64,
}

/// The tree rooted at a node, nodes numbered by *position* in
/// breadth-first order. Reversed, the order is a post-order; and as the
/// children of a node get consecutive positions after their parent's,
/// parents' positions descend as the reversed order goes, so combining
/// children into parents by position walks memory nearly in order
/// instead of jumping by node id.
struct Rooted {
    /// Per position: its node.
    order: Vec<u32>,
    /// Per position: the arc to its parent (`NO_ARC` at the root).
    parent_arc: Vec<u32>,
    /// Per position: its parent's position (0 at the root).
    parent_pos: Vec<u32>,
    /// Per position: true when the node is its parent arc's lower end.
    child_is_lower: Vec<bool>,
    /// Per node: its position.
    pos: Vec<u32>,
}

impl Rooted {
    fn new(tree: &ContourTree, root: NodeId) -> Self {
        let n = tree.nodes().len();
        let mut r = Self {
            order: Vec::with_capacity(n),
            parent_arc: Vec::with_capacity(n),
            parent_pos: Vec::with_capacity(n),
            child_is_lower: Vec::with_capacity(n),
            pos: vec![NO_ARC; n],
        };
        r.order.push(root.0);
        r.parent_arc.push(NO_ARC);
        r.parent_pos.push(0);
        r.child_is_lower.push(false);
        r.pos[root.0 as usize] = 0;
        let mut head = 0;
        while head < r.order.len() {
            r.prefetch(tree, head);
            let v = NodeId(r.order[head]);
            for &a in tree.node_arcs(v) {
                let arc = tree.arc(a);
                let u = if arc.lower == v { arc.upper } else { arc.lower };
                if r.pos[u.0 as usize] == NO_ARC {
                    r.pos[u.0 as usize] = r.order.len() as u32;
                    r.order.push(u.0);
                    r.parent_arc.push(a.0);
                    r.parent_pos.push(head as u32);
                    r.child_is_lower.push(arc.lower == u);
                }
            }
            head += 1;
        }
        r
    }

    /// Hints the cache about what the breadth-first search reads for the
    /// nodes queued after `head`: a node's arcs are found through three
    /// dependent reads (offsets, list, arc records) and lead to a fourth
    /// (the far end's position), all scattered, so each is prefetched one
    /// stage ahead of the next, `BFS_AHEAD` nodes apart; by the time the
    /// search reaches a node, its reads are in cache. (The queue is ahead
    /// of `head` except near the start and the end, where this does
    /// nothing.)
    fn prefetch(&self, tree: &ContourTree, head: usize) {
        let at = |k: usize| self.order.get(head + k * BFS_AHEAD).map(|&v| NodeId(v));
        if let Some(v) = at(4) {
            tree.prefetch_node_arcs(v);
        }
        if let Some(v) = at(3) {
            prefetch(tree.node_arcs(v), 0);
        }
        if let Some(v) = at(2) {
            for &a in tree.node_arcs(v) {
                prefetch(tree.arcs(), a.0 as usize);
            }
        }
        if let Some(v) = at(1) {
            for &a in tree.node_arcs(v) {
                let arc = tree.arc(a);
                let u = if arc.lower == v { arc.upper } else { arc.lower };
                prefetch(&self.pos, u.0 as usize);
            }
        }
    }
}

/// The distance, in queued nodes, between the stages of
/// [`Rooted::prefetch`].
const BFS_AHEAD: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{ScalarField, Values};
    use crate::progress::Progress;
    use proptest::prelude::*;

    /// A 1D field: 0 3 1 4 2 -> minima 0,1,2 at x=0,2,4, maxima at 1,3.
    #[test]
    fn regions_of_a_zigzag_are_the_pieces_beyond_each_cut() {
        let field = ScalarField::new([5, 1, 1], Values::U8(vec![0, 3, 1, 4, 2])).expect("field");
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("tree");
        let r = ArcRegions::new(&tree, &field);
        for (i, arc) in tree.arcs().iter().enumerate() {
            let (b, a) = (r.below(ArcId(i as u32)), r.above(ArcId(i as u32)));
            // Both sides share the arc's regular vertices.
            let reg = tree.arc_vertices(ArcId(i as u32)).len() as u64;
            assert_eq!(b.count + a.count, 5 + reg, "arc {arc:?}");
            assert!(b.extreme <= field.value(tree.node(arc.lower).vertex));
            assert!(a.extreme >= field.value(tree.node(arc.upper).vertex));
        }
    }

    /// Algorithm 1 as flexiso computed it before the single pass by
    /// breadth-first position: a second post-order, rooted at the global
    /// maximum, for the maxima of the sides above.
    fn regions_with_two_passes(tree: &ContourTree, field: &ScalarField) -> ArcRegions {
        let arcs = tree.arcs();
        let nodes = tree.nodes();
        let m = arcs.len();
        let mut below = vec![
            RegionSummary {
                count: 0,
                sum: 0.0,
                extreme: 0.0
            };
            m
        ];
        let mut above = below.clone();
        if nodes.is_empty() {
            return ArcRegions { below, above };
        }
        let value = |n: NodeId| field.value(tree.node(n).vertex);
        // Update for the regular vertices of each arc: count, sum, and their
        // extremes (the first and last, since they ascend).
        // In parallel over the arcs, on the values in their own type.
        let regular: Vec<(u64, f64)> = crate::with_values!(field.values(), values => {
            (0..m)
                .into_par_iter()
                .map(|a| {
                    let vs = tree.arc_vertices(ArcId(a as u32));
                    let sum: f64 = vs.iter().map(|v| values[v as usize].to_f64()).sum();
                    (vs.len() as u64, sum)
                })
                .collect()
        });
        let (total_count, total_sum) = {
            let s: f64 = regular.iter().map(|r| r.1).sum::<f64>()
                + nodes.iter().map(|n| field.value(n.vertex)).sum::<f64>();
            (field.len() as u64, s)
        };
        let global_min = value(NodeId(0));
        let global_max = value(NodeId(nodes.len() as u32 - 1));

        // Pass 1, rooted at the global minimum: count, sum, min, max of
        // every child side.
        let (order, parent) = rooted_order(tree, NodeId(0));
        let mut sub_count = vec![0u64; nodes.len()];
        let mut sub_sum = vec![0f64; nodes.len()];
        let mut sub_min = vec![0f64; nodes.len()];
        let mut sub_max = vec![0f64; nodes.len()];
        for (i, n) in nodes.iter().enumerate() {
            let f = field.value(n.vertex);
            sub_count[i] = 1;
            sub_sum[i] = f;
            sub_min[i] = f;
            sub_max[i] = f;
        }
        for &v in order.iter().rev() {
            let p = parent[v.0 as usize];
            if p == NO_ARC {
                continue;
            }
            let arc = tree.arc(ArcId(p));
            let vs = tree.arc_vertices(ArcId(p));
            let (rc, rs) = regular[p as usize];
            let vi = v.0 as usize;
            // Combine the child side with the arc's own regular vertices.
            let count = sub_count[vi] + rc;
            let sum = sub_sum[vi] + rs;
            let (mut lo, mut hi) = (sub_min[vi], sub_max[vi]);
            if let (Some(first), Some(last)) = (vs.first(), vs.last()) {
                lo = lo.min(field.value(first));
                hi = hi.max(field.value(last));
            }
            // Invert: the parent side is the field minus the child side,
            // plus the arc's regular vertices, which both sides hold.
            let inv_count = total_count - count + rc;
            let inv_sum = total_sum - sum + rs;
            if arc.lower == v {
                below[p as usize] = RegionSummary {
                    count,
                    sum,
                    extreme: lo,
                };
                // The max of this (parent) side comes from pass 2.
                above[p as usize] = RegionSummary {
                    count: inv_count,
                    sum: inv_sum,
                    extreme: f64::NAN,
                };
            } else {
                above[p as usize] = RegionSummary {
                    count,
                    sum,
                    extreme: hi,
                };
                // The parent side holds the root, the global minimum.
                below[p as usize] = RegionSummary {
                    count: inv_count,
                    sum: inv_sum,
                    extreme: global_min,
                };
            }
            // Combine into the parent node.
            let u = if arc.lower == v { arc.upper } else { arc.lower };
            let ui = u.0 as usize;
            sub_count[ui] += count;
            sub_sum[ui] += sum;
            sub_min[ui] = sub_min[ui].min(lo);
            sub_max[ui] = sub_max[ui].max(hi);
        }

        // Pass 2, rooted at the global maximum: the max of the sides above
        // arcs whose upper side held the minimum in pass 1.
        let top = NodeId(nodes.len() as u32 - 1);
        let (order, parent) = rooted_order(tree, top);
        for (i, n) in nodes.iter().enumerate() {
            sub_max[i] = field.value(n.vertex);
        }
        for &v in order.iter().rev() {
            let p = parent[v.0 as usize];
            if p == NO_ARC {
                continue;
            }
            let arc = tree.arc(ArcId(p));
            let vi = v.0 as usize;
            let mut hi = sub_max[vi];
            if let Some(last) = tree.arc_vertices(ArcId(p)).last() {
                hi = hi.max(field.value(last));
            }
            if arc.upper == v {
                above[p as usize].extreme = hi;
            } else {
                above[p as usize].extreme = global_max;
            }
            let u = if arc.lower == v { arc.upper } else { arc.lower };
            sub_max[u.0 as usize] = sub_max[u.0 as usize].max(hi);
        }
        ArcRegions { below, above }
    }

    /// Nodes in breadth-first order from `root`, and the arc to each
    /// node's parent (`NO_ARC` at the root).
    fn rooted_order(tree: &ContourTree, root: NodeId) -> (Vec<NodeId>, Vec<u32>) {
        let n = tree.nodes().len();
        let mut parent = vec![NO_ARC; n];
        let mut seen = vec![false; n];
        let mut order = Vec::with_capacity(n);
        order.push(root);
        seen[root.0 as usize] = true;
        let mut head = 0;
        while head < order.len() {
            let v = order[head];
            head += 1;
            for &a in tree.up_arcs(v).iter().chain(tree.down_arcs(v)) {
                let arc = tree.arc(a);
                let u = if arc.lower == v { arc.upper } else { arc.lower };
                if !seen[u.0 as usize] {
                    seen[u.0 as usize] = true;
                    parent[u.0 as usize] = a.0;
                    order.push(u);
                }
            }
        }
        (order, parent)
    }

    fn grid(levels: u8, max: usize) -> impl Strategy<Value = ScalarField> {
        (1..=max, 1..=max, 1..=max, 1..=levels).prop_flat_map(|(x, y, z, l)| {
            proptest::collection::vec(0..l, x * y * z)
                .prop_map(move |v| ScalarField::new([x, y, z], Values::U8(v)).expect("field"))
        })
    }

    fn same_regions(field: &ScalarField) {
        let (tree, _) = ContourTree::from_field(field, &Progress::new()).expect("tree");
        let (new, old) = (
            ArcRegions::new(&tree, field),
            regions_with_two_passes(&tree, field),
        );
        for a in 0..tree.arcs().len() as u32 {
            // Bit for bit: the sums are added in the same order.
            for (n, o) in [
                (new.below(ArcId(a)), old.below(ArcId(a))),
                (new.above(ArcId(a)), old.above(ArcId(a))),
            ] {
                assert_eq!(n.count, o.count, "arc {a}");
                assert_eq!(n.sum.to_bits(), o.sum.to_bits(), "arc {a}");
                assert_eq!(n.extreme.to_bits(), o.extreme.to_bits(), "arc {a}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn one_pass_regions_equal_the_two_pass_ones_on_random_grids(field in grid(8, 7)) {
            same_regions(&field);
        }
    }

    #[test]
    fn one_pass_regions_equal_the_two_pass_ones_on_a_noisy_scene() {
        same_regions(
            &crate::field::synthetic::Synthetic::cube(24)
                .with_noise(0.05, 3)
                .generate(),
        );
    }
}
