//! The orbit camera: a target point, a distance from it and two angles.
//!
//! World up is **+Z** (volumes are usually stacked slices along z). The eye
//! sits on a sphere of radius `distance` around `target`:
//! `eye = target + distance * (cos pitch cos yaw, cos pitch sin yaw, sin pitch)`.
//! The projection is right-handed perspective with **reversed depth**: 1 at
//! the near plane, 0 at the far one (wgpu's `[0, 1]` range; with a float
//! depth buffer this keeps precision even when zoomed in far, see the
//! renderer's depth test). Near and far planes follow the distance and the
//! size of the scene given to [`Camera::fit`], so zooming never clips it.

use glam::{Mat4, Vec2, Vec3};

/// The largest pitch, just short of the poles where the view would flip.
const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

/// A standard view along one of the volume's axes. The medical names
/// follow the usual layout of a head volume (slices stacked along z,
/// y front to back, x left to right): axial looks down the z axis (from
/// +z), coronal along y (from −y), sagittal along x (from +x). Which
/// anatomical side that is depends on the file's orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewPreset {
    /// From +z, looking down, +y up on screen.
    Axial,
    /// From −y, +z up.
    Coronal,
    /// From +x, +z up.
    Sagittal,
    /// From +x (eye on the +x side, looking towards −x).
    PlusX,
    /// From −x.
    MinusX,
    /// From +y.
    PlusY,
    /// From −y.
    MinusY,
    /// From +z (above).
    PlusZ,
    /// From −z (below).
    MinusZ,
}

impl ViewPreset {
    /// Every preset, in menu order.
    pub const ALL: [ViewPreset; 9] = [
        ViewPreset::Axial,
        ViewPreset::Coronal,
        ViewPreset::Sagittal,
        ViewPreset::PlusX,
        ViewPreset::MinusX,
        ViewPreset::PlusY,
        ViewPreset::MinusY,
        ViewPreset::PlusZ,
        ViewPreset::MinusZ,
    ];

    /// The name shown in menus.
    pub fn name(self) -> &'static str {
        match self {
            ViewPreset::Axial => "Axial (along z)",
            ViewPreset::Coronal => "Coronal (along y)",
            ViewPreset::Sagittal => "Sagittal (along x)",
            ViewPreset::PlusX => "From +x",
            ViewPreset::MinusX => "From −x",
            ViewPreset::PlusY => "From +y",
            ViewPreset::MinusY => "From −y",
            ViewPreset::PlusZ => "From +z",
            ViewPreset::MinusZ => "From −z",
        }
    }

    /// `(yaw, pitch)` of the eye, radians.
    pub fn angles(self) -> (f32, f32) {
        use std::f32::consts::{FRAC_PI_2, PI};
        match self {
            ViewPreset::PlusX | ViewPreset::Sagittal => (0.0, 0.0),
            ViewPreset::MinusX => (PI, 0.0),
            ViewPreset::PlusY => (FRAC_PI_2, 0.0),
            ViewPreset::MinusY | ViewPreset::Coronal => (-FRAC_PI_2, 0.0),
            ViewPreset::PlusZ | ViewPreset::Axial => (-FRAC_PI_2, MAX_PITCH),
            ViewPreset::MinusZ => (-FRAC_PI_2, -MAX_PITCH),
        }
    }
}

/// An orbit camera (see the module doc for the conventions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The point the camera looks at and orbits around.
    pub target: Vec3,
    /// Distance from `target` to the eye (world units, > 0).
    pub distance: f32,
    /// Angle around world +Z, radians; `-90°` looks along +Y with +X to the right.
    pub yaw: f32,
    /// Elevation above the XY plane, radians, kept inside ±89°.
    pub pitch: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Radius of the scene (set by [`Camera::fit`]); sets the near and far
    /// planes and the zoom limits.
    pub scene_radius: f32,
}

