//! Axis-aligned slices of a field: its values on the plane of the grid
//! where coordinate `axis` equals `index`, for the views' context (the
//! grey image the contours are drawn over).
//!
//! A slice of axis `a` spans the two other axes `(u, v)` in increasing
//! order (x: (y, z), y: (x, z), z: (x, y)). Images are stored top row
//! first with `v` growing upwards, so they show the way the 3D view does
//! with +Z up. Positions are in the contours' coordinates: grid index ×
//! spacing (sample `(0, 0, 0)` at the origin), as
//! [`grid_bounds`](crate::render::grid_bounds) draws the volume's box.

use super::ScalarField;

/// The two axes a slice of `axis` spans, `(u, v)`.
pub fn slice_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// The values of one slice, scaled to `[0, 1]` over the field's range.
#[derive(Clone, Debug, PartialEq)]
pub struct Slice {
    /// The axis the slice is normal to (0, 1, 2 for x, y, z).
    pub axis: usize,
    /// Its grid index along `axis`.
    pub index: usize,
    /// Samples along `u`.
    pub width: usize,
    /// Samples along `v`.
    pub height: usize,
    /// `width × height` grey values in `[0, 1]`, row `r` holding
    /// `v = height - 1 - r`.
    pub grey: Vec<f32>,
}

impl Slice {
    /// The slice of `field` normal to `axis` (clamped to 0..=2) at grid
    /// index `index` (clamped to the grid).
    pub fn of(field: &ScalarField, axis: usize, index: usize) -> Slice {
        let axis = axis.min(2);
        let dims = field.dims();
        let index = index.min(dims[axis].saturating_sub(1));
        let (u, v) = slice_axes(axis);
        let (width, height) = (dims[u], dims[v]);
        let (lo, hi) = field.range();
        let span = if hi > lo { hi - lo } else { 1.0 };
        let mut grey = Vec::with_capacity(width * height);
        for r in 0..height {
            let vi = height - 1 - r;
            for ui in 0..width {
                let mut c = [0usize; 3];
                c[axis] = index;
                c[u] = ui;
                c[v] = vi;
                let id = c[0] + dims[0] * (c[1] + dims[1] * c[2]);
                grey.push(((field.value(id as u32) - lo) / span) as f32);
            }
        }
        Slice {
            axis,
            index,
            width,
            height,
            grey,
        }
    }

    /// The world position of the plane along `axis`.
    pub fn position(&self, spacing: [f64; 3]) -> f32 {
        (self.index as f64 * spacing[self.axis]) as f32
    }

    /// The slice's rectangle in world space: the corners at the image's
    /// top-left, top-right, bottom-right and bottom-left (what
    /// [`SliceQuad`](crate::render::SliceQuad) takes).
    pub fn corners(&self, spacing: [f64; 3]) -> [[f32; 3]; 4] {
        let (u, v) = slice_axes(self.axis);
        let u1 = (self.width.saturating_sub(1) as f64 * spacing[u]) as f32;
        let v1 = (self.height.saturating_sub(1) as f64 * spacing[v]) as f32;
        let at = self.position(spacing);
        let corner = |cu: f32, cv: f32| {
            let mut p = [0.0; 3];
            p[self.axis] = at;
            p[u] = cu;
            p[v] = cv;
            p
        };
        [
            corner(0.0, v1),
            corner(u1, v1),
            corner(u1, 0.0),
            corner(0.0, 0.0),
        ]
    }

    /// The grey value at fractional grid position `(u, v)` (bilinear;
    /// clamped to the slice).
    pub fn sample(&self, u: f32, v: f32) -> f32 {
        if self.width == 0 || self.height == 0 {
            return 0.0;
        }
        let u = u.clamp(0.0, (self.width - 1) as f32);
        let v = v.clamp(0.0, (self.height - 1) as f32);
        let (u0, v0) = (u.floor() as usize, v.floor() as usize);
        let (u1, v1) = ((u0 + 1).min(self.width - 1), (v0 + 1).min(self.height - 1));
        let (fu, fv) = (u - u0 as f32, v - v0 as f32);
        let at = |ui: usize, vi: usize| self.grey[(self.height - 1 - vi) * self.width + ui];
        let bottom = at(u0, v0) * (1.0 - fu) + at(u1, v0) * fu;
        let top = at(u0, v1) * (1.0 - fu) + at(u1, v1) * fu;
        bottom * (1.0 - fv) + top * fv
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// value = x + 10 y + 100 z on a 3 × 4 × 5 grid.
    fn ramp() -> ScalarField {
        let dims = [3, 4, 5];
        let mut values = Vec::new();
        for z in 0..5 {
            for y in 0..4 {
                for x in 0..3 {
                    values.push((x + 10 * y + 100 * z) as f32);
                }
            }
        }
        ScalarField::new(dims, super::super::Values::F32(values)).expect("a valid field")
    }

    #[test]
    fn a_slice_holds_the_values_of_its_plane_top_row_first() {
        let f = ramp();
        let (lo, hi) = (0.0f32, 432.0f32);
        let grey = |v: f32| (v - lo) / (hi - lo);
        let s = Slice::of(&f, 2, 3); // z = 3: u = x, v = y
        assert_eq!((s.width, s.height), (3, 4));
        // Top-left: x = 0, y = 3.
        assert!((s.grey[0] - grey(330.0)).abs() < 1e-6);
        // Bottom-right: x = 2, y = 0.
        assert!((s.grey[3 * 4 - 1] - grey(302.0)).abs() < 1e-6);
        let s = Slice::of(&f, 0, 1); // x = 1: u = y, v = z
        assert_eq!((s.width, s.height), (4, 5));
        assert!((s.grey[0] - grey(401.0)).abs() < 1e-6);
        assert!((s.sample(1.5, 0.0) - grey(16.0)).abs() < 1e-6);
        // Out of range: clamped.
        assert_eq!(Slice::of(&f, 7, 99).axis, 2);
        assert_eq!(Slice::of(&f, 7, 99).index, 4);
    }

    #[test]
    fn corners_span_the_volume_box_at_the_slice() {
        let f = ramp();
        let s = Slice::of(&f, 1, 2);
        let c = s.corners([1.0, 2.0, 0.5]);
        // y = 2 × 2; u = x in [0, 2], v = z in [0, 2].
        assert_eq!(c[0], [0.0, 4.0, 2.0]);
        assert_eq!(c[2], [2.0, 4.0, 0.0]);
    }
}
