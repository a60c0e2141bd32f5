//! The simplification curve (paper §5): arcs left against feature size,
//! log-log, drawn as a step plot (the arcs stay constant between pruning
//! steps), with the current level as a vertical line and a point (at the
//! plot's left edge when its feature size is 0, e.g. the full tree of a
//! label map). Dragging on the plot (or the slider above it) moves the
//! level; the tree panel follows at once (a level change replays only the
//! steps in between). The arc-count box applies on Enter or when it loses
//! focus, never on a keystroke: it gives exactly the number asked for when
//! the pruning sequence has a level with that many arcs (a step removes one
//! or two arcs, so some counts are skipped), else the nearest level, and
//! says so next to the box.

use egui_plot::{GridMark, Line, Plot, PlotPoints, Points, VLine};

use crate::simplify::{Simplification, SimplifiedTree};

/// The curve panel's state.
pub struct CurvePanel {
    /// The plot's screen rect in the last frame (tests drag on it).
    pub plot_rect: Option<egui::Rect>,
    /// The step the user asked for, when not reached yet (see
    /// [`STEPS_PER_FRAME`]), and the simplification it is a step of.
    target: Option<(usize, usize)>,
    /// Pruning steps replayed per frame at most ([`STEPS_PER_FRAME`]).
    pub steps_per_frame: usize,
    /// The text of the arc-count box while it is edited.
    arcs_text: String,
    /// The count last asked for in the box and the nearest count the
    /// sequence has, when they differ (shown while that level is).
    arcs_note: Option<(usize, usize)>,
}

impl Default for CurvePanel {
    fn default() -> Self {
        CurvePanel {
            plot_rect: None,
            target: None,
            steps_per_frame: STEPS_PER_FRAME,
            arcs_text: String::new(),
            arcs_note: None,
        }
    }
}

/// Pruning steps replayed per frame at most. Any level change costs time
/// proportional to the steps in between (well under a millisecond on the
/// real volumes), but a tree of millions of arcs can ask for millions of
/// steps in one drag (0.4 s): the level then moves there over several
/// frames instead of freezing one.
pub const STEPS_PER_FRAME: usize = 50_000;

/// Labels the decades of a log10 axis: 0.01 0.1 1 10 100 1000, then 1e4.
fn decade_label(mark: GridMark) -> String {
    let n = mark.value.round();
    if (mark.value - n).abs() > 1e-6 {
        return String::new();
    }
    if (-2.0..=3.0).contains(&n) {
        crate::app::format::fmt_value(10f64.powf(n))
    } else {
        format!("1e{}", n as i64)
    }
}

/// Grid lines of a log10 axis: every decade (every few when there are
/// many), with 2..9 between them when few decades show.
fn decade_grid(input: egui_plot::GridInput) -> Vec<GridMark> {
    let (lo, hi) = input.bounds;
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return Vec::new();
    }
    let decades = hi - lo;
    let every = (decades / 8.0).ceil().max(1.0);
    let mut marks = Vec::new();
    let mut n = (lo / every).floor() * every;
    while n <= hi {
        marks.push(GridMark {
            value: n,
            step_size: every,
        });
        if decades <= 4.0 {
            for k in 2..10 {
                marks.push(GridMark {
                    value: n + (k as f64).log10(),
                    step_size: every / 10.0,
                });
            }
        }
        n += every;
    }
    marks.retain(|m| m.value >= lo && m.value <= hi);
    marks
}

/// The level of `sim` whose arc count is nearest `arcs`: the step count
/// and the arcs it leaves. Exactly `arcs` whenever some level has that
/// many (the curve's arc counts never increase, so that level is the first
/// with at most `arcs`); otherwise the nearer of its two neighbours (the
/// one with fewer arcs on a tie).
pub fn nearest_level(sim: &Simplification, arcs: usize) -> (usize, usize) {
    let curve = sim.curve();
    let s = sim.steps_for_arcs(arcs);
    let here = curve[s].arcs;
    if here == arcs || s == 0 {
        return (s, here);
    }
    let above = curve[s - 1].arcs;
    if above.abs_diff(arcs) < here.abs_diff(arcs) {
        (s - 1, above)
    } else {
        (s, here)
    }
}

/// The step plot of a curve drawn as log10 points (feature size, arcs):
/// from each level, horizontally to the next level's feature size, then
/// vertically to its arcs.
fn step_plot(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out = Vec::with_capacity(points.len() * 2);
    for (i, &p) in points.iter().enumerate() {
        if i > 0 {
            let prev = points[i - 1];
            if prev[1] != p[1] && prev[0] != p[0] {
                out.push([p[0], prev[1]]);
            }
        }
        out.push(p);
    }
    out
}

impl CurvePanel {
    /// Moves the level to step `step` of `sim` over the next frames (the
    /// contour list's "show its arc").
    pub fn go_to_step(&mut self, step: usize, sim: &std::sync::Arc<Simplification>) {
        self.target = Some((step, std::sync::Arc::as_ptr(sim) as usize));
        self.arcs_note = None;
    }

