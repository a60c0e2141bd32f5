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
//! **Link codes in the words.** Before a sweep, each vertex's word holds
//! its link code ([`Mesh::link_code`], both nibbles: [`link_words`]); the
//! sweep reads it when it visits the vertex and then overwrites it with
//! the candidate number or leafward candidate. A word is read as a code
//! only before its vertex is visited and as a result only after, so the
//! codes need no array of their own, and the sweep touches one word per
//! vertex where it touched a code and a word.
//!
//! **Memory per vertex** while sweeping: 3 bytes (its word: link code,
//! then candidate number or leafward candidate, packed in 3 bytes while
//! the candidates number fewer than 2^23: [`super::leafward`], read and
//! written through [`Word`]; else 4); per candidate 8 bytes (union-find
//! and parent: the union keeps the older root, so no rank), 7 where the
//! candidates' tables are packed ([`leafward::packs_tables`]: a noisy
//! scan, one vertex in 8 or more a candidate), whose union-find entries
//! are then 3 bytes, as the records' are. Once the
//! union-find is let go, each candidate's children are counted (1 byte),
//! and once both sweeps are done the split tree's list of the candidates'
//! vertices (4 bytes each) is read off its words. Where the words cannot
//! pack (2^23 candidates or more), each candidate's parent is written into
//! its own word instead of a table ([`sweep_parents_in_words`]): 4 bytes
//! per candidate while sweeping, the union-find's, and the parents read
//! off the words once both sweeps are done ([`number_candidates`]).

use super::leafward::{self, Leafward, Word, with_both_words, with_words};
use crate::field::{OrderView, VertexOrder};
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
#[derive(Clone, Debug, PartialEq, Eq)]
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
    /// leafward candidate (see the module documentation); in 3 bytes per
    /// vertex where the candidates allow it ([`Leafward`]).
    pub leafward: Leafward,
    /// Per candidate: its vertex (empty in the join tree: the split tree
    /// lists them).
    pub vertex: Vec<u32>,
}

/// The join tree (Carr et al. Def. 4.1): how the components of the
/// superlevel sets join as the level goes down, on the candidate nodes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JoinTree(pub SweepTree);

/// The split tree: how the components of the sublevel sets split as the
/// level goes down (join as it goes up), on the candidate nodes.
#[derive(Clone, Debug, PartialEq, Eq)]
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

/// The candidates and extrema of a mesh counted without keeping its link
/// codes (64 Ki vertices at a time, on every core): what `flexiso info`
/// needs to say how much memory the tree will take
/// ([`super::peak_bytes`]).
pub fn census_of<M: Mesh, O: VertexOrder + ?Sized>(mesh: &M, values: &O) -> Census {
    const CHUNK: usize = 1 << 16;
    let n = mesh.num_vertices();
    (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let first = c * CHUNK;
            let mut codes = vec![0u8; (n - first).min(CHUNK)];
            mesh.link_codes_into(values, first as u32, &mut codes);
            census_of_codes(&codes)
        })
        .reduce(Census::default, |a, b| a + b)
}

/// Marks a union-find root; the rest of a root's word is the component's
/// last candidate.
pub(super) const ROOT: u32 = 1 << 31;

/// The join tree: sweeps `order` (ascending) from its end.
pub fn join_tree<M: Mesh, O: VertexOrder + ?Sized>(
    mesh: &M,
    values: &O,
    link_codes: &[u8],
    candidates: usize,
    order: &[u32],
    progress: &Progress,
) -> Result<JoinTree, Cancelled> {
    let words = Leafward::of_codes(link_codes, leafward::packs(candidates));
    whole(
        mesh,
        values,
        words,
        candidates,
        true,
        order.into(),
        progress,
        true,
    )
    .map(JoinTree)
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
    let words = Leafward::of_codes(link_codes, leafward::packs(candidates));
    whole(
        mesh,
        values,
        words,
        candidates,
        false,
        order.into(),
        progress,
        true,
    )
    .map(|mut tree| {
        tree.list_vertices();
        SplitTree(tree)
    })
}

