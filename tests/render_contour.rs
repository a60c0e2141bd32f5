//! Real contours through the renderer: the contour of the synthetic scene's
//! highest blob (a near-sphere of known centre and radius) and the whole
//! isosurface, rendered headless and picked. Needs an adapter: skipped
//! without one unless `FLEXISO_REQUIRE_GPU=1`.

use flexiso::contour::{self, ContourFollower, ContourMesh};
use flexiso::field::synthetic::Synthetic;
use flexiso::field::{Isovalue, ScalarField, Values};
use flexiso::progress::Progress;
use flexiso::render::geometry::Corners;
use flexiso::render::{Camera, DEFAULT_BACKGROUND, Known, PreparedMesh, Renderer};
use flexiso::tree::{ArcId, ContourTree};
use glam::Vec3;

mod common;

use common::gpu;

fn save(name: &str, img: &image::RgbaImage) {
    if let Ok(dir) = std::env::var("FLEXISO_RENDER_TEST_OUT") {
        img.save(std::path::Path::new(&dir).join(name))
            .expect("save test image");
    }
}

fn is_background(p: &image::Rgba<u8>) -> bool {
    let bg = DEFAULT_BACKGROUND.map(|c| (c * 255.0).round() as i32);
    p.0.iter()
        .zip(bg)
        .all(|(a, b)| (i32::from(*a) - b).abs() <= 1)
}

const N: usize = 48;
/// The highest blob of the synthetic scene (unit-cube centre, radius,
/// height 1.0): see `field::synthetic`.
const BLOB_CENTRE: [f32; 3] = [0.22, 0.25, 0.25];
const BLOB_RADIUS: f32 = 0.09;

/// The contour of the global maximum's arc at `h = 0.6` is a near-sphere
/// around the blob with radius `r √ln(1/0.6)`; rendered it covers that disc
/// in its colour, and picking its centre returns its id and a point on it.
#[test]
fn blob_contour_renders_as_its_sphere_and_is_picked() {
    let Some(gpu) = gpu() else { return };
    let field = Synthetic::cube(N).generate();
    let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("tree");
    // The blob's maximum: the highest vertex within two cells of its
    // centre (the scene's global maximum is on the torus).
    let scale = (N - 1) as f32;
    let centre = Vec3::from(BLOB_CENTRE) * scale;
    let top = (0..field.len() as u32)
        .filter(|&v| {
            let [x, y, z] = field.coords(v);
            (Vec3::new(x as f32, y as f32, z as f32) - centre).length() < 2.0
        })
        .max_by(|&a, &b| field.value(a).total_cmp(&field.value(b)))
        .expect("vertices");
    let arc = (0..tree.arcs().len() as u32)
        .map(ArcId)
        .find(|&a| tree.node(tree.arc(a).upper).vertex == top)
        .expect("the maximum's arc");
    let iso = Isovalue::new(0.6);
    let seed = contour::path_seed(&tree, &field, arc, iso).expect("seed");
    let mesh = ContourFollower::new(&field).follow(&seed, iso);
    assert!(
        mesh.num_triangles() > 100,
        "{} triangles",
        mesh.num_triangles()
    );

    let radius = BLOB_RADIUS * (1.0f32 / 0.6).ln().sqrt() * scale;

    let mut r: Renderer = gpu.renderer();
    let id = u64::from(arc.0);
    r.set_mesh(
        &gpu.device,
        &gpu.queue,
        id,
        &mesh.positions,
        &mesh.normals,
        &mesh.indices,
    )
    .expect("mesh");
    r.set_style(id, [0.89, 0.45, 0.2, 1.0], true, false);
    r.set_bounds([0.0; 3], [scale; 3]);
    let mut camera = Camera::default();
    let (lo, hi) = r.visible_bounds().expect("bounds");
    camera.fit(lo, hi);
    let (w, h) = (256, 192);
    r.render(&gpu.device, &gpu.queue, &camera, w, h);
    let img = r.read_image(&gpu.device, &gpu.queue).expect("read");
    save("blob_contour.png", &img);

    // The disc: the contour's projected radius, from where the camera is.
    let d = (camera.eye() - centre).length();
    let rad_px = (radius / d).asin().tan() / (0.5 * camera.fov_y).tan() * 0.5 * h as f32;
    let covered = img
        .pixels()
        .filter(|p| {
            let c = p.0;
            // Orange surface pixels (box lines are grey).
            !is_background(p) && c[0] > c[2] + 40
        })
        .count() as f32;
    let expected = std::f32::consts::PI * rad_px * rad_px;
    assert!(
        (covered / expected - 1.0).abs() < 0.2,
        "covered {covered}, expected about {expected}"
    );
    let c = img.get_pixel(w / 2, h / 2).0;
    assert!(c[0] > 180 && c[0] > c[2] + 80, "centre {c:?}");

    let (picked, pos) = r
        .pick(&camera, w as f32, h as f32, w as f32 / 2.0, h as f32 / 2.0)
        .expect("pick");
    assert_eq!(picked, id);
    let dist = (Vec3::from(pos) - centre).length();
    assert!(
        (dist - radius).abs() < 0.15 * radius,
        "picked {pos:?} at {dist} from the centre, radius {radius}"
    );
    assert_eq!(r.pick(&camera, w as f32, h as f32, 2.0, 2.0), None);
}

