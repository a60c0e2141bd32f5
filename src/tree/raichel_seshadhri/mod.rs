//! The contour tree without the global sort (Raichel, Seshadhri: "Avoiding
//! the global sort: a faster contour tree algorithm", SoCG 2016).
//!
//! Every other engine, ours included ([`ContourTree::build`]), starts by
//! sorting all n vertices. This one never does: it compares values only
//! between vertices adjacent in the mesh, or on one monotone path of the
//! tree, and produces the *same* augmented [`ContourTree`] (same supernodes,
//! superarcs, superarc of every vertex, regular vertices of each arc in
//! value order).
//!
//! # Pipeline
//! 1. **Links** (§2, Definition 7). Each mesh edge is compared once
//!    (7 comparisons per vertex in 3D): a 14-bit mask per vertex of its
//!    upper neighbours, the rest of its link being the lower ones. The
//!    grid's link table ([`FreudenthalGrid::link_components`]) turns a mask
//!    into the components of the upper and lower link; a vertex is
//!    *critical* unless both are one component.
//! 2. **Painting** (§6, [`paint`]): the join tree restricted to the critical
//!    vertices from the maxima down, with mergeable heaps ([`heap`]), and
//!    the split tree the same way under the inverted order
//!    ([`count::Inverted`]); both at once on two threads. The colours are
//!    laid by climbs in id order, not by a search from the maxima (see
//!    [`paint`]); heap entries hold their vertex's key, so a heap compares
//!    without reading the field.
//! 3. **Merge** (Carr, Snoeyink, Axen §4, on the critical vertices only):
//!    leaf cutting is driven by the degrees alone and compares no values.
//!    Critical vertices whose superlevel and sublevel components turn out to
//!    be single (two link components that meet further away) are regular
//!    and are contracted into the superarcs.
//! 4. **Numbering**: [`ContourTree`] numbers its supernodes in the vertex
//!    order, so the t supernodes (not the n vertices) are sorted: t log t
//!    comparisons that the paper does not make and the data type asks for.
//! 5. **Locating** every regular vertex on its superarc. Climb from v to an
//!    upper neighbour, u. The mesh edge (v, u) maps to a monotone path of the
//!    tree, and the descent from v (following lower neighbours) to a minimum
//!    m' maps to a monotone path from v down to m'. So v's superarc lies on
//!    the tree path from u's place down towards m', and it is the first arc
//!    on that path whose lower end is below v. Vertices are placed after the
//!    neighbour they climb to (the lowest upper neighbour reachable along
//!    link edges, whose order step 1 already knows), so each starts from its
//!    upper neighbour's arc: one comparison when v lies on it, else a
//!    search along the rest of the path by Myers' jump pointers in the tree
//!    rooted at the global minimum (O(log depth) comparisons; a plain walk
//!    cost thousands per vertex at the foot of tooth's noisy trunk). Every
//!    comparison is with a supernode on v's own monotone path (an ancestor
//!    or descendant in the augmented tree). The way down at a node towards
//!    m' is chosen by Euler-tour intervals, without comparisons. The
//!    descents are the split tree's painting (its colour of v names m');
//!    the placing runs on all cores over chunks of ids: a vertex's superarc
//!    does not depend on the path that found it, so two threads meeting on
//!    a chain store the same value. What a search step reads of a node (its
//!    key, parent, jump pointer, depth, Euler interval) is one 32-byte
//!    record, and one climb from the start finds both the common ancestor
//!    with m' and the answer on that side.
//! 6. **Sorting each arc** by value: Σ k_a log k_a comparisons over arcs of
//!    k_a regular vertices. The paper computes the unaugmented tree and has
//!    no such term; it is the price of the augmented one.
//!
//! # What differs from the paper, and why
//! - **Raining and surgery (§3-§5) are replaced by the merge.** The paper
//!   cuts the mesh along contours into extremum-dominant pieces whose
//!   contour tree is their join tree (Theorem 21), so that painting's heaps
//!   only ever hold vertices of one monotone path of the *contour* tree.
//!   Cutting a face of the Freudenthal grid along a contour makes new
//!   vertices and faces that the implicit grid cannot hold, and the pieces
//!   would need their own explicit meshes. We paint the whole mesh twice,
//!   for the join and the split tree, and merge them; the merge compares no
//!   values, so the comparisons are those of painting the join tree and the
//!   split tree of the whole mesh. The bound of Lemma 33 then holds with the
//!   join and split trees' paths in place of the contour tree's: the same
//!   as the paper's when they are as short as the contour tree, larger
//!   when the join or split tree has a long tail where the contour tree is
//!   balanced (the paper's Figure 2), which is exactly what raining fixes.
//! - **Binomial heaps are heaps of sorted runs** ([`heap::RunHeaps`]): each
//!   colour's touched vertices, all known before the first meld, are
//!   sorted once (Σ k log2 k comparisons for k per colour, where a binomial
//!   heap is built in O(k)), and a heap is a pairing heap of runs keyed by
//!   their heads (delete-max: O(log r) amortised for r runs melded, plus
//!   one). Same operations and answers; the pointers chased live in one
//!   16-byte node per colour instead of one per entry, which took tooth's
//!   painting from 0.44 to 0.33 s.
//! - **The ripe-colour sublist L** (§6.1) is not kept; ripeness is checked
//!   by looking at every upper neighbour's colour again (at most 14 union-
//!   find lookups, no comparisons).
//! - **Augmentation** (steps 4-6) is ours: the paper stops at supernodes and
//!   superarcs.
//!
//! # Memory per vertex
//! 4 bytes of masks, 4 of critical index, 4 of place (the tree's
//! `vertex_arc`), and the paint of both orientations (4 bytes each; the
//! split tree's is kept as the descent minimum until locating ends): about
//! 20 bytes at the peak, plus O(t) for the critical vertices (colours, heap
//! entries of 8 bytes and a 16-byte node per colour, node records of 32).

