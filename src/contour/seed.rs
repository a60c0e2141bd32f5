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
//!   arc down, the path from `a` downwards runs along `e` until e's lower
//!   node, which lies below `c`. So **every** lower neighbour `b` of `a`
//!   that lies below `c` gives an edge whose crossing at `c` is on `e`.
//!   And the *lowest* lower neighbour `b1` is always below `c`: if it were
//!   above, the path of `(b1, a)` would end on `e` at height `f(b1)`
//!   (strictly between `c` and `a`, hence above e's lower node), making
//!   `b1` a vertex of `e` above `c` lower than `a`: a contradiction.
//!   (Not every lower neighbour of `a` need be below `c`: some may lie
//!   between `c` and `a` on other arcs; those we skip.)
//! * If `a` is the upper node and a join (several arcs down), the paths
//!   from `a` may go down any of them. Mirror the argument: take the
//!   highest regular vertex of `e` below `c` and its highest upper
//!   neighbour. If `e` has no regular vertex at all and its lower node
//!   is a split as well, one lower neighbour `b` of the upper node still
//!   works (the contours of `e` end at the upper node, so they reach its
//!   star): it is one whose place is reached from e's lower node by a
//!   descending walk of the tree, which we test by that walk (rare, and
//!   bounded by the part of the tree between the two).

use super::Isovalue;
use crate::field::ScalarField;
use crate::mesh::Mesh;
use crate::tree::{ArcId, ContourTree, NodeId, VertexPlace};

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
/// not span `iso` (see the module doc for the proof).
pub fn path_seed(
    tree: &ContourTree,
    field: &ScalarField,
    arc: ArcId,
    iso: Isovalue,
) -> Option<PathSeed> {
    if !arc_spans(tree, field, arc, iso) {
        return None;
    }
    let mesh = field.mesh();
    let e = tree.arc(arc);
    let upper = tree.node(e.upper);
    let regular = tree.arc_vertices(arc);
    // Regular vertices below the cut come first.
    let split = regular.partition_point(|&v| !iso.is_above(field, v));
    let seed = |below: u32, above: u32| PathSeed { arc, below, above };
    let a_regular = regular.get(split).copied();
    if let Some(a) = a_regular.or((upper.down == 1).then_some(upper.vertex)) {
        let b = extreme_neighbour(&mesh, field, a, false)?;
        debug_assert!(!iso.is_above(field, b));
        return Some(seed(b, a));
    }
    if split > 0 {
        let b = regular[split - 1];
        let a = extreme_neighbour(&mesh, field, b, true)?;
        debug_assert!(iso.is_above(field, a));
        return Some(seed(b, a));
    }
    let lower = tree.node(e.lower);
    if lower.up == 1 {
        let a = extreme_neighbour(&mesh, field, lower.vertex, true)?;
        return Some(seed(lower.vertex, a));
    }
    // A bare arc from a split up to a join: test the lower neighbours of
    // the upper node that lie below the cut.
    let mut found = None;
    mesh.for_each_neighbour(upper.vertex, |b| {
        if found.is_none() && !iso.is_above(field, b) && descends_to(tree, field, e.lower, b) {
            found = Some(b);
        }
    });
    found.map(|b| seed(b, upper.vertex))
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
    // Ascending chain: the first superarc whose upper node is above the cut
    // is the only one that can span it.
    let i = chain.partition_point(|&e| !iso.is_above(field, tree.node(tree.arc(e).upper).vertex));
    path_seed(tree, field, *chain.get(i)?, iso)
}

/// The lowest lower neighbour (`up == false`) or highest upper neighbour of
/// `v` in the vertex order.
fn extreme_neighbour(mesh: &impl Mesh, field: &ScalarField, v: u32, up: bool) -> Option<u32> {
    let mut best: Option<u32> = None;
    mesh.for_each_neighbour(v, |u| {
        let side = field.is_above(u, v) == up;
        if side {
            let better = match best {
                None => true,
                Some(b) => field.is_above(u, b) == up,
            };
            if better {
                best = Some(u);
            }
        }
    });
    best
}

/// True when the place of vertex `b` is reached from node `from` by a walk
/// that only goes down the tree (never below `b`).
fn descends_to(tree: &ContourTree, field: &ScalarField, from: NodeId, b: u32) -> bool {
    let target = tree.place(b);
    let mut stack = vec![from];
    while let Some(n) = stack.pop() {
        if target == VertexPlace::Node(n) {
            return true;
        }
        for &d in tree.down_arcs(n) {
            if target == VertexPlace::Arc(d) {
                return true;
            }
            let l = tree.arc(d).lower;
            if !field.is_above(b, tree.node(l).vertex) {
                stack.push(l);
            }
        }
    }
    false
}
