//! The simplicial mesh the contour tree is computed on.
//!
//! The engine only ever asks "which vertices share an edge with v"
//! ([`Mesh::for_each_neighbour`]); the grid implements it implicitly through
//! the Freudenthal (Kuhn) triangulation, which cuts every cube into six
//! tetrahedra around its main diagonal (0,0,0)-(1,1,1). Its edges are the
//! seven offsets ±(1,0,0), ±(0,1,0), ±(0,0,1), ±(1,1,0), ±(1,0,1), ±(0,1,1),
//! ±(1,1,1): 14 neighbours for an interior vertex in 3D, 6 in 2D (Z = 1),
//! 2 in 1D. Boundary vertices simply have fewer; nothing else is special.
//!
//! No edge list is stored: the mesh costs nothing per vertex.

use crate::field::{ScalarField, VertexOrder};
use strength_reduce::StrengthReducedU32;

/// A simplicial mesh as the contour tree engine sees it: vertices `0..n` and
/// the edges between them.
pub trait Mesh: Sync {
    /// Number of vertices.
    fn num_vertices(&self) -> usize;

    /// Calls `f` once for every vertex that shares an edge with `v`.
    fn for_each_neighbour(&self, v: u32, f: impl FnMut(u32));

    /// A bound on `|u - v|` over the edges: blocks of consecutive ids meet
    /// only within this distance of the cut between them (the divide and
    /// conquer's bands). The default, `n`, is always true and makes every
    /// vertex of a block a band vertex.
    fn edge_span(&self) -> usize {
        self.num_vertices()
    }

    /// Hints the memory system that `data[u]` will soon be read for the
    /// neighbours u of `v` (a sweep visits vertices in value order, far
    /// apart in memory, so overlapping these misses is most of its speed).
    /// The default does nothing.
    #[inline(always)]
    fn prefetch_star<T>(&self, _v: u32, _data: &[T]) {}

    /// A summary of v's upper link (low nibble: the neighbours `above`
    /// selects) and lower link (high nibble: the others), each
    /// [`LINK_EMPTY`], [`LINK_SEVERAL`] (two or more components, or a mesh
    /// that does not summarise), or the index of a neighbour in the single
    /// component, to be resolved with [`Mesh::neighbour_at`]. The default
    /// always says [`LINK_SEVERAL`], which sends the sweeps down their
    /// general path. A mesh that says [`LINK_EMPTY`] at all says it for
    /// every empty link: the extrema it counts bound the supernodes
    /// ([`crate::tree::sweep::Census::supernodes_at_most`]).
    #[inline(always)]
    fn link_code(&self, _v: u32, _above: impl FnMut(u32) -> bool) -> u8 {
        LINK_SEVERAL | LINK_SEVERAL << 4
    }

    /// [`Mesh::link_code`] of the vertices `first ..` (one per byte of
    /// `out`) in id order, each upper link taken in `order`.
    fn link_codes_into<O: VertexOrder + ?Sized>(&self, order: &O, first: u32, out: &mut [u8]) {
        for (i, code) in out.iter_mut().enumerate() {
            let v = first + i as u32;
            *code = self.link_code(v, |u| order.above(u, v));
        }
    }

    /// The neighbour of `v` named by a [`Mesh::link_code`] index.
    fn neighbour_at(&self, v: u32, _index: u8) -> u32 {
        v
    }

    /// Calls `f` with one neighbour of `v` from each connected component of
    /// the part of v's link made of the neighbours `in_set` selects (the
    /// upper or lower link). The sweeps need one union-find lookup per
    /// component, not per neighbour: neighbours joined by a link edge were
    /// already united when the later of them was swept. This default visits
    /// every selected neighbour, which is correct, only slower.
    fn for_each_link_component(
        &self,
        v: u32,
        in_set: impl FnMut(u32) -> bool,
        mut f: impl FnMut(u32),
    ) {
        let mut in_set = in_set;
        self.for_each_neighbour(v, |u| {
            if in_set(u) {
                f(u)
            }
        });
    }
}

/// [`Mesh::link_code`]: no neighbour of the link part.
pub const LINK_EMPTY: u8 = 14;
/// [`Mesh::link_code`]: several components (or not summarised).
pub const LINK_SEVERAL: u8 = 15;

