//! What to show first: the level of simplification at the curve's widest
//! plateau, and the most important branches there, each with the arc and
//! isovalue of a contour that represents it (Carr, Snoeyink, van de Panne,
//! §5: "the simplification curve ... plateaus suggest natural levels").
//!
//! **The level.** A level of `k` arcs stays on screen while the feature
//! size grows from its own (the highest cost pruned to reach it) to the
//! cost of the next step: on the log-log curve a horizontal run whose
//! length is `log(next cost / feature size)`. A long run means a big gap
//! between the features kept and those pruned: the tree there separates
//! signal from noise. [`first_screen_step`] takes the longest run among the
//! levels of [`FIRST_SCREEN_ARCS`] arcs (few enough to read, enough to show
//! something); ties go to the level with more arcs. A level of feature
//! size 0 (a label map's zero-cost prunes) measures its run from the
//! smallest positive cost of the sequence, so it never wins by division
//! by zero.
//!
//! **The branches.** A branch's importance is its pruning step (pruned
//! later = larger feature under the measure, [`super::branches`]). The
//! root branches, left when everything else is pruned, are the
//! background trunk that spans the data's whole range: they are left out,
//! and so is any branch whose range covers [`BACKGROUND_SPAN`] of the
//! values (the global extremum's branch in a scan: air, or the whole
//! head). [`important_branches`] takes the most important of the rest.
//!
//! **The isovalue.** Along a branch going up, the region its contour
//! encloses shrinks from the saddle it hangs from towards its maximum
//! (down: towards its minimum). The branch's arc next to that saddle
//! carries its largest contours that are still one component at this
//! level, each enclosing every sub-branch; its middle value is the
//! farthest from both of its nodes, so the contour shown there is not
//! about to split or merge. For a branch of one arc that is the middle of
//! its range. (The value where the contour's area peaks would need a
//! contour per candidate value: too slow for the first screen.)
//!
//! **Cost:** O(a log a) for the a live arcs of a level, plus the curve
//! once (O(steps)).

use super::branches::{BranchId, Branches};
use super::{CollapsedTree, Simplification, SimplifiedArcId, SimplifiedTree};
use crate::tree::ContourTree;

/// Arcs a first screen shows at least and at most (when the tree has
/// that many).
pub const FIRST_SCREEN_ARCS: std::ops::RangeInclusive<usize> = 8..=60;

/// A branch whose values cover this fraction of the data's range is
/// background, not a feature.
pub const BACKGROUND_SPAN: f64 = 0.9;

/// The number of steps to the level a first screen shows (see the module
/// documentation): the widest plateau of the curve among the levels with
/// [`FIRST_SCREEN_ARCS`] arcs; when no level has so many, the level of the
/// most arcs below the range (or the full tree when it has fewer).
pub fn first_screen_step(sim: &Simplification) -> usize {
    let curve = sim.curve();
    let steps = sim.steps();
    let smallest = steps
        .iter()
        .map(|s| s.cost)
        .filter(|c| *c > 0.0)
        .fold(f64::INFINITY, f64::min);
    let mut best: Option<(f64, usize)> = None;
    for (s, p) in curve.iter().enumerate() {
        if !FIRST_SCREEN_ARCS.contains(&p.arcs) {
            continue;
        }
        // The run ends where the next step's cost exceeds this feature
        // size; the last level runs to infinity (the whole curve's end).
        let next = match steps.get(s) {
            Some(st) => st.cost,
            None => f64::INFINITY,
        };
        let from = p.feature_size.max(smallest);
        let width = if next.is_infinite() {
            f64::INFINITY
        } else if next > from && from.is_finite() && from > 0.0 {
            (next / from).ln()
        } else {
            0.0
        };
        // Wider wins; on a tie, the earlier level (more arcs).
        if best.is_none_or(|(w, _)| width > w) {
            best = Some((width, s));
        }
    }
    match best {
        Some((_, s)) => s,
        None => sim.steps_for_arcs(*FIRST_SCREEN_ARCS.end()),
    }
}

/// A branch to show as a contour: which branch, the live arc holding the
/// representative contour, its isovalue, and the branch's importance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feature {
    /// The branch.
    pub branch: BranchId,
    /// The live arc whose contour represents it.
    pub arc: SimplifiedArcId,
    /// The isovalue of that contour (inside the arc's range).
    pub h: f64,
    /// The cost the branch is pruned at (its size under the measure).
    pub cost: f64,
}

