//! Nothing the user makes is lost (issue 16): undo and redo of every kind
//! of change to the scene, Escape that only closes popups and cancels
//! drags, and the question asked before unsaved changes are thrown away.
//! Driven headless with egui_kittest, as a user would.

use egui::{Color32, Key, Modifiers, Pos2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use flexiso::app::FlexisoApp;
use flexiso::app::session::Pending;
use flexiso::field::synthetic::Synthetic;
use flexiso::simplify::Measure;

mod common;

use common::harness::{click, drag, drag_and_hold, settle, tallest_arc};

/// The explorer on a small synthetic volume, in a 1200×800 window.
fn explorer() -> Harness<'static, FlexisoApp> {
    let field = Synthetic::cube(40).generate();
    let mut h = Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .with_pixels_per_point(1.0)
        .build_eframe(move |_cc| FlexisoApp::new_for_test(field));
    h.run_steps(3);
    h
}

fn key(h: &mut Harness<'_, FlexisoApp>, m: Modifiers, k: Key) {
    h.key_press_modifiers(m, k);
    settle(h);
}

fn undo(h: &mut Harness<'_, FlexisoApp>) {
    key(h, Modifiers::COMMAND, Key::Z);
}

fn heights(h: &Harness<'_, FlexisoApp>) -> Vec<f64> {
    h.state().selection().contours.iter().map(|c| c.h).collect()
}

/// One contour selected on the tallest arc, and the marker's position.
fn one_contour(h: &mut Harness<'_, FlexisoApp>) -> Pos2 {
    let (_, p) = tallest_arc(h);
    click(h, p);
    assert_eq!(h.state().selection().contours.len(), 1);
    h.state().tree_panel().drawn.markers[0].1
}

