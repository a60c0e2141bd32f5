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
//! **Reduction first, on noisy scans.** About half the candidates of a
//! scan have one child in each tree (a change of genus, or a vertex whose
//! upper link pieces meet above it): they are supernodes of neither tree.
//! Where they are at least 1/8 of the vertices, they are reduced out of
//! both trees before the merge (Def. 4.5; by Theorem 4.8 the reduced trees
//! are the join and split trees of the tree on the rest), and each record
//! is renumbered in one parallel pass to the nearest supernode leafward
//! ([`reduce_regular_candidates`]). The merge then runs on the supernodes
//! alone and the placement places a reduced candidate like any other
//! vertex of degree two in both trees. Below that share the merge on all
//! candidates is not the build's peak, and the two passes over the records
//! would cost more than they save.
//!
//! **Supernodes and superarcs.** Supernodes are the candidates with other
//! than one child in each tree. The candidates are numbered in a pre-order
//! of the rooted tree (`tin`, and `tout` past their subtree) and each
//! candidate's edge to its parent is labelled with its superarc: the edges
//! through a candidate that is not a supernode belong to one superarc. No
//! depth-first search is needed: the order in which Fig. 9 cut the
//! candidates lists each one after its children (it was a leaf when cut),
//! so one pass in that order sums the subtree sizes and one in the reverse
//! order, from the root down, gives each child the next free range inside
//! its parent's and the label of the edge above it (both passes fetch the
//! entries they will need a few candidates ahead: the order is known).
//! The superarcs are then numbered in the tree's canonical order, by lower
//! end and then upper end, by counting: a node is the lower end of as many
//! superarcs as it has up ([`canonical_arc_ids`]; on white noise a
//! comparison sort and the permutation's cycles took half the merge).
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
//! `A` and `B` come from the parents alone: visiting the candidates from
//! the highest down, those visited so far hang from the others in chains,
//! and `A(x)` is the top of `x`'s chain when `x` is visited (a find with
//! path compression; `B` the same from the lowest up). Nearly O(c) for c
//! candidates and 4 bytes each beside the answers: the monotone stacks of
//! a depth-first pass (restored as it backs up) would cost 24 bytes per
//! level of a path that, on a noisy scan, is about as long as the
//! candidates are many. Per vertex the rule reads `a`, `b` (sequentially,
//! in id order), then `A(a)`, `B(b)` and the records of `A(a)`, `b` and
//! `B(b)`: no walk, no order.
//!
//! **Memory** (n vertices, c candidates, s supernodes, beyond the values):
//! 6 bytes per vertex (the two leafward records, 3 bytes each where the
//! candidates are fewer than 2^23, else 8) and, at the merge's peak
//! (the chains), 24 per candidate (the parents, the chain pointers and
//! answers, the subtree entries; one bit for "is a supernode" with a
//! count per 64 in place of a table of supernode numbers) plus 12 per
//! supernode (its vertex and its superarc, 8 bytes, allocated at their
//! exact size). The supernodes themselves ([`Node`], 8 bytes with their
//! degrees) are made only once every vertex is placed, from their
//! vertices and the superarcs (a node's degree up is the superarcs whose
//! lower end it is): 4 bytes per supernode less through the merge and
//! the placement than while they were made first (session 39). Where at
//! least one vertex in 8 is a candidate (a noisy scan, where the merge can
//! be the build's peak) the candidates' numbers are held in 3 bytes each
//! ([`Id3`], [`leafward::packs_tables`]): 18 per candidate, not 24.
//! Elsewhere they stay in words: there they are no part of the peak, and
//! the placement, which reads them for every vertex, took 25-40 % longer
//! packed (colin27_ch2better 0.14 -> 0.20 s). About half the candidates
//! of a scan are supernodes: 30 per candidate by this count (32 before
//! session 39; 37-41 measured then on tooth, engine and colin27_ch2, 56
//! with the depth-first pass and a table of supernode numbers). The cut
//! order shares one array with the stack of leaves waiting to be cut, and
//! then with the superarcs' canonical order, counted before the chains
//! rather than beside them; the superarcs are made in place from their
//! ends. Where
//! the reduction runs, the merge's candidates are the supernodes (30 per
//! supernode packed, 34.7 measured on tooth, where it held 40 before
//! session 39; the memory model counts a quarter more than the tables:
//! `tree::merge_bytes`), and the reduction itself holds 14 per candidate
//! (both trees' parents and child counts, the candidates' vertices, one
//! map of 4 bytes) and 8 per supernode: on tooth (31 % candidates, 15 %
//! supernodes) 6 + 5.1 bytes per vertex at the merge (6 + 5.9 before
//! session 39, 6 + 13.6 before the reduction).
//!
//! Finally the regular vertices of each superarc are laid out in the vertex
//! order by one counting pass over the order (the one pass that reads the
//! vertices in value order; it only reads their superarc). An order of 4
//! bytes per vertex that the grouping owns is read from its end in slabs
//! and given back slab by slab, so that it and the arcs' vertex lists
//! hold 4 bytes per vertex together, not 8 ([`group_owned`]); 3, not 6,
//! for at most 2^24 vertices, whose order and lists both take 3 bytes per
//! id ([`super::ArcVertices`]).

use super::arc_vertices::{Entry, VertexLists};
use super::leafward::{self, Leafward, Word, with_entries, with_words};
use super::sweep::{CANDIDATE, JoinTree, NONE, SplitTree, prefetch};
use super::{ContourTree, Node, NodeId, Superarc};
use crate::field::{Order, OrderView, VertexOrder};
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;

/// Marks a node in `vertex_arc`.
pub(super) const NODE_FLAG: u32 = 1 << 31;

/// The contour tree on the candidates, as the merge leaves it: what placing
/// the other vertices needs.
pub struct CandidateTree {
    /// Per supernode: its vertex (the supernodes themselves, with their
    /// degrees, are made once the placement is done: [`place`]).
    node_vertex: Vec<u32>,
    arcs: Vec<Superarc>,
    /// Which candidates are supernodes, and their numbers.
    supernodes: Supernodes,
    /// The candidates' tables, in 3 bytes per number or 4.
    tables: Tables,
}

/// The candidates' tables the placement reads, in 3 bytes per number
/// where they are packed ([`leafward::packs_tables`]), else 4.
pub(super) enum Tables {
    Words(Chains<u32>),
    Packed(Chains<Id3>),
}

/// What the placement reads of each candidate.
pub(super) struct Chains<I> {
    /// Per candidate `a`: A(a) (`NONE` at the root).
    a_of: Vec<I>,
    /// Per candidate `b`: B(b) (`NONE` if it has none).
    b_of: Vec<I>,
    /// Per candidate: its subtree's pre-order range and the superarc of
    /// the edge above it (`NONE` at the root).
    subtree: Vec<[I; 3]>,
}

/// A candidate's number (or a pre-order position, or a superarc) as the
/// merge's tables hold it: a word, or 3 bytes on a noisy scan
/// ([`leafward::packs_tables`]; as the sweeps' records are packed, but
/// with all ones for `NONE`).
pub(super) trait Id: Copy + Send + Sync + std::fmt::Debug {
    /// The number, or `NONE`.
    fn get(self) -> u32;
    /// Stores `x` (below [`Id3::NONE`], or `NONE`, if packed).
    fn of(x: u32) -> Self;
    /// The tables the placement reads, in this width.
    fn tables(chains: Chains<Self>) -> Tables;
    /// A spare allocation of words to hold these: itself for words, none
    /// for 3 bytes (an allocation is not reused for another type).
    fn spare(words: Vec<u32>) -> Vec<Self>;
}

impl Id for u32 {
    #[inline(always)]
    fn get(self) -> u32 {
        self
    }

    #[inline(always)]
    fn of(x: u32) -> Self {
        x
    }

    fn tables(chains: Chains<Self>) -> Tables {
        Tables::Words(chains)
    }

    fn spare(words: Vec<u32>) -> Vec<Self> {
        words
    }
}

/// A number in 3 bytes, little end first; all ones stands for `NONE`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub(super) struct Id3([u8; 3]);

impl Id3 {
    /// The 3-byte pattern of `NONE`: numbers below it fit.
    pub(super) const NONE: u32 = (1 << 24) - 1;
}

impl Id for Id3 {
    #[inline(always)]
    fn get(self) -> u32 {
        let e = u32::from_le_bytes([self.0[0], self.0[1], self.0[2], 0]);
        // All ones (only `NONE`'s pattern carries into bit 24) widened to
        // `NONE`, without a branch.
        e | ((e + 1) >> 24).wrapping_neg()
    }

