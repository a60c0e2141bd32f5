//! The explorer driven like a user would, headless (egui_kittest): clicks
//! and drags at screen positions, then checks on the app's state and on
//! what the panels drew. With an adapter (wgpu, e.g. Mesa's lavapipe) the
//! 3D view renders for real; without one these tests still run the UI but
//! skip the renderer checks, unless `FLEXISO_REQUIRE_GPU=1`.

use egui::pos2;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use flexiso::app::FlexisoApp;
use flexiso::app::panels::view3d::SceneKey;
use flexiso::field::synthetic::Synthetic;
use flexiso::simplify::SimplifiedArcId;

mod common;

use common::harness::{click, drag, settle, tallest_arc};

/// The explorer on a small synthetic volume, pipeline already run, in a
/// 1200×800 window; the second value says whether the 3D view renders.
fn explorer() -> (Harness<'static, FlexisoApp>, bool) {
    let field = Synthetic::cube(40).generate();
    let gpu = common::gpu().is_some();
    let builder = Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .with_pixels_per_point(1.0);
    let builder = if gpu { builder.wgpu() } else { builder };
    let mut h = builder.build_eframe(move |_cc| FlexisoApp::new_for_test(field));
    h.run_steps(3);
    assert!(h.state().dataset().is_some(), "the test dataset loaded");
    (h, gpu)
}

#[test]
fn clicking_an_arc_selects_its_contour_and_a_mesh_appears_in_the_scene() {
    let (mut h, gpu) = explorer();
    assert!(h.state().selection().contours.is_empty());
    let (arc, p) = tallest_arc(&h);
    click(&mut h, p);
    let app = h.state();
    let sel = &app.selection().contours;
    assert_eq!(sel.len(), 1, "one contour selected by the click");
    let c = &sel[0];
    assert_eq!(
        app.level().expect("a level").live_arc_of(c.superarc),
        Some(arc),
        "the contour is on the clicked arc"
    );
    let mesh = c.mesh.as_ref().expect("the contour was extracted");
    assert!(mesh.num_triangles() > 0, "the contour has triangles");
    assert_eq!(
        app.tree_panel().drawn.markers.len(),
        1,
        "a marker sits on the arc"
    );
    if gpu {
        assert!(
            app.view3d().mesh_ids().contains(&SceneKey::Contour(c.id)),
            "the 3D view holds the contour's mesh: {:?}",
            app.view3d().mesh_ids()
        );
        assert!(app.view3d().renders > 0, "the 3D view rendered");
    }

    // Edit > Clear contours clears the selection (Escape no longer does:
    // it only closes popups and cancels drags), and the mesh leaves the
    // scene.
    h.get_by_label("Edit").click();
    h.run_steps(2);
    h.get_by_label("Clear contours").click();
    h.run_steps(3);
    assert!(h.state().selection().contours.is_empty());
    if gpu {
        assert!(h.state().view3d().mesh_ids().is_empty());
    }
}

#[test]
fn shift_click_adds_a_second_contour_and_delete_removes_one() {
    let (mut h, _) = explorer();
    let (_, p) = tallest_arc(&h);
    click(&mut h, p);
    // Another arc, far from the first one's midpoint.
    let other = h
        .state()
        .tree_panel()
        .drawn
        .arcs
        .iter()
        .copied()
        .filter(|(_, q)| q.distance(p) > 40.0)
        .max_by(|a, b| a.1.y.total_cmp(&b.1.y))
        .expect("another arc");
    common::harness::shift_click(&mut h, other.1);
    assert_eq!(h.state().selection().contours.len(), 2, "shift-click adds");
    h.key_press(egui::Key::Delete);
    h.run_steps(2);
    assert_eq!(
        h.state().selection().contours.len(),
        1,
        "Delete removes one"
    );
}

#[test]
fn dragging_a_marker_changes_the_contours_isovalue() {
    let (mut h, gpu) = explorer();
    let (arc, p) = tallest_arc(&h);
    click(&mut h, p);
    let (id, h0, v0, marker) = {
        let app = h.state();
        let c = &app.selection().contours[0];
        let (mid, pos) = app.tree_panel().drawn.markers[0];
        assert_eq!(mid, c.id);
        (c.id, c.h, c.version, pos)
    };
    // Up the screen is up in value.
    drag(&mut h, marker, marker - egui::vec2(0.0, 40.0));
    let app = h.state();
    let c = app.selection().get(id).expect("still selected");
    assert!(c.h > h0, "dragging up raised the isovalue: {h0} -> {}", c.h);
    assert!(c.version > v0, "the contour was re-extracted");
    let level = app.level().expect("level");
    let la = level.arc(arc);
    let sim = level.simplification();
    assert!(
        c.h >= sim.node_value(la.lower) && c.h < sim.node_value(la.upper),
        "the contour stays on its arc"
    );
    assert!(c.mesh.as_ref().is_some_and(|m| m.num_triangles() > 0));
    let (_, moved) = app.tree_panel().drawn.markers[0];
    assert!(
        moved.y < marker.y - 5.0,
        "the marker moved up with the drag"
    );
    if gpu {
        assert!(app.view3d().mesh_ids().contains(&SceneKey::Contour(id)));
    }
}