pub mod count;
pub mod families;
pub mod heap;
pub mod paint;

use super::merge::{NODE_FLAG, climb};
use super::{ContourTree, DEGREE_FITS, Node, NodeId, Superarc};
use crate::field::ScalarField;
use crate::mesh::{FreudenthalGrid, Mesh};
use crate::progress::{Cancelled, Progress};
use count::{Counted, CountingOrder, Inverted};
use paint::{CriticalTree, NONE, Orientation};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Seconds per stage of [`build`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Times {
    /// Upper/lower masks and link classification.
    pub links: Duration,
    /// Painting the join tree (in parallel with the split tree).
    pub join: Duration,
    /// Painting the split tree.
    pub split: Duration,
    /// Both paintings, wall clock.
    pub paint: Duration,
    /// Merging the critical join and split trees, contracting superarcs.
    pub merge: Duration,
    /// Sorting the supernodes for their numbering.
    pub number: Duration,
    /// Locating every regular vertex on its superarc.
    pub locate: Duration,
    /// Sorting the regular vertices of each superarc.
    pub arc_sort: Duration,
}

impl Times {
    /// Wall-clock total.
    pub fn total(&self) -> Duration {
        self.links + self.paint + self.merge + self.number + self.locate + self.arc_sort
    }
}

/// Value comparisons per stage of [`build`] (all zero unless the order
/// counts, see [`count::Counted`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Comparisons {
    /// One per mesh edge.
    pub links: u64,
    /// Both paintings' heap operations.
    pub paint: u64,
    /// Sorting the supernodes.
    pub number: u64,
    /// Locating the regular vertices.
    pub locate: u64,
    /// Sorting each superarc's regular vertices.
    pub arc_sort: u64,
}

impl Comparisons {
    /// The contour tree itself (supernodes and superarcs): links and painting.
    pub fn tree(&self) -> u64 {
        self.links + self.paint
    }

    /// Everything, up to the augmented tree in our numbering.
    pub fn total(&self) -> u64 {
        self.links + self.paint + self.number + self.locate + self.arc_sort
    }
}

/// What [`build`] measured.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Time per stage.
    pub times: Times,
    /// Comparisons per stage.
    pub comparisons: Comparisons,
    /// Vertices whose link is critical (painting's nodes).
    pub critical: usize,
}

/// The contour tree of a grid field; with `count`, the comparisons too (at
/// the cost of an atomic add per comparison: time it without).
pub fn from_field(
    field: &ScalarField,
    count: bool,
    progress: &Progress,
) -> Result<(ContourTree, Stats), Cancelled> {
    let grid = field.mesh();
    crate::with_values!(field.values(), v => {
        if count {
            build(&grid, &Counted::new(v.as_slice()), progress)
        } else {
            build(&grid, v.as_slice(), progress)
        }
    })
}

#[inline(always)]
fn step(v: u32, offsets: &[i64], k: u32) -> u32 {
    (v as i64 + offsets[k as usize]) as u32
}

