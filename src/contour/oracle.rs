//! Test oracles: slow, independent ways to the same contours, for the
//! property tests and the benchmarks to check the fast paths against. Not
//! part of the public API (hidden from the docs; nothing in the library or
//! the program calls them).
//!
//! * [`all_contours_by_following`]: every contour at one isovalue by
//!   following each spanning arc's path seed, where
//!   [`all_contours`](super::all_contours) sweeps the volume once.
//! * [`marching_tetrahedra`]: the whole isosurface by a plain pass over
//!   every tetrahedron, O(volume), knowing nothing of the tree: the union
//!   of all contours must be this mesh.

use super::ContourMesh;
use super::global::{follow_all, spanning_arcs};
use super::marching::{IdBuildHasher, TetTables, edge_fraction};
use super::seed::{PathSeed, PathSeeds};
use crate::field::{Isovalue, Scalar, ScalarField};
use crate::mesh::CUBE_TETRAHEDRA;
use crate::tree::{ArcId, ContourTree};
use std::collections::HashMap;

/// [`all_contours`](super::all_contours) by following every contour from
/// its path seed, in parallel: the independent way, kept for the tests.
pub fn all_contours_by_following(
    tree: &ContourTree,
    field: &ScalarField,
    iso: Isovalue,
) -> Vec<ContourMesh> {
    let path_seeds = PathSeeds::new();
    let seeds: Vec<PathSeed> = spanning_arcs(tree, field, iso)
        .into_iter()
        .filter_map(|arc| path_seeds.seed(tree, field, arc, iso))
        .collect();
    follow_all(field, &seeds, iso)
}

/// The whole isosurface at `iso` by a plain marching-tetrahedra pass over
/// every tetrahedron of the volume, as one indexed mesh (arc 0), with the
/// same case tables, interpolation and vertex sharing as contour following.
/// O(volume): the tests' oracle, not the explorer's path.
pub fn marching_tetrahedra(field: &ScalarField, iso: Isovalue) -> ContourMesh {
    let mut out = ContourMesh::empty(ArcId(0), iso.value);
    let dims = field.dims();
    if dims.iter().any(|&d| d < 2) {
        return out;
    }
    crate::with_values!(field.values(), v => march(v.as_slice(), field, iso, &mut out));
    out.normals = super::follow::vertex_normals(&out.positions, &out.indices);
    out
}

fn march<T: Scalar>(values: &[T], field: &ScalarField, iso: Isovalue, out: &mut ContourMesh) {
    let dims = field.dims();
    let spacing = field.spacing();
    let tables = TetTables::get();
    let (sy, sz) = (dims[0], dims[0] * dims[1]);
    let off = |m: u8| (m & 1) as usize + sy * (m >> 1 & 1) as usize + sz * (m >> 2 & 1) as usize;
    let mut edge_vertex: HashMap<u64, u32, IdBuildHasher> = HashMap::default();
    for z in 0..dims[2] - 1 {
        for y in 0..dims[1] - 1 {
            for x in 0..dims[0] - 1 {
                let o = x + sy * y + sz * z;
                for (p, t) in CUBE_TETRAHEDRA.iter().enumerate() {
                    let ids = t.map(|m| (o + off(m)) as u32);
                    let vals = ids.map(|v| values[v as usize].to_f64());
                    let mut mask = 0u8;
                    for l in 0..4 {
                        mask |= (iso.above_value(vals[l], ids[l]) as u8) << l;
                    }
                    let (tris, count) = &tables.cases[p][mask as usize];
                    for tri in &tris[..*count as usize] {
                        for &(b, a) in tri {
                            let (vb, va) = (ids[b as usize], ids[a as usize]);
                            let k = (vb.min(va) as u64) << 32 | vb.max(va) as u64;
                            let next = out.positions.len() as u32;
                            let idx = *edge_vertex.entry(k).or_insert_with(|| {
                                let (fb, fa) = (vals[b as usize], vals[a as usize]);
                                let s = edge_fraction(iso.value, fb, fa);
                                let (cb, ca) = (field.coords(vb), field.coords(va));
                                out.positions.push(std::array::from_fn(|k| {
                                    let (pb, pa) = (cb[k] as f64, ca[k] as f64);
                                    ((pb + s * (pa - pb)) * spacing[k]) as f32
                                }));
                                next
                            });
                            out.indices.push(idx);
                        }
                    }
                }
            }
        }
    }
}
