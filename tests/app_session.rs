//! Sessions in the explorer (issue 16): save and open give the identical
//! scene; a changed volume opens with a message and the contours that can
//! be placed; a crashed run's scene is offered at the next start; without
//! a system file dialog, a typed path saves.

use egui::Color32;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use flexiso::app::FlexisoApp;
use flexiso::app::selection::ContourState;
use flexiso::session::Session;

mod common;

use common::harness::synthetic_explorer as explorer;

/// An empty explorer (no volume yet), as at the program's start.
fn fresh() -> Harness<'static, FlexisoApp> {
    let mut h = Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .with_pixels_per_point(1.0)
        .build_eframe(|_cc| FlexisoApp::empty());
    h.run_steps(2);
    h
}

fn settle(h: &mut Harness<'_, FlexisoApp>) {
    h.run_steps(2);
    h.state_mut().wait_for_extractions();
    h.run_steps(2);
}

/// Two contours on the two longest arcs, coloured, named, one hidden; a
/// level and a camera of their own.
fn compose(h: &mut Harness<'_, FlexisoApp>) {
    let arcs = common::harness::arcs_by_length(h);
    let (a, b) = (arcs[0], arcs[1]);
    h.state_mut().select_arc(a, true);
    h.state_mut().select_arc(b, false);
    settle(h);
    let sel = h.state_mut().selection_mut();
    assert_eq!(sel.contours.len(), 2);
    sel.contours[0].colour = Color32::from_rgb(0x12, 0x34, 0x56);
    sel.contours[0].name = "brain".into();
    sel.contours[1].visible = false;
    sel.contours[1].name = "eyes".into();
    h.state_mut().camera_mut().yaw = 0.5;
    h.state_mut().camera_mut().distance *= 1.5;
    settle(h);
}

fn scene(h: &Harness<'_, FlexisoApp>) -> Vec<ContourState> {
    h.state().selection().states()
}

/// A folder of the test's own, removed when it ends.
fn scratch() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("flexiso-session-test-")
        .tempdir()
        .expect("a temp dir")
}

#[test]
fn a_saved_session_opens_as_the_identical_scene() {
    let dir = scratch();
    let mut h = explorer();
    compose(&mut h);
    let path = dir.path().join("roundtrip.json");
    assert!(h.state().unsaved_changes());
    h.state_mut().save_session(&path).expect("saved");
    assert!(!h.state().unsaved_changes(), "saved");
    let saved = Session::read(&path).expect("a session");
    assert_eq!(saved.format, "flexiso-session");
    assert_eq!(saved.version, 1);
    assert_eq!(saved.volume, "synthetic:24");
    assert_eq!(saved.contours[0].color, "#123456");
    assert_eq!(saved.contours[0].name, "brain");
    assert!(!saved.contours[1].visible);

    let mut g = fresh();
    g.state_mut().open_session(&path);
    g.state_mut().wait_for_job();
    settle(&mut g);
    assert_eq!(g.state().error(), None);
    assert_eq!(scene(&g), scene(&h), "the identical contours");
    assert_eq!(
        g.state().level().map(|l| l.num_arcs()),
        h.state().level().map(|l| l.num_arcs())
    );
    assert_eq!(g.state().measure(), h.state().measure());
    assert_eq!(g.state().view3d().camera.yaw, h.state().view3d().camera.yaw);
    assert_eq!(
        g.state().view3d().camera.distance,
        h.state().view3d().camera.distance
    );
    assert!(
        g.state()
            .selection()
            .contours
            .iter()
            .all(|c| c.mesh.is_some()),
        "every contour extracted"
    );
    assert!(!g.state().unsaved_changes(), "just opened");
}