    #[inline(always)]
    fn of(x: u32) -> Self {
        debug_assert!(x < Self::NONE || x == NONE);
        let b = x.to_le_bytes();
        Id3([b[0], b[1], b[2]])
    }

    fn tables(chains: Chains<Self>) -> Tables {
        Tables::Packed(chains)
    }

    fn spare(_: Vec<u32>) -> Vec<Self> {
        Vec::new()
    }
}

/// Merges the join and split trees (see the module documentation).
/// `candidate_vertex` lists the candidates' vertices, ascending, and
/// `supernode` which of them are supernodes ([`Supernodes::of_trees`]).
/// Arrays are dropped as soon as they are used up: on white noise about
/// half the vertices are candidates. The candidates' tables are held in 3
/// bytes per number where `packed` ([`leafward::packs_tables`]) and they
/// fit: every pre-order position and superarc number is at most the
/// candidates' count, below [`Id3::NONE`].
pub fn merge(
    join: JoinTree,
    split: SplitTree,
    candidate_vertex: Vec<u32>,
    supernode: Supernodes,
    packed: bool,
    progress: &Progress,
) -> Result<CandidateTree, Cancelled> {
    if packed && candidate_vertex.len() < Id3::NONE as usize {
        merge_in::<Id3>(join, split, candidate_vertex, supernode, progress)
    } else {
        merge_in::<u32>(join, split, candidate_vertex, supernode, progress)
    }
}

/// [`merge`] with the tables' numbers held as `I`.
fn merge_in<I: Id>(
    join: JoinTree,
    split: SplitTree,
    candidate_vertex: Vec<u32>,
    supernode: Supernodes,
    progress: &Progress,
) -> Result<CandidateTree, Cancelled> {
    let k = candidate_vertex.len();
    let (mut jt_parent, mut jt_up) = (join.0.parent, join.0.children);
    let (mut st_parent, mut st_down) = (split.0.parent, split.0.children);
    debug_assert_eq!(jt_parent.len(), k);

    // The supernodes' vertices, in vertex order (counted first: on a noisy
    // scan about half the candidates, so no vector grown by doubling).
    // Their degrees are counted from the superarcs once the vertices are
    // placed ([`place`]): 4 bytes per supernode through the merge and the
    // placement, not a [`Node`]'s 8.
    debug_assert_eq!(supernode.bits.len(), k.div_ceil(64));
    let node_vertex = supernode.gather(|c| candidate_vertex[c]);
    let supernodes = node_vertex.len();

    // Fig. 9 on the candidates; the global minimum (candidate 0) is last.
    // `cut` holds the candidates cut so far, in the order they were cut,
    // at its front, and the leaves waiting to be cut as a stack at its
    // back: each candidate is in one of the two at most once, so they
    // never meet, and no slot is read before it is written. It takes the
    // vertices' array, which is used up.
    let mut parent = crate::pages::filled(k, I::of(NONE));
    let mut cut = crate::pages::reused(candidate_vertex, k, 0u32);
    let (mut front, mut back) = (0usize, k);
    for c in 1..k {
        if jt_up[c] + st_down[c] == 1 {
            back -= 1;
            cut[back] = c as u32;
        }
    }
    while back < k {
        let x = cut[back];
        back += 1;
        cut[front] = x;
        front += 1;
        if front.is_multiple_of(1 << 20) {
            progress.check(front, k)?;
        }
        let xi = x as usize;
        let y = if jt_up[xi] == 0 {
            // Upper leaf: its edge runs down the join tree.
            let start = jt_parent[xi];
            let y = climb(&mut jt_parent, start, |y, _| {
                parent[y as usize].get() != NONE
            });
            jt_up[y as usize] -= 1;
            y
        } else {
            let start = st_parent[xi];
            let y = climb(&mut st_parent, start, |y, _| {
                parent[y as usize].get() != NONE
            });
            st_down[y as usize] -= 1;
            y
        };
        parent[xi] = I::of(y);
        let yi = y as usize;
        if y != 0 && jt_up[yi] + st_down[yi] == 1 {
            back -= 1;
            cut[back] = y;
        }
    }
    debug_assert_eq!(
        front,
        k.saturating_sub(1),
        "every candidate but the root is cut"
    );
    drop((jt_parent, jt_up, st_parent, st_down));
    progress.check(0, 1)?;

    // Pre-order ranges and superarc labels from the cut order, which lists
    // every candidate after its children (it was a leaf when cut): subtree
    // sizes in that order, then, from the root down in the reverse order,
    // each child takes the next free range inside its parent's. The middle
    // field holds the size, then the parent's next free slot, which ends as
    // `tout`. No children lists and no path as deep as the tree.
    let cut_order = &cut[..front];
    let entry = |[tin, tout, label]: [u32; 3]| [I::of(tin), I::of(tout), I::of(label)];
    let mut subtree = crate::pages::filled(k, entry([0, 1, NONE]));
    let parent_of = |x: u32| parent[x as usize].get();
    // Both passes read, at scattered places, a candidate's parent and
    // entry and its parent's entry: fetched ahead from the known order.
    let ahead = |subtree: &[[I; 3]], far: Option<&u32>, near: Option<&u32>| {
        if let Some(&far) = far {
            prefetch(&parent, far as usize);
            prefetch(subtree, far as usize);
        }
        if let Some(&near) = near {
            prefetch(subtree, parent_of(near) as usize);
        }
    };
    for (i, &x) in cut_order.iter().enumerate() {
        ahead(
            &subtree,
            cut_order.get(i + 2 * READ_AHEAD),
            cut_order.get(i + READ_AHEAD),
        );
        let size = subtree[x as usize][1].get();
        let p = &mut subtree[parent_of(x) as usize][1];
        *p = I::of(p.get() + size);
    }
    // Superarcs as (end towards the root, end away from it), candidates,
    // made into superarcs in place below: one ends at each supernode but
    // the root.
    let mut arcs: Vec<Superarc> = Vec::with_capacity(supernodes.saturating_sub(1));
    if k > 0 {
        subtree[0] = entry([0, 1, NONE]);
    }
    for (i, &x) in cut_order.iter().enumerate().rev() {
        let before = |d: usize| i.checked_sub(d).map(|j| &cut_order[j]);
        ahead(&subtree, before(2 * READ_AHEAD), before(READ_AHEAD));
        let p = parent_of(x);
        let size = subtree[x as usize][1].get();
        let tin = subtree[p as usize][1].get();
        subtree[p as usize][1] = I::of(tin + size);
        let l = if supernode.is_node(p) {
            let (upper, lower) = (NodeId(p), NodeId(NONE));
            arcs.push(Superarc { upper, lower });
            arcs.len() as u32 - 1
        } else {
            subtree[p as usize][2].get()
        };
        subtree[x as usize] = entry([tin, tin + 1, l]);
        if supernode.is_node(x) {
            arcs[l as usize].lower = NodeId(x);
        }
    }
    debug_assert_eq!(arcs.len(), supernodes.saturating_sub(1));
    progress.check(0, 1)?;
    arcs.par_iter_mut().for_each(|arc| {
        let (r, c) = (arc.upper.0, arc.lower.0);
        let (hi, lo) = if r > c { (r, c) } else { (c, r) };
        arc.upper = NodeId(supernode.node(hi));
        arc.lower = NodeId(supernode.node(lo));
    });
    // Superarcs in the tree's canonical order, by (lower, upper), now: the
    // per-vertex arrays are then made in their final form. The count takes
    // the cut order's array, and gives it back for A's pointers; A and B
    // come after, when the new numbers are let go (4 bytes per candidate
    // fewer at the merge's peak than beside them).
    let (new_id, spare) = canonical_arc_ids(&arcs, supernodes, cut);
    subtree.par_iter_mut().for_each(|[_, _, l]| {
        if l.get() != NONE {
            *l = I::of(new_id[l.get() as usize]);
        }
    });
    drop(new_id);
    // The superarcs themselves in that order: sorted in place on every core
    // (following the permutation's cycles instead is a cache miss a swap).
    arcs.par_sort_unstable_by_key(|a| (a.lower, a.upper));
    progress.check(0, 1)?;

    // A and B from the parents; the second takes the parents themselves.
    // A's copy of them goes where the cut order was (in words; packed, in
    // pages of its own), and B's answers where A's pointers were: pages
    // already touched, none faulted in afresh.
    let (a_of, pointers) = chain_tops(
        crate::pages::copied(I::spare(spare), &parent),
        true,
        Vec::new(),
    );
    progress.check(0, 1)?;
    let (b_of, _) = chain_tops(parent, false, pointers);
    progress.check(0, 1)?;
    let chains = Chains {
        a_of,
        b_of,
        subtree,
    };
    Ok(CandidateTree {
        node_vertex,
        arcs,
        supernodes: supernode,
        tables: I::tables(chains),
    })
}

