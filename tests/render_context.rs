//! Slices, the clipping plane and the cut-away box in the renderer
//! (issue 16), checked by
//! the pixels of headless renders and by picking. On whatever adapter
//! wgpu finds (Mesa's lavapipe without a GPU); without one these tests
//! print a note and pass, unless `FLEXISO_REQUIRE_GPU=1`.

use std::sync::Arc;

use flexiso::render::{
    Camera, ClipPlane, CutBox, HeadlessMesh, HeadlessScene, SliceQuad, ViewPreset, icosphere,
    render_scene_to_image,
};

mod common;

use common::gpu;

fn save(name: &str, img: &image::RgbaImage) {
    if let Ok(dir) = std::env::var("FLEXISO_RENDER_TEST_OUT") {
        let path = std::path::Path::new(&dir).join(name);
        img.save(&path).expect("save test image");
        eprintln!("saved {}", path.display());
    }
}

const RED: [f32; 4] = [0.9, 0.1, 0.1, 1.0];

fn reddish(p: &image::Rgba<u8>) -> bool {
    p[0] > 60 && u16::from(p[1]) * 2 < u16::from(p[0]) && u16::from(p[2]) * 2 < u16::from(p[0])
}

/// A slice quad across z = `z` over `[-2, 2]²`: its left half green, its
/// right half blue.
fn two_tone_slice(z: f32) -> SliceQuad {
    let image = image::RgbaImage::from_fn(64, 64, |x, _| {
        if x < 32 {
            image::Rgba([0, 200, 0, 255])
        } else {
            image::Rgba([0, 0, 220, 255])
        }
    });
    SliceQuad {
        corners: [
            [-2.0, 2.0, z],
            [2.0, 2.0, z],
            [2.0, -2.0, z],
            [-2.0, -2.0, z],
        ],
        image: Arc::new(image),
    }
}

fn camera(preset: ViewPreset) -> Camera {
    let mut c = Camera::default();
    c.fit([-2.0; 3], [2.0; 3]);
    c.set_preset(preset);
    c
}

#[test]
fn a_slice_shows_its_image_in_place_and_hides_what_lies_behind_it() {
    if gpu().is_none() {
        return;
    }
    // A red sphere below the slice at z = 0.5, seen from above.
    let (p, n, i) = icosphere([0.0, 0.0, -0.5], 0.8, 3);
    let sphere = HeadlessMesh {
        positions: &p,
        normals: &n,
        indices: &i,
        colour: RED,
    };
    let (w, h) = (200, 200);
    let scene = HeadlessScene {
        meshes: vec![sphere],
        camera: Some(camera(ViewPreset::Axial)),
        slices: vec![two_tone_slice(0.5)],
        ..Default::default()
    };
    let img = render_scene_to_image(&scene, w, h).expect("render");
    save("slice_over_sphere.png", &img);
    // Axial: +x to the right. The slice's left half is green, its right
    // half blue, as the image holds them.
    let left = img.get_pixel(w / 2 - 20, h / 2).0;
    let right = img.get_pixel(w / 2 + 20, h / 2).0;
    assert!(
        left[1] > 150 && left[0] < 40 && left[2] < 40,
        "left {left:?}"
    );
    assert!(
        right[2] > 150 && right[0] < 40 && right[1] < 40,
        "right {right:?}"
    );
    // The sphere under it is hidden.
    assert_eq!(img.pixels().filter(|p| reddish(p)).count(), 0);

    // The slice below the sphere instead: the sphere shows in front of it.
    let scene = HeadlessScene {
        slices: vec![two_tone_slice(-1.8)],
        ..scene
    };
    let img = render_scene_to_image(&scene, w, h).expect("render");
    save("sphere_over_slice.png", &img);
    assert!(reddish(img.get_pixel(w / 2, h / 2)), "the sphere in front");
    assert!(
        img.get_pixel(w / 2 - 30, h / 2).0[1] > 150,
        "the slice shows beside it"
    );
}

