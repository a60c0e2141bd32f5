//! Where the tree panel draws each node: y is the node's value, x comes
//! from a *branch decomposition* read off the whole pruning sequence, so it
//! is computed once and stays put when the level of simplification changes.
//!
//! Every pruning step cuts one branch: the pruned leaf's extremum, and the
//! nodes reduced inside the pruned arc, lie on it; the arcs left at the end
//! are root branches. A branch hangs from the branch holding its inner node
//! (pruned later, so the hierarchy is a forest). The branches are ordered
//! left to right by an in-order walk of that forest in which each branch
//! has its children alternately on its right and left, the more important
//! (pruned later) closer. Nodes take their branch's column, so the arcs
//! along a branch are vertical and side branches slant out of them.
//!
//! At a level only the live branches (not yet pruned) get columns, in that
//! fixed order, so the drawing is compact at every level and the relative
//! order of nodes never changes.

use crate::simplify::{Simplification, SimplifiedArcId, SimplifiedNodeId, SimplifiedTree};

const NONE: u32 = u32::MAX;

/// The branch decomposition of a simplification and its column order.
#[derive(Clone, Debug)]
pub struct TreeLayout {
    /// Per node: its branch.
    node_branch: Vec<u32>,
    /// Branches left to right.
    order: Vec<u32>,
    /// Number of pruning steps: branch `k < steps` is pruned at step `k`,
    /// the others are roots (never pruned).
    steps: usize,
    /// Per branch: its place in `order`.
    position: Vec<u32>,
}

impl TreeLayout {
    /// The layout of every level of `sim`.
    pub fn new(sim: &std::sync::Arc<Simplification>) -> Self {
        let steps = sim.steps();
        let nsteps = steps.len();
        let ids = sim.num_arc_ids();
        let nodes = sim.num_nodes();
        let mut pruned_at = vec![NONE; ids];
        for (k, s) in steps.iter().enumerate() {
            pruned_at[s.pruned.0 as usize] = k as u32;
        }
        let mut last = SimplifiedTree::new(std::sync::Arc::clone(sim));
        last.set_step(nsteps);
        let mut roots: Vec<u32> = last.arc_ids().to_vec();
        roots.sort_unstable();
        let mut root_of = vec![NONE; ids];
        for (i, &a) in roots.iter().enumerate() {
            root_of[a as usize] = (nsteps + i) as u32;
        }
        // Per arc id: the arc made from it by a reduction.
        let mut parent = vec![NONE; ids];
        for d in sim.base_arcs()..ids {
            if let Some((e1, e2)) = sim.reduced_from(SimplifiedArcId(d as u32)) {
                parent[e1.0 as usize] = d as u32;
                parent[e2.0 as usize] = d as u32;
            }
        }
        let fallback = nsteps as u32; // the first root
        // Per arc id: the branch its interior nodes lie on. Parents have
        // higher ids: go down from the top.
        let mut owner = vec![fallback; ids];
        for a in (0..ids).rev() {
            owner[a] = if pruned_at[a] != NONE {
                pruned_at[a]
            } else if root_of[a] != NONE {
                root_of[a]
            } else if parent[a] != NONE {
                owner[parent[a] as usize]
            } else {
                fallback
            };
        }
        let mut node_branch = vec![NONE; nodes];
        for (d, &o) in owner.iter().enumerate().skip(sim.base_arcs()) {
            if let Some((e1, _)) = sim.reduced_from(SimplifiedArcId(d as u32)) {
                node_branch[sim.lower(e1).0 as usize] = o;
            }
        }
        for (k, s) in steps.iter().enumerate() {
            let leaf = if s.lower_leaf {
                sim.lower(s.pruned)
            } else {
                sim.upper(s.pruned)
            };
            node_branch[leaf.0 as usize] = k as u32;
        }
        for &a in &roots {
            for n in [sim.upper(SimplifiedArcId(a)), sim.lower(SimplifiedArcId(a))] {
                if node_branch[n.0 as usize] == NONE {
                    node_branch[n.0 as usize] = root_of[a as usize];
                }
            }
        }
        for b in &mut node_branch {
            if *b == NONE {
                *b = fallback;
            }
        }
        let branches = nsteps + roots.len().max(1);
        // Children of each branch, most important (pruned last) first.
        let mut children: Vec<Vec<u32>> = vec![Vec::new(); branches];
        for (k, s) in steps.iter().enumerate().rev() {
            let inner = if s.lower_leaf {
                sim.upper(s.pruned)
            } else {
                sim.lower(s.pruned)
            };
            let p = node_branch[inner.0 as usize];
            // A parent is pruned later than its child (or is a root); guard
            // against anything else so the walk below terminates.
            if (p as usize) > k && (p as usize) < branches {
                children[p as usize].push(k as u32);
            } else {
                children[fallback as usize].push(k as u32);
            }
        }
        enum Visit {
            Branch(u32),
            Emit(u32),
        }
        let mut order = Vec::with_capacity(branches);
        let mut stack: Vec<Visit> = (nsteps..branches)
            .rev()
            .map(|r| Visit::Branch(r as u32))
            .collect();
        while let Some(v) = stack.pop() {
            match v {
                Visit::Emit(b) => order.push(b),
                Visit::Branch(b) => {
                    let c = &children[b as usize];
                    // Sequence: left children outermost..innermost, b,
                    // right children innermost..outermost; pushed reversed.
                    let right: Vec<u32> = c.iter().step_by(2).copied().collect();
                    let left: Vec<u32> = c.iter().skip(1).step_by(2).copied().collect();
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
        let mut position = vec![NONE; order.len().max(branches)];
        for (i, &b) in order.iter().enumerate() {
            position[b as usize] = i as u32;
        }
        Self {
            node_branch,
            order,
            steps: nsteps,
            position,
        }
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
            let b = self.node_branch[n.0 as usize];
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
        let live = |b: u32| b as usize >= self.steps || b as usize >= step;
        let count = self.order.iter().filter(|&&b| live(b)).count().max(1);
        let mut column = vec![f32::NAN; self.order.len().max(self.steps + 1)];
        let mut i = 0usize;
        for &b in &self.order {
            if live(b) {
                column[b as usize] = (i as f32 + 0.5) / count as f32;
                i += 1;
            }
        }
        self.node_branch
            .iter()
            .map(|&b| column.get(b as usize).copied().unwrap_or(f32::NAN))
            .collect()
    }

    /// The branch a node lies on.
    pub fn branch(&self, node: SimplifiedNodeId) -> u32 {
        self.node_branch[node.0 as usize]
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