/// Builds the augmented contour tree of `values` on the Freudenthal grid
/// without sorting the vertices (see the module doc).
pub fn build<O: CountingOrder + ?Sized>(
    grid: &FreudenthalGrid,
    values: &O,
    progress: &Progress,
) -> Result<(ContourTree, Stats), Cancelled> {
    let n = grid.num_vertices();
    let mut stats = Stats::default();
    if n == 0 {
        return Ok((
            ContourTree::assemble(Vec::new(), Vec::new(), Vec::new(), vec![0], Vec::new()),
            stats,
        ));
    }
    let [sx, sy] = [1i64, grid.dims()[0] as i64];
    let sz = sy * grid.dims()[1] as i64;
    let offsets: Vec<i64> = grid
        .directions()
        .iter()
        .map(|d| d[0] * sx + d[1] * sy + d[2] * sz)
        .collect();
    let half = offsets.len() / 2;

    // 1. Links: each edge compared once, from its lower-id end (directions
    // come in pairs +o, -o; the even ones have positive offsets).
    progress.stage("links");
    let t0 = Instant::now();
    let c0 = values.comparisons();
    const CHUNK: usize = 1 << 16;
    // The 7 positive offsets of a 3D grid (directions 0, 2, .., 12).
    const INTERIOR: u32 = (1 << 14) - 1;
    let mut positive = [0i64; 7];
    if half == 7 {
        for (j, p) in positive.iter_mut().enumerate() {
            *p = offsets[2 * j];
        }
    }
    let mut pos = vec![0u8; n];
    pos.par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            for_each_present(grid, (c * CHUNK) as u32, chunk.len(), |i, v, present| {
                if present == INTERIOR && half == 7 {
                    // Inside a 3D grid: every edge, without a test each.
                    let mut bits = 0u8;
                    for (j, &o) in positive.iter().enumerate() {
                        bits |= (values.above((v as i64 + o) as u32, v) as u8) << j;
                    }
                    chunk[i] = bits;
                    return;
                }
                let mut bits = 0u8;
                for j in 0..half {
                    if present & (1 << (2 * j)) != 0
                        && values.above(step(v, &offsets, 2 * j as u32), v)
                    {
                        bits |= 1 << j;
                    }
                }
                chunk[i] = bits;
            });
        });
    let mut upper = vec![0u16; n];
    let mut lower = vec![0u16; n];
    // The masks, and per chunk its critical vertices (in id order).
    let critical_chunks: Vec<Vec<u32>> = upper
        .par_chunks_mut(CHUNK)
        .zip(lower.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(c, (up, low))| {
            let mut critical = Vec::new();
            for_each_present(grid, (c * CHUNK) as u32, up.len(), |i, v, present| {
                let mut u = 0u16;
                if present == INTERIOR && half == 7 {
                    let p = pos[v as usize] as u16;
                    for (j, &o) in positive.iter().enumerate() {
                        u |= ((p >> j) & 1) << (2 * j);
                        let w = pos[(v as i64 - o) as usize] as u16;
                        u |= (((w >> j) & 1) ^ 1) << (2 * j + 1);
                    }
                } else {
                    for j in 0..half {
                        if pos[v as usize] & (1 << j) != 0 {
                            u |= 1 << (2 * j);
                        }
                        let odd = 2 * j + 1;
                        if present & (1 << odd) != 0 {
                            let w = step(v, &offsets, odd as u32);
                            // w + o_j = v: v is above w unless w's bit says so.
                            if pos[w as usize] & (1 << j) == 0 {
                                u |= 1 << odd;
                            }
                        }
                    }
                }
                let l = present as u16 & !u;
                up[i] = u;
                low[i] = l;
                if grid.link_components(u as u32, |_| {}) != 1
                    || grid.link_components(l as u32, |_| {}) != 1
                {
                    critical.push(v);
                }
            });
            critical
        })
        .collect();
    drop(pos);
    let critical: Vec<u32> = critical_chunks.concat();
    drop(critical_chunks);
    let t = critical.len();
    let mut slot = vec![NONE; n];
    for (i, &v) in critical.iter().enumerate() {
        slot[v as usize] = i as u32;
    }
    stats.critical = t;
    stats.times.links = t0.elapsed();
    stats.comparisons.links = values.comparisons() - c0;

    // 2. Painting, join and split trees at once.
    progress.stage("painting");
    let t0 = Instant::now();
    // Painting climbs, and locating climbs and descends, to the neighbour
    // nearest in id among those the mask allows: on a plateau (equal values, ordered by id) that is the
    // next vertex in the order, so the edge spans few supernodes.
    let mut by_nearness: Vec<u32> = (0..offsets.len() as u32).collect();
    by_nearness.sort_by_key(|&k| offsets[k as usize].unsigned_abs());
    let nearest: Vec<u8> = (0..1u32 << offsets.len())
        .map(|mask| {
            by_nearness
                .iter()
                .find(|&&k| mask & (1 << k) != 0)
                .map_or(0, |&k| k as u8)
        })
        .collect();

    let c0 = values.comparisons();
    let join_side = Orientation {
        grid,
        offsets: &offsets,
        upper: &upper,
        lower: &lower,
        critical: &critical,
        slot: &slot,
        nearest: &nearest,
    };
    let split_side = Orientation {
        upper: &lower,
        lower: &upper,
        ..join_side
    };
    let inverted = Inverted(values);
    let (join, split) = rayon::join(
        || {
            let t = Instant::now();
            paint::critical_join_tree(&join_side, values, progress).map(|j| (j, t.elapsed()))
        },
        || {
            let t = Instant::now();
            paint::critical_join_tree(&split_side, &inverted, &Progress::new())
                .map(|s| (s, t.elapsed()))
        },
    );
    let ((mut join, tj), (mut split, ts)) = (join?, split?);
    drop(std::mem::take(&mut join.paint));
    // The split tree's painting descends from every vertex to a minimum
    // along the lower neighbour nearest in id: what locating needs.
    let min_colour = std::mem::take(&mut split.paint);
    let minima = std::mem::take(&mut split.maxima);
    progress.check(0, 1)?;
    stats.times.join = tj;
    stats.times.split = ts;
    stats.times.paint = t0.elapsed();
    stats.comparisons.paint = values.comparisons() - c0;

    // 3. Merge on the critical vertices, then contract.
    progress.stage("merge");
    let t0 = Instant::now();
    let (up_degree, down_degree) = (join.children.clone(), split.children.clone());
    let next = merge(join, split);
    // Tree adjacency over critical indices: up neighbours, then down.
    let mut adj_off = vec![0u32; t + 1];
    for i in 0..t {
        adj_off[i + 1] = adj_off[i] + up_degree[i] + down_degree[i];
    }
    let mut fill_up: Vec<u32> = adj_off[..t].to_vec();
    let mut fill_down: Vec<u32> = (0..t).map(|i| adj_off[i] + up_degree[i]).collect();
    let mut adj = vec![NONE; adj_off[t] as usize];
    for (x, &nx) in next.iter().enumerate() {
        if nx == NONE {
            continue;
        }
        let y = (nx & !ABOVE) as usize;
        let (hi, lo) = if nx & ABOVE != 0 { (x, y) } else { (y, x) };
        adj[fill_down[hi] as usize] = lo as u32;
        fill_down[hi] += 1;
        adj[fill_up[lo] as usize] = hi as u32;
        fill_up[lo] += 1;
    }
    drop((fill_up, fill_down, next));
    let is_node = |i: usize| up_degree[i] != 1 || down_degree[i] != 1;
    stats.times.merge = t0.elapsed();

    // 4. Number the supernodes in the vertex order.
    let t0 = Instant::now();
    let c0 = values.comparisons();
    let mut node_crit: Vec<u32> = (0..t as u32).filter(|&i| is_node(i as usize)).collect();
    node_crit
        .par_sort_unstable_by(|&a, &b| values.ordering(critical[a as usize], critical[b as usize]));
    let mut node_of = vec![NONE; t];
    let nodes: Vec<Node> = node_crit
        .iter()
        .enumerate()
        .map(|(id, &i)| {
            node_of[i as usize] = id as u32;
            Node {
                vertex: critical[i as usize],
                up: up_degree[i as usize].try_into().expect(DEGREE_FITS),
                down: down_degree[i as usize].try_into().expect(DEGREE_FITS),
            }
        })
        .collect();
    stats.times.number = t0.elapsed();
    stats.comparisons.number = values.comparisons() - c0;

    // Superarcs: from each node down every chain of contracted vertices.
    let t0 = Instant::now();
    let mut place = vec![NONE; n];
    for (id, node) in nodes.iter().enumerate() {
        place[node.vertex as usize] = NODE_FLAG | id as u32;
    }
    let mut arcs: Vec<Superarc> = Vec::new();
    for (id, &i) in node_crit.iter().enumerate() {
        let i = i as usize;
        let down = &adj[(adj_off[i] + up_degree[i]) as usize..adj_off[i + 1] as usize];
        for &q in down {
            let a = arcs.len() as u32;
            let mut q = q as usize;
            while !is_node(q) {
                place[critical[q] as usize] = a;
                // A contracted vertex has one down neighbour.
                q = adj[(adj_off[q] + up_degree[q]) as usize] as usize;
            }
            arcs.push(Superarc {
                upper: NodeId(id as u32),
                lower: NodeId(node_of[q]),
            });
        }
    }
    // The node of each minimum, by its colour in the split painting.
    let min_node: Vec<u32> = minima.iter().map(|&i| node_of[i as usize]).collect();
    drop((adj, adj_off, node_crit, node_of, minima));
    stats.times.merge += t0.elapsed();

    // 5. Locate the regular vertices.
    progress.stage("augment");
    let t0 = Instant::now();
    let c0 = values.comparisons();
    // link_step[k][j]: the direction from v + d_k to v + d_j when the two
    // are joined in v's link (d_j - d_k is a direction), else NO_STEP.
    const NO_STEP: u8 = u8::MAX;
    let dirs = grid.directions();
    let link_step: Vec<[u8; 16]> = dirs
        .iter()
        .map(|dk| {
            let mut row = [NO_STEP; 16];
            for (j, dj) in dirs.iter().enumerate() {
                let diff = [dj[0] - dk[0], dj[1] - dk[1], dj[2] - dk[2]];
                if let Some(e) = dirs.iter().position(|d| *d == diff) {
                    row[j] = e as u8;
                }
            }
            row
        })
        .collect();
    // The upper neighbour to climb to: from the nearest, down the link's
    // edges while a lower upper neighbour is joined to it. Those edges were
    // compared in step 1, so this compares nothing, and the edge climbed
    // spans few supernodes even at the foot of a cliff.
    let climb = |v: u32| -> u32 {
        let up = upper[v as usize] as u32;
        let mut cur = nearest[up as usize] as usize;
        'down: loop {
            let u = step(v, &offsets, cur as u32);
            let below_u = lower[u as usize] as u32;
            let mut cand = up & !(1 << cur);
            while cand != 0 {
                let j = cand.trailing_zeros() as usize;
                cand &= cand - 1;
                let e = link_step[cur][j];
                if e != NO_STEP && below_u & (1 << e) != 0 {
                    cur = j;
                    continue 'down;
                }
            }
            return u;
        }
    };
    let walk = SuperarcWalk::new(&nodes, &arcs, |v| values.key(v));
    // Both passes below run on all cores over chunks of ids. A vertex's
    // descent minimum and its superarc are facts of the field, not of the
    // path that reached them, so two threads that meet on one chain store
    // the same value: relaxed atomics suffice, and the result does not
    // depend on the schedule (only the comparison count may, by the few
    // vertices two threads place at once).
    use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
    const LOCATE_CHUNK: usize = 1 << 14;
    let chunks = n.div_ceil(LOCATE_CHUNK);
    // The minimum each vertex descends to, as a node id: the split
    // tree's painting (its colour of v) gives it.
    let min_of = |v: u32| min_node[min_colour[v as usize] as usize];
    let place_a: Vec<AtomicU32> = place.into_iter().map(AtomicU32::new).collect();
    (0..chunks)
        .into_par_iter()
        .try_for_each_init(Vec::new, |chain, c| {
            progress.check(c * LOCATE_CHUNK, n)?;
            let end = ((c + 1) * LOCATE_CHUNK).min(n);
            for v in (c * LOCATE_CHUNK) as u32..end as u32 {
                if place_a[v as usize].load(Relaxed) != NONE {
                    continue;
                }
                let mut x = v;
                let mut from = place_a[x as usize].load(Relaxed);
                while from == NONE {
                    chain.push(x);
                    x = climb(x);
                    from = place_a[x as usize].load(Relaxed);
                }
                while let Some(y) = chain.pop() {
                    let m = min_of(y);
                    let mut arc = if from & NODE_FLAG != 0 {
                        walk.down_towards(from & !NODE_FLAG, m)
                    } else {
                        from
                    };
                    // Most vertices lie on the first arc; past it, a search
                    // by jump pointers along the rest of the path (see
                    // SuperarcWalk).
                    // (Keys kept in the walk's records: no field reads but
                    // y's own.)
                    let ky = values.key(y);
                    let lower_end = arcs[arc as usize].lower.0;
                    let rl = &walk.rec[lower_end as usize];
                    if values.above_keys(rl.key, rl.vertex, ky, y) {
                        arc = walk.locate(lower_end, m, |k, x| values.above_keys(k, x, ky, y));
                    }
                    place_a[y as usize].store(arc, Relaxed);
                    from = arc;
                }
            }
            Ok::<(), Cancelled>(())
        })?;
    drop((min_colour, min_node));
    let place: Vec<u32> = place_a.into_iter().map(AtomicU32::into_inner).collect();
    stats.times.locate = t0.elapsed();
    stats.comparisons.locate = values.comparisons() - c0;

    // 6. The regular vertices of each arc, sorted by value.
    let t0 = Instant::now();
    let c0 = values.comparisons();
    let mut offsets_arc = vec![0u32; arcs.len() + 1];
    for &p in &place {
        if p & NODE_FLAG == 0 {
            offsets_arc[p as usize + 1] += 1;
        }
    }
    for a in 1..offsets_arc.len() {
        offsets_arc[a] += offsets_arc[a - 1];
    }
    let mut fill = offsets_arc.clone();
    let mut arc_vertices = vec![0u32; offsets_arc[arcs.len()] as usize];
    for (v, &p) in place.iter().enumerate() {
        if p & NODE_FLAG == 0 {
            arc_vertices[fill[p as usize] as usize] = v as u32;
            fill[p as usize] += 1;
        }
    }
    drop(fill);
    let mut slices: Vec<&mut [u32]> = Vec::with_capacity(arcs.len());
    let mut rest = arc_vertices.as_mut_slice();
    for a in 0..arcs.len() {
        let (s, r) = rest.split_at_mut((offsets_arc[a + 1] - offsets_arc[a]) as usize);
        slices.push(s);
        rest = r;
    }
    slices
        .into_par_iter()
        .for_each(|s| s.sort_unstable_by(|&a, &b| values.ordering(a, b)));
    stats.times.arc_sort = t0.elapsed();
    stats.comparisons.arc_sort = values.comparisons() - c0;
    let tree = ContourTree::assemble(nodes, arcs, place, offsets_arc, arc_vertices);
    Ok((tree, stats))
}

