//! Divide and conquer: the join and split trees computed block by block on
//! every core and glued along the cuts (Pascucci and Cole-McLaughlin,
//! "Parallel computation of the topology of level sets", §4: a tree per
//! block, then the trees of neighbouring blocks joined through the
//! vertices they share).
//!
//! **Blocks.** The vertices are cut into blocks of consecutive ids (on a
//! grid, slabs of planes). An edge joins ids at most [`Mesh::edge_span`]
//! apart (one plane, one row and one step on a Freudenthal grid), so only
//! the vertices within that distance of a cut, the block's *band*, can have
//! neighbours in another block.
//!
//! **1. A sweep per block** ([`sweep::sweep`], both directions of every
//! block at once): the union-find sweep of Carr, Snoeyink and Axen on the
//! edges inside the block, whose *nodes* are its candidates and its band
//! (every band vertex unites with all its swept neighbours in the block, as
//! the paper's sweep does; a candidate inside uses its link components).
//! It records each node's parent in the block's join (or split) tree on its
//! nodes and, for every other vertex, the last node of the component it
//! joined, exactly as the whole sweep does. Each block reads the whole
//! vertex order for its own vertices: a packed order (8-bit values) is
//! read only in the runs of the block's ids, the others skipped undecoded
//! ([`crate::field::PackedOrder::read_within`]); plain ids are filtered.
//! Decoding all of it in each of 8 blocks had made colin27_ch2better's
//! block sweeps 2.5 times the whole sweeps' work (1.32 s against 0.53 on
//! one thread). A block tree is a join tree on its nodes, so two nodes are
//! in one superlevel component of the block exactly when they are in one
//! component of the tree edges above that level.
//!
//! **2. The glue.** The union of the block trees and of the mesh edges that
//! cross a cut (both ends are band vertices, hence nodes) is a graph on all
//! the nodes whose superlevel components, restricted to the nodes, are
//! those of the whole mesh. One more sweep over this graph, the nodes in
//! the vertex order (the blocks' sorted node lists merged), gives the join
//! tree of the whole mesh on the nodes. A band vertex that is not a
//! candidate has one component above it in the whole mesh, so it joins one
//! component and is contracted away: the candidates' parents, their
//! children counts, their numbers in the vertex order and the last
//! candidate of each component come out exactly as the whole sweep makes
//! them.
//!
//! What of the glue runs on every core: each block's tree edges are listed
//! per node on its own core, and the table step 3 climbs is made on all of
//! them. The sweep and the pass that makes the jump pointers (below) are
//! sequential, one per direction, both directions at once. The sweep looks
//! up, for a band vertex that is not a candidate, only one of the
//! components it joins: its upper link (lower, in the split tree) is one
//! piece in the whole mesh, so all of them are one already. Such vertices
//! are three quarters of colin27_ch2better's nodes in 8 blocks; there (one
//! thread) that took the sweep from 40-42 to 31-35 ms per direction, and
//! the sequential part of the glue is about 43 ms per direction, where all
//! of it was 73-80.
//!
//! **3. Every other vertex**, in parallel in id order: its block gave it
//! `x`, the last node of its component in the block when it was swept. In
//! the glued tree its component at that moment is the subtree of the last
//! ancestor `y` of `x` still swept before it, and its leafward candidate is
//! the lowest candidate of that subtree, kept per node by the glue. The
//! path from `x` to `y` crosses the bands of every block the component
//! reaches, but only its candidates matter: the band vertices on it are
//! contracted, so the answer is the lowest candidate below `x` unless a
//! candidate ancestor is swept before the vertex; the search climbs the
//! chain of candidate ancestors, whose first ones (those swept before the
//! vertex) are what it passes. One step at a time it took no steps on
//! smooth fields but about 11 a vertex and direction on scans (colin27_ch2
//! and white noise in 2 blocks), whose big components span the blocks:
//! half the blocked sweeps' time. So each node also keeps a jump pointer
//! up its chain (Myers' skew-binary pointers, one word per node), and the
//! search takes O(log depth) steps: on one thread colin27_ch2's blocked
//! sweeps went from 0.58-0.75 to 0.36-0.39 s in 2 blocks and white noise
//! 192³'s from 13.0 to 3.8 s in 8.
//!
//! The result is the [`JoinTree`] and [`SplitTree`] of the whole sweep,
//! word for word (the tests compare them), so merge and augmentation do not
//! know blocks were used.
//!
//! **Memory.** The per-vertex words are those of the whole sweep (3 bytes
//! per vertex and direction, or 4 where a block has 2^23 nodes or more:
//! a block numbers its nodes in its words); the blocks' union-finds are
//! per node, as the whole sweep's are per candidate. The glue holds 57-73
//! bytes per node at its peak, both directions at once (measured on tooth
//! in 2 and 8 blocks, before the glue read the edges across the cuts in
//! place of a sorted copy: 8 bytes per such edge less now): per direction
//! each node's block-tree children, threaded through two arrays (the
//! block trees are let go once they are), the edges across the cuts (each
//! block's, in node order), its union-find, each node's parent (in the
//! first child's slot once the node is visited) and lowest candidate, and
//! the candidates' parents and child counts; shared, the nodes' vertices,
//! order and flags. Once the lists and the union-find are let go, each
//! node's nearest candidate ancestor, lowest candidate and jump pointer
//! lie side by side (12 bytes, and the span of each jump while the
//! pointers are made): the peak of the tables above is unchanged. All of
//! it is released before the merge, and the free pages of the
//! allocator's heaps go back to the system ([`crate::pages::trim_freed`]).
//! Bands cost two planes per cut: 2 (B - 1) X Y nodes for B blocks, about
//! 1.5 % of a 512³ volume cut in 8.
//!
//! So blocks cost little on smooth fields (few nodes) and much on noisy
//! scans, where the candidates are a third of the vertices: tooth peaks at
//! 29 bytes per vertex beyond the values in 2 blocks and 39 in 8, against
//! 13.6 swept whole (39 and 48 before the glue's tables were cut). The
//! build sweeps the whole mesh instead wherever the glue would not fit in
//! the memory left (`GLUE_BYTES_PER_NODE` and `GLUE_BYTES_PER_BAND_VERTEX`
//! in [`super`]): the same trees, on two cores. It also sweeps whole on
//! fewer than [`MANY_CORES`] threads where more than one vertex in
//! [`NOISY_SHARE`] is a candidate ([`pay`]): there the glue, one core per
//! direction, costs more than the blocks save (the sweeps of tooth,
//! engine and white noise 15-18 % slower in 2 blocks on 4 cores, set out
//! from each part's time on one thread), and the peak is twice as
//! high or more. `flexiso info` quotes the same model
//! ([`super::peak_bytes_in_blocks`]) for the blocks this machine would
//! use.
//!
//! **Blocks as values.** A block's result is plain data: its node list
//! (vertex ids, ascending), its two block trees (parent and children per
//! node), and per vertex its leafward node. Nothing in it points into
//! another block, and the glue reads of the other blocks only the nodes'
//! vertices, their trees and the band's words. So a block could be computed
//! in another process and sent as these arrays; the glue would then run on
//! the nodes alone, and step 3 on each block where its words live. Only the
//! nodes (candidates and bands) cross the wire: a few per cent of the
//! vertices on smooth fields.

