//! The slice panel: context for the contours. Three orthogonal slices of
//! the volume (its grey values, with each shown contour's cross-section
//! drawn in its colour), movable by their sliders, shown here side by
//! side and as opaque quads in the 3D view; a clipping plane across one
//! axis and a cut-away box, each cutting every contour in the 3D view
//! (and in picking).
//!
//! Slices and the clip are view state, like the camera: they are saved
//! in sessions but are not steps of undo (moving a slice does not change
//! the scene the user composed).
//!
//! The images are made only when something they show changes, each
//! slice's in its own job (the newest request queued behind the one in
//! flight, replacing any queued before), never on the UI thread: cutting
//! a head surface of a few million triangles takes tens of milliseconds
//! (measured in the panel: "built in … ms"), more than a frame. A slice's
//! grey values are read once per position, a contour's cross-section once
//! per (mesh version, slice position) ([`axis_section`], in parallel for
//! big meshes) and kept for the next image, then composed
//! ([`slice_image`]). Until a rebuild is done the last image stays.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::Arc;

use egui::{Color32, RichText};

use crate::app::jobs::{Job, JobError, Notify};
use crate::contour::ContourMesh;
use crate::contour::section::axis_section;
use crate::field::ScalarField;
use crate::field::slice::{Slice, slice_axes};
use crate::render::overlay::{Section, slice_image};
use crate::render::{ClipPlane, CutBox, SliceQuad};

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

/// The cut-away box: an axis-aligned box whose inside is cut away from
/// every contour in the 3D view (and in picking), its corners as
/// fractions of the volume's box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutBoxSettings {
    /// Cutting at all.
    pub on: bool,
    /// The low corner, per axis (0..=1).
    pub lo: [f32; 3],
    /// The high corner, per axis (0..=1).
    pub hi: [f32; 3],
}

