//! Merging the join and split trees into the contour tree (Carr, Snoeyink,
//! Axen, Alg. 4.2, Fig. 9) on the candidate nodes only (§4.4), then placing
//! every other vertex on its superarc in one parallel streaming pass.
//!
//! **Why this design.** Merging the augmented trees vertex by vertex (what
//! flexiso did before; kept as the test oracle in `vertex_merge`) cuts
//! leaves in an order set by the tree, which on a smooth field is scattered
//! across the volume: every vertex is a cache miss, twice (merge, then the
//! walk to its superarc), 320 ns per vertex on `synthetic:512`. Here the
//! per-vertex work is two sequential reads and a few lookups in arrays the
//! size of the candidates, done in id order on every core; only the
//! candidates (a few per cent of the vertices on smooth fields, about half
//! on white noise) go through the merge. TTK's FTM and Viskores' contour
//! tree likewise compute the tree on critical points and attach regular
//! vertices afterwards; the attachment rule below is ours.
//!
//! **The merge** is Fig. 9 on the candidates: an upper leaf (no children in
//! the join tree, one in the split tree) is cut along its join tree edge, a
//! lower leaf along its split tree edge, and deleted from both trees (in
//! the other tree by contracting it; lazily, with path compression). Both
//! trees have the candidates as vertex set and every vertex left out is of
//! degree two in both, so they are the join and split trees of the contour
//! tree augmented with the candidates, and the merge returns that tree.
//! Keeping the global minimum for last, each other candidate `c` is cut
//! exactly once, towards its neighbour `parent[c]`: cut vertices never
//! come back, so this is the tree *rooted at the global minimum*, whatever
//! order the leaves were cut in.
//!
//! **Supernodes and superarcs.** Supernodes are the candidates with other
//! than one child in each tree. A depth-first pass from the root numbers
//! the candidates in pre-order (`tin`, and `tout` past their subtree) and
//! labels each candidate's edge to its parent with its superarc: the edges
//! through a candidate that is not a supernode belong to one superarc.
//!
//! **Placing a vertex that is not a candidate.** Let `v` lie on the edge
//! `e` between candidates `U` (above) and `L` (below), and let `a` and `b`
//! be its leafward candidates in the join and split trees: `a` is the
//! lowest candidate of the superlevel component `R+` of `v`, `b` the
//! highest of its sublevel component `R-`. The tree path from `a` to `b`
//! runs through `R+` down to `v` and through `R-` from there, so it crosses
//! the height of `v` once, on `e`. In the rooted tree one end of `e` is the
//! child:
//! - `U` is the child: `a` lies below `U` in the rooted tree, and every
//!   candidate on the path from `a` up to `U` is in `R+`, hence no lower
//!   than `a`, while `L` is lower than `a`. So `U = A(a)`, where `A(x)` is
//!   the last ancestor of `x` (inclusive) before the first one lower than
//!   `x`, and `b`, on the other side of `e`, is not in the subtree of `U`.
//! - `L` is the child: symmetrically `L = B(b)`, the last ancestor of `b`
//!   before the first one higher than `b`; and `b` is in the subtree of
//!   `A(a)`: the path from `a` climbs through `R+` (candidates no lower than
//!   `a`) at least to the common ancestor of `a` and `b`, so `A(a)` is that
//!   ancestor or above it.
//!
//! So `e` is the edge above `A(a)` unless `b` lies in the subtree of `A(a)`
//! (`tin[A(a)] <= tin[b] < tout[A(a)]`), and then the edge above `B(b)`.
//! `A` and `B` come from one depth-first pass with a monotone stack of the
//! ancestors (restored when the pass backs up): O(c log c) for c
//! candidates. Per vertex the rule reads `a`, `b` (sequentially, in id
//! order) and two small records of the candidates: no walk, no order.
//!
//! Finally the regular vertices of each superarc are laid out in the vertex
//! order by one counting pass over the order (the one pass that reads the
//! vertices in value order; it only reads their superarc).

use super::sweep::{CANDIDATE, JoinTree, NONE, SplitTree, prefetch};
use super::{ContourTree, Node, NodeId, Superarc};
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;

