//! Every contour at one isovalue: the classic isosurface as the union of
//! the contours of the superarcs spanning it, one mesh per superarc. The
//! explorer's path is one parallel sweep over the volume (see
//! `super::sweep`); following every seed in parallel and a plain
//! marching-tetrahedra pass over the whole volume are the independent
//! oracles of the tests.

use super::follow::{ContourFollower, IdBuildHasher, TetTables};
use super::seed::{PathSeed, PathSeeds, arc_spans};
use super::{ContourMesh, Isovalue};
use crate::field::{Scalar, ScalarField};
use crate::mesh::CUBE_TETRAHEDRA;
use crate::tree::{ArcId, ContourTree};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Mutex;

/// The superarcs spanning `iso`, ascending by id: one per component of
/// the level set.
pub fn spanning_arcs(tree: &ContourTree, field: &ScalarField, iso: Isovalue) -> Vec<ArcId> {
    (0..tree.arcs().len() as u32)
        .map(ArcId)
        .filter(|&a| arc_spans(tree, field, a, iso))
        .collect()
}

/// Every contour at `iso`, one mesh per spanning superarc, sorted by arc
/// id (see [`contours_through`]).
pub fn all_contours(tree: &ContourTree, field: &ScalarField, iso: Isovalue) -> Vec<ContourMesh> {
    let path_seeds = PathSeeds::new();
    let seeds: Vec<PathSeed> = spanning_arcs(tree, field, iso)
        .into_iter()
        .filter_map(|arc| path_seeds.seed(tree, field, arc, iso))
        .collect();
    contours_through(tree, field, &seeds, iso)
}

/// The contours through `seeds` at `iso`, in the seeds' order. When the
/// seeds name every contour at `iso` (one per spanning superarc), by one
/// parallel sweep over the volume whose components the seeds name (see
/// `super::sweep`); otherwise, or should the sweep's components and the
/// seeds ever not match one to one, by following each seed
/// ([`follow_all`]).
pub fn contours_through(
    tree: &ContourTree,
    field: &ScalarField,
    seeds: &[PathSeed],
    iso: Isovalue,
) -> Vec<ContourMesh> {
    if seeds.len() > 1 && seeds.len() == spanning_arcs(tree, field, iso).len() {
        match super::sweep::all_contours_by_sweep(field, seeds, iso) {
            Some(by_arc) => {
                // By arc id; back to the seeds' order.
                let mut slot: Vec<Option<ContourMesh>> = by_arc.into_iter().map(Some).collect();
                let mut arcs: Vec<(ArcId, usize)> =
                    seeds.iter().enumerate().map(|(i, s)| (s.arc, i)).collect();
                arcs.sort_unstable();
                let mut out: Vec<Option<ContourMesh>> = vec![None; seeds.len()];
                for (k, &(_, i)) in arcs.iter().enumerate() {
                    out[i] = slot[k].take();
                }
                if let Some(out) = out.into_iter().collect::<Option<Vec<_>>>() {
                    return out;
                }
            }
            None => debug_assert!(
                field.dims().iter().any(|&d| d < 2),
                "contours at {iso:?} do not match the tree's spanning arcs"
            ),
        }
    }
    follow_all(field, seeds, iso)
}

/// [`all_contours`] by following every contour from its path seed, in
/// parallel: the independent way, kept for the tests.
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

/// The contours through `seeds` at `iso`, in the seeds' order, followed in
/// parallel (rayon) with one [`ContourFollower`] per worker thread, so
/// every follower's slot array is allocated once, not once per task.
pub fn follow_all(field: &ScalarField, seeds: &[PathSeed], iso: Isovalue) -> Vec<ContourMesh> {
    let pool: Vec<Mutex<ContourFollower>> = (0..rayon::current_num_threads())
        .map(|_| Mutex::new(ContourFollower::new(field)))
        .collect();
    seeds
        .par_iter()
        .map(|seed| {
            let i = rayon::current_thread_index().unwrap_or(0) % pool.len();
            // Uncontended: only this worker thread takes this follower. A
            // poisoned lock (a panic elsewhere) still holds a usable one.
            let mut follower = pool[i].lock().unwrap_or_else(|p| p.into_inner());
            follower.follow(seed, iso)
        })
        .collect()
}

/// The whole isosurface at `iso` by a plain marching-tetrahedra pass over
/// every tetrahedron of the volume, as one indexed mesh (arc 0), with the
/// same case tables, interpolation and vertex sharing as contour following.
/// O(volume): the tests' oracle, not the explorer's path.
pub fn marching_tetrahedra(field: &ScalarField, iso: Isovalue) -> ContourMesh {
    let mut out = ContourMesh::empty(ArcId(0));
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
                                let s = if fa != fb {
                                    ((iso.value - fb) / (fa - fb)).clamp(0.0, 1.0)
                                } else {
                                    0.5
                                };
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
