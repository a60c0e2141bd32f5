//! The join tree and the split tree by union-find sweeps (Carr, Snoeyink,
//! Axen, Alg. 4.1, Fig. 6), restricted to their *candidate nodes* (§4.4).
//!
//! The join sweep visits vertices from the highest down; each vertex starts
//! a component of the superlevel set and absorbs the components of its
//! already-visited (higher) neighbours. The split sweep is the same sweep
//! from the lowest up.
//!
//! **Candidate nodes.** A vertex whose upper link and lower link are each
//! one connected, non-empty piece ([`Mesh::link_code`]) is regular in both
//! trees: one component above it, one below. Every other vertex (extrema,
//! every saddle, and vertices whose link is not summarised) is a
//! *candidate*: the supernodes of the contour tree are among them. The
//! sweeps record the two trees on the candidates only, as §4.4 of the paper
//! suggests ("instead of adding an edge to the join tree at every vertex,
//! we do so only at joins"), here at every candidate: an edge runs from
//! the last candidate added to a component to the candidate that absorbs
//! it. A union-find root's word holds the component's last candidate, so
//! no other per-vertex state is needed.
//!
//! For a vertex that is not a candidate the sweep records one number, its
//! *leafward candidate*: the last candidate of the one component it joins,
//! which is the lowest candidate of its superlevel component in the join
//! tree (the highest of its sublevel component in the split tree). The
//! merge ([`super::merge`]) places every such vertex on its superarc from
//! these two numbers alone. The same word is where the sweep finds the
//! vertex's component, so the union-find itself lives on the candidates.
//!
//! Candidates are numbered in the vertex order (`0` = global minimum), so
//! comparing two candidate numbers compares heights.
//!
//! **Memory per vertex** while sweeping: 4 bytes (its word: candidate
//! number or leafward candidate); per candidate 10 bytes (union-find,
//! rank, parent, children), and 4 more in the split sweep (its vertex).

use crate::field::VertexOrder;
use crate::mesh::{LINK_EMPTY, LINK_SEVERAL, Mesh};
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;

/// No vertex.
pub const NONE: u32 = u32::MAX;

/// Marks, in [`JoinTree::leafward`] / [`SplitTree::leafward`], a vertex that
/// is itself a candidate; the rest of the word is its candidate number.
pub const CANDIDATE: u32 = 1 << 31;

/// A sweep tree on the candidate nodes: what the join and split trees have
/// in common.
#[derive(Clone, Debug)]
pub struct SweepTree {
    /// Per candidate: its parent candidate (towards the global minimum in
    /// the join tree, the global maximum in the split tree); `NONE` at the
    /// root.
    pub parent: Vec<u32>,
    /// Per candidate: its number of children, the components of the
    /// superlevel (join) or sublevel (split) set it touches: 0 at a leaf,
    /// >= 2 at a saddle.
    pub children: Vec<u8>,
    /// Per vertex: `CANDIDATE | c` for candidate `c`; otherwise its
    /// leafward candidate (see the module documentation).
    pub leafward: Vec<u32>,
    /// Per candidate: its vertex (empty in the join tree: the split tree
    /// lists them).
    pub vertex: Vec<u32>,
}

/// The join tree (Carr et al. Def. 4.1): how the components of the
/// superlevel sets join as the level goes down, on the candidate nodes.
#[derive(Clone, Debug)]
pub struct JoinTree(pub SweepTree);

/// The split tree: how the components of the sublevel sets split as the
/// level goes down (join as it goes up), on the candidate nodes.
#[derive(Clone, Debug)]
pub struct SplitTree(pub SweepTree);

/// True when a vertex with this [`Mesh::link_code`] is a candidate node:
/// unless its upper and lower links are both one non-empty piece.
#[inline(always)]
pub fn is_candidate(code: u8) -> bool {
    (code & 0xf) >= LINK_EMPTY || (code >> 4) >= LINK_EMPTY
}

/// The candidates of a mesh, from its link codes: their number.
pub fn count_candidates(link_codes: &[u8]) -> usize {
    link_codes
        .par_chunks(1 << 16)
        .map(|c| c.iter().filter(|&&x| is_candidate(x)).count())
        .sum()
}

/// Marks a union-find root; the rest of a root's word is the component's
/// last candidate.
const ROOT: u32 = 1 << 31;

/// The join tree: sweeps `order` (ascending) from its end.
pub fn join_tree<M: Mesh, O: VertexOrder + ?Sized>(
    mesh: &M,
    values: &O,
    link_codes: &[u8],
    candidates: usize,
    order: &[u32],
    progress: &Progress,
) -> Result<JoinTree, Cancelled> {
    sweep(mesh, values, link_codes, candidates, true, order, progress).map(JoinTree)
}

/// The split tree: sweeps `order` (ascending) from its start.
pub fn split_tree<M: Mesh, O: VertexOrder + ?Sized>(
    mesh: &M,
    values: &O,
    link_codes: &[u8],
    candidates: usize,
    order: &[u32],
    progress: &Progress,
) -> Result<SplitTree, Cancelled> {
    sweep(mesh, values, link_codes, candidates, false, order, progress).map(SplitTree)
}