/// Reduces (Def. 4.5) every candidate that is regular in both trees (one
/// child in each: a change of genus, or a vertex whose several upper link
/// pieces meet above it) out of the join and split trees before the merge,
/// and renumbers the rest, the supernodes, in their order. By Theorem 4.8
/// the reduced trees are the join and split trees of the contour tree on
/// the supernodes, so [`merge`] returns the same tree from them, and the
/// placement rule (see the module documentation) places a reduced
/// candidate as it places any vertex of degree two in both trees. The
/// records are renumbered in place: a vertex's leafward candidate becomes
/// the first supernode leafward of it (in the join tree the lowest
/// supernode of its superlevel component, up the one-child chain through
/// reduced candidates; in the split tree the highest of its sublevel
/// component), and a reduced candidate's own entry becomes its leafward
/// supernode in each tree.
///
/// On a noisy scan about half the candidates go (tooth 31 % of the
/// vertices, 15 % supernodes), and every table of the merge that follows
/// is the supernodes' size: about 40 bytes per supernode at its peak
/// instead of 40 per candidate. This step holds 10 bytes per candidate and
/// 9 per supernode: both trees' parents and children, and the supernodes'
/// vertices, new parents and children; each tree's old parents become its leafward
/// supernodes in place ([`reduce_tree`]). It runs when at least one vertex
/// in `share` is a candidate to reduce ([`REDUCED_SHARE`]: where it lowers
/// the peak). Takes the supernodes among the candidates (`kept`,
/// [`Supernodes::of_trees`]) and the candidates' vertices (empty: read
/// off the split tree's record, here only the supernodes') and returns
/// the candidates' vertices and supernodes after it: the supernodes'
/// vertices, all of them supernodes, or every candidate's vertex and
/// `kept` unchanged when it does not run.
pub fn reduce_regular_candidates(
    join: &mut JoinTree,
    split: &mut SplitTree,
    candidate_vertex: Vec<u32>,
    kept: Supernodes,
    join_leafward: &mut Leafward,
    split_leafward: &mut Leafward,
    share: usize,
) -> (Vec<u32>, Supernodes) {
    let k = join.0.parent.len();
    let listed = !candidate_vertex.is_empty() || k == 0;
    if !reduces(join_leafward.len(), k, kept.count(), share) {
        if !listed {
            let all = with_entries!(&*split_leafward, w => super::sweep::candidate_vertices(w, k));
            return (all, kept);
        }
        return (candidate_vertex, kept);
    }
    let vertex = if listed {
        kept.gather(|c| candidate_vertex[c])
    } else {
        with_entries!(&*split_leafward, w => supernode_vertices(w, &kept))
    };
    drop(candidate_vertex);
    for (tree, record) in [(&mut join.0, join_leafward), (&mut split.0, split_leafward)] {
        // Per candidate, its leafward supernode in the tree at hand (a
        // supernode's own number at a supernode), over its old parents.
        let mut leafward_node = std::mem::take(&mut tree.parent);
        tree.parent = reduce_tree(&mut leafward_node, &kept);
        tree.children = kept.gather(|c| tree.children[c]);
        let renumber = |x: u32| {
            let c = x & !CANDIDATE;
            let node = leafward_node[c as usize];
            if x & CANDIDATE != 0 && kept.is_node(c) {
                CANDIDATE | node
            } else {
                node
            }
        };
        with_words!(record, w => w
            .par_chunks_mut(1 << 14)
            .for_each(|w| w.iter_mut().for_each(|e| *e = Word::of(renumber(Word::get(*e))))));
    }
    let all = Supernodes::new(vertex.len(), |_| true);
    (vertex, all)
}

/// True when [`reduce_regular_candidates`] runs on `n` vertices, `k`
/// candidates and `s` supernodes: when at least one vertex in `share` is
/// a candidate it reduces.
pub(super) fn reduces(n: usize, k: usize, s: usize, share: usize) -> bool {
    (k - s).saturating_mul(share) >= n
}

/// The parents of a tree on the supernodes (each supernode's nearest
/// ancestor that is one, numbered as a supernode; `NONE` at the root),
/// from its parents on the candidates, on every core. Each supernode walks
/// down the chain of reduced candidates below it (one child each, so each
/// of them lies on exactly one such chain) and writes itself as their
/// leafward supernode over their parents in `parent`, which becomes the
/// candidates' leafward supernodes.
fn reduce_tree(parent: &mut [u32], kept: &Supernodes) -> Vec<u32> {
    let slots = crate::pages::DisjointSlots::new(parent);
    kept.gather(|c| {
        let node = kept.node(c as u32);
        // SAFETY: a supernode's slot is read and written by its own walk
        // only; a reduced candidate has one child, so one supernode's walk
        // passes it: each slot is read and written by one thread.
        unsafe {
            let mut p = slots.read(c);
            slots.write(c, node);
            while p != NONE && !kept.is_node(p) {
                let below = slots.read(p as usize);
                slots.write(p as usize, node);
                p = below;
            }
            if p == NONE { NONE } else { kept.node(p) }
        }
    })
}

/// The vertices of the supernodes among the candidates, in their order,
/// read off a sweep's words.
fn supernode_vertices<W: Word>(words: &[W], kept: &Supernodes) -> Vec<u32> {
    super::sweep::listed_vertices(words, kept.count(), |c| {
        kept.is_node(c).then(|| kept.node(c))
    })
}

/// How a build sweeps and merges: whether its sweeps write the candidates'
/// parents into their records, which candidates it reduces first and
/// whether its tables may be packed (the tests force each way).
#[derive(Clone, Copy, Debug)]
pub(super) struct Merging {
    /// [`reduce_regular_candidates`] runs when at least one vertex in
    /// this many is a candidate it reduces.
    pub reduce_share: usize,
    /// The tables are held in 3 bytes per number where at least one
    /// vertex in this many is a candidate ([`leafward::packs_tables`]).
    pub packed_share: usize,
    /// Forces [`super::sweep::parents_in_words`] either way (`None`: where
    /// the records are words).
    pub parents_in_words: Option<bool>,
}

/// How a build merges, unless a test says otherwise.
pub(super) const MERGING: Merging = Merging {
    reduce_share: REDUCED_SHARE,
    packed_share: leafward::PACKED_TABLES_SHARE,
    parents_in_words: None,
};

/// [`reduce_regular_candidates`] runs when at least 1 vertex in this many
/// is a candidate it reduces: a merge on all candidates would then hold at
/// least 44 / 8 = 5.5 bytes per vertex for them, beside the records' 6,
/// above the grouping's 8 and the order, so the merge is the build's peak
/// and the reduction lowers it (measured when the merge held 44 bytes per
/// candidate; since session 39 it holds 30-37, and 3.75-4.7 bytes per
/// vertex beside the records' 6 are still above the grouping's 7, 6
/// since its lists narrowed in session 45). Below that the grouping is the peak
/// (measured on engine, 6 % reduced: 10.5 bytes per vertex either way),
/// and the two passes over the records would cost time (engine's merge
/// 0.06 -> 0.10 s) for nothing.
pub(super) const REDUCED_SHARE: usize = 8;

/// Which candidates are supernodes, and each supernode's number (supernodes
/// are numbered in candidate order): one bit per candidate and a count per
/// 64 of them, where a table of numbers would cost 4 bytes per candidate.
pub struct Supernodes {
    bits: Vec<u64>,
    /// Per 64 candidates: the supernodes before them.
    before: Vec<u32>,
}

impl Supernodes {
    /// The candidates of the two trees with other than one child in
    /// either: the supernodes.
    pub fn of_trees(join: &JoinTree, split: &SplitTree) -> Self {
        let (up, down) = (&join.0.children, &split.0.children);
        Self::new(up.len(), |c| up[c] != 1 || down[c] != 1)
    }

    fn new(k: usize, is_node: impl Fn(usize) -> bool + Sync) -> Self {
        let bits: Vec<u64> = (0..k.div_ceil(64))
            .into_par_iter()
            .map(|w| {
                (64 * w..k.min(64 * w + 64))
                    .filter(|&c| is_node(c))
                    .fold(0, |bits, c| bits | 1 << (c % 64))
            })
            .collect();
        let mut count = 0u32;
        let before = bits
            .iter()
            .map(|w| {
                let b = count;
                count += w.count_ones();
                b
            })
            .collect();
        Supernodes { bits, before }
    }

