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

fn decade_label(mark: GridMark) -> String {
    let v = 10f64.powf(mark.value);
    if (mark.value - mark.value.round()).abs() < 1e-6 {
        if (-3.0..=5.0).contains(&mark.value) {
            super::tree_panel::fmt_value(v)
        } else {
            format!("1e{}", mark.value.round() as i64)
        }
    } else {
        String::new()
    }
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
            .x_grid_spacer(egui_plot::log_grid_spacer(10))
            .y_grid_spacer(egui_plot::log_grid_spacer(10))
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