/// One sweep over the whole mesh: one block, whose nodes are the candidates.
/// `words` holds every vertex's link code ([`link_words`]) and becomes the
/// tree's `leafward`. It sets the progress fraction if it `report`s. The
/// caller lists the split tree's candidates' vertices
/// ([`SweepTree::list_vertices`]), once no sweep holds its union-find.
#[allow(clippy::too_many_arguments)]
pub(super) fn whole<M: Mesh, O: VertexOrder + ?Sized>(
    mesh: &M,
    values: &O,
    mut words: Leafward,
    candidates: usize,
    join: bool,
    order: OrderView<'_>,
    progress: &Progress,
    report: bool,
) -> Result<SweepTree, Cancelled> {
    let n = mesh.num_vertices();
    debug_assert_eq!(words.len(), n);
    let block = Block::new(0, n as u32, n, 0);
    // The union-find in the records' 3 bytes where the tables pack.
    let packed = leafward::packs_tables(n, candidates, leafward::PACKED_TABLES_SHARE);
    let swept = with_words!(&mut words, w => sweep_whole(
        mesh, values, candidates, join, order, block, w, packed, progress, report,
    ))?;
    Ok(SweepTree {
        parent: swept.parent,
        children: swept.children,
        leafward: words,
        vertex: Vec::new(),
    })
}

/// [`sweep`] of the whole mesh, its union-find in the records' width
/// where `packed`, else in words.
#[allow(clippy::too_many_arguments)]
fn sweep_whole<M: Mesh, O: VertexOrder + ?Sized, W: Word>(
    mesh: &M,
    values: &O,
    candidates: usize,
    join: bool,
    order: OrderView<'_>,
    block: Block,
    words: &mut [W],
    packed: bool,
    progress: &Progress,
    report: bool,
) -> Result<BlockTree, Cancelled> {
    if packed {
        sweep::<M, O, W, W, false>(
            mesh, values, candidates, join, order, block, words, false, progress, report,
        )
    } else {
        sweep::<M, O, W, u32, false>(
            mesh, values, candidates, join, order, block, words, false, progress, report,
        )
    }
}

impl SweepTree {
    /// Lists the candidates' vertices in `vertex`, read off the words: the
    /// split tree's, once the sweeps have let their union-finds go (4
    /// bytes per candidate fewer at the sweeps' peak).
    pub fn list_vertices(&mut self) {
        let candidates = self.parent.len();
        self.vertex = with_words!(&mut self.leafward, w => candidate_vertices(w, candidates));
    }
}

/// The vertex of each of the `candidates` candidates from a sweep's words
/// (`CANDIDATE | c` at candidate `c`'s vertex), on every core.
pub(super) fn candidate_vertices<W: Word>(words: &[W], candidates: usize) -> Vec<u32> {
    listed_vertices(words, candidates, Some)
}

/// The vertices of `len` of the candidates, read off a sweep's words
/// (`CANDIDATE | c` at candidate `c`'s vertex), on every core: candidate
/// `c`'s vertex goes to slot `slot(c)`, where it has one (a slot is no
/// other candidate's).
pub(super) fn listed_vertices<W: Word>(
    words: &[W],
    len: usize,
    slot: impl Fn(u32) -> Option<u32> + Sync,
) -> Vec<u32> {
    let mut vertex = crate::pages::filled(len, 0u32);
    let out = crate::pages::DisjointSlots::new(&mut vertex);
    words
        .par_chunks(1 << 16)
        .enumerate()
        .for_each(|(c, chunk)| {
            let first = (c << 16) as u32;
            for (i, &w) in chunk.iter().enumerate() {
                let w = w.get();
                if w & CANDIDATE != 0
                    && let Some(s) = slot(w & !CANDIDATE)
                {
                    // SAFETY: each candidate number is in exactly one
                    // word, and its slot is no other candidate's.
                    unsafe { out.write(s as usize, first + i as u32) };
                }
            }
        });
    vertex
}

/// Consecutive vertex ids `lo..hi` swept on their own, as one block of the
/// divide and conquer ([`super::blocks`]). Its *band* is the vertices
/// within the mesh's [`Mesh::edge_span`] of a cut to another block: only
/// they can have neighbours outside. Band vertices are nodes of the
/// block's trees, like the candidates, so that the blocks can be glued.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    /// First vertex.
    pub lo: u32,
    /// One past the last vertex.
    pub hi: u32,
    /// Vertices `inner_lo..inner_hi` are not in the band.
    inner_lo: u32,
    inner_hi: u32,
}