/// The 7 positive Freudenthal edge offsets (dx, dy, dz); their negatives are
/// the other 7.
pub const EDGE_OFFSETS: [[i64; 3]; 7] = [
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 1, 0],
    [1, 0, 1],
    [0, 1, 1],
    [1, 1, 1],
];

/// The six tetrahedra of a unit cube, as corner bit masks (bit 0 = +x,
/// bit 1 = +y, bit 2 = +z). Each is the monotone path 0 -> e_i -> e_i+e_j
/// -> 7 for one permutation (i, j, k), so every tetrahedron contains the
/// main diagonal and all its edges are Freudenthal edges.
pub const CUBE_TETRAHEDRA: [[u8; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// The Freudenthal triangulation of a regular grid, implicit.
#[derive(Clone, Debug)]
pub struct FreudenthalGrid {
    dims: [usize; 3],
    /// Linear-id offsets of the 14 neighbours of an interior vertex.
    interior_offsets: Vec<i64>,
    /// Offsets (dx, dy, dz) of all neighbours that exist in this grid's
    /// dimension (14, 6 or 2).
    directions: Vec<[i64; 3]>,
    div_x: StrengthReducedU32,
    div_y: StrengthReducedU32,
    /// For every subset (bit mask over `directions`) of a vertex's link, the
    /// representatives of its connected components (see [`LinkTable`]).
    link: LinkTable,
}

/// Connected components of every subset of the link of a grid vertex.
///
/// Two neighbours v+a and v+b are joined in the link iff (v, v+a, v+b) is a
/// triangle, which in the Freudenthal triangulation holds iff a - b is also
/// an edge offset (the three points then form a chain of the cube lattice).
/// Entry `mask`: number of components in the low 4 bits, then the direction
/// index (4 bits) of one representative per component.
#[derive(Clone, Debug)]
struct LinkTable {
    entries: Vec<u64>,
    /// Per mask, the nibble of [`Mesh::link_code`]: [`LINK_EMPTY`], the
    /// representative of the single component, or [`LINK_SEVERAL`]. One
    /// byte per entry keeps the table in L1 for the link pass.
    codes: Vec<u8>,
}

impl LinkTable {
    fn new(directions: &[[i64; 3]]) -> Self {
        let k = directions.len();
        let is_offset = |d: [i64; 3]| {
            EDGE_OFFSETS
                .iter()
                .any(|o| *o == d || [-o[0], -o[1], -o[2]] == d)
        };
        let adjacent: Vec<u32> = (0..k)
            .map(|i| {
                (0..k)
                    .filter(|&j| {
                        let (a, b) = (directions[i], directions[j]);
                        j != i && is_offset([a[0] - b[0], a[1] - b[1], a[2] - b[2]])
                    })
                    .fold(0u32, |m, j| m | 1 << j)
            })
            .collect();
        let entries = (0u32..1 << k)
            .map(|mask| {
                let (mut left, mut count, mut entry) = (mask, 0u64, 0u64);
                while left != 0 {
                    let rep = left.trailing_zeros();
                    // Flood the component of `rep` within `mask`.
                    let mut comp = 1u32 << rep;
                    loop {
                        let grown = (0..k as u32)
                            .filter(|&i| comp & (1 << i) != 0)
                            .fold(comp, |c, i| c | (adjacent[i as usize] & mask));
                        if grown == comp {
                            break;
                        }
                        comp = grown;
                    }
                    left &= !comp;
                    entry |= (rep as u64) << (4 + 4 * count);
                    count += 1;
                }
                entry | count
            })
            .collect::<Vec<u64>>();
        let codes = entries
            .iter()
            .map(|&entry| match entry & 0xf {
                0 => LINK_EMPTY,
                1 => ((entry >> 4) & 0xf) as u8,
                _ => LINK_SEVERAL,
            })
            .collect();
        Self { entries, codes }
    }
}

impl ScalarField {
    /// The Freudenthal triangulation of this field's grid (defined here,
    /// beside the mesh, so the field knows nothing of meshes).
    pub fn mesh(&self) -> FreudenthalGrid {
        FreudenthalGrid::new(self.dims())
    }
}

impl FreudenthalGrid {
    /// The triangulation of a grid of `dims` vertices. Axes of size 1 are
    /// dropped, so a (X, Y, 1) grid is the 2D triangulation.
    pub fn new(dims: [usize; 3]) -> Self {
        let mut directions = Vec::new();
        for o in EDGE_OFFSETS {
            // An offset along an axis of size 1 leaves the grid everywhere.
            if (0..3).all(|a| o[a] == 0 || dims[a] > 1) {
                directions.push(o);
                directions.push([-o[0], -o[1], -o[2]]);
            }
        }
        let (sx, sy) = (1i64, dims[0] as i64);
        let sz = sy * dims[1] as i64;
        let interior_offsets = directions
            .iter()
            .map(|d| d[0] * sx + d[1] * sy + d[2] * sz)
            .collect();
        Self {
            dims,
            interior_offsets,
            div_x: StrengthReducedU32::new(dims[0].max(1) as u32),
            div_y: StrengthReducedU32::new(dims[1].max(1) as u32),
            link: LinkTable::new(&directions),
            directions,
        }
    }

    /// Grid dimensions.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// (x, y, z) of vertex `v`, without hardware division.
    #[inline]
    pub fn coords(&self, v: u32) -> [u32; 3] {
        let (yz, x) = StrengthReducedU32::div_rem(v, self.div_x);
        let (z, y) = StrengthReducedU32::div_rem(yz, self.div_y);
        [x, y, z]
    }

    /// The vertex id at (x, y, z).
    #[inline]
    pub fn vertex(&self, x: usize, y: usize, z: usize) -> u32 {
        (x + self.dims[0] * (y + self.dims[1] * z)) as u32
    }

    /// The neighbour offsets (dx, dy, dz) of this grid.
    pub fn directions(&self) -> &[[i64; 3]] {
        &self.directions
    }

    /// Bit mask over [`Self::directions`] of the neighbours that exist at `v`.
    #[inline]
    pub fn present_directions(&self, v: u32) -> u32 {
        self.present(v)
    }

    /// The connected components of a part of a vertex's link given as a bit
    /// mask over [`Self::directions`]: calls `f` with the direction index of
    /// one neighbour per component and returns the number of components.
    /// For engines that classify links from their own comparisons.
    #[inline]
    pub fn link_components(&self, mask: u32, mut f: impl FnMut(u8)) -> u32 {
        let entry = self.link.entries[mask as usize];
        for c in 0..(entry & 0xf) {
            f(((entry >> (4 + 4 * c)) & 0xf) as u8);
        }
        (entry & 0xf) as u32
    }
}

impl FreudenthalGrid {
    /// Bit mask over `directions` of the neighbours that exist at `v`.
    #[inline(always)]
    fn present(&self, v: u32) -> u32 {
        let [x, y, z] = self.coords(v);
        let [dx, dy, dz] = self.dims.map(|d| d as u32);
        let inside = |c: u32, d: u32| d == 1 || (c > 0 && c + 1 < d);
        let all = (1u32 << self.directions.len()) - 1;
        if inside(x, dx) && inside(y, dy) && inside(z, dz) {
            return all;
        }
        let c = [x as i64, y as i64, z as i64];
        let mut mask = 0;
        for (i, d) in self.directions.iter().enumerate() {
            if (0..3).all(|a| {
                let n = c[a] + d[a];
                n >= 0 && n < self.dims[a] as i64
            }) {
                mask |= 1 << i;
            }
        }
        mask
    }
}

impl Mesh for FreudenthalGrid {
    fn num_vertices(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// The longest edge in ids: (1, 1, 1), one plane, one row and one step.
    fn edge_span(&self) -> usize {
        self.interior_offsets
            .iter()
            .map(|o| o.unsigned_abs() as usize)
            .max()
            .unwrap_or(0)
    }

    #[inline(always)]
    fn link_code(&self, v: u32, mut above: impl FnMut(u32) -> bool) -> u8 {
        let present = self.present(v);
        let mut up = 0u32;
        for (i, &o) in self.interior_offsets.iter().enumerate() {
            if present & (1 << i) != 0 && above((v as i64 + o) as u32) {
                up |= 1 << i;
            }
        }
        self.link.codes[up as usize] | self.link.codes[(present & !up) as usize] << 4
    }

    /// Walks the grid row by row in id order. The interior part of a row
    /// (nearly every vertex) is classified a run at a time: the masks of
    /// its upper links by [`VertexOrder::above_masks`] (one vector compare
    /// per neighbour offset), then two table lookups per vertex; vertices
    /// on the boundary take [`Mesh::link_code`].
    fn link_codes_into<O: VertexOrder + ?Sized>(&self, order: &O, first: u32, out: &mut [u8]) {
        const RUN: usize = 512;
        let [dx, dy, dz] = self.dims.map(|d| d as u32);
        let inside = |c: u32, d: u32| d == 1 || (c > 0 && c + 1 < d);
        // The interior x range of a row.
        let (x_lo, x_hi) = if dx == 1 { (0, 1) } else { (1, dx - 1) };
        let all = (1u32 << self.directions.len()) - 1;
        let mut masks = [0u16; RUN];
        let mut i = 0usize;
        while i < out.len() {
            let v = first + i as u32;
            let [x, y, z] = self.coords(v);
            // This row's part of `out`: vertices v .. v + row.
            let row = ((dx - x) as usize).min(out.len() - i);
            let (lo, hi) = if inside(y, dy) && inside(z, dz) {
                let lo = x_lo.max(x).min(x + row as u32);
                (lo, x_hi.min(x + row as u32).max(lo))
            } else {
                (x, x)
            };
            let boundary = |xs: std::ops::Range<u32>, out: &mut [u8]| {
                for xx in xs {
                    let u = v + (xx - x);
                    out[i + (xx - x) as usize] = self.link_code(u, |w| order.above(w, u));
                }
            };
            boundary(x..lo, out);
            let mut s = lo;
            while s < hi {
                let e = hi.min(s + RUN as u32);
                let run = &mut masks[..(e - s) as usize];
                order.above_masks(v + (s - x), &self.interior_offsets, run);
                let at = i + (s - x) as usize;
                for (code, &up) in out[at..at + run.len()].iter_mut().zip(run.iter()) {
                    let up = up as u32;
                    *code =
                        self.link.codes[up as usize] | self.link.codes[(all & !up) as usize] << 4;
                }
                s = e;
            }
            boundary(hi.max(lo)..x + row as u32, out);
            i += row;
        }
    }

    #[inline(always)]
    fn neighbour_at(&self, v: u32, index: u8) -> u32 {
        (v as i64 + self.interior_offsets[index as usize]) as u32
    }

    #[inline(always)]
    fn prefetch_star<T>(&self, v: u32, data: &[T]) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let sy = self.dims[0] as isize;
            let sz = sy * self.dims[1] as isize;
            // The star spans these 7 rows; one line each covers x-1..x+1
            // but at line boundaries.
            for o in [0, sy, -sy, sz, -sz, sz + sy, -sz - sy] {
                let i = v as isize + o;
                if i >= 0 && (i as usize) < data.len() {
                    // SAFETY: prefetch is a hint and never faults; the
                    // address is inside `data` anyway.
                    unsafe { _mm_prefetch(data.as_ptr().offset(i) as *const i8, _MM_HINT_T0) };
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (v, data);
    }

    #[inline(always)]
    fn for_each_link_component(
        &self,
        v: u32,
        mut in_set: impl FnMut(u32) -> bool,
        mut f: impl FnMut(u32),
    ) {
        let present = self.present(v);
        let mut mask = 0usize;
        for (i, &o) in self.interior_offsets.iter().enumerate() {
            if present & (1 << i) != 0 && in_set((v as i64 + o) as u32) {
                mask |= 1 << i;
            }
        }
        let entry = self.link.entries[mask];
        for c in 0..(entry & 0xf) {
            let rep = (entry >> (4 + 4 * c)) & 0xf;
            f((v as i64 + self.interior_offsets[rep as usize]) as u32);
        }
    }

    #[inline(always)]
    fn for_each_neighbour(&self, v: u32, mut f: impl FnMut(u32)) {
        let [x, y, z] = self.coords(v);
        let [dx, dy, dz] = self.dims.map(|d| d as u32);
        // Interior test per axis; an axis of size 1 never constrains since
        // its offsets were dropped.
        let inside = |c: u32, d: u32| d == 1 || (c > 0 && c + 1 < d);
        if inside(x, dx) && inside(y, dy) && inside(z, dz) {
            for &o in &self.interior_offsets {
                f((v as i64 + o) as u32);
            }
            return;
        }
        let c = [x as i64, y as i64, z as i64];
        for (d, &o) in self.directions.iter().zip(&self.interior_offsets) {
            let ok = (0..3).all(|a| {
                let n = c[a] + d[a];
                n >= 0 && n < self.dims[a] as i64
            });
            if ok {
                f((v as i64 + o) as u32);
            }
        }
    }
}

/// An explicit simplicial mesh given by its edge list, for tests and for
/// meshes that are not grids.
#[derive(Clone, Debug)]
pub struct EdgeListMesh {
    offsets: Vec<usize>,
    neighbours: Vec<u32>,
    span: usize,
}

impl EdgeListMesh {
    /// A mesh of `n` vertices with the given undirected edges.
    pub fn new(n: usize, edges: &[(u32, u32)]) -> Self {
        let mut deg = vec![0usize; n + 1];
        for &(a, b) in edges {
            deg[a as usize + 1] += 1;
            deg[b as usize + 1] += 1;
        }
        for i in 1..=n {
            deg[i] += deg[i - 1];
        }
        let mut fill = deg.clone();
        let mut neighbours = vec![0u32; deg[n]];
        for &(a, b) in edges {
            neighbours[fill[a as usize]] = b;
            fill[a as usize] += 1;
            neighbours[fill[b as usize]] = a;
            fill[b as usize] += 1;
        }
        let span = edges
            .iter()
            .map(|&(a, b)| a.abs_diff(b) as usize)
            .max()
            .unwrap_or(0);
        Self {
            offsets: deg,
            neighbours,
            span,
        }
    }
}

impl Mesh for EdgeListMesh {
    fn num_vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    fn edge_span(&self) -> usize {
        self.span
    }

    fn for_each_neighbour(&self, v: u32, mut f: impl FnMut(u32)) {
        let v = v as usize;
        for &u in &self.neighbours[self.offsets[v]..self.offsets[v + 1]] {
            f(u);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn neighbours(g: &FreudenthalGrid, v: u32) -> Vec<u32> {
        let mut out = Vec::new();
        g.for_each_neighbour(v, |u| out.push(u));
        out.sort_unstable();
        out
    }

    /// The row walk's codes against [`Mesh::link_code`] per vertex, from
    /// `first` for `len` vertices.
    fn assert_row_walk<O: VertexOrder + ?Sized>(
        g: &FreudenthalGrid,
        values: &O,
        first: usize,
        len: usize,
    ) {
        let expected: Vec<u8> = (first..first + len)
            .map(|v| g.link_code(v as u32, |u| values.above(u, v as u32)))
            .collect();
        let mut out = vec![0u8; len];
        g.link_codes_into(values, first as u32, &mut out);
        assert_eq!(out, expected, "{:?} from {first}, {len} vertices", g.dims());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]
        /// Any grid (rows longer than a run of the vectorised pass, 2D and
        /// 1D grids), any span of vertices, and values with heavy ties,
        /// NaN, -0.0 and 0.0: the vectorised compares give the codes the
        /// vertex order gives.
        #[test]
        fn row_walk_link_codes_equal_per_vertex_codes(
            dims in (1usize..1100, 1usize..6, 1usize..5),
            seed in proptest::prelude::any::<u64>(),
            levels in 1u32..6,
            span in (0.0f64..1.0, 0.0f64..1.0),
        ) {
            let dims = [dims.0, dims.1, dims.2];
            let g = FreudenthalGrid::new(dims);
            let n = g.num_vertices();
            let first = ((n as f64 * span.0) as usize).min(n - 1);
            let len = 1 + ((n - first - 1) as f64 * span.1) as usize;
            let r = |v: usize| ((v as u64 ^ seed).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as u32;
            let bytes: Vec<u8> = (0..n).map(|v| (r(v) % levels) as u8).collect();
            let halves: Vec<i16> = (0..n).map(|v| (r(v) % levels) as i16 - 2).collect();
            let floats: Vec<f32> = (0..n)
                .map(|v| match r(v) % (levels + 3) {
                    0 => f32::NAN,
                    1 => -0.0,
                    2 => 0.0,
                    k => k as f32 * 0.5 - 2.0,
                })
                .collect();
            assert_row_walk(&g, bytes.as_slice(), first, len);
            assert_row_walk(&g, halves.as_slice(), first, len);
            assert_row_walk(&g, floats.as_slice(), first, len);
        }
    }

    #[test]
    fn interior_vertex_has_14_neighbours_in_3d_6_in_2d_2_in_1d() {
        let g = FreudenthalGrid::new([4, 5, 6]);
        assert_eq!(neighbours(&g, g.vertex(1, 2, 3)).len(), 14);
        let g = FreudenthalGrid::new([4, 5, 1]);
        assert_eq!(neighbours(&g, g.vertex(1, 2, 0)).len(), 6);
        let g = FreudenthalGrid::new([7, 1, 1]);
        assert_eq!(neighbours(&g, 3), vec![2, 4]);
    }

    #[test]
    fn neighbourhood_is_symmetric_and_matches_offsets_everywhere() {
        for dims in [
            [3, 4, 5],
            [1, 3, 4],
            [3, 1, 4],
            [2, 2, 2],
            [5, 1, 1],
            [1, 1, 1],
        ] {
            let g = FreudenthalGrid::new(dims);
            let n = g.num_vertices() as u32;
            for v in 0..n {
                let nv = neighbours(&g, v);
                // Brute force: every vertex whose coordinate difference is a
                // Freudenthal offset or its negative.
                let c = g.coords(v).map(|c| c as i64);
                let mut expect: Vec<u32> = (0..n)
                    .filter(|&u| {
                        let d = g.coords(u).map(|c| c as i64);
                        let diff = [d[0] - c[0], d[1] - c[1], d[2] - c[2]];
                        EDGE_OFFSETS
                            .iter()
                            .any(|o| *o == diff || [-o[0], -o[1], -o[2]] == diff)
                    })
                    .collect();
                expect.sort_unstable();
                assert_eq!(nv, expect, "dims {dims:?} v {v}");
            }
        }
    }

    #[test]
    fn link_components_match_flooding_the_link() {
        // Random subsets of the link of an interior and a boundary vertex:
        // the representatives must hit each component of the subset's
        // induced subgraph (mesh edges among the selected neighbours) once.
        let g = FreudenthalGrid::new([4, 4, 4]);
        let mut seed = 12345u64;
        for v in [
            g.vertex(1, 2, 1),
            g.vertex(0, 0, 0),
            g.vertex(3, 1, 0),
            g.vertex(0, 3, 2),
        ] {
            let nb = neighbours(&g, v);
            for _ in 0..300 {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let chosen: Vec<u32> = nb
                    .iter()
                    .copied()
                    .filter(|&u| (seed >> (u % 60)) & 1 == 1)
                    .collect();
                let mut reps = Vec::new();
                g.for_each_link_component(v, |u| chosen.contains(&u), |u| reps.push(u));
                // Components of the chosen set under edges u1-u2 that form a
                // triangle with v (both neighbours of each other).
                let mut comp: Vec<usize> = (0..chosen.len()).collect();
                for i in 0..chosen.len() {
                    for j in 0..chosen.len() {
                        if neighbours(&g, chosen[i]).contains(&chosen[j]) {
                            let (a, b) = (comp[i], comp[j]);
                            for c in comp.iter_mut() {
                                if *c == a {
                                    *c = b;
                                }
                            }
                        }
                    }
                }
                let mut labels: Vec<usize> = reps
                    .iter()
                    .map(|r| comp[chosen.iter().position(|c| c == r).expect("rep is chosen")])
                    .collect();
                let n_reps = labels.len();
                labels.sort_unstable();
                labels.dedup();
                assert_eq!(labels.len(), n_reps, "one rep per component");
                let mut all = comp.clone();
                all.sort_unstable();
                all.dedup();
                assert_eq!(labels.len(), all.len(), "every component has a rep");
            }
        }
    }

    #[test]
    fn cube_tetrahedra_edges_are_mesh_edges() {
        for t in CUBE_TETRAHEDRA {
            for i in 0..4 {
                for j in i + 1..4 {
                    let (a, b) = (t[i], t[j]);
                    let d = [
                        ((b & 1) as i64) - ((a & 1) as i64),
                        ((b >> 1 & 1) as i64) - ((a >> 1 & 1) as i64),
                        ((b >> 2 & 1) as i64) - ((a >> 2 & 1) as i64),
                    ];
                    assert!(EDGE_OFFSETS.contains(&d), "{t:?} {a}->{b}");
                }
            }
        }
    }
}
