//! The 3D view: the contours drawn by [`crate::render::Renderer`] into its
//! own texture, shown as an egui image. Orbit camera: drag rotates, wheel
//! zooms, right or middle drag pans, double-click fits the contours shown
//! (again: the volume). A click
//! on a surface picks it. Meshes, the volume's box, slices and the clip
//! are in the volume's grid frame (index × spacing); the view places them
//! in the file's world ([`View3d::set_placement`], the map
//! [`crate::field::Geometry::to_world`] that exports use), so the camera,
//! the axis triad and picked points are in world coordinates, a rotated
//! volume's box is a parallelepiped, and the clip and slices run along
//! the volume's axes. Meshes are uploaded only when their version
//! changes; styles cost a uniform write; a frame whose camera, size and
//! scene are unchanged is not re-rendered.

use std::collections::HashMap;
use std::sync::Arc;

use egui::{Color32, Sense};

use crate::app::ids::ContourId;
use crate::field::Space;
use crate::render::overlay::LegendEntry;
use crate::render::{
    Camera, ClipPlane, CutBox, EguiTexture, MeshId, PreparedMesh, Renderer, SliceQuad, ViewPreset,
};

/// What a mesh of the scene is, as the explorer names it; the view gives
/// each its own renderer [`MeshId`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SceneKey {
    /// A selected contour.
    Contour(ContourId),
    /// Component `i` of "all contours at h".
    AtH(usize),
    /// The hover preview of an arc's contour (drawn dimmed, never picked).
    Preview,
}

/// One mesh the view should draw.
pub struct SceneMesh {
    /// What it is.
    pub key: SceneKey,
    /// Geometry, ready for the GPU (uploaded when `version` changes).
    pub mesh: Arc<PreparedMesh>,
    /// Bumped when the geometry changes.
    pub version: u64,
    /// Colour.
    pub colour: Color32,
    /// Drawn at all.
    pub visible: bool,
    /// Drawn with the selection rim.
    pub highlighted: bool,
}

/// Bytes of mesh data copied to the GPU per frame at most: 32 MiB, so
/// the 5.36 M-triangle head of colin27 (64 MB as 12-byte vertices and
/// 16-bit index runs) arrives in two frames of copying (the bench counts
/// three calls, the last one finding nothing left) instead of nine. The
/// slowest frame's copy, median / worst over a scripted drag of the head
/// on lavapipe, measured 269 / 391 ms at 32 MiB against 141 / 332 ms at
/// 8 MiB in one run on the 2-core machine under load 16 (`cargo bench
/// --bench contour`): per byte four times cheaper, per frame dearer; to be
/// re-measured quiet. Bigger scenes, like every contour of a brain at one
/// isovalue, arrive over more frames instead of holding one frame long:
/// copying into fresh buffers costs a page fault per 4 KiB besides the
/// copy.
pub const UPLOAD_BUDGET: u64 = 32 << 20;

/// What happened in the view this frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct ViewEvents {
    /// A surface was clicked: what it is; `shift` held.
    pub picked: Option<(SceneKey, bool)>,
    /// The background was clicked.
    pub clicked_empty: bool,
}

/// The 3D view's state.
pub struct View3d {
    renderer: Option<Renderer>,
    /// The orbit camera.
    pub camera: Camera,
    texture: EguiTexture,
    /// Mesh id → uploaded version.
    uploaded: HashMap<MeshId, u64>,
    /// The renderer's id of each scene mesh, and back.
    ids: HashMap<SceneKey, MeshId>,
    keys: HashMap<MeshId, SceneKey>,
    next_id: u64,
    bounds: Option<([f32; 3], [f32; 3])>,
    /// Why there is no view (no wgpu, upload error), shown instead.
    pub problem: Option<String>,
    /// Milliseconds of the last render call (software rendering is slow).
    pub last_render_ms: f64,
    /// Renders done (for tests and the frame log).
    pub renders: u64,
    /// The last double-click fitted the contours (the next fits the box).
    fitted_to_contours: bool,
    /// A box to frame once the view's shape is known (next frame).
    pending_fit: Option<([f32; 3], [f32; 3])>,
    /// Meshes still being copied to the GPU after the last frame.
    pub uploading: bool,
    /// Context and annotations (see [`ViewContext`]).
    pub context: ViewContext,
    /// The slice versions the renderer holds.
    slices_set: [u64; 3],
    /// Where the view was drawn last frame (tests, scripts).
    pub rect: Option<egui::Rect>,
    /// The grid frame in the world (see the module doc).
    placement: glam::Mat4,
    /// The world point of the last pick that hit a surface.
    pub last_pick: Option<[f32; 3]>,
}

