//! Path seeds: for a superarc `e` and a cut `c` (an [`Isovalue`]) strictly
//! inside its range, one mesh edge `(below, above)` that the contour of `e`
//! at `c` crosses, in O(log n).
//!
//! **Why it works.** Every point of the volume maps to the contour through
//! it, i.e. to a point of the contour tree, and that map is continuous and
//! keeps heights. The image of a mesh edge `(b, a)` with `b` below `a` is
//! therefore a *monotone* path of the tree from the place of `b` up to the
//! place of `a`; the edge's crossing point at level `c` lies on the contour
//! where that path passes height `c`.
//!
//! Let `a` be the lowest vertex of `e` above `c` (binary search in e's
//! sorted regular vertices; the upper node when none is above `c`).
//!
//! * If `a` is a regular vertex of `e`, or the upper node with `e` its only
//!   arc down, **every** lower neighbour `b` of `a` is below `c` and gives
//!   an edge whose crossing at `c` is on `e`. Why: the path of `(b, a)`
//!   descends from `a`, and going down from `a` the tree offers only `e`,
//!   so the path runs along `e` until it reaches `b`'s place or e's lower
//!   node. Were `b` above `c`, its place would be on `e` (the lower node
//!   is below `c`), making `b` a vertex of `e` above `c` lower than `a`: a
//!   contradiction. So `b` is below `c`, the path passes height `c` on
//!   `e`, and there the edge meets the contour of `e`.
//! * If `a` is the upper node and a join (several arcs down), mirror it:
//!   every upper neighbour of the highest regular vertex of `e` below `c`
//!   (or of e's lower node, when `e` is its only arc up and has no regular
//!   vertex below `c`) qualifies, by the same argument going up.
//! * Left is a *bare* arc: no regular vertex, a join at its top and a
//!   split at its bottom. Every edge crossing its contours then spans the
//!   whole arc (a path through `e` enters at the lower node and leaves at
//!   the upper), so one edge serves every cut, and some lower neighbour `b`
//!   of the upper node gives one (its contours close up at the upper node,
//!   inside its star). `b` qualifies iff it is not above the lower node and
//!   the tree path from `b`'s place to the upper node goes through `e`,
//!   i.e. `b`'s place is on the lower node's side of `e`: an O(1) test
//!   with the DFS intervals of a rooted tree ([`PathSeeds`] keeps them;
//!   [`path_seed`] builds them when it meets a bare arc, O(supernodes)).

use crate::field::Isovalue;
use crate::field::ScalarField;
use crate::mesh::EDGE_OFFSETS;
use crate::tree::{ArcId, ContourTree, NodeId, VertexPlace};
use std::sync::OnceLock;

/// A seed of one contour: a mesh edge from `below` to `above` that the
/// contour of `arc` at the isovalue crosses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathSeed {
    /// The superarc.
    pub arc: ArcId,
    /// The end of the edge below the isovalue.
    pub below: u32,
    /// The end of the edge above the isovalue.
    pub above: u32,
}

/// True when the contours of `arc` include one at `iso`: its lower node is
/// below the cut and its upper node above.
pub fn arc_spans(tree: &ContourTree, field: &ScalarField, arc: ArcId, iso: Isovalue) -> bool {
    let a = tree.arc(arc);
    !iso.is_above(field, tree.node(a.lower).vertex)
        && iso.is_above(field, tree.node(a.upper).vertex)
}

/// The path seed of superarc `arc` at `iso`, or `None` when the arc does
/// not span `iso` (see the module doc for the proof). O(log n), but
/// O(supernodes) for a bare arc (no regular vertex, a join on top of a
/// split): use [`PathSeeds`] to extract many contours.
pub fn path_seed(
    tree: &ContourTree,
    field: &ScalarField,
    arc: ArcId,
    iso: Isovalue,
) -> Option<PathSeed> {
    seed(tree, field, arc, iso, &OnceLock::new())
}

/// The path seed at `iso` of a chain of superarcs (a simplified or
/// collapsed arc: a monotone path of the tree, ascending): binary search
/// for the superarc spanning `iso`, then [`path_seed`].
pub fn path_seed_in_chain(
    tree: &ContourTree,
    field: &ScalarField,
    chain: &[ArcId],
    iso: Isovalue,
) -> Option<PathSeed> {
    path_seed(tree, field, chain_arc(tree, field, chain, iso)?, iso)
}

/// The only superarc of an ascending chain that can span `iso`: the first
/// whose upper node is above the cut.
fn chain_arc(
    tree: &ContourTree,
    field: &ScalarField,
    chain: &[ArcId],
    iso: Isovalue,
) -> Option<ArcId> {
    let i = chain.partition_point(|&e| !iso.is_above(field, tree.node(tree.arc(e).upper).vertex));
    chain.get(i).copied()
}

