//! The oracle the fast merge is checked against: the per-vertex merge of
//! Carr, Snoeyink, Axen (Fig. 9) exactly as flexiso ran it before the
//! candidate-node merge of [`super::merge`]: augmented join and split trees
//! (one parent per vertex), leaf cutting vertex by vertex, then every
//! regular vertex walked along its chain to its superarc. Test-only: it is
//! slow on smooth fields (every vertex visited in value order through
//! random memory) but simple enough to trust.

use super::sweep::{NONE, ROOT, link_rank, union};
use super::{ContourTree, Node, NodeId, Superarc};
use crate::field::VertexOrder;
use crate::mesh::{LINK_EMPTY, LINK_SEVERAL, Mesh};
use crate::progress::{Cancelled, Progress};

/// The whole oracle: sweeps, per-vertex merge, augmentation.
pub fn build<M: Mesh, O: VertexOrder + ?Sized>(mesh: &M, values: &O, order: &[u32]) -> ContourTree {
    if order.is_empty() {
        return ContourTree::assemble(Vec::new(), Vec::new(), Vec::new(), vec![0], Vec::new());
    }
    let codes = super::sweep::link_codes(mesh, values);
    let p = Progress::new();
    let join = sweep(mesh, values, &codes, true, order, &p).expect("not cancelled");
    let split = sweep(mesh, values, &codes, false, order, &p).expect("not cancelled");
    augment(merge(join, split, order, &p).expect("not cancelled"), order)
}

/// A sweep tree (join or split) in augmented form.
pub struct VertexSweepTree {
    /// The next vertex towards the root (the global minimum for the join
    /// tree, the global maximum for the split tree); `NONE` at the root.
    pub parent: Vec<u32>,
    /// Number of children: components of the superlevel (join) or sublevel
    /// (split) set that the vertex touches. 0 at leaves, >= 2 at saddles.
    pub children: Vec<u8>,
}

// Union-find words as in `sweep`: `ROOT | last` at a root, where `last`
// is the component's most recently added vertex (its lowest in the join
// sweep); `union` is the sweep's.

/// Sweeps `order` (the visiting order: descending for the join tree with
/// `join = true`, ascending for the split tree) and returns the augmented
/// sweep tree. `values` gives the vertex order; testing "already swept"
/// on it rather than on the union-find keeps the hot loop in the compact
/// value array (1 byte per vertex for uint8 scans) instead of 4 bytes.
pub fn sweep<M: Mesh, O: VertexOrder + ?Sized>(
    mesh: &M,
    values: &O,
    link_codes: &[u8],
    join: bool,
    order: &[u32],
    progress: &Progress,
) -> Result<VertexSweepTree, Cancelled> {
    let n = mesh.num_vertices();
    // uf[x]: NONE before x is visited; ROOT | last vertex at a root;
    // otherwise the parent in the union-find forest.
    let mut uf = vec![NONE; n];
    let mut parent = vec![NONE; n];
    let mut children = vec![0u8; n];
    let mut reps: Vec<u32> = Vec::with_capacity(16);
    const CHECK_EVERY: usize = 1 << 20;
    // How far ahead in the order to prefetch: enough vertices in flight to
    // hide DRAM latency, few enough that the lines are still in L1/L2.
    const AHEAD: usize = 12;
    for i in 0..n {
        if i % CHECK_EVERY == 0 {
            progress.check(i, n)?;
        }
        let at = |i: usize| if join { order[n - 1 - i] } else { order[i] };
        let v = at(i);
        if i + AHEAD < n {
            let w = at(i + AHEAD);
            mesh.prefetch_star(w, &uf);
        }
        let code = link_codes[v as usize];
        let code = if join { code & 0xf } else { code >> 4 };
        let mut root = v;
        uf[v as usize] = ROOT | v;
        let mut merged = 0u8;
        // One representative per component of the swept part of v's link.
        reps.clear();
        match code {
            LINK_EMPTY => {}
            LINK_SEVERAL => {
                if join {
                    mesh.for_each_link_component(v, |u| values.above(u, v), |u| reps.push(u));
                } else {
                    mesh.for_each_link_component(v, |u| values.above(v, u), |u| reps.push(u));
                }
            }
            index => reps.push(mesh.neighbour_at(v, index)),
        }
        for &u in &reps {
            let r = find(&mut uf, u);
            if r == root {
                continue;
            }
            // Component r is absorbed at v: the augmented tree arc runs
            // from its last vertex to v.
            let last = uf[r as usize] & !ROOT;
            parent[last as usize] = v;
            merged += 1;
            root = union(&mut uf, root, r, v, link_rank(root) > link_rank(r));
        }
        children[v as usize] = merged;
    }
    Ok(VertexSweepTree { parent, children })
}

/// Root of `x`'s set, halving the path on the way.
#[inline(always)]
fn find(uf: &mut [u32], mut x: u32) -> u32 {
    loop {
        let p = uf[x as usize];
        if p & ROOT != 0 {
            return x;
        }
        let gp = uf[p as usize];
        if gp & ROOT != 0 {
            return p;
        }
        uf[x as usize] = gp;
        x = gp;
    }
}

/// Marks `ct_next[x]` when x lies above its neighbour.
const ABOVE: u32 = 1 << 31;
use super::merge::{NODE_FLAG, climb};

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
    join: VertexSweepTree,
    split: VertexSweepTree,
    order: &[u32],
    progress: &Progress,
) -> Result<Merged, Cancelled> {
    let n = order.len();
    let VertexSweepTree {
        parent: mut jt_parent,
        children: mut jt_up,
    } = join;
    let VertexSweepTree {
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
                up: up.into(),
                down: down.into(),
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
            let y = climb(&mut jt_parent, start, |y, _| ct_next[y as usize] != NONE);
            ct_next[xi] = y | ABOVE;
            jt_up[y as usize] -= 1;
            y
        } else {
            let start = st_parent[xi];
            let y = climb(&mut st_parent, start, |y, _| ct_next[y as usize] != NONE);
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
