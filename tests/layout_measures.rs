//! What the tree layout keeps across measures (the module doc of
//! `flexiso::simplify::layout`, "Across measures"): a branch whose whole
//! subtree is the same under two measures (the same branches, pruned in
//! the same relative order) has its subtree's columns in the same order
//! under both when it hangs on the same side of its parent, and in
//! exactly the reverse order when on the other side.

use flexiso::field::synthetic::Synthetic;
use flexiso::progress::Progress;
use flexiso::simplify::branches::{BranchId, Branches};
use flexiso::simplify::layout::TreeLayout;
use flexiso::simplify::{CollapsedTree, Measure, Simplification, SimplifiedNodeId};
use flexiso::tree::ContourTree;
use proptest::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;

/// A branch's subtree as a value to compare across measures: per node,
/// the tip of the branch it lies on; per branch, its tip, saddle and
/// the tip of its parent inside the subtree; and the tips in the order
/// their branches are pruned.
type Signature = (
    BTreeMap<u32, u32>,
    BTreeMap<u32, (Option<u32>, Option<u32>)>,
    Vec<u32>,
);

struct Drawn {
    layout: TreeLayout,
    /// Per branch: the branches of its subtree (itself included).
    subtree: Vec<Vec<BranchId>>,
    /// Per branch: the nodes lying on it.
    nodes: Vec<Vec<u32>>,
}

impl Drawn {
    fn new(sim: &Arc<Simplification>) -> Self {
        let layout = TreeLayout::new(sim);
        let b = layout.branches();
        let mut nodes = vec![Vec::new(); b.len()];
        for v in 0..sim.num_nodes() as u32 {
            nodes[b.of_node(SimplifiedNodeId(v)).0 as usize].push(v);
        }
        // Children have smaller ids than their parents.
        let mut subtree: Vec<Vec<BranchId>> =
            (0..b.len() as u32).map(|k| vec![BranchId(k)]).collect();
        for k in 0..b.len() {
            if let Some(p) = b.parent(BranchId(k as u32)) {
                let mine = subtree[k].clone();
                subtree[p.0 as usize].extend(mine);
            }
        }
        Self {
            layout,
            subtree,
            nodes,
        }
    }

    fn branches(&self) -> &Branches {
        self.layout.branches()
    }

    fn tip(&self, b: BranchId) -> u32 {
        self.branches().tip(b).map_or(u32::MAX, |v| v.0)
    }

    fn signature(&self, b: BranchId) -> Signature {
        let br = self.branches();
        let mut on = BTreeMap::new();
        let mut shape = BTreeMap::new();
        for &d in &self.subtree[b.0 as usize] {
            for &v in &self.nodes[d.0 as usize] {
                on.insert(v, self.tip(d));
            }
            let parent = (d != b)
                .then(|| br.parent(d).map(|p| self.tip(p)))
                .flatten();
            shape.insert(self.tip(d), (br.attachment(d).map(|v| v.0), parent));
        }
        // The order in which its branches are pruned (tips, first pruned
        // first): the layout weighs an unavoidable crossing by it.
        let mut pruned = self.subtree[b.0 as usize].clone();
        pruned.sort();
        let order = pruned.into_iter().map(|d| self.tip(d)).collect();
        (on, shape, order)
    }

    /// The tips of `b`'s subtree, left to right.
    fn columns(&self, b: BranchId) -> Vec<u32> {
        let mut sub = self.subtree[b.0 as usize].clone();
        sub.sort_by_key(|&d| self.layout.place(d));
        sub.into_iter().map(|d| self.tip(d)).collect()
    }

    /// Which side of its parent `b` hangs on (None for a root).
    fn right_of_parent(&self, b: BranchId) -> Option<bool> {
        let p = self.branches().parent(b)?;
        Some(self.layout.place(b) > self.layout.place(p))
    }
}

/// For every branch of `x` whose subtree is the same in `y`: the number
/// checked, after asserting the order is kept (or reversed).
fn check_pair(x: &Drawn, y: &Drawn) -> usize {
    let by_tip: BTreeMap<u32, BranchId> = (0..y.branches().len() as u32)
        .map(|k| (y.tip(BranchId(k)), BranchId(k)))
        .collect();
    let mut agreed = 0;
    for k in 0..x.branches().len() as u32 {
        let bx = BranchId(k);
        let Some(&by) = by_tip.get(&x.tip(bx)) else {
            continue;
        };
        if x.subtree[bx.0 as usize].len() < 2 || x.signature(bx) != y.signature(by) {
            continue;
        }
        agreed += 1;
        let (cx, mut cy) = (x.columns(bx), y.columns(by));
        if x.right_of_parent(bx) != y.right_of_parent(by) {
            cy.reverse();
        }
        assert_eq!(cx, cy, "subtree of tip {} laid out differently", x.tip(bx));
    }
    agreed
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn subtrees_that_agree_across_measures_keep_their_order(
        seed in 0u64..10_000, n in 5usize..11, noise in 0.05f32..0.8,
    ) {
        let field = Synthetic { noise, seed, ..Synthetic::cube(n) }.generate();
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
        let collapsed = CollapsedTree::new(&tree, &field);
        let drawn: Vec<Drawn> = Measure::ALL
            .iter()
            .map(|&m| Drawn::new(&Arc::new(Simplification::from_collapsed(&collapsed, m))))
            .collect();
        let mut agreed = 0;
        for i in 0..drawn.len() {
            for j in 0..drawn.len() {
                if i != j {
                    agreed += check_pair(&drawn[i], &drawn[j]);
                }
            }
        }
        eprintln!("{n}³ noise {noise:.2}: {agreed} agreeing subtrees (of two or more branches) checked");
    }
}

#[test]
fn the_same_decomposition_gives_the_same_layout() {
    let field = Synthetic {
        noise: 0.3,
        seed: 7,
        ..Synthetic::cube(9)
    }
    .generate();
    let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
    let collapsed = CollapsedTree::new(&tree, &field);
    let sim = Arc::new(Simplification::from_collapsed(&collapsed, Measure::Volume));
    let (x, y) = (Drawn::new(&sim), Drawn::new(&sim));
    for k in 0..x.branches().len() as u32 {
        assert_eq!(x.layout.place(BranchId(k)), y.layout.place(BranchId(k)));
    }
    assert!(check_pair(&x, &y) > 0);
}
