//! Contour following against independent oracles: topology of every
//! extracted contour, the tree's Betti prediction, and a plain
//! marching-tetrahedra pass over the whole volume.

use flexiso::contour::oracle::{all_contours_by_following, marching_tetrahedra};
use flexiso::contour::topology::triangle_area;
use flexiso::contour::{
    ContourFollower, ContourMesh, MeshTopology, PathSeed, PathSeeds, all_contours,
    contours_through, path_seed, path_seed_in_chain,
};
use flexiso::field::{Isovalue, ScalarField, Values};
use flexiso::measure::betti::ContourTopology;
use flexiso::progress::Progress;
use flexiso::tree::{ArcId, ContourTree};
use proptest::prelude::*;

fn tree_of(field: &ScalarField) -> ContourTree {
    ContourTree::from_field(field, &Progress::new())
        .expect("not cancelled")
        .0
}

/// Checks every contour at `iso`, returns them.
fn check_all(
    field: &ScalarField,
    tree: &ContourTree,
    betti: &ContourTopology,
    iso: Isovalue,
) -> Vec<ContourMesh> {
    let contours = all_contours(tree, field, iso);
    for c in &contours {
        let t = MeshTopology::of(&c.positions, &c.indices);
        assert!(
            c.num_triangles() > 0,
            "arc {:?} at {iso:?}: empty contour",
            c.arc
        );
        assert_eq!(t.components, 1, "arc {:?}: one component", c.arc);
        assert_eq!(t.non_manifold_edges, 0, "manifold edges");
        assert_eq!(t.non_manifold_vertices, 0, "manifold vertices");
        assert_eq!(t.misoriented_edges, 0, "consistently oriented");
        assert_eq!(t.vertices, c.positions.len(), "no unused vertex");
        assert!(
            c.indices
                .chunks_exact(3)
                .all(|tri| triangle_area(&c.positions, tri) > 0.0),
            "arc {:?} at {iso:?}: a zero-area triangle",
            c.arc
        );
        assert_eq!(c.normals.len(), c.positions.len());
        assert_eq!(
            t.is_closed(),
            !c.touches_boundary,
            "closed iff inside the box"
        );
        let predicted = betti.at(c.arc, field, iso);
        assert_eq!(
            t.euler, predicted.euler,
            "arc {:?} at {iso:?}: Euler characteristic",
            c.arc
        );
        assert_eq!(
            t.is_closed(),
            predicted.closed(),
            "arc {:?}: closedness",
            c.arc
        );
    }
    // No two vertices at one place, within a contour or between two.
    let mut places: Vec<[u32; 3]> = contours
        .iter()
        .flat_map(|c| c.positions.iter().map(|p| p.map(f32::to_bits)))
        .collect();
    let len = places.len();
    places.sort_unstable();
    places.dedup();
    assert_eq!(places.len(), len, "at {iso:?}: two vertices at one place");
    // Seeds in any order get their own contours back, in their order.
    let seeds = PathSeeds::new();
    let reversed: Vec<PathSeed> = contours
        .iter()
        .rev()
        .filter_map(|c| seeds.seed(tree, field, c.arc, iso))
        .collect();
    let through = contours_through(tree, field, &reversed, iso);
    assert_eq!(through.len(), contours.len());
    for (t, c) in through.iter().zip(contours.iter().rev()) {
        assert_eq!((t.arc, t.num_triangles()), (c.arc, c.num_triangles()));
    }
    // The parallel sweep and following every seed give the same contours.
    let followed = all_contours_by_following(tree, field, iso);
    assert_eq!(contours.len(), followed.len(), "as many contours as seeds");
    for (c, f) in contours.iter().zip(&followed) {
        assert_eq!(c.arc, f.arc, "the same arcs, in arc order");
        assert_eq!(
            c.positions.len(),
            f.positions.len(),
            "arc {:?}: vertices",
            c.arc
        );
        assert_eq!(c.touches_boundary, f.touches_boundary, "arc {:?}", c.arc);
        assert_eq!(
            c.triangle_soup(),
            f.triangle_soup(),
            "arc {:?} at {iso:?}: the same oriented triangles",
            c.arc
        );
        for n in &c.normals {
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!((l - 1.0).abs() < 1e-4, "unit normals, got {n:?}");
        }
    }
    // The union is the plain isosurface.
    let all = marching_tetrahedra(field, iso);
    let whole = MeshTopology::of(&all.positions, &all.indices);
    let tris: usize = contours.iter().map(|c| c.num_triangles()).sum();
    assert_eq!(
        tris,
        all.num_triangles(),
        "same triangles as marching tetrahedra"
    );
    let area: f64 = contours
        .iter()
        .map(|c| MeshTopology::of(&c.positions, &c.indices).area)
        .sum();
    assert!(
        (area - whole.area).abs() <= 1e-4 * (1.0 + whole.area),
        "area {area} vs {}",
        whole.area
    );
    assert_eq!(
        contours.len(),
        whole.components,
        "one contour per level-set component"
    );
    contours
}