#[test]
fn moving_the_curve_slider_changes_the_number_of_arcs_drawn() {
    let (mut h, _) = explorer();
    let before = h.state().tree_panel().drawn.arcs.len();
    assert_eq!(before, h.state().level().expect("level").num_arcs());
    let rect = h.state().curve_panel().plot_rect.expect("curve drawn");
    let y = rect.center().y;
    // To the right: larger feature size, fewer arcs.
    drag(
        &mut h,
        pos2(rect.left() + 0.2 * rect.width(), y),
        pos2(rect.left() + 0.8 * rect.width(), y),
    );
    let after = h.state().tree_panel().drawn.arcs.len();
    assert!(
        after < before,
        "dragging the level to larger features drew fewer arcs: {before} -> {after}"
    );
    assert_eq!(after, h.state().level().expect("level").num_arcs());
}

/// Clicks the arc-count box, selects its text and types `n` over it.
fn type_arcs(h: &mut Harness<'_, FlexisoApp>, n: usize) {
    h.get_by_label("arcs:").click();
    h.run_steps(1);
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    h.run_steps(1);
    h.get_by_label("arcs:").type_text(&n.to_string());
}

/// The arc-count box applies on Enter, not on each keystroke, and gives
/// exactly the count asked for when the pruning sequence has that level;
/// a count the sequence skips gives the nearest level, and says so.
#[test]
fn the_arc_count_box_applies_on_enter_and_gives_the_exact_count() {
    let (mut h, _) = explorer();
    let sim = std::sync::Arc::clone(h.state().level().expect("level").simplification());
    let counts: Vec<usize> = sim.curve().iter().map(|p| p.arcs).collect();
    let start = h.state().level().expect("level").num_arcs();
    // A two-digit count the sequence has (nearest 25), other than the
    // level shown, whose first digit alone would be another level.
    let asked = counts
        .iter()
        .copied()
        .filter(|&n| (10..100).contains(&n) && n != start && !counts.contains(&(n / 10)))
        .min_by_key(|&n| n.abs_diff(25))
        .expect("a two-digit level");
    type_arcs(&mut h, asked);
    h.run_steps(3);
    assert_eq!(
        h.state().level().expect("level").num_arcs(),
        start,
        "typing without Enter changes nothing"
    );
    h.key_press(egui::Key::Enter);
    h.run_steps(3);
    let level = h.state().level().expect("level");
    assert_eq!(level.num_arcs(), asked, "exactly the count typed");
    assert_eq!(h.state().tree_panel().drawn.arcs.len(), asked);

    // A count no level has (a step with a reduction removes two arcs).
    let gap = (2..counts[0])
        .find(|n| !counts.contains(n))
        .expect("a count the sequence skips");
    type_arcs(&mut h, gap);
    h.key_press(egui::Key::Enter);
    h.run_steps(3);
    let got = h.state().level().expect("level").num_arcs();
    assert_eq!(got.abs_diff(gap), 1, "the nearest level to {gap}: {got}");
    let note = format!("no level has {gap} arcs: nearest {got}");
    assert!(h.query_by_label(&note).is_some(), "the box says so");
}

/// Simplifying never orphans a contour silently: one whose branch is
/// pruned keeps a marker on the live arc that absorbed it, or the contour
/// list says it is hidden by simplification (and no marker is drawn).
#[test]
fn simplifying_keeps_every_selected_contour_marked_or_listed_as_hidden() {
    let (mut h, _) = explorer();
    // Contours on the shortest arcs of a fine level: the first pruned.
    let arcs: Vec<SimplifiedArcId> = {
        let level = h.state().level().expect("level");
        let sim = level.simplification();
        let mut arcs: Vec<SimplifiedArcId> = level.arcs().map(|a| a.id).collect();
        arcs.sort_by(|x, y| {
            let span = |a: SimplifiedArcId| {
                let la = level.arc(a);
                sim.node_value(la.upper) - sim.node_value(la.lower)
            };
            span(*x).total_cmp(&span(*y)).then(x.cmp(y))
        });
        arcs.truncate(8);
        arcs
    };
    for a in arcs {
        h.state_mut().select_arc(a, false);
    }
    settle(&mut h);
    let n = h.state().selection().contours.len();
    assert!(n >= 4, "several contours selected: {n}");
    assert_eq!(h.state().tree_panel().drawn.markers.len(), n);

    h.state_mut().set_level_arcs(3);
    h.run_steps(3);
    let app = h.state();
    let level = app.level().expect("level");
    assert!(level.num_arcs() <= 3);
    let markers = &app.tree_panel().drawn.markers;
    let mut absorbed = 0;
    let mut hidden = 0;
    for c in &app.selection().contours {
        let marked = markers.iter().any(|m| m.0 == c.id);
        match level.absorbing_arc_of(c.superarc) {
            Some(a) => {
                assert!(level.is_live(a));
                assert!(marked, "contour #{} keeps its marker", c.id);
                if level.live_arc_of(c.superarc).is_none() {
                    absorbed += 1;
                }
            }
            None => {
                assert!(!marked, "no marker for hidden contour #{}", c.id);
                hidden += 1;
            }
        }
    }
    assert!(absorbed > 0, "some pruned contours stay attached");
    let listed = h
        .query_all_by_label(flexiso::app::panels::contour_list::HIDDEN)
        .count();
    assert_eq!(listed, hidden, "every hidden contour is listed as such");
}

