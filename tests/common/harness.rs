//! Driving the explorer headless with egui_kittest as a user would:
//! clicks, drags, and waiting for the contour extractions in flight.

use egui::Pos2;
use egui_kittest::Harness;
use flexiso::app::FlexisoApp;
use flexiso::simplify::SimplifiedArcId;

/// Lets the contour extractions in flight finish and the panels redraw.
pub fn settle(h: &mut Harness<'_, FlexisoApp>) {
    h.run_steps(2);
    h.state_mut().wait_for_extractions();
    h.run_steps(2);
    h.state_mut().wait_for_slices();
    h.run_steps(1);
}

/// A click: press and release at `p` (after moving there).
pub fn click(h: &mut Harness<'_, FlexisoApp>, p: Pos2) {
    h.hover_at(p);
    h.run_steps(1);
    h.drag_at(p);
    h.run_steps(1);
    h.drop_at(p);
    settle(h);
}

/// Presses the button at `a`, moves to `b` in small steps, and leaves it
/// held there.
pub fn drag_and_hold(h: &mut Harness<'_, FlexisoApp>, a: Pos2, b: Pos2) {
    h.hover_at(a);
    h.run_steps(1);
    h.drag_at(a);
    h.run_steps(1);
    for i in 1..=10 {
        h.hover_at(a + (b - a) * (i as f32 / 10.0));
        h.run_steps(1);
    }
}

/// A drag from `a` to `b` in small moves.
pub fn drag(h: &mut Harness<'_, FlexisoApp>, a: Pos2, b: Pos2) {
    drag_and_hold(h, a, b);
    h.drop_at(b);
    settle(h);
}

/// The live arc spanning the widest range of values, and where the tree
/// panel drew its midpoint.
pub fn tallest_arc(h: &Harness<'_, FlexisoApp>) -> (SimplifiedArcId, Pos2) {
    let app = h.state();
    let level = app.level().expect("level");
    let sim = level.simplification();
    let span = |a: SimplifiedArcId| {
        let la = level.arc(a);
        sim.node_value(la.upper) - sim.node_value(la.lower)
    };
    app.tree_panel()
        .drawn
        .arcs
        .iter()
        .copied()
        .max_by(|x, y| span(x.0).total_cmp(&span(y.0)))
        .expect("the tree panel drew arcs")
}

/// The shown arcs, longest in value first.
pub fn arcs_by_length(h: &Harness<'_, FlexisoApp>) -> Vec<SimplifiedArcId> {
    let level = h.state().level().expect("level");
    let sim = level.simplification();
    let mut arcs: Vec<_> = level
        .arcs()
        .map(|a| (a.id, sim.node_value(a.upper) - sim.node_value(a.lower)))
        .collect();
    arcs.sort_by(|x, y| y.1.total_cmp(&x.1));
    arcs.into_iter().map(|(a, _)| a).collect()
}

/// The explorer on `synthetic:24` (a volume a session can name), in a
/// 1200×800 window, its pipeline already run.
pub fn synthetic_explorer() -> Harness<'static, FlexisoApp> {
    let mut h = Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .with_pixels_per_point(1.0)
        .build_eframe(|_cc| {
            let mut app = FlexisoApp::empty();
            app.open("synthetic:24");
            app.wait_for_job();
            app
        });
    h.run_steps(3);
    assert!(h.state().dataset().is_some());
    h
}

/// A click with shift held (adds to the selection): press and release at
/// `p`, the shift modifier on both events and held between them.
pub fn shift_click(h: &mut Harness<'_, FlexisoApp>, p: Pos2) {
    h.hover_at(p);
    h.run_steps(1);
    for pressed in [true, false] {
        h.event_modifiers(
            egui::Event::PointerButton {
                pos: p,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: egui::Modifiers::SHIFT,
            },
            egui::Modifiers::SHIFT,
        );
        h.run_steps(1);
    }
    settle(h);
}