/// What the view shows besides the meshes: slices, the clipping plane,
/// labels, the legend and the axis triad. Set by the app each frame;
/// the renderer is told only what changed.
#[derive(Clone, Debug, Default)]
pub struct ViewContext {
    /// Per axis: the image's version and its quad.
    pub slices: [Option<(u64, SliceQuad)>; 3],
    /// The clipping plane.
    pub clip: Option<ClipPlane>,
    /// The cut-away box.
    pub cut_box: Option<CutBox>,
    /// Names drawn beside the contours (empty: none).
    pub labels: Vec<Label>,
    /// The legend of the visible contours (empty: none).
    pub legend: Vec<LegendEntry>,
    /// Draw the axis triad.
    pub triad: bool,
    /// The space world coordinates are given in: the triad names the
    /// anatomical direction of each axis (LPS: x left, y posterior, z
    /// superior; RAS: right, anterior, superior) and the space.
    pub space: Space,
}

impl ViewContext {
    /// Whether the clipping plane and the cut-away box keep `p`.
    pub fn keeps(&self, p: [f32; 3]) -> bool {
        self.clip.is_none_or(|c| c.keeps(p)) && self.cut_box.is_none_or(|b| b.keeps(p))
    }
}

/// What the triad writes at the tips of the world's x, y and z axes: the
/// anatomical direction each points to in `space` (LPS: left, posterior,
/// superior; RAS: right, anterior, superior), or the axis names when the
/// file names no space.
pub fn triad_names(space: Space) -> [&'static str; 3] {
    match space {
        Space::Lps => ["L", "P", "S"],
        Space::Ras => ["R", "A", "S"],
        Space::Unnamed => ["x", "y", "z"],
    }
}

/// A name drawn in the view at a point of its contour.
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    /// The text.
    pub text: String,
    /// Its contour's colour.
    pub colour: Color32,
    /// Where, in the grid frame (as the meshes; placed when drawn).
    pub anchor: [f32; 3],
}

impl Default for View3d {
    fn default() -> Self {
        Self::new()
    }
}

fn rgba(c: Color32) -> [f32; 4] {
    c.to_normalized_gamma_f32()
}

impl View3d {
    /// An empty view.
    pub fn new() -> Self {
        Self {
            renderer: None,
            camera: Camera::default(),
            texture: EguiTexture::new(),
            uploaded: HashMap::new(),
            ids: HashMap::new(),
            keys: HashMap::new(),
            next_id: 0,
            bounds: None,
            problem: None,
            last_render_ms: 0.0,
            renders: 0,
            fitted_to_contours: false,
            pending_fit: None,
            uploading: false,
            context: ViewContext::default(),
            slices_set: [0; 3],
            rect: None,
            placement: glam::Mat4::IDENTITY,
            last_pick: None,
        }
    }

    /// Places the grid frame in the world by the affine map `model` (for
    /// a volume, its [`crate::field::Geometry::affine`]); call before
    /// [`View3d::set_bounds`]. A map that is not invertible is ignored.
    pub fn set_placement(&mut self, model: glam::Mat4) {
        let det = model.determinant();
        if !(model.is_finite() && det.is_finite() && det.abs() > f32::EPSILON) {
            return;
        }
        self.placement = model;
        if let Some(r) = &mut self.renderer {
            r.set_placement(model);
        }
    }