/// A level far away is reached over several frames, a bounded number of
/// steps each, and ends where it would have in one go.
#[test]
fn a_far_level_is_reached_over_several_frames() {
    let far = |limit: Option<usize>| {
        let (mut h, _) = explorer();
        if let Some(l) = limit {
            h.state_mut().curve_panel_mut().steps_per_frame = l;
        }
        let rect = h.state().curve_panel().plot_rect.expect("curve drawn");
        let (a, b) = (
            pos2(rect.left() + 0.1 * rect.width(), rect.center().y),
            pos2(rect.left() + 0.9 * rect.width(), rect.center().y),
        );
        let step = |h: &Harness<'_, FlexisoApp>| h.state().level().expect("level").step();
        let start = step(&h);
        let mut largest_move = 0;
        let mut frame = |h: &mut Harness<'_, FlexisoApp>| {
            let before = step(h);
            h.run_steps(1);
            largest_move = largest_move.max(step(h).abs_diff(before));
        };
        h.hover_at(a);
        frame(&mut h);
        h.drag_at(a);
        frame(&mut h);
        for i in 1..=10 {
            h.hover_at(a + (b - a) * (i as f32 / 10.0));
            frame(&mut h);
        }
        h.drop_at(b);
        for _ in 0..10_000 {
            let before = step(&h);
            frame(&mut h);
            if step(&h) == before {
                break;
            }
        }
        let level = h.state().level().expect("level");
        (start, largest_move, level.step(), level.num_arcs())
    };
    let (start, _, end, arcs) = far(None);
    let (start1, largest_move, end1, arcs1) = far(Some(1));
    assert_eq!(start, start1);
    assert!(
        end > start + 2,
        "the drag asks for several steps: {start} -> {end}"
    );
    // One step per pass; egui may run a frame in two passes.
    assert!(largest_move <= 2, "{largest_move} steps in one frame");
    assert!(largest_move < end - start, "not reached in one frame");
    assert_eq!((end1, arcs1), (end, arcs), "the same level in the end");
}

#[test]
fn opening_a_bad_file_shows_an_error_and_keeps_the_old_dataset() {
    let (mut h, _) = explorer();
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("broken.nrrd");
    std::fs::write(
        &bad,
        b"NRRD0004\ntype: float\ndimension: 3\nsizes: 10 10\n\n",
    )
    .expect("write");
    let arcs = h.state().level().expect("level").num_arcs();
    h.state_mut().open(&bad.to_string_lossy());
    h.state_mut().wait_for_job();
    h.run_steps(3);
    let app = h.state();
    let err = app.error().expect("an error is shown").to_string();
    assert!(
        err.contains("broken.nrrd"),
        "the message names the file: {err}"
    );
    assert_eq!(app.dataset().expect("dataset kept").name, "test");
    assert_eq!(app.level().expect("level kept").num_arcs(), arcs);
    assert!(
        h.query_by_label_contains("broken.nrrd").is_some(),
        "the message is on screen"
    );
}

#[test]
fn dragging_a_marker_up_through_a_join_splits_the_contour_into_the_arcs_above() {
    let (mut h, _) = explorer();
    // An arc whose upper node is a join at this level, and the arcs above.
    let (arc, ups) = {
        let app = h.state();
        let level = app.level().expect("level");
        let sim = level.simplification();
        let mut found = None;
        for a in level.arcs() {
            let ups: Vec<SimplifiedArcId> = level
                .arcs()
                .filter(|b| b.lower == a.upper)
                .map(|b| b.id)
                .collect();
            if ups.len() >= 2 && sim.node_value(a.upper) > sim.node_value(a.lower) {
                found = Some((a.id, ups));
                break;
            }
        }
        found.expect("the test volume has a join")
    };
    h.state_mut().select_arc(arc, true);
    settle(&mut h);
    let marker = h.state().tree_panel().drawn.markers[0].1;
    // Just above the join: below the middle of every arc above it.
    let target_y = {
        let d = &h.state().tree_panel().drawn;
        ups.iter()
            .map(|u| {
                let i = d.arcs.iter().position(|x| x.0 == *u).expect("drawn");
                d.arcs[i].1.y
            })
            .fold(f32::MIN, f32::max)
    };
    assert!(target_y < marker.y, "the join is above the marker");
    drag(&mut h, marker, pos2(marker.x, target_y));
    let app = h.state();
    let sel = &app.selection().contours;
    assert_eq!(
        sel.len(),
        ups.len(),
        "one contour per arc above the join: {:?}",
        sel.iter().map(|c| (c.superarc, c.h)).collect::<Vec<_>>()
    );
    let mut on: Vec<SimplifiedArcId> = sel
        .iter()
        .map(|c| {
            app.level()
                .expect("a level")
                .live_arc_of(c.superarc)
                .expect("live")
        })
        .collect();
    on.sort();
    let mut want = ups.clone();
    want.sort();
    assert_eq!(on, want, "the contours sit on the arcs above the join");
    let group = sel[0].group;
    assert!(sel.iter().all(|c| c.group == group), "they move together");
    let colours: std::collections::HashSet<egui::Color32> = sel.iter().map(|c| c.colour).collect();
    assert_eq!(
        colours.len(),
        sel.len(),
        "each piece of the split has its own colour"
    );
    let markers = &app.tree_panel().drawn.markers;
    assert_eq!(markers.len(), sel.len(), "each piece has its marker");
    for (i, a) in markers.iter().enumerate() {
        for b in &markers[i + 1..] {
            assert!(
                a.1.distance(b.1) >= 4.0,
                "markers {a:?} and {b:?} are stacked"
            );
        }
    }
    assert!(
        sel.iter()
            .all(|c| c.mesh.as_ref().is_some_and(|m| m.num_triangles() > 0)),
        "each was extracted"
    );

    // Dragging back down below the join merges them into one again.
    let m = h.state().tree_panel().drawn.markers[0].1;
    drag(&mut h, m, marker);
    assert_eq!(h.state().selection().contours.len(), 1, "merged again");
}

