//! Collapsing zero-height superarcs (paper §5): the tree that measures,
//! simplification, the curve and the explorer start from.
//!
//! Simulation of simplicity makes every vertex distinct, so a plateau of a
//! quantised scan becomes a thicket of supernodes joined by superarcs whose
//! two ends have the same value. Such an arc stands for no range of
//! isovalues. We contract **all** of them at once: a union-find on the
//! supernodes joins the two ends of every zero-height arc, each class (a
//! *group*, all of one value) becomes one node, and the tree stays a tree
//! (contracting edges of a tree cannot close a cycle). A group may end up
//! with any number of arcs up and down. A group left with exactly one arc
//! up and one down is a regular point and is reduced away, so its two arcs
//! become one; every arc of the collapsed tree therefore stands for a chain
//! of original superarcs, ascending, each spanning a distinct value range:
//! a contour at isovalue `h` on the arc is found by binary search on the
//! chain, exactly as on an arc of a simplified tree.
//!
//! Regions are not lost: the two sides of an arc of the collapsed tree are
//! the two sides of the top and bottom superarcs of its chain in the
//! perturbed tree, so the plateau vertices of a collapsed group count in
//! every region that holds the group.
//!
//! **Cost:** O(t log t) for t superarcs (a union-find, a climb through
//! each chain and one parallel sort into canonical order), run beside the
//! region summaries ([`ArcRegions`], which it does not need until the end).
//!
//! **Memory:** per original supernode 4 bytes (its group); per collapsed arc
//! 56 bytes (ends, chain range, both region summaries); per original arc 4
//! bytes (the chains).

use crate::field::ScalarField;
use crate::measure::geometric::{ArcRegions, RegionSummary, node_values};
use crate::tree::{ArcId, ContourTree, NodeId};

/// The contour tree with every zero-height superarc contracted and the
/// resulting regular nodes reduced.
#[derive(Clone, Debug)]
pub struct CollapsedTree {
    /// Per collapsed node: the representative vertex (the lowest supernode
    /// of its group in the vertex order).
    node_vertex: Vec<u32>,
    /// Per collapsed node: its value.
    node_value: Vec<f64>,
    /// Per collapsed node: arcs up and down.
    node_degree: Vec<(u32, u32)>,
    /// Per original supernode: its collapsed node, or `REDUCED` when its
    /// group was a regular point that got reduced away.
    group_node: Vec<u32>,
    /// Per arc: (upper, lower) collapsed nodes.
    arcs: Vec<(u32, u32)>,
    /// Per arc: the original superarcs it stands for, ascending:
    /// `chain[chain_offsets[a]..chain_offsets[a + 1]]`.
    chain_offsets: Vec<u32>,
    chain: Vec<ArcId>,
    /// Per arc: the region below it (below its top superarc).
    below: Vec<RegionSummary>,
    /// Per arc: the region above it (above its bottom superarc).
    above: Vec<RegionSummary>,
    /// Superarcs of the perturbed tree.
    perturbed_arcs: usize,
}

/// Marks an original supernode whose group was reduced away.
pub const REDUCED: u32 = u32::MAX;

impl CollapsedTree {
    /// Collapses `tree` (built from `field`) and computes the region
    /// summaries of its arcs (Algorithm 1, [`ArcRegions`]). This is the
    /// last time the field is read: simplification works on the summaries.
    ///
    /// The regions and the collapse do not depend on each other: they run
    /// side by side (rayon), and the summaries are attached at the end.
    pub fn new(tree: &ContourTree, field: &ScalarField) -> Self {
        // Both read the nodes' values, scattered over the field: once.
        let node_values = node_values(tree, field);
        let (regions, mut collapsed) = rayon::join(
            || ArcRegions::with_node_values(tree, field, &node_values),
            || Self::without_regions(tree, &node_values),
        );
        collapsed.attach(&regions);
        collapsed
    }