/// The `max` most important branches live at `level` (most important
/// first), leaving out the background (see the module documentation),
/// each with its representative contour. `range` is the data's smallest
/// and largest value.
pub fn important_branches(
    level: &SimplifiedTree,
    branches: &Branches,
    range: (f64, f64),
    max: usize,
) -> Vec<Feature> {
    let sim = level.simplification();
    let span = (range.1 - range.0).max(0.0);
    // Per live branch: its arc nearest the saddle it hangs from, i.e. the
    // lowest arc of a branch going up, the highest of one going down.
    let mut first: std::collections::HashMap<BranchId, (SimplifiedArcId, f64, f64)> =
        std::collections::HashMap::new();
    let mut ids: Vec<u32> = level.arc_ids().to_vec();
    ids.sort_unstable();
    for a in ids {
        let a = SimplifiedArcId(a);
        let b = branches.of_arc(a);
        if (b.0 as usize) >= branches.steps() {
            continue; // a root: the background trunk
        }
        let (hi, lo) = (sim.node_value(sim.upper(a)), sim.node_value(sim.lower(a)));
        let down = branches.goes_down(b);
        let better = |(_, l, h): (SimplifiedArcId, f64, f64)| {
            if down { hi > h } else { lo < l }
        };
        match first.get(&b) {
            Some(&cur) if !better(cur) => {}
            _ => {
                first.insert(b, (a, lo, hi));
            }
        }
    }
    let mut out: Vec<Feature> = first
        .into_iter()
        .filter_map(|(b, (arc, lo, hi))| {
            let cost = sim.steps()[b.0 as usize].cost;
            // The whole branch: from its saddle to its tip.
            let tip = branches.tip(b).map(|n| sim.node_value(n));
            let saddle = branches.attachment(b).map(|n| sim.node_value(n));
            let reach = match (tip, saddle) {
                (Some(t), Some(s)) => (t - s).abs(),
                _ => hi - lo,
            };
            if span > 0.0 && reach >= BACKGROUND_SPAN * span {
                return None;
            }
            (hi > lo).then_some(Feature {
                branch: b,
                arc,
                h: 0.5 * (lo + hi),
                cost,
            })
        })
        .collect();
    // Pruned later first (the step orders by cost, ties included).
    out.sort_by_key(|x| std::cmp::Reverse(x.branch));
    out.truncate(max);
    out
}

/// The vertices on the two sides of the contours of arc `a` (of any
/// level): `below`, the region on its lower node's side of a cut just
/// below its upper node (what pruning it as a lower leaf levels off), and
/// `above`, the upper node's side of a cut just above its lower node. Both
/// hold the arc's own vertices; the smaller one is what a contour of the
/// arc encloses. Read off the collapsed tree's region summaries (paper
/// §4, Algorithm 1), O(1): a reduced arc's sides are those of the top and
/// bottom arcs of its chain.
pub fn arc_regions(
    sim: &Simplification,
    collapsed: &CollapsedTree,
    a: SimplifiedArcId,
) -> Option<ArcSides> {
    let chain = sim.chain(a);
    let base = |s: crate::tree::ArcId| {
        sim.superarc_base
            .get(s.0 as usize)
            .copied()
            .filter(|&b| (b as usize) < collapsed.num_arcs())
    };
    let top = base(*chain.last()?)?;
    let bottom = base(*chain.first()?)?;
    Some(ArcSides {
        below: collapsed.below(top).count,
        above: collapsed.above(bottom).count,
    })
}

/// The two sides of an arc's contours, in vertices ([`arc_regions`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArcSides {
    /// Vertices on the lower node's side.
    pub below: u64,
    /// Vertices on the upper node's side.
    pub above: u64,
}

impl ArcSides {
    /// The side a contour encloses (the smaller), and true when it is
    /// the one above.
    pub fn enclosed(&self) -> (u64, bool) {
        if self.above <= self.below {
            (self.above, true)
        } else {
            (self.below, false)
        }
    }
}

