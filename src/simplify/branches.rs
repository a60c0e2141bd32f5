//! The branch decomposition of a pruning sequence (Pascucci et al.'s
//! branch decomposition, read off Carr, Snoeyink, van de Panne's §3.3
//! pruning order).
//!
//! Every pruning step cuts one *branch*: the pruned leaf's extremum, and
//! the nodes reduced inside the pruned arc, lie on it; the arcs left at
//! the end are *root* branches. A branch hangs from the branch holding its
//! inner node (the node it was pruned into), which is pruned later, so the
//! hierarchy is a forest. Branch `k` for `k < steps` is the branch pruned
//! at step `k`; branches `steps..` are the roots, by arc id.
//!
//! At any level the live nodes are exactly those of branches not pruned
//! yet, and a branch's importance is its step: pruned later = larger
//! feature. The tree layout ([`super::layout`]) orders branches left to
//! right from this forest, so it is computed once for every level.
//!
//! **Memory:** 4 bytes per node, 12 per branch (plus the children lists).

use super::{Simplification, SimplifiedArcId, SimplifiedNodeId, SimplifiedTree};
use std::sync::Arc;

const NONE: u32 = u32::MAX;

/// A branch: `k < steps` is pruned at step `k`, the others are roots.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct BranchId(pub u32);

/// The branch decomposition of a simplification.
#[derive(Clone, Debug)]
pub struct Branches {
    /// Number of pruning steps (branches below it are pruned ones).
    steps: usize,
    /// Per node: its branch.
    node_branch: Vec<u32>,
    /// Per branch: the branch it hangs from (`NONE` for roots).
    parent: Vec<u32>,
    /// Per branch: the branches hanging from it, most important (pruned
    /// last) first.
    children: Vec<Vec<u32>>,
    /// Per branch: the node it hangs from (its saddle; `NONE` for roots).
    attach: Vec<u32>,
    /// Per branch: its extremum (the pruned leaf's end; for a root, its
    /// arc's upper node).
    tip: Vec<u32>,
    /// Per arc id: the branch it lies on (the arc finally pruned, or the
    /// root, that the reductions made from it end in).
    arc_branch: Vec<u32>,
    /// Per branch: true when its tip is a minimum (a lower leaf pruned).
    lower_tip: Vec<bool>,
}