    /// The number of arcs [`CollapsedTree::new`] leaves, without the region
    /// summaries (which read every vertex's value): for a report of the
    /// tree that goes no further.
    pub fn count_arcs(tree: &ContourTree, field: &ScalarField) -> usize {
        Self::without_regions(tree, &node_values(tree, field)).num_arcs()
    }

    /// As [`CollapsedTree::new`], with the regions already computed.
    pub fn with_regions(tree: &ContourTree, field: &ScalarField, regions: &ArcRegions) -> Self {
        let mut collapsed = Self::without_regions(tree, &node_values(tree, field));
        collapsed.attach(regions);
        collapsed
    }

    /// The two sides of each arc: below its top superarc, above its
    /// bottom one.
    fn attach(&mut self, regions: &ArcRegions) {
        use rayon::prelude::*;
        let (offsets, chain) = (&self.chain_offsets, &self.chain);
        (0..self.arcs.len())
            .into_par_iter()
            .map(|a| {
                let (s, e) = (offsets[a] as usize, offsets[a + 1] as usize);
                (*regions.below(chain[e - 1]), *regions.above(chain[s]))
            })
            .unzip_into_vecs(&mut self.below, &mut self.above);
    }

    /// The collapsed tree with no region summaries yet.
    fn without_regions(tree: &ContourTree, node_values: &[f64]) -> Self {
        let nodes = tree.nodes();
        // Each node's value read once, beforehand: the arcs below visit
        // nodes in no order, and the values array is far larger than the
        // cache.
        let value = |n: NodeId| node_values[n.0 as usize];
        // Union-find on supernodes; the root of a class is its smallest
        // node, i.e. its lowest in the vertex order.
        let mut uf: Vec<u32> = (0..nodes.len() as u32).collect();
        fn find(uf: &mut [u32], mut x: u32) -> u32 {
            while uf[x as usize] != x {
                let p = uf[uf[x as usize] as usize];
                uf[x as usize] = p;
                x = p;
            }
            x
        }
        let is_flat = |a: &crate::tree::Superarc| value(a.upper) == value(a.lower);
        for arc in tree.arcs() {
            if is_flat(arc) {
                let (a, b) = (find(&mut uf, arc.upper.0), find(&mut uf, arc.lower.0));
                let (lo, hi) = (a.min(b), a.max(b));
                uf[hi as usize] = lo;
            }
        }
        let group: Vec<u32> = (0..nodes.len() as u32).map(|i| find(&mut uf, i)).collect();
        // Degrees of the groups, counting only arcs of non-zero height, and
        // for groups with one arc up, that arc (the chains walk through them).
        let mut up = vec![0u32; nodes.len()];
        let mut down = vec![0u32; nodes.len()];
        let mut up_arc = vec![u32::MAX; nodes.len()];
        for (a, arc) in tree.arcs().iter().enumerate() {
            if !is_flat(arc) {
                let (gu, gl) = (group[arc.upper.0 as usize], group[arc.lower.0 as usize]);
                down[gu as usize] += 1;
                up[gl as usize] += 1;
                up_arc[gl as usize] = a as u32;
            }
        }
        let regular = |g: u32| up[g as usize] == 1 && down[g as usize] == 1;
        // Collapsed nodes: the non-regular groups, numbered in the vertex
        // order of their representatives (group roots ascend with node ids).
        let mut node_of_group = vec![REDUCED; nodes.len()];
        let mut node_vertex = Vec::new();
        let mut node_value = Vec::new();
        let mut node_degree = Vec::new();
        for g in 0..nodes.len() as u32 {
            if group[g as usize] == g && !regular(g) {
                node_of_group[g as usize] = node_vertex.len() as u32;
                node_vertex.push(nodes[g as usize].vertex);
                node_value.push(value(NodeId(g)));
                node_degree.push((up[g as usize], down[g as usize]));
            }
        }
        // Arcs: from every non-zero-height superarc whose lower group is a
        // collapsed node, climb through regular groups.
        let mut arcs = Vec::new();
        let mut chain_offsets = vec![0u32];
        let mut chain = Vec::new();
        for (a, arc) in tree.arcs().iter().enumerate() {
            if is_flat(arc) || regular(group[arc.lower.0 as usize]) {
                continue;
            }
            let bottom = ArcId(a as u32);
            let mut top = bottom;
            chain.push(bottom);
            loop {
                let g = group[tree.arc(top).upper.0 as usize];
                if !regular(g) {
                    break;
                }
                top = ArcId(up_arc[g as usize]);
                chain.push(top);
            }
            let gl = group[arc.lower.0 as usize];
            let gu = group[tree.arc(top).upper.0 as usize];
            arcs.push((node_of_group[gu as usize], node_of_group[gl as usize]));
            chain_offsets.push(chain.len() as u32);
        }
        // Canonical order: by (lower, upper) node, like the tree's arcs.
        // (The keys are distinct: no superarc is the bottom of two chains.)
        let mut keyed: Vec<(u32, u32, ArcId, u32)> = arcs
            .iter()
            .enumerate()
            .map(|(a, &(u, l))| (l, u, chain[chain_offsets[a] as usize], a as u32))
            .collect();
        {
            use rayon::prelude::*;
            keyed.par_sort_unstable();
        }
        let perm: Vec<usize> = keyed.into_iter().map(|k| k.3 as usize).collect();
        let mut s_offsets = vec![0u32];
        let mut s_chain = Vec::with_capacity(chain.len());
        for &a in &perm {
            s_chain.extend_from_slice(
                &chain[chain_offsets[a] as usize..chain_offsets[a + 1] as usize],
            );
            s_offsets.push(s_chain.len() as u32);
        }
        let group_node = group.iter().map(|&g| node_of_group[g as usize]).collect();
        Self {
            node_vertex,
            node_value,
            node_degree,
            group_node,
            arcs: perm.iter().map(|&a| arcs[a]).collect(),
            chain_offsets: s_offsets,
            chain: s_chain,
            below: Vec::new(),
            above: Vec::new(),
            perturbed_arcs: tree.arcs().len(),
        }
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.node_vertex.len()
    }

