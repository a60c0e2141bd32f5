//! The simplification curve (paper §5): arcs left against feature size,
//! log-log, with the current level as a vertical line. Dragging on the plot
//! (or the slider below it) moves the level; the tree panel follows at once
//! (a level change replays only the steps in between).

use egui_plot::{GridMark, Line, Plot, PlotPoints, Points, VLine};

use crate::simplify::SimplifiedTree;

/// The curve panel's state.
#[derive(Default)]
pub struct CurvePanel {
    /// The plot's screen rect in the last frame (tests drag on it).
    pub plot_rect: Option<egui::Rect>,
    /// The curve in log10 coordinates (feature size, arcs), cached per
    /// simplification.
    points: Vec<[f64; 2]>,
    key: usize,
}

/// Labels the decades of a log10 axis: 0.01 0.1 1 10 100 1000, then 1e4.
fn decade_label(mark: GridMark) -> String {
    let n = mark.value.round();
    if (mark.value - n).abs() > 1e-6 {
        return String::new();
    }
    if (-2.0..=3.0).contains(&n) {
        super::tree_panel::fmt_value(10f64.powf(n))
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

impl CurvePanel {
    /// Draws the curve and the level controls; moves `level`. Returns true
    /// when the level changed.
    pub fn ui(&mut self, ui: &mut egui::Ui, level: &mut SimplifiedTree) -> bool {
        let sim = std::sync::Arc::clone(level.simplification());
        let key = std::sync::Arc::as_ptr(&sim) as usize;
        if key != self.key || self.points.is_empty() {
            self.key = key;
            self.points = sim
                .curve()
                .iter()
                .filter(|p| p.feature_size > 0.0 && p.arcs > 0)
                .map(|p| [p.feature_size.log10(), (p.arcs as f64).log10()])
                .collect();
        }
        let before = level.step();
        let current = level.feature_size();
        let mut target_fs: Option<f64> = None;

        ui.horizontal(|ui| {
            let mut arcs = level.num_arcs();
            let max_arcs = sim.base_arcs().max(1);
            let r = ui.add(
                egui::Slider::new(&mut arcs, 1..=max_arcs)
                    .logarithmic(true)
                    .text("arcs shown"),
            );
            if r.changed() {
                level.set_level(arcs);
            }
            ui.label(format!(
                "feature size {}",
                super::tree_panel::fmt_value(level.feature_size())
            ));
        });

        let points = self.points.clone();
        let cur_x = if current > 0.0 {
            Some(current.log10())
        } else {
            None
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
                plot_ui.line(Line::new("curve", PlotPoints::from(points.clone())).width(1.5));
                if let Some(x) = cur_x {
                    plot_ui.vline(VLine::new("level", x).width(2.0));
                    let y = (level.num_arcs().max(1) as f64).log10();
                    plot_ui.points(Points::new("current", vec![[x, y]]).radius(4.0));
                }
                let r = plot_ui.response();
                if (r.dragged() || r.clicked())
                    && let Some(p) = plot_ui.pointer_coordinate()
                {
                    target_fs = Some(10f64.powf(p.x));
                }
            });
        self.plot_rect = Some(resp.response.rect);
        if let Some(fs) = target_fs {
            level.set_feature_size(fs);
        }
        level.step() != before
    }
}