#[test]
fn all_contours_at_h_extracts_every_component_in_the_background() {
    let (mut h, gpu) = explorer();
    // The option: every component (the default is one per shown arc).
    h.state_mut().set_every_component(true);
    h.state_mut().set_show_all(true);
    h.run_steps(2);
    let ctx = h.ctx.clone();
    h.state_mut().wait_for_all_contours(&ctx);
    h.run_steps(2);
    let app = h.state();
    let n = app.all_contours_shown();
    let (tree, field) = {
        let ds = app.dataset().expect("dataset");
        (ds.tree.clone(), ds.field.clone())
    };
    let expected = flexiso::contour::all_contours(
        &tree,
        &field,
        flexiso::field::Isovalue::new(app.global_h()),
    )
    .iter()
    .filter(|m| !m.indices.is_empty())
    .count();
    assert!(n > 0, "some contours at the middle value");
    assert_eq!(n, expected);
    if gpu {
        assert_eq!(app.view3d().mesh_ids().len(), n, "all drawn");
    }
}

#[test]
fn exports_write_meshes_the_tree_as_json_and_the_3d_view_as_png() {
    let (mut h, gpu) = explorer();
    let (_, p) = tallest_arc(&h);
    click(&mut h, p);
    let dir = tempfile::tempdir().expect("tempdir");
    for ext in ["ply", "obj", "stl"] {
        let path = dir.path().join(format!("contours.{ext}"));
        let n = h.state().export_contours(&path).expect("export");
        assert_eq!(n, 1);
        assert!(std::fs::metadata(&path).expect("written").len() > 100);
    }
    // As the menu does it: written on another thread, reported after.
    let ply = dir.path().join("background.ply");
    h.state_mut().start_contour_export(ply.clone());
    h.state_mut().wait_for_exports();
    assert_eq!(h.state().error(), None);
    assert!(
        h.state()
            .info()
            .is_some_and(|i| i.starts_with("wrote 1 contour"))
    );
    assert_eq!(
        std::fs::read(&ply).expect("written"),
        std::fs::read(dir.path().join("contours.ply")).expect("written"),
        "the same file as written at once"
    );
    let json_path = dir.path().join("tree.json");
    h.state_mut().start_tree_export(json_path.clone());
    h.state_mut().wait_for_exports();
    assert!(h.state().info().is_some_and(|i| i.starts_with("wrote")));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json_path).expect("read")).expect("parse");
    let shown = h.state().level().expect("level").num_arcs();
    assert_eq!(
        json["simplified"]["arcs"].as_array().map(Vec::len),
        Some(shown),
        "the JSON holds the level shown"
    );
    assert!(json["nodes"].as_array().is_some_and(|n| !n.is_empty()));
    if gpu {
        let png = dir.path().join("view.png");
        // Without the legend, whose swatch has the contour's colour too.
        h.state_mut().view_options_mut().legend = false;
        h.state_mut().request_screenshot(png.clone());
        h.run_steps(2);
        h.state_mut().wait_for_exports();
        assert_eq!(h.state().error(), None);
        let img = image::open(&png).expect("screenshot written").to_rgba8();
        assert!(img.width() > 100 && img.height() > 100);
        // The contour's colour shows somewhere in the view.
        let colour = h.state().selection().contours[0].colour;
        let close = img.pixels().any(|p| {
            (i32::from(p[0]) - i32::from(colour.r())).abs() < 60
                && (i32::from(p[1]) - i32::from(colour.g())).abs() < 60
                && (i32::from(p[2]) - i32::from(colour.b())).abs() < 60
                && p[0] != p[2]
        });
        assert!(close, "the screenshot shows the contour");
    }
    // A failed write is reported; the window goes on.
    h.state_mut()
        .start_tree_export(dir.path().join("no_such_dir").join("tree.json"));
    h.state_mut().wait_for_exports();
    assert!(
        h.state()
            .error()
            .is_some_and(|e| e.contains("cannot write")),
        "{:?}",
        h.state().error()
    );
}

#[test]
fn betti_numbers_arrive_in_the_background_for_the_tooltips() {
    let (mut h, _) = explorer();
    let topo = h.state_mut().wait_for_betti().expect("Betti numbers");
    let app = h.state();
    let ds = app.dataset().expect("dataset");
    // Every superarc has at least one stretch.
    for a in 0..ds.tree.arcs().len() as u32 {
        assert!(!topo.segments(flexiso::tree::ArcId(a)).is_empty());
    }
}

#[test]
fn another_measure_recomputes_the_simplification_and_keeps_the_selection() {
    let (mut h, _) = explorer();
    let (_, p) = tallest_arc(&h);
    click(&mut h, p);
    let before = h.state().dataset().expect("dataset").sim.clone();
    assert_eq!(before.measure(), flexiso::simplify::Measure::Hypervolume);
    h.state_mut()
        .set_measure(flexiso::simplify::Measure::Height);
    assert!(
        h.state().busy(),
        "the simplification runs in the background"
    );
    h.state_mut().wait_for_job();
    h.run_steps(3);
    let app = h.state();
    let ds = app.dataset().expect("dataset");
    assert_eq!(ds.sim.measure(), flexiso::simplify::Measure::Height);
    assert!(!std::sync::Arc::ptr_eq(&ds.sim, &before));
    assert_eq!(app.selection().contours.len(), 1, "the selection stays");
    assert_eq!(
        app.tree_panel().drawn.arcs.len(),
        app.level().expect("level").num_arcs()
    );
}

