//! Headless rendering and picking on whatever adapter wgpu finds (Mesa's
//! llvmpipe on machines without a GPU). Without an adapter these tests print
//! a note and pass, unless `FLEXISO_REQUIRE_GPU=1`, where they fail.

use flexiso::render::geometry::{self, Corners};
use flexiso::render::{
    Camera, DEFAULT_BACKGROUND, HeadlessMesh, PreparedMesh, Renderer, icosphere, render_to_image,
};
use glam::Vec3;

mod common;

use common::gpu;

/// Whether the `FLEXISO_RENDER_TEST_OUT` folder is set; then the images
/// are saved there for a person to look at.
fn save(name: &str, img: &image::RgbaImage) {
    if let Ok(dir) = std::env::var("FLEXISO_RENDER_TEST_OUT") {
        let path = std::path::Path::new(&dir).join(name);
        img.save(&path).expect("save test image");
        eprintln!("saved {}", path.display());
    }
}

fn background() -> [u8; 4] {
    DEFAULT_BACKGROUND.map(|c| (c * 255.0).round() as u8)
}

fn is_background(p: &image::Rgba<u8>) -> bool {
    p.0.iter()
        .zip(background())
        .all(|(a, b)| (i32::from(*a) - i32::from(b)).abs() <= 1)
}

/// The radius in pixels of a sphere of radius `r` at distance `d` from the
/// eye, seen on a viewport `h` pixels high.
fn projected_radius(camera: &Camera, r: f32, d: f32, h: u32) -> f32 {
    let half = (r / d).asin().tan();
    half / (0.5 * camera.fov_y).tan() * 0.5 * h as f32
}

#[test]
fn sphere_covers_its_disc_lit_from_the_viewer() {
    // render_to_image opens its own GPU; this only checks there is one.
    if gpu().is_none() {
        return;
    }
    let (p, n, i) = icosphere([0.0; 3], 1.0, 4);
    let red = [0.9, 0.15, 0.1, 1.0];
    let mut camera = Camera::default();
    camera.fit([-1.5; 3], [1.5; 3]);
    let (w, h) = (240, 180);
    let img = render_to_image(
        &[HeadlessMesh {
            positions: &p,
            normals: &n,
            indices: &i,
            colour: red,
        }],
        None,
        Some(&camera),
        w,
        h,
    )
    .expect("render");
    save("sphere.png", &img);
    assert_eq!(img.dimensions(), (w, h));

    // Coverage: the lit disc has the area the projection predicts (±8%;
    // the icosphere is slightly inside the true sphere).
    let covered = img.pixels().filter(|p| !is_background(p)).count() as f32;
    let rad = projected_radius(&camera, 1.0, camera.distance, h);
    let expected = std::f32::consts::PI * rad * rad;
    assert!(
        (covered / expected - 1.0).abs() < 0.08,
        "covered {covered} pixels, expected about {expected}"
    );

    // Colour at the centre: red, bright (headlight faces it).
    let c = img.get_pixel(w / 2, h / 2).0;
    // (The specular spot of the headlight whitens it a little.)
    assert!(
        c[0] > 200 && c[0] > c[1] + 80 && c[0] > c[2] + 80,
        "centre {c:?}"
    );
    // Near the rim the headlight grazes: darker than the centre.
    let rim = img.get_pixel(w / 2 + (0.93 * rad) as u32, h / 2).0;
    assert!(
        rim[0] < c[0] - 40 && !is_background(img.get_pixel(w / 2 + (0.93 * rad) as u32, h / 2)),
        "rim {rim:?} centre {c:?}"
    );
    // Corners: background.
    for (x, y) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
        assert!(is_background(img.get_pixel(x, y)), "corner {x},{y}");
    }
}