impl Block {
    /// The block `lo..hi` of a mesh of `n` vertices whose edges join ids at
    /// most `span` apart.
    pub fn new(lo: u32, hi: u32, n: usize, span: usize) -> Self {
        let inner_lo = if lo == 0 {
            lo
        } else {
            (lo as u64 + span as u64).min(hi as u64) as u32
        };
        let inner_hi = if hi as usize == n {
            hi
        } else {
            (hi as u64).saturating_sub(span as u64).max(lo as u64) as u32
        };
        Self {
            lo,
            hi,
            inner_lo,
            inner_hi,
        }
    }

    /// True if `v` is in the block.
    #[inline(always)]
    pub fn contains(&self, v: u32) -> bool {
        self.lo <= v && v < self.hi
    }

    /// True if `v` (in the block) may have a neighbour outside it.
    #[inline(always)]
    pub fn in_band(&self, v: u32) -> bool {
        v < self.inner_lo || v >= self.inner_hi
    }

    /// The number of vertices in the band (if the block is thinner than
    /// two spans, inner_hi < inner_lo and the band is the whole block).
    pub fn band_len(&self) -> usize {
        ((self.inner_lo - self.lo) + (self.hi - self.inner_hi.max(self.inner_lo))) as usize
    }

    /// The nodes of the block's trees: its candidates and its band, from
    /// the words of the whole mesh while they hold the link codes.
    pub fn count_nodes<W: Word>(&self, words: &[W]) -> usize {
        let (ilo, ihi) = (
            self.inner_lo as usize,
            self.inner_hi.max(self.inner_lo) as usize,
        );
        let candidates: usize = words[ilo..ihi]
            .par_chunks(1 << 16)
            .map(|c| c.iter().filter(|&&w| is_candidate(w.get() as u8)).count())
            .sum();
        self.band_len() + candidates
    }
}

/// A block's join or split tree on its nodes, numbered in the vertex order
/// within the block.
pub(super) struct BlockTree {
    /// Per node: its parent node, `NONE` at a root.
    pub parent: Vec<u32>,
    /// Per node: the components it joins.
    pub children: Vec<u8>,
    /// Per node: its vertex, ascending (only when asked for).
    pub vertex: Vec<u32>,
    /// Per node: whether it is a candidate, not only a band vertex (when
    /// the vertices are asked for, in a block with a band).
    pub candidate: Vec<bool>,
}

