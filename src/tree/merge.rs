//! Merging the join and split trees into the augmented contour tree
//! (Carr, Snoeyink, Axen, Fig. 9), then grouping the regular vertices into
//! superarcs.
//!
//! A vertex is an *upper leaf* of the contour tree when it has no children
//! in the join tree and one in the split tree; a *lower leaf* the other way
//! round. Repeatedly, a leaf x is cut off: its contour tree arc goes to its
//! parent in the join tree (upper leaf) or in the split tree (lower leaf);
//! it is then deleted from both trees, in one as a leaf, in the other by
//! contracting a vertex with one child. Contraction is lazy: a deleted
//! vertex keeps its parent pointer, and lookups skip deleted vertices with
//! path compression.
//!
//! Each vertex but the last gets exactly one arc, `ct_next[x]`, to the
//! neighbour it was cut towards. We keep the global minimum for last (it is
//! a leaf, and a tree always has a second leaf to cut instead), so the last
//! vertex is a supernode. Then along every superarc the arcs all point the
//! same way: a superarc s - r1 - ... - rk - t has k + 1 arcs owned by k
//! regular vertices and exactly one of its ends, so the chain is
//! s -> r1 -> ... -> rk -> t. Following `ct_next` from any regular vertex
//! thus ends at the same supernode for the whole superarc, through the same
//! last vertex rk, which names the superarc.

use super::sweep::{NONE, SweepTree};
use super::{ContourTree, Node, NodeId, Superarc};
use crate::progress::{Cancelled, Progress};

/// Marks `ct_next[x]` when x lies above its neighbour.
const ABOVE: u32 = 1 << 31;
/// Marks a node in `vertex_arc`.
pub(super) const NODE_FLAG: u32 = 1 << 31;

/// The contour tree as the merge leaves it: supernodes and one arc per
/// vertex, before superarcs are formed.
pub struct Merged {
    nodes: Vec<Node>,
    vertex_arc: Vec<u32>,
    ct_next: Vec<u32>,
}

/// Merges the two sweep trees into the augmented contour tree. `order` is
/// the vertex order ascending.
pub fn merge(
    join: SweepTree,
    split: SweepTree,
    order: &[u32],
    progress: &Progress,
) -> Result<Merged, Cancelled> {
    let n = order.len();
    let SweepTree {
        parent: mut jt_parent,
        children: mut jt_up,
    } = join;
    let SweepTree {
        parent: mut st_parent,
        children: mut st_down,
    } = split;

    // Supernodes, in vertex order: up- and down-degrees in the contour tree
    // are the join tree's children and the split tree's children.
    let mut vertex_arc = vec![NONE; n];
    let mut nodes = Vec::new();
    for &v in order {
        let (up, down) = (jt_up[v as usize], st_down[v as usize]);
        if up != 1 || down != 1 {
            vertex_arc[v as usize] = NODE_FLAG | nodes.len() as u32;
            nodes.push(Node {
                vertex: v,
                up: up as u32,
                down: down as u32,
            });
        }
    }
    if n == 1 {
        return Ok(Merged {
            nodes,
            vertex_arc,
            ct_next: vec![NONE],
        });
    }

    let global_min = order[0];
    let mut ct_next = vec![NONE; n];
    let mut leaves: Vec<u32> = order
        .iter()
        .copied()
        .filter(|&v| v != global_min && jt_up[v as usize] + st_down[v as usize] == 1)
        .collect();
    let mut cut = 0usize;
    while let Some(x) = leaves.pop() {
        cut += 1;
        if cut.is_multiple_of(1 << 20) {
            progress.check(cut, n)?;
        }
        let xi = x as usize;
        let y = if jt_up[xi] == 0 {
            // Upper leaf: its arc runs down the join tree. It leaves the
            // join tree as a leaf and is contracted out of the split tree.
            let start = jt_parent[xi];
            let y = live_parent(&mut jt_parent, &ct_next, start);
            ct_next[xi] = y | ABOVE;
            jt_up[y as usize] -= 1;
            y
        } else {
            let start = st_parent[xi];
            let y = live_parent(&mut st_parent, &ct_next, start);
            ct_next[xi] = y;
            st_down[y as usize] -= 1;
            y
        };
        let yi = y as usize;
        if y != global_min && jt_up[yi] + st_down[yi] == 1 {
            leaves.push(y);
        }
    }
    debug_assert_eq!(cut, n - 1, "every vertex but the global minimum is cut");
    Ok(Merged {
        nodes,
        vertex_arc,
        ct_next,
    })
}