#[test]
fn the_window_keeps_drawing_while_a_tree_builds_in_the_background() {
    // Large enough that the job (about a second) outlasts any frame of a
    // loaded machine's software renderer (up to 350 ms measured): a 128³
    // field was built in 0.35 s, as long as one slow frame.
    let (mut h, _) = explorer();
    h.state_mut().open("synthetic:192");
    let mut steps: Vec<f64> = Vec::new();
    let started = std::time::Instant::now();
    while h.state().busy() && started.elapsed().as_secs() < 120 {
        let t = std::time::Instant::now();
        h.step();
        steps.push(t.elapsed().as_secs_f64() * 1e3);
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(!h.state().busy(), "the job finished");
    let total = started.elapsed().as_secs_f64() * 1e3;
    steps.sort_by(f64::total_cmp);
    let max = steps.last().copied().unwrap_or(0.0);
    let median = steps.get(steps.len() / 2).copied().unwrap_or(0.0);
    eprintln!(
        "UI frames while building: {} in {total:.0} ms, median {median:.1} ms, max {max:.1} ms",
        steps.len()
    );
    assert!(steps.len() >= 3, "frames kept coming while the job ran");
    // Generous: the machine may be shared; a blocked UI would take the
    // whole build (hundreds of ms) in one frame.
    assert!(max < 0.5 * total.max(200.0), "no frame waited for the job");
    h.run_steps(3);
    let app = h.state();
    assert_eq!(
        app.dataset().expect("new dataset").field.dims(),
        [192, 192, 192]
    );
    assert!(app.selection().contours.is_empty());
}

#[test]
fn a_path_typed_in_the_open_window_loads_in_the_background() {
    let (mut h, _) = explorer();
    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("Open a path…").click();
    h.run_steps(2);
    h.get_by_label("Path:").click();
    h.run_steps(1);
    h.get_by_label("Path:").type_text("synthetic:24");
    h.run_steps(1);
    h.get_by_label("Open path").click();
    h.run_steps(2);
    assert!(h.state().busy(), "the volume loads in the background");
    h.state_mut().wait_for_job();
    h.run_steps(3);
    let app = h.state();
    assert_eq!(app.dataset().expect("opened").field.dims(), [24, 24, 24]);
    assert_eq!(app.error(), None);
    assert!(h.query_by_label("Open path").is_none(), "the window closed");
}

#[test]
fn opening_another_volume_cancels_the_running_job() {
    let (mut h, _) = explorer();
    h.state_mut().open("synthetic:160");
    h.run_steps(2);
    h.state_mut().open("synthetic:20");
    h.state_mut().wait_for_job();
    h.run_steps(3);
    let app = h.state();
    assert_eq!(app.error(), None, "a cancelled job is no error");
    assert_eq!(app.dataset().expect("opened").field.dims(), [20, 20, 20]);
    // The cancelled job's late result never replaces it.
    std::thread::sleep(std::time::Duration::from_millis(300));
    h.run_steps(3);
    assert_eq!(
        h.state().dataset().expect("still").field.dims(),
        [20, 20, 20]
    );
    assert!(!h.state().busy());
}

/// A file dropped on the window, as the windowing integration hands it over.
#[derive(Debug)]
struct Dropped(std::path::PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &std::path::Path {
        &self.0
    }
    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

#[test]
fn a_volume_dropped_on_the_window_opens() {
    let (mut h, _) = explorer();
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("blob.nrrd");
    let mut bytes =
        b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 6 5 4\nencoding: raw\n\n".to_vec();
    bytes.extend((0..6 * 5 * 4).map(|i: u32| ((i * 37) % 251) as u8));
    std::fs::write(&path, bytes).expect("write");
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(path)));
    h.run_steps(1);
    assert!(h.state().busy(), "the dropped file loads in the background");
    h.state_mut().wait_for_job();
    h.run_steps(3);
    let app = h.state();
    assert_eq!(app.error(), None);
    let ds = app.dataset().expect("opened");
    assert_eq!(ds.name, "blob.nrrd");
    assert_eq!(ds.field.dims(), [6, 5, 4]);
}

/// The explorer as the window opens `field`: the first screen.
fn first_screen(field: flexiso::field::ScalarField) -> (Harness<'static, FlexisoApp>, bool) {
    let gpu = common::gpu().is_some();
    let builder = Harness::builder()
        .with_size(egui::vec2(1600.0, 1000.0))
        .with_pixels_per_point(1.0);
    let builder = if gpu { builder.wgpu() } else { builder };
    let mut h = builder.build_eframe(move |_cc| FlexisoApp::new_for_test_first_screen(field));
    h.run_steps(3);
    settle(&mut h);
    h.run_steps(3);
    (h, gpu)
}

