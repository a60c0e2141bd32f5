//! The slice panel: context for the contours. Three orthogonal slices of
//! the volume (its grey values, with each shown contour's cross-section
//! drawn in its colour), movable by their sliders, shown here side by
//! side and as opaque quads in the 3D view; and a clipping plane across
//! one axis that cuts every contour in the 3D view (and in picking).
//!
//! Slices and the clip are view state, like the camera: they are saved
//! in sessions but are not steps of undo (moving a slice does not change
//! the scene the user composed).
//!
//! The images are made on the UI thread, only when something they show
//! changes: a slice's grey values are read once per position (a few
//! milliseconds even for 256³), a contour's cross-section once per
//! (mesh version, slice position) ([`axis_section`], in parallel for big
//! meshes), then composed ([`slice_image`]).

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::Arc;

use egui::{Color32, RichText};

use crate::contour::ContourMesh;
use crate::contour::section::axis_section;
use crate::field::ScalarField;
use crate::field::slice::{Slice, slice_axes};
use crate::render::overlay::{Section, slice_image};
use crate::render::{ClipPlane, SliceQuad};

/// A cross-section: line segments in the slice's plane.
type Segments = Vec<[[f32; 2]; 2]>;

/// The axes' names.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// Which slices are shown, and where.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SliceSettings {
    /// Shown, per axis.
    pub on: [bool; 3],
    /// Grid index along each axis.
    pub index: [usize; 3],
}

/// The clipping plane: `p[axis] = at` of the volume's box, cutting what
/// lies above it (`keep_below`) or below it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipSettings {
    /// Cutting at all.
    pub on: bool,
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// Where, as a fraction of the box along `axis` (0..=1).
    pub at: f32,
    /// Keep what lies below `at` (else above).
    pub keep_below: bool,
}

impl Default for ClipSettings {
    fn default() -> Self {
        ClipSettings {
            on: false,
            axis: 1,
            at: 0.5,
            keep_below: false,
        }
    }
}

/// A contour whose cross-sections the slices show.
#[derive(Clone)]
pub struct SectionSource {
    /// Names the contour (with `version`, the cache key).
    pub id: u64,
    /// Bumped when the mesh changes.
    pub version: u64,
    /// The mesh.
    pub mesh: Arc<ContourMesh>,
    /// sRGB.
    pub colour: [u8; 3],
}

/// A slice's image, made for one state of what it shows.
struct Built {
    key: u64,
    image: Arc<image::RgbaImage>,
    quad: SliceQuad,
    /// Bumped per rebuild (the 3D view re-uploads on change).
    version: u64,
    texture: Option<(u64, egui::TextureHandle)>,
}

/// The slice panel's state.
pub struct SlicePanel {
    /// The slices.
    pub slices: SliceSettings,
    /// The clipping plane.
    pub clip: ClipSettings,
    /// The panel is shown (under the 3D view).
    pub open: bool,
    field: Option<Arc<ScalarField>>,
    grey: HashMap<(usize, usize), Arc<Slice>>,
    sections: HashMap<(u64, u64, usize, usize), Arc<Segments>>,
    built: [Option<Built>; 3],
    next_version: u64,
    /// Milliseconds the last rebuild of the images took.
    pub build_ms: f64,
    /// Where each contour's label goes (none: all of it is cut away), by
    /// (contour, mesh version, clipping plane).
    pub(crate) label_anchors: HashMap<(u64, u64, u64), Option<[f32; 3]>>,
}

impl Default for SlicePanel {
    fn default() -> Self {
        SlicePanel {
            slices: SliceSettings {
                on: [false; 3],
                index: [0; 3],
            },
            clip: ClipSettings::default(),
            open: false,
            field: None,
            grey: HashMap::new(),
            sections: HashMap::new(),
            built: [None, None, None],
            next_version: 1,
            build_ms: 0.0,
            label_anchors: HashMap::new(),
        }
    }
}

impl SlicePanel {
    /// Shows `field` from now on: a new volume puts the slices in its
    /// middle and forgets the images.
    pub fn set_field(&mut self, field: &Arc<ScalarField>) {
        if self.field.as_ref().is_some_and(|f| Arc::ptr_eq(f, field)) {
            return;
        }
        let dims = field.dims();
        self.slices.index = std::array::from_fn(|a| dims[a] / 2);
        self.field = Some(Arc::clone(field));
        self.grey.clear();
        self.sections.clear();
        self.built = [None, None, None];
    }