/// Marks a node in `vertex_arc`.
pub(super) const NODE_FLAG: u32 = 1 << 31;

/// The contour tree on the candidates, as the merge leaves it: what placing
/// the other vertices needs.
pub struct CandidateTree {
    nodes: Vec<Node>,
    arcs: Vec<Superarc>,
    /// Per candidate: `NODE_FLAG | node` for a supernode, otherwise the
    /// superarc it lies inside.
    candidate_place: Vec<u32>,
    /// Per candidate `a`: pre-order range of `A(a)`'s subtree and the
    /// superarc of the edge above `A(a)`.
    join_side: Vec<[u32; 3]>,
    /// Per candidate `b`: its pre-order number and the superarc of the edge
    /// above `B(b)` (`NONE` if it has none).
    split_side: Vec<[u32; 2]>,
}

/// Merges the join and split trees (see the module documentation).
/// `candidate_vertex` lists the candidates' vertices, ascending.
/// Arrays are dropped as soon as they are used up: on white noise about
/// half the vertices are candidates.
pub fn merge(
    join: JoinTree,
    split: SplitTree,
    candidate_vertex: Vec<u32>,
    progress: &Progress,
) -> Result<CandidateTree, Cancelled> {
    let k = candidate_vertex.len();
    let (mut jt_parent, mut jt_up) = (join.0.parent, join.0.children);
    let (mut st_parent, mut st_down) = (split.0.parent, split.0.children);
    debug_assert_eq!(jt_parent.len(), k);

    // Supernodes, in vertex order.
    let mut node_of = crate::pages::filled(k, NONE);
    let mut nodes = Vec::new();
    for c in 0..k {
        let (up, down) = (jt_up[c], st_down[c]);
        if up != 1 || down != 1 {
            node_of[c] = nodes.len() as u32;
            nodes.push(Node {
                vertex: candidate_vertex[c],
                up: up as u32,
                down: down as u32,
            });
        }
    }

    drop(candidate_vertex);

    // Fig. 9 on the candidates; the global minimum (candidate 0) is last.
    let mut parent = crate::pages::filled(k, NONE);
    let mut leaves: Vec<u32> = (1..k as u32)
        .filter(|&c| jt_up[c as usize] + st_down[c as usize] == 1)
        .collect();
    let mut cut = 0usize;
    while let Some(x) = leaves.pop() {
        cut += 1;
        if cut.is_multiple_of(1 << 20) {
            progress.check(cut, k)?;
        }
        let xi = x as usize;
        let y = if jt_up[xi] == 0 {
            // Upper leaf: its edge runs down the join tree.
            let start = jt_parent[xi];
            let y = live_parent(&mut jt_parent, &parent, start);
            jt_up[y as usize] -= 1;
            y
        } else {
            let start = st_parent[xi];
            let y = live_parent(&mut st_parent, &parent, start);
            st_down[y as usize] -= 1;
            y
        };
        parent[xi] = y;
        let yi = y as usize;
        if y != 0 && jt_up[yi] + st_down[yi] == 1 {
            leaves.push(y);
        }
    }
    debug_assert_eq!(
        cut,
        k.saturating_sub(1),
        "every candidate but the root is cut"
    );
    drop((jt_parent, jt_up, st_parent, st_down, leaves));
    progress.check(0, 1)?;

    // Children lists of the rooted tree.
    let mut first = vec![0u32; k + 1];
    for &p in &parent[1..] {
        first[p as usize + 1] += 1;
    }
    for c in 0..k {
        first[c + 1] += first[c];
    }
    let mut fill = first.clone();
    let mut child = vec![0u32; k.saturating_sub(1)];
    for (c, &p) in parent.iter().enumerate().skip(1) {
        child[fill[p as usize] as usize] = c as u32;
        fill[p as usize] += 1;
    }
    drop((fill, parent));

    // One depth-first pass: pre-order, A and B, superarc labels.
    let mut tin = crate::pages::filled(k, 0u32);
    let mut tout = crate::pages::filled(k, 0u32);
    let mut a_of = crate::pages::filled(k, NONE);
    let mut b_of = crate::pages::filled(k, NONE);
    let mut label = crate::pages::filled(k, NONE);
    // Superarcs as (end towards the root, end away from it), candidates.
    let mut ends: Vec<(u32, u32)> = Vec::new();
    let mut path: Vec<u32> = Vec::new();
    let mut next_child: Vec<u32> = Vec::new();
    // Monotone stacks of depths on the path: ancestors' candidate numbers
    // increasing (for A) and decreasing (for B) with depth; each entry's
    // overwritten slot saved per depth to restore on the way back.
    let (mut inc, mut inc_len, mut dec, mut dec_len) = (Vec::new(), 0usize, Vec::new(), 0usize);
    let mut saved: Vec<Saved> = Vec::new();
    let mut time = 0u32;
    if k > 0 {
        path.push(0);
        next_child.push(first[0]);
        enter(
            0,
            &path,
            (&mut inc, &mut inc_len),
            (&mut dec, &mut dec_len),
            &mut saved,
            (&mut a_of, &mut b_of),
        );
        tin[0] = time;
        time += 1;
    }
    while let Some(&x) = path.last() {
        let d = path.len() - 1;
        let i = next_child[d];
        if i < first[x as usize + 1] {
            next_child[d] = i + 1;
            let c = child[i as usize];
            path.push(c);
            next_child.push(first[c as usize]);
            enter(
                c,
                &path,
                (&mut inc, &mut inc_len),
                (&mut dec, &mut dec_len),
                &mut saved,
                (&mut a_of, &mut b_of),
            );
            tin[c as usize] = time;
            time += 1;
            let l = if x == 0 || node_of[x as usize] != NONE {
                ends.push((x, NONE));
                ends.len() as u32 - 1
            } else {
                label[x as usize]
            };
            label[c as usize] = l;
            if node_of[c as usize] != NONE {
                ends[l as usize].1 = c;
            }
        } else {
            tout[x as usize] = time;
            let Saved {
                inc: (p, old_len, old_val),
                dec: (q, old_dlen, old_dval),
            } = saved[d];
            if old_val != EMPTY {
                inc[p as usize] = old_val;
            }
            inc_len = old_len as usize;
            if old_dval != EMPTY {
                dec[q as usize] = old_dval;
            }
            dec_len = old_dlen as usize;
            saved.pop();
            path.pop();
            next_child.pop();
        }
    }
    drop((child, first, path, next_child, inc, dec, saved));

    let mut arcs: Vec<Superarc> = ends
        .iter()
        .map(|&(r, c)| {
            let (hi, lo) = if r > c { (r, c) } else { (c, r) };
            Superarc {
                upper: NodeId(node_of[hi as usize]),
                lower: NodeId(node_of[lo as usize]),
            }
        })
        .collect();
    // Superarcs in the tree's canonical order, by (lower, upper), now: the
    // per-vertex arrays are then made in their final form.
    let mut perm: Vec<u32> = (0..arcs.len() as u32).collect();
    perm.sort_unstable_by_key(|&a| (arcs[a as usize].lower, arcs[a as usize].upper));
    let mut new_id = vec![0u32; arcs.len()];
    for (new, &old) in perm.iter().enumerate() {
        new_id[old as usize] = new as u32;
    }
    arcs = perm.iter().map(|&a| arcs[a as usize]).collect();
    for l in label.iter_mut().filter(|l| **l != NONE) {
        *l = new_id[*l as usize];
    }
    let join_side: Vec<[u32; 3]> = a_of
        .iter()
        .map(|&a| {
            if a == NONE {
                [0, 0, NONE]
            } else {
                let a = a as usize;
                [tin[a], tout[a], label[a]]
            }
        })
        .collect();
    drop((a_of, tout));
    let split_side: Vec<[u32; 2]> = b_of
        .iter()
        .zip(&tin)
        .map(|(&b, &t)| [t, if b == NONE { NONE } else { label[b as usize] }])
        .collect();
    drop((b_of, tin));
    let mut candidate_place = node_of;
    for (p, &l) in candidate_place.iter_mut().zip(&label) {
        *p = if *p != NONE { NODE_FLAG | *p } else { l };
    }
    Ok(CandidateTree {
        nodes,
        arcs,
        candidate_place,
        join_side,
        split_side,
    })
}

