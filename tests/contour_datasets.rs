//! Contours of real scans from the shared data folder (skipped when it is
//! absent, unless FLEXISO_REQUIRE_DATA=1): at several isovalues, every
//! contour is a connected, manifold, consistently oriented mesh whose Euler
//! characteristic the tree predicts, the same as following each seed
//! gives, and together they are the plain marching-tetrahedra isosurface.

mod common;

use flexiso::contour::oracle::{all_contours_by_following, marching_tetrahedra};
use flexiso::contour::{MeshTopology, all_contours};
use flexiso::field::Isovalue;
use flexiso::field::io::{ReadOptions, read_volume};
use flexiso::measure::betti::ContourTopology;
use flexiso::progress::Progress;
use flexiso::tree::ContourTree;

fn check_dataset(name: &str, isovalues: &[f64]) {
    let Some(path) = common::dataset(name) else {
        return;
    };
    let field = read_volume(&path, &ReadOptions::default())
        .expect("readable")
        .field;
    let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
    let betti = ContourTopology::new(&tree, &field);
    for &h in isovalues {
        let iso = Isovalue::new(h);
        let contours = all_contours(&tree, &field, iso);
        // The parallel sweep names every contour as following its seed does.
        let followed = all_contours_by_following(&tree, &field, iso);
        assert_eq!(contours.len(), followed.len(), "{name} h = {h}: contours");
        for (c, f) in contours.iter().zip(&followed) {
            assert_eq!((c.arc, c.touches_boundary), (f.arc, f.touches_boundary));
            assert_eq!(c.num_triangles(), f.num_triangles(), "{name} h = {h}");
            assert_eq!(c.positions.len(), f.positions.len(), "{name} h = {h}");
        }
        let mut triangles = 0;
        let mut area = 0.0;
        for c in &contours {
            let t = MeshTopology::of(&c.positions, &c.indices);
            let at = format!("{name} h = {h}, arc {:?}", c.arc);
            assert!(c.num_triangles() > 0, "{at}: empty");
            assert_eq!(t.components, 1, "{at}: connected");
            assert_eq!(
                t.non_manifold_edges + t.non_manifold_vertices,
                0,
                "{at}: manifold"
            );
            assert_eq!(t.misoriented_edges, 0, "{at}: oriented");
            assert_eq!(
                t.is_closed(),
                !c.touches_boundary,
                "{at}: closed iff inside"
            );
            let predicted = betti.at(c.arc, &field, iso);
            assert_eq!(t.euler, predicted.euler, "{at}: χ");
            assert_eq!(t.is_closed(), predicted.closed(), "{at}: closedness");
            triangles += c.num_triangles();
            area += t.area;
        }
        let whole = marching_tetrahedra(&field, iso);
        let w = MeshTopology::of(&whole.positions, &whole.indices);
        assert_eq!(
            triangles,
            whole.num_triangles(),
            "{name} h = {h}: triangles"
        );
        assert!(
            (area - w.area).abs() <= 1e-6 * (1.0 + w.area),
            "{name} h = {h}: area"
        );
        assert_eq!(contours.len(), w.components, "{name} h = {h}: components");
    }
}

#[test]
fn nucleon_contours_match_marching_tetrahedra_and_betti() {
    check_dataset("nucleon.nrrd", &[20.0, 60.5, 128.0, 200.0]);
}

#[test]
fn fuel_contours_match_marching_tetrahedra_and_betti() {
    check_dataset("fuel.nrrd", &[10.0, 50.0, 99.5]);
}

#[test]
fn neghip_contours_match_marching_tetrahedra_and_betti() {
    check_dataset("neghip.nrrd", &[30.0, 80.0, 150.0]);
}

/// The parallel extraction (through the sweep) against the serial
/// follower on a scan: at each isovalue, every contour of at least
/// `min_triangles` (the largest one always) has the same triangles (as
/// position triples), as many shared vertices, the same boundary flag and
/// topology, and the Euler characteristic the tree predicts.
fn check_parallel_extraction(name: &str, isovalues: &[f64], min_triangles: usize) {
    use flexiso::contour::{ContourFollower, PathSeeds};
    let Some(path) = common::dataset(name) else {
        return;
    };
    let field = read_volume(&path, &ReadOptions::default())
        .expect("readable")
        .field;
    let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
    let betti = ContourTopology::new(&tree, &field);
    let seeds = PathSeeds::new();
    let mut oracle = ContourFollower::new(&field);
    let mut fast = ContourFollower::new(&field).with_serial_limit(0);
    for &h in isovalues {
        let iso = Isovalue::new(h);
        let mut followed: Vec<_> = flexiso::contour::global::spanning_arcs(&tree, &field, iso)
            .into_iter()
            .filter_map(|a| seeds.seed(&tree, &field, a, iso))
            .map(|s| (s, oracle.follow(&s, iso)))
            .collect();
        followed.sort_by_key(|(_, c)| std::cmp::Reverse(c.num_triangles()));
        for (k, (seed, want)) in followed.iter().enumerate() {
            if k > 0 && want.num_triangles() < min_triangles {
                break;
            }
            let at = format!("{name} h = {h}, arc {:?}", seed.arc);
            let got = fast
                .extract(&tree, seed, iso, &|| false)
                .expect("not cancelled");
            assert_eq!(got.positions.len(), want.positions.len(), "{at}: vertices");
            assert_eq!(got.normals.len(), got.positions.len(), "{at}: normals");
            assert_eq!(got.touches_boundary, want.touches_boundary, "{at}");
            assert!(
                got.triangle_soup() == want.triangle_soup(),
                "{at}: the same triangles"
            );
            let (a, b) = (
                MeshTopology::of(&got.positions, &got.indices),
                MeshTopology::of(&want.positions, &want.indices),
            );
            assert_eq!(
                (a.euler, a.components, a.edges),
                (b.euler, b.components, b.edges)
            );
            assert_eq!(a.euler, betti.at(seed.arc, &field, iso).euler, "{at}: χ");
        }
    }
}

#[test]
fn parallel_extraction_matches_following_on_neghip_and_fuel() {
    check_parallel_extraction("neghip.nrrd", &[30.0, 80.0, 150.0], 100);
    check_parallel_extraction("fuel.nrrd", &[10.0, 50.0, 99.5], 100);
}

#[test]
fn parallel_extraction_matches_following_on_the_colin27_head() {
    // 64.5: the head's contour, 5.36 M triangles.
    check_parallel_extraction("colin27_ch2.nrrd", &[64.5], 200_000);
}