use super::leafward::{self, Leafward, Word, with_both_words, with_words};
use super::sweep::{
    self, Block, BlockTree, CANDIDATE, JoinTree, LinkWords, NONE, ROOT, SplitTree, SweepTree, find,
    link_rank, next_node, union,
};
use crate::field::{OrderView, VertexOrder};
use crate::mesh::Mesh;
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// The join and split trees, each with the time it took.
pub type SweptTrees = ((JoinTree, Duration), (SplitTree, Duration));

/// The band vertices of all blocks `cuts` bounds in a mesh of `n`
/// vertices whose edges span `span` ids: the nodes the blocks add to the
/// candidates.
pub fn band_vertices(cuts: &[u32], n: usize, span: usize) -> usize {
    cuts.windows(2)
        .map(|w| Block::new(w[0], w[1], n, span).band_len())
        .sum()
}

/// Cuts of the ids `0..n` into `blocks` blocks of nearly equal size:
/// `blocks + 1` ids from 0 to n (fewer blocks if there are fewer ids).
pub fn even_cuts(n: usize, blocks: usize) -> Vec<u32> {
    let b = blocks.clamp(1, n.max(1));
    (0..=b).map(|i| (i * n / b) as u32).collect()
}

/// How many blocks the engine cuts a mesh of `n` vertices into by default:
/// enough that the two sweeps of all blocks keep every core busy (one block
/// on two cores or fewer, where the join and split sweeps already run side
/// by side), but no block thinner than 16 bands.
pub fn default_blocks(n: usize, span: usize) -> usize {
    let threads = rayon::current_num_threads();
    if threads <= 2 {
        return 1;
    }
    let thickest = n / (16 * span.max(1));
    threads.div_ceil(2).min(thickest).max(1)
}