/// Two spheres on the view axis, the near one small: the near one is in
/// front at the centre whichever order they were added in, and picking the
/// centre returns it, with a point on its near surface.
#[test]
fn nearer_mesh_wins_in_image_and_pick() {
    let Some(gpu) = gpu() else { return };
    let mut camera = Camera::default();
    camera.fit([-2.0; 3], [2.0; 3]);
    let towards_eye = (camera.eye() - camera.target).normalize();
    let near_centre = camera.target + 1.5 * towards_eye;
    let (fp, fnn, fi) = icosphere(camera.target.to_array(), 1.0, 3);
    let (np, nn, ni) = icosphere(near_centre.to_array(), 0.4, 3);
    let (w, h) = (200, 200);
    for order in [[1u64, 2], [2, 1]] {
        let mut r = gpu.renderer();
        for id in order {
            let (p, n, i) = if id == 1 {
                (&fp, &fnn, &fi)
            } else {
                (&np, &nn, &ni)
            };
            r.set_mesh(&gpu.device, &gpu.queue, id, p, n, i)
                .expect("mesh");
        }
        assert!(r.set_style(1, [0.9, 0.1, 0.1, 1.0], true, false));
        assert!(r.set_style(2, [0.1, 0.8, 0.1, 1.0], true, false));
        r.render(&gpu.device, &gpu.queue, &camera, w, h);
        let img = r.read_image(&gpu.device, &gpu.queue).expect("read");
        save(&format!("two_spheres_{}.png", order[0]), &img);
        let c = img.get_pixel(w / 2, h / 2).0;
        assert!(
            c[1] > 150 && c[1] > c[0] + 60 && c[1] > c[2] + 60,
            "centre should be the near green sphere: {c:?}"
        );
        // Off the small sphere but on the big one: red.
        let off = img.get_pixel(w / 2, h / 2 + 20).0;
        assert!(off[0] > 100 && off[1] < 80, "red sphere around it: {off:?}");

        let (id, pos) = r
            .pick(&camera, w as f32, h as f32, w as f32 / 2.0, h as f32 / 2.0)
            .expect("pick at the centre");
        assert_eq!(id, 2);
        let expected = near_centre + 0.4 * towards_eye;
        assert!(
            (Vec3::from(pos) - expected).length() < 0.02,
            "{pos:?} vs {expected}"
        );
        assert_eq!(r.pick(&camera, w as f32, h as f32, 1.0, 1.0), None);
        // Hidden meshes are not picked: the far sphere shows through.
        r.set_style(2, [0.1, 0.8, 0.1, 1.0], false, false);
        let (id, _) = r
            .pick(&camera, w as f32, h as f32, w as f32 / 2.0, h as f32 / 2.0)
            .expect("pick the far sphere");
        assert_eq!(id, 1);
    }
}

