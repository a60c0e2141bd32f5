//! The live arcs at each node of a level: [`SimplifiedTree::arcs_above`]
//! and [`SimplifiedTree::arcs_below`] in O(degree).
//!
//! Following a level set past a node (Carr, Snoeyink, van de Panne §4:
//! going up through a join the contour becomes the contours of every arc
//! above it) needs the arcs at that node *at the level shown*, which change
//! with every prune and vertex reduction. Each node keeps two intrusive
//! doubly linked lists over arc ids, one of its live arcs above (whose
//! lower end it is) and one of those below; [`SimplifiedTree::set_step`]
//! links and unlinks an arc wherever it inserts or removes it, so a step
//! still costs O(1) and a query costs what it returns. A level built
//! afresh (a long jump of the slider) drops the lists, and the first query
//! there builds them from the live arcs in O(live arcs): a slider moved
//! across millions of arcs does not pay for lists nobody reads.
//!
//! **Memory:** 16 bytes per arc id (two links of two `u32`) and 8 bytes per
//! node (two list heads).

use super::{NONE, Simplification, SimplifiedArcId, SimplifiedNodeId, SimplifiedTree};

/// Per node, its live arcs above and below (see the module documentation).
#[derive(Clone, Debug)]
pub(super) struct LiveAdjacency {
    /// Per node: the first live arc above it, `NONE` when there is none.
    head_up: Vec<u32>,
    /// Per node: the first live arc below it.
    head_down: Vec<u32>,
    /// Per arc id: (previous, next) in its lower node's list of arcs above.
    up_link: Vec<[u32; 2]>,
    /// Per arc id: (previous, next) in its upper node's list of arcs below.
    down_link: Vec<[u32; 2]>,
}

/// Which of a node's two lists.
#[derive(Clone, Copy)]
enum Side {
    /// Arcs above the node (the node is their lower end).
    Up,
    /// Arcs below the node (the node is their upper end).
    Down,
}

impl LiveAdjacency {
    /// The lists of a level whose live arcs are `live`.
    pub(super) fn of_level(sim: &Simplification, live: &[u32]) -> Self {
        let mut adj = Self {
            head_up: vec![NONE; sim.num_nodes()],
            head_down: vec![NONE; sim.num_nodes()],
            up_link: vec![[NONE; 2]; sim.num_arc_ids()],
            down_link: vec![[NONE; 2]; sim.num_arc_ids()],
        };
        for &a in live.iter().rev() {
            adj.link(sim, a);
        }
        adj
    }

    fn lists(&mut self, side: Side) -> (&mut Vec<u32>, &mut Vec<[u32; 2]>) {
        match side {
            Side::Up => (&mut self.head_up, &mut self.up_link),
            Side::Down => (&mut self.head_down, &mut self.down_link),
        }
    }

    fn push(&mut self, side: Side, node: u32, a: u32) {
        let (head, link) = self.lists(side);
        let first = head[node as usize];
        link[a as usize] = [NONE, first];
        if first != NONE {
            link[first as usize][0] = a;
        }
        head[node as usize] = a;
    }

    fn take(&mut self, side: Side, node: u32, a: u32) {
        let (head, link) = self.lists(side);
        let [prev, next] = link[a as usize];
        if prev == NONE {
            head[node as usize] = next;
        } else {
            link[prev as usize][1] = next;
        }
        if next != NONE {
            link[next as usize][0] = prev;
        }
        link[a as usize] = [NONE; 2];
    }

    /// Arc `a` becomes live: it joins the lists of both its ends.
    pub(super) fn link(&mut self, sim: &Simplification, a: u32) {
        self.push(Side::Up, sim.ends[a as usize].lower, a);
        self.push(Side::Down, sim.ends[a as usize].upper, a);
    }

    /// Arc `a` is no longer live: it leaves both lists.
    pub(super) fn unlink(&mut self, sim: &Simplification, a: u32) {
        self.take(Side::Up, sim.ends[a as usize].lower, a);
        self.take(Side::Down, sim.ends[a as usize].upper, a);
    }

    fn iter(
        &self,
        side: Side,
        node: SimplifiedNodeId,
    ) -> impl Iterator<Item = SimplifiedArcId> + '_ {
        let (head, link) = match side {
            Side::Up => (&self.head_up, &self.up_link),
            Side::Down => (&self.head_down, &self.down_link),
        };
        let mut a = head.get(node.0 as usize).copied().unwrap_or(NONE);
        std::iter::from_fn(move || {
            (a != NONE).then(|| {
                let here = a;
                a = link[a as usize][1];
                SimplifiedArcId(here)
            })
        })
    }
}

