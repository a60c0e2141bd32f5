//! The menu bar (File, Edit, View, Help, measure, isovalue, "all contours at h"), the
//! "Open a path" window and the status bar. They edit only what they are
//! handed and return what the user asked for as [`Action`]s; the app
//! carries them out.

use egui::{Key, RichText};

use crate::app::dataset::Dataset;
use crate::app::format::fmt_value;
use crate::app::jobs::Running;
use crate::app::jobs::dialog::DialogKind;
use crate::render::ViewPreset;
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
pick it. View > presets look along an axis; View > Slices and clipping \
shows three slices of the volume (grey values, each contour's \
cross-section in its colour) and a plane that cuts every contour.
Keys: Ctrl+O opens, Ctrl+S saves the session, Ctrl+Z undoes, \
Ctrl+Shift+Z or Ctrl+Y redoes, Delete removes the active contour, Escape \
closes a popup or cancels a drag (Edit > Clear contours clears). Drop a \
volume file on the window to open it.";

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
    /// A path typed for what a dialog would have asked.
    Path(DialogKind, String),
    /// Undo the last change to the scene.
    Undo,
    /// Redo the last change undone.
    Redo,
    /// Remove every contour (undoable).
    ClearContours,
    /// Save the session (where it was last saved, else ask where).
    SaveSession,
    /// Close the window (asking first when there are unsaved changes).
    Quit,
    /// Look along a standard axis.
    Preset(ViewPreset),
}

/// What the 3D view shows besides the contours (the View menu's
/// switches).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViewOptions {
    /// The slice panel (slices and clipping) is open.
    pub slices_panel: bool,
    /// Contour names beside the contours.
    pub labels: bool,
    /// The legend of the visible contours (also in PNG exports).
    pub legend: bool,
    /// The axis triad.
    pub triad: bool,
}

impl Default for ViewOptions {
    fn default() -> Self {
        ViewOptions {
            slices_panel: false,
            labels: false,
            legend: true,
            triad: true,
        }
    }
}

/// What the Edit menu offers, set by the app each frame.
#[derive(Clone, Debug, Default)]
pub struct EditState {
    /// What undo would undo.
    pub undo: Option<String>,
    /// What redo would redo.
    pub redo: Option<String>,
    /// Contours selected.
    pub contours: usize,
}