    /// Number of arcs.
    pub fn num_arcs(&self) -> usize {
        self.arcs.len()
    }

    /// Superarcs of the perturbed tree it was made from.
    pub fn perturbed_arcs(&self) -> usize {
        self.perturbed_arcs
    }

    /// The representative mesh vertex of a node: the lowest supernode of
    /// its group in the vertex order.
    pub fn node_vertex(&self, node: u32) -> u32 {
        self.node_vertex[node as usize]
    }

    /// The value of a node (every supernode of its group has it).
    pub fn node_value(&self, node: u32) -> f64 {
        self.node_value[node as usize]
    }

    /// Arcs (up, down) at a node.
    pub fn node_degree(&self, node: u32) -> (u32, u32) {
        self.node_degree[node as usize]
    }

    /// The collapsed node an original supernode was merged into, or `None`
    /// when its group was a regular point and reduced away (it then lies
    /// inside the chain of an arc).
    pub fn node_of(&self, node: NodeId) -> Option<u32> {
        let g = self.group_node[node.0 as usize];
        (g != REDUCED).then_some(g)
    }

    /// (upper, lower) nodes of an arc.
    pub fn arc(&self, arc: u32) -> (u32, u32) {
        self.arcs[arc as usize]
    }

    /// The original superarcs an arc stands for, ascending in value; each
    /// spans a value range disjoint from the others but for its ends.
    pub fn chain(&self, arc: u32) -> &[ArcId] {
        let a = arc as usize;
        &self.chain[self.chain_offsets[a] as usize..self.chain_offsets[a + 1] as usize]
    }

    /// The region below an arc (pruned as a lower leaf).
    pub fn below(&self, arc: u32) -> &RegionSummary {
        &self.below[arc as usize]
    }

    /// The region above an arc (pruned as an upper leaf).
    pub fn above(&self, arc: u32) -> &RegionSummary {
        &self.above[arc as usize]
    }
}