    /// The number of supernodes.
    pub fn count(&self) -> usize {
        self.before.last().map_or(0, |&b| b as usize)
            + self.bits.last().map_or(0, |w| w.count_ones() as usize)
    }

    /// `f(c)` for every supernode `c`, in candidate order, on every core.
    fn gather<T: Copy + Default + Send + Sync>(&self, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
        let mut out = crate::pages::filled(self.count(), T::default());
        let slots = crate::pages::DisjointSlots::new(&mut out);
        self.bits.par_iter().enumerate().for_each(|(w, &bits)| {
            let (mut bits, mut i) = (bits, self.before[w] as usize);
            while bits != 0 {
                let c = 64 * w + bits.trailing_zeros() as usize;
                // SAFETY: supernode c's number, i, is the slot of no other.
                unsafe { slots.write(i, f(c)) };
                bits &= bits - 1;
                i += 1;
            }
        });
        out
    }

    #[inline]
    fn is_node(&self, c: u32) -> bool {
        self.bits[c as usize / 64] & (1 << (c % 64)) != 0
    }

    /// The number of supernode `c`.
    #[inline]
    fn node(&self, c: u32) -> u32 {
        let (w, b) = (c as usize / 64, c % 64);
        self.before[w] + (self.bits[w] & ((1u64 << b) - 1)).count_ones()
    }
}

/// Each superarc's number in the canonical order, by lower end and then
/// upper end, without a comparison sort: counting the superarcs of each
/// of the `nodes` lower ends places each superarc among those of its
/// lower end, and those few (one per arc up from a saddle) are then
/// ordered by their upper ends. The canonical order is listed in `spare`'s
/// allocation, given back with the numbers.
fn canonical_arc_ids(arcs: &[Superarc], nodes: usize, spare: Vec<u32>) -> (Vec<u32>, Vec<u32>) {
    let lower = |a: u32| arcs[a as usize].lower;
    let upper = |a: u32| arcs[a as usize].upper;
    // Each lower end's count, then where its superarcs start.
    let mut next = vec![0u32; nodes];
    for arc in arcs {
        next[arc.lower.0 as usize] += 1;
    }
    let mut first = 0u32;
    for slot in &mut next {
        let count = *slot;
        *slot = first;
        first += count;
    }
    // The superarcs in the canonical order.
    let mut by_order = crate::pages::reused(spare, arcs.len(), 0u32);
    for (a, arc) in arcs.iter().enumerate() {
        let slot = &mut next[arc.lower.0 as usize];
        by_order[*slot as usize] = a as u32;
        *slot += 1;
    }
    drop(next);
    by_order
        .par_chunk_by_mut(|&a, &b| lower(a) == lower(b))
        .for_each(|same_lower| same_lower.sort_unstable_by_key(|&a| upper(a)));
    let mut new_id = crate::pages::filled(arcs.len(), 0u32);
    let slots = crate::pages::DisjointSlots::new(&mut new_id);
    by_order.par_iter().enumerate().for_each(|(new, &old)| {
        // SAFETY: `by_order` is a permutation: each old number once.
        unsafe { slots.write(old as usize, new as u32) };
    });
    (new_id, by_order)
}

/// For every candidate `x` but the root, the last of its ancestors
/// (inclusive) before the first one lower than x (`lower`: A(x)) or
/// higher (B(x)); `NONE` if there is no such ancestor (B of a candidate
/// higher than all its ancestors) and at the root.
///
/// Candidates are visited from the highest down for A (the lowest up for
/// B); the visited ones hang from the others in chains, and x's answer is
/// the top of its chain when x is visited. `up[c]` points to a visited
/// ancestor of `c` in its chain, at first its parent, and finding a top
/// compresses the path to it; a top stays in its chain when its parent is
/// visited later, so the pointers stay valid. The pointers are the
/// `parent` array it takes (pass a copy to keep the parents): 4 bytes per
/// candidate beside the answer, and no stack as deep as the tree. The
/// answers are written into `spare` where it is large enough; the
/// pointers are given back with them, for the caller to reuse.
fn chain_tops<I: Id>(parent: Vec<I>, lower: bool, spare: Vec<I>) -> (Vec<I>, Vec<I>) {
    let k = parent.len();
    let mut up = parent;
    // Every answer but the root's is written below.
    let mut top = crate::pages::reused(spare, k, I::of(NONE));
    if let Some(root) = top.first_mut() {
        *root = I::of(NONE);
    }
    for i in 1..k {
        let x = if lower { k - i } else { i } as u32;
        // Visited before x: higher than x for A, lower for B.
        let visited = |u: u32| u != NONE && (u > x) == lower;
        let t = climb(&mut up, x, |_, next| visited(next));
        // A chain up to the root (candidate 0) has nothing beyond it.
        top[x as usize] = I::of(if t == 0 { NONE } else { t });
    }
    (top, up)
}

/// Follows `pointer` from `start` while `go_on(node, pointer[node])`
/// holds, then points every node passed straight at the node it stopped
/// at (full path compression), and returns that node: the find of Fig.
/// 9's lazy contraction (the nearest ancestor not yet cut) and of the
/// chains of [`chain_tops`].
#[inline]
pub(super) fn climb<I: Id>(pointer: &mut [I], start: u32, go_on: impl Fn(u32, u32) -> bool) -> u32 {
    let mut end = start;
    while go_on(end, pointer[end as usize].get()) {
        end = pointer[end as usize].get();
    }
    let mut c = start;
    while c != end {
        let next = pointer[c as usize].get();
        pointer[c as usize] = I::of(end);
        c = next;
    }
    end
}

/// Every vertex placed (see the module documentation): the supernodes,
/// the superarcs and each vertex's place, what [`group`] lays out.
pub struct Placed {
    nodes: Vec<Node>,
    arcs: Vec<Superarc>,
    /// Each vertex's superarc, or `NODE_FLAG | node`: the first record,
    /// packed where it was.
    vertex_arc: Leafward,
}

/// Places every vertex (see the module documentation). `join_leafward`
/// and `split_leafward` are the sweeps' per-vertex records; the first
/// becomes the tree's `vertex_arc`. Needs no vertex order: a build that
/// let the order go makes it again only after this, when the second
/// record and the candidates' tables are gone.
pub fn place(tree: CandidateTree, join_leafward: Leafward, split_leafward: Leafward) -> Placed {
    let CandidateTree {
        node_vertex,
        arcs,
        supernodes,
        tables,
    } = tree;
    let vertex_arc = match tables {
        Tables::Words(chains) => place_with(&chains, &supernodes, join_leafward, split_leafward),
        Tables::Packed(chains) => place_with(&chains, &supernodes, join_leafward, split_leafward),
    };
    let nodes = nodes_of(node_vertex, &arcs);
    Placed {
        nodes,
        arcs,
        vertex_arc,
    }
}

/// Each vertex's place from its two records, written over the first as
/// the second is given back ([`leafward::combine`]).
fn place_with<I: Id>(
    chains: &Chains<I>,
    supernodes: &Supernodes,
    join_leafward: Leafward,
    split_leafward: Leafward,
) -> Leafward {
    let Chains {
        a_of,
        b_of,
        subtree,
    } = chains;
    leafward::combine(join_leafward, split_leafward, |j, s| {
        if j & CANDIDATE != 0 {
            let c = j & !CANDIDATE;
            if supernodes.is_node(c) {
                NODE_FLAG | supernodes.node(c)
            } else {
                subtree[c as usize][2].get()
            }
        } else {
            let [lo, hi, above_a] = match a_of[j as usize].get() {
                NONE => [0, 0, NONE],
                a => subtree[a as usize].map(Id::get),
            };
            let tb = subtree[s as usize][0].get();
            if lo <= tb && tb < hi {
                match b_of[s as usize].get() {
                    NONE => NONE,
                    b => subtree[b as usize][2].get(),
                }
            } else {
                above_a
            }
        }
    })
}

/// The supernodes from their vertices and the superarcs: a node's degree
/// up is the number of superarcs whose lower end it is, down the number
/// whose upper end it is (its children in the join and split trees,
/// counted again where the merge cut them down).
fn nodes_of(node_vertex: Vec<u32>, arcs: &[Superarc]) -> Vec<Node> {
    let mut nodes: Vec<Node> = node_vertex
        .into_par_iter()
        .map(|vertex| Node {
            vertex,
            up: 0,
            down: 0,
        })
        .collect();
    for arc in arcs {
        nodes[arc.lower.0 as usize].up += 1;
        nodes[arc.upper.0 as usize].down += 1;
    }
    nodes
}

