//! Path seeds and contour following: the single contour of one superarc at
//! one isovalue, as an indexed triangle mesh (Carr & Snoeyink, "Path seeds
//! and flexible isosurfaces"; Carr, Snoeyink & van de Panne, §3).
//!
//! * [`seed`]: an edge of the mesh the contour crosses, found in O(log n)
//!   by binary search in the superarc's sorted regular vertices (and, for a
//!   simplified arc, first in its chain of superarcs); [`PathSeeds`] keeps
//!   what bare arcs need, for O(1) beyond the search.
//! * [`follow`]: from that edge, a flood through the Freudenthal tetrahedra
//!   the isovalue crosses, emitting marching-tetrahedra triangles; cost
//!   proportional to the contour, never to the volume.
//! * [`global`]: every contour at one isovalue (the classic isosurface, one
//!   mesh per superarc) by one parallel sweep over the volume whose
//!   components the arcs' path seeds name (`sweep`); following every seed
//!   instead, and a plain marching-tetrahedra pass over the whole volume,
//!   are the tests' oracles (`oracle`, hidden: not part of the API).
//! * [`topology`]: vertices, edges, Euler characteristic, boundary,
//!   orientation, area and volume of an extracted mesh.
//! * [`export`]: binary PLY, OBJ and binary STL.
//!
//! **The isovalue convention.** An [`Isovalue`] is a cut in the vertex
//! order, not just a number: vertex `v` is *above* it iff
//! `(f(v), v) > (value, tie)` lexicographically, the same simulation of
//! simplicity the contour tree is built with. [`Isovalue::new`] puts the cut
//! just above every vertex of value `h` (`tie = u32::MAX`): the level set at
//! `h + ε`. Seeds, following, the global isosurface and the Betti numbers
//! all ask [`Isovalue::is_above`], so extraction at `h = f(v)` exactly sees
//! no vertex *on* the level set: every crossed edge has one end strictly on
//! each side, interpolation never divides by zero (an edge with both ends
//! at `h` gets its midpoint), and the contours of the arcs spanning the cut
//! tile the level set without holes. A vertex at exactly `h` lies below,
//! and its contour vertices are kept a little way inside their edges
//! ([`marching::edge_fraction`]), never at the vertex itself, so a cut at a
//! data value gives no zero-area triangle and no two vertices at one place,
//! with the topology the tree predicts; [`ContourMesh::orient_outward`]
//! turns closed contours to face out for export.
//!
//! **Orientation.** Triangles wind counter-clockwise seen from the *lower*
//! side: their normals point downhill, towards lower values, i.e. outwards
//! around a maximum (a bright organ in a scan, a blob). Vertex normals are
//! the field's downhill gradient, or the area-weighted triangle normal
//! where the gradient vanishes or disagrees (see [`follow`]).
//!
//! Only 3D grids (every axis at least 2 vertices) have tetrahedra; a 2D
//! image yields empty contours.

pub mod drag;
pub mod export;
pub mod follow;
pub mod global;
pub mod marching;
#[doc(hidden)]
pub mod oracle;
pub mod section;
pub mod seed;
mod sweep;
pub mod topology;

#[doc(no_inline)]
pub use crate::field::Isovalue;
pub use drag::DraggedContour;
pub use follow::{ContourFollower, FollowerScratch};
pub use global::{all_contours, contours_through, follow_all};
pub use seed::{PathSeed, PathSeeds, arc_spans, path_seed, path_seed_in_chain};
pub use topology::MeshTopology;

use crate::field::ScalarField;
use crate::tree::ArcId;

/// The frame a mesh's positions are given in. Contours are made in the
/// grid frame (index × spacing, vertex 0 at the origin, axes along x, y,
/// z); [`ContourMesh::to_frame`] moves them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Frame {
    /// Voxel indices: vertex (i, j, k) at (i, j, k).
    Index,
    /// Index × spacing, axis-aligned from vertex 0: what the engine makes
    /// and the explorer draws.
    #[default]
    Grid,
    /// The file's world: origin, directions and spacing
    /// ([`crate::field::Geometry`]), in its named space (LPS, RAS), so the
    /// mesh lines up with the volume in 3D Slicer, ParaView or ITK-SNAP.
    World,
}

/// One extracted contour: an indexed triangle mesh in the grid frame
/// (grid coordinates times spacing; see [`Frame`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ContourMesh {
    /// The superarc whose contour this is.
    pub arc: ArcId,
    /// The isovalue it was extracted at (the value of its cut).
    pub isovalue: f64,
    /// Vertex positions, one per crossed mesh edge.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, pointing towards lower values.
    pub normals: Vec<[f32; 3]>,
    /// Three indices per triangle, counter-clockwise seen from below.
    pub indices: Vec<u32>,
    /// True when the contour reaches the volume's boundary (it is then an
    /// open surface, cut by the box).
    pub touches_boundary: bool,
    /// Whether the triangles wind counter-clockwise seen from the side of
    /// the contour that holds the volume's first vertex (a corner of the
    /// box): for a closed contour, seen from outside (its signed volume is
    /// positive); for an open one, the side the renderer then takes for
    /// outside. Known when the extraction knew it without a pass over the
    /// triangles (the sweep knows every vertex's side); None otherwise.
    pub ccw_outward: Option<bool>,
    /// The box of the positions (least and greatest coordinate per axis),
    /// when the extraction knew it without a pass over them; None
    /// otherwise, and after the positions move ([`ContourMesh::to_frame`]).
    pub bounds: Option<[[f32; 3]; 2]>,
    /// Stretches of the triangles whose corners lie in a known range of
    /// vertices, in order and covering every corner, when the extraction
    /// knew them (the sweep: one per cube layer, whose triangles' corners
    /// lie on the edges owned by the layer's two planes); empty otherwise.
    /// The GPU's preparation finds its 16-bit index runs from them without
    /// a pass over the triangles.
    pub bands: Vec<TriangleBand>,
}