/// Calls `f(i, v, present)` for the vertices v = first + i, i < len, with
/// the mask of the directions present at v, computed from coordinates kept
/// up to date (not divided out per vertex) and all directions inside.
#[inline(always)]
fn for_each_present(
    grid: &FreudenthalGrid,
    first: u32,
    len: usize,
    mut f: impl FnMut(usize, u32, u32),
) {
    let [dx, dy, dz] = grid.dims().map(|d| d as u32);
    let inside = |c: u32, d: u32| d == 1 || (c > 0 && c + 1 < d);
    let all = (1u32 << grid.directions().len()) - 1;
    let [mut x, mut y, mut z] = grid.coords(first);
    let mut row_inside = inside(y, dy) && inside(z, dz);
    for i in 0..len {
        let v = first + i as u32;
        let present = if row_inside && inside(x, dx) {
            all
        } else {
            grid.present_directions(v)
        };
        f(i, v, present);
        x += 1;
        if x == dx {
            x = 0;
            y += 1;
            if y == dy {
                y = 0;
                z += 1;
            }
            row_inside = inside(y, dy) && inside(z, dz);
        }
    }
}

/// Marks `next[x]` when x lies above its neighbour.
const ABOVE: u32 = 1 << 31;

/// Carr, Snoeyink, Axen's leaf cutting on the critical join and split
/// trees (the same as the engine's merge, on t vertices instead of n):
/// every critical vertex but the global minimum gets its contour tree
/// neighbour `next[x]`, with [`ABOVE`] when x is the upper end. No values
/// are compared: which vertex is a leaf follows from the degrees alone.
fn merge(join: CriticalTree, split: CriticalTree) -> Vec<u32> {
    let CriticalTree {
        parent: mut jp,
        children: mut jc,
        ..
    } = join;
    let CriticalTree {
        parent: mut sp,
        children: mut sc,
        ..
    } = split;
    let t = jp.len();
    let mut next = vec![NONE; t];
    if t <= 1 {
        return next;
    }
    let global_min = jp.iter().position(|&p| p == NONE).unwrap_or(0);
    let mut cut = vec![false; t];
    let mut leaves: Vec<u32> = (0..t as u32)
        .filter(|&v| v as usize != global_min && jc[v as usize] + sc[v as usize] == 1)
        .collect();
    while let Some(x) = leaves.pop() {
        let xi = x as usize;
        let y = if jc[xi] == 0 {
            let start = jp[xi];
            let y = climb(&mut jp, start, |y, _| cut[y as usize]);
            next[xi] = y | ABOVE;
            jc[y as usize] -= 1;
            y
        } else {
            let start = sp[xi];
            let y = climb(&mut sp, start, |y, _| cut[y as usize]);
            next[xi] = y;
            sc[y as usize] -= 1;
            y
        };
        cut[xi] = true;
        let yi = y as usize;
        if yi != global_min && jc[yi] + sc[yi] == 1 {
            leaves.push(y);
        }
    }
    next
}