/// Whether blocks pay on `threads` cores for a mesh of `n` vertices of
/// which `candidates` are candidate nodes: always on [`MANY_CORES`] or
/// more, and below that only where at most one vertex in
/// [`NOISY_SHARE`] is a candidate. The glue sweeps every candidate on one
/// core per direction, and step 3 climbs further where they are many, so
/// on a noisy scan few cores do not win back what the glue costs, while
/// the blocks double the peak memory or more (tooth on 4 threads: 21.5
/// bytes per vertex in 2 blocks, 11.2 whole). A build that cuts the mesh
/// for the machine sweeps it whole where they do not pay
/// ([`chosen_blocks`]); cuts asked for are swept as asked.
///
/// Measured one part at a time on one thread (session 37, the README),
/// and set out for 4 cores in 2 blocks (each direction's wall time: the
/// block sweeps, sort of the nodes and edges across the cuts over 4
/// cores, the glue on one, step 3 over 2), against one direction's
/// whole sweep (the two run side by side): tooth (31 % candidates) 45
/// ms against 38, engine (12 %) 134 against 115, white noise 192³ (52 %)
/// 951 against 830; but colin27_ch2 (7.4 %) 84 against 94 and
/// colin27_ch2better (1.4 %) 216 against 281-340. On 8 cores in 4 blocks
/// the noisy ones gain too: tooth 34 against 38, engine 102 against 115,
/// white noise 573 against 830.
pub fn pay(threads: usize, n: usize, candidates: usize) -> bool {
    threads >= MANY_CORES || candidates.saturating_mul(NOISY_SHARE) <= n
}

/// The blocks a build cuts a mesh of `n` vertices, `candidates` of them
/// candidate nodes, into on this machine: [`default_blocks`] where they
/// [`pay`], else 1 (the whole mesh).
pub fn chosen_blocks(n: usize, span: usize, candidates: usize) -> usize {
    if pay(rayon::current_num_threads(), n, candidates) {
        default_blocks(n, span)
    } else {
        1
    }
}

/// From this many threads on, blocks pay whatever the candidates ([`pay`]).
pub const MANY_CORES: usize = 6;

/// Below [`MANY_CORES`], blocks pay only where at most one vertex in this
/// many is a candidate ([`pay`]).
pub const NOISY_SHARE: usize = 10;