/// The nearest ancestor of `y` (inclusive) not yet cut, compressing the
/// path to it.
#[inline]
fn live_parent(parent: &mut [u32], ct_next: &[u32], start: u32) -> u32 {
    let mut y = start;
    while ct_next[y as usize] != NONE {
        y = parent[y as usize];
    }
    let mut c = start;
    while c != y {
        let next = parent[c as usize];
        parent[c as usize] = y;
        c = next;
    }
    y
}

/// Groups the regular vertices into superarcs (see the module doc) and
/// assembles the tree.
pub fn augment(merged: Merged, order: &[u32]) -> ContourTree {
    let Merged {
        nodes,
        mut vertex_arc,
        ct_next,
    } = merged;
    let n = order.len();
    let is_node = |va: u32| va != NONE && va & NODE_FLAG != 0;
    let mut arcs: Vec<Superarc> = Vec::new();
    // Superarcs with regular vertices are found at their last vertex rk;
    // their start (the supernode that owns the first arc) is filled below.
    for x in 0..n {
        let next = ct_next[x];
        if next == NONE {
            continue;
        }
        let y = (next & !ABOVE) as usize;
        let x_above = next & ABOVE != 0;
        match (is_node(vertex_arc[x]), is_node(vertex_arc[y])) {
            (true, true) => {
                let (a, b) = (
                    NodeId(vertex_arc[x] & !NODE_FLAG),
                    NodeId(vertex_arc[y] & !NODE_FLAG),
                );
                let (upper, lower) = if x_above { (a, b) } else { (b, a) };
                arcs.push(Superarc { upper, lower });
            }
            (false, true) => {
                // x is the last regular vertex of its superarc; its end is y.
                let end = NodeId(vertex_arc[y] & !NODE_FLAG);
                vertex_arc[x] = arcs.len() as u32;
                // The other end is not known yet: a placeholder that the
                // start pass overwrites.
                let (upper, lower) = if x_above {
                    (NodeId(u32::MAX), end)
                } else {
                    (end, NodeId(u32::MAX))
                };
                arcs.push(Superarc { upper, lower });
            }
            _ => {}
        }
    }
    // Label every regular vertex by walking its chain to a labelled vertex;
    // a second walk writes the label, so each vertex is walked O(1) times.
    for x in 0..n {
        if vertex_arc[x] != NONE {
            continue;
        }
        let mut y = x;
        while vertex_arc[y] == NONE {
            y = (ct_next[y] & !ABOVE) as usize;
        }
        let label = vertex_arc[y];
        let mut y = x;
        while vertex_arc[y] == NONE {
            vertex_arc[y] = label;
            y = (ct_next[y] & !ABOVE) as usize;
        }
    }
    // The start node of each superarc with regular vertices: the node whose
    // arc points at its first regular vertex.
    for x in 0..n {
        let next = ct_next[x];
        if next == NONE || !is_node(vertex_arc[x]) {
            continue;
        }
        let y = (next & !ABOVE) as usize;
        if !is_node(vertex_arc[y]) {
            let arc = &mut arcs[vertex_arc[y] as usize];
            let s = NodeId(vertex_arc[x] & !NODE_FLAG);
            if arc.upper.0 == u32::MAX {
                arc.upper = s;
            } else {
                arc.lower = s;
            }
        }
    }
    drop(ct_next);

    // Regular vertices of each superarc, in vertex order: count, then place
    // while walking the order ascending.
    let mut offsets = vec![0u32; arcs.len() + 1];
    for &va in &vertex_arc {
        if !is_node(va) {
            offsets[va as usize + 1] += 1;
        }
    }
    for a in 1..offsets.len() {
        offsets[a] += offsets[a - 1];
    }
    let mut fill = offsets.clone();
    let mut arc_vertices = vec![0u32; offsets[arcs.len()] as usize];
    for &v in order {
        let va = vertex_arc[v as usize];
        if !is_node(va) {
            arc_vertices[fill[va as usize] as usize] = v;
            fill[va as usize] += 1;
        }
    }
    ContourTree::assemble(nodes, arcs, vertex_arc, offsets, arc_vertices)
}
