//! The list of selected contours: colour, name, visibility, isolation,
//! removal, and each contour's measurements (triangles, area, volume, genus) as
//! they arrive from the extraction jobs. A contour with no live arc at the
//! shown level (its branch pruned and no arc left where it was absorbed)
//! is listed as hidden by simplification: its marker is not drawn until a
//! finer level shows its arc again. A "show its arc" button on such a
//! contour (and on one whose marker sits on the arc that absorbed it) is
//! the way back: it moves the level to the coarsest one where the
//! contour's own arc is shown.

use egui::{Color32, RichText};

use crate::app::format::fmt_value;
use crate::app::selection::Selection;
use crate::simplify::SimplifiedTree;
use crate::simplify::branches::Branches;
use crate::tree::ContourTree;

/// The note on a contour the simplification hides.
pub const HIDDEN: &str = "hidden by simplification";

/// The label of the way back to a hidden contour's arc.
pub const SHOW_ARC: &str = "show its arc";

/// The coarsest level (steps) at which the arc of original superarc `s`
/// is shown: the step that prunes its branch (None when it is never
/// pruned, or has zero height).
pub fn coarsest_step_showing(
    level: &SimplifiedTree,
    branches: &Branches,
    s: crate::tree::ArcId,
) -> Option<usize> {
    let b = branches.of_superarc(level.simplification(), s)?;
    ((b.0 as usize) < branches.steps()).then_some(b.0 as usize)
}