/// The superarc tree rooted at the global minimum, with Euler-tour
/// intervals, to choose at a node the down arc that leads towards a given
/// minimum without comparing values.
struct SuperarcWalk<K> {
    /// Per node, its down arcs.
    down_off: Vec<u32>,
    down: Vec<u32>,
    /// Per arc, its lower node.
    lower: Vec<u32>,
    /// Per node, what a search step reads, in one record (separate arrays
    /// made every step of a search four or five cache misses).
    rec: Vec<NodeRec<K>>,
}

/// One node of [`SuperarcWalk`]: its vertex and the vertex's key (what a
/// search compares, read here and not from the field), parent in the rooted tree and
/// the arc to it, depth and Myers' jump pointer (an ancestor whose depth
/// depends on the node's depth only, so that any monotone search along the
/// ancestors takes O(log depth) steps), and its Euler-tour interval.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct NodeRec<K> {
    key: K,
    vertex: u32,
    parent: u32,
    jump: u32,
    depth: u32,
    parent_arc: u32,
    tin: u32,
    tout: u32,
}

impl<K: Copy> SuperarcWalk<K> {
    fn new(nodes: &[Node], arcs: &[Superarc], key: impl Fn(u32) -> K) -> Self {
        let k = nodes.len();
        let mut down_off = vec![0u32; k + 1];
        let mut deg = vec![0u32; k + 1];
        for a in arcs {
            down_off[a.upper.0 as usize + 1] += 1;
            deg[a.upper.0 as usize] += 1;
            deg[a.lower.0 as usize] += 1;
        }
        for i in 1..=k {
            down_off[i] += down_off[i - 1];
        }
        let mut fill = down_off.clone();
        let mut down = vec![0u32; arcs.len()];
        // Undirected adjacency for the rooting, with the arc of each entry.
        let mut adj_off = vec![0u32; k + 1];
        for i in 0..k {
            adj_off[i + 1] = adj_off[i] + deg[i];
        }
        let mut adj_fill = adj_off.clone();
        let mut adj = vec![(0u32, 0u32); 2 * arcs.len()];
        for (i, a) in arcs.iter().enumerate() {
            let (u, l) = (a.upper.0 as usize, a.lower.0 as usize);
            down[fill[u] as usize] = i as u32;
            fill[u] += 1;
            adj[adj_fill[u] as usize] = (l as u32, i as u32);
            adj_fill[u] += 1;
            adj[adj_fill[l] as usize] = (u as u32, i as u32);
            adj_fill[l] += 1;
        }
        let lower = arcs.iter().map(|a| a.lower.0).collect();
        // Nodes are in vertex order: node 0 is the global minimum.
        let mut rec: Vec<NodeRec<K>> = nodes
            .iter()
            .map(|n| NodeRec {
                key: key(n.vertex),
                vertex: n.vertex,
                parent: NONE,
                jump: 0,
                depth: 0,
                parent_arc: NONE,
                tin: 0,
                tout: 0,
            })
            .collect();
        if k > 0 {
            let mut clock = 0u32;
            let mut stack: Vec<(u32, u32)> = vec![(0, adj_off[0])];
            rec[0].tin = clock;
            clock += 1;
            while let Some(top) = stack.len().checked_sub(1) {
                let (v, e) = stack[top];
                if e < adj_off[v as usize + 1] {
                    let (w, arc) = adj[e as usize];
                    stack[top].1 += 1;
                    if w != rec[v as usize].parent {
                        let rv = rec[v as usize];
                        let j = rv.jump;
                        let (dj, djj) = (
                            rec[j as usize].depth,
                            rec[rec[j as usize].jump as usize].depth,
                        );
                        let jump = if rv.depth - dj == dj - djj {
                            rec[j as usize].jump
                        } else {
                            v
                        };
                        let rw = &mut rec[w as usize];
                        rw.parent = v;
                        rw.parent_arc = arc;
                        rw.depth = rv.depth + 1;
                        rw.jump = jump;
                        rw.tin = clock;
                        clock += 1;
                        stack.push((w, adj_off[w as usize]));
                    }
                } else {
                    rec[v as usize].tout = clock;
                    stack.pop();
                }
            }
        }
        Self {
            down_off,
            down,
            lower,
            rec,
        }
    }