impl Branches {
    /// The branches of every level of `sim`.
    pub fn new(sim: &Arc<Simplification>) -> Self {
        let steps = sim.steps();
        let nsteps = steps.len();
        let ids = sim.num_arc_ids();
        let nodes = sim.num_nodes();
        let mut pruned_at = vec![NONE; ids];
        for (k, s) in steps.iter().enumerate() {
            pruned_at[s.pruned.0 as usize] = k as u32;
        }
        let mut last = SimplifiedTree::new(Arc::clone(sim));
        last.set_step(nsteps);
        let mut roots: Vec<u32> = last.arc_ids().to_vec();
        roots.sort_unstable();
        let mut root_of = vec![NONE; ids];
        for (i, &a) in roots.iter().enumerate() {
            root_of[a as usize] = (nsteps + i) as u32;
        }
        // Per arc id: the arc made from it by a reduction.
        let mut parent_arc = vec![NONE; ids];
        for d in sim.base_arcs()..ids {
            if let Some((e1, e2)) = sim.reduced_from(SimplifiedArcId(d as u32)) {
                parent_arc[e1.0 as usize] = d as u32;
                parent_arc[e2.0 as usize] = d as u32;
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
            } else if parent_arc[a] != NONE {
                owner[parent_arc[a] as usize]
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
        let branches = nsteps + roots.len().max(1);
        let mut tip = vec![NONE; branches];
        let mut lower_tip = vec![false; branches];
        for (k, s) in steps.iter().enumerate() {
            lower_tip[k] = s.lower_leaf;
            let leaf = if s.lower_leaf {
                sim.lower(s.pruned)
            } else {
                sim.upper(s.pruned)
            };
            node_branch[leaf.0 as usize] = k as u32;
            tip[k] = leaf.0;
        }
        for &a in &roots {
            let r = root_of[a as usize];
            tip[r as usize] = sim.upper(SimplifiedArcId(a)).0;
            for n in [sim.upper(SimplifiedArcId(a)), sim.lower(SimplifiedArcId(a))] {
                if node_branch[n.0 as usize] == NONE {
                    node_branch[n.0 as usize] = r;
                }
            }
        }
        for b in &mut node_branch {
            if *b == NONE {
                *b = fallback;
            }
        }
        let mut children: Vec<Vec<u32>> = vec![Vec::new(); branches];
        let mut parent = vec![NONE; branches];
        let mut attach = vec![NONE; branches];
        for (k, s) in steps.iter().enumerate().rev() {
            let inner = if s.lower_leaf {
                sim.upper(s.pruned)
            } else {
                sim.lower(s.pruned)
            };
            attach[k] = inner.0;
            let p = node_branch[inner.0 as usize];
            // A parent is pruned later than its child (or is a root); guard
            // against anything else so walks over the forest terminate.
            let p = if (p as usize) > k && (p as usize) < branches {
                p
            } else {
                fallback
            };
            children[p as usize].push(k as u32);
            parent[k] = p;
        }
        Self {
            steps: nsteps,
            node_branch,
            parent,
            children,
            attach,
            tip,
            arc_branch: owner,
            lower_tip,
        }
    }

    /// The branch original superarc `s` lies on (None for a zero-height
    /// superarc collapsed into a node): a contour of `s` is shown at a
    /// level exactly while this branch is live.
    pub fn of_superarc(&self, sim: &Simplification, s: crate::tree::ArcId) -> Option<BranchId> {
        let a = *sim.superarc_base.get(s.0 as usize)?;
        let b = *self.arc_branch.get(a as usize)?;
        (a != NONE).then_some(BranchId(b))
    }

    /// The branch arc `a` lies on.
    pub fn of_arc(&self, a: SimplifiedArcId) -> BranchId {
        BranchId(self.arc_branch[a.0 as usize])
    }

    /// True when branch `b` ends in a minimum below the saddle it hangs
    /// from (false: a maximum above it; roots count as maxima).
    pub fn goes_down(&self, b: BranchId) -> bool {
        self.lower_tip[b.0 as usize]
    }

    /// Number of branches (pruned ones and roots).
    pub fn len(&self) -> usize {
        self.children.len()
    }

    /// True when there is no branch (never: a tree has a root branch).
    pub fn is_empty(&self) -> bool {
        self.children.is_empty()
    }

    /// Number of pruning steps: branches below it are pruned, at their
    /// own step.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The root branches.
    pub fn roots(&self) -> impl DoubleEndedIterator<Item = BranchId> {
        (self.steps..self.len()).map(|b| BranchId(b as u32))
    }

    /// True when branch `b` is live after `step` steps.
    pub fn is_live(&self, b: BranchId, step: usize) -> bool {
        b.0 as usize >= self.steps || b.0 as usize >= step
    }

    /// The branch a node lies on.
    pub fn of_node(&self, n: SimplifiedNodeId) -> BranchId {
        BranchId(self.node_branch[n.0 as usize])
    }

    /// The branch `b` hangs from (None for a root).
    pub fn parent(&self, b: BranchId) -> Option<BranchId> {
        let p = self.parent[b.0 as usize];
        (p != NONE).then_some(BranchId(p))
    }

    /// The branches hanging from `b`, most important (pruned last) first.
    pub fn children(&self, b: BranchId) -> impl ExactSizeIterator<Item = BranchId> + '_ {
        self.children[b.0 as usize].iter().map(|&c| BranchId(c))
    }

    /// The node `b` hangs from, its saddle (None for a root).
    pub fn attachment(&self, b: BranchId) -> Option<SimplifiedNodeId> {
        let n = self.attach[b.0 as usize];
        (n != NONE).then_some(SimplifiedNodeId(n))
    }

    /// The extremum at the free end of `b` (for a root, its arc's upper
    /// node).
    pub fn tip(&self, b: BranchId) -> Option<SimplifiedNodeId> {
        let n = self.tip[b.0 as usize];
        (n != NONE).then_some(SimplifiedNodeId(n))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::simplify::Measure;
    use crate::tree::ContourTree;

    #[test]
    fn every_branch_hangs_from_a_later_one_and_live_nodes_lie_on_live_branches() {
        let field = Synthetic {
            noise: 0.2,
            ..Synthetic::cube(12)
        }
        .generate();
        let (tree, _) = ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
        let sim = Arc::new(Simplification::new(&tree, &field, Measure::Volume));
        let b = Branches::new(&sim);
        assert_eq!(b.len(), sim.steps().len() + b.roots().count());
        for k in 0..b.steps() {
            let p = b.parent(BranchId(k as u32)).unwrap();
            assert!(p.0 as usize > k, "branch {k} hangs from {p:?}");
            assert!(b.children(p).any(|c| c.0 as usize == k));
        }
        let mut level = SimplifiedTree::new(Arc::clone(&sim));
        for step in [0, b.steps() / 2, b.steps()] {
            level.set_step(step);
            for n in level.nodes() {
                assert!(b.is_live(b.of_node(n), step), "node {n:?} at step {step}");
            }
        }
    }
}