/// A monotone stack entry: candidate number (high half), depth (low half),
/// so the binary search reads one contiguous array.
type StackEntry = u64;

/// An overwritten slot that was never there.
const EMPTY: u64 = u64::MAX;

/// What entering a candidate overwrote in each stack: (slot, old length,
/// old entry), restored when it is left.
#[derive(Clone, Copy)]
struct Saved {
    inc: (u32, u32, StackEntry),
    dec: (u32, u32, StackEntry),
}

/// Entering candidate `x` (the last of `path`) in the depth-first pass:
/// A(x) and B(x) from the monotone stacks, then x pushed on both.
fn enter(
    x: u32,
    path: &[u32],
    (inc, inc_len): (&mut Vec<StackEntry>, &mut usize),
    (dec, dec_len): (&mut Vec<StackEntry>, &mut usize),
    saved: &mut Vec<Saved>,
    (a_of, b_of): (&mut [u32], &mut [u32]),
) {
    let d = (path.len() - 1) as u32;
    let kid = |e: StackEntry| (e >> 32) as u32;
    let depth = |e: StackEntry| e as u32 as usize;
    // Deepest ancestor lower than x: the stack's candidates increase with
    // depth, so those lower than x are a prefix. The parent is on top of
    // both stacks, so one of the two searches is over at once.
    let live = &inc[..*inc_len];
    let p = if live.last().is_some_and(|&e| kid(e) < x) {
        live.len()
    } else {
        live.partition_point(|&e| kid(e) < x)
    };
    if p > 0 {
        a_of[x as usize] = path[depth(inc[p - 1]) + 1];
    }
    let live = &dec[..*dec_len];
    let q = if live.last().is_some_and(|&e| kid(e) > x) {
        live.len()
    } else {
        live.partition_point(|&e| kid(e) > x)
    };
    if q > 0 {
        b_of[x as usize] = path[depth(dec[q - 1]) + 1];
    }
    // The slots overwritten, even past the live length: they may hold
    // live entries of an ancestor's stack, restored when x is left.
    let entry = ((x as u64) << 32) | d as u64;
    saved.push(Saved {
        inc: (
            p as u32,
            *inc_len as u32,
            inc.get(p).copied().unwrap_or(EMPTY),
        ),
        dec: (
            q as u32,
            *dec_len as u32,
            dec.get(q).copied().unwrap_or(EMPTY),
        ),
    });
    if p == inc.len() {
        inc.push(entry);
    } else {
        inc[p] = entry;
    }
    *inc_len = p + 1;
    if q == dec.len() {
        dec.push(entry);
    } else {
        dec[q] = entry;
    }
    *dec_len = q + 1;
}