impl SimplifiedTree {
    fn live_adjacency(&self) -> &LiveAdjacency {
        self.adjacency
            .get_or_init(|| LiveAdjacency::of_level(&self.sim, &self.live_arcs))
    }

    /// The live arcs whose lower end is `node` (the arcs a level set
    /// passes into going up through it), in no particular order; O(degree).
    pub fn arcs_above(&self, node: SimplifiedNodeId) -> impl Iterator<Item = SimplifiedArcId> + '_ {
        self.live_adjacency().iter(Side::Up, node)
    }

    /// The live arcs whose upper end is `node`, in no particular order;
    /// O(degree).
    pub fn arcs_below(&self, node: SimplifiedNodeId) -> impl Iterator<Item = SimplifiedArcId> + '_ {
        self.live_adjacency().iter(Side::Down, node)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::simplify::Measure;
    use crate::tree::ContourTree;
    use proptest::prelude::*;
    use std::sync::Arc;

    /// The oracle: every live arc scanned.
    fn scanned(
        level: &SimplifiedTree,
        node: SimplifiedNodeId,
        above: bool,
    ) -> Vec<SimplifiedArcId> {
        let sim = level.simplification();
        let mut v: Vec<SimplifiedArcId> = level
            .arc_ids()
            .iter()
            .map(|&a| SimplifiedArcId(a))
            .filter(|&a| {
                if above {
                    sim.lower(a) == node
                } else {
                    sim.upper(a) == node
                }
            })
            .collect();
        v.sort();
        v
    }

    fn check_every_node(level: &SimplifiedTree) {
        for n in 0..level.simplification().num_nodes() as u32 {
            let n = SimplifiedNodeId(n);
            let mut up: Vec<_> = level.arcs_above(n).collect();
            let mut down: Vec<_> = level.arcs_below(n).collect();
            up.sort();
            down.sort();
            assert_eq!(
                up,
                scanned(level, n, true),
                "above node {n:?} at step {}",
                level.step()
            );
            assert_eq!(
                down,
                scanned(level, n, false),
                "below node {n:?} at step {}",
                level.step()
            );
            assert_eq!(level.degree(n), (up.len() as u32, down.len() as u32));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn arcs_at_a_node_are_the_live_arcs_ending_there_at_every_level(
            seed in 0u64..1000, n in 4usize..9, noise in 0.05f32..0.6,
            jumps in proptest::collection::vec(0usize..1000, 1..8),
        ) {
            let field = Synthetic { noise, seed, ..Synthetic::cube(n) }.generate();
            let (tree, _) = ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
            let sim = Arc::new(Simplification::new(&tree, &field, Measure::Volume));
            let mut level = SimplifiedTree::new(Arc::clone(&sim));
            check_every_node(&level);
            let last = sim.steps().len();
            for j in jumps {
                level.set_step(j % (last + 1));
                check_every_node(&level);
            }
            level.set_step(last);
            check_every_node(&level);
        }

        #[test]
        fn a_level_built_afresh_is_the_level_walked_to(
            seed in 0u64..1000, n in 4usize..9, noise in 0.05f32..0.6,
            jumps in proptest::collection::vec(0usize..1000, 1..8),
        ) {
            let field = Synthetic { noise, seed, ..Synthetic::cube(n) }.generate();
            let (tree, _) = ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
            let sim = Arc::new(Simplification::new(&tree, &field, Measure::Hypervolume));
            let mut walked = SimplifiedTree::new(Arc::clone(&sim));
            let mut built = SimplifiedTree::new(Arc::clone(&sim));
            let last = sim.steps().len();
            for j in jumps.into_iter().chain([last, 0]) {
                let j = j % (last + 1);
                walked.walk(j);
                built.rebuild(j);
                let sorted = |t: &SimplifiedTree| {
                    let mut v = t.arc_ids().to_vec();
                    v.sort_unstable();
                    v
                };
                prop_assert_eq!(sorted(&walked), sorted(&built), "live arcs at step {}", j);
                prop_assert_eq!(built.num_arcs(), sim.curve()[j].arcs);
                for v in 0..sim.num_nodes() as u32 {
                    let v = SimplifiedNodeId(v);
                    prop_assert_eq!(walked.degree(v), built.degree(v));
                }
                check_every_node(&built);
                // A built level walks on like any other.
                built.walk(j / 2);
                walked.walk(j / 2);
                prop_assert_eq!(sorted(&walked), sorted(&built));
                check_every_node(&built);
            }
        }
    }
}
