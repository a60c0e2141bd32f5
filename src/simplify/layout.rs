//! Where the explorer's tree panel draws each node: y is the node's value,
//! x comes from the branch decomposition ([`super::branches`]) of the whole
//! pruning sequence, so it is computed once and stays put when the level
//! of simplification changes.
//!
//! The branches are ordered left to right by an in-order walk of the
//! branch forest in which each branch has its children alternately on its
//! right and left, the more important (pruned later) closer. Nodes take
//! their branch's column, so the arcs along a branch are vertical and side
//! branches slant out of them.
//!
//! At a level only the live branches (not yet pruned) get columns, in that
//! fixed order, so the drawing is compact at every level and the relative
//! order of nodes never changes.

use super::branches::{BranchId, Branches};
use super::{Simplification, SimplifiedNodeId, SimplifiedTree};

const NONE: u32 = u32::MAX;

/// The branch decomposition of a simplification and its column order.
#[derive(Clone, Debug)]
pub struct TreeLayout {
    /// The branches.
    branches: Branches,
    /// Branches left to right.
    order: Vec<u32>,
    /// Per branch: its place in `order`.
    position: Vec<u32>,
}

impl TreeLayout {
    /// The layout of every level of `sim`.
    pub fn new(sim: &std::sync::Arc<Simplification>) -> Self {
        let branches = Branches::new(sim);
        let n = branches.len();
        enum Visit {
            Branch(BranchId),
            Emit(BranchId),
        }
        let mut order = Vec::with_capacity(n);
        let roots: Vec<BranchId> = branches.roots().collect();
        let mut stack: Vec<Visit> = roots.into_iter().rev().map(Visit::Branch).collect();
        while let Some(v) = stack.pop() {
            match v {
                Visit::Emit(b) => order.push(b.0),
                Visit::Branch(b) => {
                    let c: Vec<BranchId> = branches.children(b).collect();
                    // Sequence: left children outermost..innermost, b,
                    // right children innermost..outermost; pushed reversed.
                    let right: Vec<BranchId> = c.iter().step_by(2).copied().collect();
                    let left: Vec<BranchId> = c.iter().skip(1).step_by(2).copied().collect();
                    for &r in right.iter().rev() {
                        stack.push(Visit::Branch(r));
                    }
                    stack.push(Visit::Emit(b));
                    for &l in &left {
                        stack.push(Visit::Branch(l));
                    }
                }
            }
        }
        let mut position = vec![NONE; order.len().max(n)];
        for (i, &b) in order.iter().enumerate() {
            position[b as usize] = i as u32;
        }
        Self {
            branches,
            order,
            position,
        }
    }

    /// The branch decomposition the layout is made from.
    pub fn branches(&self) -> &Branches {
        &self.branches
    }

    /// Writes the columns of the nodes live at `level` into `columns`
    /// (indexed by node id, grown as needed; other entries are left as
    /// they were): the same as [`TreeLayout::columns`] on those nodes, in
    /// O(a log a) for a live arcs instead of O(tree), so moving the level
    /// of a tree of millions of arcs costs the UI thread only what it
    /// shows.
    pub fn live_columns(&self, level: &SimplifiedTree, columns: &mut Vec<f32>) {
        let nodes = level.nodes();
        let place = |n: SimplifiedNodeId| {
            let b = self.branches.of_node(n).0;
            self.position.get(b as usize).copied().unwrap_or(NONE)
        };
        let mut places: Vec<u32> = nodes.iter().map(|&n| place(n)).collect();
        places.sort_unstable();
        places.dedup();
        let count = places.len().max(1) as f32;
        if let Some(last) = nodes.last()
            && columns.len() <= last.0 as usize
        {
            columns.resize(last.0 as usize + 1, f32::NAN);
        }
        for n in nodes {
            let rank = places.partition_point(|&p| p < place(n));
            columns[n.0 as usize] = (rank as f32 + 0.5) / count;
        }
    }

    /// The columns of the nodes at `level`: x in `[0, 1]` per node id
    /// (NaN for nodes of pruned branches). O(branches).
    pub fn columns(&self, level: &SimplifiedTree) -> Vec<f32> {
        let step = level.step();
        let live = |b: u32| self.branches.is_live(BranchId(b), step);
        let count = self.order.iter().filter(|&&b| live(b)).count().max(1);
        let mut column = vec![f32::NAN; self.order.len().max(self.branches.steps() + 1)];
        let mut i = 0usize;
        for &b in &self.order {
            if live(b) {
                column[b as usize] = (i as f32 + 0.5) / count as f32;
                i += 1;
            }
        }
        (0..level.simplification().num_nodes() as u32)
            .map(|n| {
                let b = self.branches.of_node(SimplifiedNodeId(n)).0;
                column.get(b as usize).copied().unwrap_or(f32::NAN)
            })
            .collect()
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::simplify::Measure;
    use crate::tree::ContourTree;
    use std::sync::Arc;

    #[test]
    fn every_live_node_has_a_column_at_every_level() {
        let field = Synthetic::cube(24).generate();
        let (tree, _) = ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
        let sim = Arc::new(Simplification::new(&tree, &field, Measure::Hypervolume));
        let layout = TreeLayout::new(&sim);
        let mut level = SimplifiedTree::new(Arc::clone(&sim));
        let last = sim.steps().len();
        for step in [0, last / 3, last / 2, last] {
            level.set_step(step);
            let col = layout.columns(&level);
            let mut xs: Vec<f32> = Vec::new();
            for n in level.nodes() {
                let x = col[n.0 as usize];
                assert!((0.0..=1.0).contains(&x), "node {n:?} at step {step}: {x}");
                xs.push(x);
            }
            assert!(!xs.is_empty());
        }
    }

    #[test]
    fn live_columns_equal_the_full_pass_at_every_level() {
        for (field, measure) in [
            (Synthetic::cube(24).generate(), Measure::Hypervolume),
            (Synthetic::cube(20).generate(), Measure::Height),
            (
                Synthetic {
                    noise: 0.1,
                    ..Synthetic::cube(16)
                }
                .generate(),
                Measure::Volume,
            ),
        ] {
            let (tree, _) =
                ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
            let sim = Arc::new(Simplification::new(&tree, &field, measure));
            let layout = TreeLayout::new(&sim);
            let mut level = SimplifiedTree::new(Arc::clone(&sim));
            let mut live = Vec::new();
            // Down every level, then jumps back up: entries of nodes that
            // were live earlier stay behind and must not matter.
            let last = sim.steps().len();
            let order: Vec<usize> = (0..=last).chain([last / 2, 0, last / 3]).collect();
            for step in order {
                level.set_step(step);
                let full = layout.columns(&level);
                layout.live_columns(&level, &mut live);
                for n in level.nodes() {
                    assert_eq!(
                        live[n.0 as usize], full[n.0 as usize],
                        "node {n:?} at step {step}"
                    );
                }
            }
        }
    }
}
