//! Plane sections of contour meshes: the segments where a triangle mesh
//! crosses an axis-aligned plane, for drawing each contour's
//! cross-section on a slice of the volume in its colour.
//!
//! Intersecting the contour's own mesh (rather than running marching
//! squares on the slice) keeps the section to that one contour, however
//! many other components share its isovalue.
//!
//! A vertex counts as above the plane when `p[axis] >= at` (ties go
//! up), so every triangle the plane crosses has exactly one or two
//! vertices on each side and yields exactly one segment, joining the
//! crossing points of its two edges that change side. A crossing point is
//! computed from the edge's endpoints in a fixed order (the
//! lexicographically smaller position first), so the two triangles
//! sharing an edge produce bit-identical points, even where a mesh
//! repeats a vertex: the segments of a closed mesh chain into closed
//! loops.

use rayon::prelude::*;

/// Triangles above which the section is cut in parallel chunks.
const PARALLEL_TRIANGLES: usize = 50_000;

/// The segments where the mesh (`positions`, three `indices` per
/// triangle) crosses the plane `p[axis] = at`, each as two points in the
/// plane's `(u, v)` coordinates ([`slice_axes`](crate::field::slice::slice_axes)).
/// Triangles with an index out of range are skipped. Sorted by
/// triangle (deterministic).
pub fn axis_section(
    positions: &[[f32; 3]],
    indices: &[u32],
    axis: usize,
    at: f32,
) -> Vec<[[f32; 2]; 2]> {
    let axis = axis.min(2);
    let (u, v) = crate::field::slice::slice_axes(axis);
    let triangle = |t: &[u32]| -> Option<[[f32; 2]; 2]> {
        let p = [
            positions.get(t[0] as usize)?,
            positions.get(t[1] as usize)?,
            positions.get(t[2] as usize)?,
        ];
        let above = p.map(|q| q[axis] >= at);
        if above[0] == above[1] && above[1] == above[2] {
            return None;
        }
        let mut points = [[0.0f32; 2]; 2];
        let mut n = 0;
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            if above[a] == above[b] {
                continue;
            }
            // Fixed order: the smaller position first.
            let smaller = p[a]
                .iter()
                .zip(p[b].iter())
                .map(|(x, y)| x.total_cmp(y))
                .find(|o| o.is_ne())
                .is_none_or(|o| o.is_lt());
            let (a, b) = if smaller { (a, b) } else { (b, a) };
            let (pa, pb) = (p[a], p[b]);
            let s = (at - pa[axis]) / (pb[axis] - pa[axis]);
            points[n] = [pa[u] + s * (pb[u] - pa[u]), pa[v] + s * (pb[v] - pa[v])];
            n += 1;
        }
        (n == 2).then_some(points)
    };
    if indices.len() / 3 > PARALLEL_TRIANGLES {
        indices.par_chunks_exact(3).filter_map(triangle).collect()
    } else {
        indices.chunks_exact(3).filter_map(triangle).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn a_sphere_is_cut_in_a_closed_circle_of_its_radius_at_that_height() {
        let (p, _, i) = crate::render::icosphere([0.0; 3], 2.0, 3);
        for at in [0.0f32, 0.7, -1.3] {
            let segments = axis_section(&p, &i, 2, at);
            assert!(!segments.is_empty());
            let r = (4.0 - at * at).sqrt();
            let mut ends: HashMap<[u32; 2], usize> = HashMap::new();
            for s in &segments {
                for q in s {
                    let d = (q[0] * q[0] + q[1] * q[1]).sqrt();
                    // Chords of the sphere lie just inside it.
                    assert!(d <= r + 1e-4 && d > r - 0.1, "{d} vs {r}");
                    *ends.entry(q.map(f32::to_bits)).or_default() += 1;
                }
            }
            // Closed: every end is shared by an even number of segments
            // (two, or more where the plane passes through a vertex: at
            // z = 0 the icosphere has vertices on the plane).
            assert!(ends.values().all(|&n| n % 2 == 0), "open section at {at}");
        }
        // Above the top: nothing.
        assert!(axis_section(&p, &i, 2, 2.5).is_empty());
        // Out-of-range indices are skipped, not a panic.
        assert!(axis_section(&p, &[0, 1, 99_999], 0, 0.0).is_empty());
    }
}