/// Draws the list; edits the selection (colour, visibility, isolation,
/// removal, the active contour); `level` tells which contours the
/// simplification hides. Returns the step to move the level to when a
/// "show its arc" button was clicked.
pub fn ui(
    ui: &mut egui::Ui,
    selection: &mut Selection,
    tree: Option<&ContourTree>,
    level: Option<&SimplifiedTree>,
    branches: Option<&Branches>,
) -> Option<usize> {
    ui.heading("Contours");
    if selection.contours.is_empty() {
        ui.label("Click an arc in the tree (shift-click adds), or a surface.");
        ui.label("Drag a marker to move its isovalue.");
        return None;
    }
    let mut go_to = None;
    ui.horizontal(|ui| {
        if ui
            .button("Clear")
            .on_hover_text("Edit > Clear contours")
            .clicked()
        {
            selection.clear();
        }
        if selection.isolated.is_some() && ui.button("Show all").clicked() {
            show_all(selection);
        }
    });
    let mut remove = None;
    let mut isolate = None;
    let mut unisolate = false;
    egui::ScrollArea::vertical().show(ui, |ui| {
        for c in &mut selection.contours {
            let active = selection.active == Some(c.id);
            egui::Frame::group(ui.style())
                .stroke(egui::Stroke::new(
                    if active { 2.0 } else { 1.0 },
                    if active {
                        c.colour
                    } else {
                        Color32::from_gray(70)
                    },
                ))
                .show(ui, |ui| {
                    ui.horizontal(|ui| {
                        super::colour::colour_button(ui, &mut c.colour);
                        let arc = tree.map(|t| {
                            let a = t.arc(c.superarc);
                            format!("{}:{}", t.node(a.upper).vertex, t.node(a.lower).vertex)
                        });
                        if ui
                            .selectable_label(active, format!("#{}  h = {}", c.id, fmt_value(c.h)))
                            .on_hover_text("click: make it the active contour")
                            .on_hover_text(format!(
                                "superarc {} (vertices upper:lower)",
                                arc.unwrap_or_default()
                            ))
                            .clicked()
                        {
                            selection.active = Some(c.id);
                        }
                    });
                    if let Some(l) = level
                        && l.live_arc_of(c.superarc).is_none()
                    {
                        let hidden = l.absorbing_arc_of(c.superarc).is_none();
                        ui.horizontal(|ui| {
                            if hidden {
                                ui.label(RichText::new(HIDDEN).weak()).on_hover_text(
                                    "its branch is pruned at this level: a finer level (more arcs) shows its marker again",
                                );
                            } else {
                                ui.label(RichText::new("on the arc that absorbed it").weak());
                            }
                            if let Some(step) =
                                branches.and_then(|b| coarsest_step_showing(l, b, c.superarc))
                                && ui
                                    .small_button(SHOW_ARC)
                                    .on_hover_text(
                                        "move to the coarsest level where this contour's own arc is shown",
                                    )
                                    .clicked()
                            {
                                go_to = Some(step);
                            }
                        });
                    }
                    ui.add(
                        egui::TextEdit::singleline(&mut c.name)
                            .hint_text("name")
                            .desired_width(f32::INFINITY),
                    );
                    ui.horizontal(|ui| {
                        if ui.checkbox(&mut c.visible, "visible").changed()
                            && c.visible
                            && selection.isolated.is_some_and(|i| i != c.id)
                        {
                            // Another one shown: none is alone any more.
                            unisolate = true;
                        }
                        let iso = selection.isolated == Some(c.id);
                        if ui.selectable_label(iso, "isolate").clicked() {
                            isolate = Some((c.id, !iso));
                        }
                        if ui.button("delete").clicked() {
                            remove = Some(c.id);
                        }
                    });
                    match &c.topology {
                        Some(t) => {
                            ui.label(format!(
                                "{} triangles, area {}",
                                t.triangles,
                                fmt_value(t.area)
                            ));
                            ui.label(format!(
                                "{}  genus {}{}",
                                if t.is_closed() {
                                    format!("volume {}", fmt_value(t.volume))
                                } else {
                                    format!(
                                        "open ({} boundary loop{})",
                                        t.boundary_loops,
                                        if t.boundary_loops == 1 { "" } else { "s" }
                                    )
                                },
                                t.genus(),
                                if t.components > 1 {
                                    format!(", {} components", t.components)
                                } else {
                                    String::new()
                                }
                            ));
                            ui.label(
                                RichText::new(if c.extracting() {
                                    "extracting…".to_string()
                                } else {
                                    format!("extracted in {}", fmt_ms(c.extract_ms))
                                })
                                .weak(),
                            );
                        }
                        // No spinner while a job runs: a spinner redraws
                        // the window every frame, and without a GPU every
                        // frame rasterises the 3D view on the cores the
                        // job needs (a drag step of a 1 M-triangle contour
                        // took 4 times as long). The job's answer redraws.
                        None if c.extracting() => {
                            ui.label("extracting…");
                        }
                        None if c.mesh.is_some() => {
                            let n = c.mesh.as_ref().map_or(0, |m| m.num_triangles());
                            ui.label(format!("{n} triangles"));
                            // Wrapped: a long line would widen the panel
                            // and shift the 3D view.
                            ui.horizontal_wrapped(|ui| {
                                ui.label(format!(
                                    "measuring… (extracted in {})",
                                    fmt_ms(c.extract_ms)
                                ));
                            });
                        }
                        None => {
                            ui.label("no contour at this value");
                        }
                    }
                });
        }
    });
    if let Some(id) = remove {
        selection.remove(id);
    }
    if unisolate {
        selection.isolated = None;
    }
    match isolate {
        // Isolating shows only this one: every other row's visible box
        // is unticked, and ticked again when isolation ends.
        Some((id, true)) => {
            for c in &mut selection.contours {
                c.visible = c.id == id;
            }
            selection.isolated = Some(id);
        }
        Some((_, false)) => show_all(selection),
        None => {}
    }
    go_to
}

/// Ends isolation: every contour visible again.
fn show_all(selection: &mut Selection) {
    for c in &mut selection.contours {
        c.visible = true;
    }
    selection.isolated = None;
}

/// A duration: milliseconds below a second, else seconds.
fn fmt_ms(ms: f64) -> String {
    if ms >= 1000.0 {
        format!("{:.1} s", ms / 1e3)
    } else {
        format!("{ms:.1} ms")
    }
}