/// What every first screen shows: a level on the curve's widest plateau
/// of a readable size, at least three contours (the most important
/// branches), each extracted, in its own colour, marked on the tree, and
/// the 3D view framed on them.
fn check_first_screen(h: &Harness<'_, FlexisoApp>, name: &str) {
    use flexiso::simplify::overview::{FIRST_SCREEN_ARCS, first_screen_step};
    let app = h.state();
    let level = app.level().expect("a level");
    let sim = level.simplification();
    assert_eq!(
        level.step(),
        first_screen_step(sim),
        "{name}: the plateau level"
    );
    assert!(
        FIRST_SCREEN_ARCS.contains(&level.num_arcs()),
        "{name}: {} arcs shown",
        level.num_arcs()
    );
    let sel = &app.selection().contours;
    assert!(
        sel.len() >= 3,
        "{name}: {} contours on the first screen",
        sel.len()
    );
    assert!(sel.len() <= 6, "{name}: {} contours", sel.len());
    let colours: std::collections::HashSet<egui::Color32> = sel.iter().map(|c| c.colour).collect();
    assert_eq!(colours.len(), sel.len(), "{name}: each in its own colour");
    for c in sel {
        let m = c.mesh.as_ref().expect("extracted");
        assert!(m.num_triangles() > 0, "{name}: contour #{} is empty", c.id);
        assert!(
            level.live_arc_of(c.superarc).is_some(),
            "{name}: contour #{} lies on a shown arc",
            c.id
        );
    }
    assert_eq!(
        app.tree_panel().drawn.markers.len(),
        sel.len(),
        "{name}: all marked"
    );
    assert!(!app.framing_pending(), "{name}: the 3D view was framed");
    // Framed on the contours: the camera looks at the middle of their box.
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for c in sel {
        let m = c.mesh.as_ref().expect("extracted");
        for p in &m.positions {
            for (k, &pk) in p.iter().enumerate() {
                lo[k] = lo[k].min(pk);
                hi[k] = hi[k].max(pk);
            }
        }
    }
    let t = app.view3d().camera.target.to_array();
    for (k, &tk) in t.iter().enumerate() {
        let mid = 0.5 * (lo[k] + hi[k]);
        assert!(
            (tk - mid).abs() <= 0.02 * (hi[k] - lo[k]).max(1.0),
            "{name}: camera target {t:?}, contours' box {lo:?}..{hi:?}"
        );
    }
}

/// The volume `spec` names (a path or `synthetic`), read as the CLI would.
fn load(spec: &str) -> flexiso::field::ScalarField {
    flexiso::field::source::VolumeSource::parse(spec, flexiso::field::io::ReadOptions::default())
        .expect("a volume")
        .load()
        .expect("read")
        .field
}

#[test]
fn the_first_screen_of_the_default_dataset_shows_at_least_three_contours() {
    let (h, _) = first_screen(load("synthetic"));
    check_first_screen(&h, "synthetic");
}

#[test]
fn the_first_screen_of_colin27_ch2_shows_at_least_three_contours() {
    let Some(path) = common::data::dataset("colin27_ch2.nrrd") else {
        return;
    };
    let (h, _) = first_screen(load(path.to_str().expect("a UTF-8 path")));
    check_first_screen(&h, "colin27_ch2");
}

/// The README's walk-through, as a newcomer does it in the window: on
/// colin27_ch2's first screen (the brain among its contours), choose the
/// volume measure in its box, type 46 in the arcs box and press Enter,
/// then shift-click the two down-going branches at the far left. Both
/// clicks add (the first-screen contours stay) and the two new contours
/// are the eyes: two small closed surfaces side by side, mirror images
/// across the brain's mid-plane.
#[test]
fn the_brain_and_both_eyes_of_colin27_in_five_actions() {
    let Some(path) = common::data::dataset("colin27_ch2.nrrd") else {
        return;
    };
    let (mut h, _) = first_screen(load(path.to_str().expect("a UTF-8 path")));
    let first: Vec<_> = h
        .state()
        .selection()
        .contours
        .iter()
        .map(|c| c.id)
        .collect();
    assert!(first.len() >= 3, "the first screen shows contours");
    // The brain: the first-screen contour with the most triangles.
    let brain_box = {
        let sel = &h.state().selection().contours;
        let brain = sel
            .iter()
            .filter_map(|c| c.mesh.as_ref())
            .max_by_key(|m| m.num_triangles())
            .expect("a mesh");
        mesh_box(brain)
    };

    // 1–2: the measure box, then "volume".
    h.get_by_label("measure").click();
    h.run_steps(2);
    h.get_by_label("volume").click();
    h.run_steps(2);
    h.state_mut().wait_for_job();
    h.run_steps(3);
    assert_eq!(
        h.state().dataset().expect("dataset").sim.measure(),
        flexiso::simplify::Measure::Volume
    );
    // 3: 46 arcs, Enter.
    type_arcs(&mut h, 46);
    h.key_press(egui::Key::Enter);
    h.run_steps(3);
    settle(&mut h);
    assert_eq!(h.state().level().expect("level").num_arcs(), 46);

    // The down-going branches' tips: shown arcs whose lower node is a
    // leaf (a minimum); the two drawn farthest left.
    let leftmost: Vec<(SimplifiedArcId, egui::Pos2)> = {
        let app = h.state();
        let level = app.level().expect("level");
        let mut degree = std::collections::HashMap::new();
        for a in level.arcs() {
            *degree.entry(a.upper).or_insert(0) += 1;
            *degree.entry(a.lower).or_insert(0) += 1;
        }
        let mut tips: Vec<_> = app
            .tree_panel()
            .drawn
            .arcs
            .iter()
            .copied()
            .filter(|&(a, _)| degree[&level.arc(a).lower] == 1)
            .collect();
        tips.sort_by(|x, y| x.1.x.total_cmp(&y.1.x));
        tips.truncate(2);
        tips
    };
    assert_eq!(leftmost.len(), 2, "two down-going branches");
    // 4–5: shift-click each.
    for &(_, p) in &leftmost {
        common::harness::shift_click(&mut h, p);
    }
    let sel = &h.state().selection().contours;
    assert_eq!(sel.len(), first.len() + 2, "both shift-clicks added");
    for id in &first {
        assert!(sel.iter().any(|c| c.id == *id), "contour #{id} stayed");
    }
    let eyes: Vec<_> = sel
        .iter()
        .filter(|c| !first.contains(&c.id))
        .map(|c| c.mesh.as_ref().expect("extracted"))
        .collect();
    let (blo, bhi) = brain_box;
    let mid = 0.5 * (blo[0] + bhi[0]);
    let (a, b) = (mesh_box(eyes[0]), mesh_box(eyes[1]));
    let centre = |(lo, hi): ([f32; 3], [f32; 3])| -> [f32; 3] {
        std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]))
    };
    let (ca, cb) = (centre(a), centre(b));
    eprintln!(
        "eyes centred at {ca:?} and {cb:?}; brain x {} .. {}",
        blo[0], bhi[0]
    );
    let width = bhi[0] - blo[0];
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let size = a.1[k] - a.0[k];
        assert!(
            size > 0.0 && size < 0.25 * width,
            "an eye is small: {axis} size {size} (brain width {width})"
        );
    }
    assert!(
        (0.5 * (ca[0] + cb[0]) - mid).abs() < 0.05 * width,
        "mirror images across the mid-plane: x {} and {}, mid {mid}",
        ca[0],
        cb[0]
    );
    assert!(
        (ca[0] - cb[0]).abs() > 0.2 * width,
        "side by side: x {} and {}",
        ca[0],
        cb[0]
    );
    for k in 1..3 {
        assert!(
            (ca[k] - cb[k]).abs() < 0.05 * width,
            "at the same height and depth: {ca:?} and {cb:?}"
        );
    }
}