/// A transparent sphere in front of an opaque one blends with it; the box
/// lines are drawn; the highlighted style changes the rim; a resize makes a
/// new target.
#[test]
fn transparency_bounds_highlight_and_resize() {
    let Some(gpu) = gpu() else { return };
    let mut camera = Camera::default();
    camera.fit([-2.0; 3], [2.0; 3]);
    let towards_eye = (camera.eye() - camera.target).normalize();
    let (fp, fnn, fi) = icosphere(camera.target.to_array(), 0.8, 3);
    let (np, nn, ni) = icosphere((camera.target + 1.2 * towards_eye).to_array(), 0.6, 3);
    let mut r = gpu.renderer();
    r.set_mesh(&gpu.device, &gpu.queue, 10, &fp, &fnn, &fi)
        .expect("far");
    r.set_mesh(&gpu.device, &gpu.queue, 20, &np, &nn, &ni)
        .expect("near");
    r.set_style(10, [0.9, 0.1, 0.1, 1.0], true, false);
    r.set_style(20, [0.1, 0.2, 0.95, 0.5], true, false);
    r.set_bounds([-2.0; 3], [2.0; 3]);
    let (w, h) = (200, 160);
    r.render(&gpu.device, &gpu.queue, &camera, w, h);
    assert!(r.is_current(&camera, w, h));
    let g0 = r.target_generation();
    let img = r.read_image(&gpu.device, &gpu.queue).expect("read");
    save("transparent.png", &img);
    let c = img.get_pixel(w / 2, h / 2).0;
    assert!(
        c[0] > 60 && c[2] > 60,
        "red behind half-transparent blue: {c:?}"
    );
    // The box: some non-background pixels far from the spheres.
    let lines = img
        .enumerate_pixels()
        .filter(|(x, y, p)| {
            let (dx, dy) = (*x as f32 - w as f32 / 2.0, *y as f32 - h as f32 / 2.0);
            dx.hypot(dy) > 60.0 && !is_background(p)
        })
        .count();
    assert!(lines > 50, "bounding box lines: {lines} pixels");

    // Highlight: rim pixels change.
    r.set_style(10, [0.9, 0.1, 0.1, 1.0], true, true);
    assert!(
        !r.is_current(&camera, w, h),
        "a style change needs a render"
    );
    r.render(&gpu.device, &gpu.queue, &camera, w, h);
    let hi = r.read_image(&gpu.device, &gpu.queue).expect("read");
    save("highlight.png", &hi);
    assert_eq!(r.target_generation(), g0, "same size: same target");
    let changed = img
        .pixels()
        .zip(hi.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 200, "highlight changed {changed} pixels");

    assert!(!r.is_current(&camera, 120, 90), "a resize needs a render");
    r.render(&gpu.device, &gpu.queue, &camera, 120, 90);
    assert_ne!(r.target_generation(), g0);
    assert_eq!(r.target_size(), Some((120, 90)));
    let small = r.read_image(&gpu.device, &gpu.queue).expect("read");
    assert_eq!(small.dimensions(), (120, 90));
}

#[test]
fn malformed_meshes_are_refused_and_empty_ones_draw_nothing() {
    let Some(gpu) = gpu() else { return };
    let mut r: Renderer = gpu.renderer();
    let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let n = [[0.0, 0.0, 1.0]; 3];
    assert!(
        r.set_mesh(&gpu.device, &gpu.queue, 1, &p, &n, &[0, 1, 3])
            .is_err()
    );
    assert!(
        r.set_mesh(&gpu.device, &gpu.queue, 1, &p, &n, &[0, 1])
            .is_err()
    );
    assert!(
        r.set_mesh(&gpu.device, &gpu.queue, 1, &p, &n[..2], &[0, 1, 2])
            .is_err()
    );
    assert!(!r.has_mesh(1));
    // Missing normals are computed.
    r.set_mesh(&gpu.device, &gpu.queue, 1, &p, &[], &[0, 1, 2])
        .expect("no normals");
    r.set_mesh(&gpu.device, &gpu.queue, 2, &[], &[], &[])
        .expect("empty");
    assert_eq!(r.mesh_ids(), vec![1, 2]);
    let camera = Camera::default();
    r.render(&gpu.device, &gpu.queue, &camera, 64, 64);
    assert!(r.remove_mesh(2));
    assert!(!r.set_style(2, [1.0; 4], true, false));
}

/// A torus around the z axis: `(positions, normals, indices)`, outward
/// normals, counter-clockwise outward winding.
fn torus(
    centre: Vec3,
    major: f32,
    minor: f32,
    n: u32,
    m: u32,
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let (mut p, mut nn, mut idx) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let u = i as f32 / n as f32 * std::f32::consts::TAU;
        for j in 0..m {
            let v = j as f32 / m as f32 * std::f32::consts::TAU;
            let normal = Vec3::new(u.cos() * v.cos(), u.sin() * v.cos(), v.sin());
            let ring = Vec3::new(u.cos(), u.sin(), 0.0) * major;
            p.push((centre + ring + minor * normal).to_array());
            nn.push(normal.to_array());
            let (i1, j1) = ((i + 1) % n, (j + 1) % m);
            let (a, b, c, d) = (i * m + j, i1 * m + j, i1 * m + j1, i * m + j1);
            idx.extend([a, b, c, a, c, d]);
        }
    }
    (p, nn, idx)
}