/// Lays out the regular vertices of each superarc in the vertex `order`:
/// the tree's parts, which [`Grouped::into_tree`] assembles without the
/// order (a build lets it go first).
pub fn group<O: VertexOrder + ?Sized>(placed: Placed, order: OrderView<'_>, values: &O) -> Grouped {
    let (offsets, arc_vertices) = with_entries!(&placed.vertex_arc, vertex_arc => group_by_arc(vertex_arc, &placed.ends(values), order));
    Grouped {
        placed,
        offsets,
        arc_vertices,
    }
}

/// [`group`] with an order the grouping owns (and lets go): where the
/// superarcs are few enough for it and the order is ids (narrow or not),
/// read from its end in slabs, each slab's pages given back once grouped
/// ([`group_by_arc_consuming`]).
pub fn group_owned<O: VertexOrder + ?Sized>(placed: Placed, order: Order, values: &O) -> Grouped {
    let (n, arcs) = (order.view().len(), placed.arcs.len());
    let ids = !matches!(order, Order::Packed(_));
    let consuming = ids && arcs * CONSUMING_CHUNKS * rayon::current_num_threads() * SLABS <= n;
    let (offsets, arc_vertices) = with_entries!(&placed.vertex_arc, vertex_arc => if consuming {
        group_by_arc_consuming(vertex_arc, arcs, order)
    } else {
        group_by_arc(vertex_arc, &placed.ends(values), order.view())
    });
    Grouped {
        placed,
        offsets,
        arc_vertices,
    }
}

/// Every vertex placed and the regular ones grouped by superarc.
pub struct Grouped {
    placed: Placed,
    offsets: Vec<u32>,
    arc_vertices: VertexLists,
}

impl Grouped {
    /// The contour tree.
    pub fn into_tree(self) -> ContourTree {
        let Placed {
            nodes,
            arcs,
            vertex_arc,
        } = self.placed;
        ContourTree::assemble_places(nodes, arcs, vertex_arc, self.offsets, self.arc_vertices)
    }
}

impl Placed {
    /// The superarcs' ends, in the order `values` give.
    fn ends<'a, O: ?Sized>(&'a self, values: &'a O) -> ArcEnds<'a, O> {
        ArcEnds {
            values,
            arcs: &self.arcs,
            nodes: &self.nodes,
        }
    }
}

/// The superarcs' ends, between which each superarc's regular vertices
/// lie in the vertex order, and that order: what lets the grouping count
/// the vertices of each chunk of the order without reading it
/// ([`count_by_spans`]).
struct ArcEnds<'a, O: ?Sized> {
    values: &'a O,
    arcs: &'a [Superarc],
    nodes: &'a [Node],
}

/// The regular vertices of each superarc in the vertex order: stable
/// grouping of `order` by superarc. With few superarcs (smooth fields) the
/// order is cut into chunks, each counted ([`count_by_spans`]) and placed
/// by its own thread (slots of chunk `i` for an arc follow those of chunks
/// before it): four per thread, or one per thread on 4 threads or more
/// where the superarcs are fewer than an eighth of the vertices per
/// thread (counts of half a byte per vertex at most). Otherwise, since
/// per-chunk counts would outweigh the vertices, one count, and the order
/// read in slabs by ranges of superarcs ([`scatter_by_arc_ranges`]) on
/// several threads. That scatter has every thread read every gathered
/// pair, work that grows with the threads: one chunk per thread took
/// colin27_ch2better's augmentation from 0.28 to 0.19 s of work on 16
/// threads, aneurism's from 0.115 to 0.080 (measured oversubscribed on 2
/// cores, where the time is the work), mni152_t1's from 0.050-0.054 to
/// 0.043-0.045 s on 4 and 8. On 2 threads one chunk per thread was no
/// faster (colin27_ch2) or slower (engine), so there it is not used.
fn group_by_arc<W: Word, O: VertexOrder + ?Sized>(
    vertex_arc: &[W],
    ends: &ArcEnds<'_, O>,
    order: OrderView<'_>,
) -> (Vec<u32>, VertexLists) {
    let threads = rayon::current_num_threads();
    let slab = (order.len() / SLAB_SHARE).clamp(threads * GATHER_CHUNKS, SLAB);
    if VertexLists::narrows(order.len()) {
        let (offsets, ids) = group_by_arc_in(vertex_arc, ends, order, slab);
        (offsets, VertexLists::Narrow(ids))
    } else {
        let (offsets, ids) = group_by_arc_in(vertex_arc, ends, order, slab);
        (offsets, VertexLists::Wide(ids))
    }
}

/// [`group_by_arc`], reading the order in slabs of `slab` positions where
/// it goes by ranges of superarcs, the lists in entries `E`.
fn group_by_arc_in<W: Word, O: VertexOrder + ?Sized, E: Entry>(
    vertex_arc: &[W],
    ends: &ArcEnds<'_, O>,
    order: OrderView<'_>,
    slab: usize,
) -> (Vec<u32>, Vec<E>) {
    let (n, arcs) = (order.len(), ends.arcs.len());
    let threads = rayon::current_num_threads();
    let chunks = if threads > 1 && arcs * threads * 4 <= n / 16 {
        threads * 4
    } else if threads >= 4 && arcs * threads <= n / 8 {
        // Above, at most half a byte per vertex of counts.
        threads
    } else {
        1
    };
    let chunk_len = n.div_ceil(chunks).max(1);
    let ranges: Vec<std::ops::Range<usize>> = (0..n.div_ceil(chunk_len))
        .map(|c| c * chunk_len..((c + 1) * chunk_len).min(n))
        .collect();
    let mut counts: Vec<Vec<u32>> = if ranges.len() <= 1 {
        // One chunk (or none, with no vertex): its counts are the
        // superarcs' sizes, which any order gives, so they are read off
        // `vertex_arc` in id order (streaming, on every core) rather than
        // through the order.
        vec![arc_sizes(vertex_arc, arcs)]
    } else {
        let counts = count_by_spans(order, vertex_arc, &ranges, ends);
        debug_assert!(counts == count_in_ranges(order, vertex_arc, arcs, &ranges));
        counts
    };
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
    let mut arc_vertices = crate::pages::filled(total as usize, E::entry(0));
    let dst = crate::pages::DisjointSlots::new(&mut arc_vertices);
    if counts.len() == 1 && threads > 1 {
        let next = counts.pop().expect("one count");
        // SAFETY: each arc owns the slots from its offset to the next
        // (the prefix sums above).
        unsafe { scatter_by_arc_ranges(order, vertex_arc, &offsets, next, slab, &dst) };
    } else {
        // SAFETY: each (chunk, arc) owns a disjoint range of slots below
        // `total`, as long as the chunk has vertices on the arc (the
        // prefix sums above).
        unsafe { scatter_ranges(order, vertex_arc, ranges, counts, &dst) };
    }
    (offsets, arc_vertices)
}