#[test]
fn the_clipping_plane_cuts_away_the_side_it_faces() {
    if gpu().is_none() {
        return;
    }
    let (p, n, i) = icosphere([0.0; 3], 1.5, 4);
    let sphere = HeadlessMesh {
        positions: &p,
        normals: &n,
        indices: &i,
        colour: RED,
    };
    let (w, h) = (240, 200);
    let count_halves = |img: &image::RgbaImage| {
        let mut halves = [0usize; 2];
        for (x, _, px) in img.enumerate_pixels() {
            if reddish(px) {
                halves[usize::from(x >= w / 2)] += 1;
            }
        }
        halves
    };
    // Coronal (from −y): +x to the right.
    let uncut = HeadlessScene {
        meshes: vec![sphere],
        camera: Some(camera(ViewPreset::Coronal)),
        ..Default::default()
    };
    let img = render_scene_to_image(&uncut, w, h).expect("render");
    let [l, r] = count_halves(&img);
    assert!(l > 500 && r > 500, "both halves drawn uncut: {l} {r}");
    assert!((l as f32 / r as f32 - 1.0).abs() < 0.1);

    // Keep x ≤ 0.3: the right half is gone but for the strip 0 < x < 0.3;
    // the left half stays whole.
    let cut = HeadlessScene {
        clip: Some(ClipPlane::axis(0, 0.3, true)),
        ..uncut.clone()
    };
    let img = render_scene_to_image(&cut, w, h).expect("render");
    save("sphere_clipped.png", &img);
    let [cl, cr] = count_halves(&img);
    assert!(
        (cl as f32 / l as f32 - 1.0).abs() < 0.02,
        "left {cl} of {l}"
    );
    assert!(cr > 0 && cr * 3 < r, "right {cr} of {r}");
    // Nothing right of the plane's image (x = 0.3 projects left of
    // 0.3/1.5 of the disc's radius from the centre, plus a margin).
    let centre_x = w as f32 / 2.0;
    let rad = {
        let (mut lo, mut hi) = (w, 0);
        for (x, _, px) in img.enumerate_pixels() {
            if reddish(px) {
                lo = lo.min(x);
                hi = hi.max(x);
            }
        }
        assert!(hi > lo);
        centre_x - lo as f32
    };
    for (x, _, px) in img.enumerate_pixels() {
        if reddish(px) {
            assert!(
                (x as f32 - centre_x) < rad * 0.3 / 1.5 * 1.25 + 2.0,
                "a red pixel at x = {x} beyond the cut"
            );
        }
    }

    // Keeping the other side mirrors it.
    let other = HeadlessScene {
        clip: Some(ClipPlane::axis(0, -0.3, false)),
        ..uncut
    };
    let img = render_scene_to_image(&other, w, h).expect("render");
    let [ol, or] = count_halves(&img);
    assert!(or > ol * 3, "the right half kept: {ol} {or}");
}

/// Two spheres along x, mesh 1 at x = +2 and mesh 2 at x = -2, and a
/// camera on +x, so that mesh 1 is in front.
fn two_spheres_seen_from_plus_x(g: &flexiso::render::Gpu) -> (flexiso::render::Renderer, Camera) {
    let mut r = g.renderer();
    for (id, x) in [(1u64, 2.0), (2u64, -2.0)] {
        let (p, n, i) = icosphere([x, 0.0, 0.0], 0.8, 3);
        r.set_mesh(&g.device, &g.queue, id, &p, &n, &i)
            .expect("mesh");
    }
    let mut c = Camera::default();
    c.fit([-3.0; 3], [3.0; 3]);
    c.set_preset(ViewPreset::PlusX);
    (r, c)
}

#[test]
fn picking_skips_what_the_clip_cuts_away_and_what_lies_behind_a_slice() {
    let Some(g) = gpu() else { return };
    let (mut r, c) = two_spheres_seen_from_plus_x(&g);
    let (w, h) = (200.0, 200.0);
    let pick = |r: &flexiso::render::Renderer| r.pick(&c, w, h, w / 2.0, h / 2.0).map(|x| x.0);
    assert_eq!(pick(&r), Some(1u64.into()), "the near sphere");
    // Cut away x > 0: the far sphere is picked through the cut.
    r.set_clip(Some(ClipPlane::axis(0, 0.0, true)));
    assert_eq!(pick(&r), Some(2u64.into()), "through the cut");
    let hit = r.pick(&c, w, h, w / 2.0, h / 2.0).expect("a hit").1;
    assert!(hit[0] < -1.0, "on the far sphere: {hit:?}");
    // Keep only x > 0: the near sphere again; from the other side, none
    // that is kept lies behind the eye's cut side.
    r.set_clip(Some(ClipPlane::axis(0, 0.0, false)));
    assert_eq!(pick(&r), Some(1u64.into()));
    // Hidden meshes are not picked.
    r.set_clip(Some(ClipPlane::axis(0, 0.0, true)));
    r.set_style(2u64, RED, false, false);
    assert_eq!(pick(&r), None, "the far one hidden, the near one cut");
    r.set_clip(None);
    r.set_style(2u64, RED, true, false);
    // A slice between the eye and the spheres stops the ray.
    r.set_slice(
        0,
        Some(SliceQuad {
            corners: [
                [2.9, -3.0, 3.0],
                [2.9, 3.0, 3.0],
                [2.9, 3.0, -3.0],
                [2.9, -3.0, -3.0],
            ],
            image: Arc::new(image::RgbaImage::new(4, 4)),
        }),
    );
    assert_eq!(pick(&r), None, "behind a slice");
    // Between the spheres: the near one only.
    r.set_slice(
        0,
        Some(SliceQuad {
            corners: [
                [0.0, -3.0, 3.0],
                [0.0, 3.0, 3.0],
                [0.0, 3.0, -3.0],
                [0.0, -3.0, -3.0],
            ],
            image: Arc::new(image::RgbaImage::new(4, 4)),
        }),
    );
    assert_eq!(pick(&r), Some(1u64.into()));
    r.set_style(1u64, RED, false, false);
    assert_eq!(pick(&r), None, "the far one is behind the slice");
}