#[test]
fn a_session_on_a_changed_volume_opens_what_it_can_and_says_what_it_could_not() {
    let dir = scratch();
    let mut h = explorer();
    compose(&mut h);
    let path = dir.path().join("changed.json");
    h.state_mut().save_session(&path).expect("saved");
    let mut s = Session::read(&path).expect("a session");
    s.contours[1].superarc = [u32::MAX, 7];
    s.dims = Some([24, 24, 25]);
    s.write(&path).expect("written");

    let mut g = fresh();
    g.state_mut().open_session(&path);
    g.state_mut().wait_for_job();
    settle(&mut g);
    assert_eq!(g.state().selection().contours.len(), 1, "the one that fits");
    assert_eq!(g.state().selection().contours[0].name, "brain");
    let info = g.state().info().expect("a message");
    assert!(info.contains("1 of 2 contours"), "{info}");
    assert!(info.contains("volume changed"), "{info}");
}

#[test]
fn a_bad_session_file_shows_an_error() {
    let dir = scratch();
    let mut g = fresh();
    let path = dir.path().join("bad.json");
    std::fs::write(&path, r#"{"format": "something-else"}"#).expect("written");
    g.state_mut().open_session(&path);
    g.run_steps(2);
    let e = g.state().error().expect("an error");
    assert!(e.contains("flexiso-session"), "{e}");
    g.state_mut().open_session(&dir.path().join("missing.json"));
    assert!(
        g.state()
            .error()
            .is_some_and(|e| e.contains("missing.json"))
    );
}

#[test]
fn after_a_crash_the_recovery_file_is_offered_and_restores_the_scene() {
    let dir = scratch();
    let path = dir.path().join("recovery.json");
    let _ = std::fs::remove_file(&path);
    let mut h = explorer();
    h.state_mut().set_recovery_file(path.clone());
    compose(&mut h);
    h.state_mut().autosave_now();
    assert!(path.exists(), "the recovery file is written");
    // The run "crashes": the app is dropped without closing.
    let before = scene(&h);
    drop(h);

    let mut g = fresh();
    g.state_mut().set_recovery_file(path.clone());
    g.run_steps(2);
    assert!(g.state().recovery_offered());
    assert!(g.query_by_label("Recover the last scene?").is_some());
    g.get_by_label("Recover").click();
    g.run_steps(2);
    g.state_mut().wait_for_job();
    settle(&mut g);
    assert!(!g.state().recovery_offered());
    assert_eq!(scene(&g), before, "the same scene");
    assert!(
        g.state().unsaved_changes(),
        "a recovered scene is saved nowhere"
    );
}

#[test]
fn the_recovery_file_is_written_off_the_ui_thread() {
    // A recovery file that cannot be written until someone reads it: a
    // named pipe, as a stalled network disk would be.
    let dir = scratch();
    let pipe = dir.path().join("recovery.json");
    let made = std::process::Command::new("mkfifo").arg(&pipe).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("skipped: mkfifo is not available here");
        return;
    }
    // The reader opens the pipe when told, or after 20 s should the
    // write hold the test's thread (the bug this test is for).
    let (go, wait) = std::sync::mpsc::channel::<()>();
    let reader = {
        let pipe = pipe.clone();
        std::thread::spawn(move || {
            let _ = wait.recv_timeout(std::time::Duration::from_secs(20));
            std::fs::read_to_string(&pipe).expect("the pipe read")
        })
    };
    let mut h = explorer();
    h.state_mut().set_recovery_file(pipe.clone());
    assert!(!h.state().recovery_offered(), "a pipe is not offered");
    compose(&mut h);
    let t = std::time::Instant::now();
    h.state_mut().autosave_later();
    h.run_steps(2);
    let held = t.elapsed();
    go.send(()).expect("the reader waits");
    let written = reader.join().expect("the reader");
    assert!(
        held < std::time::Duration::from_secs(10),
        "the window waited {held:?} for the recovery file"
    );
    let s = Session::from_json(&written, &pipe).expect("a whole session");
    assert_eq!(s.contours.len(), 2);
}

#[test]
fn a_recovery_file_that_cannot_be_written_is_shown_as_an_error() {
    // Its folder would be inside a plain file: no write can succeed.
    let dir = scratch();
    let file = dir.path().join("a-file");
    std::fs::write(&file, "not a folder").expect("written");
    let mut h = explorer();
    h.state_mut().set_recovery_file(file.join("recovery.json"));
    compose(&mut h);
    assert_eq!(h.state().error(), None);
    h.state_mut().autosave_now();
    h.run_steps(2);
    let e = h.state().error().expect("an error shown");
    assert!(e.contains("recovery file"), "{e}");
    assert!(e.contains("save the session"), "{e}");
}

