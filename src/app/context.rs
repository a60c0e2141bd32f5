//! Context and annotations in the 3D view, wired once per frame: the
//! slice panel's slices, clipping plane and cut-away box
//! ([`panels::slices`]), the
//! contours' names as labels, the legend of the visible contours and the
//! axis triad ([`ViewContext`]). All of it is view state: the View menu's
//! switches, the slices and the clip are saved in sessions but are not
//! steps of undo, like the camera.
//!
//! [`panels::slices`]: super::panels::slices

use std::sync::Arc;

use super::FlexisoApp;
use super::panels::menu::ViewOptions;
use super::panels::slices::{SectionSource, SlicePanel, rgb};
use super::panels::view3d::{Label, ViewContext};
use super::selection::Contour;
use crate::render::overlay::LegendEntry;
use crate::render::{ClipPlane, CutBox, ViewPreset, label_anchor};

/// What a contour is called in the legend and its label: its name, or
/// "contour N" without one.
pub fn display_name(c: &Contour) -> String {
    if c.name.trim().is_empty() {
        format!("contour {}", c.id)
    } else {
        c.name.clone()
    }
}

/// Names a clipping plane and a cut-away box in a cache key.
fn clip_key(clip: Option<ClipPlane>, cut: Option<CutBox>) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::hash::DefaultHasher::new();
    if let Some(c) = clip {
        for x in c.normal.iter().chain([&c.offset]) {
            x.to_bits().hash(&mut h);
        }
    }
    if let Some(b) = cut {
        1u8.hash(&mut h);
        for x in b.lo.iter().chain(&b.hi) {
            x.to_bits().hash(&mut h);
        }
    }
    h.finish()
}

impl FlexisoApp {
    /// Hands the 3D view this frame's slices, clip and annotations,
    /// rebuilding slice images whose content changed.
    pub(super) fn update_context(&mut self) {
        let Some(ds) = &self.dataset else {
            self.view3d.context = ViewContext::default();
            return;
        };
        let space = ds.field.geometry().space;
        self.slices.set_field(&ds.field);
        let shown: Vec<&Contour> = self
            .selection
            .contours
            .iter()
            .filter(|c| self.selection.shown(c) && c.mesh.is_some())
            .collect();
        let sources: Vec<SectionSource> = shown
            .iter()
            .filter_map(|c| {
                Some(SectionSource {
                    id: c.id.0,
                    version: c.version,
                    mesh: Arc::clone(c.mesh.as_ref()?),
                    colour: rgb(c.colour),
                })
            })
            .collect();
        self.slices.update(&sources);
        let view = self.menu.view;
        let clip = self.slices.clip_plane();
        let cut_box = self.slices.cut_box();
        let labels = if view.labels {
            shown
                .iter()
                .filter_map(|c| {
                    let key = (c.id.0, c.version, clip_key(clip, cut_box));
                    let anchor = match self.slices.label_anchors.get(&key) {
                        Some(a) => (*a)?,
                        None => {
                            let a = label_anchor(&c.mesh.as_ref()?.positions, clip, cut_box);
                            self.slices.label_anchors.insert(key, a);
                            a?
                        }
                    };
                    Some(Label {
                        text: display_name(c),
                        colour: c.colour,
                        anchor,
                    })
                })
                .collect()
        } else {
            Vec::new()
        };
        if self.slices.label_anchors.len() > 4 * shown.len() + 16 {
            let live: Vec<(u64, u64)> = shown.iter().map(|c| (c.id.0, c.version)).collect();
            self.slices
                .label_anchors
                .retain(|k, _| live.contains(&(k.0, k.1)));
        }
        self.view3d.context = ViewContext {
            slices: self.slices.quads(),
            clip,
            cut_box,
            labels,
            legend: if view.legend {
                self.legend_entries()
            } else {
                Vec::new()
            },
            triad: view.triad,
            space,
        };
    }

    /// The legend of the visible selected contours, in the order they
    /// were picked (the 3D view's and the PNG export's).
    pub fn legend_entries(&self) -> Vec<LegendEntry> {
        self.selection
            .contours
            .iter()
            .filter(|c| self.selection.shown(c))
            .map(|c| LegendEntry {
                name: display_name(c),
                colour: rgb(c.colour),
            })
            .collect()
    }

    /// The slice panel's state (its slices and clipping plane), to change
    /// as its controls do (tests, scripts).
    pub fn slices_mut(&mut self) -> &mut SlicePanel {
        &mut self.slices
    }

    /// The slice panel.
    pub fn slices(&self) -> &SlicePanel {
        &self.slices
    }

    /// Blocks until the slices' images are rebuilt (tests, scripts).
    pub fn wait_for_slices(&mut self) {
        self.slices.wait();
    }

    /// The View menu's switches, to change (tests, scripts).
    pub fn view_options_mut(&mut self) -> &mut ViewOptions {
        &mut self.menu.view
    }

    /// The View menu's switches.
    pub fn view_options(&self) -> ViewOptions {
        self.menu.view
    }

    /// Looks along a standard axis, as the View menu does.
    pub fn set_view_preset(&mut self, preset: ViewPreset) {
        self.view3d.set_preset(preset);
    }

    /// The slice panel under the 3D view, when open.
    pub(super) fn slice_panel(&mut self, ui: &mut egui::Ui) {
        if !self.menu.view.slices_panel || self.dataset.is_none() {
            return;
        }
        egui::Panel::bottom("slices")
            .resizable(true)
            .default_size(230.0)
            .min_size(120.0)
            .show(ui, |ui| self.slices.ui(ui));
    }
}