/// One sweep of `block` (descending for the join tree, ascending for the
/// split tree) on the edges inside it, with `nodes` nodes (its candidates
/// and band). `leafward` is the block's part of the per-vertex word
/// (`leafward[v - lo]`), which holds the link code of every vertex not
/// yet visited (see the module documentation). `values` gives the vertex
/// order; testing "already swept" on it rather than on the union-find
/// keeps the hot loop in the compact value array. Only a `report`ing sweep sets the progress
/// fraction; every sweep stops when it is cancelled.
///
/// The union-find is over the nodes only: a vertex's one word is
/// `CANDIDATE | c` for node `c`, otherwise its leafward node, which is in
/// its component, so `find` starts there. A vertex that is not a node is
/// never a union-find node: it costs one read of a neighbour's word, a
/// `find` in the (on smooth fields, cache-sized) node forest and one write.
#[allow(clippy::too_many_arguments)]
pub(super) fn sweep<M: Mesh, O: VertexOrder + ?Sized, W: Word, U: Word, const BLOCKED: bool>(
    mesh: &M,
    values: &O,
    nodes: usize,
    join: bool,
    order: OrderView<'_>,
    block: Block,
    leafward: &mut [W],
    keep_vertex: bool,
    progress: &Progress,
    report: bool,
) -> Result<BlockTree, Cancelled> {
    let n = order.len();
    let lo = block.lo;
    debug_assert_eq!(leafward.len(), (block.hi - lo) as usize);
    // Without BLOCKED, the block is the whole mesh and has no band (one
    // compiled loop each, so the whole sweep pays nothing for blocks).
    debug_assert!(BLOCKED || (lo == 0 && block.hi as usize == n));
    // uf[c]: ROOT | last node of the component at a root, otherwise the
    // parent in the union-find forest; held as `U`, whose value is only
    // its type: 3 bytes where the tables pack ([`leafward::packs_tables`]).
    let shift = UF_SHIFT * 4 / size_of::<U>();
    let mut uf_words = crate::pages::filled(shift + nodes, U::of(0));
    let uf = &mut uf_words[shift..];
    let mut parent = crate::pages::filled(nodes, NONE);
    let mut vertex = vec![0u32; if keep_vertex { nodes } else { 0 }];
    let mut candidate = vec![false; if BLOCKED && keep_vertex { nodes } else { 0 }];
    let mut reps: Vec<u32> = Vec::with_capacity(16);
    // The number of the next node visited.
    let mut next: u32 = if join { nodes as u32 } else { 0 };
    // The block's vertices in sweep order, a chunk of the order at a time.
    const CHUNK: usize = 1 << 16;
    let mut visit: Vec<u32> = Vec::with_capacity(CHUNK);
    // A packed order's chunk, decoded.
    let mut ids: Vec<u32> = Vec::new();
    // The join sweep's chunk, in the order it visits it.
    let mut backwards: Vec<u32> = Vec::with_capacity(if join { CHUNK } else { 0 });

    // How far ahead in the order to prefetch a vertex's neighbours (and
    // read its own word to find them): enough vertices in flight to hide
    // DRAM latency, few enough that the lines are still in L1/L2.
    const AHEAD: usize = 12;
    // How far ahead its own word is fetched, for that read. Where the
    // order runs through consecutive ids (ties, broken by id: the brains'
    // flat regions, a smooth float field's underflowed tails) the words
    // are a stream of 3 bytes each, and 24 of them, the distance this
    // was, are barely a line: the stream stalled, most where it runs
    // down (the join sweep). 64 took colin27_ch2better's sweeps from
    // 0.31 to 0.27 s and `synthetic:256`'s join sweep from 0.13 to 0.11
    // (one thread); noisy scans and white noise are unchanged.
    const WORD_AHEAD: usize = 64;
    for start in (0..n).step_by(CHUNK) {
        if start % (1 << 20) == 0 {
            if report {
                progress.check(start, n)?;
            } else if progress.is_cancelled() {
                return Err(Cancelled);
            }
        }
        let end = (start + CHUNK).min(n);
        let range = if join { n - end..n - start } else { start..end };
        // The vertices to visit: the order itself for the whole mesh, else
        // the block's vertices of it (a packed order skips the other
        // blocks' runs undecoded); copied backwards for the join sweep. A
        // tight copy reads the order downwards at full speed; the sweep's
        // loop reading it downwards between its stalls was slower (one
        // thread, `synthetic:256`'s join sweep 0.104-0.107 s, now
        // 0.098-0.102).
        let seq = if !BLOCKED {
            order.read(range, &mut ids)
        } else {
            order.read_within(range, block.lo..block.hi, &mut visit)
        };
        let seq = if join {
            backwards.clear();
            backwards.extend(seq.iter().rev());
            &backwards[..]
        } else {
            seq
        };
        let m = seq.len();
        for i in 0..m {
            let v = seq[i];
            if i + AHEAD < m {
                // A vertex that is not a node reads one neighbour's word
                // and its own: two lines, not its whole star. Its own word
                // (its code) was prefetched AHEAD vertices ago. (Indices
                // are relative to the block: the hints only add offsets.)
                let w = seq[i + AHEAD];
                let cw = leafward[(w - lo) as usize].get() as u8;
                if is_candidate(cw) || (BLOCKED && block.in_band(w)) {
                    mesh.prefetch_star(w - lo, leafward);
                } else {
                    let c = if join { cw & 0xf } else { cw >> 4 };
                    prefetch(leafward, (mesh.neighbour_at(w, c) - lo) as usize);
                }
                if i + WORD_AHEAD < m {
                    prefetch(leafward, (seq[i + WORD_AHEAD] - lo) as usize);
                }
            }
            // Not visited yet: the word is v's link code.
            let full = leafward[(v - lo) as usize].get() as u8;
            let code = if join { full & 0xf } else { full >> 4 };
            let band = BLOCKED && block.in_band(v);
            if !band && !is_candidate(full) {
                // One component beyond v, reached through one neighbour: v
                // remembers its last node. Nothing else.
                let u = mesh.neighbour_at(v, code);
                let r = find(uf, leafward[(u - lo) as usize].get() & !CANDIDATE);
                leafward[(v - lo) as usize] = W::of(uf[r as usize].get() & !ROOT);
                continue;
            }
            let kid = next_node(&mut next, join);
            leafward[(v - lo) as usize] = W::of(CANDIDATE | kid);
            if keep_vertex {
                vertex[kid as usize] = v;
                if BLOCKED {
                    candidate[kid as usize] = is_candidate(full);
                }
            }
            let mut root = kid;
            uf[kid as usize] = U::of(ROOT | kid);
            // One representative per component of the swept part of v's
            // link (inside the block).
            reps.clear();
            let swept = |u: u32| {
                if join {
                    values.above(u, v)
                } else {
                    values.above(v, u)
                }
            };
            if band {
                mesh.for_each_neighbour(v, |u| {
                    if block.contains(u) && swept(u) {
                        reps.push(u)
                    }
                });
            } else {
                swept_link_components(mesh, v, code, swept, &mut reps);
            }
            for &u in &reps {
                let r = find(uf, leafward[(u - lo) as usize].get() & !CANDIDATE);
                if r == root {
                    continue;
                }
                // Component r is absorbed at v: the tree edge runs from its
                // last node to v.
                let last = uf[r as usize].get() & !ROOT;
                parent[last as usize] = kid;
                root = union(uf, root, r, kid, (root > r) == join);
            }
        }
    }
    debug_assert_eq!(next, if join { 0 } else { nodes as u32 });
    // A node's children are the components it absorbed, each of which
    // named it as the parent of its last node: counted now, once the
    // union-find is let go, rather than kept beside it during the sweep.
    drop(uf_words);
    let children = count_children(&parent);
    Ok(BlockTree {
        parent,
        children,
        vertex,
        candidate,
    })
}

