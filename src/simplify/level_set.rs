//! Following a level set past a node, at one level of simplification.
//!
//! A contour of arc `a` at value `v` is a component of the level set; as
//! `v` rises past `a`'s upper node it becomes the contours of every arc
//! above that node (a join seen from below splits the contour), and as it
//! falls past the lower node, those of every arc below (Carr, Snoeyink,
//! van de Panne §2: each arc of the contour tree is one contour class,
//! and crossing a node moves into the classes adjacent to it in the
//! direction of travel). Repeating this until the arc reached spans `v`
//! gives the arcs holding the level set at `v` that the contour becomes.
//! Since travel is monotone (a node is passed only upward from below or
//! downward from above), the walk visits each arc at most once per path
//! and ends at arcs spanning `v` or at arcs ending in an extremum, where
//! the contour stays at the arc's end.

use super::{SimplifiedArcId, SimplifiedTree};

impl SimplifiedTree {
    /// The live arcs holding the level set at `v` reached from live arc
    /// `start` by following it monotonically through the nodes in between
    /// (every arc above an upper node, every arc below a lower one); an arc
    /// ending at an extremum keeps the contour at its end. In depth-first
    /// order, arcs at a node by id; no arc twice. O(arcs visited × degree).
    pub fn level_set_arcs(&self, start: SimplifiedArcId, v: f64) -> Vec<SimplifiedArcId> {
        let sim = self.simplification();
        let mut out = Vec::new();
        let mut stack = vec![start];
        while let Some(a) = stack.pop() {
            let (u, l) = (sim.upper(a), sim.lower(a));
            let (top, bottom) = (sim.node_value(u), sim.node_value(l));
            let mut next: Vec<SimplifiedArcId> = if v >= top {
                self.arcs_above(u).collect()
            } else if v < bottom {
                self.arcs_below(l).collect()
            } else {
                Vec::new()
            };
            if next.is_empty() {
                if !out.contains(&a) {
                    out.push(a);
                }
            } else {
                next.sort();
                stack.extend(next.into_iter().rev());
            }
        }
        out
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::simplify::{Measure, Simplification};
    use crate::tree::ContourTree;
    use std::sync::Arc;

    /// The oracle: the same walk scanning every live arc at each hop (the
    /// explorer's code before `arcs_above` existed).
    fn scanning(level: &SimplifiedTree, start: SimplifiedArcId, v: f64) -> Vec<SimplifiedArcId> {
        let sim = level.simplification();
        let mut out = Vec::new();
        let mut stack = vec![start];
        while let Some(a) = stack.pop() {
            let (u, l) = (sim.upper(a), sim.lower(a));
            let (top, bottom) = (sim.node_value(u), sim.node_value(l));
            let ids = level.arc_ids().iter().map(|&b| SimplifiedArcId(b));
            let mut next: Vec<SimplifiedArcId> = if v >= top {
                ids.filter(|&b| sim.lower(b) == u).collect()
            } else if v < bottom {
                ids.filter(|&b| sim.upper(b) == l).collect()
            } else {
                Vec::new()
            };
            if next.is_empty() {
                if !out.contains(&a) {
                    out.push(a);
                }
            } else {
                next.sort();
                stack.extend(next.into_iter().rev());
            }
        }
        out
    }

    #[test]
    fn level_set_following_matches_the_scanning_walk_at_every_level() {
        for (seed, noise) in [(1, 0.2f32), (7, 0.4), (11, 0.05)] {
            let field = Synthetic {
                noise,
                seed,
                ..Synthetic::cube(9)
            }
            .generate();
            let (tree, _) =
                ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
            let sim = Arc::new(Simplification::new(&tree, &field, Measure::Hypervolume));
            let (lo, hi) = field.range();
            let mut level = SimplifiedTree::new(Arc::clone(&sim));
            let last = sim.steps().len();
            for step in [0, last / 4, last / 2, last] {
                level.set_step(step);
                let mut arcs: Vec<u32> = level.arc_ids().to_vec();
                arcs.sort();
                for &a in arcs.iter().step_by(3) {
                    for k in 0..=8 {
                        let v = lo + (hi - lo) * k as f64 / 8.0;
                        let a = SimplifiedArcId(a);
                        assert_eq!(level.level_set_arcs(a, v), scanning(&level, a, v));
                    }
                }
            }
        }
    }
}