/// The join and split trees of the whole mesh, computed in the blocks
/// `cuts` defines (`cuts[0] = 0 < cuts[1] < ... = n`) and glued, with the
/// time each took. Identical to [`sweep::join_tree`] and
/// [`sweep::split_tree`], except that in one block the split tree's
/// candidates' vertices are not listed (the caller reads them off its
/// words when it needs them, [`sweep::SweepTree::list_vertices`]). `words`
/// are the sweeps' words seeded with the link codes
/// ([`sweep::link_words`]). In one block, where `parents_in_words`, each
/// candidate's parent is written into its word while sweeping
/// ([`sweep::sweep_parents_in_words`]).
pub fn sweep_trees<M: Mesh, O: VertexOrder + ?Sized>(
    mesh: &M,
    values: &O,
    words: LinkWords,
    order: OrderView<'_>,
    cuts: &[u32],
    parents_in_words: bool,
    progress: &Progress,
) -> Result<SweptTrees, Cancelled> {
    let n = mesh.num_vertices();
    let LinkWords {
        join: mut join_words,
        split: mut split_words,
        census,
    } = words;
    let candidates = census.candidates;
    assert!(
        cuts.first() == Some(&0)
            && cuts.last() == Some(&(n as u32))
            && cuts.windows(2).all(|w| w[0] < w[1]),
        "cuts run from 0 to n, increasing"
    );
    // A vertex id names a union-find root in the same word as its flag.
    if cuts.len() <= 2 && parents_in_words && n <= sweep::ROOT as usize {
        let (mut join, mut split) = (join_words.into_words(), split_words.into_words());
        let (j, s) = rayon::join(
            || {
                let t = Instant::now();
                sweep::sweep_parents_in_words(
                    mesh, values, candidates, true, order, &mut join, progress, true,
                )
                .map(|_| t.elapsed())
            },
            || {
                let t = Instant::now();
                sweep::sweep_parents_in_words(
                    mesh, values, candidates, false, order, &mut split, progress, false,
                )
                .map(|starts| (starts, t.elapsed()))
            },
        );
        let (join_time, (starts, split_time)) = (j?, s?);
        let (join_parent, split_parent) =
            sweep::number_candidates(order, &mut join, &mut split, &starts, candidates);
        return Ok((
            (
                JoinTree(sweep::tree_of_parents(join_parent, join)),
                join_time,
            ),
            (
                SplitTree(sweep::tree_of_parents(split_parent, split)),
                split_time,
            ),
        ));
    }
    if cuts.len() <= 2 {
        let (join, split) = rayon::join(
            || {
                let t = Instant::now();
                sweep::whole(
                    mesh, values, join_words, candidates, true, order, progress, true,
                )
                .map(|s| (JoinTree(s), t.elapsed()))
            },
            || {
                let t = Instant::now();
                sweep::whole(
                    mesh,
                    values,
                    split_words,
                    candidates,
                    false,
                    order,
                    progress,
                    false,
                )
                .map(|s| (SplitTree(s), t.elapsed()))
            },
        );
        return Ok((join?, split?));
    }
    let t = Instant::now();
    let span = mesh.edge_span();
    let blocks: Vec<Block> = cuts
        .windows(2)
        .map(|w| Block::new(w[0], w[1], n, span))
        .collect();
    let nodes_in: Vec<usize> = with_words!(&mut join_words, w => {
        let w = &*w;
        blocks.par_iter().map(|b| b.count_nodes(w)).collect()
    });
    // A block's nodes are numbered in its words: too many for 3 bytes
    // (bands of a mesh with nearly 2^23 candidates), the words widen.
    if join_words.is_packed() && !nodes_in.iter().all(|&k| leafward::packs(k)) {
        (join_words, split_words) = (join_words.widen(), split_words.widen());
    }
    let mut offset = vec![0u32; blocks.len() + 1];
    for (b, &k) in nodes_in.iter().enumerate() {
        offset[b + 1] = offset[b] + k as u32;
    }

    // 1. Both sweeps of every block, all at once.
    let mut join_trees: Vec<BlockTree> = with_both_words!(&mut join_words, &mut split_words, (j, s) => {
        sweep_blocks(mesh, values, order, &blocks, &nodes_in, j, s, progress)
    })?;
    let mut split_trees = join_trees.split_off(blocks.len());
    // The blocks' union-finds, freed in every thread's heap.
    crate::pages::trim_freed();

    // 2. The nodes in the vertex order (each block's list is sorted: the
    // sort merges runs). The split trees' node lists move into one, each
    // let go as it is copied.
    let total_nodes = offset[blocks.len()] as usize;
    let mut node_vertex: Vec<u32> = Vec::with_capacity(total_nodes);
    let mut candidate: Vec<bool> = Vec::with_capacity(total_nodes);
    for t in &mut split_trees {
        node_vertex.extend_from_slice(&std::mem::take(&mut t.vertex));
        candidate.extend_from_slice(&std::mem::take(&mut t.candidate));
    }
    let mut by_order: Vec<u32> = (0..node_vertex.len() as u32).collect();
    by_order
        .par_sort_by(|&a, &b| values.ordering(node_vertex[a as usize], node_vertex[b as usize]));
    progress.check(0, 1)?;
    // The mesh edges across the cuts: (node, neighbour node) with the
    // neighbour above (join) or below (split), from each block's band
    // vertices in the order of their nodes, so that the lists come sorted
    // by node (a sort of them took a third of the glue).
    let block_of = |v: u32| blocks.partition_point(|b| b.hi <= v);
    let (join_crossing, split_crossing): (Vec<_>, Vec<_>) = blocks
        .par_iter()
        .enumerate()
        .map(|(b, block)| {
            let (mut above, mut below) = (Vec::new(), Vec::new());
            let node = |w: u32| offset[block_of(w)] + (split_words.get(w as usize) & !CANDIDATE);
            for gu in offset[b]..offset[b + 1] {
                let u = node_vertex[gu as usize];
                if !block.in_band(u) {
                    continue;
                }
                debug_assert_eq!(node(u), gu);
                mesh.for_each_neighbour(u, |w| {
                    if !block.contains(w) {
                        debug_assert!(
                            split_words.get(w as usize) & CANDIDATE != 0,
                            "a band vertex is a node"
                        );
                        if values.above(w, u) {
                            above.push((gu, node(w)));
                        } else {
                            below.push((gu, node(w)));
                        }
                    }
                });
            }
            (above, below)
        })
        .unzip();
    let gluing = Gluing {
        values,
        candidates,
        blocks: &blocks,
        offset: &offset,
        node_vertex: &node_vertex,
        candidate: &candidate,
        by_order: &by_order,
    };
    // 2 and 3, each direction on its own: its glue, then every vertex's
    // final word, on the cores the other glue leaves idle (a glue is one
    // sequential pass); each lets its edges across go once glued.
    let glue_and_place = |join: bool,
                          trees: Vec<BlockTree>,
                          crossing: Vec<Vec<(u32, u32)>>,
                          words: &mut Leafward| {
        let glued = gluing.glue(join, trees, &crossing);
        drop(crossing);
        if !progress.is_cancelled() {
            with_words!(words, w => gluing.place(join, &glued, w));
        }
        (glued.parent, glued.children, glued.vertex)
    };
    let ((join_parent, join_children, _), (split_parent, split_children, split_vertex)) =
        rayon::join(
            || glue_and_place(true, join_trees, join_crossing, &mut join_words),
            || glue_and_place(false, split_trees, split_crossing, &mut split_words),
        );
    progress.check(0, 1)?;
    drop((node_vertex, candidate, by_order));
    crate::pages::trim_freed();
    let elapsed = t.elapsed();
    let join = SweepTree {
        parent: join_parent,
        children: join_children,
        leafward: join_words,
        vertex: Vec::new(),
    };
    let split = SweepTree {
        parent: split_parent,
        children: split_children,
        leafward: split_words,
        vertex: split_vertex,
    };
    Ok(((JoinTree(join), elapsed), (SplitTree(split), elapsed)))
}