/// A scene with self-occlusion (a torus), nesting (a transparent shell
/// around a core) and the volume box: checks depth where the torus hides
/// its own far side, and saves the picture for a person to look at.
#[test]
fn torus_hides_its_far_side_and_shell_shows_its_core() {
    let Some(gpu) = gpu() else { return };
    let (tp, tn, ti) = torus(Vec3::new(0.3, 0.3, 0.3), 0.2, 0.07, 64, 24);
    let (cp, cn, ci) = icosphere([0.72, 0.7, 0.65], 0.06, 3);
    let (sp, sn, si) = icosphere([0.72, 0.7, 0.65], 0.16, 4);
    let mut r = gpu.renderer();
    r.set_mesh(&gpu.device, &gpu.queue, 1, &tp, &tn, &ti)
        .expect("torus");
    r.set_mesh(&gpu.device, &gpu.queue, 2, &cp, &cn, &ci)
        .expect("core");
    r.set_mesh(&gpu.device, &gpu.queue, 3, &sp, &sn, &si)
        .expect("shell");
    r.set_style(1, [0.89, 0.45, 0.20, 1.0], true, false);
    r.set_style(2, [0.85, 0.2, 0.3, 1.0], true, false);
    r.set_style(3, [0.3, 0.6, 0.85, 0.35], true, false);
    r.set_bounds([0.0; 3], [1.0; 3]);
    let mut camera = Camera::default();
    camera.fit([0.0; 3], [1.0; 3]);
    let (w, h) = (480, 360);
    r.render(&gpu.device, &gpu.queue, &camera, w, h);
    let img = r.read_image(&gpu.device, &gpu.queue).expect("read");
    save("scene.png", &img);

    let vp = Renderer::view_proj(&camera, w as f32, h as f32);
    let to_px = |p: Vec3| {
        let q = vp.project_point3(p);
        (
            ((q.x + 1.0) * 0.5 * w as f32) as u32,
            ((1.0 - q.y) * 0.5 * h as f32) as u32,
        )
    };
    // The core shows through the shell: reddish at its centre.
    let (x, y) = to_px(Vec3::new(0.72, 0.7, 0.65));
    let c = img.get_pixel(x, y).0;
    assert!(c[0] > c[2], "core through the shell: {c:?}");
    // Picking at the core's pixel hits the shell first (it is drawn and
    // pickable though transparent).
    let (id, _) = r
        .pick(&camera, w as f32, h as f32, x as f32 + 0.5, y as f32 + 0.5)
        .expect("pick");
    assert_eq!(id, 3);
    // The torus hole is background (or box lines), its ring is orange, and
    // the pick on the ring's near side lands on the near side.
    let eye = camera.eye();
    let ring_near = Vec3::new(0.3, 0.1, 0.3 + 0.07);
    let (x, y) = to_px(ring_near);
    let o = img.get_pixel(x, y).0;
    assert!(o[0] > o[2] + 60, "torus ring: {o:?}");
    let (id, pos) = r
        .pick(&camera, w as f32, h as f32, x as f32 + 0.5, y as f32 + 0.5)
        .expect("pick torus");
    assert_eq!(id, 1);
    assert!((Vec3::from(pos) - eye).length() <= (ring_near - eye).length() + 0.05);
}

