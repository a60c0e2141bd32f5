//! The contour tree checked against brute-force oracles that work from the
//! definitions on the mesh, not from the engine's code:
//!
//! (a) the join and split trees recomputed from the output contour tree equal
//!     those computed by definition (Carr et al. Def. 4.1) by flooding the
//!     superlevel / sublevel sets on the mesh;
//! (b) every vertex's up/down degree equals the number of components of
//!     {f > f(v)} / {f < f(v)} (vertex order) adjacent to v, by flooding;
//! (c) for isovalues h that are not vertex values, the number of superarcs
//!     spanning h equals the number of components of the level set {f = h},
//!     found by flooding the simplices h crosses through shared crossed
//!     facets.

mod common;

use flexiso::field::{ScalarField, Values};
use flexiso::mesh::Mesh;
use flexiso::progress::Progress;
use flexiso::tree::sweep::{self, JoinTree, SplitTree};
use flexiso::tree::{ArcId, ContourTree, blocks};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

fn build(field: &ScalarField) -> ContourTree {
    ContourTree::from_field(field, &Progress::new())
        .expect("not cancelled")
        .0
}

/// Checks (a), (b), (c) and the tree's own consistency.
fn check_against_oracles(field: &ScalarField) {
    common::tree_oracle::check_against_oracles(field, &build(field));
}

fn grid(dims: [usize; 3], values: Vec<u8>) -> ScalarField {
    ScalarField::new(dims, Values::U8(values)).expect("valid field")
}

/// Random grids up to 6^3 with few distinct values (many ties).
fn random_grid() -> impl Strategy<Value = ScalarField> {
    (1usize..=6, 1usize..=6, 1usize..=6, 1u8..=12).prop_flat_map(|(x, y, z, levels)| {
        proptest::collection::vec(0..levels, x * y * z).prop_map(move |v| grid([x, y, z], v))
    })
}

fn random_2d_grid() -> impl Strategy<Value = ScalarField> {
    (1usize..=9, 1usize..=9, 1u8..=6).prop_flat_map(|(x, y, levels)| {
        proptest::collection::vec(0..levels, x * y).prop_map(move |v| grid([x, y, 1], v))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn contour_tree_matches_definitions_on_random_3d_grids(field in random_grid()) {
        check_against_oracles(&field);
    }

    #[test]
    fn contour_tree_matches_definitions_on_random_2d_grids(field in random_2d_grid()) {
        check_against_oracles(&field);
    }

    #[test]
    fn contour_tree_matches_definitions_on_distinct_float_values(
        (dims, values) in (2usize..=5, 2usize..=5, 1usize..=5).prop_flat_map(|(x, y, z)| {
            (Just([x, y, z]), proptest::collection::vec(-1000.0f32..1000.0, x * y * z))
        })
    ) {
        check_against_oracles(&ScalarField::new(dims, Values::F32(values)).expect("valid"));
    }
}

#[test]
fn chain_1d_has_one_arc_per_monotone_run() {
    // 0 5 1 4 2: minima at 0, 2 (value 1), 4 (value 2); maxima at 1, 3.
    let field = grid([5, 1, 1], vec![0, 5, 1, 4, 2]);
    let tree = build(&field);
    let (max, min, join, split) = tree.kind_counts();
    assert_eq!((max, min, join, split), (2, 3, 1, 2));
    assert_eq!(tree.arcs().len(), 4);
    check_against_oracles(&field);
}

#[test]
fn two_maxima_and_a_saddle_in_2d() {
    #[rustfmt::skip]
    let values = vec![
        0, 0, 0, 0, 0,
        0, 9, 3, 8, 0,
        0, 0, 0, 0, 0,
    ];
    let field = grid([5, 3, 1], values);
    let tree = build(&field);
    let (max, min, join, split) = tree.kind_counts();
    assert_eq!((max, min, join, split), (2, 1, 1, 0));
    // The join saddle is the vertex of value 3 at (2,1).
    let join_node = tree.nodes().iter().find(|n| n.up == 2).expect("a join");
    assert_eq!(join_node.vertex, 7);
    check_against_oracles(&field);
}

#[test]
fn nested_shell_splits_into_inside_and_outside_contours() {
    // A 7^3 grid: a high shell at Chebyshev radius 2 around a low core,
    // low outside. Going down from the shell's values, one contour (the
    // shell's) splits into an inner and an outer surface: a split saddle.
    let n = 7;
    let mut values = vec![0u8; n * n * n];
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let r = [x, y, z]
                    .iter()
                    .map(|&c| (c as i64 - 3).unsigned_abs())
                    .max()
                    .unwrap_or(0);
                values[x + n * (y + n * z)] = match r {
                    0 => 2,
                    1 => 1,
                    2 => 10,
                    _ => 3,
                };
            }
        }
    }
    // Make the values distinct enough inside each region by a small ramp so
    // the tree is easy to state: one max (the shell), two minima (core and
    // outside), one split saddle.
    let field = grid([n, n, n], values);
    let tree = build(&field);
    let (_, min, _, split) = tree.kind_counts();
    assert_eq!(min, 2, "core and outside");
    assert!(split >= 1, "the shell's contour splits");
    // At h = 5 there are two contours: inside and outside of the shell.
    let spanning = tree
        .arcs()
        .iter()
        .filter(|a| {
            field.value(tree.node(a.lower).vertex) < 5.0
                && field.value(tree.node(a.upper).vertex) > 5.0
        })
        .count();
    assert_eq!(spanning, 2);
    check_against_oracles(&field);
}