/// Every contour at one isovalue, each its own mesh: all drawn, each
/// pickable at its own projected centre.
#[test]
fn all_contours_render_and_each_is_pickable() {
    let Some(gpu) = gpu() else { return };
    let field = Synthetic::cube(N).generate();
    let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("tree");
    let meshes = contour::all_contours(&tree, &field, Isovalue::new(0.45));
    let meshes: Vec<_> = meshes
        .into_iter()
        .filter(|m| m.num_triangles() > 0)
        .collect();
    assert!(meshes.len() >= 3, "{} contours", meshes.len());
    let mut r = gpu.renderer();
    let palette = [
        [0.89, 0.45, 0.20, 1.0],
        [0.30, 0.60, 0.85, 1.0],
        [0.45, 0.75, 0.35, 1.0],
        [0.85, 0.35, 0.55, 1.0],
    ];
    for (k, m) in meshes.iter().enumerate() {
        let id = u64::from(m.arc.0);
        r.set_mesh(
            &gpu.device,
            &gpu.queue,
            id,
            &m.positions,
            &m.normals,
            &m.indices,
        )
        .expect("mesh");
        r.set_style(id, palette[k % palette.len()], true, false);
    }
    let scale = (N - 1) as f32;
    r.set_bounds([0.0; 3], [scale; 3]);
    let mut camera = Camera::default();
    camera.fit([0.0; 3], [scale; 3]);
    let (w, h) = (480, 360);
    r.render(&gpu.device, &gpu.queue, &camera, w, h);
    let img = r.read_image(&gpu.device, &gpu.queue).expect("read");
    save("all_contours.png", &img);
    let covered = img.pixels().filter(|p| !is_background(p)).count();
    assert!(covered > (w * h) as usize / 50, "{covered} pixels drawn");
    // Some contour is hit at its own centre's pixel, unless another one
    // is in front; at least half of them must be picked there.
    let vp = Renderer::view_proj(&camera, w as f32, h as f32);
    let mut hits = 0;
    for m in &meshes {
        let c = m
            .positions
            .iter()
            .fold(Vec3::ZERO, |a, p| a + Vec3::from(*p))
            / m.positions.len() as f32;
        // Aim at a vertex near the centroid's screen position.
        let nearest = m
            .positions
            .iter()
            .map(|p| Vec3::from(*p))
            .min_by(|a, b| a.distance(c).total_cmp(&b.distance(c)))
            .expect("vertices");
        let q = vp.project_point3(nearest);
        let (x, y) = ((q.x + 1.0) * 0.5 * w as f32, (1.0 - q.y) * 0.5 * h as f32);
        if r.pick(&camera, w as f32, h as f32, x, y)
            .map(|(id, _)| id.0)
            == Some(u64::from(m.arc.0))
        {
            hits += 1;
        }
    }
    assert!(
        hits * 2 >= meshes.len(),
        "{hits} of {} picked",
        meshes.len()
    );
}

/// Every spanning arc's contour at `iso`, extracted by the sweep.
fn swept_contours(field: &ScalarField, iso: f64) -> Vec<ContourMesh> {
    let (tree, _) = ContourTree::from_field(field, &Progress::new()).expect("tree");
    let iso = Isovalue::new(iso);
    let mut sweep = ContourFollower::new(field).with_serial_limit(0);
    (0..tree.arcs().len() as u32)
        .filter_map(|a| contour::path_seed(&tree, field, ArcId(a), iso))
        .map(|seed| {
            sweep
                .extract(&tree, &seed, iso, &|| false)
                .expect("not cancelled")
        })
        .collect()
}

