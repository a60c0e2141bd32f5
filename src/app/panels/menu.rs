//! The menu bar (File, Help, measure, isovalue, "all contours at h"), the
//! "Open a path" window and the status bar. They edit only what they are
//! handed and return what the user asked for as [`Action`]s; the app
//! carries them out.

use egui::{Key, RichText};

use crate::app::dataset::Dataset;
use crate::app::format::fmt_value;
use crate::app::jobs::Running;
use crate::app::jobs::dialog::DialogKind;
use crate::simplify::{Measure, SimplifiedTree};

/// The controls, as the Help menu shows them.
pub const CONTROLS: &str = "\
Tree: click an arc to see its contour (at the isovalue line when the arc \
spans it, else at the arc's middle); shift-click adds one. Drag a marker \
to move its contour's isovalue: past a node it follows the level set (it \
splits going up through a join, contours that meet merge). Drag the \
dashed line to move the isovalue. Wheel zooms, right or middle drag pans, \
double-click resets.
Curve: drag on it, or the slider, to simplify the tree (log-log: arcs \
against feature size).
3D view: drag rotates, wheel zooms, right or middle drag pans, \
double-click fits the contours (again: the volume); click a surface to \
pick it.
Keys: Ctrl+O opens, Delete removes the active contour, Escape clears. \
Drop a volume file on the window to open it.";

/// What the user asked for from the menu.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Show a file dialog.
    Dialog(DialogKind),
    /// Open this file or synthetic spec.
    Open(String),
    /// Rank the leaves by another measure.
    SetMeasure(Measure),
    /// Cancel the pipeline job.
    CancelJob,
}

/// The menu's own state: the "Open a path" window.
#[derive(Default)]
pub struct Menu {
    path_window: bool,
    path_input: String,
    /// Where the "all contours at h" checkbox was drawn (scripts).
    pub all_checkbox: Option<egui::Rect>,
}

impl Menu {
    /// The menu bar; edits the global isovalue and the "all contours"
    /// switch.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        measure: Measure,
        dataset: Option<&Dataset>,
        global_h: &mut f64,
        show_all: &mut bool,
    ) -> Vec<Action> {
        let mut actions = Vec::new();
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("Open…  (Ctrl+O)").clicked() {
                    actions.push(Action::Dialog(DialogKind::Open));
                }
                if ui.button("Open the built-in dataset").clicked() {
                    actions.push(Action::Open("synthetic".into()));
                }
                // Without a desktop portal or GTK the dialog cannot show:
                // a typed path always works.
                if ui.button("Open a path…").clicked() {
                    self.path_window = true;
                }
                ui.separator();
                if ui.button("Export contours (PLY/OBJ/STL)…").clicked() {
                    actions.push(Action::Dialog(DialogKind::ExportContours));
                }
                if ui.button("Save 3D view as PNG…").clicked() {
                    actions.push(Action::Dialog(DialogKind::Screenshot));
                }
                if ui.button("Export tree as JSON…").clicked() {
                    actions.push(Action::Dialog(DialogKind::TreeJson));
                }
                ui.separator();
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("Help", |ui| {
                ui.label(CONTROLS);
            });
            ui.separator();
            let mut chosen = measure;
            egui::ComboBox::from_label("measure")
                .selected_text(chosen.name())
                .show_ui(ui, |ui| {
                    for m in Measure::ALL {
                        ui.selectable_value(&mut chosen, m, m.name());
                    }
                });
            if chosen != measure {
                actions.push(Action::SetMeasure(chosen));
            }
            ui.separator();
            if let Some(ds) = dataset {
                let (lo, hi) = ds.range;
                ui.add(
                    egui::Slider::new(global_h, lo..=hi)
                        .text("isovalue")
                        .custom_formatter(|v, _| fmt_value(v)),
                );
                let r = ui.checkbox(show_all, "all contours at h");
                self.all_checkbox = Some(r.rect);
            }
        });
        actions
    }

    /// The "Open a path" window, when open.
    pub fn path_window(&mut self, ctx: &egui::Context) -> Option<Action> {
        if !self.path_window {
            return None;
        }
        let mut open = true;
        let mut go = false;
        egui::Window::new("Open a volume")
            .open(&mut open)
            .collapsible(false)
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    let label = ui.label("Path:");
                    let r = ui
                        .add(
                            egui::TextEdit::singleline(&mut self.path_input)
                                .hint_text("file, folder or synthetic:N")
                                .desired_width(320.0),
                        )
                        .labelled_by(label.id);
                    go |= r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
                });
                go |= ui.button("Open path").clicked();
            });
        let mut action = None;
        if go && !self.path_input.trim().is_empty() {
            action = Some(Action::Open(self.path_input.trim().to_string()));
            open = false;
        }
        self.path_window = open;
        action
    }
}

/// What the status bar reports.
pub struct Status<'a> {
    /// The pipeline job in flight.
    pub running: Option<&'a Running>,
    /// The dataset and level shown.
    pub shown: Option<(&'a Dataset, &'a SimplifiedTree)>,
    /// UI time of the last frame, ms.
    pub ui_ms: f64,
    /// Time of the last 3D render, ms.
    pub render_ms: f64,
    /// Contours being extracted.
    pub extracting: usize,
    /// "All contours at h": (on, extracting, meshes shown, ms).
    pub all: (bool, bool, usize, f64),
}

/// The status bar: job progress (with Cancel), the dataset, timings.
pub fn status_bar(ui: &mut egui::Ui, s: &Status<'_>) -> Option<Action> {
    let mut action = None;
    ui.horizontal_wrapped(|ui| {
        if let Some(r) = s.running {
            let (stage, f) = r.progress.get();
            ui.add(egui::ProgressBar::new(f).desired_width(220.0).text(format!(
                "{}: {stage} {:.0}%",
                r.what,
                100.0 * f
            )));
            ui.label(format!("{:.1} s", r.started.elapsed().as_secs_f64()));
            if ui.button("Cancel").clicked() {
                action = Some(Action::CancelJob);
            }
            ui.separator();
        }
        match s.shown {
            Some((ds, level)) => {
                let [x, y, z] = ds.field.dims();
                let (lo, hi) = ds.range;
                let t = ds.times;
                ui.label(RichText::new(&ds.name).strong());
                ui.label(format!(
                    "{x}×{y}×{z} {}  values {} .. {}",
                    ds.field.values().type_name(),
                    fmt_value(lo),
                    fmt_value(hi)
                ));
                ui.separator();
                ui.label(format!(
                    "superarcs {}  collapsed {}  shown {}",
                    ds.tree.arcs().len(),
                    ds.sim.base_arcs(),
                    level.num_arcs()
                ));
                ui.separator();
                ui.label(format!(
                    "read {:.2} s  tree {:.2} s  simplify {:.2} s",
                    t.load.as_secs_f64(),
                    t.tree.as_secs_f64(),
                    (t.simplify + t.layout).as_secs_f64()
                ));
                ui.separator();
                ui.label(format!("ui {:.1} ms  3D {:.1} ms", s.ui_ms, s.render_ms));
                if s.extracting > 0 {
                    ui.spinner();
                    ui.label(format!("extracting {} contour(s)", s.extracting));
                }
                let (on, extracting, n, ms) = s.all;
                if extracting {
                    ui.spinner();
                    ui.label("extracting all contours at h…");
                } else if on {
                    ui.label(format!("{n} contours at h ({ms:.0} ms)"));
                }
            }
            None => {
                if s.running.is_none() {
                    ui.label("no dataset: File > Open (Ctrl+O) or drop a file");
                }
            }
        }
    });
    action
}