/// The number of the next node a sweep visits, from the top down for the
/// join tree (`next` counts down to it) and from the bottom up for the
/// split tree (`next` counts past it): nodes are numbered in the order.
#[inline(always)]
pub(super) fn next_node(next: &mut u32, join: bool) -> u32 {
    if join {
        *next -= 1;
        *next
    } else {
        *next += 1;
        *next - 1
    }
}

/// One representative per component of the swept part of `v`'s link,
/// pushed onto `reps`, from `v`'s half of its link code: none where it is
/// empty, one neighbour where it is one piece, else each piece's.
#[inline(always)]
fn swept_link_components<M: Mesh>(
    mesh: &M,
    v: u32,
    code: u8,
    swept: impl FnMut(u32) -> bool,
    reps: &mut Vec<u32>,
) {
    match code {
        LINK_EMPTY => {}
        LINK_SEVERAL => mesh.for_each_link_component(v, swept, |u| reps.push(u)),
        index => reps.push(mesh.neighbour_at(v, index)),
    }
}

/// Each node's children, from the nodes' parents.
fn count_children(parent: &[u32]) -> Vec<u8> {
    let mut children = crate::pages::filled(parent.len(), 0u8);
    for &p in parent {
        if p != NONE {
            children[p as usize] += 1;
        }
    }
    children
}

/// True where a build's sweeps write each candidate's parent into its own
/// word ([`sweep_parents_in_words`]): where its records are words, not
/// packed ([`leafward::packs`]: 2^23 candidates or more, a noisy scan of a
/// billion vertices or white noise), unless `forced` says otherwise (the
/// tests), and where a vertex id leaves the union-find's root bit free.
pub fn parents_in_words(n: usize, candidates: usize, forced: Option<bool>) -> bool {
    forced.unwrap_or(!leafward::packs(candidates)) && n <= ROOT as usize
}

