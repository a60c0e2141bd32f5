//! The explorer's 3D view in world coordinates (issue 17, item 1): a
//! volume with an origin and a rotated direction (SimpleITK's oriented
//! neghip, `formats/real-tools/`) is placed by the same map `extract`
//! writes with (`--space world`), so what the view frames and what a
//! click picks are points of the exported meshes, and the voxels SimpleITK
//! lists land where SimpleITK says. Skipped without the data folder; the
//! rendered part also needs an adapter (lavapipe) unless
//! `FLEXISO_REQUIRE_GPU=1`.
#![allow(clippy::unwrap_used)]

use egui_kittest::Harness;
use flexiso::app::FlexisoApp;
use flexiso::app::panels::view3d::triad_names;
use flexiso::contour::{ContourMesh, Frame, Isovalue, all_contours};
use flexiso::field::io::{ReadOptions, read_volume};
use flexiso::field::{ScalarField, Space};
use glam::Vec3;

mod common;

fn oriented() -> Option<ScalarField> {
    let dir = common::dataset("formats/real-tools")?;
    let v = read_volume(
        &dir.join("neghip_oriented_sitk.mha"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert!(
        !v.field.geometry().is_identity(),
        "the file has an origin and a rotated direction"
    );
    Some(v.field)
}

/// Every contour at `h` as `extract --space world` writes it.
fn exported(app: &FlexisoApp, h: f64) -> Vec<ContourMesh> {
    let ds = app.dataset().unwrap();
    let mut meshes = all_contours(&ds.tree, &ds.field, Isovalue::new(h));
    for m in &mut meshes {
        m.to_frame(&ds.field, Frame::World);
    }
    meshes.retain(|m| !m.indices.is_empty());
    meshes
}

fn bounds(meshes: &[ContourMesh]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in meshes.iter().flat_map(|m| &m.positions) {
        lo = lo.min(Vec3::from(*p));
        hi = hi.max(Vec3::from(*p));
    }
    (lo, hi)
}

/// The distance from `p` to the nearest triangle of `meshes`.
fn distance_to(meshes: &[ContourMesh], p: Vec3) -> f32 {
    let mut best = f32::INFINITY;
    for m in meshes {
        let v = |i: u32| Vec3::from(m.positions[i as usize]);
        for t in m.indices.chunks_exact(3) {
            best = best.min(point_triangle(p, v(t[0]), v(t[1]), v(t[2])));
        }
    }
    best
}

/// Distance from `p` to triangle `abc` (Ericson, Real-Time Collision
/// Detection §5.1.5: the closest point by Voronoi regions).
fn point_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return p.distance(a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return p.distance(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return p.distance(a + ab * (d1 / (d1 - d3)));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return p.distance(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return p.distance(a + ac * (d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return p.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denom = 1.0 / (va + vb + vc);
    p.distance(a + ab * (vb * denom) + ac * (vc * denom))
}

#[test]
fn the_view_places_the_grid_where_simpleitk_and_the_exports_do() {
    let Some(field) = oriented() else { return };
    let app = FlexisoApp::new_for_test(field);
    let ds = app.dataset().unwrap();
    let m = app.view3d().placement();
    // The five voxels SimpleITK lists, through the view's placement.
    let dir = common::dataset("formats/real-tools").unwrap();
    let text = std::fs::read_to_string(dir.join("neghip_oriented_points.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let s = ds.field.spacing();
    for (k, v) in json["index_to_physical"].as_object().unwrap() {
        let idx: Vec<f64> = serde_json::from_str(k).unwrap();
        let grid = Vec3::new(
            (idx[0] * s[0]) as f32,
            (idx[1] * s[1]) as f32,
            (idx[2] * s[2]) as f32,
        );
        let lps = Vec3::new(
            v[0].as_f64().unwrap() as f32,
            v[1].as_f64().unwrap() as f32,
            v[2].as_f64().unwrap() as f32,
        );
        let w = m.transform_point3(grid);
        assert!(
            w.distance(lps) < 1e-3,
            "voxel {k}: view {w} != SimpleITK {lps}"
        );
    }
    // Each contour the app holds (grid frame) placed by the view is the
    // exported mesh, vertex for vertex.
    let h = app.global_h();
    let mut grid = all_contours(&ds.tree, &ds.field, Isovalue::new(h));
    grid.retain(|c| !c.indices.is_empty());
    let world = exported(&app, h);
    assert_eq!(grid.len(), world.len());
    assert!(!world.is_empty(), "neghip has contours at h = {h}");
    for (g, w) in grid.iter().zip(&world) {
        for (p, q) in g.positions.iter().zip(&w.positions) {
            let placed = m.transform_point3(Vec3::from(*p));
            assert!(placed.distance(Vec3::from(*q)) < 1e-3, "{placed} != {q:?}");
        }
    }
    // And the grid frame is far from the world here: the test could fail.
    let (glo, _) = bounds(&grid);
    let (wlo, _) = bounds(&world);
    assert!(glo.distance(wlo) > 10.0, "grid {glo} vs world {wlo}");
}

#[test]
fn framing_and_picking_in_the_view_give_the_exported_world_coordinates() {
    let Some(field) = oriented() else { return };
    if common::gpu().is_none() {
        return;
    }
    let mut h = Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .with_pixels_per_point(1.0)
        .wgpu()
        .build_eframe(move |_cc| FlexisoApp::new_for_test(field));
    h.run_steps(3);
    h.state_mut().set_every_component(true);
    h.state_mut().set_show_all(true);
    h.run_steps(2);
    let ctx = h.ctx.clone();
    h.state_mut().wait_for_all_contours(&ctx);
    h.run_steps(3);
    let iso = h.state().global_h();
    let world = exported(h.state(), iso);
    assert_eq!(h.state().all_contours_shown(), world.len());

    // The triad names the file's space: SimpleITK writes LPS.
    let view = h.state().view3d();
    assert_eq!(view.context.space, Space::Lps);
    assert_eq!(triad_names(view.context.space), ["L", "P", "S"]);

    // What the view draws spans the exported meshes' world box.
    let (lo, hi) = view.renderer().unwrap().visible_bounds().unwrap();
    let (elo, ehi) = bounds(&world);
    assert!(
        Vec3::from(lo).distance(elo) < 1e-2 && Vec3::from(hi).distance(ehi) < 1e-2,
        "view box {lo:?}..{hi:?} != exported {elo}..{ehi}"
    );
    // The volume's box is framed in the world: the camera looks at its
    // world centre (origin + rotated half extent).
    let placement = view.placement();
    let centre = placement.transform_point3(Vec3::splat(31.5) * Vec3::new(0.9, 1.1, 1.3));
    assert!(
        view.camera.target.distance(centre) < 1e-2,
        "camera target {} != the volume's world centre {centre}",
        view.camera.target
    );

    // A click on the contour in the middle of the view picks a point on
    // an exported mesh.
    let rect = view.rect.unwrap();
    let camera = view.camera;
    let r = view.renderer().unwrap();
    let mut hits = 0;
    for i in 0..9 {
        let x = rect.width() * (0.3 + 0.05 * i as f32);
        for j in 0..9 {
            let y = rect.height() * (0.3 + 0.05 * j as f32);
            if let Some((_, p)) = r.pick(&camera, rect.width(), rect.height(), x, y) {
                let d = distance_to(&world, Vec3::from(p));
                assert!(
                    d < 1e-2,
                    "picked {p:?} lies {d} from every exported contour"
                );
                hits += 1;
            }
        }
    }
    assert!(hits > 0, "some ray hits a contour");
}

/// `flexiso render --session` places the volume as the window does: a
/// session saved from the window on the oriented volume renders its
/// contour where the saved camera sees the contour's world position, not
/// where its grid-frame position would be.
#[test]
fn render_session_places_the_oriented_volume_as_the_window_does() {
    let Some(dir) = common::dataset("formats/real-tools") else {
        return;
    };
    let Some(field) = oriented() else { return };
    if common::gpu().is_none() {
        return;
    }
    let file = dir.join("neghip_oriented_sitk.mha");
    let mut h = Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .with_pixels_per_point(1.0)
        .wgpu()
        .build_eframe(move |_cc| FlexisoApp::new_for_test(field));
    h.run_steps(2);
    h.state_mut().open(file.to_str().unwrap());
    h.state_mut().wait_for_job();
    h.run_steps(3);
    let arcs = common::harness::arcs_by_length(&h);
    h.state_mut().select_arc(arcs[0], true);
    common::harness::settle(&mut h);
    h.state_mut().selection_mut().contours[0].colour = egui::Color32::from_rgb(255, 0, 0);
    common::harness::settle(&mut h);
    let mesh = h.state().selection().contours[0]
        .mesh
        .clone()
        .expect("a mesh");
    let placement = h.state().view3d().placement();
    let out = tempfile::tempdir().unwrap();
    let path = out.path().join("s.json");
    h.state_mut().save_session(&path).expect("saved");
    let s = flexiso::session::Session::read(&path).unwrap();
    let c = s.camera.expect("the camera saved");
    let (w, ht) = (480u32, 360u32);
    let png = out.path().join("s.png");
    let size = format!("{w}x{ht}");
    let run = common::flexiso(&[
        "render",
        "--session",
        path.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
        "--size",
        &size,
        "--no-legend",
        "--no-labels",
    ]);
    assert!(run.success(), "{}", run.stderr);
    let img = image::open(&png).unwrap().to_rgba8();
    // Kept for a look when the test fails.
    let _ = std::fs::copy(
        &png,
        std::env::temp_dir().join("flexiso-render-session-world.png"),
    );
    // Where the red pixels are.
    let (mut n, mut sx, mut sy) = (0u64, 0f64, 0f64);
    for (x, y, p) in img.enumerate_pixels() {
        if p[0] > 120 && p[1] < 60 && p[2] < 60 {
            n += 1;
            sx += f64::from(x);
            sy += f64::from(y);
        }
    }
    assert!(n > 5, "the contour is in the picture ({n} red pixels)");
    let (cx, cy) = (sx / n as f64, sy / n as f64);
    // Where the saved camera sees the contour's box centre, placed in the
    // world and (for contrast) left in the grid frame.
    let (lo, hi) = bounds(std::slice::from_ref(&*mesh));
    let grid_centre = 0.5 * (lo + hi);
    let mut camera = flexiso::render::Camera {
        target: c.target.into(),
        distance: c.distance,
        yaw: c.yaw,
        pitch: c.pitch,
        fov_y: c.fov_y,
        ..Default::default()
    };
    camera.scene_radius = 100.0;
    let vp = camera.view_proj(w as f32 / ht as f32);
    let to_pixel = |p: Vec3| {
        let q = vp * p.extend(1.0);
        let (x, y) = (q.x / q.w, q.y / q.w);
        (
            f64::from((x + 1.0) * 0.5 * w as f32),
            f64::from((1.0 - y) * 0.5 * ht as f32),
        )
    };
    let world = to_pixel(placement.transform_point3(grid_centre));
    let grid = to_pixel(grid_centre);
    let dist = |a: (f64, f64), b: (f64, f64)| ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt();
    assert!(
        dist(world, grid) > 40.0,
        "the test can fail: world {world:?} and grid {grid:?} project apart"
    );
    assert!(
        dist((cx, cy), world) < 12.0,
        "red pixels centred at ({cx:.0}, {cy:.0}); the world position projects to {world:?}, \
         the grid one to {grid:?}"
    );
}