/// Step 1: the join and split sweeps of every block, all at once; the
/// join trees first, then the split trees, block by block.
#[allow(clippy::too_many_arguments)]
fn sweep_blocks<M: Mesh, O: VertexOrder + ?Sized, W: Word>(
    mesh: &M,
    values: &O,
    order: OrderView<'_>,
    blocks: &[Block],
    nodes_in: &[usize],
    join_words: &mut [W],
    split_words: &mut [W],
    progress: &Progress,
) -> Result<Vec<BlockTree>, Cancelled> {
    let mut tasks: Vec<(bool, usize, &mut [W])> = Vec::with_capacity(2 * blocks.len());
    for (join, words) in [(true, join_words), (false, split_words)] {
        let mut rest = words;
        for (b, block) in blocks.iter().enumerate() {
            let (head, tail) = rest.split_at_mut((block.hi - block.lo) as usize);
            tasks.push((join, b, head));
            rest = tail;
        }
    }
    tasks
        .into_par_iter()
        .map(|(join, b, words)| {
            if progress.is_cancelled() {
                return Err(Cancelled);
            }
            let tree = sweep::sweep::<M, O, W, u32, true>(
                mesh,
                values,
                nodes_in[b],
                join,
                order,
                blocks[b],
                words,
                !join,
                progress,
                join && b == 0,
            );
            if progress.is_cancelled() {
                return Err(Cancelled);
            }
            tree
        })
        .collect()
}