    /// The map from the grid frame to the world in use.
    pub fn placement(&self) -> glam::Mat4 {
        self.placement
    }

    /// The world box around the grid-frame box `[lo, hi]`.
    fn world_box(&self, (lo, hi): ([f32; 3], [f32; 3])) -> ([f32; 3], [f32; 3]) {
        crate::render::placed_box(self.placement, lo, hi)
    }

    /// Looks along a standard axis, fitted to the volume.
    pub fn set_preset(&mut self, preset: ViewPreset) {
        if let Some(b) = self.bounds {
            let (lo, hi) = self.world_box(b);
            self.camera.fit(lo, hi);
        }
        self.camera.set_preset(preset);
    }

    /// Tells the renderer about changed slices and the clip.
    fn sync_context(&mut self) {
        let Some(r) = &mut self.renderer else { return };
        for (slot, s) in self.context.slices.iter().enumerate() {
            let version = s.as_ref().map_or(0, |(v, _)| *v);
            if self.slices_set[slot] != version {
                r.set_slice(slot, s.as_ref().map(|(_, q)| q.clone()));
                self.slices_set[slot] = version;
            }
        }
        r.set_clip(self.context.clip);
        r.set_cut_box(self.context.cut_box);
    }

    /// The labels as a picture of the view `width × height` pixels shows
    /// them (PNG exports): projected by the camera, those whose point the
    /// clipping plane cuts away left out.
    pub fn image_labels(&self, width: u32, height: u32) -> Vec<crate::render::overlay::ImageLabel> {
        let vp = self.camera.view_proj(width as f32 / height.max(1) as f32) * self.placement;
        self.context
            .labels
            .iter()
            .filter(|l| self.context.keeps(l.anchor))
            .filter_map(|l| {
                Some(crate::render::overlay::ImageLabel {
                    text: l.text.clone(),
                    colour: [l.colour.r(), l.colour.g(), l.colour.b()],
                    at: crate::render::overlay::project_to_image(vp, l.anchor, width, height)?,
                })
            })
            .collect()
    }