/// Writes the regular vertices of each superarc to `dst`, in the order,
/// those on arc `a` from slot `next[a]` on: the order read in slabs of
/// `slab` positions, each cut into [`GATHER_CHUNKS`] tasks per thread;
/// each slab's ids are gathered beside their superarcs on every core (the
/// scattered reads of `vertex_arc`), then each thread reads the whole slab
/// in sequence (it stays in the cache) and writes the vertices of its own
/// range of superarcs, the ranges balanced by their vertices (`offsets`).
/// No count per chunk of the order (a word per superarc and chunk, which
/// outweighs the vertices on a scan) and no second pass through the order:
/// each superarc's slots are written in the order by the one thread that
/// owns it. Before, this grouping was one sequential pass (0.04 s of
/// colin27_ch2's 0.25 s on 2 threads).
///
/// # Safety
/// Superarc `a`'s slots, from `next[a]` on as many as it has vertices, lie
/// in `dst` and are no other's.
unsafe fn scatter_by_arc_ranges<W: Word, E: Entry>(
    order: OrderView<'_>,
    vertex_arc: &[W],
    offsets: &[u32],
    mut next: Vec<u32>,
    slab: usize,
    dst: &crate::pages::DisjointSlots<'_, E>,
) {
    let (n, arcs) = (order.len(), next.len());
    let total = offsets[arcs];
    let threads = rayon::current_num_threads();
    // Thread t's superarcs start at the first whose slots start at or past
    // its share of the vertices.
    let mut ranges: Vec<&mut [u32]> = Vec::with_capacity(threads);
    let (mut rest, mut first) = (next.as_mut_slice(), 0);
    let mut firsts = Vec::with_capacity(threads);
    for t in 1..=threads {
        let share = total as u64 * t as u64 / threads as u64;
        let end = offsets[..arcs].partition_point(|&o| (o as u64) < share);
        let end = if t == threads { arcs } else { end.max(first) };
        let (range, tail) = rest.split_at_mut(end - first);
        if !range.is_empty() {
            ranges.push(range);
            firsts.push(first as u32);
        }
        (rest, first) = (tail, end);
    }
    let slab = slab.clamp(1, n.max(1));
    let gather = slab.div_ceil(threads * GATHER_CHUNKS);
    let mut pairs = vec![0u64; slab];
    for start in (0..n).step_by(slab) {
        let pairs = &mut pairs[..slab.min(n - start)];
        pairs
            .par_chunks_mut(gather)
            .enumerate()
            .for_each(|(c, out)| {
                let first = start + c * gather;
                let mut k = 0;
                order.for_each_chunk(first..first + out.len(), |ids| {
                    for (i, &v) in ids.iter().enumerate() {
                        if let Some(&w) = ids.get(i + ORDER_AHEAD) {
                            prefetch(vertex_arc, w as usize);
                        }
                        out[k] = (vertex_arc[v as usize].get() as u64) << 32 | v as u64;
                        k += 1;
                    }
                });
            });
        let pairs = &*pairs;
        ranges
            .par_iter_mut()
            .zip(&firsts)
            .with_max_len(1)
            .for_each(|(next, &first)| {
                let len = next.len() as u32;
                for &p in pairs {
                    // A node's word (NODE_FLAG) wraps far beyond every range.
                    let i = ((p >> 32) as u32).wrapping_sub(first);
                    if i < len {
                        let slot = &mut next[i as usize];
                        // SAFETY: superarc `first + i`'s slots are the
                        // caller's for it, written by this range's thread.
                        unsafe { dst.write(*slot as usize, E::entry(p as u32)) };
                        *slot += 1;
                    }
                }
            });
    }
}

/// Positions of the order [`scatter_by_arc_ranges`] gathers at a time, at
/// most: 4 MiB of (id, superarc) pairs, which every thread then reads.
const SLAB: usize = 1 << 19;
/// Or a this-th of the vertices where that is less: a quarter of a byte
/// per vertex (the whole 4 MiB was 2.7 bytes per vertex on tooth, above
/// the build's peak).
const SLAB_SHARE: usize = 32;
/// Tasks per thread in the gathering of a slab.
const GATHER_CHUNKS: usize = 4;

/// At most this many threads count the superarcs' sizes by ranges
/// ([`arc_sizes`]): each reads every vertex, so more would read the
/// records more often than they save.
const COUNT_RANGES: usize = 2;

/// How far ahead in the cut order the merge's pre-order passes prefetch
/// a candidate's entries.
const READ_AHEAD: usize = 16;

/// How far ahead in the vertex order the grouping's passes prefetch each
/// vertex's superarc. The reads are scattered over the volume, but where
/// the order runs through consecutive ids (ties, broken by id) they are a
/// stream of 4-byte words (16 to a line; 21 of the 3-byte places): 64 took the
/// augmentation of `synthetic:256` from 0.18-0.20 to 0.15 s and of
/// colin27_ch2better from 0.42-0.47 to 0.38-0.40 s (one thread).
const ORDER_AHEAD: usize = 64;

/// Slabs of the order [`group_by_arc_consuming`] reads one after another.
const SLABS: usize = 8;
/// Chunks of a slab per thread, each counted and placed on its own.
const CONSUMING_CHUNKS: usize = 2;

/// The size of each superarc (its regular vertices), read off
/// `vertex_arc` in id order on every core: a count per thread, summed,
/// where those counts hold at most 2 bytes per vertex together (smooth
/// fields; scans on 2 threads); otherwise one count cut into ranges of
/// superarcs, up to [`COUNT_RANGES`], each counted by one thread reading
/// every vertex. A count per thread on a noisy scan is a word per superarc
/// per thread (0.6 bytes per vertex each on tooth: 9.5 on 16 threads,
/// above the build's peak); the ranges cost 7-15 ms more on colin27_ch2
/// on 2 threads (0.25 s to the tree), and one count shared by atomic
/// increments was 10 ms slower.
fn arc_sizes<W: Word>(vertex_arc: &[W], arcs: usize) -> Vec<u32> {
    let threads = rayon::current_num_threads();
    if arcs.saturating_mul(threads).saturating_mul(2) > vertex_arc.len() {
        let mut count = vec![0u32; arcs];
        let per = arcs.div_ceil(threads.min(COUNT_RANGES)).max(1 << 12);
        count
            .par_chunks_mut(per)
            .enumerate()
            .for_each(|(t, range)| {
                let first = (t * per) as u32;
                let len = range.len() as u32;
                for a in vertex_arc.iter().map(|a| a.get()) {
                    // A node's word (NODE_FLAG) wraps far beyond every range.
                    let i = a.wrapping_sub(first);
                    if i < len {
                        range[i as usize] += 1;
                    }
                }
            });
        return count;
    }
    let per = vertex_arc.len().div_ceil(threads).max(1 << 16);
    vertex_arc
        .par_chunks(per)
        .map(|part| {
            let mut count = vec![0u32; arcs];
            for a in part.iter().map(|a| a.get()).filter(|&a| a & NODE_FLAG == 0) {
                count[a as usize] += 1;
            }
            count
        })
        .reduce_with(|mut x, y| {
            x.iter_mut().zip(y).for_each(|(x, y)| *x += y);
            x
        })
        .unwrap_or_else(|| vec![0; arcs])
}

/// [`group_by_arc`] for an order the grouping owns: read from its end in
/// [`SLABS`] slabs, each slab's pages given back once it is grouped, so
/// that the order and the arcs' vertex lists (whose pages are touched as
/// they are written) hold about 4 bytes per vertex together, not 8 (3,
/// not 6, for a narrow order, whose slabs are widened one at a time,
/// beside the 3-byte lists of a mesh of at most 2^24 vertices): on a
/// float field, whose order is not remade, that
/// was the build's peak. Each arc's slots fill from its end down, slab by
/// slab and, within a slab, chunk by chunk from the last: the same layout.
fn group_by_arc_consuming<W: Word>(
    vertex_arc: &[W],
    arcs: usize,
    order: Order,
) -> (Vec<u32>, VertexLists) {
    // Where an id and a superarc (or `arcs` for a node) fit in one word
    // together, the count writes each position's superarc beside its id,
    // so that the scatter reads the slab in sequence instead of looking
    // every vertex up again at a scattered place: the smooth fields, whose
    // superarcs are few.
    let id_bits = usize::BITS - (order.view().len().max(2) - 1).leading_zeros();
    let fits = id_bits < u32::BITS && (arcs as u64) < 1 << (u32::BITS - id_bits);
    let packed = fits.then_some(id_bits);
    if VertexLists::narrows(order.view().len()) {
        let (offsets, ids) = group_by_arc_in_slabs(vertex_arc, arcs, order, packed);
        (offsets, VertexLists::Narrow(ids))
    } else {
        let (offsets, ids) = group_by_arc_in_slabs(vertex_arc, arcs, order, packed);
        (offsets, VertexLists::Wide(ids))
    }
}