/// The xorshift generator of `seed` (not 0): each call the next state.
fn xorshift(mut s: u64) -> impl FnMut() -> u64 {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

/// A float32 field of `dims` with values from a xorshift of `seed`, in
/// [0, 1): no ties.
fn noisy_field(dims: (usize, usize, usize), seed: u64) -> ScalarField {
    let n = dims.0 * dims.1 * dims.2;
    let mut next = xorshift(seed | 1);
    let values: Vec<f32> = (0..n)
        .map(|_| (next() >> 40) as f32 / (1u64 << 24) as f32)
        .collect();
    ScalarField::new([dims.0, dims.1, dims.2], Values::F32(values)).expect("valid")
}

/// An 8-bit grid with sides `least` plus up to `spread - 1` each and
/// values below `levels` (many ties), drawn by `below` (a number below
/// its argument).
fn random_u8_grid(
    below: &mut impl FnMut(u64) -> u64,
    least: [usize; 3],
    spread: u64,
    levels: u64,
) -> ScalarField {
    let d = least.map(|l| l + below(spread) as usize);
    let values: Vec<u8> = (0..d[0] * d[1] * d[2])
        .map(|_| below(levels) as u8)
        .collect();
    ScalarField::new(d, Values::U8(values)).expect("valid")
}

fn random_field() -> impl Strategy<Value = ScalarField> {
    (2usize..7, 2usize..7, 2usize..7).prop_flat_map(|(x, y, z)| {
        proptest::collection::vec(0u8..7, x * y * z)
            .prop_map(move |v| ScalarField::new([x, y, z], Values::U8(v)).expect("valid"))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn contours_match_marching_tetrahedra_and_betti_on_random_grids(
        field in random_field(),
        h in 0u32..14,
    ) {
        let tree = tree_of(&field);
        let betti = ContourTopology::new(&tree, &field);
        // Even h: exactly a vertex value (ties everywhere); odd: between.
        let iso = Isovalue::new(h as f64 / 2.0);
        check_all(&field, &tree, &betti, iso);
    }

    #[test]
    fn extraction_just_above_any_vertex_works(field in random_field(), pick in 0usize..1000) {
        let tree = tree_of(&field);
        let betti = ContourTopology::new(&tree, &field);
        let v = (pick % field.len()) as u32;
        check_all(&field, &tree, &betti, Isovalue::just_above(&field, v));
    }

    #[test]
    fn contours_on_noisy_float_grids(
        dims in (3usize..9, 3usize..9, 3usize..9),
        seed in any::<u64>(),
        t in 0.0f64..1.0,
    ) {
        let field = noisy_field(dims, seed);
        let tree = tree_of(&field);
        let betti = ContourTopology::new(&tree, &field);
        check_all(&field, &tree, &betti, Isovalue::new(t));
    }
}

/// A field sampled from `f` on `n` points per axis over [lo, hi]^3-ish boxes.
fn analytic(
    dims: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
    f: impl Fn([f64; 3]) -> f64,
) -> ScalarField {
    let mut v = Vec::new();
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let p = [x, y, z];
                let q: [f64; 3] = std::array::from_fn(|k| {
                    lo[k] + (hi[k] - lo[k]) * p[k] as f64 / (dims[k] - 1) as f64
                });
                v.push(f(q) as f32);
            }
        }
    }
    ScalarField::new(dims, Values::F32(v)).expect("valid")
}

/// The contours at `h` with their (Euler characteristic, closed) sorted.
fn contour_topologies(field: &ScalarField, h: f64) -> Vec<(i64, bool)> {
    let tree = tree_of(field);
    let betti = ContourTopology::new(&tree, field);
    let mut out: Vec<(i64, bool)> = check_all(field, &tree, &betti, Isovalue::new(h))
        .iter()
        .map(|c| {
            let t = MeshTopology::of(&c.positions, &c.indices);
            (t.euler, t.is_closed())
        })
        .collect();
    out.sort_unstable();
    out
}

#[test]
fn sphere_contour_has_euler_characteristic_two() {
    let f = analytic([20, 20, 20], [-1.0; 3], [1.0; 3], |p| {
        -(p[0] * p[0] + p[1] * p[1] + 1.3 * p[2] * p[2] + 0.1 * p[0])
    });
    assert_eq!(contour_topologies(&f, -0.5), vec![(2, true)]);
}