/// Path seeds of one tree, O(1) for every arc: the DFS intervals that
/// resolve bare arcs, built on first need (O(supernodes), 12 bytes per
/// supernode) and kept. Share one between threads.
#[derive(Debug, Default)]
pub struct PathSeeds {
    tour: OnceLock<Tour>,
}

impl PathSeeds {
    /// Seeds for any tree (the tree is passed to each call; always the
    /// same one).
    pub fn new() -> Self {
        Self::default()
    }

    /// [`path_seed`], with the DFS intervals kept.
    pub fn seed(
        &self,
        tree: &ContourTree,
        field: &ScalarField,
        arc: ArcId,
        iso: Isovalue,
    ) -> Option<PathSeed> {
        seed(tree, field, arc, iso, &self.tour)
    }

    /// [`path_seed_in_chain`], with the DFS intervals kept.
    pub fn seed_in_chain(
        &self,
        tree: &ContourTree,
        field: &ScalarField,
        chain: &[ArcId],
        iso: Isovalue,
    ) -> Option<PathSeed> {
        self.seed(tree, field, chain_arc(tree, field, chain, iso)?, iso)
    }
}

fn seed(
    tree: &ContourTree,
    field: &ScalarField,
    arc: ArcId,
    iso: Isovalue,
    tour: &OnceLock<Tour>,
) -> Option<PathSeed> {
    if !arc_spans(tree, field, arc, iso) {
        return None;
    }
    let e = tree.arc(arc);
    let upper = tree.node(e.upper);
    let regular = tree.arc_vertices(arc);
    // Regular vertices below the cut come first.
    let split = regular.partition_point(|v| !iso.is_above(field, v));
    let seed = |below: u32, above: u32| PathSeed { arc, below, above };
    let a_regular = regular.get(split);
    if let Some(a) = a_regular.or((upper.down == 1).then_some(upper.vertex)) {
        // Any lower neighbour (module doc): the first.
        let b = first_neighbour(field, a, false)?;
        debug_assert!(!iso.is_above(field, b));
        return Some(seed(b, a));
    }
    let lower = tree.node(e.lower);
    let b = match split {
        0 if lower.up == 1 => lower.vertex,
        0 => {
            let tour = tour.get_or_init(|| Tour::new(tree));
            let mut found = None;
            for_each_neighbour(field, upper.vertex, |b| {
                if found.is_none()
                    && !field.is_above(b, lower.vertex)
                    && tour.on_lower_side(tree, arc, b)
                {
                    found = Some(b);
                }
            });
            return found.map(|b| seed(b, upper.vertex));
        }
        _ => regular
            .get(split - 1)
            .expect("split is within the regular vertices"),
    };
    let a = first_neighbour(field, b, true)?;
    debug_assert!(iso.is_above(field, a));
    Some(seed(b, a))
}

/// The first lower (`up == false`) or upper neighbour of `v` in the vertex
/// order.
fn first_neighbour(field: &ScalarField, v: u32, up: bool) -> Option<u32> {
    let mut found: Option<u32> = None;
    for_each_neighbour(field, v, |u| {
        if found.is_none() && field.is_above(u, v) == up {
            found = Some(u);
        }
    });
    found
}

/// Calls `f` on every neighbour of `v` in the Freudenthal triangulation.
/// (Not [`ScalarField::mesh`]: building its link tables costs far more
/// than a seed.)
fn for_each_neighbour(field: &ScalarField, v: u32, mut f: impl FnMut(u32)) {
    let dims = field.dims().map(|d| d as i64);
    let c = field.coords(v).map(|x| x as i64);
    for o in EDGE_OFFSETS {
        for sign in [1, -1] {
            let n: [i64; 3] = std::array::from_fn(|k| c[k] + sign * o[k]);
            if (0..3).all(|k| (0..dims[k]).contains(&n[k])) {
                f((n[0] + dims[0] * (n[1] + dims[1] * n[2])) as u32);
            }
        }
    }
}

/// The two sides of one contour: the contour of superarc `arc` at a cut,
/// a point inside the arc, splits the tree in two when it is taken out,
/// and the *upper* side is the part that holds the arc's upper node. A
/// vertex lies on the side its place lies on (a regular vertex of `arc`
/// itself: on the upper side when it is above the cut).
///
/// **Why it matters.** The image of a mesh edge is a monotone path of the
/// tree (module doc). An edge whose ends lie on different sides therefore
/// passes the taken-out point, at the cut's height, which a monotone path
/// passes once: the edge crosses the cut, and its crossing lies on this
/// contour. Conversely the crossing of an edge on this contour is that
/// point, where going up the tree offers only the arc's upper part and
/// going down only its lower part: the edge's upper end is on the upper
/// side, its lower end on the lower. So the side bit, marched in place of
/// "above the cut", gives this contour's crossed edges and tetrahedra
/// exactly (with the same cases: on them the side is the same as above),
/// and no other contour's: no components to tell apart.
///
/// One bit per supernode and per superarc, filled by a search of the upper
/// side (O(its supernodes)).
#[derive(Debug)]
pub struct CutSides {
    arc: ArcId,
    nodes: Vec<u64>,
    arcs: Vec<u64>,
}