/// Triangle corners `indices[corners]` that all lie in `vertices`: see
/// [`ContourMesh::bands`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TriangleBand {
    /// The band's triangle corners, as a range of the mesh's indices.
    pub corners: std::ops::Range<u32>,
    /// The vertices every one of those corners lies in.
    pub vertices: std::ops::Range<u32>,
}

impl ContourMesh {
    /// An empty contour of `arc` at `isovalue`.
    pub fn empty(arc: ArcId, isovalue: f64) -> Self {
        Self {
            arc,
            isovalue,
            positions: Vec::new(),
            normals: Vec::new(),
            indices: Vec::new(),
            touches_boundary: false,
            ccw_outward: None,
            bounds: None,
            bands: Vec::new(),
        }
    }

    /// Not a contour but arrays to recycle: room for a contour of
    /// `vertices` and `triangles` and a quarter more, every element zero
    /// and every page already touched, for [`ContourFollower::recycle`]
    /// before the first steps of a drag, which would otherwise fault in
    /// fresh pages (see [`crate::pages`]).
    pub fn spare(arc: ArcId, vertices: usize, triangles: usize) -> Self {
        Self {
            positions: crate::pages::spare(vertices),
            normals: crate::pages::spare(vertices),
            indices: crate::pages::spare(3 * triangles),
            ..Self::empty(arc, f64::NAN)
        }
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// The mesh up to the order of its vertices and triangles: each
    /// oriented triangle by its corners' positions (their bits), turned to
    /// start at its least corner, all sorted. Two ways of extracting a
    /// contour give the same mesh when these are equal.
    pub fn triangle_soup(&self) -> Vec<[[u32; 3]; 3]> {
        let mut soup: Vec<[[u32; 3]; 3]> = self
            .indices
            .chunks_exact(3)
            .map(|t| {
                let p = [0, 1, 2].map(|i| self.positions[t[i] as usize].map(f32::to_bits));
                let k = (0..3).min_by_key(|&k| p[k]).unwrap_or(0);
                [p[k], p[(k + 1) % 3], p[(k + 2) % 3]]
            })
            .collect();
        soup.sort_unstable();
        soup
    }

    /// Six times the signed volume the mesh encloses (the divergence
    /// theorem, about the first vertex for precision); positive
    /// when a closed mesh's triangles wind counter-clockwise seen from
    /// outside.
    pub fn signed_volume6(&self) -> f64 {
        let Some(&o) = self.positions.first() else {
            return 0.0;
        };
        let p = |i: u32| {
            let q = self.positions[i as usize];
            [0, 1, 2].map(|k| f64::from(q[k]) - f64::from(o[k]))
        };
        self.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [p(t[0]), p(t[1]), p(t[2])];
                a[0] * (b[1] * c[2] - b[2] * c[1])
                    + a[1] * (b[2] * c[0] - b[0] * c[2])
                    + a[2] * (b[0] * c[1] - b[1] * c[0])
            })
            .sum()
    }

    /// Orients a closed contour outward for export: when it encloses a
    /// negative signed volume (a contour around a minimum, whose downhill
    /// normals point in), its triangles are rewound and its normals
    /// negated, so every closed contour has positive signed volume and
    /// normals pointing out of the region it encloses. An open contour (one
    /// that touches the volume's boundary encloses nothing) keeps the
    /// engine's convention: normals downhill, towards lower values.
    pub fn orient_outward(&mut self) {
        if self.touches_boundary
            || self
                .ccw_outward
                .unwrap_or_else(|| self.signed_volume6() >= 0.0)
        {
            return;
        }
        self.ccw_outward = Some(true);
        for t in self.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        for n in &mut self.normals {
            *n = n.map(|x| -x);
        }
    }

    /// Moves a mesh made in the grid frame of `field` into `frame`:
    /// positions and normals (by the inverse transpose, so they stay
    /// perpendicular), and the triangles rewound when the move is a
    /// reflection, so each keeps facing the same side of the surface.
    pub fn to_frame(&mut self, field: &ScalarField, frame: Frame) {
        let spacing = field.spacing();
        let g = field.geometry();
        let f64s = |p: [f32; 3]| p.map(f64::from);
        let f32s = |p: [f64; 3]| p.map(|x| x as f32);
        if frame != Frame::Grid {
            self.bounds = None;
        }
        match frame {
            Frame::Grid => {}
            Frame::Index => {
                for p in &mut self.positions {
                    *p = f32s(std::array::from_fn(|a| f64::from(p[a]) / spacing[a]));
                }
                for n in &mut self.normals {
                    let m: [f64; 3] = std::array::from_fn(|a| f64::from(n[a]) * spacing[a]);
                    let l = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
                    if l > 0.0 {
                        *n = f32s(m.map(|x| x / l));
                    }
                }
            }
            Frame::World => {
                for p in &mut self.positions {
                    *p = f32s(g.to_world(f64s(*p)));
                }
                for n in &mut self.normals {
                    *n = f32s(g.normal_to_world(f64s(*n)));
                }
                if g.is_reflection() {
                    for t in self.indices.chunks_exact_mut(3) {
                        t.swap(1, 2);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::field::Values;
    use crate::progress::Progress;
    use crate::tree::ContourTree;
    use proptest::prelude::*;

    /// A random grid of small integers: many vertices lie exactly on any
    /// integer isovalue.
    fn grid() -> impl Strategy<Value = ScalarField> {
        (2usize..7, 2usize..7, 2usize..6).prop_flat_map(|(x, y, z)| {
            proptest::collection::vec(0u8..5, x * y * z)
                .prop_map(move |v| ScalarField::new([x, y, z], Values::U8(v)).unwrap())
        })
    }

    /// How many positions of `meshes` repeat one before them (float32 bit
    /// for bit, as a reader merging vertices sees them).
    fn repeated_positions<'a>(meshes: impl Iterator<Item = &'a ContourMesh>) -> usize {
        let mut keys: Vec<[u32; 3]> = meshes
            .flat_map(|m| m.positions.iter().map(|p| p.map(f32::to_bits)))
            .collect();
        let len = keys.len();
        keys.sort_unstable();
        keys.dedup();
        len - keys.len()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// At an isovalue equal to data values (every vertex of value `h`
        /// lies below the cut): no triangle of zero area, no two mesh
        /// vertices at one place (within a contour or between the
        /// contours at `h`), every contour a consistently oriented
        /// manifold; orienting makes every closed contour enclose a
        /// positive volume. (Its Euler characteristic against the tree's
        /// prediction: `tests/contour_properties.rs`.)
        #[test]
        fn cuts_at_data_values_give_no_zero_area_triangle_and_closed_contours_face_out(
            field in grid(),
            h in 0u8..5,
        ) {
            let (tree, _) = ContourTree::from_field(&field, &Progress::new()).unwrap();
            let mut all = global::all_contours(&tree, &field, Isovalue::new(f64::from(h)));
            prop_assert_eq!(repeated_positions(all.iter()), 0);
            for m in &mut all {
                for t in m.indices.chunks_exact(3) {
                    prop_assert!(topology::triangle_area(&m.positions, t) > 0.0, "a zero-area triangle {:?} in {:?}", t, m.arc);
                }
                let before = MeshTopology::of(&m.positions, &m.indices);
                prop_assert_eq!(before.non_manifold_edges, 0);
                prop_assert_eq!(before.non_manifold_vertices, 0);
                prop_assert_eq!(before.misoriented_edges, 0);
                m.orient_outward();
                let oriented = MeshTopology::of(&m.positions, &m.indices);
                prop_assert_eq!(oriented.misoriented_edges, 0);
                prop_assert_eq!(oriented.euler, before.euler);
                if !m.touches_boundary && !m.indices.is_empty() {
                    prop_assert!(oriented.is_closed());
                    let v = m.signed_volume6();
                    prop_assert!(v > 0.0, "closed contour faces in: {}", v);
                }
            }
        }
    }

    #[test]
    fn a_cut_exactly_through_a_plane_of_vertices_passes_beside_them() {
        // A ramp along x with integer values: the level set x = 2 passes
        // through a plane of vertices, every one regular. Interpolated
        // without the margin, each crossed edge from the plane would put
        // its contour vertex on a vertex of the plane.
        let n = 5;
        let v: Vec<u8> = (0..n * n * n).map(|i| (i % n) as u8).collect();
        let field = ScalarField::new([n; 3], Values::U8(v)).unwrap();
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).unwrap();
        let all = global::all_contours(&tree, &field, Isovalue::new(2.0));
        assert_eq!(all.len(), 1);
        let m = &all[0];
        assert!(m.num_triangles() > 0);
        assert!(
            m.indices
                .chunks_exact(3)
                .all(|t| topology::triangle_area(&m.positions, t) > 0.0)
        );
        assert_eq!(repeated_positions(std::iter::once(m)), 0);
        // The plane x = 2 (a disk cut by the box), within the margin.
        for p in &m.positions {
            assert!(
                (f64::from(p[0]) - 2.0).abs() <= marching::EDGE_MARGIN + 1e-6,
                "{p:?}"
            );
            assert!(
                f64::from(p[0]) > 2.0,
                "beside the plane, on its upper side: {p:?}"
            );
        }
        let t = MeshTopology::of(&m.positions, &m.indices);
        assert_eq!((t.euler, t.components, t.boundary_loops), (1, 1, 1));
    }
}