#[test]
fn ctrl_z_undoes_a_selection_and_ctrl_shift_z_and_ctrl_y_redo_it() {
    let mut h = explorer();
    one_contour(&mut h);
    undo(&mut h);
    assert!(
        h.state().selection().contours.is_empty(),
        "selection undone"
    );
    key(&mut h, Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    assert_eq!(
        h.state().selection().contours.len(),
        1,
        "Ctrl+Shift+Z redoes"
    );
    let c = &h.state().selection().contours[0];
    assert!(c.mesh.is_some(), "the redone contour is extracted again");
    undo(&mut h);
    key(&mut h, Modifiers::COMMAND, Key::Y);
    assert_eq!(h.state().selection().contours.len(), 1, "Ctrl+Y redoes");
}

#[test]
fn a_marker_drag_is_one_step_however_many_frames_it_took() {
    let mut h = explorer();
    let m = one_contour(&mut h);
    let before = heights(&h);
    drag(&mut h, m, m + egui::vec2(0.0, -40.0));
    let after = heights(&h);
    assert_ne!(before, after, "the drag moved the isovalue");
    undo(&mut h);
    assert_eq!(heights(&h), before, "one undo undoes the whole drag");
    key(&mut h, Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    assert_eq!(heights(&h), after, "redo moves it back");
}

#[test]
fn escape_mid_drag_cancels_it_and_leaves_no_step() {
    let mut h = explorer();
    let m = one_contour(&mut h);
    let before = heights(&h);
    drag_and_hold(&mut h, m, m + egui::vec2(0.0, -40.0));
    assert_ne!(heights(&h), before, "the drag is moving the contour");
    h.key_press(Key::Escape);
    h.run_steps(1);
    // Moving on with the button still held drags nothing any more.
    h.hover_at(m + egui::vec2(0.0, -60.0));
    h.run_steps(1);
    h.drop_at(m + egui::vec2(0.0, -60.0));
    settle(&mut h);
    assert_eq!(heights(&h), before, "the contour is back where it was");
    assert_eq!(h.state().undo_label(), Some("new selection"));
}

#[test]
fn escape_with_a_popup_open_closes_it_and_keeps_the_contours() {
    let mut h = explorer();
    one_contour(&mut h);
    h.get_by_label("File").click();
    h.run_steps(2);
    assert!(h.query_by_label("Save session as…").is_some(), "menu open");
    h.key_press(Key::Escape);
    h.run_steps(2);
    assert!(
        h.query_by_label("Save session as…").is_none(),
        "menu closed"
    );
    assert_eq!(h.state().selection().contours.len(), 1, "nothing cleared");
}

#[test]
fn clear_contours_is_an_explicit_undoable_command_and_numbers_restart() {
    let mut h = explorer();
    one_contour(&mut h);
    h.get_by_label("Edit").click();
    h.run_steps(2);
    h.get_by_label("Clear contours").click();
    settle(&mut h);
    assert!(h.state().selection().contours.is_empty());
    undo(&mut h);
    assert_eq!(h.state().selection().contours.len(), 1, "clear undone");
    h.get_by_label("Edit").click();
    h.run_steps(2);
    h.get_by_label("Clear contours").click();
    settle(&mut h);
    one_contour(&mut h);
    assert_eq!(
        h.state().selection().contours[0].id.0,
        0,
        "numbering starts again after a clear"
    );
}

/// The contour's name field: the text input whose text is not the curve
/// panel's arc count.
fn name_field<'a>(h: &'a Harness<'_, FlexisoApp>) -> egui_kittest::Node<'a> {
    h.query_all_by_role(egui::accesskit::Role::TextInput)
        .find(|n| n.value().is_none_or(|v| v.trim().parse::<usize>().is_err()))
        .expect("the name field")
}

#[test]
fn colour_name_visibility_and_deletion_each_undo() {
    let mut h = explorer();
    one_contour(&mut h);
    // Colour (as the picker sets it).
    h.state_mut().selection_mut().contours[0].colour = Color32::from_rgb(1, 2, 3);
    settle(&mut h);
    assert_eq!(h.state().undo_label(), Some("colour of contour 0"));
    undo(&mut h);
    assert_ne!(
        h.state().selection().contours[0].colour,
        Color32::from_rgb(1, 2, 3)
    );
    // Name, typed in the list: one step when typing ends.
    name_field(&h).focus();
    h.run_steps(1);
    name_field(&h).type_text("brain");
    h.run_steps(2);
    assert_eq!(h.state().selection().contours[0].name, "brain");
    h.key_press(Key::Enter);
    settle(&mut h);
    assert_eq!(h.state().undo_label(), Some("name of contour 0"));
    undo(&mut h);
    assert_eq!(h.state().selection().contours[0].name, "");
    // Visibility.
    h.get_by_label("visible").click();
    settle(&mut h);
    assert!(!h.state().selection().contours[0].visible);
    undo(&mut h);
    assert!(h.state().selection().contours[0].visible);
    // Deletion.
    h.get_by_label("delete").click();
    settle(&mut h);
    assert!(h.state().selection().contours.is_empty());
    undo(&mut h);
    assert_eq!(h.state().selection().contours.len(), 1, "deletion undone");
    assert!(h.state().selection().contours[0].mesh.is_some());
}

#[test]
fn the_level_and_the_measure_undo() {
    let mut h = explorer();
    one_contour(&mut h);
    let arcs = h.state().level().expect("level").num_arcs();
    h.state_mut().set_level_arcs(arcs / 2);
    settle(&mut h);
    let fewer = h.state().level().expect("level").num_arcs();
    assert!(fewer < arcs);
    undo(&mut h);
    assert_eq!(h.state().level().expect("level").num_arcs(), arcs);

    let m = h.state().measure();
    let other = if m == Measure::Height {
        Measure::Volume
    } else {
        Measure::Height
    };
    h.state_mut().set_measure(other);
    h.state_mut().wait_for_job();
    settle(&mut h);
    assert_eq!(
        h.state().undo_label().map(str::to_string),
        Some(format!("measure {}", other.name()))
    );
    undo(&mut h);
    h.state_mut().wait_for_job();
    settle(&mut h);
    assert_eq!(h.state().measure(), m, "measure undone");
    assert_eq!(h.state().level().expect("level").num_arcs(), arcs);
    assert_eq!(h.state().selection().contours.len(), 1, "the contour stays");
}

#[test]
fn quitting_with_unsaved_changes_asks_first() {
    let mut h = explorer();
    // Nothing made yet: Quit quits.
    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("Quit").click();
    h.run_steps(2);
    assert!(h.state().closing(), "nothing to lose: no question");

    let mut h = explorer();
    one_contour(&mut h);
    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("Quit").click();
    h.run_steps(2);
    assert_eq!(h.state().confirming(), Some(&Pending::Quit));
    assert!(
        h.query_by_label("Unsaved changes").is_some(),
        "the question shows"
    );
    h.get_by_label("Cancel").click();
    h.run_steps(2);
    assert_eq!(h.state().confirming(), None);
    assert!(!h.state().closing(), "Cancel keeps the window");
    assert_eq!(h.state().selection().contours.len(), 1);

    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("Quit").click();
    h.run_steps(2);
    h.get_by_label("Discard changes").click();
    h.run_steps(2);
    assert!(h.state().closing(), "Discard closes");
}

#[test]
fn opening_another_volume_with_unsaved_changes_asks_first() {
    let mut h = explorer();
    one_contour(&mut h);
    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("Open the built-in dataset").click();
    h.run_steps(2);
    assert_eq!(
        h.state().confirming(),
        Some(&Pending::Open("synthetic".into()))
    );
    assert!(!h.state().busy(), "nothing opens before the answer");
    h.key_press(Key::Escape);
    h.run_steps(2);
    assert_eq!(h.state().confirming(), None, "Escape cancels the question");
    assert!(!h.state().busy());
    assert_eq!(h.state().selection().contours.len(), 1);
}

/// The picker's hex field (its text is a colour code).
fn hex_field<'a>(h: &'a Harness<'_, FlexisoApp>) -> Option<egui_kittest::Node<'a>> {
    h.query_all_by_role(egui::accesskit::Role::TextInput)
        .find(|n| n.value().is_some_and(|v| v.starts_with('#')))
}

#[test]
fn the_colour_picker_sets_a_swatch_or_a_typed_code_each_undone_and_escape_only_closes_it() {
    let mut h = explorer();
    one_contour(&mut h);
    let before = h.state().selection().contours[0].colour;
    // A swatch of the palette.
    let swatch = flexiso::app::selection::palette(3);
    assert_ne!(before, swatch, "another colour than the contour's");
    h.get_by_label("colour").click();
    h.run_steps(2);
    assert!(
        h.query_by_label("palette 3").is_some(),
        "the picker is open"
    );
    h.get_by_label("palette 3").click();
    settle(&mut h);
    assert_eq!(h.state().selection().contours[0].colour, swatch);
    // Escape closes the picker, and only that.
    h.key_press(Key::Escape);
    settle(&mut h);
    assert!(h.query_by_label("palette 3").is_none(), "the picker closed");
    assert_eq!(h.state().selection().contours.len(), 1, "nothing cleared");
    assert_eq!(h.state().selection().contours[0].colour, swatch, "kept");
    assert_eq!(h.state().undo_label(), Some("colour of contour 0"));
    undo(&mut h);
    assert_eq!(h.state().selection().contours[0].colour, before, "undone");

    // A code typed in the hex field, one key at a time as a person types.
    h.get_by_label("colour").click();
    h.run_steps(2);
    hex_field(&h).expect("the hex field").focus();
    h.run_steps(1);
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.run_steps(1);
    for c in "#102030".chars() {
        hex_field(&h)
            .expect("the hex field")
            .type_text(&c.to_string());
        h.run_steps(1);
    }
    h.key_press(Key::Enter);
    settle(&mut h);
    assert_eq!(
        h.state().selection().contours[0].colour,
        Color32::from_rgb(0x10, 0x20, 0x30)
    );
    h.key_press(Key::Escape);
    settle(&mut h);
    assert!(hex_field(&h).is_none(), "the picker closed");
    assert_eq!(h.state().undo_label(), Some("colour of contour 0"));
    undo(&mut h);
    assert_eq!(h.state().selection().contours[0].colour, before, "undone");
}

#[test]
fn isolating_unticks_the_other_rows_and_undoes_as_one_step() {
    let mut h = explorer();
    let arcs = common::harness::arcs_by_length(&h);
    h.state_mut().select_arc(arcs[0], true);
    h.state_mut().select_arc(arcs[1], false);
    settle(&mut h);
    assert_eq!(h.state().selection().contours.len(), 2);
    let visible = |h: &Harness<'_, FlexisoApp>| -> Vec<bool> {
        h.state()
            .selection()
            .contours
            .iter()
            .map(|c| c.visible)
            .collect()
    };
    // The first row's "isolate": the other row's visible box unticked.
    h.get_all_by_label("isolate")
        .next()
        .expect("an isolate button")
        .click();
    settle(&mut h);
    // (The rows' visible boxes show these values.)
    assert_eq!(visible(&h), [true, false]);
    assert!(h.state().selection().isolated.is_some());
    undo(&mut h);
    assert_eq!(visible(&h), [true, true], "undone in one step");
    assert_eq!(h.state().selection().isolated, None);
}