/// What the glue of one direction leaves.
struct Glued {
    /// Per candidate: its parent candidate, `NONE` at the root.
    parent: Vec<u32>,
    /// Per candidate: its number of children.
    children: Vec<u8>,
    /// The candidates' vertices, ascending (split direction only).
    vertex: Vec<u32>,
    /// Per node: its nearest candidate ancestor in the glued tree (the
    /// tree of the nodes: a node's parent absorbed its component while it
    /// was the component's last node), `NONE` if it has none; the lowest
    /// candidate of its subtree (join) / highest (split), by number, with
    /// [`CANDIDATE`] set where the node is itself a candidate (its word
    /// once glued); and a jump pointer up its chain of candidate
    /// ancestors. Step 3 climbs through the first and third and reads the
    /// second where it stops.
    ancestor_lowest_jump: Vec<[u32; 3]>,
}

/// The fields of [`Glued::ancestor_lowest_jump`].
const ANCESTOR: usize = 0;
const LOWEST: usize = 1;
const JUMP: usize = 2;

/// What both glues read.
struct Gluing<'a, O: ?Sized> {
    values: &'a O,
    candidates: usize,
    blocks: &'a [Block],
    /// Node `offset[b] + i` is node `i` of block `b`.
    offset: &'a [u32],
    node_vertex: &'a [u32],
    /// Per node: whether it is a candidate.
    candidate: &'a [bool],
    /// All nodes, ascending in the vertex order.
    by_order: &'a [u32],
}

