//! Context in the explorer (issue 16), driven headless with egui_kittest:
//! view presets from the View menu, slices with each contour's
//! cross-section, picking that ignores hidden and clipped contours, and
//! slices, clip and view switches kept in sessions. The 3D parts need an
//! adapter (Mesa's lavapipe without a GPU) and are skipped without one
//! unless `FLEXISO_REQUIRE_GPU=1`.

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use flexiso::app::FlexisoApp;
use flexiso::field::{ScalarField, Values};
use flexiso::session::Session;

mod common;

use common::harness::{click, settle, synthetic_explorer};

/// Two separate bumps on a 32³ grid, centred at x = 9 and x = 23 (y = z
/// = 16): seen from +x, the second hides the first.
fn two_bumps() -> ScalarField {
    let n = 32;
    let mut values = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let bump = |cx: f32| {
                    let d2 = (x as f32 - cx).powi(2)
                        + (y as f32 - 16.0).powi(2)
                        + (z as f32 - 16.0).powi(2);
                    (-d2 / 18.0).exp()
                };
                values.push(bump(9.0).max(bump(23.0)));
            }
        }
    }
    ScalarField::new([n, n, n], Values::F32(values)).expect("a valid field")
}

fn explorer(gpu: bool) -> Harness<'static, FlexisoApp> {
    let field = two_bumps();
    let builder = Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .with_pixels_per_point(1.0);
    let builder = if gpu { builder.wgpu() } else { builder };
    let mut h = builder.build_eframe(move |_cc| FlexisoApp::new_for_test(field));
    h.run_steps(3);
    assert!(h.state().dataset().is_some());
    h
}

/// "All contours at h" on at h = 0.5 (one sphere per bump), seen from +x.
fn both_spheres_from_plus_x(h: &mut Harness<'_, FlexisoApp>) {
    h.state_mut().set_show_all(true);
    h.run_steps(2);
    let ctx = h.ctx.clone();
    h.state_mut().wait_for_all_contours(&ctx);
    h.run_steps(2);
    assert_eq!(h.state().all_contours_shown(), 2, "one contour per bump");
    h.state_mut()
        .set_view_preset(flexiso::render::ViewPreset::PlusX);
    h.run_steps(2);
}

/// The x of the centre of the only selected contour's mesh.
fn selected_x(h: &Harness<'_, FlexisoApp>) -> f32 {
    let sel = &h.state().selection().contours;
    assert_eq!(sel.len(), 1, "one contour selected");
    let m = sel[0].mesh.as_ref().expect("extracted");
    m.positions.iter().map(|p| p[0]).sum::<f32>() / m.positions.len() as f32
}

fn view_centre(h: &Harness<'_, FlexisoApp>) -> egui::Pos2 {
    h.state()
        .view3d()
        .rect
        .expect("the view was drawn")
        .center()
}

#[test]
fn the_view_menu_presets_look_along_the_axes() {
    let mut h = explorer(false);
    for (label, pitch_deg) in [
        ("Axial (along z)", 89.0f32),
        ("From −z", -89.0),
        ("From +x", 0.0),
    ] {
        h.get_by_label("View").click();
        h.run_steps(2);
        h.get_by_label(label).click();
        h.run_steps(2);
        let c = h.state().view3d().camera;
        assert!(
            (c.pitch.to_degrees() - pitch_deg).abs() < 0.5,
            "{label}: pitch {}",
            c.pitch.to_degrees()
        );
    }
    let c = h.state().view3d().camera;
    assert!(c.yaw.abs() < 1e-4, "from +x: yaw {}", c.yaw);
}

#[test]
fn picking_ignores_hidden_contours_and_their_copies_at_h() {
    let Some(_) = common::gpu() else { return };
    let mut h = explorer(true);
    both_spheres_from_plus_x(&mut h);
    let centre = view_centre(&h);
    click(&mut h, centre);
    assert!(selected_x(&h) > 16.0, "the near bump is picked first");
    // Hidden, it and its faded copy at h let the click through.
    h.state_mut().selection_mut().contours[0].visible = false;
    settle(&mut h);
    click(&mut h, centre);
    assert!(
        selected_x(&h) < 16.0,
        "the far bump is picked through the hidden one"
    );
}