    /// The arc at a height on the monotone path from node `s` down to the
    /// minimum `m`: `above(k, x)` says whether the vertex x (of key k) of a
    /// node is above that height (true at `s`, false at `m`). The path climbs from `s` to
    /// the common ancestor c and descends to `m`; along each part `above`
    /// changes once, and jump pointers find the change in O(log depth)
    /// comparisons; whether the subtree of a node holds `m` (Euler-tour
    /// intervals, no comparison) tells the two parts apart. (A walk of a few nodes from each part's start before
    /// the jumps was tried: on tooth the change is rarely near, and it
    /// raised locating from 12.6 to 14.2 comparisons per vertex.)
    fn locate(&self, s: u32, m: u32, mut above: impl FnMut(K, u32) -> bool) -> u32 {
        let tm = self.rec[m as usize].tin;
        let holds_m = |r: &NodeRec<K>| r.tin <= tm && tm < r.tout;
        let rs = &self.rec[s as usize];
        let (c, dc) = if holds_m(rs) {
            (s, rs.depth)
        } else {
            // On s's side: the last ancestor x of s above the height whose
            // subtree does not hold m (below c); s is one. One climb finds
            // it and c, the first ancestor that holds m (finding c first,
            // then searching, read the same records twice).
            let mut x = s;
            loop {
                let rx = &self.rec[x as usize];
                let rj = &self.rec[rx.jump as usize];
                if !holds_m(rj) && above(rj.key, rj.vertex) {
                    x = rx.jump;
                    continue;
                }
                let rp = &self.rec[rx.parent as usize];
                if holds_m(rp) {
                    // The parent is c: past it, the path descends to m.
                    if !above(rp.key, rp.vertex) {
                        return rx.parent_arc;
                    }
                    break (rx.parent, rp.depth);
                }
                if above(rp.key, rp.vertex) {
                    x = rx.parent;
                    continue;
                }
                return rx.parent_arc;
            }
        };
        // On m's side: the last ancestor of m below the height.
        let mut x = m;
        loop {
            let rx = &self.rec[x as usize];
            let rj = &self.rec[rx.jump as usize];
            if rj.depth > dc && !above(rj.key, rj.vertex) {
                x = rx.jump;
                continue;
            }
            let p = rx.parent;
            let rp = &self.rec[p as usize];
            if p != c && !above(rp.key, rp.vertex) {
                x = p;
                continue;
            }
            return rx.parent_arc;
        }
    }