/// A mesh bigger than the per-call budget goes to the GPU over several
/// calls: meanwhile the old geometry is drawn (and picked), then the new
/// one, pixel for pixel as if uploaded at once.
#[test]
fn budgeted_upload_swaps_in_the_complete_mesh() {
    let Some(gpu) = gpu() else { return };
    let (small_p, small_n, small_i) = icosphere([0.25, 0.5, 0.5], 0.1, 1);
    let (big_p, big_n, big_i) = icosphere([0.7, 0.5, 0.5], 0.2, 5);
    let mut camera = Camera::default();
    camera.fit([0.0; 3], [1.0; 3]);
    let (w, h) = (160, 120);

    let mut direct = gpu.renderer();
    direct
        .set_mesh(&gpu.device, &gpu.queue, 1, &big_p, &big_n, &big_i)
        .expect("big sphere");
    direct.render(&gpu.device, &gpu.queue, &camera, w, h);
    let expected = direct.read_image(&gpu.device, &gpu.queue).expect("read");

    let mut r = gpu.renderer();
    r.set_mesh(&gpu.device, &gpu.queue, 1, &small_p, &small_n, &small_i)
        .expect("small sphere");
    let big = flexiso::render::PreparedMesh::new(&big_p, &big_n, &big_i).expect("valid");
    let bytes = big.gpu_bytes();
    r.set_prepared_mesh(&gpu.device, 1, std::sync::Arc::new(big))
        .expect("queued");
    let budget = 10_000;
    let mut calls = 0;
    while r.upload_pending(&gpu.device, &gpu.queue, budget) {
        calls += 1;
        // Not yet swapped: the small sphere is still what is drawn.
        let hit = r.pick(&camera, w as f32, h as f32, 0.0, 0.0);
        assert!(hit.is_none());
        let bounds = r.visible_bounds().expect("the old mesh");
        assert!(bounds.1[0] < 0.4, "still the small sphere: {bounds:?}");
        assert!(calls < 10_000, "the upload never finishes");
    }
    assert!(!r.has_pending_uploads());
    assert_eq!(calls as u64, bytes.div_ceil(budget) - 1, "{bytes} bytes");
    let bounds = r.visible_bounds().expect("the new mesh");
    assert!(bounds.1[0] > 0.85, "now the big sphere: {bounds:?}");
    r.render(&gpu.device, &gpu.queue, &camera, w, h);
    let img = r.read_image(&gpu.device, &gpu.queue).expect("read");
    assert!(
        img.as_raw() == expected.as_raw(),
        "same picture as uploaded at once"
    );
}

// The compact vertex format: 12 bytes per vertex, 16-bit positions in the
// mesh's box, octahedral normals; 16-bit index runs where corners allow.

#[test]
fn compact_vertices_round_trip_within_the_quantisation_error() {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let n = 5000;
    let positions: Vec<[f32; 3]> = (0..n)
        .map(|_| [180.0 * rnd() + 3.0, 217.0 * rnd() - 40.0, 0.5 * rnd()])
        .collect();
    let mut normals: Vec<[f32; 3]> = (0..n)
        .map(|_| [2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0])
        .collect();
    // The octahedron's folds and corners.
    normals[..8].copy_from_slice(&[
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
        [1.0, -1.0, -1.0],
        [-1e-9, 1e-9, -1.0],
    ]);
    let indices: Vec<u32> = (0..n as u32 - 2).flat_map(|i| [i, i + 1, i + 2]).collect();
    let m = flexiso::render::PreparedMesh::new(&positions, &normals, &indices).expect("valid");
    assert_eq!(
        m.gpu_bytes(),
        12 * n as u64 + m.corners().bytes().len() as u64
    );
    let (lo, hi) = m.bounds().expect("a box");
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let err = (hi - lo) / 65535.0 * 0.5 + (hi.abs().max(lo.abs())) * 1e-6;
    for i in 0..n {
        let (p, nr) = m.vertex(i);
        let d = (Vec3::from(p) - Vec3::from(positions[i])).abs();
        assert!(
            d.cmple(err).all(),
            "vertex {i}: {p:?} vs {:?}",
            positions[i]
        );
        let want = Vec3::from(normals[i]).as_dvec3().normalize();
        let got = Vec3::from(nr).as_dvec3();
        assert!((got.length() - 1.0).abs() < 1e-5);
        // 16-bit octahedral: well under 0.01°.
        let angle = got.cross(want).length().atan2(got.dot(want));
        assert!(
            angle < 0.01f64.to_radians(),
            "normal {i}: {}°",
            angle.to_degrees()
        );
    }
    assert_eq!(
        geometry::decode_normal(geometry::encode_normal([0.0; 3])),
        [0.0, 0.0, 1.0]
    );
    assert_eq!(
        geometry::decode_normal(geometry::encode_normal([f32::NAN; 3])),
        [0.0, 0.0, 1.0]
    );
}