#[test]
fn picking_goes_through_what_the_clipping_plane_cuts_away() {
    let Some(_) = common::gpu() else { return };
    let mut h = explorer(true);
    both_spheres_from_plus_x(&mut h);
    // Cut away x > 16 (the near bump).
    let clip = &mut h.state_mut().slices_mut().clip;
    clip.on = true;
    clip.axis = 0;
    clip.at = 0.5;
    clip.keep_below = true;
    h.run_steps(2);
    let centre = view_centre(&h);
    click(&mut h, centre);
    assert!(selected_x(&h) < 16.0, "the far bump, through the cut");
}

#[test]
fn picking_goes_through_what_the_cut_away_box_cuts_away() {
    let Some(_) = common::gpu() else { return };
    let mut h = explorer(true);
    both_spheres_from_plus_x(&mut h);
    // Cut away the box x > 16 (the near bump), every y and z.
    let cut = &mut h.state_mut().slices_mut().cut_box;
    cut.on = true;
    cut.lo = [0.5, 0.0, 0.0];
    cut.hi = [1.0, 1.0, 1.0];
    h.run_steps(2);
    assert!(
        h.state()
            .view3d()
            .renderer()
            .expect("a renderer")
            .cut_box()
            .is_some(),
        "the 3D view cuts"
    );
    let centre = view_centre(&h);
    click(&mut h, centre);
    assert!(selected_x(&h) < 16.0, "the far bump, through the box");
}

#[test]
fn a_slice_shows_each_contours_cross_section_in_its_colour() {
    let gpu = common::gpu().is_some();
    let mut h = explorer(gpu);
    both_spheres_from_plus_x(&mut h);
    let centre = view_centre(&h);
    click(&mut h, centre);
    if !gpu {
        // Without a renderer no click picks: select a bump as the list would.
        let app = h.state();
        let ds = app.dataset().expect("dataset");
        let (field, tree) = (ds.field.clone(), ds.tree.clone());
        let h_mid = app.global_h();
        let arc = tree
            .arcs()
            .iter()
            .enumerate()
            .find(|(_, a)| {
                field.value(tree.node(a.upper).vertex) > h_mid
                    && field.value(tree.node(a.lower).vertex) < h_mid
            })
            .map(|(i, _)| flexiso::tree::ArcId(i as u32))
            .expect("an arc spans h");
        h.state_mut()
            .selection_mut()
            .add(&field, &tree, arc, h_mid, true);
        settle(&mut h);
    }
    let colour = h.state().selection().contours[0].colour;
    h.state_mut().view_options_mut().slices_panel = true;
    let s = &mut h.state_mut().slices_mut().slices;
    s.on = [false, false, true];
    s.index[2] = 16;
    settle(&mut h);
    let img = h.state().slices().image(2).expect("the z slice is shown");
    let coloured = img
        .pixels()
        .filter(|p| p.0[..3] == [colour.r(), colour.g(), colour.b()])
        .count();
    assert!(
        coloured > 50,
        "the contour's cross-section: {coloured} pixels"
    );
    // Grey elsewhere.
    let grey = img
        .pixels()
        .filter(|p| p.0[0] == p.0[1] && p.0[1] == p.0[2])
        .count();
    assert!(grey > coloured, "mostly grey values");
    // Hidden, its cross-section goes.
    h.state_mut().selection_mut().contours[0].visible = false;
    settle(&mut h);
    let img = h.state().slices().image(2).expect("still shown");
    assert!(
        !img.pixels()
            .any(|p| p.0[..3] == [colour.r(), colour.g(), colour.b()])
    );
    if gpu {
        let r = h.state().view3d().renderer().expect("a renderer");
        assert!(r.slice(2).is_some(), "the 3D view holds the slice");
        assert!(r.slice(0).is_none());
    }
}