    #[inline]
    fn in_subtree(&self, x: u32, root: u32) -> bool {
        let (tx, r) = (self.rec[x as usize].tin, &self.rec[root as usize]);
        r.tin <= tx && tx < r.tout
    }

    /// The down arc of node `p` on the tree path from `p` to node `m`
    /// (which lies below it on a monotone path).
    #[inline]
    fn down_towards(&self, p: u32, m: u32) -> u32 {
        let arcs =
            &self.down[self.down_off[p as usize] as usize..self.down_off[p as usize + 1] as usize];
        let parent = self.rec[p as usize].parent;
        for &a in arcs {
            let q = self.lower[a as usize];
            let toward = if q == parent {
                !self.in_subtree(m, p)
            } else {
                self.in_subtree(m, q)
            };
            if toward {
                return a;
            }
        }
        // Unreachable on a correct tree; any arc keeps the walk finite.
        arcs[0]
    }
}

/// The paper's bound without its constant (Theorem 1): Σ log2 ℓ_v over the
/// supernodes v, ℓ_v the number of nodes on the longest monotone path of
/// the tree through v. Add the mesh's size N for the whole bound.
pub fn shape_term(tree: &ContourTree) -> f64 {
    let nodes = tree.nodes();
    let k = nodes.len();
    // Nodes are in the vertex order, so one pass each way settles the
    // longest paths down (to a minimum) and up (to a maximum).
    let mut down = vec![1u32; k];
    for i in 0..k {
        for &a in tree.up_arcs(NodeId(i as u32)) {
            let u = tree.arc(a).upper.0 as usize;
            down[u] = down[u].max(down[i] + 1);
        }
    }
    let mut up = vec![1u32; k];
    for i in (0..k).rev() {
        for &a in tree.down_arcs(NodeId(i as u32)) {
            let l = tree.arc(a).lower.0 as usize;
            up[l] = up[l].max(up[i] + 1);
        }
    }
    (0..k).map(|i| ((up[i] + down[i] - 1) as f64).log2()).sum()
}