#[test]
fn a_flat_mesh_quantises_its_flat_axis_to_its_plane() {
    let p = [[0.0, 0.0, 7.5], [1.0, 0.0, 7.5], [0.0, 2.0, 7.5]];
    let m = flexiso::render::PreparedMesh::new(&p, &[], &[0, 1, 2]).expect("valid");
    for (i, want) in p.iter().enumerate() {
        assert_eq!(m.vertex(i).0, *want);
    }
}

/// A `n × n` height field in row order: triangles row by row, so runs of
/// rows stay within 65,536 vertices of their first.
fn terrain(n: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
    let positions = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32 / n as f32, (i / n) as f32 / n as f32);
            [x, y, 0.1 * (6.0 * x).sin() * (5.0 * y).cos()]
        })
        .collect();
    let mut indices = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let v = x + n * y;
            indices.extend([v, v + 1, v + n + 1, v, v + n + 1, v + n]);
        }
    }
    (positions, indices)
}

#[test]
fn nearby_corners_travel_as_16_bit_runs_and_scattered_ones_as_32_bit() {
    let (p, i) = terrain(400);
    let m = PreparedMesh::new(&p, &[], &i).expect("valid");
    let Corners::Short { runs, .. } = m.corners() else {
        panic!("row-ordered triangles fit 16-bit runs");
    };
    assert!(runs.len() > 2, "160,000 vertices need several runs");
    for r in runs {
        let span = i[r.start as usize..r.end as usize].iter();
        assert!(
            span.clone()
                .all(|&v| v >= r.base && v - r.base <= u16::MAX as u32)
        );
    }
    assert_eq!(m.corners().to_absolute(), i, "every corner as it was");
    assert_eq!(m.gpu_bytes(), 12 * p.len() as u64 + 2 * i.len() as u64);
    // Corners scattered over the whole mesh: 32-bit.
    let n = p.len() as u32;
    let scattered: Vec<u32> = i
        .iter()
        .map(|&v| v.wrapping_mul(2_654_435_761) % n)
        .collect();
    let m = PreparedMesh::new(&p, &[], &scattered).expect("valid");
    assert!(matches!(m.corners(), Corners::Long(_)));
    assert_eq!(m.corners().to_absolute(), scattered);
    // An odd number of 16-bit corners is padded to whole 4-byte words.
    let m = PreparedMesh::new(&p[..3], &[], &[0, 1, 2]).expect("valid");
    assert_eq!(m.corners().bytes().len(), 8);
    assert_eq!(m.corners().len(), 3);
}

/// A mesh prepared in the arrays of another (a drag step reusing the
/// GPU form of the mesh two steps before) is the same as one prepared in
/// fresh arrays, whatever the other was: 16- or 32-bit, larger or smaller.
#[test]
fn a_mesh_prepared_in_recycled_arrays_is_the_same() {
    let (p, i) = terrain(400);
    let n = p.len() as u32;
    let scattered: Vec<u32> = i
        .iter()
        .map(|&v| v.wrapping_mul(2_654_435_761) % n)
        .collect();
    let (sp, si) = terrain(60);
    let (bp, bn, bi) = icosphere([0.5; 3], 0.3, 5);
    type Mesh<'a> = (&'a [[f32; 3]], &'a [[f32; 3]], &'a [u32]);
    let meshes: [Mesh; 5] = [
        (&p, &[], &i),
        (&p, &[], &scattered),
        (&sp, &[], &si),
        (&bp, &bn, &bi),
        (&p[..3], &[], &[0, 1, 2]),
    ];
    for (a, &(ap, an, ai)) in meshes.iter().enumerate() {
        for (b, &(bp, bn, bi)) in meshes.iter().enumerate() {
            let spare = PreparedMesh::new(bp, bn, bi).expect("valid");
            let reused = PreparedMesh::new_reusing(ap, an, ai, spare).expect("valid");
            let fresh = PreparedMesh::new(ap, an, ai).expect("valid");
            assert!(
                reused == fresh,
                "mesh {a} prepared in the arrays of mesh {b}"
            );
        }
    }
}