/// The box of a mesh's positions.
fn mesh_box(m: &flexiso::contour::ContourMesh) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in &m.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

#[test]
fn hovering_an_arc_says_what_it_is_and_previews_its_contour_dimmed() {
    use flexiso::app::jobs::preview::PreviewState;
    let (mut h, gpu) = explorer();
    let (arc, p) = tallest_arc(&h);
    h.hover_at(p);
    h.run_steps(2);
    let app = h.state();
    let info = app
        .tree_panel()
        .hover_info
        .clone()
        .expect("the hovered arc's info");
    assert_eq!(info.arc, arc);
    let ds = app.dataset().expect("dataset");
    let n: u64 = ds.field.dims().iter().map(|&d| d as u64).product();
    let sides = info.sides.expect("the sides of its contours");
    assert!(
        sides.above + sides.below >= n,
        "{sides:?} cover the {n} voxels"
    );
    assert!(sides.enclosed().0 <= n / 2 + 1 || sides.above.min(sides.below) == sides.enclosed().0);
    let e = info.extent.expect("where its contours lie");
    for (k, &d) in ds.field.dims().iter().enumerate() {
        assert!(e.min[k] <= e.max[k] && e.max[k] < d);
    }
    let text = info.describe(ds.field.spacing());
    assert!(
        text.contains("voxels") && text.contains("lies in"),
        "{text}"
    );
    // The preview is the contour a click would select.
    let want = flexiso::app::panels::tree::TreePanel::contour_of_arc(
        ds,
        app.level().expect("level"),
        arc,
        app.global_h(),
    )
    .expect("the arc has a contour");
    assert_eq!(app.preview().key(), Some((want.0, want.1.to_bits())));
    h.state_mut().wait_for_preview();
    h.run_steps(2);
    let app = h.state();
    assert_eq!(app.preview().state, PreviewState::Ready);
    assert!(app.preview().mesh.is_some(), "a preview mesh");
    assert!(
        app.selection().contours.is_empty(),
        "hovering selects nothing"
    );
    if gpu {
        assert!(app.view3d().mesh_ids().contains(&SceneKey::Preview));
    }
    // Moving off the arcs ends it.
    let corner = app.tree_panel().drawn.rect.expect("drawn").min + egui::vec2(3.0, 3.0);
    h.hover_at(corner);
    h.run_steps(2);
    assert!(h.state().tree_panel().hovered.is_none());
    assert_eq!(h.state().preview().key(), None);
    assert!(h.state().preview().mesh.is_none());
}

#[test]
fn all_contours_at_h_shows_one_contour_per_arc_of_the_shown_tree() {
    let (mut h, gpu) = explorer();
    h.state_mut().set_level_arcs(12);
    h.state_mut().set_show_all(true);
    h.run_steps(2);
    let ctx = h.ctx.clone();
    h.state_mut().wait_for_all_contours(&ctx);
    h.run_steps(2);
    let app = h.state();
    let level = app.level().expect("level");
    let sim = level.simplification();
    let hv = app.global_h();
    let spanning: Vec<SimplifiedArcId> = level
        .arcs()
        .filter(|a| sim.node_value(a.lower) <= hv && hv < sim.node_value(a.upper))
        .map(|a| a.id)
        .collect();
    assert!(!spanning.is_empty());
    let arcs = app.all_contour_arcs();
    assert_eq!(
        arcs.len(),
        spanning.len(),
        "one contour per shown arc spanning h"
    );
    let mut on: Vec<SimplifiedArcId> = arcs
        .iter()
        .map(|s| level.live_arc_of(*s).expect("on a shown arc"))
        .collect();
    on.sort();
    on.dedup();
    assert_eq!(on.len(), spanning.len(), "each on its own arc");
    let every = {
        let ds = app.dataset().expect("dataset");
        flexiso::contour::all_contours(&ds.tree, &ds.field, flexiso::field::Isovalue::new(hv))
            .iter()
            .filter(|m| !m.indices.is_empty())
            .count()
    };
    assert!(every >= arcs.len());
    if gpu {
        for _ in 0..20 {
            if h.state().all_contours_on_screen() {
                break;
            }
            h.run_steps(1);
        }
        assert!(h.state().all_contours_on_screen(), "uploaded");
    }
    // The option shows every component.
    h.state_mut().set_every_component(true);
    h.run_steps(2);
    h.state_mut().wait_for_all_contours(&ctx);
    h.run_steps(2);
    assert_eq!(h.state().all_contours_shown(), every);
}