impl<O: VertexOrder + ?Sized> Gluing<'_, O> {
    /// True if `u` is swept before `v` in this direction.
    fn before(&self, join: bool, u: u32, v: u32) -> bool {
        if join {
            self.values.above(u, v)
        } else {
            self.values.above(v, u)
        }
    }

    /// The sweep over all nodes: block tree edges and the mesh edges that
    /// cross a cut (`crossing[b]`: (node, neighbour swept before it) for
    /// the band of block `b`). The block trees are let go once their edges
    /// are listed per node, and the lists and the union-find before each
    /// node's nearest candidate ancestor is found.
    fn glue(&self, join: bool, trees: Vec<BlockTree>, crossing: &[Vec<(u32, u32)>]) -> Glued {
        let k = self.node_vertex.len();
        // Per node, the nodes it is joined to and that are swept before it:
        // its children in its block's tree, threaded through `link` (a
        // node's first child until it is visited, then its parent in the
        // glued tree) and `sibling`; its neighbours across a cut, in its
        // block's list at that block's cursor (below).
        let mut link = vec![NONE; k];
        let mut sibling = vec![NONE; k];
        // Each block's on its own core: a block's tree joins its own nodes.
        let mut parts = Vec::with_capacity(trees.len());
        let (mut link_rest, mut sibling_rest) = (&mut link[..], &mut sibling[..]);
        for (b, t) in trees.into_iter().enumerate() {
            let m = t.parent.len();
            let (l, link_tail) = link_rest.split_at_mut(m);
            let (s, sibling_tail) = sibling_rest.split_at_mut(m);
            (link_rest, sibling_rest) = (link_tail, sibling_tail);
            parts.push((self.offset[b], t, l, s));
        }
        parts.into_par_iter().for_each(|(base, t, link, sibling)| {
            for (c, &p) in t.parent.iter().enumerate() {
                if p != NONE {
                    sibling[c] = link[p as usize];
                    link[p as usize] = base + c as u32;
                }
            }
        });
        // Per block, a cursor into its edges across the cuts (listed in node
        // order): the sweep visits each block's nodes in their order, so a
        // node's edges are at its block's cursor (split: from the front;
        // join: from the back). A binary search of one sorted list per
        // node, with a bit per node that had any, took 60 % of the sweep:
        // one thread, 8 blocks, colin27_ch2better's glue sweep took 0.13 s
        // per direction, now 0.05 (`synthetic:256` 0.11 and 0.03).
        debug_assert!(crossing.iter().all(|c| c.is_sorted_by_key(|&(g, _)| g)));
        let mut cursor: Vec<usize> = crossing
            .iter()
            .map(|c| if join { c.len() } else { 0 })
            .collect();
        let mut reps: Vec<u32> = Vec::with_capacity(16);

        let mut uf = vec![NONE; k];
        let mut lowest = vec![NONE; k];
        let mut parent = vec![NONE; self.candidates];
        let mut children = vec![0u8; self.candidates];
        let mut vertex = Vec::with_capacity(if join { 0 } else { self.candidates });
        let mut next: u32 = if join { self.candidates as u32 } else { 0 };
        // A node's block: the inner cuts at or below its number, counted
        // without branches (a binary search of the offsets per node took
        // 8 % of the sweep).
        let inner_cuts = &self.offset[1..self.offset.len() - 1];
        let visit: Box<dyn Iterator<Item = &u32>> = if join {
            Box::new(self.by_order.iter().rev())
        } else {
            Box::new(self.by_order.iter())
        };
        for &g in visit {
            let first_child = std::mem::replace(&mut link[g as usize], NONE);
            let b: usize = inner_cuts.iter().map(|&o| usize::from(o <= g)).sum();
            let edges = &crossing[b];
            let at = &mut cursor[b];
            let across = if join {
                let end = *at;
                while *at > 0 && edges[*at - 1].0 == g {
                    *at -= 1;
                }
                &edges[*at..end]
            } else {
                let start = *at;
                while *at < edges.len() && edges[*at].0 == g {
                    *at += 1;
                }
                &edges[start..*at]
            };
            uf[g as usize] = ROOT | g;
            if !self.candidate[g as usize] {
                // Regular in the whole mesh: its upper link (lower, in the
                // split tree) is one piece of swept vertices, so all it is
                // joined to is one component already, and one of them names
                // it (the module documentation says what that saves). The
                // vertex is contracted away.
                let x = if first_child != NONE {
                    first_child
                } else {
                    across.first().map_or(NONE, |&(_, w)| w)
                };
                debug_assert_ne!(
                    x, NONE,
                    "a band vertex that is not a candidate joins one component"
                );
                if x != NONE {
                    let r = find(&mut uf, x);
                    let last = uf[r as usize] & !ROOT;
                    // Visited: its slot of `link` now holds its parent.
                    link[last as usize] = g;
                    lowest[g as usize] = lowest[last as usize];
                    union(&mut uf, g, r, g, link_rank(g) > link_rank(r));
                }
                #[cfg(debug_assertions)]
                {
                    let root = find(&mut uf, g);
                    let mut c = first_child;
                    while c != NONE {
                        assert_eq!(
                            find(&mut uf, c),
                            root,
                            "one component beyond a regular vertex"
                        );
                        c = sibling[c as usize];
                    }
                    for &(_, w) in across {
                        assert_eq!(
                            find(&mut uf, w),
                            root,
                            "one component beyond a regular vertex"
                        );
                    }
                }
                continue;
            }
            reps.clear();
            let mut child = first_child;
            while child != NONE {
                reps.push(child);
                child = sibling[child as usize];
            }
            reps.extend(across.iter().map(|&(_, w)| w));
            let kid = next_node(&mut next, join);
            let mut root = g;
            let mut merged = 0u8;
            for &x in &reps {
                let r = find(&mut uf, x);
                if r == root {
                    continue;
                }
                let last = uf[r as usize] & !ROOT;
                // Visited: its slot of `link` now holds its parent.
                link[last as usize] = g;
                parent[lowest[last as usize] as usize] = kid;
                merged += 1;
                root = union(&mut uf, root, r, g, link_rank(root) > link_rank(r));
            }
            lowest[g as usize] = kid;
            children[kid as usize] = merged;
            if !join {
                vertex.push(self.node_vertex[g as usize]);
            }
        }
        debug_assert_eq!(next, if join { 0 } else { self.candidates as u32 });
        debug_assert!(
            cursor
                .iter()
                .zip(crossing)
                .all(|(&at, c)| at == if join { 0 } else { c.len() }),
            "every edge across a cut was read at its node"
        );
        drop((sibling, uf));
        // Each node's nearest candidate ancestor, root first (a parent
        // before its children), written over its parent: step 3 climbs
        // from candidate to candidate. Beside it a jump pointer up the
        // same chain (Myers' skew-binary pointers: a node jumps where its
        // ancestor's jump jumps when the two jumps span equal numbers of
        // ancestors, else to that ancestor), so that the climb takes
        // O(log depth) steps. The pass keeps the number of ancestors each
        // jump spans (not the depths: two reads per node, not three) and
        // finds the candidates by their flag beside their lowest candidate
        // (one thread, 8 blocks: colin27_ch2better's pass 24-26 -> 20-21
        // ms per direction). The spans lie apart, let go after the pass:
        // beside the jumps they were 4 bytes more per node when the table
        // is made from the parents and lowest candidates, the glue's peak.
        let mut ancestor_lowest_jump: Vec<[u32; 3]> = link
            .par_iter()
            .zip(&lowest)
            .zip(self.candidate)
            .map(|((&p, &l), &c)| [p, if c { CANDIDATE | l } else { l }, NONE])
            .collect();
        drop((link, lowest));
        let mut span = vec![0u32; k];
        let root_first: Box<dyn Iterator<Item = &u32>> = if join {
            Box::new(self.by_order.iter())
        } else {
            Box::new(self.by_order.iter().rev())
        };
        for &g in root_first {
            let g = g as usize;
            let p = ancestor_lowest_jump[g][ANCESTOR];
            if p == NONE {
                continue;
            }
            let parent = ancestor_lowest_jump[p as usize];
            let a = if parent[LOWEST] & CANDIDATE != 0 {
                p
            } else {
                parent[ANCESTOR]
            };
            ancestor_lowest_jump[g][ANCESTOR] = a;
            if a == NONE {
                continue;
            }
            let (a, j) = (a as usize, ancestor_lowest_jump[a as usize][JUMP]);
            let jj = if j == NONE {
                NONE
            } else {
                ancestor_lowest_jump[j as usize][JUMP]
            };
            let (jump, spans) = if jj != NONE && span[j as usize] == span[a] {
                (jj, 1 + 2 * span[a])
            } else {
                (a as u32, 1)
            };
            ancestor_lowest_jump[g][JUMP] = jump;
            span[g] = spans;
        }
        Glued {
            parent,
            children,
            vertex,
            ancestor_lowest_jump,
        }
    }

    /// Step 3: every vertex's word, from its block's word and the glue.
    fn place<W: Word>(&self, join: bool, glued: &Glued, words: &mut [W]) {
        const CHUNK: usize = 1 << 16;
        let mut rest = words;
        for (b, block) in self.blocks.iter().enumerate() {
            let (mine, tail) = rest.split_at_mut((block.hi - block.lo) as usize);
            rest = tail;
            let base = self.offset[b];
            mine.par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(c, chunk)| {
                    let first = block.lo + (c * CHUNK) as u32;
                    for (i, word) in chunk.iter_mut().enumerate() {
                        let w = word.get();
                        if w & CANDIDATE != 0 {
                            // A node: a candidate's own number, flagged,
                            // or the lowest candidate a band vertex joined.
                            let g = (base + (w & !CANDIDATE)) as usize;
                            *word = W::of(glued.ancestor_lowest_jump[g][LOWEST]);
                            continue;
                        }
                        let v = first + i as u32;
                        // The last ancestor y of x swept before v: no candidate
                        // lies between x and y unless the nearest candidate
                        // ancestor of x is swept before v too, and then the
                        // search goes on from there. Below x, up to a
                        // candidate, every node is a contracted band vertex
                        // of one child, so y's lowest candidate is x's.
                        // The ancestors swept before v are a prefix of the
                        // chain: a jump to one of them skips only such.
                        let mut x = base + w;
                        let before = |g: u32| self.before(join, self.node_vertex[g as usize], v);
                        let lowest = loop {
                            let [c, lowest, j] = glued.ancestor_lowest_jump[x as usize];
                            if c == NONE || !before(c) {
                                break lowest & !CANDIDATE;
                            }
                            x = if j != c && before(j) { j } else { c };
                        };
                        *word = W::of(lowest);
                    }
                });
        }
    }
}