impl Default for Camera {
    /// Looks at the unit cube `[0,1]³` from the front, slightly from the
    /// right and above.
    fn default() -> Self {
        let mut c = Camera {
            target: Vec3::ZERO,
            distance: 1.0,
            yaw: (-90.0f32 + 30.0).to_radians(),
            pitch: 25.0f32.to_radians(),
            fov_y: 35.0f32.to_radians(),
            scene_radius: 1.0,
        };
        c.fit([0.0; 3], [1.0; 3]);
        c
    }
}

impl Camera {
    /// Aims at the centre of the box and backs off until the whole box (its
    /// bounding sphere) is in view; keeps the viewing angles.
    pub fn fit(&mut self, bbox_min: [f32; 3], bbox_max: [f32; 3]) {
        let (lo, hi) = (Vec3::from(bbox_min), Vec3::from(bbox_max));
        let radius = if lo.is_finite() && hi.is_finite() {
            0.5 * (hi - lo).length()
        } else {
            0.0
        };
        let radius = if radius > 0.0 { radius } else { 1.0 };
        self.target = if lo.is_finite() && hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            Vec3::ZERO
        };
        self.scene_radius = radius;
        // The sphere fits the vertical field of view; a wide viewport only
        // adds margin at the sides. 5% margin.
        self.distance = 1.05 * radius / (0.5 * self.fov_y).sin();
    }

    /// Looks along a standard axis ([`ViewPreset`]), keeping the target
    /// and the distance. (Straight down the z axis is 89°: the orbit
    /// keeps off the poles.)
    pub fn set_preset(&mut self, preset: ViewPreset) {
        let (yaw, pitch) = preset.angles();
        self.yaw = yaw.rem_euclid(std::f32::consts::TAU);
        self.pitch = pitch;
    }

    /// The world directions that point right and up on screen (unit
    /// vectors), e.g. to draw an axis triad.
    pub fn screen_axes(&self) -> (Vec3, Vec3) {
        self.right_up()
    }

    /// Rotates around the target: `dx` radians of yaw, `dy` radians of pitch
    /// (positive `dy` raises the eye). A drag of `d` pixels is typically
    /// `orbit(-0.01 * d.x, 0.01 * d.y)`.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw = (self.yaw + dx).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch + dy).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Multiplies the distance by `factor` (< 1 moves closer), within
    /// `[scene_radius / 1000, scene_radius * 100]`. A scroll of `s` points is
    /// typically `zoom((-0.002 * s).exp())`.
    pub fn zoom(&mut self, factor: f32) {
        if !(factor.is_finite() && factor > 0.0) {
            return;
        }
        let r = self.scene_radius.max(f32::MIN_POSITIVE);
        self.distance = (self.distance * factor).clamp(r * 1e-3, r * 1e2);
    }

    /// Moves the target in the view plane so that the scene follows a drag
    /// of `(dx, dy)` pixels (y down) in a viewport `viewport_h` pixels high:
    /// a point at the target's depth stays under the pointer.
    pub fn pan(&mut self, dx: f32, dy: f32, viewport_h: f32) {
        if viewport_h.is_nan() || viewport_h <= 0.0 {
            return;
        }
        let world_per_pixel = 2.0 * self.distance * (0.5 * self.fov_y).tan() / viewport_h;
        let (right, up) = self.right_up();
        self.target += (-right * dx + up * dy) * world_per_pixel;
    }

    /// The eye position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * cy, cp * sy, sp)
    }

    /// Unit vectors to the right and up on screen, in world coordinates.
    fn right_up(&self) -> (Vec3, Vec3) {
        let forward = (self.target - self.eye()).normalize_or(Vec3::Y);
        let right = forward.cross(Vec3::Z).normalize_or(Vec3::X);
        let up = right.cross(forward);
        (right, up)
    }

    /// The near and far clip distances: around the scene sphere, never
    /// closer than 1/1000 of the distance (depth precision).
    fn near_far(&self) -> (f32, f32) {
        let r = self.scene_radius.max(f32::MIN_POSITIVE);
        let near = (self.distance - 2.0 * r).max(self.distance * 1e-3);
        let far = self.distance + 2.0 * r;
        (near, far)
    }

    /// The world-to-view matrix (right-handed, looking down −Z of view space).
    pub fn view(&self) -> Mat4 {
        let (_, up) = self.right_up();
        Mat4::look_at_rh(self.eye(), self.target, up)
    }

    /// The world-to-clip matrix for a viewport of `aspect` = width / height
    /// (reversed depth: near → 1, far → 0).
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let (near, far) = self.near_far();
        // Swapping near and far reverses depth.
        Mat4::perspective_rh(self.fov_y, aspect, far, near) * self.view()
    }

    /// The picking ray through normalized device coordinates `ndc` (x right,
    /// y up, both in `[-1, 1]`): the eye and a unit direction.
    pub fn ray(&self, ndc: [f32; 2], aspect: f32) -> (Vec3, Vec3) {
        let inv = self.view_proj(aspect).inverse();
        // Any point between the clip planes on that pixel gives the direction.
        let p = inv.project_point3(Vec2::from(ndc).extend(0.5));
        let eye = self.eye();
        (eye, (p - eye).normalize_or(self.target - eye))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_look_along_their_axes() {
        let mut c = Camera::default();
        c.fit([0.0; 3], [2.0; 3]);
        let along = |c: &Camera| (c.target - c.eye()).normalize();
        for (p, d) in [
            (ViewPreset::PlusX, Vec3::NEG_X),
            (ViewPreset::MinusX, Vec3::X),
            (ViewPreset::PlusY, Vec3::NEG_Y),
            (ViewPreset::Coronal, Vec3::Y),
            (ViewPreset::Axial, Vec3::NEG_Z),
            (ViewPreset::MinusZ, Vec3::Z),
        ] {
            c.set_preset(p);
            assert!(along(&c).dot(d) > 0.999, "{p:?}: {}", along(&c));
        }
        // Axial: +y up on screen, +x to the right.
        c.set_preset(ViewPreset::Axial);
        let (right, up) = c.screen_axes();
        assert!(right.dot(Vec3::X) > 0.99 && up.dot(Vec3::Y) > 0.99);
        // Coronal: +z up, +x right.
        c.set_preset(ViewPreset::Coronal);
        let (right, up) = c.screen_axes();
        assert!(right.dot(Vec3::X) > 0.99 && up.dot(Vec3::Z) > 0.99);
    }

    #[test]
    fn centre_ray_hits_target_after_fit() {
        let mut c = Camera::default();
        c.fit([-1.0, -2.0, 0.0], [3.0, 2.0, 5.0]);
        let (o, d) = c.ray([0.0, 0.0], 1.5);
        let to_target = (c.target - o).normalize();
        assert!(d.dot(to_target) > 0.9999);
        assert!((c.target - Vec3::new(1.0, 0.0, 2.5)).length() < 1e-6);
    }

    #[test]
    fn fitted_box_corners_are_inside_clip_space() {
        let mut c = Camera::default();
        c.fit([0.0; 3], [10.0, 20.0, 5.0]);
        let vp = c.view_proj(1.0);
        for i in 0..8 {
            let p = Vec3::new(
                if i & 1 == 0 { 0.0 } else { 10.0 },
                if i & 2 == 0 { 0.0 } else { 20.0 },
                if i & 4 == 0 { 0.0 } else { 5.0 },
            );
            let q = vp.project_point3(p);
            assert!(q.x.abs() <= 1.0 && q.y.abs() <= 1.0, "{p} -> {q}");
            assert!((0.0..=1.0).contains(&q.z), "{p} -> {q}");
        }
    }

    #[test]
    fn pan_moves_target_in_view_plane_and_zoom_is_clamped() {
        let mut c = Camera::default();
        let before = c;
        c.pan(10.0, 0.0, 100.0);
        let moved = c.target - before.target;
        assert!(moved.length() > 0.0);
        assert!(moved.dot(before.target - before.eye()).abs() < 1e-4);
        c.zoom(1e-9);
        assert!(c.distance >= c.scene_radius * 1e-3 * 0.999);
        c.zoom(f32::NAN);
        assert!(c.distance.is_finite());
        c.orbit(0.0, 10.0);
        assert!(c.pitch <= MAX_PITCH);
    }
}