    /// Labels, legend and triad over the image.
    fn draw_annotations(&self, ui: &egui::Ui, rect: egui::Rect) {
        let painter = ui.painter_at(rect);
        let aspect = rect.width() / rect.height().max(1.0);
        let vp = self.camera.view_proj(aspect) * self.placement;
        let mut placed: Vec<[f32; 4]> = Vec::new();
        for l in &self.context.labels {
            if !self.context.keeps(l.anchor) {
                continue;
            }
            let q = vp * glam::Vec3::from(l.anchor).extend(1.0);
            if q.w <= 0.0 {
                continue;
            }
            let ndc = q.truncate() / q.w;
            let p = egui::pos2(
                rect.left() + (0.5 + 0.5 * ndc.x) * rect.width(),
                rect.top() + (0.5 - 0.5 * ndc.y) * rect.height(),
            );
            let font = egui::FontId::proportional(14.0);
            let galley = painter.layout_no_wrap(l.text.clone(), font, Color32::WHITE);
            let at = p + egui::vec2(8.0, -8.0 - galley.size().y);
            let bg = egui::Rect::from_min_size(at, galley.size()).expand(3.0);
            // Nearby labels would cover each other: one moves up.
            let lift = crate::render::overlay::clear_of(
                &placed,
                [bg.min.x, bg.min.y, bg.max.x, bg.max.y],
                3.0,
            );
            let (at, bg) = (
                at - egui::vec2(0.0, lift),
                bg.translate(egui::vec2(0.0, -lift)),
            );
            placed.push([bg.min.x, bg.min.y, bg.max.x, bg.max.y]);
            painter.line_segment([p, bg.left_bottom()], egui::Stroke::new(1.0, l.colour));
            painter.circle_filled(p, 3.0, l.colour);
            painter.rect_filled(bg, 3.0, Color32::from_black_alpha(170));
            painter.rect_stroke(
                bg,
                3.0,
                egui::Stroke::new(1.0, l.colour),
                egui::StrokeKind::Outside,
            );
            painter.galley(at, galley, Color32::WHITE);
        }
        if !self.context.legend.is_empty() {
            let font = egui::FontId::proportional(14.0);
            let line = 20.0;
            let galleys: Vec<_> = self
                .context
                .legend
                .iter()
                .map(|e| painter.layout_no_wrap(e.name.clone(), font.clone(), Color32::WHITE))
                .collect();
            let text_w = galleys.iter().map(|g| g.size().x).fold(0.0, f32::max);
            let origin = rect.left_top() + egui::vec2(8.0, 8.0);
            let bg = egui::Rect::from_min_size(
                origin,
                egui::vec2(text_w + 36.0, 8.0 + line * galleys.len() as f32),
            );
            painter.rect_filled(bg, 4.0, Color32::from_rgba_unmultiplied(20, 20, 22, 190));
            for (i, (e, g)) in self.context.legend.iter().zip(galleys).enumerate() {
                let top = origin.y + 4.0 + i as f32 * line;
                let [r, gg, b] = e.colour;
                painter.rect_filled(
                    egui::Rect::from_min_size(
                        egui::pos2(origin.x + 6.0, top + 3.0),
                        egui::vec2(14.0, 14.0),
                    ),
                    2.0,
                    Color32::from_rgb(r, gg, b),
                );
                let h = g.size().y;
                painter.galley(
                    egui::pos2(origin.x + 28.0, top + 0.5 * (line - h)),
                    g,
                    Color32::WHITE,
                );
            }
        }
        if self.context.triad {
            let (right, up) = self.camera.screen_axes();
            let forward = up.cross(right);
            let centre = rect.left_bottom() + egui::vec2(44.0, -44.0);
            let len = 30.0;
            let names = triad_names(self.context.space);
            let axes = [
                (glam::Vec3::X, names[0], Color32::from_rgb(230, 80, 70)),
                (glam::Vec3::Y, names[1], Color32::from_rgb(100, 200, 90)),
                (glam::Vec3::Z, names[2], Color32::from_rgb(90, 140, 240)),
            ];
            let mut order: Vec<_> = axes.iter().collect();
            // Farthest first, so the nearest axis is drawn on top.
            order.sort_by(|a, b| a.0.dot(forward).total_cmp(&b.0.dot(forward)).reverse());
            painter.circle_filled(centre, 40.0, Color32::from_black_alpha(90));
            for (axis, name, colour) in order {
                let d = egui::vec2(axis.dot(right), -axis.dot(up));
                let tip = centre + len * d;
                painter.line_segment([centre, tip], egui::Stroke::new(2.5, *colour));
                painter.text(
                    centre + (len + 8.0) * d,
                    egui::Align2::CENTER_CENTER,
                    *name,
                    egui::FontId::proportional(13.0),
                    *colour,
                );
            }
            if self.context.space != Space::Unnamed {
                painter.text(
                    centre + egui::vec2(0.0, 40.0 + 2.0),
                    egui::Align2::CENTER_TOP,
                    self.context.space.name(),
                    egui::FontId::proportional(11.0),
                    Color32::from_gray(200),
                );
            }
        }
    }

    /// Frames the box `[min, max]` (contours' bounds, grid frame) at the
    /// next frame, when the view's width and height are known: the whole
    /// box shows however narrow the view is.
    pub fn fit_to(&mut self, min: [f32; 3], max: [f32; 3]) {
        let (min, max) = self.world_box((min, max));
        self.camera.fit(min, max);
        self.pending_fit = Some((min, max));
        self.fitted_to_contours = true;
    }

    /// Sets the volume's box (grid frame, drawn faint where
    /// [`View3d::set_placement`] puts it) and fits the camera to it.
    pub fn set_bounds(&mut self, min: [f32; 3], max: [f32; 3]) {
        self.bounds = Some((min, max));
        let (wmin, wmax) = self.world_box((min, max));
        self.camera.fit(wmin, wmax);
        self.pending_fit = Some((wmin, wmax));
        if let Some(r) = &mut self.renderer {
            r.set_bounds(min, max);
        }
    }