const BLUE: [f32; 4] = [0.1, 0.2, 0.9, 1.0];

fn bluish(p: &image::Rgba<u8>) -> bool {
    p[2] > 60 && u16::from(p[0]) * 2 < u16::from(p[2]) && u16::from(p[1]) * 3 < u16::from(p[2]) * 2
}

#[test]
fn the_cut_away_box_opens_a_corner_onto_what_lies_inside() {
    if gpu().is_none() {
        return;
    }
    // A blue ball inside a red one: from outside only the red shows.
    let (po, no, io) = icosphere([0.0; 3], 1.5, 4);
    let (pi, ni, ii) = icosphere([0.0; 3], 0.8, 4);
    let outer = HeadlessMesh {
        positions: &po,
        normals: &no,
        indices: &io,
        colour: RED,
    };
    let inner = HeadlessMesh {
        positions: &pi,
        normals: &ni,
        indices: &ii,
        colour: BLUE,
    };
    let (w, h) = (240, 240);
    // Coronal (from −y): +x to the right, +z up.
    let whole = HeadlessScene {
        meshes: vec![outer, inner],
        camera: Some(camera(ViewPreset::Coronal)),
        ..Default::default()
    };
    let img = render_scene_to_image(&whole, w, h).expect("render");
    assert_eq!(
        img.pixels().filter(|p| bluish(p)).count(),
        0,
        "the inner ball hidden"
    );
    let red = img.pixels().filter(|p| reddish(p)).count();
    assert!(red > 5000, "{red} red pixels");

    // Cut away the octant x > 0, y < 0 (towards the eye), z > 0: the
    // inner ball shows in the picture's upper right quarter, only there.
    let cut = HeadlessScene {
        cut_box: Some(CutBox {
            lo: [0.0, -2.0, 0.0],
            hi: [2.0, 0.0, 2.0],
        }),
        ..whole.clone()
    };
    let img = render_scene_to_image(&cut, w, h).expect("render");
    save("cut_away_box.png", &img);
    let (cx, cy) = (w / 2, h / 2);
    let mut quarters = [0usize; 4];
    for (x, y, p) in img.enumerate_pixels() {
        if !bluish(p) {
            continue;
        }
        // A margin of a few pixels around the quarters' borders.
        let (dx, dy) = (x as i64 - cx as i64, y as i64 - cy as i64);
        if dx.abs() < 4 || dy.abs() < 4 {
            continue;
        }
        quarters[usize::from(dx > 0) + 2 * usize::from(dy > 0)] += 1;
    }
    // Index 1: right, above the centre (dy < 0).
    assert!(
        quarters[1] > 150,
        "the inner ball through the cut: {quarters:?}"
    );
    assert_eq!(
        quarters[0] + quarters[2] + quarters[3],
        0,
        "hidden elsewhere: {quarters:?}"
    );
    // The red ball still fills the other three quarters.
    let red_cut = img.pixels().filter(|p| reddish(p)).count();
    assert!(red_cut * 4 > red * 2, "{red_cut} of {red} red pixels stay");
}

#[test]
fn picking_skips_what_the_cut_away_box_cuts_away() {
    let Some(g) = gpu() else { return };
    let (mut r, c) = two_spheres_seen_from_plus_x(&g);
    let (w, h) = (200.0, 200.0);
    let pick = |r: &flexiso::render::Renderer| r.pick(&c, w, h, w / 2.0, h / 2.0);
    assert_eq!(pick(&r).map(|x| x.0), Some(1u64.into()), "the near sphere");
    // The near sphere inside the box: the far one is picked through it.
    r.set_cut_box(Some(CutBox {
        lo: [1.0, -1.0, -1.0],
        hi: [3.0, 1.0, 1.0],
    }));
    let (id, hit) = pick(&r).expect("a hit");
    assert_eq!(Some(id), Some(2u64.into()), "through the box");
    assert!(hit[0] < -1.0, "on the far sphere: {hit:?}");
    // Only the near sphere's front cap cut away: its inside, behind the
    // cap, is hit (it is drawn there).
    r.set_cut_box(Some(CutBox {
        lo: [2.3, -1.0, -1.0],
        hi: [3.0, 1.0, 1.0],
    }));
    let (id, hit) = pick(&r).expect("a hit");
    assert_eq!(Some(id), Some(1u64.into()), "the near sphere's far side");
    assert!(hit[0] < 2.0, "behind the cap: {hit:?}");
    // A box off the ray changes nothing.
    r.set_cut_box(Some(CutBox {
        lo: [1.0, 2.0, 2.0],
        hi: [3.0, 3.0, 3.0],
    }));
    assert_eq!(pick(&r).map(|x| x.0), Some(1u64.into()));
    r.set_cut_box(None);
    assert_eq!(pick(&r).map(|x| x.0), Some(1u64.into()));
}