impl Default for CutBoxSettings {
    fn default() -> Self {
        // One octant: the corner at the box's high x, y and z.
        CutBoxSettings {
            on: false,
            lo: [0.5; 3],
            hi: [1.0; 3],
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
    /// The cut-away box.
    pub cut_box: CutBoxSettings,
    /// The panel is shown (under the 3D view).
    pub open: bool,
    field: Option<Arc<ScalarField>>,
    grey: HashMap<(usize, usize), Arc<Slice>>,
    sections: HashMap<SectionKey, Arc<Segments>>,
    built: [Option<Built>; 3],
    /// The image each slice's job is making (None: the built one is
    /// current).
    requested: [Option<u64>; 3],
    jobs: [Job<Rebuilt>; 3],
    next_version: u64,
    /// Milliseconds the last rebuild of a slice's image took (in its job).
    pub build_ms: f64,
    /// Of which cutting the contours' cross-sections not cached before.
    pub section_ms: f64,
    /// Triangles those cross-sections were cut from.
    pub section_triangles: usize,
    /// Where each contour's label goes (none: all of it is cut away), by
    /// (contour, mesh version, clipping plane).
    pub(crate) label_anchors: HashMap<(u64, u64, u64), Option<[f32; 3]>>,
}

impl Default for SlicePanel {
    fn default() -> Self {
        Self::new(None)
    }
}

impl SlicePanel {
    /// No volume yet; the slices' jobs call `notify` when done.
    pub fn new(notify: Option<Notify>) -> Self {
        SlicePanel {
            slices: SliceSettings {
                on: [false; 3],
                index: [0; 3],
            },
            clip: ClipSettings::default(),
            cut_box: CutBoxSettings::default(),
            open: false,
            field: None,
            grey: HashMap::new(),
            sections: HashMap::new(),
            built: [None, None, None],
            requested: [None; 3],
            jobs: std::array::from_fn(|_| Job::new(notify.clone())),
            next_version: 1,
            build_ms: 0.0,
            section_ms: 0.0,
            section_triangles: 0,
            label_anchors: HashMap::new(),
        }
    }

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
        self.requested = [None; 3];
        for j in &mut self.jobs {
            j.cancel();
        }
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

    /// The cut-away box in world coordinates, when on.
    pub fn cut_box(&self) -> Option<CutBox> {
        let (lo, hi) = self.bounds()?;
        let c = &self.cut_box;
        if !c.on {
            return None;
        }
        let (a, b) = crate::session::SessionCutBox {
            min: c.lo,
            max: c.hi,
        }
        .world(lo, hi);
        Some(CutBox { lo: a, hi: b })
    }

    /// Rebuilds the images whose content changed: the slice moved, or a
    /// contour shown on it changed (mesh, colour, visibility: pass only
    /// the visible ones). The rebuild runs in the slice's job; the image
    /// shown until it is done is the last one built.
    pub fn update(&mut self, sources: &[SectionSource]) {
        let Some(field) = self.field.clone() else {
            return;
        };
        self.poll();
        let dims = field.dims();
        #[allow(clippy::needless_range_loop)] // axis indexes four arrays
        for axis in 0..3 {
            if !self.slices.on[axis] {
                self.built[axis] = None;
                self.jobs[axis].cancel();
                self.requested[axis] = None;
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
            let current = self.requested[axis].or(self.built[axis].as_ref().map(|b| b.key));
            if current == Some(key) {
                continue;
            }
            self.requested[axis] = Some(key);
            let request = Request {
                axis,
                index,
                key,
                field: Arc::clone(&field),
                grey: self.grey.get(&(axis, index)).cloned(),
                sources: sources
                    .iter()
                    .map(|s| {
                        let k = (s.id, s.version, axis, index);
                        (
                            k,
                            Arc::clone(&s.mesh),
                            s.colour,
                            self.sections.get(&k).cloned(),
                        )
                    })
                    .collect(),
            };
            self.jobs[axis].start_latest(format!("slice {}", AXES[axis]), move |p| {
                build(request, &|| p.is_cancelled()).ok_or(JobError::Cancelled)
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
    }

    /// Installs the slices' finished rebuilds; true if one was installed.
    pub fn poll(&mut self) -> bool {
        let mut any = false;
        for axis in 0..3 {
            while let Some(outcome) = self.jobs[axis].poll_take() {
                if let Ok(b) = outcome {
                    self.install(b);
                    any = true;
                }
            }
        }
        any
    }

    /// Blocks until every slice's rebuild (and any queued behind it) is
    /// done, and installs them (tests, scripts).
    pub fn wait(&mut self) {
        for axis in 0..3 {
            while self.jobs[axis].is_running() {
                if !self.jobs[axis].wait() {
                    break;
                }
                if let Some(Ok(b)) = self.jobs[axis].take() {
                    self.install(b);
                }
            }
        }
    }

    /// True while a slice is being rebuilt.
    pub fn rebuilding(&self) -> bool {
        self.jobs.iter().any(|j| j.is_running())
    }

    fn install(&mut self, b: Rebuilt) {
        let axis = b.axis;
        if !self.slices.on[axis]
            || self
                .field
                .as_ref()
                .is_none_or(|f| !Arc::ptr_eq(f, &b.field))
        {
            return;
        }
        self.grey.insert((axis, b.index), b.grey);
        self.sections.extend(b.new_sections);
        if self.requested[axis] == Some(b.key) {
            self.requested[axis] = None;
        }
        self.build_ms = b.ms;
        self.section_ms = b.section_ms;
        self.section_triangles = b.triangles;
        let version = self.next_version;
        self.next_version += 1;
        let texture = self.built[axis].take().and_then(|t| t.texture);
        self.built[axis] = Some(Built {
            key: b.key,
            image: b.image,
            quad: b.quad,
            version,
            texture,
        });
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
            // The controls scroll when the panel is low; the images take
            // the rest of the width.
            ui.vertical(|ui| {
                ui.set_width(250.0);
                egui::ScrollArea::vertical()
                    .id_salt("slice controls")
                    .show(ui, |ui| {
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
                        ui.separator();
                        ui.checkbox(&mut self.cut_box.on, RichText::new("Cut-away box").strong())
                            .on_hover_text(
                                "Cut away what lies inside a box from every contour \
                         (its extent as fractions of the volume's box)",
                            );
                        for (a, name) in AXES.iter().enumerate() {
                            ui.add_enabled_ui(self.cut_box.on, |ui| {
                                ui.horizontal(|ui| {
                                    let l = ui.label(format!("{name} from"));
                                    ui.add(
                                        egui::DragValue::new(&mut self.cut_box.lo[a])
                                            .range(0.0..=1.0)
                                            .speed(0.005)
                                            .fixed_decimals(2),
                                    )
                                    .labelled_by(l.id);
                                    let l = ui.label("to");
                                    ui.add(
                                        egui::DragValue::new(&mut self.cut_box.hi[a])
                                            .range(0.0..=1.0)
                                            .speed(0.005)
                                            .fixed_decimals(2),
                                    )
                                    .labelled_by(l.id);
                                });
                            });
                        }
                        if self.rebuilding() {
                            ui.label(RichText::new("updating the slices…").weak().small());
                        } else if self.built.iter().any(Option::is_some) {
                            ui.label(
                                RichText::new(format!(
                                    "built in {:.0} ms (cross-sections of {} triangles: {:.0} ms)",
                                    self.build_ms, self.section_triangles, self.section_ms
                                ))
                                .weak()
                                .small(),
                            );
                        }
                    });
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

/// Names a cross-section in the cache: (contour, mesh version, axis,
/// grid index).
type SectionKey = (u64, u64, usize, usize);

/// A contour on a slice: its cache key, mesh, colour, and its
/// cross-section when cached.
type ToCut = (SectionKey, Arc<ContourMesh>, [u8; 3], Option<Arc<Segments>>);

/// What a slice's job is given: the slice, and each contour shown on it
/// with its cross-section when cached.
struct Request {
    axis: usize,
    index: usize,
    key: u64,
    field: Arc<ScalarField>,
    grey: Option<Arc<Slice>>,
    sources: Vec<ToCut>,
}

/// A slice's rebuilt image, with what the job read and cut for it (for
/// the caches).
struct Rebuilt {
    axis: usize,
    index: usize,
    key: u64,
    field: Arc<ScalarField>,
    grey: Arc<Slice>,
    new_sections: Vec<(SectionKey, Arc<Segments>)>,
    image: Arc<image::RgbaImage>,
    quad: SliceQuad,
    ms: f64,
    section_ms: f64,
    triangles: usize,
}

/// Makes a slice's image (in its job): the grey values, the missing
/// cross-sections ([`axis_section`]), then the picture ([`slice_image`]).
/// None when `cancelled` says so between contours.
fn build(r: Request, cancelled: &dyn Fn() -> bool) -> Option<Rebuilt> {
    let t = std::time::Instant::now();
    let spacing = r.field.spacing();
    let grey = r
        .grey
        .unwrap_or_else(|| Arc::new(Slice::of(&r.field, r.axis, r.index)));
    let at = grey.position(spacing);
    let mut new_sections = Vec::new();
    let mut segments: Vec<(Arc<Segments>, [u8; 3])> = Vec::with_capacity(r.sources.len());
    let mut section_ms = 0.0;
    let mut triangles = 0;
    for (k, mesh, colour, cached) in r.sources {
        if cancelled() {
            return None;
        }
        let segs = match cached {
            Some(s) => s,
            None => {
                let ts = std::time::Instant::now();
                let s = Arc::new(axis_section(&mesh.positions, &mesh.indices, r.axis, at));
                section_ms += ts.elapsed().as_secs_f64() * 1e3;
                triangles += mesh.indices.len() / 3;
                new_sections.push((k, Arc::clone(&s)));
                s
            }
        };
        segments.push((segs, colour));
    }
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
    Some(Rebuilt {
        axis: r.axis,
        index: r.index,
        key: r.key,
        field: r.field,
        grey,
        new_sections,
        image,
        quad,
        ms: t.elapsed().as_secs_f64() * 1e3,
        section_ms,
        triangles,
    })
}

/// sRGB bytes of a colour (no alpha).
pub fn rgb(c: Color32) -> [u8; 3] {
    [c.r(), c.g(), c.b()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Values;

    fn panel_and_sphere() -> (SlicePanel, SectionSource) {
        let n = 16;
        let field = Arc::new(
            ScalarField::new([n, n, n], Values::F32(vec![0.5; n * n * n])).expect("a field"),
        );
        let (positions, normals, indices) = crate::render::icosphere([7.5; 3], 4.0, 3);
        let mesh = ContourMesh {
            arc: crate::tree::ArcId(0),
            isovalue: 0.5,
            positions,
            normals,
            indices,
            touches_boundary: false,
            ccw_outward: None,
            bounds: None,
            bands: Vec::new(),
        };
        let mut p = SlicePanel::new(None);
        p.set_field(&field);
        p.slices.on = [false, false, true];
        p.slices.index[2] = 7;
        let s = SectionSource {
            id: 1,
            version: 1,
            mesh: Arc::new(mesh),
            colour: [255, 0, 0],
        };
        (p, s)
    }

    fn count(img: &image::RgbaImage, rgb: [u8; 3]) -> usize {
        img.pixels().filter(|p| p.0[..3] == rgb).count()
    }

    #[test]
    fn a_slice_is_rebuilt_in_its_job_and_a_new_colour_reuses_the_cut() {
        let (mut p, mut s) = panel_and_sphere();
        let triangles = s.mesh.indices.len() / 3;
        p.update(std::slice::from_ref(&s));
        // Not on this thread: the image comes once the job is done.
        p.wait();
        let img = p.image(2).expect("built");
        assert!(count(&img, [255, 0, 0]) > 50, "the sphere's section");
        assert_eq!(p.section_triangles, triangles, "the mesh was cut");
        // Only the colour changes: the image again, the cut from the cache.
        s.colour = [0, 0, 255];
        p.update(std::slice::from_ref(&s));
        p.wait();
        let img = p.image(2).expect("built");
        assert_eq!(count(&img, [255, 0, 0]), 0);
        assert!(count(&img, [0, 0, 255]) > 50);
        assert_eq!(p.section_triangles, 0, "nothing cut again");
        // Unchanged: no rebuild at all.
        p.update(std::slice::from_ref(&s));
        assert!(!p.rebuilding());
        // Moved: cut again, while the old image stays until then.
        p.slices.index[2] = 9;
        p.update(std::slice::from_ref(&s));
        assert!(p.image(2).is_some(), "the last image stays meanwhile");
        p.wait();
        assert_eq!(p.section_triangles, triangles);
        // Switched off: no image, a late rebuild is dropped.
        p.slices.index[2] = 3;
        p.update(std::slice::from_ref(&s));
        p.slices.on[2] = false;
        p.update(std::slice::from_ref(&s));
        p.wait();
        assert!(p.image(2).is_none());
    }
}
