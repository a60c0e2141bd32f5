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
    /// The coincident vertices joined by mesh edges form clusters, and
    /// each cluster is decided on its own, by a local check: it collapses
    /// to one vertex (its zero-area triangles vanish) when
    ///
    /// 1. its Euler characteristic is 1 (the part of the mesh inside it is
    ///    a disk, the star of a vertex regular at the cut), and
    /// 2. the link of the vertex it would become is one cycle (an interior
    ///    vertex) or one path (on the mesh's boundary): the triangles with
    ///    exactly one corner in the cluster, each seen as the edge opposite
    ///    that corner, join up with every link vertex on at most two of
    ///    them and no edge twice, and
    /// 3. the cluster's star (its triangles, as the collapses before left
    ///    them) and the cone the collapse makes of it are the same surface:
    ///    the same Euler characteristic and number of boundary loops, no
    ///    edge on three triangles. A cluster holding a whole boundary loop
    ///    (the hole a contour makes where it meets the volume's side at a
    ///    vertex of the isovalue) would close it; one touching the
    ///    boundary twice would pinch it.
    ///
    /// Collapsing a disk is a sequence of edge contractions; (2) is the
    /// link condition (Dey, Edelsbrunner, Guha & Nekhayev, "Topology
    /// preserving edge contraction", 1999) for the whole sequence: a
    /// neighbour reached from two places of the cluster would show twice
    /// in the link (its edge to the new vertex on four triangles), two
    /// triangles becoming one shows as an edge twice, an annulus as a link
    /// in two pieces. Clusters are decided in turn, each against the mesh
    /// as the collapses before it left it; a cluster refused because its
    /// link held a neighbouring cluster's zero-area edges is asked again
    /// after that neighbour collapsed (rounds until one collapses nothing).
    ///
    /// What stays unwelded, with its zero-area triangles, includes what no
    /// welding can flatten without changing the topology the tree
    /// predicts: a whole contour shrunk to one point (the contour of a
    /// minimum or maximum whose value is the isovalue: a sphere of no
    /// size) and the tube or pinch around a saddle whose value is the
    /// isovalue. Two clusters at one place (two sheets touching at such a
    /// saddle) stay two vertices: welding them would make the mesh
    /// non-manifold. The topology is checked afterwards and the whole weld
    /// of the contour undone should it have changed.
    ///
    /// Not yet complete: the three checks are not the exact condition.
    /// Some clusters they refuse could be collapsed alone without changing
    /// the topology (an oracle that collapses each leftover cluster and
    /// recounts the whole mesh finds them on random grids), and on some
    /// contours they accept a collapse the final check then undoes, with
    /// the rest of that contour's weld. Measured on colin27_ch2 at `--iso
    /// 64` (a data value): zero-area triangles 419,767 in 527 contours
    /// before (403,909 in the head, whose weld was undone whole), 50,460
    /// in 528 after (36,524 in the head).
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
        let mut size = vec![0u32; n];
        for &r in &roots {
            chi[r as usize] += 1;
            size[r as usize] += 1;
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
        drop(edges);
        let clustered = |v: u32| size[roots[v as usize] as usize] > 1;
        // The triangles around each clustered vertex, and the members of
        // each cluster (compressed rows, by root).
        let rows = |keys: &mut dyn Iterator<Item = (u32, u32)>| -> (Vec<u32>, Vec<u32>) {
            let pairs: Vec<(u32, u32)> = keys.collect();
            let mut start = vec![0u32; n + 1];
            for &(k, _) in &pairs {
                start[k as usize + 1] += 1;
            }
            for i in 0..n {
                start[i + 1] += start[i];
            }
            let mut fill = start.clone();
            let mut items = vec![0u32; pairs.len()];
            for (k, x) in pairs {
                items[fill[k as usize] as usize] = x;
                fill[k as usize] += 1;
            }
            (start, items)
        };
        let (tri_start, tris) = rows(
            &mut self
                .indices
                .iter()
                .enumerate()
                .filter_map(|(c, &v)| clustered(v).then_some((v, (c / 3) as u32))),
        );
        let (member_start, members) = rows(
            &mut (0..n as u32)
                .filter(|&v| clustered(v))
                .map(|v| (roots[v as usize], v)),
        );
        // Decide the clusters in turn; `target` maps every vertex to the
        // vertex it has become so far. A cluster's link may hold the
        // zero-area edges of a neighbouring cluster not yet collapsed (a
        // link in pieces that the neighbour's collapse joins), so the
        // refused are asked again, round after round, until a round
        // collapses nothing.
        let mut target: Vec<u32> = (0..n as u32).collect();
        // The triangles around clustered vertex `c`, as their corners.
        let star = |c: u32| {
            tris[tri_start[c as usize] as usize..tri_start[c as usize + 1] as usize]
                .iter()
                .map(|&t| &self.indices[3 * t as usize..3 * t as usize + 3])
        };
        let mut link: Vec<(u32, u32)> = Vec::new();
        let (mut region, mut collapsed): (Vec<[u32; 3]>, Vec<[u32; 3]>) = (Vec::new(), Vec::new());
        let mut pending: Vec<usize> = (0..n)
            .filter(|&r| size[r] >= 2 && roots[r] == r as u32 && chi[r] == 1)
            .collect();
        loop {
            let before = pending.len();
            pending.retain(|&r| {
                let cluster = &members[member_start[r] as usize..member_start[r + 1] as usize];
                link.clear();
                for &c in cluster {
                    for t in star(c) {
                        let inside = |v: u32| roots[v as usize] == r as u32;
                        if t.iter().filter(|&&v| inside(v)).count() != 1 {
                            continue;
                        }
                        // The edge opposite c, as the collapses so far
                        // left it (gone when it became a point).
                        let k = t.iter().position(|&v| v == c).unwrap_or(0);
                        let a = target[t[(k + 1) % 3] as usize];
                        let b = target[t[(k + 2) % 3] as usize];
                        if a != b {
                            link.push((a.min(b), a.max(b)));
                        }
                    }
                }
                // The star of the cluster and what the collapse makes of
                // it must be the same surface: a cluster holding a whole
                // boundary loop (the hole a contour makes where it meets
                // the volume's side at a vertex of the isovalue) would
                // close it, one touching the boundary twice would pinch.
                region.clear();
                collapsed.clear();
                for &c in cluster {
                    for t in star(c) {
                        let m = [0, 1, 2].map(|k| target[t[k] as usize]);
                        if m[0] == m[1] || m[1] == m[2] || m[0] == m[2] {
                            continue;
                        }
                        // Once per triangle: from its first corner inside.
                        let first = t.iter().position(|&v| roots[v as usize] == r as u32);
                        if first.map(|k| t[k]) != Some(c) {
                            continue;
                        }
                        region.push(m);
                        let w = m.map(|v| {
                            if roots[v as usize] == r as u32 {
                                r as u32
                            } else {
                                v
                            }
                        });
                        if w[0] != w[1] && w[1] != w[2] && w[0] != w[2] {
                            collapsed.push(w);
                        }
                    }
                }
                let weld = link_shape(&mut link).is_some()
                    && surface_shape(&region).is_some()
                    && surface_shape(&region) == surface_shape(&collapsed);
                if weld {
                    for &c in cluster {
                        target[c as usize] = r as u32;
                    }
                }
                !weld
            });
            if pending.len() == before {
                break;
            }
        }
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

/// The Euler characteristic and the number of boundary loops of a small
/// patch of triangles, or None when an edge has more than two.
fn surface_shape(triangles: &[[u32; 3]]) -> Option<(i64, usize)> {
    let mut vertices: Vec<u32> = triangles.iter().flatten().copied().collect();
    vertices.sort_unstable();
    vertices.dedup();
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [0, 1, 2].map(|k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    let index = |v: u32| vertices.partition_point(|&u| u < v);
    let mut parent: Vec<usize> = (0..vertices.len()).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    let (mut distinct, mut boundary_vertices) = (0usize, Vec::new());
    let mut i = 0;
    while i < edges.len() {
        let j = i + edges[i..].partition_point(|&e| e == edges[i]);
        match j - i {
            1 => {
                let (a, b) = edges[i];
                boundary_vertices.extend([a, b]);
                let (ra, rb) = (root(&mut parent, index(a)), root(&mut parent, index(b)));
                if ra != rb {
                    parent[ra] = rb;
                }
            }
            2 => {}
            _ => return None,
        }
        distinct += 1;
        i = j;
    }
    boundary_vertices.sort_unstable();
    boundary_vertices.dedup();
    let mut loops: Vec<usize> = boundary_vertices
        .iter()
        .map(|&v| root(&mut parent, index(v)))
        .collect();
    loops.sort_unstable();
    loops.dedup();
    let euler = vertices.len() as i64 - distinct as i64 + triangles.len() as i64;
    Some((euler, loops.len()))
}

/// What the link of a vertex is, when it is that of a manifold vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LinkShape {
    /// One simple cycle: an interior vertex.
    Cycle,
    /// One simple path: a vertex on the boundary.
    Path,
}

/// The shape of the undirected edges `link` (sorted in place) when they
/// form one simple cycle or one simple path: no edge twice, every vertex
/// on at most two edges, connected, and none or two ends. An empty link
/// is neither.
fn link_shape(link: &mut [(u32, u32)]) -> Option<LinkShape> {
    if link.is_empty() {
        return None;
    }
    link.sort_unstable();
    if link.windows(2).any(|w| w[0] == w[1]) {
        return None;
    }
    let mut ends: Vec<u32> = link.iter().flat_map(|&(a, b)| [a, b]).collect();
    ends.sort_unstable();
    let mut vertices: Vec<(u32, u32)> = Vec::new(); // (vertex, degree)
    for v in ends {
        match vertices.last_mut() {
            Some((u, d)) if *u == v => *d += 1,
            _ => vertices.push((v, 1)),
        }
    }
    if vertices.iter().any(|&(_, d)| d > 2) {
        return None;
    }
    let loose = vertices.iter().filter(|&&(_, d)| d == 1).count();
    let shape = match loose {
        0 => LinkShape::Cycle,
        2 => LinkShape::Path,
        _ => return None,
    };
    // Degrees at most two make each piece a path or a cycle; one piece
    // (counted by a union-find) is what is wanted.
    let index = |v: u32| vertices.partition_point(|&(u, _)| u < v);
    let mut parent: Vec<usize> = (0..vertices.len()).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    let mut pieces = vertices.len();
    for &(a, b) in link.iter() {
        let (ra, rb) = (root(&mut parent, index(a)), root(&mut parent, index(b)));
        if ra != rb {
            parent[ra] = rb;
            pieces -= 1;
        }
    }
    (pieces == 1).then_some(shape)
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

    /// The clusters of `m`: coincident vertices joined by mesh edges, two
    /// or more each (the oracle's own flood, not the weld's union-find).
    fn clusters(m: &ContourMesh) -> Vec<Vec<u32>> {
        let n = m.positions.len();
        let mut adj = vec![Vec::new(); n];
        for t in m.indices.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a != b && m.positions[a as usize] == m.positions[b as usize] {
                    adj[a as usize].push(b);
                    adj[b as usize].push(a);
                }
            }
        }
        let mut seen = vec![false; n];
        let mut out = Vec::new();
        for s in 0..n {
            if seen[s] || adj[s].is_empty() {
                continue;
            }
            let (mut stack, mut c) = (vec![s as u32], Vec::new());
            seen[s] = true;
            while let Some(v) = stack.pop() {
                c.push(v);
                for &w in &adj[v as usize] {
                    if !seen[w as usize] {
                        seen[w as usize] = true;
                        stack.push(w);
                    }
                }
            }
            out.push(c);
        }
        out
    }

    /// The topology of `m` with the vertices of `cluster` made one (its
    /// triangles with two corners in it dropped).
    fn collapsed(m: &ContourMesh, cluster: &[u32]) -> MeshTopology {
        let r = cluster[0];
        let map = |v: u32| if cluster.contains(&v) { r } else { v };
        let mut indices = Vec::new();
        for t in m.indices.chunks_exact(3) {
            let t = [map(t[0]), map(t[1]), map(t[2])];
            if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                indices.extend_from_slice(&t);
            }
        }
        MeshTopology::of(&m.positions, &indices)
    }

    fn shape(t: &MeshTopology) -> (i64, usize, usize, usize, usize, usize) {
        (
            t.euler,
            t.components,
            t.boundary_loops,
            t.non_manifold_edges,
            t.non_manifold_vertices,
            t.misoriented_edges,
        )
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
                // Every zero-area triangle left has two corners at one
                // place, in a cluster that no weld can collapse: made one
                // alone, it would change the topology (the oracle: the
                // whole mesh's topology, not the weld's local check).
                for t in m.indices.chunks_exact(3) {
                    if area2(&m, t) == 0.0 {
                        let p = |i: u32| m.positions[i as usize];
                        prop_assert!(
                            p(t[0]) == p(t[1]) || p(t[1]) == p(t[2]) || p(t[0]) == p(t[2]),
                            "a zero-area triangle with three places: {:?}", t
                        );
                    }
                }
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

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// No cluster the weld leaves could be collapsed alone without
        /// changing the topology (the oracle recounts the whole mesh).
        /// Known gap, see [`ContourMesh::weld`]: the local checks refuse
        /// some such clusters; run with `--ignored` to see one.
        #[test]
        #[ignore = "known gap of the weld's local checks (see ContourMesh::weld)"]
        fn no_cluster_left_by_the_weld_could_be_welded_alone(
            field in grid(),
            h in 0u8..5,
        ) {
            let (tree, _) = ContourTree::from_field(&field, &Progress::new()).unwrap();
            for mut m in global::all_contours(&tree, &field, Isovalue::new(f64::from(h))) {
                m.weld();
                let after = MeshTopology::of(&m.positions, &m.indices);
                for c in clusters(&m) {
                    prop_assert_ne!(
                        shape(&collapsed(&m, &c)),
                        shape(&after),
                        "the cluster {:?} at {:?} could have been welded",
                        c,
                        m.positions[c[0] as usize]
                    );
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
