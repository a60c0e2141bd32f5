//! The Raichel-Seshadhri engine (`flexiso::tree::raichel_seshadhri`)
//! against the current engine and against the brute-force oracles of
//! tests/common/tree_oracle.rs (shared with tests/tree_oracle.rs):
//!
//! (a) the join and split trees recomputed from the output contour tree equal
//!     those computed by definition (Carr et al. Def. 4.1) by flooding the
//!     superlevel / sublevel sets on the mesh;
//! (b) every vertex's up/down degree equals the number of components of
//!     {f > f(v)} / {f < f(v)} (vertex order) adjacent to v, by flooding;
//! (c) for isovalues h that are not vertex values, the number of superarcs
//!     spanning h equals the number of components of the level set {f = h}.
//!
//! and, stronger, the tree is *identical* to the current engine's: same
//! supernodes, superarcs, place of every vertex, arc vertices in order.

use flexiso::field::{ScalarField, Values};
use flexiso::progress::Progress;
use flexiso::tree::raichel_seshadhri::{self, families};
use flexiso::tree::{ArcId, ContourTree};
use proptest::prelude::*;

mod common;

use common::tree_oracle::check_against_oracles;

/// The tree of the new engine; with `count`, through the counting order.
fn rs_tree(field: &ScalarField, count: bool) -> ContourTree {
    raichel_seshadhri::from_field(field, count, &Progress::new())
        .expect("not cancelled")
        .0
}

fn engine_tree(field: &ScalarField) -> ContourTree {
    ContourTree::from_field(field, &Progress::new())
        .expect("not cancelled")
        .0
}

/// Asserts two trees are the same augmented tree, field by field.
fn assert_same_tree(new: &ContourTree, old: &ContourTree) {
    assert_eq!(new.nodes(), old.nodes(), "supernodes");
    assert_eq!(new.arcs(), old.arcs(), "superarcs");
    assert_eq!(new.num_vertices(), old.num_vertices());
    for a in 0..old.arcs().len() as u32 {
        assert_eq!(
            new.arc_vertices(ArcId(a)),
            old.arc_vertices(ArcId(a)),
            "regular vertices of arc {a}"
        );
    }
    for v in 0..old.num_vertices() as u32 {
        assert_eq!(new.place(v), old.place(v), "place of vertex {v}");
    }
}

/// The new engine's tree equals the engine's, passes the oracles, and
/// counting comparisons does not change it.
fn check(field: &ScalarField) {
    let new = rs_tree(field, false);
    assert_same_tree(&new, &engine_tree(field));
    assert_same_tree(&rs_tree(field, true), &new);
    check_against_oracles(field, &new);
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

/// Larger grids (up to 16^3, many critical points) against the engine only:
/// the oracles are quadratic.
fn random_large_grid() -> impl Strategy<Value = ScalarField> {
    (2usize..=16, 2usize..=16, 1usize..=16, 2u8..=30).prop_flat_map(|(x, y, z, levels)| {
        proptest::collection::vec(0..levels, x * y * z).prop_map(move |v| grid([x, y, z], v))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn same_tree_as_the_engine_and_the_definitions_on_random_3d_grids(field in random_grid()) {
        check(&field);
    }

    #[test]
    fn same_tree_as_the_engine_and_the_definitions_on_random_2d_grids(field in random_2d_grid()) {
        check(&field);
    }

    #[test]
    fn same_tree_as_the_engine_and_the_definitions_on_distinct_float_values(
        (dims, values) in (2usize..=5, 2usize..=5, 1usize..=5).prop_flat_map(|(x, y, z)| {
            (Just([x, y, z]), proptest::collection::vec(-1000.0f32..1000.0, x * y * z))
        })
    ) {
        check(&ScalarField::new(dims, Values::F32(values)).expect("valid"));
    }

    #[test]
    fn same_tree_as_the_engine_on_larger_random_grids(field in random_large_grid()) {
        assert_same_tree(&rs_tree(&field, false), &engine_tree(&field));
    }
}

#[test]
fn hand_examples_give_the_engines_tree() {
    check(&grid([1, 1, 1], vec![3]));
    check(&grid([2, 1, 1], vec![3, 3]));
    check(&grid([5, 1, 1], vec![0, 5, 1, 4, 2]));
    check(&grid([4, 4, 3], vec![7; 48]));
    check(&grid([2, 2, 2], vec![1, 0, 0, 1, 0, 1, 1, 0]));
    #[rustfmt::skip]
    let two_hills = vec![
        0, 0, 0, 0, 0,
        0, 9, 3, 8, 0,
        0, 0, 0, 0, 0,
    ];
    check(&grid([5, 3, 1], two_hills));
}

#[test]
fn a_ring_of_high_values_joins_itself_without_a_supernode() {
    // 2D: a ring of 9s around a low centre. The vertex where the ring closes
    // has two upper link components in one superlevel component: painting
    // must not make it a join.
    #[rustfmt::skip]
    let ring = vec![
        0, 0, 0, 0, 0, 0,
        0, 9, 9, 9, 9, 0,
        0, 9, 1, 1, 9, 0,
        0, 9, 1, 1, 9, 0,
        0, 9, 9, 9, 9, 0,
        0, 0, 0, 0, 0, 0,
    ];
    check(&grid([6, 6, 1], ring));
}

#[test]
fn experiment_families_give_the_engines_tree() {
    for n in [8, 13, 16, 24] {
        for field in [families::short_and_fat(n), families::tall_and_thin(n)] {
            assert_same_tree(&rs_tree(&field, false), &engine_tree(&field));
        }
    }
    check(&families::short_and_fat(9));
    check(&families::tall_and_thin(9));
}

#[test]
fn short_and_fat_needs_fewer_comparisons_than_a_sort_and_tall_and_thin_more_painting() {
    let n = 32;
    let count = |field: &ScalarField| {
        raichel_seshadhri::from_field(field, true, &Progress::new())
            .expect("not cancelled")
            .1
            .comparisons
    };
    let fat = count(&families::short_and_fat(n));
    let thin = count(&families::tall_and_thin(n));
    let v = (n * n * n) as f64;
    // Every edge once: 7 per vertex, less on the boundary.
    assert!(fat.links as f64 <= 7.0 * v);
    assert!((fat.total() as f64) < v * v.log2(), "{fat:?}");
    // The staircase's painting heaps hold whole spines: more per critical
    // point than the octree's.
    assert!(thin.paint > fat.paint, "{thin:?} vs {fat:?}");
}