#[test]
fn slices_clip_and_view_switches_are_saved_in_the_session() {
    let mut h = explorer(false);
    {
        let app = h.state_mut();
        let p = app.slices_mut();
        p.slices.on = [true, false, true];
        p.slices.index = [5, 9, 20];
        p.clip.on = true;
        p.clip.axis = 2;
        p.clip.at = 0.25;
        p.clip.keep_below = false;
        p.cut_box.on = true;
        p.cut_box.lo = [0.0, 0.25, 0.5];
        p.cut_box.hi = [0.5, 1.0, 1.0];
        app.view_options_mut().labels = true;
    }
    h.run_steps(2);
    let dir = tempfile::tempdir().expect("a temp dir");
    let path = dir.path().join("s.json");
    h.state_mut().save_session(&path).expect("saved");
    let s = Session::read(&path).expect("a session");
    let slices = s.slices.expect("slices saved").as_array();
    assert_eq!(slices, [Some(5), None, Some(20)]);
    let clip = s.clip.clone().expect("clip saved");
    assert_eq!(
        (clip.axis.as_str(), clip.at, clip.keep.as_str()),
        ("z", 0.25, "above")
    );
    assert!(s.view.expect("view saved").labels);
    let cut = s.cut_box.expect("cut-away box saved");
    assert_eq!((cut.min, cut.max), ([0.0, 0.25, 0.5], [0.5, 1.0, 1.0]));

    // Applied to a fresh explorer on the same volume, they come back.
    let mut g = explorer(false);
    {
        let app = g.state_mut();
        let p = app.slices_mut();
        p.slices.on = [false; 3];
    }
    g.run_steps(1);
    g.state_mut().apply_session_for_test(&s);
    g.run_steps(2);
    let p = g.state().slices();
    assert_eq!(p.slices.on, [true, false, true]);
    assert_eq!((p.slices.index[0], p.slices.index[2]), (5, 20));
    assert!(p.clip.on && p.clip.axis == 2 && !p.clip.keep_below);
    assert!(p.cut_box.on);
    assert_eq!((p.cut_box.lo, p.cut_box.hi), (cut.min, cut.max));
    // In world coordinates: the 32³ grid's box is [0, 31]³.
    let b = p.cut_box().expect("on");
    assert_eq!((b.lo, b.hi), ([0.0, 7.75, 15.5], [15.5, 31.0, 31.0]));
    assert!(g.state().view_options().labels);
    // A session without one: no box.
    let plain = Session {
        cut_box: None,
        ..s.clone()
    };
    g.state_mut().apply_session_for_test(&plain);
    assert!(!g.state().slices().cut_box.on);
}