/// A mesh drawn in 16-bit runs (one draw each, from its base vertex) is
/// the same picture as the same mesh drawn with 32-bit indices.
#[test]
fn index_runs_draw_the_same_picture_as_32_bit_indices() {
    let Some(gpu) = gpu() else { return };
    let (p, i) = terrain(400);
    // Reversed vertex numbering within each triangle's reach stays in
    // runs; a permutation that scatters them forces 32-bit indices.
    let n = p.len() as u32;
    // A bijection: the multiplier is prime to n = 2^8 5^4.
    let perm = |v: u32| (u64::from(v) * 2_654_435_761 % u64::from(n)) as u32;
    let mut q = vec![[0f32; 3]; p.len()];
    for (v, x) in p.iter().enumerate() {
        q[perm(v as u32) as usize] = *x;
    }
    let j: Vec<u32> = i.iter().map(|&v| perm(v)).collect();
    let mut camera = Camera::default();
    camera.fit([0.0, 0.0, -0.1], [1.0, 1.0, 0.1]);
    let picture = |p: &[[f32; 3]], i: &[u32], short: bool| {
        let m = PreparedMesh::new(p, &[], i).expect("valid");
        assert_eq!(matches!(m.corners(), Corners::Short { .. }), short);
        let mut r = gpu.renderer();
        r.set_prepared_mesh(&gpu.device, 1, std::sync::Arc::new(m))
            .expect("queued");
        r.upload_pending(&gpu.device, &gpu.queue, u64::MAX);
        r.render(&gpu.device, &gpu.queue, &camera, 200, 150);
        r.read_image(&gpu.device, &gpu.queue).expect("read")
    };
    let a = picture(&p, &i, true);
    let b = picture(&q, &j, false);
    save("terrain.png", &a);
    let drawn = a.pixels().filter(|x| !is_background(x)).count();
    assert!(drawn > 3000, "{drawn} pixels drawn");
    assert!(a.as_raw() == b.as_raw(), "the same picture");
}

/// A drag replaces one large mesh again and again, each over several
/// frames: the buffers of the mesh drawn before are reused for the next,
/// and the picture is the same as an upload at once.
#[test]
fn repeated_budgeted_uploads_reuse_buffers_and_draw_the_last_mesh() {
    let Some(gpu) = gpu() else { return };
    let (a_p, a_n, a_i) = icosphere([0.4, 0.5, 0.5], 0.3, 5);
    let (b_p, b_n, b_i) = icosphere([0.6, 0.5, 0.5], 0.25, 5);
    let mut camera = Camera::default();
    camera.fit([0.0; 3], [1.0; 3]);
    let mut direct = gpu.renderer();
    direct
        .set_mesh(&gpu.device, &gpu.queue, 1, &a_p, &a_n, &a_i)
        .expect("a");
    direct.render(&gpu.device, &gpu.queue, &camera, 160, 120);
    let expected = direct.read_image(&gpu.device, &gpu.queue).expect("read");
    let mut r = gpu.renderer();
    for (p, n, i) in [(&a_p, &a_n, &a_i), (&b_p, &b_n, &b_i), (&a_p, &a_n, &a_i)] {
        let m = PreparedMesh::new(p, n, i).expect("valid");
        r.set_prepared_mesh(&gpu.device, 1, std::sync::Arc::new(m))
            .expect("queued");
        let mut calls = 0;
        while r.upload_pending(&gpu.device, &gpu.queue, 100_000) {
            calls += 1;
        }
        assert!(calls > 1, "over several calls");
    }
    r.render(&gpu.device, &gpu.queue, &camera, 160, 120);
    let img = r.read_image(&gpu.device, &gpu.queue).expect("read");
    assert!(img.as_raw() == expected.as_raw(), "the last mesh, whole");
}