/// The two sweeps of the whole mesh with each candidate's parent written
/// into its own word, not into a table beside the union-find: per
/// candidate 4 bytes while sweeping (the union-find), not 8, on the
/// volumes whose records are words (4 bytes per vertex each:
/// [`parents_in_words`]), where the candidates are many and their tables
/// set the peak (the noisy 1024³ scan: 304 M candidates, 28 %; 16 bytes
/// per candidate were 4.5 bytes per vertex beside the records' 8).
///
/// A union-find root's word names the vertex of its component's last
/// candidate, not its number. When a component is absorbed, its last
/// candidate's word (until then `CANDIDATE |` its own number) becomes
/// `CANDIDATE |` the absorbing candidate's number: its parent, which is
/// in the same component from then on, so that a `find` starting there
/// still finds it. A vertex that is not a candidate reads its number off
/// the last candidate's word, which is still its own then. Once both
/// sweeps are done, [`number_candidates`] reads the parents off the words
/// and writes each candidate's own number (its rank in the order) back:
/// the same [`SweepTree`]s as [`whole`] makes.
#[allow(clippy::too_many_arguments)]
pub(super) fn sweep_parents_in_words<M: Mesh, O: VertexOrder + ?Sized>(
    mesh: &M,
    values: &O,
    nodes: usize,
    join: bool,
    order: OrderView<'_>,
    words: &mut [u32],
    progress: &Progress,
    report: bool,
) -> Result<Vec<u32>, Cancelled> {
    let n = order.len();
    debug_assert_eq!(words.len(), n);
    debug_assert!(n <= ROOT as usize);
    let mut uf_words = crate::pages::filled(UF_SHIFT + nodes, 0u32);
    let uf = &mut uf_words[UF_SHIFT..];
    let mut reps: Vec<u32> = Vec::with_capacity(16);
    let mut next: u32 = if join { nodes as u32 } else { 0 };
    const CHUNK: usize = NUMBERED_CHUNK;
    // The ascending sweep's first number in each chunk of the order.
    let mut starts = Vec::with_capacity(if join { 0 } else { n.div_ceil(CHUNK) });
    let mut ids: Vec<u32> = Vec::new();
    let mut backwards: Vec<u32> = Vec::with_capacity(if join { CHUNK } else { 0 });
    // As in [`sweep`].
    const AHEAD: usize = 12;
    const WORD_AHEAD: usize = 64;
    for start in (0..n).step_by(CHUNK) {
        if start % (1 << 20) == 0 {
            if report {
                progress.check(start, n)?;
            } else if progress.is_cancelled() {
                return Err(Cancelled);
            }
        }
        if !join {
            starts.push(next);
        }
        let end = (start + CHUNK).min(n);
        let range = if join { n - end..n - start } else { start..end };
        let seq = order.read(range, &mut ids);
        let seq = if join {
            backwards.clear();
            backwards.extend(seq.iter().rev());
            &backwards[..]
        } else {
            seq
        };
        let m = seq.len();
        for i in 0..m {
            let v = seq[i];
            if i + AHEAD < m {
                let w = seq[i + AHEAD];
                let cw = words[w as usize] as u8;
                if is_candidate(cw) {
                    mesh.prefetch_star(w, words);
                } else {
                    let c = if join { cw & 0xf } else { cw >> 4 };
                    prefetch(words, mesh.neighbour_at(w, c) as usize);
                }
                if i + WORD_AHEAD < m {
                    prefetch(words, seq[i + WORD_AHEAD] as usize);
                }
            }
            let full = words[v as usize] as u8;
            let code = if join { full & 0xf } else { full >> 4 };
            if !is_candidate(full) {
                let u = mesh.neighbour_at(v, code);
                let r = find(uf, words[u as usize] & !CANDIDATE);
                let last = uf[r as usize] & !ROOT;
                // The last candidate's own number: it is not absorbed yet.
                words[v as usize] = words[last as usize] & !CANDIDATE;
                continue;
            }
            let kid = next_node(&mut next, join);
            words[v as usize] = CANDIDATE | kid;
            let mut root = kid;
            uf[kid as usize] = ROOT | v;
            reps.clear();
            let swept = |u: u32| {
                if join {
                    values.above(u, v)
                } else {
                    values.above(v, u)
                }
            };
            swept_link_components(mesh, v, code, swept, &mut reps);
            for &u in &reps {
                let r = find(uf, words[u as usize] & !CANDIDATE);
                if r == root {
                    continue;
                }
                // Component r is absorbed at v: its last candidate's parent.
                let last = uf[r as usize] & !ROOT;
                words[last as usize] = CANDIDATE | kid;
                root = union_naming(uf, root, r, kid, v, (root > r) == join);
            }
        }
    }
    debug_assert_eq!(next, if join { 0 } else { nodes as u32 });
    Ok(starts)
}

/// The chunks of the order whose first candidate numbers
/// [`sweep_parents_in_words`] lists for [`number_candidates`].
const NUMBERED_CHUNK: usize = 1 << 16;

