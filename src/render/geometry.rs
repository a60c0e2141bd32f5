//! CPU-side geometry: meshes prepared for the GPU (and kept for picking),
//! ray casts, vertex normals and a test sphere.
//!
//! Picking casts the ray on the CPU against every triangle of each mesh
//! whose bounding box the ray enters, nearest box first, stopping once a
//! box starts beyond the nearest hit. This needs no GPU round trip, is exact
//! and handles transparent meshes; it reads the [`PreparedMesh`] the vertex
//! buffer was filled from (24 bytes per vertex, 12 per triangle, the same
//! as the GPU's copy) and costs about 5 ns per triangle tested (rayon
//! splits meshes above [`PARALLEL_TRIANGLES`]).

use glam::Vec3;
use rayon::prelude::*;

/// Meshes with more triangles than this are ray-tested in parallel.
pub const PARALLEL_TRIANGLES: usize = 200_000;

/// A mesh made ready for the GPU: validated, normals computed when it came
/// without, positions and normals interleaved as the vertex buffer holds
/// them, with its box. Building one costs a few passes over the mesh, so
/// the app builds it on the thread that extracted the contour and the UI
/// thread only copies bytes ([`Renderer::set_prepared_mesh`]). The renderer
/// keeps it (shared) as its CPU copy for picking.
///
/// [`Renderer::set_prepared_mesh`]: super::Renderer::set_prepared_mesh
#[derive(Clone, Debug)]
pub struct PreparedMesh {
    /// Position then normal of each vertex.
    pub(crate) vertices: Vec<[f32; 6]>,
    /// Triangle corners, three per triangle, each `< vertices.len()`.
    pub(crate) indices: Vec<u32>,
    /// Axis-aligned bounding box (min, max); inverted (min > max) when empty.
    pub(crate) bbox: (Vec3, Vec3),
    /// Whether counter-clockwise triangles face outwards: the signed volume
    /// enclosed is positive. Exact for closed meshes, a majority vote for
    /// open ones; decides the draw order of a transparent mesh's halves.
    pub(crate) ccw_outward: bool,
}

impl Default for PreparedMesh {
    fn default() -> Self {
        PreparedMesh {
            vertices: Vec::new(),
            indices: Vec::new(),
            bbox: bbox_of(&[], &[]),
            ccw_outward: true,
        }
    }
}

impl PreparedMesh {
    /// Checks and interleaves a mesh. `normals` has one normal per
    /// position, or is empty to have them computed from the triangles
    /// ([`compute_normals`]); `indices` holds three corners per triangle.
    /// The error says what is malformed.
    pub fn new(
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        indices: &[u32],
    ) -> Result<Self, String> {
        if !normals.is_empty() && normals.len() != positions.len() {
            return Err(format!(
                "{} normals for {} positions",
                normals.len(),
                positions.len()
            ));
        }
        if !indices.len().is_multiple_of(3) {
            return Err(format!(
                "{} indices is not a whole number of triangles",
                indices.len()
            ));
        }
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(format!(
                "index {bad} is out of range for {} positions",
                positions.len()
            ));
        }
        if indices.len() > u32::MAX as usize {
            return Err(format!(
                "{} triangles are too many to draw",
                indices.len() / 3
            ));
        }
        let computed;
        let normals = if normals.is_empty() {
            computed = compute_normals(positions, indices);
            &computed[..]
        } else {
            normals
        };
        let vertices = positions
            .iter()
            .zip(normals)
            .map(|(p, n)| [p[0], p[1], p[2], n[0], n[1], n[2]])
            .collect();
        let bbox = bbox_of(positions, indices);
        Ok(PreparedMesh {
            vertices,
            indices: indices.to_vec(),
            bbox,
            ccw_outward: signed_volume(positions, indices, bbox) >= 0.0,
        })
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// Bytes the GPU buffers take (vertices and indices).
    pub fn gpu_bytes(&self) -> u64 {
        (std::mem::size_of_val(&self.vertices[..]) + std::mem::size_of_val(&self.indices[..]))
            as u64
    }

    fn position(&self, i: u32) -> Vec3 {
        let v = &self.vertices[i as usize];
        Vec3::new(v[0], v[1], v[2])
    }

    /// Centre of the bounding box (for back-to-front sorting).
    pub fn centre(&self) -> Vec3 {
        if self.bbox.0.cmple(self.bbox.1).all() {
            0.5 * (self.bbox.0 + self.bbox.1)
        } else {
            Vec3::ZERO
        }
    }

    /// The nearest hit of the ray `origin + t dir` (t > 0) with the mesh:
    /// `(t, point)`.
    pub fn ray_hit(&self, origin: Vec3, dir: Vec3) -> Option<(f32, Vec3)> {
        let test = |tri: &[u32]| -> Option<f32> {
            let p = |k: usize| self.position(tri[k]);
            ray_triangle(origin, dir, p(0), p(1), p(2))
        };
        let best = if self.indices.len() / 3 > PARALLEL_TRIANGLES {
            self.indices
                .par_chunks_exact(3)
                .filter_map(test)
                .reduce_with(f32::min)
        } else {
            self.indices
                .chunks_exact(3)
                .filter_map(test)
                .reduce(f32::min)
        };
        best.map(|t| (t, origin + t * dir))
    }
}