#[test]
fn torus_contour_has_genus_one() {
    let f = analytic([40, 40, 16], [-1.0, -1.0, -0.4], [1.0, 1.0, 0.4], |p| {
        let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
        // Tilted so the ridge circle is not a plateau of maxima.
        -((rho - 0.6).powi(2) + p[2] * p[2]) + 0.01 * p[0]
    });
    assert_eq!(contour_topologies(&f, -0.04), vec![(0, true)]);
}

#[test]
fn double_torus_contour_has_genus_two() {
    let f = analytic([72, 40, 16], [-0.3, -0.7, -0.25], [2.3, 0.7, 0.25], |p| {
        let [x, y, z] = p;
        let g = x * (x - 1.0).powi(2) * (x - 2.0) + y * y;
        -(g * g + z * z) + 0.001 * x
    });
    assert_eq!(contour_topologies(&f, -0.01), vec![(-2, true)]);
}

#[test]
fn nested_spheres_are_two_contours() {
    // A hollow shell around a core: below the shell's crest the level set
    // is an outer sphere and an inner one; deeper inside, a core sphere.
    let f = analytic([30, 30, 30], [-1.0; 3], [1.0; 3], |p| {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        (-((r - 0.6) / 0.15).powi(2)).exp() + 0.02 * p[2]
    });
    assert_eq!(contour_topologies(&f, 0.5), vec![(2, true), (2, true)]);
}

#[test]
fn a_contour_cut_by_the_box_is_open() {
    let f = analytic([12, 12, 12], [0.0; 3], [1.0; 3], |p| {
        p[0] + 0.3 * p[1] + 0.1 * p[2]
    });
    assert_eq!(contour_topologies(&f, 0.6), vec![(1, false)]);
}

