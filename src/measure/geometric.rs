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
//! maximum is not invertible, so a second, cheaper post-order rooted at the
//! global maximum gives it. Both passes are O(t) over the superarcs plus
//! one O(n) pass summing the values of the regular vertices.
//!
//! A new measure (surface area, say) adds a field to [`RegionSummary`], its
//! Update for the regular vertices of an arc, and one match arm per cost.
//!
//! **Memory:** 48 bytes per superarc ([`ArcRegions`]), 12 bytes per
//! supernode while computing; nothing per vertex.

use crate::field::{Scalar, ScalarField};
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
        let value = |n: NodeId| field.value(tree.node(n).vertex);
        // Update for the regular vertices of each arc: count, sum, and their
        // extremes (the first and last, since they ascend).
        // In parallel over the arcs, on the values in their own type.
        let regular: Vec<(u64, f64)> = crate::with_values!(field.values(), values => {
            (0..m)
                .into_par_iter()
                .map(|a| {
                    let vs = tree.arc_vertices(ArcId(a as u32));
                    let sum: f64 = vs.iter().map(|&v| values[v as usize].to_f64()).sum();
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
            if let (Some(&first), Some(&last)) = (vs.first(), vs.last()) {
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
            if let Some(&last) = tree.arc_vertices(ArcId(p)).last() {
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

/// Nodes in breadth-first order from `root`, and the arc to each node's
/// parent (`NO_ARC` at the root). Reversed, the order is a post-order.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{ScalarField, Values};
    use crate::progress::Progress;

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
}