/// [`group_by_arc_consuming`], each slab's superarcs written beside its
/// ids where `packed` gives the ids' bits.
fn group_by_arc_in_slabs<W: Word, E: Entry>(
    vertex_arc: &[W],
    arcs: usize,
    mut order: Order,
    packed: Option<u32>,
) -> (Vec<u32>, Vec<E>) {
    let n = order.view().len();
    let sizes = arc_sizes(vertex_arc, arcs);
    let mut offsets = vec![0u32; arcs + 1];
    for a in 0..arcs {
        offsets[a + 1] = offsets[a] + sizes[a];
    }
    drop(sizes);
    // Zeroed lazily (fresh pages): only what is written is held.
    let mut arc_vertices = vec![E::entry(0); offsets[arcs] as usize];
    let dst = crate::pages::DisjointSlots::new(&mut arc_vertices);
    let mut free_end: Vec<u32> = offsets[1..].to_vec();
    let chunks = CONSUMING_CHUNKS * rayon::current_num_threads();
    let slab = n.div_ceil(SLABS).max(1);
    // A slab of a narrow (or packed) order, widened.
    let mut wide = Vec::new();
    let mut hi = n;
    while hi > 0 {
        let lo = hi.saturating_sub(slab);
        let ids: &mut [u32] = match &mut order {
            Order::Ids(ids) => &mut ids[lo..hi],
            narrow => {
                wide.clear();
                narrow
                    .view()
                    .for_each_chunk(lo..hi, |ids| wide.extend_from_slice(ids));
                &mut wide
            }
        };
        let per = (hi - lo).div_ceil(chunks).max(1);
        let ranges: Vec<std::ops::Range<usize>> = (0..hi - lo)
            .step_by(per)
            .map(|s| s..(s + per).min(hi - lo))
            .collect();
        let mut starts = match packed {
            Some(id_bits) => count_and_pack(ids, per, vertex_arc, arcs, id_bits),
            None => count_in_ranges(OrderView::Ids(ids), vertex_arc, arcs, &ranges),
        };
        // The last chunk's vertices of an arc take its highest free slots.
        for (a, end) in free_end.iter_mut().enumerate() {
            for c in starts.iter_mut().rev() {
                *end -= c[a];
                c[a] = *end;
            }
        }
        // SAFETY: each (slab, chunk, arc) owns a disjoint range of slots,
        // as long as the chunk has vertices on the arc (taken from the
        // arc's free end above).
        match packed {
            // SAFETY: as above.
            Some(id_bits) => unsafe { scatter_packed(ids, per, id_bits, starts, &dst) },
            None => unsafe {
                scatter_ranges(OrderView::Ids(ids), vertex_arc, ranges, starts, &dst)
            },
        }
        order.truncate_releasing(lo);
        hi = lo;
    }
    debug_assert!(free_end.iter().zip(&offsets).all(|(e, o)| e == o));
    (offsets, arc_vertices)
}

/// Per range of positions of the order: how many of its regular vertices
/// lie on each of the `arcs` superarcs, a range per task.
fn count_in_ranges<W: Word>(
    order: OrderView<'_>,
    vertex_arc: &[W],
    arcs: usize,
    ranges: &[std::ops::Range<usize>],
) -> Vec<Vec<u32>> {
    ranges
        .par_iter()
        .map(|range| {
            let mut count = vec![0u32; arcs];
            for_each_arc(order, vertex_arc, range.clone(), |_, a| {
                count[a as usize] += 1
            });
            count
        })
        .collect()
}

/// [`count_in_ranges`] without going through the order. A superarc's
/// regular vertices lie between its ends in the vertex order, so where
/// both ends fall in one range all its vertices do, and its count there
/// is its size. Only the superarcs that straddle a bound between ranges
/// are counted range by range, each of their vertices put in its range by
/// comparing it with the bounds between its superarc's ends. That is one
/// pass over `vertex_arc` and the values in id order, streaming on every
/// core, where the pass through the order looks every vertex's superarc
/// up at a scattered place: colin27_ch2better (35 M vertices, 244 K
/// superarcs, 8 ranges, 1,551 of them straddling) on 2 threads 46-47 ms
/// before, 29-31 now (the ranges of the nodes and ends 6-8 ms, the pass
/// 18-21, the counts laid out 4).
fn count_by_spans<W: Word, O: VertexOrder + ?Sized>(
    order: OrderView<'_>,
    vertex_arc: &[W],
    ranges: &[std::ops::Range<usize>],
    ends: &ArcEnds<'_, O>,
) -> Vec<Vec<u32>> {
    let (arcs, chunks, values) = (ends.arcs.len(), ranges.len(), ends.values);
    // The first vertex of each range but the first.
    let mut ids = Vec::new();
    let bound: Vec<u32> = ranges[1..]
        .iter()
        .map(|r| order.read(r.start..r.start + 1, &mut ids)[0])
        .collect();
    // True if `v` is at or after `b` in the order.
    let from = |v: u32, b: u32| v == b || values.above(v, b);
    // The range of each node (one for each bound it is at or after), and
    // of each superarc's ends.
    let node_range: Vec<u32> = ends
        .nodes
        .par_iter()
        .map(|node| bound.iter().filter(|&&b| from(node.vertex, b)).count() as u32)
        .collect();
    let span: Vec<[u32; 2]> = ends
        .arcs
        .par_iter()
        .map(|arc| [arc.lower, arc.upper].map(|e| node_range[e.0 as usize]))
        .collect();
    // The straddling superarcs, numbered.
    let mut straddling = 0u32;
    let slot: Vec<u32> = span
        .iter()
        .map(|&[lo, hi]| {
            if lo == hi {
                return NONE;
            }
            straddling += 1;
            straddling - 1
        })
        .collect();
    let per = vertex_arc
        .len()
        .div_ceil(rayon::current_num_threads())
        .max(1 << 16);
    let (size, across) = vertex_arc
        .par_chunks(per)
        .enumerate()
        .map(|(i, part)| {
            let mut size = vec![0u32; arcs];
            let mut across = vec![0u32; straddling as usize * chunks];
            for (v, a) in (i as u32 * per as u32..).zip(part.iter().map(|a| a.get())) {
                if a & NODE_FLAG != 0 {
                    continue;
                }
                match slot[a as usize] {
                    NONE => size[a as usize] += 1,
                    s => {
                        // Its range: its arc's first, and one more for
                        // each bound between its arc's ends that it is at
                        // or after.
                        let [lo, hi] = span[a as usize];
                        let c = bound[lo as usize..hi as usize]
                            .iter()
                            .fold(lo, |c, &b| c + u32::from(from(v, b)));
                        across[s as usize * chunks + c as usize] += 1;
                    }
                }
            }
            (size, across)
        })
        .reduce_with(|(mut size, mut across), (s, a)| {
            size.iter_mut().zip(s).for_each(|(x, y)| *x += y);
            across.iter_mut().zip(a).for_each(|(x, y)| *x += y);
            (size, across)
        })
        .unwrap_or_else(|| (vec![0; arcs], vec![0; straddling as usize * chunks]));
    let mut counts = vec![vec![0u32; arcs]; chunks];
    for (a, (&[lo, hi], &s)) in span.iter().zip(&slot).enumerate() {
        if s == NONE {
            counts[lo as usize][a] = size[a];
        } else {
            for c in lo..=hi {
                counts[c as usize][a] = across[s as usize * chunks + c as usize];
            }
        }
    }
    // The tables above are under a MiB each on a scan, carved from the
    // threads' heaps, which would keep them resident beside the arcs'
    // vertex lists: colin27_ch2better's peak was 8-10 MiB higher.
    drop((node_range, span, slot, size, across));
    crate::pages::trim_freed();
    counts
}

/// [`count_in_ranges`] over the chunks of `per` positions of `slab`, which
/// it rewrites: each id `v` becomes `v | arc << id_bits`, with `arcs` in
/// place of the superarc of a node (every superarc below `arcs` and every
/// id below `1 << id_bits`).
fn count_and_pack<W: Word>(
    slab: &mut [u32],
    per: usize,
    vertex_arc: &[W],
    arcs: usize,
    id_bits: u32,
) -> Vec<Vec<u32>> {
    slab.par_chunks_mut(per)
        .map(|ids| {
            let mut count = vec![0u32; arcs];
            for i in 0..ids.len() {
                if let Some(&w) = ids.get(i + ORDER_AHEAD) {
                    prefetch(vertex_arc, w as usize);
                }
                let v = ids[i];
                let va = vertex_arc[v as usize].get();
                let a = if va & NODE_FLAG == 0 {
                    count[va as usize] += 1;
                    va
                } else {
                    arcs as u32
                };
                ids[i] = v | a << id_bits;
            }
            count
        })
        .collect()
}

/// [`scatter_ranges`] for a slab that [`count_and_pack`] rewrote, read in
/// sequence.
///
/// # Safety
/// As for [`scatter_ranges`], with the chunks of `per` positions of `slab`
/// as the ranges.
unsafe fn scatter_packed<E: Entry>(
    slab: &[u32],
    per: usize,
    id_bits: u32,
    starts: Vec<Vec<u32>>,
    dst: &crate::pages::DisjointSlots<'_, E>,
) {
    let id = (1u32 << id_bits) - 1;
    slab.par_chunks(per)
        .zip(starts.into_par_iter())
        .for_each(|(words, mut fill)| {
            for &w in words {
                if let Some(slot) = fill.get_mut((w >> id_bits) as usize) {
                    // SAFETY: the caller's (chunk, arc) slots are its own.
                    unsafe { dst.write(*slot as usize, E::entry(w & id)) };
                    *slot += 1;
                }
            }
        });
}