    /// The volume's box in the contours' coordinates.
    fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        self.field
            .as_ref()
            .map(|f| crate::render::grid_bounds(f.dims(), f.spacing()))
    }

    /// The clipping plane in world coordinates, when on.
    pub fn clip_plane(&self) -> Option<ClipPlane> {
        let (lo, hi) = self.bounds()?;
        let c = &self.clip;
        if !c.on {
            return None;
        }
        let a = c.axis.min(2);
        let at = lo[a] + c.at.clamp(0.0, 1.0) * (hi[a] - lo[a]);
        Some(ClipPlane::axis(a, at, c.keep_below))
    }

    /// Rebuilds the images whose content changed: the slice moved, or a
    /// contour shown on it changed (mesh, colour, visibility: pass only
    /// the visible ones).
    pub fn update(&mut self, sources: &[SectionSource]) {
        let Some(field) = self.field.clone() else {
            return;
        };
        let t = std::time::Instant::now();
        let mut rebuilt = false;
        let dims = field.dims();
        let spacing = field.spacing();
        #[allow(clippy::needless_range_loop)] // axis indexes four arrays
        for axis in 0..3 {
            if !self.slices.on[axis] {
                self.built[axis] = None;
                continue;
            }
            let index = self.slices.index[axis].min(dims[axis].saturating_sub(1));
            self.slices.index[axis] = index;
            let mut h = std::hash::DefaultHasher::new();
            index.hash(&mut h);
            for s in sources {
                (s.id, s.version, s.colour).hash(&mut h);
            }
            let key = h.finish();
            if self.built[axis].as_ref().is_some_and(|b| b.key == key) {
                continue;
            }
            rebuilt = true;
            let grey = Arc::clone(
                self.grey
                    .entry((axis, index))
                    .or_insert_with(|| Arc::new(Slice::of(&field, axis, index))),
            );
            let at = grey.position(spacing);
            let segments: Vec<(Arc<Segments>, [u8; 3])> = sources
                .iter()
                .map(|s| {
                    let segs = self
                        .sections
                        .entry((s.id, s.version, axis, index))
                        .or_insert_with(|| {
                            Arc::new(axis_section(&s.mesh.positions, &s.mesh.indices, axis, at))
                        });
                    (Arc::clone(segs), s.colour)
                })
                .collect();
            let sections: Vec<Section<'_>> = segments
                .iter()
                .map(|(s, c)| Section {
                    segments: s,
                    colour: *c,
                })
                .collect();
            let longest = grey.width.max(grey.height).max(1);
            let upscale = (512usize.div_ceil(longest)).clamp(1, 4) as u32;
            let image = Arc::new(slice_image(
                &grey,
                spacing,
                upscale,
                &sections,
                (upscale as f32).max(2.0),
            ));
            let quad = SliceQuad {
                corners: grey.corners(spacing),
                image: Arc::clone(&image),
            };
            let version = self.next_version;
            self.next_version += 1;
            let texture = self.built[axis].take().and_then(|b| b.texture);
            self.built[axis] = Some(Built {
                key,
                image,
                quad,
                version,
                texture,
            });
        }
        // Forget the sections of meshes and positions no longer shown.
        if self.sections.len() > 64 {
            let live: std::collections::HashSet<(u64, u64)> =
                sources.iter().map(|s| (s.id, s.version)).collect();
            let index = self.slices.index;
            self.sections
                .retain(|k, _| live.contains(&(k.0, k.1)) && index[k.2] == k.3);
        }
        if self.grey.len() > 48 {
            let index = self.slices.index;
            self.grey.retain(|k, _| index[k.0] == k.1);
        }
        if rebuilt {
            self.build_ms = t.elapsed().as_secs_f64() * 1e3;
        }
    }

    /// The slices to draw in the 3D view: per axis, the image's version
    /// and its quad.
    pub fn quads(&self) -> [Option<(u64, SliceQuad)>; 3] {
        std::array::from_fn(|a| self.built[a].as_ref().map(|b| (b.version, b.quad.clone())))
    }

    /// The image of the slice along `axis`, when shown (tests).
    pub fn image(&self, axis: usize) -> Option<Arc<image::RgbaImage>> {
        self.built.get(axis)?.as_ref().map(|b| Arc::clone(&b.image))
    }

    /// The panel: the controls, then the slices side by side.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let Some(field) = self.field.clone() else {
            ui.label("No volume.");
            return;
        };
        let dims = field.dims();
        ui.horizontal_top(|ui| {
            ui.vertical(|ui| {
                ui.set_width(250.0);
                ui.label(RichText::new("Slices").strong());
                for a in 0..3 {
                    ui.horizontal(|ui| {
                        ui.checkbox(&mut self.slices.on[a], AXES[a]);
                        let max = dims[a].saturating_sub(1);
                        ui.add_enabled(
                            self.slices.on[a],
                            egui::Slider::new(&mut self.slices.index[a], 0..=max)
                                .text(format!("{} slice", AXES[a])),
                        );
                    });
                }
                ui.separator();
                ui.label(RichText::new("Clipping plane").strong());
                ui.horizontal(|ui| {
                    ui.checkbox(&mut self.clip.on, "cut");
                    egui::ComboBox::from_id_salt("clip axis")
                        .width(44.0)
                        .selected_text(AXES[self.clip.axis.min(2)])
                        .show_ui(ui, |ui| {
                            for (a, name) in AXES.iter().enumerate() {
                                ui.selectable_value(&mut self.clip.axis, a, *name);
                            }
                        });
                    ui.selectable_value(&mut self.clip.keep_below, true, "keep below");
                    ui.selectable_value(&mut self.clip.keep_below, false, "keep above");
                });
                ui.add_enabled(
                    self.clip.on,
                    egui::Slider::new(&mut self.clip.at, 0.0..=1.0)
                        .text("clip at")
                        .fixed_decimals(2),
                );
            });
            ui.separator();
            let shown: Vec<usize> = (0..3).filter(|&a| self.built[a].is_some()).collect();
            if shown.is_empty() {
                ui.label(
                    RichText::new(
                        "Tick a slice to see the volume's grey values there, each shown \
                         contour's cross-section in its colour.",
                    )
                    .weak(),
                );
                return;
            }
            let avail = ui.available_size();
            let h = (avail.y - 20.0).max(60.0);
            let each_w = (avail.x / shown.len() as f32 - 8.0).max(60.0);
            let spacing = field.spacing();
            for a in shown {
                let Some(b) = &mut self.built[a] else {
                    continue;
                };
                let tex = match &mut b.texture {
                    Some((v, t)) if *v == b.version => t.clone(),
                    slot => {
                        let img = &b.image;
                        let colour = egui::ColorImage::from_rgba_unmultiplied(
                            [img.width() as usize, img.height() as usize],
                            img.as_raw(),
                        );
                        let t = match slot.take() {
                            Some((_, mut t)) => {
                                t.set(colour, egui::TextureOptions::LINEAR);
                                t
                            }
                            None => ui.ctx().load_texture(
                                format!("slice {}", AXES[a]),
                                colour,
                                egui::TextureOptions::LINEAR,
                            ),
                        };
                        *slot = Some((b.version, t.clone()));
                        t
                    }
                };
                // The slice's own aspect (world units).
                let (u, v) = slice_axes(a);
                let wu = (dims[u].saturating_sub(1).max(1) as f64 * spacing[u]) as f32;
                let wv = (dims[v].saturating_sub(1).max(1) as f64 * spacing[v]) as f32;
                let scale = (each_w / wu).min(h / wv);
                let size = egui::vec2(wu * scale, wv * scale);
                ui.vertical(|ui| {
                    ui.label(
                        RichText::new(format!(
                            "{} = {}  ({} up, {} right)",
                            AXES[a], self.slices.index[a], AXES[v], AXES[u]
                        ))
                        .small(),
                    );
                    ui.add(egui::Image::new((tex.id(), size)))
                        .on_hover_text(format!("slice {} = {}", AXES[a], self.slices.index[a]));
                });
            }
        });
    }
}

/// sRGB bytes of a colour (no alpha).
pub fn rgb(c: Color32) -> [u8; 3] {
    [c.r(), c.g(), c.b()]
}