/// After both [`sweep_parents_in_words`]: each candidate's parent in the
/// join and in the split tree, read off its two words (`NONE` where a word
/// names the candidate itself: the root), and its own number written back
/// into both, as [`sweep`] leaves them. A candidate's number is its rank in
/// the order: each chunk of the order is numbered from the first number
/// the split sweep gave in it (`starts`), all chunks at once.
pub(super) fn number_candidates(
    order: OrderView<'_>,
    join: &mut [u32],
    split: &mut [u32],
    starts: &[u32],
    nodes: usize,
) -> (Vec<u32>, Vec<u32>) {
    let n = order.len();
    let mut join_parent = crate::pages::filled(nodes, NONE);
    let mut split_parent = crate::pages::filled(nodes, NONE);
    let slots = [join, split].map(crate::pages::DisjointSlots::new);
    let parents = [join_parent.as_mut_slice(), split_parent.as_mut_slice()]
        .map(crate::pages::DisjointSlots::new);
    starts
        .par_iter()
        .enumerate()
        .for_each_init(Vec::new, |ids, (c, &first)| {
            let range = c * NUMBERED_CHUNK..(n.min((c + 1) * NUMBERED_CHUNK));
            let seq = order.read(range, ids);
            let mut number = first;
            for (i, &x) in seq.iter().enumerate() {
                if let Some(&y) = seq.get(i + 16) {
                    slots.iter().for_each(|w| w.prefetch(y as usize));
                }
                // SAFETY: a vertex is in the order once, so its words are
                // read and written by this chunk alone, as is the slot of
                // the number it is given.
                unsafe {
                    if slots[0].read(x as usize) & CANDIDATE == 0 {
                        continue;
                    }
                    for (w, p) in slots.iter().zip(&parents) {
                        let named = w.read(x as usize) & !CANDIDATE;
                        p.write(number as usize, if named == number { NONE } else { named });
                        w.write(x as usize, CANDIDATE | number);
                    }
                }
                number += 1;
            }
        });
    (join_parent, split_parent)
}

/// [`SweepTree`] of a tree whose parents [`number_candidates`] read.
pub(super) fn tree_of_parents(parent: Vec<u32>, words: Vec<u32>) -> SweepTree {
    SweepTree {
        children: count_children(&parent),
        parent,
        leafward: Leafward::Words(words),
        vertex: Vec::new(),
    }
}

/// Words by which a sweep's union-find starts into its allocation: 65
/// cache lines and a page, so that `uf[c]` and `parent[c]`, two arrays of
/// one size allocated one after the other, do not fall on the same cache
/// sets (most likely; this machine has no hardware counters to show it). Without it the sweeps on white noise were 10 % slower than with
/// a rank array of one byte per node between the two; that array, unused,
/// or this shift restored the speed (3 alternated runs each).
const UF_SHIFT: usize = 1040;

/// Unites the component of `root` with the other component `r` when the
/// node `kid` is visited (`root == kid` while `kid` is still alone); the
/// new root's word names `kid` as the last node. Returns the new root:
/// `r` if `kid` is alone, else `root` where `root_stays`.
///
/// No rank is kept, so the sweeps hold 8 bytes per node, not 9. The
/// sweeps keep the *older* root, visited first (`root_stays` compares the
/// nodes' numbers, given in the order visited): a component that has
/// grown longer is likely the larger, as union by rank would have it, and
/// path halving in [`find`] keeps the paths short: as fast as union by
/// rank, measured on white noise and on the scans (with [`UF_SHIFT`]).
/// Which root survives never shows in the trees: they depend only on the
/// components.
#[inline(always)]
pub(super) fn union<U: Word>(uf: &mut [U], root: u32, r: u32, kid: u32, root_stays: bool) -> u32 {
    union_naming(uf, root, r, kid, kid, root_stays)
}

/// [`union`] whose new root's word names `last` (a vertex, in
/// [`sweep_parents_in_words`]) rather than `kid`.
#[inline(always)]
fn union_naming<U: Word>(
    uf: &mut [U],
    root: u32,
    r: u32,
    kid: u32,
    last: u32,
    root_stays: bool,
) -> u32 {
    let (hi, lo) = if root != kid && root_stays {
        (root, r)
    } else {
        (r, root)
    };
    uf[lo as usize] = U::of(hi);
    uf[hi as usize] = U::of(ROOT | last);
    hi
}

/// A fixed pseudo-random total order of the nodes, for a [`union`] whose
/// nodes are not numbered in the order visited: linking by random index
/// (Goel, Khanna, Larkin and Tarjan, SODA 2014) is as good as by rank in
/// expectation. A multiplication by an odd constant permutes the words.
#[inline(always)]
pub(super) fn link_rank(x: u32) -> u32 {
    x.wrapping_mul(0x9E37_79B9)
}