/// The menu's own state: the typed-path window.
#[derive(Default)]
pub struct Menu {
    /// The typed-path window, when open, and what it asks for.
    path_window: Option<DialogKind>,
    path_input: String,
    /// Where the "all contours at h" checkbox was drawn (scripts).
    pub all_checkbox: Option<egui::Rect>,
    /// "All contours at h" shows every component of the level set, not
    /// one per arc of the shown tree.
    pub every_component: bool,
    /// The Edit menu's entries.
    pub edit: EditState,
    /// The View menu's switches.
    pub view: ViewOptions,
    /// File > Export contours also writes a session beside the meshes.
    pub session_with_export: bool,
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
                    self.ask_path(DialogKind::Open);
                }
                ui.separator();
                if ui.button("Open session…").clicked() {
                    actions.push(Action::Dialog(DialogKind::OpenSession));
                }
                if ui.button("Save session  (Ctrl+S)").clicked() {
                    actions.push(Action::SaveSession);
                }
                if ui.button("Save session as…").clicked() {
                    actions.push(Action::Dialog(DialogKind::SaveSession));
                }
                ui.separator();
                if ui.button("Export contours (PLY/OBJ/STL/VTP)…").clicked() {
                    actions.push(Action::Dialog(DialogKind::ExportContours));
                }
                ui.checkbox(
                    &mut self.session_with_export,
                    "…and a session beside the meshes",
                );
                if ui.button("Save 3D view as PNG…").clicked() {
                    actions.push(Action::Dialog(DialogKind::Screenshot));
                }
                if ui.button("Export tree as JSON…").clicked() {
                    actions.push(Action::Dialog(DialogKind::TreeJson));
                }
                ui.separator();
                if ui.button("Quit").clicked() {
                    actions.push(Action::Quit);
                }
            });
            ui.menu_button("Edit", |ui| {
                let e = &self.edit;
                let undo = match &e.undo {
                    Some(l) => format!("Undo {l}  (Ctrl+Z)"),
                    None => "Undo  (Ctrl+Z)".into(),
                };
                if ui
                    .add_enabled(e.undo.is_some(), egui::Button::new(undo))
                    .clicked()
                {
                    actions.push(Action::Undo);
                }
                let redo = match &e.redo {
                    Some(l) => format!("Redo {l}  (Ctrl+Shift+Z)"),
                    None => "Redo  (Ctrl+Shift+Z)".into(),
                };
                if ui
                    .add_enabled(e.redo.is_some(), egui::Button::new(redo))
                    .clicked()
                {
                    actions.push(Action::Redo);
                }
                ui.separator();
                if ui
                    .add_enabled(e.contours > 0, egui::Button::new("Clear contours"))
                    .clicked()
                {
                    actions.push(Action::ClearContours);
                }
            });
            ui.menu_button("View", |ui| {
                for p in ViewPreset::ALL {
                    if ui.button(p.name()).clicked() {
                        actions.push(Action::Preset(p));
                    }
                    if p == ViewPreset::Sagittal {
                        ui.separator();
                    }
                }
                ui.separator();
                let v = &mut self.view;
                ui.checkbox(&mut v.slices_panel, "Slices and clipping");
                ui.checkbox(&mut v.labels, "Contour names in the view");
                ui.checkbox(&mut v.legend, "Legend (also in PNG exports)");
                ui.checkbox(&mut v.triad, "Axis triad");
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
                let r = ui
                    .checkbox(show_all, "all contours at h")
                    .on_hover_text("one contour per arc of the shown tree that spans h");
                self.all_checkbox = Some(r.rect);
                if *show_all {
                    ui.checkbox(&mut self.every_component, "every component")
                        .on_hover_text(
                            "every component of the level set, the simplification's noise included",
                        );
                }
            }
        });
        actions
    }

    /// Opens the typed-path window for `kind` (the menu's "Open a
    /// path…", and every dialog when no system dialog can show).
    pub fn ask_path(&mut self, kind: DialogKind) {
        self.path_window = Some(kind);
    }

    /// What the typed-path window asks for, when open.
    pub fn asking_path(&self) -> Option<DialogKind> {
        self.path_window
    }

    /// The typed-path window, when open.
    pub fn path_window(&mut self, ctx: &egui::Context) -> Option<Action> {
        let kind = self.path_window?;
        let opening = matches!(kind, DialogKind::Open | DialogKind::OpenSession);
        let mut open = true;
        let mut go = false;
        egui::Window::new(kind.title())
            .id(egui::Id::unique("typed path"))
            .open(&mut open)
            .collapsible(false)
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    let label = ui.label("Path:");
                    let r = ui
                        .add(
                            egui::TextEdit::singleline(&mut self.path_input)
                                .hint_text(if kind == DialogKind::Open {
                                    "file, folder or synthetic:N"
                                } else {
                                    "file"
                                })
                                .desired_width(320.0),
                        )
                        .labelled_by(label.id);
                    go |= r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
                });
                if kind != DialogKind::Open {
                    ui.label("No system file dialog here: type the path.");
                }
                go |= ui
                    .button(if opening { "Open path" } else { "Save to path" })
                    .clicked();
            });
        let mut action = None;
        if go && !self.path_input.trim().is_empty() {
            let p = self.path_input.trim().to_string();
            action = Some(match kind {
                DialogKind::Open => Action::Open(p),
                k => Action::Path(k, p),
            });
            open = false;
        }
        if !open {
            self.path_window = None;
        }
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
                // No spinners: one redraws the window every frame, which
                // without a GPU rasterises the 3D view on the cores the
                // extraction needs (see contour_list).
                if s.extracting > 0 {
                    ui.label(format!("extracting {} contour(s)…", s.extracting));
                }
                let (on, extracting, n, ms) = s.all;
                if extracting {
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
