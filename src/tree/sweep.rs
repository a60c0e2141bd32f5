//! Join and split trees by union-find sweeps (Carr, Snoeyink, Axen, Fig. 6).
//!
//! The join tree sweep visits vertices from the highest down; each vertex
//! starts a component of the superlevel set and absorbs the components of
//! its already-visited (higher) neighbours. The split tree sweep is the same
//! sweep from the lowest up. Both produce the *augmented* tree as a parent
//! array: `parent[w] = v` when the component whose lowest vertex was `w`
//! (the last vertex added to it) is absorbed by `v`, which is exactly the
//! arc (w, v) of the augmented join tree.
//!
//! The union-find is by rank with path halving; a root's own word holds the
//! component's most recently added vertex, so no separate "lowest vertex"
//! array is needed. Memory per sweep: 4 bytes per vertex of union-find, 1 of
//! rank, 4 of parent, 1 of degree.

use crate::field::VertexOrder;
use crate::mesh::{LINK_EMPTY, LINK_SEVERAL, Mesh};
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;

/// No vertex.
pub const NONE: u32 = u32::MAX;

/// A sweep tree (join or split) in augmented form.
pub struct SweepTree {
    /// The next vertex towards the root (the global minimum for the join
    /// tree, the global maximum for the split tree); `NONE` at the root.
    pub parent: Vec<u32>,
    /// Number of children: components of the superlevel (join) or sublevel
    /// (split) set that the vertex touches. 0 at leaves, >= 2 at saddles.
    pub children: Vec<u8>,
}

/// Marks a union-find root; the rest of a root's word is the component's
/// most recently added vertex (its lowest in the join sweep).
const ROOT: u32 = 1 << 31;

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
) -> Result<SweepTree, Cancelled> {
    let n = mesh.num_vertices();
    // uf[x]: NONE before x is visited; ROOT | last vertex at a root;
    // otherwise the parent in the union-find forest.
    let mut uf = vec![NONE; n];
    let mut rank = vec![0u8; n];
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
            if i + 2 * AHEAD < n {
                let w2 = at(i + 2 * AHEAD) as usize;
                prefetch(link_codes, w2);
            }
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
            if root == v {
                // v is still a singleton: hang it under r. Its rank is 0, so
                // r's rank stays a valid bound on height without reading it.
                uf[v as usize] = r;
                uf[r as usize] = ROOT | v;
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
            uf[hi as usize] = ROOT | v;
            root = hi;
        }
        children[v as usize] = merged;
    }
    Ok(SweepTree { parent, children })
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
fn prefetch<T>(data: &[T], i: usize) {
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
