//! Painting (§6): the join tree restricted to a set of critical vertices,
//! computed without sorting them.
//!
//! Every maximum spills its own colour down the mesh edges, each vertex
//! taking the colour of one of its upper neighbours, so that an edge's
//! colour is its upper end's colour, a colour per vertex is the whole
//! painting, and a vertex is *touched* by the colours of its upper
//! neighbours. The paper paints by a descending search from the maxima
//! (the first edge to reach a vertex gives its colour); what painting
//! relies on is only that each vertex's colour is a maximum that reaches it
//! by a descending path through vertices of that colour. We get that
//! without a search: each vertex climbs to its upper neighbour nearest in
//! id until a painted vertex, and the chain takes that colour; the climbs
//! run in id order on all cores (a breadth-first search from all maxima at
//! once visited the volume in wavefront order, a cache miss per vertex, and
//! cost brainweb_t1's painting half its time). The split tree's painting
//! (descents along the lower neighbour nearest in id) is also what
//! locating needs of every vertex: the minimum it descends to.
//!
//! Each critical vertex that is not a maximum goes into the heap T(c) of
//! one colour per component of its upper link (one per up-star). A vertex
//! is *ripe* when it is the highest vertex of the heap of every colour that
//! touches it (Definition 25); `update` finds one by climbing from heap top
//! to heap top on a stack of increasing heights (Corollary 28), and `build`
//! processes it: it becomes the join-tree parent of the attachment vertex
//! att(c) of each of its colours, leaves their heaps, the heaps are melded
//! and the colours united, and it becomes the attachment of the union
//! (Claim 30). Values are compared only inside the heaps: between vertices
//! on one descending path of the tree, never two unrelated maxima.
//!
//! Generalisation beyond the paper: it assumes the degree of a vertex in
//! the tree equals the number of its up-stars. In 3D (and around holes in
//! 2D) two components of a vertex's upper link can belong to one component
//! of the superlevel set; the vertex is then put in one heap per link
//! component, may meet itself in a melded heap (all its copies are on top
//! when it is ripe, and all are removed), and its degree is the number of
//! distinct colour classes that touch it, which counts the components of
//! the superlevel set, as the join tree's definition does.
//!
//! The heap entries of one colour lie together in memory (counted, then
//! placed), and hold the key (value) of their vertex, so that a heap's
//! comparisons read no field values ([`super::count::CountingOrder`]).
//!
//! Memory: 4 bytes per vertex of paint (returned: the split tree's is kept
//! for locating), 8 bytes per heap entry for values of up to 4 bytes, 33
//! per colour (its run heap's node, class root and top, union-find).

use super::count::CountingOrder;
use super::heap::{self, RunHeaps};
use crate::mesh::FreudenthalGrid;
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// No vertex / no critical vertex.
pub const NONE: u32 = u32::MAX;

/// The join tree (or, under the inverted order, the split tree) restricted
/// to the critical vertices, indexed by critical index.
pub struct CriticalTree {
    /// Critical index of the next critical vertex towards the root; `NONE`
    /// at the root (the global minimum of the orientation).
    pub parent: Vec<u32>,
    /// Number of children: components of the superlevel set that touch the
    /// vertex (0 at maxima).
    pub children: Vec<u32>,
    /// The painting: per vertex, its colour (an index into `maxima`).
    pub paint: Vec<u32>,
    /// Per colour, the critical index of its maximum.
    pub maxima: Vec<u32>,
}

/// What painting sees of the mesh, in one orientation.
pub struct Orientation<'a> {
    /// The grid.
    pub grid: &'a FreudenthalGrid,
    /// Linear id offset of each direction of the grid.
    pub offsets: &'a [i64],
    /// Per vertex, bit mask over the directions of its upper neighbours.
    pub upper: &'a [u16],
    /// Per vertex, bit mask of its lower neighbours.
    pub lower: &'a [u16],
    /// The critical vertices (a superset of the tree's nodes).
    pub critical: &'a [u32],
    /// Per vertex: its critical index, or `NONE`.
    pub slot: &'a [u32],
    /// Per bit mask of directions, the direction of the neighbour nearest
    /// in id among those the mask holds (0 for the empty mask).
    pub nearest: &'a [u8],
}

