//! The 3D view: the contours drawn by [`crate::render::Renderer`] into its
//! own texture, shown as an egui image. Orbit camera: drag rotates, wheel
//! zooms, right or middle drag pans, double-click fits the contours shown
//! (again: the volume). A click
//! on a surface picks it. Meshes are uploaded only when their version
//! changes; styles cost a uniform write; a frame whose camera, size and
//! scene are unchanged is not re-rendered.

use std::collections::HashMap;
use std::sync::Arc;

use egui::{Color32, Sense};

use crate::app::ids::ContourId;
use crate::render::{Camera, EguiTexture, MeshId, PreparedMesh, Renderer};

/// What a mesh of the scene is, as the explorer names it; the view gives
/// each its own renderer [`MeshId`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SceneKey {
    /// A selected contour.
    Contour(ContourId),
    /// Component `i` of "all contours at h".
    AtH(usize),
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
        }
    }

    /// Sets the volume's box (drawn faint) and fits the camera to it.
    pub fn set_bounds(&mut self, min: [f32; 3], max: [f32; 3]) {
        self.bounds = Some((min, max));
        self.camera.fit(min, max);
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
        let Some(renderer) = &mut self.renderer else {
            return events;
        };
        if renderer.upload_pending(&rs.device, &rs.queue, UPLOAD_BUDGET) {
            ui.ctx().request_repaint();
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
            // Fit the contours shown; a second double-click fits the volume.
            let contours = renderer.visible_bounds();
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
            if let Some((lo, hi)) = target {
                self.camera.fit(lo, hi);
            }
        } else if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
        {
            let local = p - rect.min;
            match renderer.pick(&self.camera, rect.width(), rect.height(), local.x, local.y) {
                Some((id, _)) => {
                    events.picked = self
                        .keys
                        .get(&id)
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