/// The mesh prepared for the GPU as a maker that knows nothing but the
/// winding (a pass over positions for the box, over the triangles for the
/// runs).
fn prepared_from_scratch(m: &ContourMesh) -> PreparedMesh {
    let known = Known {
        ccw_outward: m.ccw_outward,
        ..Known::default()
    };
    PreparedMesh::new_known(
        &m.positions,
        &m.normals,
        &m.indices,
        known,
        PreparedMesh::default(),
    )
    .expect("a contour is a valid mesh")
}

/// What the sweep knows of a contour (its box, its triangles by cube
/// layer) prepares the same GPU mesh as passes over it: the same
/// quantised vertices in the same box, every corner as it was; the
/// layers' 16-bit runs when a run can hold a layer (a head-sized sphere:
/// several runs), the scan's when not (a plane of 90,000 vertices); bands
/// that lie about their corners are caught as the corners are written.
#[test]
fn what_the_sweep_knows_prepares_the_same_gpu_mesh() {
    let n = 110usize;
    let c = (n - 1) as f64 / 2.0;
    let ball: Vec<f32> = (0..n * n * n)
        .map(|v| {
            let [x, y, z] = [v % n, v / n % n, v / (n * n)].map(|k| k as f64 - c);
            let wobble = (x * 0.3).sin() * (y * 0.2).cos() + (z * 0.25).sin();
            ((x * x + y * y + z * z).sqrt() + wobble) as f32
        })
        .collect();
    let ball = ScalarField::new([n; 3], Values::F32(ball)).expect("valid");
    let (m, k) = (300usize, 4usize);
    let sheet: Vec<f32> = (0..m * m * k)
        .map(|v| {
            let [x, y, z] = [v % m, v / m % m, v / (m * m)].map(|k| k as f64);
            (z + 0.3 * ((x * 0.7).sin() * (y * 1.3).cos())) as f32
        })
        .collect();
    let sheet = ScalarField::new([m, m, k], Values::F32(sheet)).expect("valid");
    let mut cases = vec![
        (swept_contours(&ball, 50.0), true),
        (swept_contours(&sheet, 1.5), false),
        (swept_contours(&Synthetic::cube(N).generate(), 0.45), true),
    ];
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..12 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let d = [
            5 + state % 11,
            5 + (state >> 8) % 11,
            5 + (state >> 16) % 11,
        ]
        .map(|d| d as usize);
        let mut s = state;
        let values: Vec<u8> = (0..d[0] * d[1] * d[2])
            .map(|_| {
                s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                (s >> 61) as u8
            })
            .collect();
        let field = ScalarField::new(d, Values::U8(values)).expect("valid");
        cases.push((swept_contours(&field, 3.5), true));
    }
    let mut several_runs = false;
    for (meshes, banded) in cases {
        assert!(!meshes.is_empty());
        for mesh in &meshes {
            assert!(
                mesh.bounds.is_some() && !mesh.bands.is_empty(),
                "the sweep knows"
            );
            let want = prepared_from_scratch(mesh);
            let (p, nr, i) = (&mesh.positions, &mesh.normals, &mesh.indices);
            let got = PreparedMesh::new_known(p, nr, i, mesh.into(), PreparedMesh::default())
                .expect("valid");
            assert_eq!(got.gpu_vertices(), want.gpu_vertices(), "quantised alike");
            assert_eq!(got.bounds(), want.bounds(), "the same box");
            assert_eq!(got.corners().to_absolute(), mesh.indices, "every corner");
            if let Corners::Short { runs, .. } = got.corners() {
                several_runs |= runs.len() > 1;
                // The runs are the bands', joined: no scan was made.
                let band_start = |r: u32| mesh.bands.iter().any(|b| b.corners.start == r);
                assert!(!banded || runs.iter().all(|r| band_start(r.start)));
            } else if banded {
                panic!("{} triangles in 32-bit corners", mesh.num_triangles());
            }
            // Bands that claim the wrong vertices: the scan's runs.
            let mut lying = mesh.clone();
            for b in &mut lying.bands {
                b.vertices.start += 1;
            }
            let got = PreparedMesh::new_known(p, nr, i, (&lying).into(), PreparedMesh::default())
                .expect("valid");
            assert_eq!(got.corners(), want.corners(), "the scan's runs");
        }
    }
    assert!(several_runs, "a contour in several 16-bit runs");
}