/// One sweep (descending for the join tree, ascending for the split tree).
/// `values` gives the vertex order; testing "already swept" on it rather
/// than on the union-find keeps the hot loop in the compact value array.
///
/// The union-find is over the candidates only: a vertex's one word is
/// `CANDIDATE | c` for candidate `c`, otherwise its leafward candidate,
/// which is in its component, so `find` starts there. A vertex that is not
/// a candidate is never a union-find node: it costs one read of a
/// neighbour's word, a `find` in the (on smooth fields, cache-sized)
/// candidate forest and one write.
fn sweep<M: Mesh, O: VertexOrder + ?Sized>(
    mesh: &M,
    values: &O,
    link_codes: &[u8],
    candidates: usize,
    join: bool,
    order: &[u32],
    progress: &Progress,
) -> Result<SweepTree, Cancelled> {
    let n = mesh.num_vertices();
    let mut leafward = vec![NONE; n];
    // uf[c]: ROOT | last candidate of the component at a root, otherwise
    // the parent in the union-find forest.
    let mut uf = vec![NONE; candidates];
    let mut rank = vec![0u8; candidates];
    let mut parent = vec![NONE; candidates];
    let mut children = vec![0u8; candidates];
    // Only the split sweep lists the candidates' vertices (they are the
    // same for both).
    let mut vertex = vec![0u32; if join { 0 } else { candidates }];
    let mut reps: Vec<u32> = Vec::with_capacity(16);
    // The candidate number of the next candidate visited.
    let mut next: u32 = if join { candidates as u32 } else { 0 };
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
            // A vertex that is not a candidate reads one neighbour's word
            // and writes its own: two lines, not its whole star. Its code
            // was prefetched AHEAD vertices ago.
            let w = at(i + AHEAD);
            let cw = link_codes[w as usize];
            if is_candidate(cw) {
                mesh.prefetch_star(w, &leafward);
            } else {
                let c = if join { cw & 0xf } else { cw >> 4 };
                prefetch(&leafward, mesh.neighbour_at(w, c) as usize);
                prefetch(&leafward, w as usize);
            }
            if i + 2 * AHEAD < n {
                let w2 = at(i + 2 * AHEAD) as usize;
                prefetch(link_codes, w2);
            }
        }
        let full = link_codes[v as usize];
        let code = if join { full & 0xf } else { full >> 4 };
        if !is_candidate(full) {
            // One component beyond v, reached through one neighbour: v
            // remembers its last candidate. Nothing else.
            let u = mesh.neighbour_at(v, code);
            let r = find(&mut uf, leafward[u as usize] & !CANDIDATE);
            leafward[v as usize] = uf[r as usize] & !ROOT;
            continue;
        }
        let kid = if join {
            next -= 1;
            next
        } else {
            next += 1;
            next - 1
        };
        leafward[v as usize] = CANDIDATE | kid;
        if !join {
            vertex[kid as usize] = v;
        }
        let mut root = kid;
        uf[kid as usize] = ROOT | kid;
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
            let r = find(&mut uf, leafward[u as usize] & !CANDIDATE);
            if r == root {
                continue;
            }
            // Component r is absorbed at v: the tree edge runs from its
            // last candidate to v.
            let last = uf[r as usize] & !ROOT;
            parent[last as usize] = kid;
            merged += 1;
            if root == kid {
                // v is still a singleton: hang it under r. Its rank is 0, so
                // r's rank stays a valid bound on height without reading it.
                uf[kid as usize] = r;
                uf[r as usize] = ROOT | kid;
                root = r;
                continue;
            }
            let (hi, lo) = if rank[r as usize] > rank[root as usize] {
                (r, root)
            } else {
                (root, r)
            };
            if rank[hi as usize] == rank[lo as usize] {
                rank[hi as usize] += 1;
            }
            uf[lo as usize] = hi;
            uf[hi as usize] = ROOT | kid;
            root = hi;
        }
        children[kid as usize] = merged;
    }
    debug_assert_eq!(next, if join { 0 } else { candidates as u32 });
    Ok(SweepTree {
        parent,
        children,
        leafward,
        vertex,
    })
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

#[inline(always)]
pub(crate) fn prefetch<T>(data: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if i < data.len() {
        // SAFETY: a prefetch never faults; the address is inside `data`.
        unsafe {
            std::arch::x86_64::_mm_prefetch(
                data.as_ptr().add(i) as *const i8,
                std::arch::x86_64::_MM_HINT_T0,
            )
        };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (data, i);
}

/// Summaries of every vertex's upper link (low nibble) and lower link (high
/// nibble), see [`Mesh::link_code`]. Computed in id order, where the stars
/// of consecutive vertices overlap in cache, and in parallel; the sweeps,
/// which visit vertices in value order, then read one byte per vertex
/// instead of the values of all its neighbours.
pub fn link_codes<M: Mesh, O: VertexOrder + ?Sized>(mesh: &M, values: &O) -> Vec<u8> {
    let n = mesh.num_vertices();
    let mut codes = vec![0u8; n];
    codes
        .par_chunks_mut(1 << 16)
        .enumerate()
        .for_each(|(c, chunk)| {
            mesh.link_codes_into(values, (c << 16) as u32, chunk);
        });
    codes
}