#[test]
fn a_hidden_contour_has_a_way_back_to_the_level_that_shows_its_arc() {
    let (mut h, _) = explorer();
    // The contour of the branch pruned first among those shown.
    let (arc, step) = {
        let app = h.state();
        let level = app.level().expect("level");
        let b = app.dataset().expect("dataset").layout.branches();
        level
            .arcs()
            .map(|a| (a.id, b.of_arc(a.id)))
            .filter(|(_, br)| (br.0 as usize) < b.steps())
            .min_by_key(|(_, br)| *br)
            .map(|(a, br)| (a, br.0 as usize))
            .expect("a pruned branch is shown")
    };
    h.state_mut().select_arc(arc, true);
    settle(&mut h);
    h.state_mut().set_level_arcs(1);
    h.run_steps(3);
    let s = h.state().selection().contours[0].superarc;
    assert!(h.state().level().expect("level").live_arc_of(s).is_none());
    h.get_by_label(flexiso::app::panels::contour_list::SHOW_ARC)
        .click();
    h.run_steps(6);
    let level = h.state().level().expect("level");
    assert_eq!(level.step(), step, "the coarsest level that shows the arc");
    assert!(level.live_arc_of(s).is_some(), "its arc is shown again");
    assert_eq!(
        h.state().tree_panel().drawn.markers.len(),
        1,
        "and its marker"
    );
}

#[test]
fn fitting_frames_the_whole_box_in_a_narrow_view() {
    use flexiso::app::panels::view3d::fit_in_view;
    let (lo, hi) = ([0.0f32, 0.0, 0.0], [100.0f32, 60.0, 40.0]);
    for aspect in [0.4f32, 0.7, 1.0, 1.8] {
        let mut cam = flexiso::render::Camera::default();
        fit_in_view(&mut cam, lo, hi, aspect);
        let m = cam.view_proj(aspect);
        for i in 0..8 {
            let c = glam::Vec3::new(
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            );
            let p = m.project_point3(c);
            assert!(
                p.x.abs() <= 1.0 && p.y.abs() <= 1.0,
                "aspect {aspect}: corner {c} at {p} is cut off"
            );
        }
    }
}

/// Double-click in the 3D view fits the contours as they are now: after a
/// marker drag moved a contour, the camera centres on the contour's new
/// box, not on the one it had when it was first extracted.
#[test]
fn double_click_fits_the_contours_current_geometry_after_a_drag() {
    let (mut h, gpu) = explorer();
    if !gpu {
        return;
    }
    let (_, p) = tallest_arc(&h);
    click(&mut h, p);
    let centre = |h: &Harness<'_, FlexisoApp>| {
        let c = &h.state().selection().contours[0];
        let (lo, hi) = mesh_box(c.mesh.as_ref().expect("extracted"));
        glam::Vec3::from(lo).lerp(glam::Vec3::from(hi), 0.5)
    };
    let before = centre(&h);
    let marker = h.state().tree_panel().drawn.markers[0].1;
    drag(&mut h, marker, marker - egui::vec2(0.0, 150.0));
    let after = centre(&h);
    assert!(
        after.distance(before) > 2.0,
        "the drag moved the contour: {before} -> {after}"
    );
    // Near a corner of the 3D view, off the contour.
    let view = h.state().view3d().rect.expect("the view was drawn");
    let q = view.right_top() + egui::vec2(-60.0, 120.0);
    h.hover_at(q);
    h.run_steps(1);
    // Two clicks in one frame: a double-click (the harness's frames are
    // a quarter second apart, queued events one frame each).
    for pressed in [true, false, true, false] {
        h.input_mut().events.push(egui::Event::PointerButton {
            pos: q,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        });
    }
    h.step();
    h.run_steps(2);
    settle(&mut h);
    let t = h.state().view3d().camera.target;
    assert!(
        t.distance(after) < 0.5 && t.distance(before) > 0.5,
        "the camera looks at {t}: the contour's box is centred at {after} now, {before} before the drag"
    );
}

#[test]
fn the_tree_panel_labels_important_values_clear_of_each_other_and_the_markers() {
    let (mut h, _) = explorer();
    let (_, p) = tallest_arc(&h);
    click(&mut h, p);
    let app = h.state();
    let drawn = &app.tree_panel().drawn;
    let labels = &drawn.value_labels;
    assert!(!labels.is_empty(), "some values labelled");
    assert!(labels.len() <= flexiso::app::panels::tree::MAX_VALUE_LABELS);
    let sim = app.level().expect("a level").simplification();
    for (k, (n, r, text)) in labels.iter().enumerate() {
        assert_eq!(*text, flexiso::app::format::fmt_value(sim.node_value(*n)));
        assert!(
            labels[k + 1..].iter().all(|(_, q, _)| !q.intersects(*r)),
            "label {text} overlaps another"
        );
        for (_, m) in &drawn.markers {
            assert!(
                !r.intersects(egui::Rect::from_center_size(*m, egui::vec2(14.0, 14.0))),
                "label {text} on a marker"
            );
        }
        assert!(drawn.rect.expect("drawn").contains_rect(*r));
    }
}