/// Where the contours of an arc lie: the grid box and centroid of the
/// regular vertices of its chain of superarcs (the vertices its contours
/// sweep over as the isovalue runs along the arc), in grid indices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent {
    /// Smallest index on each axis.
    pub min: [usize; 3],
    /// Largest index on each axis.
    pub max: [usize; 3],
    /// Mean index of the vertices read.
    pub centroid: [f64; 3],
    /// Vertices on the chain (all of them, read or not).
    pub vertices: usize,
}

/// The [`Extent`] of arc `a`'s contours from the augmented tree's vertex
/// lists, reading at most `budget` vertices (evenly strided when the
/// chain holds more: the box may then miss a few outermost vertices, the
/// centroid is a sample mean). None when the chain has no regular vertex.
/// O(min(chain vertices, budget)).
pub fn arc_extent(
    tree: &ContourTree,
    sim: &Simplification,
    dims: [usize; 3],
    a: SimplifiedArcId,
    budget: usize,
) -> Option<Extent> {
    let chain = sim.chain(a);
    let total: usize = chain.iter().map(|&s| tree.arc_vertices(s).len()).sum();
    if total == 0 || dims.contains(&0) {
        return None;
    }
    let stride = total.div_ceil(budget.max(1)).max(1);
    let (nx, nxy) = (dims[0], dims[0] * dims[1]);
    let mut min = [usize::MAX; 3];
    let mut max = [0usize; 3];
    let mut sum = [0f64; 3];
    let mut read = 0usize;
    let mut i = 0usize;
    for &s in chain {
        for v in tree.arc_vertices(s) {
            if i.is_multiple_of(stride) {
                let v = v as usize;
                let c = [v % nx, (v / nx) % dims[1], v / nxy];
                for (k, &ck) in c.iter().enumerate() {
                    min[k] = min[k].min(ck);
                    max[k] = max[k].max(ck);
                    sum[k] += ck as f64;
                }
                read += 1;
            }
            i += 1;
        }
    }
    let n = read.max(1) as f64;
    Some(Extent {
        min,
        max,
        centroid: [sum[0] / n, sum[1] / n, sum[2] / n],
        vertices: total,
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::simplify::Measure;
    use crate::tree::ContourTree;
    use std::sync::Arc;

    fn sim_of(noise: f32, n: usize) -> Arc<Simplification> {
        let field = Synthetic {
            noise,
            ..Synthetic::cube(n)
        }
        .generate();
        let (tree, _) = ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
        Arc::new(Simplification::new(&tree, &field, Measure::Hypervolume))
    }

    /// The run of each level on the curve, by brute force from the
    /// definition.
    fn plateau_width(sim: &Simplification, s: usize) -> f64 {
        let smallest = sim
            .steps()
            .iter()
            .map(|s| s.cost)
            .filter(|c| *c > 0.0)
            .fold(f64::INFINITY, f64::min);
        match sim.steps().get(s) {
            None => f64::INFINITY,
            Some(st) => {
                let from = sim.curve()[s].feature_size.max(smallest);
                if st.cost > from {
                    (st.cost / from).ln()
                } else {
                    0.0
                }
            }
        }
    }

    #[test]
    fn the_first_screen_is_the_widest_plateau_with_a_readable_number_of_arcs() {
        for (noise, n) in [(0.0, 16), (0.2, 14), (0.5, 12), (1.0, 10)] {
            let sim = sim_of(noise, n);
            let s = first_screen_step(&sim);
            let arcs = sim.curve()[s].arcs;
            let in_range: Vec<usize> = (0..sim.curve().len())
                .filter(|&k| FIRST_SCREEN_ARCS.contains(&sim.curve()[k].arcs))
                .collect();
            if in_range.is_empty() {
                assert!(arcs < *FIRST_SCREEN_ARCS.start() || s == sim.steps().len());
                continue;
            }
            assert!(
                FIRST_SCREEN_ARCS.contains(&arcs),
                "noise {noise}: {arcs} arcs"
            );
            let w = plateau_width(&sim, s);
            for k in in_range {
                assert!(
                    plateau_width(&sim, k) <= w,
                    "noise {noise}: level {k} has a wider plateau than the chosen {s}"
                );
            }
        }
    }

    #[test]
    fn important_branches_are_live_non_root_and_ranked_with_their_contour_inside_the_arc() {
        let sim = sim_of(0.3, 14);
        let branches = Branches::new(&sim);
        let mut level = SimplifiedTree::new(Arc::clone(&sim));
        level.set_step(first_screen_step(&sim));
        let lo = (0..sim.num_nodes() as u32)
            .map(|n| sim.node_value(crate::simplify::SimplifiedNodeId(n)))
            .fold(f64::INFINITY, f64::min);
        let hi = (0..sim.num_nodes() as u32)
            .map(|n| sim.node_value(crate::simplify::SimplifiedNodeId(n)))
            .fold(f64::NEG_INFINITY, f64::max);
        let f = important_branches(&level, &branches, (lo, hi), 6);
        assert!(!f.is_empty(), "a noisy cube has features");
        assert!(f.len() <= 6);
        for w in f.windows(2) {
            assert!(w[0].branch > w[1].branch, "most important first");
            assert!(w[0].cost >= w[1].cost);
        }
        for x in &f {
            assert!(level.is_live(x.arc));
            assert_eq!(branches.of_arc(x.arc), x.branch);
            assert!((x.branch.0 as usize) < branches.steps(), "no root");
            let a = level.arc(x.arc);
            let (vu, vl) = (sim.node_value(a.upper), sim.node_value(a.lower));
            assert!(vl < x.h && x.h < vu, "the isovalue is inside the arc");
            // Nearest the saddle: no other live arc of the branch lies
            // between it and the saddle.
            for other in level.arcs().filter(|o| branches.of_arc(o.id) == x.branch) {
                let (ou, ol) = (sim.node_value(other.upper), sim.node_value(other.lower));
                if branches.goes_down(x.branch) {
                    assert!(ou <= vu);
                } else {
                    assert!(ol >= vl);
                }
            }
        }
        // Every live non-root, non-background branch more important than
        // the last one shown is shown.
        if let Some(last) = f.last() {
            for a in level.arcs() {
                let b = branches.of_arc(a.id);
                if (b.0 as usize) < branches.steps() && b > last.branch {
                    let reach = match (branches.tip(b), branches.attachment(b)) {
                        (Some(t), Some(s)) => (sim.node_value(t) - sim.node_value(s)).abs(),
                        _ => 0.0,
                    };
                    if reach < BACKGROUND_SPAN * (hi - lo) {
                        assert!(f.iter().any(|x| x.branch == b), "branch {b:?} left out");
                    }
                }
            }
        }
    }

    #[test]
    fn an_arcs_sides_partition_the_volume_and_its_extent_boxes_its_vertices() {
        let field = Synthetic {
            noise: 0.3,
            ..Synthetic::cube(12)
        }
        .generate();
        let (tree, _) = ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
        let collapsed = CollapsedTree::new(&tree, &field);
        let sim = Arc::new(Simplification::from_collapsed(&collapsed, Measure::Volume));
        let n = field.dims().iter().product::<usize>() as u64;
        let mut level = SimplifiedTree::new(Arc::clone(&sim));
        for step in [0, sim.steps().len() / 2] {
            level.set_step(step);
            for a in level.arcs() {
                let sides = arc_regions(&sim, &collapsed, a.id).unwrap();
                // The sides overlap in the arc's own vertices, and cover
                // everything between them.
                let own: u64 = a
                    .chain
                    .iter()
                    .map(|&s| tree.arc_vertices(s).len() as u64)
                    .sum();
                assert!(sides.above + sides.below >= n, "{sides:?} of {n}");
                assert!(sides.above >= own && sides.below >= own);
                // Volume measure: a leaf's cost is its side's size.
                if step == 0 {
                    assert_eq!(sides.below as f64, a.up_cost);
                    assert_eq!(sides.above as f64, a.down_cost);
                }
                // The extent boxes every vertex of the chain (budget large
                // enough to read all of them).
                if let Some(e) = arc_extent(&tree, &sim, field.dims(), a.id, usize::MAX) {
                    assert_eq!(e.vertices as u64, own);
                    for &s in a.chain {
                        for v in tree.arc_vertices(s) {
                            let c = field.coords(v);
                            for (k, &ck) in c.iter().enumerate() {
                                assert!(e.min[k] <= ck && ck <= e.max[k]);
                            }
                        }
                    }
                    for (k, &ck) in e.centroid.iter().enumerate() {
                        assert!(e.min[k] as f64 <= ck && ck <= e.max[k] as f64);
                    }
                } else {
                    assert_eq!(own, 0);
                }
            }
        }
    }
}