/// Root of `x`'s set, halving the path on the way.
#[inline(always)]
pub(super) fn find<U: Word>(uf: &mut [U], mut x: u32) -> u32 {
    loop {
        let p = uf[x as usize].get();
        if p & ROOT != 0 {
            return x;
        }
        let gp = uf[p as usize].get();
        if gp & ROOT != 0 {
            return p;
        }
        uf[x as usize] = U::of(gp);
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

/// The two sweeps' words, seeded with every vertex's link code (the same
/// code in both; see the module documentation), and the candidates and
/// extrema counted.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LinkWords {
    /// The join sweep's words.
    pub join: Leafward,
    /// The split sweep's words.
    pub split: Leafward,
    /// The candidate nodes among the vertices, and the extrema among them.
    pub census: Census,
}

/// True when a vertex with this [`Mesh::link_code`] is a local extremum:
/// its upper or its lower link is empty.
#[inline(always)]
pub fn is_extremum(code: u8) -> bool {
    (code & 0xf) == LINK_EMPTY || (code >> 4) == LINK_EMPTY
}

/// What the link classification tells of a mesh before it is swept: its
/// candidate nodes, and the extrema among them, which bound the supernodes
/// ([`Census::supernodes_at_most`]). The memory model
/// ([`super::peak_bytes`]) is read from it before the sweeps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Census {
    /// Vertices whose link is not one piece above and one below.
    pub candidates: usize,
    /// Vertices with an empty upper or lower link ([`is_extremum`]).
    pub extrema: usize,
}

impl Census {
    /// The most supernodes the contour tree can have. A supernode is a
    /// leaf, which is an extremum, or a node of degree 3 or more (a
    /// candidate with two children or more in a sweep tree), and a tree
    /// with `L` leaves has at most `L - 2` nodes of degree 3 or more: at
    /// most `2L - 2` supernodes with `L` extrema, and never more than the
    /// candidates. On the shared scans this is 0.1-2 % above the real
    /// count (tooth 235,174 for 231,242; colin27_ch2better 245,650 for
    /// 244,260), where half the candidates, the estimate before, was 4-12 %
    /// above it, 74 % on a noisy 1024³ scan, and on aneurism 31 % below
    /// (37,597 for 54,197). A mesh that does not summarise its links
    /// reports no extrema: then every candidate counts.
    pub fn supernodes_at_most(&self) -> usize {
        if self.extrema >= 2 {
            self.candidates.min(2 * self.extrema - 2)
        } else {
            self.candidates
        }
    }
}

/// [`LinkWords`]: [`link_codes`] without an array of codes, 64 Ki
/// vertices at a time on every core. The words start in 3 bytes each
/// (the candidates are counted as the codes are written) and are widened
/// in place if the candidates are too many for that ([`leafward`]).
pub fn link_words<M: Mesh, O: VertexOrder + ?Sized>(mesh: &M, values: &O) -> LinkWords {
    let n = mesh.num_vertices();
    let packed = leafward::packs(0);
    let mut join = Leafward::zeroed(n, packed);
    let mut split = Leafward::zeroed(n, packed);
    let census = with_both_words!(&mut join, &mut split, (j, s) => seed_words(mesh, values, j, s));
    if !leafward::packs(census.candidates) {
        (join, split) = (join.widen(), split.widen());
    }
    LinkWords {
        join,
        split,
        census,
    }
}

/// Writes every vertex's link code to both sweeps' words; returns the
/// candidates and extrema counted.
fn seed_words<M: Mesh, O: VertexOrder + ?Sized, W: Word>(
    mesh: &M,
    values: &O,
    join: &mut [W],
    split: &mut [W],
) -> Census {
    const CHUNK: usize = 1 << 16;
    join.par_chunks_mut(CHUNK)
        .zip(split.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(c, (j, s))| {
            let mut codes = [0u8; CHUNK];
            let codes = &mut codes[..j.len()];
            mesh.link_codes_into(values, (c * CHUNK) as u32, codes);
            for ((j, s), &code) in j.iter_mut().zip(s.iter_mut()).zip(codes.iter()) {
                *j = W::of(code as u32);
                *s = W::of(code as u32);
            }
            census_of_codes(codes)
        })
        .reduce(Census::default, |a, b| a + b)
}

/// The candidates and extrema among these link codes.
fn census_of_codes(codes: &[u8]) -> Census {
    codes.iter().fold(Census::default(), |c, &code| Census {
        candidates: c.candidates + is_candidate(code) as usize,
        extrema: c.extrema + is_extremum(code) as usize,
    })
}

impl std::ops::Add for Census {
    type Output = Census;
    fn add(self, other: Census) -> Census {
        Census {
            candidates: self.candidates + other.candidates,
            extrema: self.extrema + other.extrema,
        }
    }
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