#[test]
fn without_a_system_dialog_a_typed_path_saves_the_session() {
    let dir = scratch();
    // SAFETY: this test binary's other tests neither read nor write the
    // environment.
    unsafe { std::env::set_var("FLEXISO_NO_DIALOG", "1") };
    let mut h = explorer();
    compose(&mut h);
    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("Save session as…").click();
    let mut asked = false;
    for _ in 0..50 {
        h.run_steps(1);
        if h.query_by_label("Save to path").is_some() {
            asked = true;
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(asked, "the typed-path window shows");
    let path = dir.path().join("typed.json");
    let _ = std::fs::remove_file(&path);
    h.get_by_label("Path:").click();
    h.run_steps(1);
    h.get_by_label("Path:").type_text(&path.to_string_lossy());
    h.run_steps(1);
    h.get_by_label("Save to path").click();
    h.run_steps(2);
    assert!(path.exists(), "{:?}", h.state().error());
    assert!(!h.state().unsaved_changes());
    // A path that cannot be written is an error shown.
    h.state_mut().selection_mut().contours[0].name = "changed".into();
    settle(&mut h);
    assert!(
        h.state_mut()
            .save_session(std::path::Path::new("/nonexistent-dir/x.json"))
            .is_err()
    );
    assert!(h.state().error().is_some_and(|e| e.contains("cannot save")));
}

#[test]
fn render_session_draws_each_visible_contour_in_its_colour() {
    let dir = scratch();
    if common::gpu().is_none() {
        return;
    }
    let mut h = explorer();
    compose(&mut h);
    let path = dir.path().join("render.json");
    h.state_mut().save_session(&path).expect("saved");
    let mut s = Session::read(&path).expect("a session");
    // Both shown, in two colours far from the grey background.
    s.contours[0].color = "#ff0000".into();
    s.contours[1].color = "#00ff00".into();
    s.contours[1].visible = true;
    s.camera = None;
    s.write(&path).expect("written");
    let png = dir.path().join("render.png");
    let out = common::flexiso(&[
        "render",
        "--session",
        path.to_str().expect("utf-8"),
        "--out",
        png.to_str().expect("utf-8"),
        "--size",
        "320x240",
        // The legend's swatches have the colours too: the contours alone.
        "--no-legend",
    ]);
    assert!(out.success(), "{}", out.stderr);
    let img = image::open(&png).expect("png").to_rgba8();
    let count = |keep: fn(&[u8]) -> bool| img.pixels().filter(|p| keep(&p.0)).count();
    let red = count(|p| p[0] > 60 && p[1] < p[0] / 2 && p[2] < p[0] / 2);
    let green = count(|p| p[1] > 60 && p[0] < p[1] / 2 && p[2] < p[1] / 2);
    assert!(red > 10, "the red contour is drawn: {red} pixels");
    assert!(green > 10, "the green contour is drawn: {green} pixels");
}

#[test]
fn an_export_with_the_session_ticked_writes_it_beside_the_meshes() {
    let dir = scratch();
    let mut h = explorer();
    compose(&mut h);
    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("…and a session beside the meshes").click();
    h.run_steps(2);
    let ply = dir.path().join("beside.ply");
    let beside = FlexisoApp::session_beside(&ply);
    assert_eq!(beside, ply.with_extension("session.json"));
    let _ = std::fs::remove_file(&beside);
    h.state_mut().start_contour_export(ply.clone());
    h.state_mut().wait_for_exports();
    assert_eq!(h.state().error(), None);
    assert!(ply.exists(), "the meshes");
    let s = flexiso::session::Session::read(&beside).expect("the session beside them");
    assert_eq!(s.contours.len(), 2, "the whole scene, hidden contour too");
    assert_eq!(s.contours[0].name, "brain");
    assert_eq!(s.contours[0].color, "#123456");
}