impl CutSides {
    /// The sides of the contours of `arc` (any cut inside it).
    pub fn new(tree: &ContourTree, arc: ArcId) -> Self {
        let bit = |bits: &[u64], i: u32| bits[i as usize / 64] >> (i % 64) & 1 == 1;
        let set = |bits: &mut [u64], i: u32| bits[i as usize / 64] |= 1 << (i % 64);
        let mut nodes = vec![0u64; tree.nodes().len().div_ceil(64)];
        let mut arcs = vec![0u64; tree.arcs().len().div_ceil(64)];
        let top = tree.arc(arc).upper;
        set(&mut nodes, top.0);
        set(&mut arcs, arc.0);
        let mut stack = vec![top];
        while let Some(x) = stack.pop() {
            for &d in tree.node_arcs(x) {
                if bit(&arcs, d.0) {
                    continue;
                }
                set(&mut arcs, d.0);
                let e = tree.arc(d);
                let y = if e.lower == x { e.upper } else { e.lower };
                if !bit(&nodes, y.0) {
                    set(&mut nodes, y.0);
                    stack.push(y);
                }
            }
        }
        Self { arc, nodes, arcs }
    }

    /// The superarc whose contours these are.
    pub fn arc(&self) -> ArcId {
        self.arc
    }

    /// True when vertex `v` lies on the upper side; `above` says whether it
    /// lies above the cut (asked only for the arc's own regular vertices).
    #[inline(always)]
    pub fn is_upper(&self, tree: &ContourTree, v: u32, above: impl FnOnce() -> bool) -> bool {
        let (bits, i) = match tree.place(v) {
            VertexPlace::Node(n) => (&self.nodes, n.0),
            VertexPlace::Arc(d) if d == self.arc => return above(),
            VertexPlace::Arc(d) => (&self.arcs, d.0),
        };
        bits[i as usize / 64] >> (i % 64) & 1 == 1
    }
}

/// The contour tree rooted at its first node, by DFS: per node the arc to
/// its parent and the interval of DFS entry times of its subtree, so "is
/// x below this arc" is two comparisons.
#[derive(Debug)]
struct Tour {
    /// Per node: (entry time, largest entry time in its subtree).
    interval: Vec<(u32, u32)>,
    /// Per node: the arc to its parent (`u32::MAX` at a root).
    parent_arc: Vec<u32>,
}

impl Tour {
    fn new(tree: &ContourTree) -> Self {
        let n = tree.nodes().len();
        let mut interval = vec![(u32::MAX, 0); n];
        let mut parent_arc = vec![u32::MAX; n];
        let mut time = 0u32;
        // (node, next arc index to look at).
        let mut stack: Vec<(u32, usize)> = Vec::new();
        for root in 0..n as u32 {
            if interval[root as usize].0 != u32::MAX {
                continue;
            }
            interval[root as usize].0 = time;
            time += 1;
            stack.push((root, 0));
            while let Some(&mut (x, ref mut i)) = stack.last_mut() {
                let id = NodeId(x);
                let (up, down) = (tree.up_arcs(id), tree.down_arcs(id));
                if *i < up.len() + down.len() {
                    let a = if *i < up.len() {
                        up[*i]
                    } else {
                        down[*i - up.len()]
                    };
                    *i += 1;
                    let arc = tree.arc(a);
                    let y = if arc.lower == id {
                        arc.upper
                    } else {
                        arc.lower
                    };
                    if interval[y.0 as usize].0 == u32::MAX {
                        interval[y.0 as usize].0 = time;
                        time += 1;
                        parent_arc[y.0 as usize] = a.0;
                        stack.push((y.0, 0));
                    }
                } else {
                    interval[x as usize].1 = time - 1;
                    stack.pop();
                }
            }
        }
        Self {
            interval,
            parent_arc,
        }
    }

    /// True when `x` is in the subtree of node `root`.
    fn in_subtree(&self, root: NodeId, x: NodeId) -> bool {
        let (lo, hi) = self.interval[root.0 as usize];
        (lo..=hi).contains(&self.interval[x.0 as usize].0)
    }

    /// True when the place of vertex `b` lies on the lower node's side of
    /// `arc` (cutting `arc` splits the tree in two).
    fn on_lower_side(&self, tree: &ContourTree, arc: ArcId, b: u32) -> bool {
        let e = tree.arc(arc);
        let x = match tree.place(b) {
            VertexPlace::Node(n) => n,
            VertexPlace::Arc(d) if d == arc => return true,
            // Both ends of another arc lie on the same side of `arc`.
            VertexPlace::Arc(d) => tree.arc(d).lower,
        };
        if self.parent_arc[e.lower.0 as usize] == arc.0 {
            self.in_subtree(e.lower, x)
        } else {
            !self.in_subtree(e.upper, x)
        }
    }
}
