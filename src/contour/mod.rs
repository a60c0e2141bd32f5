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
//! tile the level set without holes. A vertex at exactly `h` lies below, so
//! its contour vertices may coincide with it (zero-area triangles that keep
//! the mesh a combinatorial manifold).
//!
//! **Orientation.** Triangles wind counter-clockwise seen from the *lower*
//! side: their normals point downhill, towards lower values, i.e. outwards
//! around a maximum (a bright organ in a scan, a blob). Vertex normals are
//! the field's downhill gradient, or the area-weighted triangle normal
//! where the gradient vanishes or disagrees (see [`follow`]).
//!
//! Only 3D grids (every axis at least 2 vertices) have tetrahedra; a 2D
//! image yields empty contours.

pub mod export;
pub mod follow;
pub mod global;
#[doc(hidden)]
pub mod oracle;
pub mod seed;
mod sweep;
pub mod topology;

#[doc(no_inline)]
pub use crate::field::Isovalue;
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
    /// Vertex positions, one per crossed mesh edge.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, pointing towards lower values.
    pub normals: Vec<[f32; 3]>,
    /// Three indices per triangle, counter-clockwise seen from below.
    pub indices: Vec<u32>,
    /// True when the contour reaches the volume's boundary (it is then an
    /// open surface, cut by the box).
    pub touches_boundary: bool,
}

impl ContourMesh {
    /// An empty contour of `arc`.
    pub fn empty(arc: ArcId) -> Self {
        Self {
            arc,
            positions: Vec::new(),
            normals: Vec::new(),
            indices: Vec::new(),
            touches_boundary: false,
        }
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.indices.len() / 3
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