    /// Moves `level` towards step `target` by at most `steps_per_frame`
    /// steps, asking for another frame until it is there.
    fn approach(&mut self, ui: &egui::Ui, level: &mut SimplifiedTree, target: usize) {
        let now = level.step();
        let next = if target > now {
            target.min(now + self.steps_per_frame.max(1))
        } else {
            target.max(now.saturating_sub(self.steps_per_frame.max(1)))
        };
        level.set_step(next);
        // Stop there, or where the sequence ends.
        if level.step() == target || level.step() == now {
            self.target = None;
        } else {
            let sim = std::sync::Arc::as_ptr(level.simplification()) as usize;
            self.target = Some((target, sim));
            ui.ctx().request_repaint();
        }
    }

    /// Draws the curve and the level controls; moves `level`. Returns true
    /// when the level changed.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        level: &mut SimplifiedTree,
        curve: &[[f64; 2]],
    ) -> bool {
        let sim = std::sync::Arc::clone(level.simplification());
        let before = level.step();
        // The level still to reach, unless it is of another
        // simplification (another measure or volume arrived meanwhile).
        let pending = match self.target.take() {
            Some((t, of)) if of == std::sync::Arc::as_ptr(&sim) as usize => Some(t),
            _ => None,
        };
        let current = level.feature_size();
        let mut target_fs: Option<f64> = None;
        let mut target_step: Option<usize> = None;

        ui.horizontal(|ui| {
            let mut arcs = level.num_arcs();
            let max_arcs = sim.base_arcs().max(1);
            let r = ui.add(
                egui::Slider::new(&mut arcs, 1..=max_arcs)
                    .logarithmic(true)
                    .show_value(false)
                    .text("arcs shown"),
            );
            if r.changed() {
                target_step = Some(sim.steps_for_arcs(arcs));
                self.arcs_note = None;
            }
            let label = ui.label("arcs:");
            let r = ui
                .add(
                    egui::TextEdit::singleline(&mut self.arcs_text)
                        .id_salt("arc_count")
                        .desired_width(56.0),
                )
                .labelled_by(label.id);
            let escaped = ui.input(|i| i.key_pressed(egui::Key::Escape));
            if r.lost_focus() && !escaped {
                match self.arcs_text.trim().parse::<usize>() {
                    Ok(n) => {
                        let (s, got) = nearest_level(&sim, n);
                        target_step = Some(s);
                        self.arcs_note = (got != n).then_some((n, got));
                    }
                    Err(_) => self.arcs_text = level.num_arcs().to_string(),
                }
            } else if !r.has_focus() {
                self.arcs_text = level.num_arcs().to_string();
            }
            if let Some((asked, got)) = self.arcs_note {
                if got == level.num_arcs() || target_step.is_some() || pending.is_some() {
                    ui.label(format!("no level has {asked} arcs: nearest {got}"));
                } else {
                    self.arcs_note = None;
                }
            }
            ui.label(format!(
                "feature size {}",
                crate::app::format::fmt_value(level.feature_size())
            ));
        });

        let points = step_plot(curve);
        // A level of feature size 0 (the full tree; any level of a label
        // map's zero-cost prunes) sits at the plot's left edge.
        let left = curve.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
        let cur_x = if current > 0.0 {
            current.log10()
        } else if left.is_finite() {
            left
        } else {
            0.0
        };
        let height = ui.available_height().max(60.0);
        let resp = Plot::new("simplification_curve")
            .height(height)
            .allow_drag(false)
            .allow_zoom(false)
            .allow_scroll(false)
            .allow_boxed_zoom(false)
            .allow_double_click_reset(false)
            .show_crosshair(false)
            .x_axis_label("feature size")
            .y_axis_label("arcs")
            .x_axis_formatter(|m, _| decade_label(m))
            .y_axis_formatter(|m, _| decade_label(m))
            .x_grid_spacer(decade_grid)
            .y_grid_spacer(decade_grid)
            .show(ui, |plot_ui| {
                // Not as a band: egui_plot draws a line with several
                // points per pixel column as a filled min-max band, which
                // turns a step plot's vertical drops into a wedge.
                plot_ui.line(
                    Line::new("curve", PlotPoints::from(points))
                        .width(1.5)
                        .allow_band(false),
                );
                let x = cur_x;
                plot_ui.vline(VLine::new("level", x).width(2.0));
                let y = (level.num_arcs().max(1) as f64).log10();
                plot_ui.points(Points::new("current", vec![[x, y]]).radius(4.0));
                let r = plot_ui.response();
                if (r.dragged() || r.clicked())
                    && let Some(p) = plot_ui.pointer_coordinate()
                {
                    target_fs = Some(10f64.powf(p.x));
                }
            });
        self.plot_rect = Some(resp.response.rect);
        if let Some(fs) = target_fs {
            target_step = Some(sim.steps_for_feature_size(fs));
        }
        // One move per frame, towards what was asked last.
        if let Some(t) = target_step.or(pending) {
            self.approach(ui, level, t);
        }
        level.step() != before
    }
}