/// Six times the signed volume enclosed by the triangles (divergence
/// theorem), measured from the box centre to keep the sums small.
fn signed_volume(positions: &[[f32; 3]], indices: &[u32], bbox: (Vec3, Vec3)) -> f64 {
    let o = if bbox.0.cmple(bbox.1).all() {
        0.5 * (bbox.0 + bbox.1)
    } else {
        Vec3::ZERO
    };
    indices
        .chunks_exact(3)
        .map(|t| {
            let p = |k: usize| (Vec3::from(positions[t[k] as usize]) - o).as_dvec3();
            p(0).dot(p(1).cross(p(2)))
        })
        .filter(|v| v.is_finite())
        .sum()
}

/// The bounding box of the vertices used by the triangles (inverted when
/// there are none).
fn bbox_of(positions: &[[f32; 3]], indices: &[u32]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    if indices.is_empty() {
        return (lo, hi);
    }
    for p in positions {
        let p = Vec3::from(*p);
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    (lo, hi)
}

/// Where the ray enters the box: the smallest `t ≥ 0` inside it, or None
/// when it misses (slab test; an inverted box is always missed).
pub(crate) fn ray_box(origin: Vec3, dir: Vec3, lo: Vec3, hi: Vec3) -> Option<f32> {
    if !lo.cmple(hi).all() {
        return None;
    }
    // A huge finite reciprocal instead of ∞ keeps 0·∞ = NaN out when the
    // ray lies in a slab's plane.
    let inv = Vec3::select(dir.cmpeq(Vec3::ZERO), Vec3::splat(1e30), dir.recip());
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    let tmin = t0.min(t1);
    let tmax = t0.max(t1);
    let enter = tmin.max_element().max(0.0);
    let exit = tmax.min_element();
    (enter <= exit).then_some(enter)
}

/// Möller–Trumbore ray–triangle intersection, both faces: the ray
/// parameter `t > 0` of the hit, if any.
pub(crate) fn ray_triangle(origin: Vec3, dir: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    // Relative threshold: the determinant scales with the triangle's area.
    if det.abs() <= 1e-12 * e1.length_squared().max(e2.length_squared()) || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(-1e-6..=1.0 + 1e-6).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < -1e-6 || u + v > 1.0 + 1e-6 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// Area-weighted vertex normals (unit length; zero for unused vertices), for
/// meshes that come without normals. The orientation follows the winding:
/// counter-clockwise triangles face their normal.
pub fn compute_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![Vec3::ZERO; positions.len()];
    for tri in indices.chunks_exact(3) {
        let [i, j, k] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        if i >= positions.len() || j >= positions.len() || k >= positions.len() {
            continue;
        }
        let (a, b, c) = (
            Vec3::from(positions[i]),
            Vec3::from(positions[j]),
            Vec3::from(positions[k]),
        );
        // The cross product's length is twice the area: area weighting.
        let n = (b - a).cross(c - a);
        if n.is_finite() {
            acc[i] += n;
            acc[j] += n;
            acc[k] += n;
        }
    }
    acc.into_iter()
        .map(|n| n.normalize_or_zero().to_array())
        .collect()
}

/// A sphere mesh (icosahedron subdivided `subdivisions` times, vertices
/// pushed to the sphere): `(positions, normals, indices)`, outward normals
/// and counter-clockwise winding seen from outside. For tests and demos;
/// 20·4ⁿ triangles.
pub fn icosphere(
    centre: [f32; 3],
    radius: f32,
    subdivisions: u32,
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from(*p).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, verts: &mut Vec<Vec3>| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push((0.5 * (verts[a as usize] + verts[b as usize])).normalize());
                (verts.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = mid(a, b, &mut verts);
            let bc = mid(b, c, &mut verts);
            let ca = mid(c, a, &mut verts);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let centre = Vec3::from(centre);
    let positions = verts
        .iter()
        .map(|n| (centre + radius * *n).to_array())
        .collect();
    let normals = verts.iter().map(|n| n.to_array()).collect();
    (positions, normals, tris.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_hits_the_near_side_of_a_sphere() {
        let (p, _, i) = icosphere([0.0, 0.0, 0.0], 1.0, 3);
        let m = PreparedMesh::new(&p, &[], &i).expect("a valid mesh");
        let (t, hit) = m
            .ray_hit(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0))
            .expect("hit");
        assert!((t - 4.0).abs() < 0.01, "{t}");
        assert!((hit.z - 1.0).abs() < 0.01);
        assert!(
            m.ray_hit(Vec3::new(2.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0))
                .is_none()
        );
    }

    #[test]
    fn winding_orientation_is_detected() {
        let (p, _, mut i) = icosphere([5.0, 0.0, 0.0], 1.0, 1);
        assert!(
            PreparedMesh::new(&p, &[], &i)
                .expect("a valid mesh")
                .ccw_outward
        );
        for t in i.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        assert!(
            !PreparedMesh::new(&p, &[], &i)
                .expect("a valid mesh")
                .ccw_outward
        );
    }

    #[test]
    fn ray_box_enters_and_misses() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        let t = ray_box(Vec3::new(0.5, 0.5, -1.0), Vec3::Z, lo, hi);
        assert_eq!(t, Some(1.0));
        assert_eq!(ray_box(Vec3::new(2.0, 0.5, -1.0), Vec3::Z, lo, hi), None);
        // Inside the box the entry is the origin.
        assert_eq!(ray_box(Vec3::splat(0.5), Vec3::X, lo, hi), Some(0.0));
    }

    #[test]
    fn computed_normals_of_a_sphere_point_outward() {
        let (p, n0, i) = icosphere([1.0, 2.0, 3.0], 2.0, 2);
        let n = compute_normals(&p, &i);
        for (a, b) in n.iter().zip(&n0) {
            assert!(Vec3::from(*a).dot(Vec3::from(*b)) > 0.99);
        }
    }
}