    /// The scene meshes the renderer holds (tests), sorted.
    pub fn mesh_ids(&self) -> Vec<SceneKey> {
        let mut keys: Vec<SceneKey> = self
            .renderer
            .as_ref()
            .map(|r| r.mesh_ids())
            .unwrap_or_default()
            .iter()
            .filter_map(|id| self.keys.get(id).copied())
            .collect();
        keys.sort();
        keys
    }

    /// The renderer id of scene mesh `key`, made on first use.
    fn mesh_id(&mut self, key: SceneKey) -> MeshId {
        if let Some(&id) = self.ids.get(&key) {
            return id;
        }
        let id = MeshId(self.next_id);
        self.next_id += 1;
        self.ids.insert(key, id);
        self.keys.insert(id, key);
        id
    }

    /// The renderer, once created (tests, screenshots).
    pub fn renderer(&self) -> Option<&Renderer> {
        self.renderer.as_ref()
    }

    /// Draws the view into `ui`'s remaining space.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        rs: Option<&egui_wgpu::RenderState>,
        scene: &[SceneMesh],
    ) -> ViewEvents {
        let mut events = ViewEvents::default();
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        self.rect = Some(rect);
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "3D view"));
        let Some(rs) = rs else {
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "3D view unavailable: no wgpu render state",
                egui::FontId::proportional(14.0),
                Color32::GRAY,
            );
            return events;
        };
        if self.renderer.is_none() {
            let mut r = Renderer::new(&rs.device, Renderer::sample_count_for(&rs.adapter));
            r.set_placement(self.placement);
            if let Some((lo, hi)) = self.bounds {
                r.set_bounds(lo, hi);
            }
            self.renderer = Some(r);
        }

        // Sync meshes: remove the gone, upload the changed, restyle all.
        let wanted: HashMap<SceneKey, &SceneMesh> = scene.iter().map(|m| (m.key, m)).collect();
        let gone: Vec<SceneKey> = self
            .ids
            .keys()
            .filter(|k| !wanted.contains_key(k))
            .copied()
            .collect();
        for key in gone {
            if let Some(id) = self.ids.remove(&key) {
                self.keys.remove(&id);
                self.uploaded.remove(&id);
                if let Some(r) = &mut self.renderer {
                    r.remove_mesh(id);
                }
            }
        }
        for m in scene {
            let id = self.mesh_id(m.key);
            let Some(renderer) = &mut self.renderer else {
                break;
            };
            if self.uploaded.get(&id) != Some(&m.version) {
                match renderer.set_prepared_mesh(&rs.device, id, Arc::clone(&m.mesh)) {
                    Ok(()) => {
                        self.uploaded.insert(id, m.version);
                    }
                    Err(e) => self.problem = Some(e.to_string()),
                }
            }
            renderer.set_style(id, rgba(m.colour), m.visible, m.highlighted);
        }
        self.sync_context();
        let Some(renderer) = &mut self.renderer else {
            return events;
        };
        self.uploading = renderer.upload_pending(&rs.device, &rs.queue, UPLOAD_BUDGET);
        if self.uploading {
            ui.ctx().request_repaint();
        }
        if let Some((lo, hi)) = self.pending_fit.take() {
            fit_in_view(
                &mut self.camera,
                lo,
                hi,
                rect.width() / rect.height().max(1.0),
            );
        }

        // Camera.
        if response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            self.camera.orbit(-0.01 * d.x, 0.01 * d.y);
        }
        if response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
        {
            let d = response.drag_delta();
            self.camera.pan(d.x, d.y, rect.height());
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.camera.zoom((-0.002 * scroll).exp());
            }
        }
        if response.double_clicked() {
            // Fit the contours shown, at their current geometry (the
            // scene's meshes, not what was last uploaded); a second
            // double-click fits the volume.
            let contours = scene_bounds(scene);
            let target = match (contours, self.fitted_to_contours) {
                (Some(b), false) => {
                    self.fitted_to_contours = true;
                    Some(b)
                }
                _ => {
                    self.fitted_to_contours = false;
                    self.bounds
                }
            };
            let placement = self.placement;
            if let Some((lo, hi)) =
                target.map(|(lo, hi)| crate::render::placed_box(placement, lo, hi))
            {
                fit_in_view(
                    &mut self.camera,
                    lo,
                    hi,
                    rect.width() / rect.height().max(1.0),
                );
            }
        } else if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
        {
            let local = p - rect.min;
            match renderer.pick(&self.camera, rect.width(), rect.height(), local.x, local.y) {
                Some((id, at)) => {
                    self.last_pick = Some(at);
                    events.picked = self
                        .keys
                        .get(&id)
                        .filter(|k| **k != SceneKey::Preview)
                        .map(|&k| (k, ui.input(|i| i.modifiers.shift)));
                }
                None => events.clicked_empty = true,
            }
        }

        let px = (rect.size() * ui.pixels_per_point()).round();
        let (w, h) = (px.x.max(1.0) as u32, px.y.max(1.0) as u32);
        if !renderer.is_current(&self.camera, w, h) {
            let t = std::time::Instant::now();
            renderer.render(&rs.device, &rs.queue, &self.camera, w, h);
            self.last_render_ms = t.elapsed().as_secs_f64() * 1e3;
            self.renders += 1;
        }
        let id = self
            .texture
            .update(&mut rs.renderer.write(), &rs.device, renderer);
        if let Some(id) = id {
            ui.painter().image(
                id,
                rect,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                Color32::WHITE,
            );
        }
        self.draw_annotations(ui, rect);
        if scene.is_empty() {
            ui.painter().text(
                rect.center_top() + egui::vec2(0.0, 24.0),
                egui::Align2::CENTER_TOP,
                "Click an arc in the contour tree to see its contour here",
                egui::FontId::proportional(14.0),
                Color32::from_gray(150),
            );
        }
        if let Some(p) = &self.problem {
            ui.painter().text(
                rect.left_bottom() + egui::vec2(8.0, -8.0),
                egui::Align2::LEFT_BOTTOM,
                p,
                egui::FontId::proportional(12.0),
                Color32::LIGHT_RED,
            );
        }
        events
    }

    /// The last rendered image (for the screenshot export).
    pub fn read_image(&self, rs: &egui_wgpu::RenderState) -> anyhow::Result<image::RgbaImage> {
        let r = self
            .renderer
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("the 3D view has not been drawn yet"))?;
        Ok(r.read_image(&rs.device, &rs.queue)?)
    }
}