#[test]
fn render_session_draws_the_legend_the_slices_and_the_clip() {
    if common::gpu().is_none() {
        return;
    }
    let mut h = synthetic_explorer();
    let arcs = common::harness::arcs_by_length(&h);
    h.state_mut().select_arc(arcs[0], true);
    h.state_mut().select_arc(arcs[1], false);
    settle(&mut h);
    {
        let sel = h.state_mut().selection_mut();
        sel.contours[0].colour = egui::Color32::from_rgb(255, 0, 0);
        sel.contours[0].name = "brain".into();
        sel.contours[1].colour = egui::Color32::from_rgb(0, 255, 0);
        sel.contours[1].name = "eyes".into();
    }
    settle(&mut h);
    let dir = tempfile::tempdir().expect("a temp dir");
    let path = dir.path().join("s.json");
    h.state_mut().save_session(&path).expect("saved");
    let render = |extra: &[&str], png: &std::path::Path| {
        let mut args = vec![
            "render",
            "--session",
            path.to_str().expect("utf-8"),
            "--out",
            png.to_str().expect("utf-8"),
            "--size",
            "480x360",
        ];
        args.extend_from_slice(extra);
        let out = common::flexiso(&args);
        assert!(out.success(), "{}", out.stderr);
        image::open(png).expect("png").to_rgba8()
    };
    // The legend: a swatch of each colour in the top-left corner.
    let with = render(&[], &dir.path().join("with.png"));
    let without = render(&["--no-legend"], &dir.path().join("without.png"));
    let corner = |img: &image::RgbaImage, rgb: [u8; 3]| {
        let mut n = 0;
        for y in 0..80 {
            for x in 0..160 {
                if img.get_pixel(x, y).0[..3] == rgb {
                    n += 1;
                }
            }
        }
        n
    };
    for rgb in [[255, 0, 0], [0, 255, 0]] {
        assert!(corner(&with, rgb) >= 25, "a swatch of {rgb:?}");
        assert_eq!(
            corner(&without, rgb),
            0,
            "no swatch of {rgb:?} without the legend"
        );
    }
    let light = |img: &image::RgbaImage| {
        let mut n = 0;
        for y in 0..80 {
            for x in 0..160 {
                let p = img.get_pixel(x, y).0;
                if p[0] > 180 && p[1] > 180 && p[2] > 180 {
                    n += 1;
                }
            }
        }
        n
    };
    assert!(light(&with) > light(&without) + 20, "the names' text");

    // Labels on in the session: each contour's name beside it, the dot,
    // leader and border in its colour, the name in white.
    let mut s = Session::read(&path).expect("a session");
    s.view = Some(flexiso::session::SessionView {
        labels: true,
        legend: false,
        ..Default::default()
    });
    s.write(&path).expect("written");
    let labelled = render(&[], &dir.path().join("labelled.png"));
    let unlabelled = render(&["--no-labels"], &dir.path().join("unlabelled.png"));
    let exact =
        |img: &image::RgbaImage, rgb: [u8; 3]| img.pixels().filter(|p| p.0[..3] == rgb).count();
    for rgb in [[255, 0, 0], [0, 255, 0]] {
        assert!(
            exact(&labelled, rgb) >= exact(&unlabelled, rgb) + 20,
            "a label in {rgb:?}: {} pixels, {} without labels",
            exact(&labelled, rgb),
            exact(&unlabelled, rgb)
        );
    }
    let white = |img: &image::RgbaImage| {
        img.pixels()
            .filter(|p| p.0[..3].iter().all(|&c| c > 200))
            .count()
    };
    assert!(
        white(&labelled) >= white(&unlabelled) + 20,
        "the names' text"
    );

    // A slice across z, the contours clipped away: grey values fill the
    // picture where the contours were.
    // Through the middle of the red contour.
    let z = {
        let m = h.state().selection().contours[0]
            .mesh
            .clone()
            .expect("extracted");
        let (lo, hi) = m
            .positions
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), p| {
                (lo.min(p[2]), hi.max(p[2]))
            });
        (0.5 * (lo + hi)).round() as usize
    };
    let mut s = Session::read(&path).expect("a session");
    s.slices = Some(flexiso::session::SessionSlices::from_array([
        None,
        None,
        Some(z),
    ]));
    s.clip = Some(flexiso::session::SessionClip {
        axis: "z".into(),
        at: 0.0,
        keep: "below".into(),
    });
    s.camera = None;
    s.write(&path).expect("written");
    let sliced = render(&["--no-legend"], &dir.path().join("sliced.png"));
    let greys = |img: &image::RgbaImage| {
        img.pixels()
            .filter(|p| p.0[0] == p.0[1] && p.0[1] == p.0[2] && p.0[0] > 40)
            .count()
    };
    let (sliced_greys, unsliced_greys) = (greys(&sliced), greys(&without));
    assert!(
        sliced_greys > unsliced_greys + 1000,
        "the slice's grey values: {sliced_greys} pixels, {unsliced_greys} without it"
    );
    let contour = sliced
        .pixels()
        .filter(|p| p.0[0] > 100 && p.0[1] < 60 && p.0[2] < 60)
        .count();
    assert!(contour > 0, "the red contour's cross-section on the slice");
}

#[test]
fn a_png_export_carries_the_contours_names_when_labels_are_on() {
    if common::gpu().is_none() {
        return;
    }
    let mut h = explorer(true);
    let arcs = common::harness::arcs_by_length(&h);
    h.state_mut().select_arc(arcs[0], true);
    settle(&mut h);
    {
        let sel = h.state_mut().selection_mut();
        sel.contours[0].colour = egui::Color32::from_rgb(255, 0, 0);
        sel.contours[0].name = "brain".into();
    }
    h.state_mut().view_options_mut().legend = false;
    settle(&mut h);
    let dir = tempfile::tempdir().expect("a temp dir");
    let mut shot = |labels: bool, name: &str| {
        h.state_mut().view_options_mut().labels = labels;
        settle(&mut h);
        let png = dir.path().join(name);
        h.state_mut().request_screenshot(png.clone());
        h.run_steps(2);
        h.state_mut().wait_for_exports();
        assert_eq!(h.state().error(), None);
        image::open(&png).expect("written").to_rgba8()
    };
    let with = shot(true, "labels.png");
    let without = shot(false, "plain.png");
    let exact =
        |img: &image::RgbaImage, rgb: [u8; 3]| img.pixels().filter(|p| p.0[..3] == rgb).count();
    assert!(
        exact(&with, [255, 0, 0]) >= exact(&without, [255, 0, 0]) + 20,
        "the label's dot and border: {} red pixels, {} without",
        exact(&with, [255, 0, 0]),
        exact(&without, [255, 0, 0])
    );
    let white = |img: &image::RgbaImage| {
        img.pixels()
            .filter(|p| p.0[..3].iter().all(|&c| c > 200))
            .count()
    };
    assert!(white(&with) >= white(&without) + 20, "the name's text");
}
