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
//! the mesh a combinatorial manifold); [`ContourMesh::weld`] merges them
//! for export where that keeps the topology, and
//! [`ContourMesh::orient_outward`] turns closed contours to face out.
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
pub mod marching;
#[doc(hidden)]
pub mod oracle;
pub mod section;
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

    /// Six times the signed volume the mesh encloses (the divergence
    /// theorem, about the first vertex for precision); positive
    /// when a closed mesh's triangles wind counter-clockwise seen from
    /// outside.
    fn signed_volume6(&self) -> f64 {
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
        if self.touches_boundary || self.signed_volume6() >= 0.0 {
            return;
        }
        for t in self.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        for n in &mut self.normals {
            *n = n.map(|x| -x);
        }
    }

    /// Welds the vertices that a cut exactly at a vertex value put at one
    /// position (see the module doc: a vertex at the isovalue lies below,
    /// so every crossed edge from it yields a mesh vertex at its place, and
    /// the triangles between them have no area).
    ///
    /// The coincident vertices joined by mesh edges form clusters; a
    /// cluster whose Euler characteristic is 1 (a disk, the star of a
    /// regular vertex) collapses to one vertex and its zero-area triangles
    /// vanish. That is an edge contraction of a disk, which keeps the
    /// surface and its topology; anything else (the cluster at a saddle
    /// exactly at the isovalue, an annulus or several sheets meeting at a
    /// point, where welding would pinch the surface) is left as it is.
    /// The topology is checked afterwards and the weld undone should it
    /// have changed, so the result always has the Euler characteristic,
    /// boundary and manifoldness the tree predicts.
    ///
    /// The check and the undo are for the whole mesh, not per cluster: one
    /// cluster whose collapse would change the topology (a disk by its own
    /// count whose collapse still glues two sheets, or makes an edge
    /// shared by three triangles) keeps *every* cluster of that contour
    /// unwelded. Such a contour is exported with its zero-area triangles
    /// and coincident vertices, as the follower made it (still manifold,
    /// with the predicted topology). Measured on colin27_ch2 at `--iso 64`
    /// (a data value): 1240 of 1767 contours welded clean; 527 kept
    /// 419,767 zero-area triangles, 403,909 of them in the largest contour
    /// (5.36 M triangles). Welding cluster by cluster needs the link
    /// condition checked locally for each collapse; not done yet.
    pub fn weld(&mut self) {
        let n = self.positions.len();
        if n == 0 {
            return;
        }
        let key = |i: usize| self.positions[i].map(f32::to_bits);
        // Union coincident vertices along the mesh's edges.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        }
        let mut any = false;
        for t in self.indices.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a != b && key(a as usize) == key(b as usize) {
                    let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                    if ra != rb {
                        parent[ra as usize] = rb;
                    }
                    any = true;
                }
            }
        }
        if !any {
            return;
        }
        // Each cluster's Euler characteristic: V - E + F of the part of
        // the mesh inside it.
        let roots: Vec<u32> = (0..n as u32).map(|v| find(&mut parent, v)).collect();
        let mut chi = vec![0i64; n];
        for &r in &roots {
            chi[r as usize] += 1;
        }
        let mut edges: Vec<(u32, u32)> = Vec::new();
        for t in self.indices.chunks_exact(3) {
            let inside = |a: u32, b: u32| roots[a as usize] == roots[b as usize];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if inside(a, b) {
                    edges.push((a.min(b), a.max(b)));
                }
            }
            if inside(t[0], t[1]) && inside(t[1], t[2]) {
                chi[roots[t[0] as usize] as usize] += 1;
            }
        }
        edges.sort_unstable();
        edges.dedup();
        for &(a, _) in &edges {
            chi[roots[a as usize] as usize] -= 1;
        }
        // Collapse the disks: every vertex of one to its root.
        let target: Vec<u32> = (0..n)
            .map(|v| {
                let r = roots[v];
                if chi[r as usize] == 1 { r } else { v as u32 }
            })
            .collect();
        let before = MeshTopology::of(&self.positions, &self.indices);
        let mut indices = Vec::with_capacity(self.indices.len());
        for t in self.indices.chunks_exact(3) {
            let m = [
                target[t[0] as usize],
                target[t[1] as usize],
                target[t[2] as usize],
            ];
            if m[0] != m[1] && m[1] != m[2] && m[0] != m[2] {
                indices.extend_from_slice(&m);
            }
        }
        // Drop the vertices no triangle uses any more, keeping order.
        let mut used = vec![false; n];
        for &v in &indices {
            used[v as usize] = true;
        }
        let mut new_id = vec![u32::MAX; n];
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        for v in 0..n {
            if used[v] {
                new_id[v] = positions.len() as u32;
                positions.push(self.positions[v]);
                normals.push(self.normals.get(v).copied().unwrap_or([0.0; 3]));
            }
        }
        for v in &mut indices {
            *v = new_id[*v as usize];
        }
        let after = MeshTopology::of(&positions, &indices);
        let same = |t: &MeshTopology| {
            (
                t.euler,
                t.components,
                t.boundary_loops,
                t.non_manifold_edges,
                t.non_manifold_vertices,
                t.misoriented_edges,
            )
        };
        if same(&before) == same(&after) {
            self.positions = positions;
            self.normals = normals;
            self.indices = indices;
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

    fn area2(m: &ContourMesh, t: &[u32]) -> f64 {
        let p = |i: u32| m.positions[i as usize].map(f64::from);
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Welding keeps the topology, and where it welds leaves no
        /// triangle with two corners at one place; orienting makes every
        /// closed contour enclose a positive volume.
        #[test]
        fn welding_keeps_topology_and_orienting_makes_closed_contours_face_out(
            field in grid(),
            h in 0u8..5,
        ) {
            let (tree, _) = ContourTree::from_field(&field, &Progress::new()).unwrap();
            for mut m in global::all_contours(&tree, &field, Isovalue::new(f64::from(h))) {
                let before = MeshTopology::of(&m.positions, &m.indices);
                m.weld();
                let after = MeshTopology::of(&m.positions, &m.indices);
                prop_assert_eq!(before.euler, after.euler);
                prop_assert_eq!(before.components, after.components);
                prop_assert_eq!(before.boundary_loops, after.boundary_loops);
                prop_assert_eq!(after.non_manifold_edges, before.non_manifold_edges);
                prop_assert_eq!(after.misoriented_edges, 0);
                prop_assert_eq!(m.normals.len(), m.positions.len());
                m.orient_outward();
                let oriented = MeshTopology::of(&m.positions, &m.indices);
                prop_assert_eq!(oriented.misoriented_edges, 0);
                if !m.touches_boundary && !m.indices.is_empty() {
                    prop_assert!(oriented.is_closed());
                    // Positive, or zero for a contour flattened onto
                    // vertices at the isovalue (it encloses nothing).
                    let v = m.signed_volume6();
                    prop_assert!(v >= 0.0, "closed contour faces in: {}", v);
                }
            }
        }
    }

    #[test]
    fn a_cut_exactly_at_a_regular_vertex_is_welded_away() {
        // A ramp along x with integer values: the level set x = 2 passes
        // through a plane of vertices, every one regular.
        let n = 5;
        let v: Vec<u8> = (0..n * n * n).map(|i| (i % n) as u8).collect();
        let field = ScalarField::new([n; 3], Values::U8(v)).unwrap();
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).unwrap();
        let all = global::all_contours(&tree, &field, Isovalue::new(2.0));
        assert_eq!(all.len(), 1);
        let mut m = all.into_iter().next().unwrap();
        let zero = |m: &ContourMesh| {
            m.indices
                .chunks_exact(3)
                .filter(|t| area2(m, t) == 0.0)
                .count()
        };
        assert!(
            zero(&m) > 0,
            "the cut at the vertices makes zero-area triangles"
        );
        let before = MeshTopology::of(&m.positions, &m.indices);
        m.weld();
        assert_eq!(zero(&m), 0, "no zero-area triangle once welded");
        let mut keys: Vec<[u32; 3]> = m.positions.iter().map(|p| p.map(f32::to_bits)).collect();
        keys.sort_unstable();
        let len = keys.len();
        keys.dedup();
        assert_eq!(keys.len(), len, "no duplicate positions");
        let after = MeshTopology::of(&m.positions, &m.indices);
        assert_eq!(
            (after.euler, after.boundary_loops),
            (before.euler, before.boundary_loops)
        );
    }
}