/// The bounds of the visible meshes of `scene` (the hover preview left
/// out) in the grid frame, None when nothing is drawn.
pub fn scene_bounds(scene: &[SceneMesh]) -> Option<([f32; 3], [f32; 3])> {
    let mut lo = glam::Vec3::splat(f32::INFINITY);
    let mut hi = glam::Vec3::splat(f32::NEG_INFINITY);
    for m in scene
        .iter()
        .filter(|m| m.visible && m.key != SceneKey::Preview)
    {
        lo = lo.min(m.mesh.bbox.0);
        hi = hi.max(m.mesh.bbox.1);
    }
    lo.cmple(hi).all().then(|| (lo.to_array(), hi.to_array()))
}

/// Fits `camera` to the box for a view of `aspect` = width / height:
/// [`Camera::fit`] frames the box's sphere in the vertical field of view;
/// a view narrower than tall needs the eye farther back for the sphere to
/// fit the horizontal one too (else the box is cut at the sides).
pub fn fit_in_view(camera: &mut Camera, lo: [f32; 3], hi: [f32; 3], aspect: f32) {
    camera.fit(lo, hi);
    if aspect.is_finite() && aspect > 0.0 && aspect < 1.0 {
        let half_x = (aspect * (0.5 * camera.fov_y).tan()).atan();
        camera.distance = 1.05 * camera.scene_radius / half_x.sin();
    }
}