/// The nearest ancestor of `start` (inclusive) not yet cut, compressing the
/// path to it.
#[inline]
fn live_parent(tree_parent: &mut [u32], cut_to: &[u32], start: u32) -> u32 {
    let mut y = start;
    while cut_to[y as usize] != NONE {
        y = tree_parent[y as usize];
    }
    let mut c = start;
    while c != y {
        let next = tree_parent[c as usize];
        tree_parent[c as usize] = y;
        c = next;
    }
    y
}

/// Every vertex placed (see the module documentation): the supernodes,
/// the superarcs and each vertex's place, what [`group`] lays out.
pub struct Placed {
    nodes: Vec<Node>,
    arcs: Vec<Superarc>,
    vertex_arc: Vec<u32>,
}

/// Places every vertex (see the module documentation). `join_leafward`
/// and `split_leafward` are the sweeps' per-vertex records; the first
/// becomes the tree's `vertex_arc`. Needs no vertex order: a build that
/// let the order go makes it again only after this, when the second
/// record and the candidates' tables are gone.
pub fn place(tree: CandidateTree, mut join_leafward: Vec<u32>, split_leafward: Vec<u32>) -> Placed {
    let CandidateTree {
        nodes,
        arcs,
        candidate_place,
        join_side,
        split_side,
    } = tree;
    join_leafward
        .par_chunks_mut(1 << 14)
        .zip(split_leafward.par_chunks(1 << 14))
        .for_each(|(js, ss)| {
            for (j, &s) in js.iter_mut().zip(ss) {
                *j = if *j & CANDIDATE != 0 {
                    candidate_place[(*j & !CANDIDATE) as usize]
                } else {
                    let [lo, hi, above_a] = join_side[*j as usize];
                    let [tb, above_b] = split_side[s as usize];
                    if lo <= tb && tb < hi {
                        above_b
                    } else {
                        above_a
                    }
                };
            }
        });
    Placed {
        nodes,
        arcs,
        vertex_arc: join_leafward,
    }
}

