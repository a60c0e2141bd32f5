//! Every contour at one isovalue: the classic isosurface as the union of
//! the contours of the superarcs spanning it, one mesh per superarc. The
//! explorer's path is one parallel sweep over the volume (see
//! `super::sweep`); following every seed in parallel and a plain
//! marching-tetrahedra pass over the whole volume are the independent
//! oracles of the tests ([`super::oracle`]).

use super::ContourMesh;
use super::follow::ContourFollower;
use super::seed::{PathSeed, PathSeeds, arc_spans};
use crate::field::{Isovalue, ScalarField};
use crate::tree::{ArcId, ContourTree};
use rayon::prelude::*;
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