#[test]
fn follower_is_reusable_and_seed_lies_on_the_contour() {
    let field = flexiso::field::synthetic::Synthetic::cube(24).generate();
    let tree = tree_of(&field);
    let mut follower = ContourFollower::new(&field);
    let (lo, hi) = field.range();
    for k in 1..10 {
        let iso = Isovalue::new(lo + (hi - lo) * k as f64 / 10.0);
        for a in 0..tree.arcs().len() as u32 {
            let Some(seed) = path_seed(&tree, &field, ArcId(a), iso) else {
                continue;
            };
            assert!(iso.is_above(&field, seed.above) && !iso.is_above(&field, seed.below));
            let first = follower.follow(&seed, iso);
            let again = follower.follow(&seed, iso);
            assert_eq!(first, again);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Every spanning arc has a seed, on an edge the cut crosses, whose
    /// contour is the arc's (the one all_contours extracts), whether the
    /// arc has regular vertices or is bare (a join on top of a split).
    #[test]
    fn every_spanning_arc_has_a_seed_on_its_own_contour(
        field in random_field(),
        h in 0u32..14,
    ) {
        let tree = tree_of(&field);
        let iso = Isovalue::new(h as f64 / 2.0);
        let all = all_contours(&tree, &field, iso);
        let seeds = PathSeeds::new();
        let mut follower = ContourFollower::new(&field);
        for c in &all {
            let seed = path_seed(&tree, &field, c.arc, iso).expect("a spanning arc has a seed");
            prop_assert_eq!(Some(seed), seeds.seed(&tree, &field, c.arc, iso));
            prop_assert!(iso.is_above(&field, seed.above) && !iso.is_above(&field, seed.below));
            let mine = follower.follow(&seed, iso);
            prop_assert_eq!(mine.triangle_soup(), c.triangle_soup());
        }
        for a in 0..tree.arcs().len() as u32 {
            let spans = flexiso::contour::arc_spans(&tree, &field, ArcId(a), iso);
            prop_assert_eq!(path_seed(&tree, &field, ArcId(a), iso).is_some(), spans);
        }
    }
}

#[test]
fn seeds_in_simplified_chains_land_on_the_spanning_superarc() {
    use flexiso::simplify::{Measure, Simplification, SimplifiedTree};
    let field = flexiso::field::synthetic::Synthetic::cube(20)
        .with_noise(0.05, 7)
        .generate();
    let tree = tree_of(&field);
    let sim = std::sync::Arc::new(Simplification::new(&tree, &field, Measure::Volume));
    let mut level = SimplifiedTree::new(sim);
    level.set_level(6);
    let (lo, hi) = field.range();
    let mut follower = ContourFollower::new(&field);
    let mut extracted = 0;
    for k in 1..20 {
        let iso = Isovalue::new(lo + (hi - lo) * k as f64 / 20.0);
        for arc in level.arcs() {
            let chain = arc.chain;
            let spanning: Vec<ArcId> = chain
                .iter()
                .copied()
                .filter(|&e| flexiso::contour::arc_spans(&tree, &field, e, iso))
                .collect();
            assert!(spanning.len() <= 1, "a chain is a monotone path");
            let seed = path_seed_in_chain(&tree, &field, chain, iso);
            assert_eq!(seed.map(|s| s.arc), spanning.first().copied());
            if let Some(seed) = seed {
                let c = follower.follow(&seed, iso);
                let t = MeshTopology::of(&c.positions, &c.indices);
                assert!(c.num_triangles() > 0 && t.components == 1);
                extracted += 1;
            }
        }
    }
    assert!(extracted > 10, "the test exercised chains");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    /// A follower built on the tables of followers of other fields (of
    /// other sizes, and of the same size) extracts what a fresh one does:
    /// the explorer's worker carries them from job to job.
    #[test]
    fn follower_tables_carried_across_fields_give_the_same_contours(
        a in random_field(),
        b in random_field(),
        h in 0u32..14,
    ) {
        let iso = Isovalue::new(h as f64 / 2.0);
        let mut scratch = flexiso::contour::FollowerScratch::default();
        // a, b, a again: the table is sized for b, then for a with b's
        // records left in it.
        for field in [&a, &b, &a] {
            let tree = tree_of(field);
            for arc in 0..tree.arcs().len() as u32 {
                let Some(seed) = path_seed(&tree, field, ArcId(arc), iso) else {
                    continue;
                };
                let fresh = ContourFollower::new(field).follow(&seed, iso);
                let mut carried = ContourFollower::with_scratch(field, std::mem::take(&mut scratch));
                let mesh = carried.follow(&seed, iso);
                scratch = carried.into_scratch();
                prop_assert_eq!(mesh, fresh);
            }
        }
    }
}

/// Checks that `extract` (on every core, through the sweep when
/// `serial_limit` is 0) gives the contour `follow` gives: the same
/// oriented triangles on as many shared vertices, the same boundary flag,
/// the same topology, and at each position the same unit normal (up to
/// the order the area-weighted sums were added in).
fn assert_same_contour(fast: &ContourMesh, oracle: &ContourMesh, at: &str) {
    assert_eq!(fast.arc, oracle.arc, "{at}: arc");
    assert_eq!(
        fast.positions.len(),
        oracle.positions.len(),
        "{at}: shared vertices"
    );
    assert_eq!(fast.normals.len(), fast.positions.len(), "{at}: normals");
    assert_eq!(
        fast.touches_boundary, oracle.touches_boundary,
        "{at}: boundary"
    );
    // A winding the extraction knew is the one a closed contour's
    // triangles have.
    if let Some(ccw) = fast.ccw_outward.filter(|_| !fast.touches_boundary) {
        let v = oracle.signed_volume6();
        assert!(v != 0.0, "{at}: a closed contour encloses something");
        assert_eq!(ccw, v > 0.0, "{at}: winding seen from outside");
    }
    assert_eq!(
        fast.triangle_soup(),
        oracle.triangle_soup(),
        "{at}: the same oriented triangles"
    );
    let (a, b) = (
        MeshTopology::of(&fast.positions, &fast.indices),
        MeshTopology::of(&oracle.positions, &oracle.indices),
    );
    assert_eq!(
        (a.euler, a.components, a.vertices, a.edges, a.boundary_edges),
        (b.euler, b.components, b.vertices, b.edges, b.boundary_edges),
        "{at}: topology"
    );
    let by_position = |m: &ContourMesh| {
        let mut v: Vec<([u32; 3], [f32; 3])> = m
            .positions
            .iter()
            .zip(&m.normals)
            .map(|(p, n)| (p.map(f32::to_bits), *n))
            .collect();
        v.sort_unstable_by(|x, y| {
            x.0.cmp(&y.0).then(
                x.1.iter()
                    .zip(&y.1)
                    .fold(std::cmp::Ordering::Equal, |o, (a, b)| {
                        o.then(a.total_cmp(b))
                    }),
            )
        });
        v
    };
    let (pa, pb) = (by_position(fast), by_position(oracle));
    let mut far = Vec::new();
    for ((p, n), (q, m)) in pa.iter().zip(&pb) {
        assert_eq!(p, q, "{at}: the same vertex positions");
        let d = (0..3).map(|k| (n[k] - m[k]).abs()).fold(0f32, f32::max);
        if d > 1e-3 {
            far.push((*n, *m));
        }
    }
    // A vertex whose downhill gradient is (nearly) perpendicular to its
    // area-weighted normal takes the one or the other depending on the
    // order the face normals were summed in (on integer grids the dot
    // product can be exactly zero); such vertices are rare.
    assert!(
        far.len() <= 2 + pa.len() / 500,
        "{at}: {} of {} normals differ: {far:?}",
        far.len(),
        pa.len()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// The parallel extraction (forced through the sweep) gives every
    /// spanning arc's contour as the serial follower does, with the
    /// Euler characteristic the tree predicts.
    #[test]
    fn parallel_extraction_matches_the_follower_on_random_grids(
        field in random_field(),
        h in 0u32..14,
    ) {
        let tree = tree_of(&field);
        let betti = ContourTopology::new(&tree, &field);
        let iso = Isovalue::new(h as f64 / 2.0);
        let mut oracle = ContourFollower::new(&field);
        let mut fast = ContourFollower::new(&field).with_serial_limit(0);
        for arc in 0..tree.arcs().len() as u32 {
            let Some(seed) = path_seed(&tree, &field, ArcId(arc), iso) else {
                continue;
            };
            let want = oracle.follow(&seed, iso);
            let got = fast.extract(&tree, &seed, iso, &|| false).expect("not cancelled");
            assert_same_contour(&got, &want, &format!("arc {arc} at {iso:?}"));
            let t = MeshTopology::of(&got.positions, &got.indices);
            prop_assert_eq!(t.euler, betti.at(ArcId(arc), &field, iso).euler);
        }
    }

    /// A drag step's size hint (what `extract_expecting` is told) only
    /// chooses the path: up to the serial limit (the flood first, the
    /// sweep if it grows past the limit) and beyond it (straight to the
    /// sweep) all give the follower's contour, on two threads as on a
    /// 2-core machine, also when written into a recycled mesh's arrays.
    #[test]
    fn a_size_hint_never_changes_the_contour(
        dims in (3usize..12, 3usize..12, 3usize..12),
        seed in any::<u64>(),
        t in 0.0f64..1.0,
    ) {
        let field = noisy_field(dims, seed);
        let tree = tree_of(&field);
        let iso = Isovalue::new(t);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("pool");
        let limit = flexiso::contour::follow::serial_limit(field.len(), 2);
        let mut oracle = ContourFollower::new(&field);
        let mut fast = ContourFollower::new(&field);
        let mut last = None;
        for arc in 0..tree.arcs().len() as u32 {
            let Some(seed) = path_seed(&tree, &field, ArcId(arc), iso) else {
                continue;
            };
            let want = oracle.follow(&seed, iso);
            for hint in [None, Some(1), Some(limit), Some(limit + 1), Some(1 << 40)] {
                // Written into the arrays of the last contour extracted
                // (of this arc or another, larger or smaller).
                if let Some(spare) = last.take() {
                    fast.recycle(spare);
                }
                let got = pool
                    .install(|| fast.extract_expecting(&tree, &seed, iso, hint, &|| false))
                    .expect("not cancelled");
                assert_same_contour(&got, &want, &format!("arc {arc} at {iso:?}, hint {hint:?}"));
                last = Some(got);
            }
        }
    }

    #[test]
    fn parallel_extraction_matches_the_follower_on_noisy_float_grids(
        dims in (3usize..12, 3usize..12, 3usize..12),
        seed in any::<u64>(),
        t in 0.0f64..1.0,
        limit in prop_oneof![Just(0usize), Just(20), Just(usize::MAX)],
    ) {
        let field = noisy_field(dims, seed);
        let tree = tree_of(&field);
        let betti = ContourTopology::new(&tree, &field);
        let iso = Isovalue::new(t);
        let mut oracle = ContourFollower::new(&field);
        let mut fast = ContourFollower::new(&field).with_serial_limit(limit);
        for arc in 0..tree.arcs().len() as u32 {
            let Some(seed) = path_seed(&tree, &field, ArcId(arc), iso) else {
                continue;
            };
            let want = oracle.follow(&seed, iso);
            let got = fast.extract(&tree, &seed, iso, &|| false).expect("not cancelled");
            assert_same_contour(&got, &want, &format!("arc {arc} at {iso:?}"));
            let t = MeshTopology::of(&got.positions, &got.indices);
            prop_assert_eq!(t.euler, betti.at(ArcId(arc), &field, iso).euler);
        }
    }
}

/// Cancellation: a request cancelled before it starts, in the flood, or
/// in any phase of the sweep returns no mesh at all, and the follower's
/// next extraction is whole and right. Where the flood races the sweep
/// (limit 5000: past 1250 triangles) a cancel seen by one side only may
/// let the other finish: then its mesh is whole and right, never partial.
#[test]
fn cancelled_extraction_returns_nothing_and_leaves_the_follower_sound() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let field = flexiso::field::synthetic::Synthetic::cube(96).generate();
    let tree = tree_of(&field);
    let (lo, hi) = field.range();
    let mut follower = ContourFollower::new(&field);
    // The largest contour at a few isovalues.
    let (iso, seed) = (1..10)
        .map(|k| Isovalue::new(lo + (hi - lo) * k as f64 / 10.0))
        .flat_map(|iso| {
            let (tree, field) = (&tree, &field);
            (0..tree.arcs().len() as u32)
                .filter_map(move |a| path_seed(tree, field, ArcId(a), iso).map(|s| (iso, s)))
                .collect::<Vec<_>>()
        })
        .max_by_key(|(iso, s)| follower.follow(s, *iso).num_triangles())
        .expect("a contour");
    let want = ContourFollower::new(&field).follow(&seed, iso);
    assert!(want.num_triangles() > 20_000, "a contour worth cancelling");
    for limit in [0, 5_000, usize::MAX] {
        let mut follower = ContourFollower::new(&field).with_serial_limit(limit);
        // How many times an uncancelled extraction asks.
        let asked = AtomicUsize::new(0);
        let whole = follower
            .extract(&tree, &seed, iso, &|| {
                asked.fetch_add(1, Ordering::Relaxed);
                false
            })
            .expect("not cancelled");
        assert_same_contour(&whole, &want, &format!("limit {limit}"));
        let asked = asked.into_inner();
        assert!(asked >= 2, "limit {limit}: asked {asked} times");
        for stop_at in [1, 2, asked / 2, asked] {
            let calls = AtomicUsize::new(0);
            let r = follower.extract(&tree, &seed, iso, &|| {
                calls.fetch_add(1, Ordering::Relaxed) + 1 >= stop_at
            });
            match r {
                Ok(m) if limit == 5_000 && stop_at > 1 => {
                    assert_same_contour(&m, &want, &format!("limit {limit}, raced past a cancel"))
                }
                r => assert_eq!(
                    r.map(|m| m.num_triangles()),
                    Err(flexiso::contour::follow::Cancelled),
                    "limit {limit}, cancelled at call {stop_at} of {asked}"
                ),
            }
            let again = follower
                .extract(&tree, &seed, iso, &|| false)
                .expect("not cancelled");
            assert_same_contour(&again, &want, &format!("limit {limit}, after a cancel"));
        }
    }
}

/// The flood raced against the sweep (a contour of unknown size past a
/// quarter of the serial limit, no other extraction running, or always):
/// whichever side wins, and whichever is
/// slowed (a cancel check that sleeps on the flood's thread or on the
/// others), the contour is the follower's, whole; the race leaves the
/// follower sound for the next extraction.
#[test]
fn the_flood_raced_against_the_sweep_gives_the_followers_contour() {
    use std::time::Duration;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    for (dims, seed, t) in [
        ((40, 36, 30), 7, 0.5),
        ((24, 50, 20), 11, 0.45),
        ((30, 30, 30), 3, 0.6),
    ] {
        let field = noisy_field(dims, seed);
        let tree = tree_of(&field);
        let iso = Isovalue::new(t);
        let mut oracle = ContourFollower::new(&field);
        let (seed, want) = (0..tree.arcs().len() as u32)
            .filter_map(|a| path_seed(&tree, &field, ArcId(a), iso))
            .map(|s| {
                let m = oracle.follow(&s, iso);
                (s, m)
            })
            .max_by_key(|(_, m)| m.num_triangles())
            .expect("a contour");
        let size = want.num_triangles();
        assert!(size > 60_000, "{dims:?}: a contour worth racing ({size})");
        let (mut swept, mut flooded) = (0, 0);
        // The race starts past a quarter of the limit: the flood gives up
        // at its limit (just past the contour, or a third short of it).
        // Raced always, or only when no other extraction runs (the
        // default: the tests beside this one make it either way).
        for (limit, always) in [size + 1, size * 3 / 4, 4 * size]
            .into_iter()
            .flat_map(|l| [(l, true), (l, false)])
        {
            let follower = ContourFollower::new(&field).with_serial_limit(limit);
            let mut follower = if always {
                follower.racing_always()
            } else {
                follower
            };
            for slow in [None, Some(true), Some(false)] {
                let got = pool.install(|| {
                    let flood = std::thread::current().id();
                    follower
                        .extract(&tree, &seed, iso, &|| {
                            let on_flood = std::thread::current().id() == flood;
                            if slow == Some(on_flood) {
                                std::thread::sleep(Duration::from_millis(3));
                            }
                            false
                        })
                        .expect("not cancelled")
                });
                let at = format!("{dims:?} limit {limit} (contour {size}), slowed {slow:?}");
                assert_same_contour(&got, &want, &at);
                // The sweep's meshes come with their box.
                if got.bounds.is_some() {
                    swept += 1;
                } else {
                    flooded += 1;
                }
            }
            let again = follower.follow(&seed, iso);
            assert_same_contour(&again, &want, "after the race");
        }
        eprintln!("{dims:?}: {swept} won by the sweep, {flooded} by the flood");
    }
}

/// The `pick`-th (cyclically) of the arcs spanning `iso`, if any.
fn spanning_arc(
    tree: &ContourTree,
    field: &ScalarField,
    iso: Isovalue,
    pick: usize,
) -> Option<ArcId> {
    let spanning: Vec<ArcId> = (0..tree.arcs().len() as u32)
        .map(ArcId)
        .filter(|&a| path_seed(tree, field, a, iso).is_some())
        .collect();
    (!spanning.is_empty()).then(|| spanning[pick % spanning.len()])
}

/// Drags one contour through `cuts` from `arc` at `from`: at each cut the
/// step to every spanning arc reached through the slab gives what the
/// follower gives for that arc there; arcs not reached are refused and
/// leave the dragged contour as it was. Every other mesh is given back
/// once checked ([`DraggedContour::recycle`]), so that steps are made both
/// in fresh arrays and in recycled ones of other sizes. Returns how many
/// steps were taken.
fn drag_matches_the_follower(
    field: &ScalarField,
    tree: &ContourTree,
    arc: ArcId,
    from: Isovalue,
    cuts: &[Isovalue],
) -> usize {
    use flexiso::contour::DraggedContour;
    use flexiso::contour::drag::Refused;
    let Some(seed) = path_seed(tree, field, arc, from) else {
        return 0;
    };
    let mut oracle = ContourFollower::new(field);
    let shared = std::sync::Arc::new(field.clone());
    let Some((mut dragged, first)) =
        DraggedContour::start(&shared, &seed, from, &|| false).expect("not cancelled")
    else {
        return 0;
    };
    assert_same_contour(&first, &oracle.follow(&seed, from), "start");
    dragged.recycle(first);
    let mut steps = 0;
    for &to in cuts {
        let mut moved = false;
        for c in 0..tree.arcs().len() as u32 {
            let Some(seed) = path_seed(tree, field, ArcId(c), to) else {
                continue;
            };
            let before = (dragged.arc(), dragged.isovalue(), dragged.num_triangles());
            match dragged
                .step(tree, ArcId(c), to, usize::MAX, &|| false)
                .expect("not cancelled")
            {
                Ok(mesh) => {
                    let at = format!("{before:?} -> arc {c} at {to:?}");
                    assert_same_contour(&mesh, &oracle.follow(&seed, to), &at);
                    if steps % 2 == 1 {
                        dragged.recycle(mesh);
                    }
                    moved = true;
                    steps += 1;
                    break;
                }
                Err(Refused::NotConnected) => {
                    assert_eq!(
                        (dragged.arc(), dragged.isovalue(), dragged.num_triangles()),
                        before,
                        "a refused step changes nothing"
                    );
                }
                Err(Refused::TooLarge) => panic!("no budget was set"),
            }
        }
        if !moved {
            // Nothing at `to` is reached from here (the contour would
            // vanish): the dragged contour stays where it is.
            continue;
        }
    }
    steps
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Dragging a contour step by step (up, down, across nodes, joining
    /// and leaving pieces) gives at every cut the contour the follower
    /// gives there.
    #[test]
    fn dragged_contours_match_the_follower_on_random_grids(
        field in random_field(),
        start in 0u32..14,
        pick in 0usize..100,
        cuts in proptest::collection::vec(0u32..14, 1..6),
    ) {
        let tree = tree_of(&field);
        let from = Isovalue::new(start as f64 / 2.0);
        let arc = spanning_arc(&tree, &field, from, pick);
        prop_assume!(arc.is_some());
        let arc = arc.expect("assumed");
        let cuts: Vec<Isovalue> = cuts.iter().map(|&c| Isovalue::new(c as f64 / 2.0)).collect();
        drag_matches_the_follower(&field, &tree, arc, from, &cuts);
    }

    #[test]
    fn dragged_contours_match_the_follower_on_noisy_float_grids(
        dims in (3usize..10, 3usize..10, 3usize..10),
        seed in any::<u64>(),
        start in 0.0f64..1.0,
        pick in 0usize..100,
        cuts in proptest::collection::vec(0.0f64..1.0, 1..6),
    ) {
        let field = noisy_field(dims, seed);
        let tree = tree_of(&field);
        let from = Isovalue::new(start);
        let arc = spanning_arc(&tree, &field, from, pick);
        prop_assume!(arc.is_some());
        let arc = arc.expect("assumed");
        // Small steps (what a drag makes) as well as far ones.
        let cuts: Vec<Isovalue> = cuts
            .iter()
            .enumerate()
            .map(|(i, &c)| Isovalue::new(if i % 2 == 0 { start + (c - 0.5) * 0.1 } else { c }))
            .collect();
        drag_matches_the_follower(&field, &tree, arc, from, &cuts);
    }
}

/// Starting a dragged contour within a limit of tetrahedra: a contour
/// with more gives up (None), one within it is the same as started
/// without a limit; on 100 random grids.
#[test]
fn a_dragged_contour_started_within_a_limit_gives_up_past_it() {
    use flexiso::contour::DraggedContour;
    let mut state = xorshift(0x2545_F491_4F6C_DD1D);
    let mut next = move |n: u64| state() % n;
    let mut gave_up = 0;
    for _ in 0..100 {
        let field = random_u8_grid(&mut next, [5, 5, 4], 6, 9);
        let tree = tree_of(&field);
        let iso = Isovalue::new(next(16) as f64 / 2.0);
        let Some(arc) = spanning_arc(&tree, &field, iso, next(5) as usize) else {
            continue;
        };
        let seed = path_seed(&tree, &field, arc, iso).expect("spans");
        let shared = std::sync::Arc::new(field.clone());
        let Some((_, whole)) =
            DraggedContour::start(&shared, &seed, iso, &|| false).expect("not cancelled")
        else {
            continue;
        };
        // A crossed tetrahedron holds one or two triangles.
        let triangles = whole.num_triangles();
        if triangles < 4 {
            continue;
        }
        let under = DraggedContour::start_within(&shared, &seed, iso, triangles / 2 - 1, &|| false)
            .expect("not cancelled");
        assert!(
            under.is_none(),
            "{triangles} triangles within a limit of {}",
            triangles / 2 - 1
        );
        gave_up += 1;
        let (_, within) = DraggedContour::start_within(&shared, &seed, iso, triangles, &|| false)
            .expect("not cancelled")
            .expect("within its limit");
        assert_eq!(within.triangle_soup(), whole.triangle_soup());
    }
    assert!(gave_up > 50, "{gave_up} contours tried");
}

/// The drags above take steps, many across nodes (not only within one
/// arc): 200 random grids, five cuts each.
#[test]
fn drags_cross_nodes_on_random_grids() {
    let mut state = xorshift(0x9E37_79B9_7F4A_7C15);
    let mut next = move |n: u64| state() % n;
    let (mut steps, mut across) = (0, 0);
    for _ in 0..200 {
        let field = random_u8_grid(&mut next, [4, 4, 3], 4, 7);
        let tree = tree_of(&field);
        let from = Isovalue::new(next(14) as f64 / 2.0);
        let Some(arc) = (0..tree.arcs().len() as u32)
            .map(ArcId)
            .find(|&a| path_seed(&tree, &field, a, from).is_some())
        else {
            continue;
        };
        let cuts: Vec<Isovalue> = (0..5)
            .map(|_| Isovalue::new(next(14) as f64 / 2.0))
            .collect();
        let n = drag_matches_the_follower(&field, &tree, arc, from, &cuts);
        steps += n;
        // Where the first step left the first arc's span.
        let a = tree.arc(arc);
        let span = (
            field.value(tree.node(a.lower).vertex),
            field.value(tree.node(a.upper).vertex),
        );
        across += usize::from(n > 0 && !(span.0 < cuts[0].value && cuts[0].value < span.1));
    }
    assert!(steps > 300, "{steps} steps taken");
    assert!(across > 50, "{across} drags left their first arc");
}

/// The explorer keeps a contour for dragging only where a kept step beat
/// the parallel sweep in the measurements the limit is fitted to
/// (colin27_ch2, 2 cores: kept faster at 229k-326k triangles, the sweep at
/// 802k-881k), fewer on more cores (the kept step is partly serial), the
/// cap on one core (no sweep there) and on large volumes.
#[test]
fn a_contour_is_kept_for_dragging_only_where_its_steps_beat_the_sweep() {
    use flexiso::contour::drag::kept_limit;
    let colin = 181 * 217 * 181;
    let cap = 1_000_000;
    let two = kept_limit(colin, 2, cap);
    assert!((326_000..802_000).contains(&two), "{two}");
    assert!(kept_limit(colin, 16, cap) < two / 4);
    assert_eq!(kept_limit(colin, 1, cap), cap);
    assert_eq!(kept_limit(8 * colin, 2, cap), cap);
    assert!(kept_limit(colin / 8, 2, cap) <= two / 8 + 1);
}