#[test]
fn plateau_of_equal_values_is_resolved_by_vertex_id() {
    let field = grid([4, 4, 3], vec![7; 48]);
    let tree = build(&field);
    // Simulation of simplicity: ids increase along the grid, so the order is
    // a monotone ramp: one minimum (id 0), one maximum (id 47), one arc.
    assert_eq!(tree.nodes().len(), 2);
    assert_eq!(tree.nodes()[0].vertex, 0);
    assert_eq!(tree.nodes()[1].vertex, 47);
    assert_eq!(tree.arc_vertices(ArcId(0)).len(), 46);
    check_against_oracles(&field);
}

#[test]
fn single_vertex_and_tiny_grids() {
    let tree = build(&grid([1, 1, 1], vec![3]));
    assert_eq!(tree.nodes().len(), 1);
    assert!(tree.arcs().is_empty());
    check_against_oracles(&grid([2, 1, 1], vec![3, 3]));
    check_against_oracles(&grid([2, 2, 2], vec![1, 0, 0, 1, 0, 1, 1, 0]));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    /// The engine's general path (an explicit mesh: every neighbour looked
    /// up, no link table) gives the same tree as the grid's fast path.
    #[test]
    fn explicit_edge_list_mesh_gives_the_same_tree(field in random_grid()) {
        let grid = field.mesh();
        let mut edges = Vec::new();
        for v in 0..field.len() as u32 {
            grid.for_each_neighbour(v, |u| if u > v { edges.push((v, u)) });
        }
        let explicit = flexiso::mesh::EdgeListMesh::new(field.len(), &edges);
        let order = field.vertex_order();
        let Values::U8(values) = field.values() else { unreachable!("u8 grid") };
        let (general, _) = ContourTree::build(&explicit, values.as_slice(), &order, &Progress::new()).expect("not cancelled");
        let fast = build(&field);
        prop_assert_eq!(general.nodes(), fast.nodes());
        prop_assert_eq!(general.arcs(), fast.arcs());
        for a in 0..fast.arcs().len() as u32 {
            prop_assert_eq!(general.arc_vertices(ArcId(a)), fast.arc_vertices(ArcId(a)));
        }
    }
}

/// Random cuts of `0..n` into blocks of consecutive ids: any number of
/// blocks from 2 up to one per vertex, at random places (so blocks one
/// vertex thick, blocks thinner than a band, and cuts inside plateaus).
fn random_cuts(n: usize, seed: u64) -> Vec<u32> {
    let mut state = seed | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    if n < 2 {
        return vec![0, n as u32];
    }
    let blocks = 2 + (next() % (n as u64 - 1)) as usize;
    let mut inner: Vec<u32> = (1..n as u32).collect();
    // A random subset of blocks - 1 inner cuts.
    for i in 0..blocks - 1 {
        let j = i + (next() % (inner.len() - i) as u64) as usize;
        inner.swap(i, j);
    }
    inner.truncate(blocks - 1);
    inner.sort_unstable();
    let mut cuts = vec![0];
    cuts.extend(inner);
    cuts.push(n as u32);
    cuts
}

