//! Where a grid sits in the world: origin, axis directions and the name of
//! the space, as scanners and the tools that read their files (3D Slicer,
//! ITK, ParaView) place it.
//!
//! Vertex (i, j, k) lies at
//!
//! ```text
//! world = origin + i·sx·d_i + j·sy·d_j + k·sz·d_k
//! ```
//!
//! where (sx, sy, sz) is the field's spacing and d_i, d_j, d_k are the unit
//! directions of the three grid axes ([`Geometry::direction`]). The engine
//! never needs this: it works on vertex ids and values. Contours are made
//! in the *grid frame* (index × spacing, the origin at vertex 0, axes along
//! x, y, z), and [`Geometry::to_world`] moves a point of that frame into
//! the world. A direction matrix may be a reflection (NIfTI files often
//! are): [`Geometry::is_reflection`] says so, and then the triangles of a
//! mesh moved into the world must be wound the other way to keep facing
//! the same side.
//!
//! Spaces: DICOM, ITK and MetaImage use LPS (x to the patient's left, y to
//! posterior, z to superior); NIfTI uses RAS (x right, y anterior), the
//! same axes with x and y negated. NRRD names its space; VTK files name
//! none ([`Space::Unnamed`]). Coordinates are kept in the space the file
//! used, named, never silently converted.

/// The coordinate system world positions are given in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Space {
    /// No anatomical meaning given (VTK files, synthetic fields, scanner
    /// coordinates of NRRD).
    #[default]
    Unnamed,
    /// Left, posterior, superior (DICOM, ITK, MetaImage; NRRD
    /// `left-posterior-superior`).
    Lps,
    /// Right, anterior, superior (NIfTI; NRRD `right-anterior-superior`).
    Ras,
}

impl Space {
    /// The short name: "LPS", "RAS" or "unnamed".
    pub fn name(self) -> &'static str {
        match self {
            Space::Unnamed => "unnamed",
            Space::Lps => "LPS",
            Space::Ras => "RAS",
        }
    }
}

impl std::fmt::Display for Space {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The placement of a grid in the world (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// World position of vertex (0, 0, 0).
    pub origin: [f64; 3],
    /// `direction[a]`: the unit world direction of grid axis `a`.
    pub direction: [[f64; 3]; 3],
    /// The space of `origin` and `direction`.
    pub space: Space,
}

impl Default for Geometry {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// Why a geometry is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// An origin or direction component is NaN or infinite.
    #[error("origin {origin:?} or direction {direction:?} is not finite")]
    NotFinite {
        /// The origin given.
        origin: [f64; 3],
        /// The direction given.
        direction: [[f64; 3]; 3],
    },
    /// The axis directions do not span space (a zero or repeated axis).
    #[error("direction {0:?} is degenerate (its axes do not span space)")]
    Degenerate([[f64; 3]; 3]),
}

impl Geometry {
    /// Origin 0, axes along x, y, z, no named space: the grid frame is the
    /// world.
    pub const IDENTITY: Geometry = Geometry {
        origin: [0.0; 3],
        direction: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        space: Space::Unnamed,
    };

    /// A geometry from an origin and three axis vectors of any non-zero
    /// length (they are normalised: their lengths are the spacing's
    /// business). Fails on non-finite numbers and on axes that do not span
    /// space.
    pub fn new(
        origin: [f64; 3],
        axes: [[f64; 3]; 3],
        space: Space,
    ) -> Result<Geometry, GeometryError> {
        let finite = origin
            .iter()
            .chain(axes.iter().flatten())
            .all(|c| c.is_finite());
        if !finite {
            return Err(GeometryError::NotFinite {
                origin,
                direction: axes,
            });
        }
        let mut direction = axes;
        for d in &mut direction {
            let n = norm(*d);
            if n == 0.0 {
                return Err(GeometryError::Degenerate(axes));
            }
            *d = d.map(|c| c / n);
        }
        if det(direction).abs() < 1e-6 {
            return Err(GeometryError::Degenerate(axes));
        }
        Ok(Geometry {
            origin,
            direction,
            space,
        })
    }

    /// True when this is [`Geometry::IDENTITY`] up to the space's name.
    pub fn is_identity(&self) -> bool {
        self.origin == [0.0; 3] && self.direction == Self::IDENTITY.direction
    }

    /// True when the direction matrix reverses orientation (determinant
    /// below zero): a mesh moved into the world must then flip its
    /// triangles' winding to keep facing the same way.
    pub fn is_reflection(&self) -> bool {
        det(self.direction) < 0.0
    }

    /// A point of the grid frame (index × spacing) in the world.
    #[inline]
    pub fn to_world(&self, p: [f64; 3]) -> [f64; 3] {
        let d = &self.direction;
        std::array::from_fn(|c| self.origin[c] + p[0] * d[0][c] + p[1] * d[1][c] + p[2] * d[2][c])
    }