#[inline(always)]
fn step(v: u32, offsets: &[i64], k: u32) -> u32 {
    (v as i64 + offsets[k as usize]) as u32
}

/// Root of colour `c`'s class, halving the path.
#[inline]
fn find(uf: &mut [u32], mut c: u32) -> u32 {
    while uf[c as usize] != c {
        let p = uf[c as usize];
        uf[c as usize] = uf[p as usize];
        c = uf[c as usize];
    }
    c
}

/// Paints the mesh and builds the critical join tree in the orientation
/// `order` (the field's own order for the join tree, [`super::count::Inverted`]
/// for the split tree).
pub fn critical_join_tree<O: CountingOrder + ?Sized>(
    m: &Orientation<'_>,
    order: &O,
    progress: &Progress,
) -> Result<CriticalTree, Cancelled> {
    let n = m.upper.len();
    let t = m.critical.len();
    const CHECK_EVERY: usize = 1 << 20;

    // init 1: the initial painting, one colour per maximum. Every other
    // vertex takes the colour of one upper neighbour (the nearest in id):
    // following those choices climbs strictly to a maximum, so each colour
    // is a maximum reachable from the vertex by a descending path and its
    // vertices are connected through the edges chosen, which is all that
    // the paper's descending search guarantees and all that painting uses.
    // (A breadth-first search from all maxima at once did the same but
    // visited the volume in wavefront order, a cache miss per vertex; the
    // climb runs in id order on all cores, each chain stored once.)
    let mut att: Vec<u32> = Vec::new();
    let paint_a: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(NONE)).collect();
    for (i, &v) in m.critical.iter().enumerate() {
        if m.upper[v as usize] == 0 {
            paint_a[v as usize].store(att.len() as u32, Relaxed);
            att.push(i as u32);
        }
    }
    let maxima = att.clone();
    const PAINT_CHUNK: usize = 1 << 14;
    (0..n.div_ceil(PAINT_CHUNK))
        .into_par_iter()
        .try_for_each_init(Vec::new, |chain: &mut Vec<u32>, c| {
            if (c * PAINT_CHUNK).is_multiple_of(CHECK_EVERY) {
                progress.check(c * PAINT_CHUNK, 2 * n)?;
            }
            let end = ((c + 1) * PAINT_CHUNK).min(n);
            for v in (c * PAINT_CHUNK) as u32..end as u32 {
                if paint_a[v as usize].load(Relaxed) != NONE {
                    continue;
                }
                // Unpainted vertices are not maxima: each climbs.
                let mut x = v;
                let col = loop {
                    let p = paint_a[x as usize].load(Relaxed);
                    if p != NONE {
                        break p;
                    }
                    chain.push(x);
                    x = step(x, m.offsets, m.nearest[m.upper[x as usize] as usize] as u32);
                };
                for &y in chain.iter() {
                    paint_a[y as usize].store(col, Relaxed);
                }
                chain.clear();
            }
            Ok::<(), Cancelled>(())
        })?;
    let paint: Vec<u32> = paint_a.into_iter().map(AtomicU32::into_inner).collect();
    let colours = att.len();

    // init 4-5: every non-maximal critical vertex into the heap of one
    // colour of each up-star; rep(c) = c, att(c) = its maximum.
    // Per colour class: its heap's root entry and the item on top (`NONE`
    // when empty), side by side, so that asking a class for its highest
    // vertex, which `update` does for every colour of every vertex it
    // visits, is one cache line and no visit to the heap's arena.
    let mut root = vec![[heap::NONE, NONE]; colours];
    let mut uf: Vec<u32> = (0..colours as u32).collect();
    let mut rank = vec![0u8; colours];
    let mut processed = vec![false; t];
    let mut remaining = 0usize;
    // col(v) of every critical vertex, distinct initial colours, kept
    // beside it so that the loop below reads one short row per vertex
    // instead of the paint of all its upper neighbours.
    let mut col_off = vec![0u32; t + 1];
    let mut cols: Vec<u32> = Vec::with_capacity(2 * t);
    for (i, &v) in m.critical.iter().enumerate() {
        let start = cols.len();
        let mut up = m.upper[v as usize] as u32;
        while up != 0 {
            let c = paint[step(v, m.offsets, up.trailing_zeros()) as usize];
            up &= up - 1;
            if !cols[start..].contains(&c) {
                cols.push(c);
            }
        }
        col_off[i + 1] = cols.len() as u32;
    }
    // The entries of each colour's heap, counted, then placed together in
    // critical order and sorted from the top: the heaps are heaps of these
    // runs ([`RunHeaps`]), one node per colour.
    let mut start = vec![0u32; colours + 1];
    for &v in m.critical {
        let up = m.upper[v as usize] as u32;
        m.grid.link_components(up, |k| {
            let c = paint[step(v, m.offsets, k as u32) as usize] as usize;
            start[c + 1] += 1;
        });
    }
    for c in 0..colours {
        start[c + 1] += start[c];
    }
    let blank = order.key(m.critical.first().copied().unwrap_or(0));
    let mut entries = vec![(blank, NONE); start[colours] as usize];
    let mut fill = start.clone();
    for (i, &v) in m.critical.iter().enumerate() {
        let up = m.upper[v as usize] as u32;
        if up == 0 {
            processed[i] = true;
            continue;
        }
        remaining += 1;
        let key = order.key(v);
        m.grid.link_components(up, |k| {
            let c = paint[step(v, m.offsets, k as u32) as usize] as usize;
            entries[fill[c] as usize] = (key, i as u32);
            fill[c] += 1;
        });
    }
    drop(fill);
    let mut heaps = RunHeaps::new(entries, &start, order);
    for (c, r) in root.iter_mut().enumerate() {
        let h = heaps.run(c as u32);
        *r = [h, heaps.top(h).unwrap_or(NONE)];
    }
    drop(start);

    let mut parent = vec![NONE; t];
    let mut children = vec![0u32; t];
    let mut stack: Vec<u32> = Vec::new();
    let mut cursor = 0usize;
    let mut cur: Vec<u32> = Vec::with_capacity(16);
    let mut done = 0usize;
    while remaining > 0 {
        done += 1;
        if done.is_multiple_of(CHECK_EVERY / 16) {
            progress.check(n + done * n / t.max(1), 2 * n)?;
        }
        // update(K): climb to a ripe vertex. The stack and the heaps name
        // critical vertices by their index.
        if stack.is_empty() {
            while processed[cursor] {
                cursor += 1;
            }
            stack.push(cursor as u32);
        }
        let hs = loop {
            let h = *stack.last().unwrap_or(&NONE);
            if processed[h as usize] {
                // Pushed twice and already processed from the top.
                stack.pop();
                if stack.is_empty() {
                    break NONE;
                }
                continue;
            }
            // The classes of h's colours, kept in `cur` for build when h
            // turns out ripe.
            let mut blocker = NONE;
            cur.clear();
            for &c in &cols[col_off[h as usize] as usize..col_off[h as usize + 1] as usize] {
                let r = find(&mut uf, c);
                let top = root[r as usize][1];
                if top != NONE && top != h {
                    blocker = top;
                    break;
                }
                if !cur.contains(&r) {
                    cur.push(r);
                }
            }
            if blocker == NONE {
                break h;
            }
            stack.push(blocker);
        };
        if hs == NONE {
            continue;
        }
        stack.pop();
        // build 2b-f: process the ripe vertex (its classes are in `cur`).
        let mut melded = heap::NONE;
        for &r in &cur {
            parent[att[r as usize] as usize] = hs;
            let mut hr = root[r as usize][0];
            while heaps.top(hr) == Some(hs) {
                hr = heaps.pop(hr, order);
            }
            root[r as usize] = [heap::NONE, NONE];
            melded = heaps.meld(melded, hr, order);
        }
        // Union by rank: the representative is the class of highest rank.
        let mut c = cur[0];
        for &r in &cur[1..] {
            if rank[r as usize] > rank[c as usize] {
                c = r;
            }
        }
        for &r in &cur {
            if r != c {
                if rank[r as usize] == rank[c as usize] {
                    rank[c as usize] += 1;
                }
                uf[r as usize] = c;
            }
        }
        root[c as usize] = [melded, heaps.top(melded).unwrap_or(NONE)];
        att[c as usize] = hs;
        children[hs as usize] = cur.len() as u32;
        processed[hs as usize] = true;
        remaining -= 1;
    }
    Ok(CriticalTree {
        parent,
        children,
        paint,
        maxima,
    })
}