/// The join and split trees of `mesh`, whole and in the blocks `cuts`.
fn sweep_trees_both_ways<M: Mesh>(
    mesh: &M,
    values: &[u8],
    order: &[u32],
    cuts: &[u32],
) -> ((JoinTree, SplitTree), (JoinTree, SplitTree)) {
    let p = Progress::new();
    let codes = sweep::link_codes(mesh, values);
    let candidates = sweep::count_candidates(&codes);
    let whole = (
        sweep::join_tree(mesh, values, &codes, candidates, order, &p).expect("not cancelled"),
        sweep::split_tree(mesh, values, &codes, candidates, order, &p).expect("not cancelled"),
    );
    // The words seeded with the codes, as the engine makes them.
    let words = sweep::link_words(mesh, values);
    assert_eq!(words.census.candidates, candidates);
    assert!(
        codes
            .iter()
            .enumerate()
            .all(|(i, &c)| words.join.get(i) == c as u32)
    );
    assert_eq!(words.join, words.split);
    // The same with a word per vertex (what a mesh of 2^23 candidates or
    // more gets), whole and in blocks: the same trees, word for word.
    let wide = sweep::LinkWords {
        join: words.join.clone().widen(),
        split: words.split.clone().widen(),
        census: words.census,
    };
    // The whole sweeps with each candidate's parent written into its word
    // (what the engine does with words): the same trees, word for word.
    let whole_words = sweep::LinkWords {
        join: words.join.clone(),
        split: words.split.clone(),
        census: words.census,
    };
    let n = mesh.num_vertices() as u32;
    let ((in_words_join, _), (mut in_words_split, _)) =
        blocks::sweep_trees(mesh, values, whole_words, order.into(), &[0, n], true, &p)
            .expect("not cancelled");
    in_words_split.0.list_vertices();
    assert!(!in_words_join.0.leafward.is_packed());
    let widened = |mut t: sweep::SweepTree| {
        t.leafward = t.leafward.widen();
        t
    };
    assert_eq!(widened(whole.0.0.clone()), in_words_join.0);
    assert_eq!(widened(whole.1.0.clone()), in_words_split.0);
    let ((join, _), (mut split, _)) =
        blocks::sweep_trees(mesh, values, words, order.into(), cuts, false, &p)
            .expect("not cancelled");
    let ((wide_join, _), (mut wide_split, _)) =
        blocks::sweep_trees(mesh, values, wide, order.into(), cuts, false, &p)
            .expect("not cancelled");
    // In one block the split tree's vertices are left in its words.
    if cuts.len() <= 2 {
        split.0.list_vertices();
        wide_split.0.list_vertices();
    }
    assert!(join.0.leafward.is_packed() && !wide_join.0.leafward.is_packed());
    assert_eq!(widened(join.0.clone()), wide_join.0);
    assert_eq!(widened(split.0.clone()), wide_split.0);
    (whole, (join, split))
}

fn u8_values(field: &ScalarField) -> &[u8] {
    let Values::U8(values) = field.values() else {
        unreachable!("u8 grid")
    };
    values.as_slice()
}