    /// [`Geometry::to_world`] as a 4×4 affine matrix, column-major
    /// (`m[c][r]`: column `c`, row `r`), for a renderer to place the grid
    /// frame in the world: columns 0..3 are the images of the unit
    /// vectors (the directions), column 3 the origin. Built from
    /// `to_world` itself, so it is the same map exports use.
    pub fn affine(&self) -> [[f64; 4]; 4] {
        let o = self.to_world([0.0; 3]);
        let column = |a: usize| {
            let mut e = [0.0; 3];
            e[a] = 1.0;
            let w = self.to_world(e);
            [w[0] - o[0], w[1] - o[1], w[2] - o[2], 0.0]
        };
        [column(0), column(1), column(2), [o[0], o[1], o[2], 1.0]]
    }

    /// A normal of the grid frame in the world: the inverse transpose of
    /// the direction matrix (the matrix itself when it is a rotation),
    /// normalised.
    pub fn normal_to_world(&self, n: [f64; 3]) -> [f64; 3] {
        // inverse transpose = cofactor matrix / det; the sign of det is
        // kept so a reflection moves the normal with the surface.
        let d = &self.direction;
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        // Columns of M^-T are (d1×d2, d2×d0, d0×d1) / det (rows of M^-1 as
        // columns); M's columns are the axis directions.
        let c = [cross(d[1], d[2]), cross(d[2], d[0]), cross(d[0], d[1])];
        let dt = det(self.direction);
        let w: [f64; 3] =
            std::array::from_fn(|k| (n[0] * c[0][k] + n[1] * c[1][k] + n[2] * c[2][k]) / dt);
        let l = norm(w);
        if l > 0.0 { w.map(|x| x / l) } else { w }
    }

    /// The same placement in `space`: LPS and RAS differ by negating x and
    /// y; an unnamed space is taken as it is.
    pub fn in_space(&self, space: Space) -> Geometry {
        let flip = matches!(
            (self.space, space),
            (Space::Lps, Space::Ras) | (Space::Ras, Space::Lps)
        );
        if !flip {
            return Geometry { space, ..*self };
        }
        let f = |v: [f64; 3]| [-v[0], -v[1], v[2]];
        Geometry {
            origin: f(self.origin),
            direction: self.direction.map(f),
            space,
        }
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The determinant of the matrix whose columns are `m[0], m[1], m[2]`:
/// the triple product m0 · (m1 × m2).
fn det(m: [[f64; 3]; 3]) -> f64 {
    let [a, b, c] = m;
    a[0] * (b[1] * c[2] - b[2] * c[1])
        + a[1] * (b[2] * c[0] - b[0] * c[2])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
    }

    #[test]
    fn a_rotated_grid_places_its_axes_along_the_directions() {
        // MetaImage's TransformMatrix 0 -1 0 1 0 0 0 0 1: axis i along -y,
        // axis j along +x.
        let g = Geometry::new(
            [-12.5, 40.0, 7.25],
            [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            Space::Lps,
        )
        .unwrap();
        assert!(close(g.to_world([0.0; 3]), [-12.5, 40.0, 7.25]));
        assert!(close(
            g.to_world([63.0 * 0.9, 0.0, 0.0]),
            [-12.5, -16.7, 7.25]
        ));
        assert!(close(
            g.to_world([0.0, 63.0 * 1.1, 0.0]),
            [56.8, 40.0, 7.25]
        ));
        assert!(!g.is_reflection());
        // A rotation moves normals like points (without the origin).
        assert!(close(g.normal_to_world([1.0, 0.0, 0.0]), [0.0, -1.0, 0.0]));
        // The matrix is the same map.
        let m = g.affine();
        let p = [3.0, -2.0, 5.5];
        let by_matrix: [f64; 3] =
            std::array::from_fn(|r| (0..3).map(|c| m[c][r] * p[c]).sum::<f64>() + m[3][r]);
        assert!(close(by_matrix, g.to_world(p)));
    }

    #[test]
    fn lps_and_ras_differ_by_negating_x_and_y() {
        let g = Geometry::new([1.0, 2.0, 3.0], Geometry::IDENTITY.direction, Space::Lps).unwrap();
        let r = g.in_space(Space::Ras);
        assert_eq!(r.origin, [-1.0, -2.0, 3.0]);
        assert!(close(r.to_world([1.0, 1.0, 1.0]), [-2.0, -3.0, 4.0]));
        assert_eq!(r.in_space(Space::Lps), g);
    }

    #[test]
    fn a_reflection_is_detected_and_its_normals_follow_the_surface() {
        let g = Geometry::new(
            [0.0; 3],
            [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            Space::Ras,
        )
        .unwrap();
        assert!(g.is_reflection());
        assert!(close(g.normal_to_world([1.0, 0.0, 0.0]), [-1.0, 0.0, 0.0]));
    }

    #[test]
    fn degenerate_and_non_finite_directions_are_refused() {
        let flat = [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(matches!(
            Geometry::new([0.0; 3], flat, Space::Unnamed),
            Err(GeometryError::Degenerate(_))
        ));
        assert!(
            Geometry::new(
                [f64::NAN, 0.0, 0.0],
                Geometry::IDENTITY.direction,
                Space::Lps
            )
            .is_err()
        );
        let zero = [[0.0; 3], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(Geometry::new([0.0; 3], zero, Space::Lps).is_err());
    }
}