/// Writes the regular vertices of each range of positions of the order to
/// `dst`, in the order, those on arc `a` from slot `starts[r][a]` on, a
/// range per task.
///
/// # Safety
/// The slots each (range, arc) writes, from its start on as many as the
/// range has vertices on the arc, lie in `dst` and are no other's.
unsafe fn scatter_ranges<W: Word, E: Entry>(
    order: OrderView<'_>,
    vertex_arc: &[W],
    ranges: Vec<std::ops::Range<usize>>,
    starts: Vec<Vec<u32>>,
    dst: &crate::pages::DisjointSlots<'_, E>,
) {
    ranges
        .into_par_iter()
        .zip(starts.into_par_iter())
        .for_each(|(range, mut fill)| {
            for_each_arc(order, vertex_arc, range, |v, a| {
                let slot = &mut fill[a as usize];
                // SAFETY: the caller's (range, arc) slots are its own.
                unsafe { dst.write(*slot as usize, E::entry(v)) };
                *slot += 1;
            });
        });
}

/// Calls `f(v, arc)` for each regular vertex `v` at the positions `range`
/// of the order, with its superarc; the superarcs are read ahead (the
/// reads are scattered over the volume).
fn for_each_arc<W: Word>(
    order: OrderView<'_>,
    vertex_arc: &[W],
    range: std::ops::Range<usize>,
    mut f: impl FnMut(u32, u32),
) {
    order.for_each_chunk(range, |ids| {
        for (i, &v) in ids.iter().enumerate() {
            if let Some(&w) = ids.get(i + ORDER_AHEAD) {
                prefetch(vertex_arc, w as usize);
            }
            let va = vertex_arc[v as usize].get();
            if va & NODE_FLAG == 0 {
                f(v, va);
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        /// A number in 3 bytes reads back as written, `NONE` included.
        #[test]
        fn a_number_in_3_bytes_reads_back(x in 0u32..Id3::NONE) {
            prop_assert_eq!(Id3::of(x).get(), x);
            prop_assert_eq!(Id3::of(NONE).get(), NONE);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Numbering superarcs by counting their lower ends gives the
        /// order of a comparison sort by (lower, upper).
        #[test]
        fn counting_the_lower_ends_sorts_the_superarcs(
            nodes in 2u32..400,
            pairs in prop::collection::vec((any::<u32>(), any::<u32>()), 0..3000),
        ) {
            let mut arcs: Vec<Superarc> = pairs
                .iter()
                .map(|&(a, b)| (a % nodes, b % nodes))
                .filter(|&(a, b)| a != b)
                .map(|(a, b)| Superarc { upper: NodeId(a.max(b)), lower: NodeId(a.min(b)) })
                .collect();
            // No two superarcs join the same two nodes; the rest in any order.
            arcs.sort_unstable_by_key(|a| (a.upper, a.lower));
            arcs.dedup();
            arcs.sort_by_key(|a| (a.lower.0 ^ a.upper.0).wrapping_mul(0x9E37_79B9));
            // A spare allocation of any size, as the merge's is.
            let spare = vec![7u32; (nodes as usize * 3) % 11];
            let (new_id, _) = canonical_arc_ids(&arcs, nodes as usize, spare);
            let mut placed = vec![None; arcs.len()];
            for (arc, &id) in arcs.iter().zip(&new_id) {
                prop_assert!(placed[id as usize].replace(*arc).is_none(), "one arc per number");
            }
            let mut sorted = arcs.clone();
            sorted.sort_unstable_by_key(|a| (a.lower, a.upper));
            let placed: Vec<Superarc> = placed.into_iter().flatten().collect();
            prop_assert_eq!(placed, sorted);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(60))]
        /// The grouping that reads its order from the end in slabs and
        /// gives it back, and the one by ranges of superarcs, lay out every
        /// arc's vertices exactly as the one that reads it whole: in the
        /// order, arc by arc.
        #[test]
        fn the_consuming_grouping_is_the_grouping(
            n in 0usize..3000,
            arcs in 1usize..400,
            nodes in 0usize..50,
            seed in any::<u64>(),
        ) {
            let hash = |i: u64| (i ^ seed).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 20;
            let vertex_arc: Vec<u32> = (0..n as u64)
                .map(|i| if (hash(i) as usize) % 50 < nodes { NODE_FLAG | 7 } else { (hash(i + 1) % arcs as u64) as u32 })
                .collect();
            let mut order: Vec<u32> = (0..n as u32).collect();
            order.sort_by_key(|&v| hash(v as u64 + 99));
            // Values that give this order, and as each superarc's ends its
            // first and last vertex in it (any vertex where it has none).
            let mut rank = vec![0u32; n];
            for (i, &v) in order.iter().enumerate() {
                rank[v as usize] = i as u32;
            }
            let mut nodes = vec![Node::default(); 2 * arcs];
            for &v in order.iter().rev() {
                if let Some(node) = nodes.get_mut(2 * vertex_arc[v as usize] as usize) {
                    node.vertex = v;
                }
            }
            for &v in &order {
                if let Some(node) = nodes.get_mut(2 * vertex_arc[v as usize] as usize + 1) {
                    node.vertex = v;
                }
            }
            let superarcs: Vec<Superarc> = (0..arcs as u32)
                .map(|a| Superarc { lower: NodeId(2 * a), upper: NodeId(2 * a + 1) })
                .collect();
            let ends = ArcEnds { values: &rank[..], arcs: &superarcs, nodes: &nodes };
            let whole = group_by_arc(&vertex_arc, &ends, OrderView::Ids(&order));
            let consumed = group_by_arc_consuming(&vertex_arc, arcs, Order::Ids(order.clone()));
            prop_assert_eq!(&whole, &consumed);
            // From a narrow order (3 bytes per id), its slabs widened.
            let narrow = || Order::Narrow(order.iter().map(|&v| crate::field::narrow_id(v)).collect());
            prop_assert_eq!(&whole, &group_by_arc_consuming(&vertex_arc, arcs, narrow()));
            let (o, ids) = group_by_arc_in_slabs(&vertex_arc, arcs, narrow(), None);
            prop_assert_eq!(&whole, &(o, VertexLists::Narrow(ids)));
            // From the places packed in 3 bytes each, as a tree keeps them.
            let mut places = Leafward::zeroed(n, true);
            with_words!(&mut places, w => w.iter_mut().zip(&vertex_arc).for_each(|(w, &x)| *w = Word::of(x)));
            prop_assert!(places.is_packed());
            let from_packed = with_entries!(&places, p => (
                group_by_arc(p, &ends, OrderView::Ids(&order)),
                group_by_arc_consuming(p, arcs, Order::Ids(order.clone())),
            ));
            prop_assert_eq!(&whole, &from_packed.0);
            prop_assert_eq!(&whole, &from_packed.1);
            // Read back from the order itself, not written beside the ids.
            // The lists in 4 bytes per id (meshes of more than 2^24
            // vertices), as the 3-byte lists.
            let (o, ids) = group_by_arc_in_slabs::<_, u32>(&vertex_arc, arcs, Order::Ids(order.clone()), None);
            prop_assert_eq!(&whole, &(o, VertexLists::of_ids(ids, n)));
            // Read in slabs by ranges of superarcs on 5 threads.
            let slab = 1 + (hash(7) % 300) as usize;
            let by_ranges = rayon::ThreadPoolBuilder::new().num_threads(5).build().expect("a pool of 5 threads").install(|| {
                group_by_arc_in::<_, _, u32>(&vertex_arc, &ends, OrderView::Ids(&order), slab)
            });
            prop_assert_eq!(&whole, &(by_ranges.0, VertexLists::of_ids(by_ranges.1, n)));
            // Counted by the superarcs' spans on 3 threads: the counts of
            // the pass through the order.
            let ranges: Vec<std::ops::Range<usize>> = (0..n.div_ceil(97)).map(|c| c * 97..(c * 97 + 97).min(n)).collect();
            if !ranges.is_empty() {
                let by_spans = rayon::ThreadPoolBuilder::new().num_threads(3).build().expect("a pool of 3 threads").install(|| {
                    count_by_spans(OrderView::Ids(&order), &vertex_arc, &ranges, &ends)
                });
                prop_assert_eq!(by_spans, count_in_ranges(OrderView::Ids(&order), &vertex_arc, arcs, &ranges));
            }
            // And it is the grouping: each arc's vertices, in the order.
            let (offsets, verts) = consumed;
            for a in 0..arcs {
                let expect: Vec<u32> = order.iter().copied().filter(|&v| vertex_arc[v as usize] == a as u32).collect();
                prop_assert_eq!(verts.slice(offsets[a] as usize..offsets[a + 1] as usize).to_vec(), expect);
            }
        }
    }
}