/// Every vertex's place and every arc's vertices, in order.
fn assert_same_tree(a: &ContourTree, b: &ContourTree) -> Result<(), TestCaseError> {
    prop_assert_eq!(a.nodes(), b.nodes());
    prop_assert_eq!(a.arcs(), b.arcs());
    for arc in 0..a.arcs().len() as u32 {
        prop_assert_eq!(a.arc_vertices(ArcId(arc)), b.arc_vertices(ArcId(arc)));
    }
    for v in 0..a.num_vertices() as u32 {
        prop_assert_eq!(a.place(v), b.place(v));
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Divide and conquer: the join and split trees computed in random
    /// blocks and glued are the whole sweep's, word for word (parents,
    /// children counts, every vertex's leafward candidate, the candidates'
    /// vertices), on 3D grids with heavy ties.
    #[test]
    fn blocked_sweeps_equal_the_whole_sweeps_on_random_3d_grids(field in random_grid(), seed in any::<u64>()) {
        let cuts = random_cuts(field.len(), seed);
        let order = field.vertex_order();
        let (whole, blocked) = sweep_trees_both_ways(&field.mesh(), u8_values(&field), &order, &cuts);
        prop_assert_eq!(whole, blocked, "cuts {:?}", cuts);
    }

    #[test]
    fn blocked_sweeps_equal_the_whole_sweeps_on_random_2d_grids(field in random_2d_grid(), seed in any::<u64>()) {
        let cuts = random_cuts(field.len(), seed);
        let order = field.vertex_order();
        let (whole, blocked) = sweep_trees_both_ways(&field.mesh(), u8_values(&field), &order, &cuts);
        prop_assert_eq!(whole, blocked, "cuts {:?}", cuts);
    }

    /// The blocked tree is the tree: same nodes, arcs, arc vertices in
    /// order and place of every vertex, and it passes the oracles.
    #[test]
    fn blocked_tree_is_the_tree_on_random_grids(field in random_grid(), seed in any::<u64>()) {
        let cuts = random_cuts(field.len(), seed);
        let order = field.vertex_order();
        let (blocked, _) = ContourTree::build_in_blocks(&field.mesh(), u8_values(&field), &order, &cuts, &Progress::new())
            .expect("not cancelled");
        assert_same_tree(&blocked, &build(&field))?;
        common::tree_oracle::check_against_oracles(&field, &blocked);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    /// Blocks of a general mesh (its span from its edge list, every vertex
    /// through the general link path), including meshes whose vertex ids
    /// are shuffled so that edges reach far across the cuts.
    #[test]
    fn blocked_sweeps_equal_the_whole_sweeps_on_explicit_meshes(field in random_grid(), seed in any::<u64>(), shuffle in any::<bool>()) {
        let n = field.len();
        let grid = field.mesh();
        let mut id: Vec<u32> = (0..n as u32).collect();
        if shuffle {
            let mut s = seed | 1;
            for i in (1..n).rev() {
                s ^= s << 13; s ^= s >> 7; s ^= s << 17;
                id.swap(i, (s % (i as u64 + 1)) as usize);
            }
        }
        let mut values = vec![0u8; n];
        for (v, &x) in u8_values(&field).iter().enumerate() {
            values[id[v] as usize] = x;
        }
        let mut edges = Vec::new();
        for v in 0..n as u32 {
            grid.for_each_neighbour(v, |u| if u > v { edges.push((id[v as usize], id[u as usize])) });
        }
        let mesh = flexiso::mesh::EdgeListMesh::new(n, &edges);
        let field2 = ScalarField::new([n, 1, 1], Values::U8(values.clone())).expect("valid");
        let order = field2.vertex_order();
        let cuts = random_cuts(n, seed.rotate_left(17));
        let (whole, blocked) = sweep_trees_both_ways(&mesh, &values, &order, &cuts);
        prop_assert_eq!(whole, blocked, "cuts {:?}", cuts);
    }
}

/// The default number of blocks follows the thread count, and on a few
/// cores the share of candidates ([`blocks::pay`]: a noisy grid is swept
/// whole on 3 and 4 threads); the tree follows neither. Built on 1, 2, 3,
/// 4 and 8 threads, it is the same, vertex for vertex, on a noisy grid
/// and a smooth one, large enough to be cut.
#[test]
fn tree_is_the_same_on_every_thread_count() {
    for (noise, blocked_on) in [(0.3, &[8][..]), (0.0, &[3, 4, 8][..])] {
        let field = flexiso::field::synthetic::Synthetic {
            dims: [40, 36, 48],
            ..flexiso::field::synthetic::Synthetic::cube(1)
        }
        .with_noise(noise, 7)
        .generate();
        let reference = build(&field);
        for threads in [1, 2, 3, 4, 8] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let (tree, times) =
                pool.install(|| ContourTree::from_field(&field, &Progress::new()).expect("tree"));
            assert_eq!(
                times.blocks > 1,
                blocked_on.contains(&threads),
                "noise {noise}, {threads} threads: {} blocks",
                times.blocks
            );
            assert_same_tree(&tree, &reference).expect("same tree");
        }
    }
}

/// Above 2^24 vertices the arcs' vertex lists keep 4 bytes per id (below,
/// 3: every other test): on an image of 4097 x 4096 ramps, every regular
/// vertex lies in the list of the superarc its place names, once, the
/// lists ascending in the vertex order, and the others are supernodes.
#[test]
fn the_vertex_lists_of_a_mesh_above_2_24_vertices_are_in_words() {
    use flexiso::tree::{ArcVertices, VertexPlace};
    let (w, h) = (4097usize, 4096usize);
    let values: Vec<u8> = (0..w * h)
        .map(|i| ((i % w) / 61 * 3 + (i / w) / 53 * 5) as u8)
        .collect();
    let field = grid([w, h, 1], values);
    let n = field.len();
    assert!(n > 1 << 24);
    let tree = build(&field);
    assert!(tree.arcs().len() > 100, "{} arcs", tree.arcs().len());
    let mut seen = vec![false; n];
    for a in 0..tree.arcs().len() as u32 {
        let vs = tree.arc_vertices(ArcId(a));
        assert!(matches!(vs, ArcVertices::Wide(_)));
        let mut below = tree.node(tree.arc(ArcId(a)).lower).vertex;
        for v in vs {
            assert_eq!(tree.place(v), VertexPlace::Arc(ArcId(a)), "vertex {v}");
            assert!(
                !std::mem::replace(&mut seen[v as usize], true),
                "vertex {v} twice"
            );
            assert!(field.is_above(v, below), "arc {a} not ascending at {v}");
            below = v;
        }
        assert!(field.is_above(tree.node(tree.arc(ArcId(a)).upper).vertex, below));
    }
    for (v, seen) in seen.iter().enumerate() {
        assert_eq!(
            *seen,
            !matches!(tree.place(v as u32), VertexPlace::Node(_)),
            "vertex {v}"
        );
    }
}