/// Lays out the regular vertices of each superarc in the vertex `order`
/// and assembles the tree.
pub fn group(placed: Placed, order: &[u32]) -> ContourTree {
    let Placed {
        nodes,
        arcs,
        vertex_arc,
    } = placed;
    let (offsets, arc_vertices) = group_by_arc(&vertex_arc, arcs.len(), order);
    ContourTree::assemble(nodes, arcs, vertex_arc, offsets, arc_vertices)
}

/// The regular vertices of each superarc in the vertex order: stable
/// grouping of `order` by superarc. With few superarcs (smooth fields) the
/// order is cut into chunks, each counted and placed by its own thread
/// (slots of chunk `i` for an arc follow those of chunks before it);
/// otherwise one pass, since per-chunk counts would outweigh the vertices.
fn group_by_arc(vertex_arc: &[u32], arcs: usize, order: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let is_node = |va: u32| va & NODE_FLAG != 0;
    let threads = rayon::current_num_threads();
    let chunks = if threads > 1 && arcs * threads * 4 <= order.len() / 16 {
        threads * 4
    } else {
        1
    };
    let chunk_len = order.len().div_ceil(chunks).max(1);
    const AHEAD: usize = 16;
    let mut counts: Vec<Vec<u32>> = order
        .par_chunks(chunk_len)
        .map(|c| {
            let mut count = vec![0u32; arcs];
            for (i, &v) in c.iter().enumerate() {
                if let Some(&w) = c.get(i + AHEAD) {
                    prefetch(vertex_arc, w as usize);
                }
                let va = vertex_arc[v as usize];
                if !is_node(va) {
                    count[va as usize] += 1;
                }
            }
            count
        })
        .collect();
    let mut offsets = vec![0u32; arcs + 1];
    let mut total = 0u32;
    for a in 0..arcs {
        offsets[a] = total;
        for c in counts.iter_mut() {
            let here = c[a];
            c[a] = total;
            total += here;
        }
    }
    offsets[arcs] = total;
    let mut arc_vertices = crate::pages::filled(total as usize, 0u32);
    let dst = SharedSlots(arc_vertices.as_mut_ptr());
    order
        .par_chunks(chunk_len)
        .zip(counts.into_par_iter())
        .for_each(|(c, mut fill)| {
            let dst = &dst;
            for (i, &v) in c.iter().enumerate() {
                if let Some(&w) = c.get(i + AHEAD) {
                    prefetch(vertex_arc, w as usize);
                }
                let va = vertex_arc[v as usize];
                if !is_node(va) {
                    let slot = &mut fill[va as usize];
                    // SAFETY: each (chunk, arc) owns a disjoint range of
                    // slots below `total` (the prefix sums above), and
                    // writes each slot once.
                    unsafe { *dst.0.add(*slot as usize) = v };
                    *slot += 1;
                }
            }
        });
    (offsets, arc_vertices)
}

/// `arc_vertices` written from several threads at disjoint slots.
struct SharedSlots(*mut u32);
// SAFETY: only used for writes to disjoint slots (see `group_by_arc`).
unsafe impl Sync for SharedSlots {}
