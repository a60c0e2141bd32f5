//! Dragging one contour: its mesh at a new isovalue made from its mesh at
//! the last one, at the cost of the change rather than of the contour.
//!
//! **What changes between two cuts.** Let the contour of arc `a` at cut `h`
//! move to the contour of arc `c` at cut `h'` (say `h < h'`; downwards is
//! the mirror image). A tetrahedron's marching-tetrahedra piece depends
//! only on which of its corners lie above the cut, so a tetrahedron none of
//! whose corners is *flipped* (above `h`, not above `h'`) is crossed at
//! `h'` exactly as at `h`, by the same triangles on the same crossed edges
//! (only the points along those edges move). The flipped vertices that
//! matter are those of the *slab component*: the part of `{h ≤ f ≤ h'}`
//! connected to the contour. In the augmented contour tree that is a
//! connected piece `K` of the tree restricted to `[h, h']`, reached from
//! `(a, h)`: its arcs, and of each arc the regular vertices and nodes
//! between the two cuts (a binary search in the arc's sorted vertices). A
//! tetrahedron with a flipped corner lies wholly in that one slab
//! component (its part of the slab is convex), so:
//!
//! * the contour at `h'` of every arc of `K` spanning `h'` is made of the
//!   tetrahedra of the contours at `h` of the arcs of `K` spanning `h`
//!   that have no flipped corner, and of the tetrahedra with a flipped
//!   corner that `h'` crosses;
//! * `c`'s contour is that set less the contours of the other arcs of `K`
//!   spanning `h'` (pieces that split off the dragged contour, followed
//!   from their path seeds and removed), given that the contours of the
//!   other arcs of `K` spanning `h` (pieces that join it) were added first
//!   (followed from their seeds).
//!
//! So a step costs the tree walk over `K`, the 24 tetrahedra around each
//! flipped vertex, the pieces that join or leave, and then passes over the
//! contour's vertices and triangles that the output needs anyway (every
//! vertex moves along its edge: positions and normals are recomputed, in
//! parallel). On an 8-bit scan one value unit flips a few tens of
//! thousands of vertices of a head surface of 2.7 million.
//!
//! **State.** The contour is kept as the follower keeps it while flooding
//! ([`super::follow`]): a record per mesh vertex it touches (found through
//! a slot table over the volume, never cleared), holding which tetrahedra
//! of that vertex's cube are in the contour, where each one's triangles
//! are, and the contour vertex on each of the 7 mesh edges it owns. The
//! triangles of a tetrahedron sit in one slot of a pair array (removal
//! swaps the last pair in); contour vertices count the triangles that use
//! them and are freed, and their slots reused, when none does.
//!
//! **Memory:** 4 bytes per volume vertex (the slots) plus about 60 bytes
//! per touched mesh vertex, 32 per crossed tetrahedron and 9 per contour
//! vertex: about 350 MB for a 5.4 M-triangle head surface, held while one
//! contour is dragged.
//!
//! **Measured, and where the explorer uses it**
//! (`FLEXISO_BENCH_DRAG=1 FLEXISO_BENCH_QUICK=1 FLEXISO_BENCH_VOLUMES=colin27_ch2
//! cargo bench --bench contour`, the 2-core machine shared with a build,
//! load 3-4): on the colin27_ch2 head (5.4-5.7 M triangles, steps of +1
//! from h = 64 along its chain at the 100-arc level) a step flips 33-38 k
//! vertices, re-evaluates 745-790 k tetrahedra and joins or drops 10-30 k
//! tetrahedra of other pieces, yet costs 700-911 ms (median; 571 ms on a
//! quiet machine) against 492-619 ms (quiet: 422 ms) for extracting the head afresh on both cores in the same
//! run. The change itself takes 200-300 ms (about 300 ns per
//! tetrahedron), and the output passes 400 ms more: every vertex moves, so
//! positions, normals and triangles are rewritten. On a 0.8 M-triangle
//! contour a step costs 43-69 ms against 89-187 ms following it serially
//! (longer steps). **Flood order is not the cause:** putting records,
//! pairs and vertices in volume order (the sweep's) once the flood ends
//! was tried (a back-and-forth drag of one value unit, 40 steps at 854k
//! triangles and 12 on the head): steps 49-51 -> 51-55 ms at 854k and
//! 466 -> 500 ms on the head, and the start 1159 -> 1825 ms; the flood's
//! depth-first order is already local, so it was left out. The explorer
//! drags by a kept contour only contours small enough that a kept step
//! beats extracting afresh on every core ([`kept_limit`]: about 460k
//! triangles on colin27 with 2 cores, never more than 1 M; see
//! `app::jobs::extraction` for the measurements), and extracts larger
//! ones afresh by [`super::ContourFollower::extract`]. It starts one in the
//! background as soon as such a contour has been extracted afresh (a
//! click), so that a drag's first step is a step too.
//!
//! **Cancellation.** A step changes its state without asking (that part is
//! short); the output passes stop when `cancel` says so, leaving the state
//! at the new cut, whole, for the next step.

use super::follow::tet_of_edge;
use super::marching::{
    Cancelled, TetTables, add_area_normals, choose_normals, corner, downhill_vector, edge_fraction,
    end_gradient,
};
use super::sweep::split_lengths;
use super::{ContourMesh, PathSeed, path_seed};
use crate::field::{Isovalue, Scalar, ScalarField};
use crate::mesh::CUBE_TETRAHEDRA;
use crate::tree::{ArcId, ContourTree, NodeId};
use rayon::prelude::*;
use std::collections::HashSet;
use std::sync::Arc;
use strength_reduce::StrengthReducedU32;

/// The largest change [`DraggedContour::step`] should take on for a
/// contour of `triangles` triangles (flipped vertices plus the triangles of
/// joining and leaving pieces), beyond which extracting afresh is cheaper:
/// a flipped vertex re-evaluates 24 tetrahedra (about 250 ns), the sweep
/// costs about 110 ns of CPU per triangle of the contour and the follower
/// 125 ns, so the two meet near half a flip per triangle.
pub fn step_budget(triangles: usize) -> usize {
    (triangles / 2).max(4096)
}

/// The largest contour worth dragging by a kept [`DraggedContour`] in a
/// volume of `voxels` on `threads` cores: where a kept step and a step
/// extracted afresh by the parallel sweep cost the same (new isovalue to
/// mesh ready for upload, their arrays recycled as the explorer does), at
/// most `cap` (the kept state's memory: about 65 bytes per triangle).
/// A kept step costs what changed plus passes over the whole contour
/// (every vertex moves), partly serial ([`KEPT_NS`]); the sweep a pass
/// over the volume plus the contour's triangles, on every core
/// ([`AFRESH_VOXEL_NS`]). About 460k triangles on colin27 (7.1 M voxels)
/// on 2 cores, 65k on 16; on one core the sweep is not used (the
/// follower floods), and `cap` holds.
pub fn kept_limit(voxels: usize, threads: usize, cap: usize) -> usize {
    if threads < 2 {
        return cap;
    }
    let p = threads as f64;
    // K t (s + (1 - s) / p) = (V v + A t) / p, solved for t.
    let kept = KEPT_NS * (KEPT_SERIAL * p + 1.0 - KEPT_SERIAL) - AFRESH_TRIANGLE_NS;
    if kept <= 0.0 {
        return cap;
    }
    ((AFRESH_VOXEL_NS * voxels as f64 / kept) as usize).min(cap)
}

/// A kept contour's drag step of one value unit, with its GPU preparation,
/// in nanoseconds of wall time per triangle on one core, and the share of
/// it that stays serial on more: measured on colin27_ch2 (2026-12-05,
/// session 25, release, `FLEXISO_BENCH_DRAG=1 FLEXISO_BENCH_QUICK=1 cargo
/// bench --bench contour`, with `RAYON_NUM_THREADS=1` and 2; the 20-step
/// drags of a 229k-326k and an 802k-881k-triangle contour, medians): 22 and
/// 63 ms on one core, 15 and 45 ms on two (1.45 times faster), against 21
/// and 32 ms for the same steps extracted afresh by the sweep on two.
const KEPT_NS: f64 = 78.0;
/// See [`KEPT_NS`]: 1.45 times faster on 2 cores.
const KEPT_SERIAL: f64 = 0.38;
/// The same drag steps extracted afresh by the parallel sweep and prepared,
/// in nanoseconds of CPU, spread over the cores: per voxel of the volume
/// and per triangle of the contour (21, 32 and 126 ms on two cores at
/// 0.27, 0.84 and 5.5 M triangles, in the runs of [`KEPT_NS`]).
const AFRESH_VOXEL_NS: f64 = 4.4;
/// See [`AFRESH_VOXEL_NS`].
const AFRESH_TRIANGLE_NS: f64 = 40.0;

/// An empty slot (edge without contour vertex, tetrahedron without pair,
/// freed vertex).
const NONE: u32 = u32::MAX;

/// What the dragged contour holds at one mesh vertex `v`: the tetrahedra
/// of the cube whose lowest corner is `v` (bit `p`: permutation `p`), the
/// pair of triangles of each, and the contour vertex on each of the 7 mesh
/// edges `(v, v + d)`.
#[derive(Clone, Copy, Debug)]
struct Record {
    vertex: u32,
    /// Tetrahedra in the contour.
    tets: u8,
    /// Tetrahedra queued in this step's re-evaluation.
    touched: u8,
    /// Contour vertex on the edge of offset (bit mask) `d`, at `edge[d - 1]`.
    edge: [u32; 7],
    /// Pair index of tetrahedron `p`.
    pair: [u32; 6],
}

/// The triangles of one crossed tetrahedron.
#[derive(Clone, Copy, Debug)]
struct Pair {
    tris: [[u32; 3]; 2],
    count: u8,
    /// A crossed face of it lies on the volume's boundary.
    boundary: bool,
    perm: u8,
    rec: u32,
}

/// What a contour vertex needs at every cut, read once when it is made:
/// the values at its edge's ends (below, above) and the field's gradient
/// there, so that moving it is a streaming pass.
#[derive(Clone, Copy, Debug, Default)]
struct EdgeEnds {
    fb: f64,
    fa: f64,
    gb: [f32; 3],
    ga: [f32; 3],
}

/// A tetrahedron: the record of its cube's lowest corner and its
/// permutation.
#[derive(Clone, Copy, Debug)]
struct Tet {
    rec: u32,
    perm: u8,
}

/// The 24 tetrahedra around a vertex: (cube corner the vertex is, as a bit
/// mask; permutation).
fn star() -> &'static [(u8, u8)] {
    static S: std::sync::OnceLock<Vec<(u8, u8)>> = std::sync::OnceLock::new();
    S.get_or_init(|| {
        let mut s = Vec::new();
        for (p, t) in CUBE_TETRAHEDRA.iter().enumerate() {
            for &m in t {
                s.push((m, p as u8));
            }
        }
        s
    })
}

/// Why a step could not be taken from the last contour (the caller then
/// extracts the new one afresh and starts again from it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refused {
    /// The new contour is not reached from the last one through the slab
    /// between the two cuts (another part of the tree).
    NotConnected,
    /// The change is as large as the contour: extracting afresh is cheaper.
    TooLarge,
}

/// One contour being dragged: its mesh at the last cut, kept so that the
/// next cut costs what changed (see the module doc). Keep one per dragged
/// contour; [`DraggedContour::start`] begins at a cut, then
/// [`DraggedContour::step`] moves it.
pub struct DraggedContour {
    field: Arc<ScalarField>,
    dims: [usize; 3],
    corner_offset: [u32; 8],
    iso: Isovalue,
    arc: ArcId,
    slot: Vec<u32>,
    records: Vec<Record>,
    pairs: Vec<Pair>,
    /// Per contour vertex: its mesh edge (end below, end above), `below ==
    /// NONE` when free.
    vedge: Vec<(u32, u32)>,
    /// Per contour vertex: values and gradients at its edge's ends.
    ends: Vec<EdgeEnds>,
    /// Triangles using each contour vertex.
    refs: Vec<u8>,
    free: Vec<u32>,
    /// Pairs with a crossed face on the volume's boundary.
    boundary: usize,
    /// Triangles of all pairs.
    triangles: usize,
    stack: Vec<Tet>,
    /// Per-thread sums of area-weighted normals, kept between steps.
    sums: Vec<Vec<[f32; 3]>>,
    /// The output's map from contour vertex slots to mesh vertices and
    /// its vertices' downhill gradients, kept between steps (a fresh page
    /// costs as much as the work done on it).
    renumber: Vec<u32>,
    gradients: Vec<[f32; 3]>,
    /// A mesh this contour made earlier and its caller let go
    /// ([`DraggedContour::recycle`]): the next mesh is written into its
    /// arrays, and the tetrahedra of a step are queued in `queued`.
    spare: ContourMesh,
    queued: Vec<Tet>,
    detached: Vec<Pair>,
    div_x: StrengthReducedU32,
    div_y: StrengthReducedU32,
}

impl DraggedContour {
    /// The contour through `seed` at `iso`, followed from the seed (on
    /// this thread) and kept for the steps that follow; None on a 2D grid
    /// or when the seed's edge is not crossed.
    pub fn start(
        field: &Arc<ScalarField>,
        seed: &PathSeed,
        iso: Isovalue,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<Option<(Self, ContourMesh)>, Cancelled> {
        Self::start_within(field, seed, iso, usize::MAX, cancel)
    }

    /// [`DraggedContour::start`], given up (None) once the flood has taken
    /// in more than about `limit` tetrahedra (each holds one or two of the
    /// contour's triangles; the flood asks every 16k): a drag that jumps
    /// to a contour too large to keep then costs a bounded part of a
    /// serial flood, not all of it.
    pub fn start_within(
        field: &Arc<ScalarField>,
        seed: &PathSeed,
        iso: Isovalue,
        limit: usize,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<Option<(Self, ContourMesh)>, Cancelled> {
        let Some(mut d) = Self::keep(field, seed, iso, limit, cancel)? else {
            return Ok(None);
        };
        let mesh = d.mesh(cancel)?;
        Ok(Some((d, mesh)))
    }

    /// [`DraggedContour::start_within`] without making the mesh: for a
    /// contour whose mesh at `iso` the caller already has.
    pub fn keep(
        field: &Arc<ScalarField>,
        seed: &PathSeed,
        iso: Isovalue,
        limit: usize,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<Option<Self>, Cancelled> {
        let dims = field.dims();
        if dims.iter().any(|&d| d < 2) {
            return Ok(None);
        }
        let (sy, sz) = (dims[0] as u32, (dims[0] * dims[1]) as u32);
        let mut d = Self {
            field: Arc::clone(field),
            dims,
            corner_offset: std::array::from_fn(|m| {
                (m as u32 & 1) + sy * (m as u32 >> 1 & 1) + sz * (m as u32 >> 2 & 1)
            }),
            iso,
            arc: seed.arc,
            slot: vec![0; field.len()],
            records: Vec::new(),
            pairs: Vec::new(),
            vedge: Vec::new(),
            ends: Vec::new(),
            refs: Vec::new(),
            free: Vec::new(),
            boundary: 0,
            triangles: 0,
            stack: Vec::new(),
            sums: Vec::new(),
            renumber: Vec::new(),
            gradients: Vec::new(),
            spare: ContourMesh::empty(seed.arc, iso.value),
            queued: Vec::new(),
            detached: Vec::new(),
            div_x: StrengthReducedU32::new(dims[0] as u32),
            div_y: StrengthReducedU32::new(dims[1] as u32),
        };
        let Some((origin, perm)) = tet_of_edge(field, seed.below, seed.above) else {
            return Ok(None);
        };
        let start = d.tet(origin, perm);
        if !crate::with_values!(field.values(), v => d.flood_add(v.as_slice(), start, iso, limit, cancel))?
        {
            return Ok(None);
        }
        Ok(Some(d))
    }

    /// The cut the kept contour is at.
    pub fn isovalue(&self) -> Isovalue {
        self.iso
    }

    /// The superarc the kept contour belongs to.
    pub fn arc(&self) -> ArcId {
        self.arc
    }

    /// Triangles of the kept contour.
    pub fn num_triangles(&self) -> usize {
        self.triangles
    }

    /// Gives back a mesh this contour made (or any other) once the caller
    /// is done with it: the next step writes its mesh into these arrays
    /// instead of fresh ones. A drag step's output is tens of MiB that
    /// would otherwise be new pages, faulted in and zeroed by the kernel
    /// on every step (a third of an 854k-triangle step here); the result
    /// is the same either way.
    pub fn recycle(&mut self, mesh: ContourMesh) {
        self.spare = mesh;
    }

    /// Moves the kept contour to the contour of `arc` at `iso` and returns
    /// its mesh: the same oriented triangles on the same shared vertices
    /// as following `arc`'s path seed at `iso` gives (in another order).
    /// `Ok(Err(_))` leaves the kept contour as it was when `arc`'s contour
    /// is not reached through the slab between the two cuts, or when the
    /// change would cost more than `budget` flipped vertices and
    /// triangles of joining or leaving pieces; `Err(Cancelled)` leaves it
    /// at the new cut, whole.
    pub fn step(
        &mut self,
        tree: &ContourTree,
        arc: ArcId,
        iso: Isovalue,
        budget: usize,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<Result<ContourMesh, Refused>, Cancelled> {
        if cancel() {
            return Err(Cancelled);
        }
        let field = Arc::clone(&self.field);
        let field = &*field;
        let Some(slab) = Slab::find(tree, field, self.arc, self.iso, iso, budget) else {
            return Ok(Err(Refused::TooLarge));
        };
        if !slab.new.contains(&arc) {
            return Ok(Err(Refused::NotConnected));
        }
        let done = crate::with_values!(field.values(), v => self.apply(v.as_slice(), tree, &slab, arc, iso, budget));
        if !done {
            // A joining or leaving piece was larger than the budget: the
            // kept contour is no longer whole.
            self.records.clear();
            self.pairs.clear();
            self.vedge.clear();
            self.ends.clear();
            self.refs.clear();
            self.free.clear();
            self.boundary = 0;
            self.triangles = 0;
            return Ok(Err(Refused::TooLarge));
        }
        self.iso = iso;
        self.arc = arc;
        self.mesh(cancel).map(Ok)
    }

    /// The changes of one step (see the module doc); false when a piece
    /// outgrew `budget` (the state is then broken: the caller clears it).
    fn apply<T: Scalar>(
        &mut self,
        values: &[T],
        tree: &ContourTree,
        slab: &Slab,
        arc: ArcId,
        iso: Isovalue,
        budget: usize,
    ) -> bool {
        let field = Arc::clone(&self.field);
        let field = &*field;
        let old = self.iso;
        let mut left = budget.saturating_sub(slab.flipped);
        // Pieces that join: the other contours at the old cut.
        for &x in &slab.old {
            if x == self.arc {
                continue;
            }
            let Some(start) =
                path_seed(tree, field, x, old).and_then(|s| tet_of_edge(field, s.below, s.above))
            else {
                continue;
            };
            let start = self.tet(start.0, start.1);
            if self.records[start.rec as usize].tets & 1 << start.perm != 0 {
                continue;
            }
            let before = self.pairs.len();
            if !matches!(
                self.flood_add(values, start, old, left, &|| false),
                Ok(true)
            ) {
                return false;
            }
            left = left.saturating_sub(self.pairs.len() - before);
        }
        // Every tetrahedron around a flipped vertex, once.
        let star = star();
        let [nx, ny, nz] = self.dims;
        let mut queued = std::mem::take(&mut self.queued);
        queued.clear();
        queued.reserve(8 * slab.flipped);
        // In id order: neighbouring vertices share records and cache lines.
        let mut flipped: Vec<u32> = slab.vertices(tree).collect();
        flipped.sort_unstable();
        for v in flipped {
            let (x, y, z) = (
                v as usize % nx,
                v as usize / nx % ny,
                v as usize / (nx * ny),
            );
            for &(m, p) in star {
                let c = corner(m);
                let (ox, oy, oz) = (x as i64 - c[0], y as i64 - c[1], z as i64 - c[2]);
                if ox < 0
                    || oy < 0
                    || oz < 0
                    || ox + 1 >= nx as i64
                    || oy + 1 >= ny as i64
                    || oz + 1 >= nz as i64
                {
                    continue;
                }
                let origin = v - self.corner_offset[m as usize];
                let r = self.record(origin);
                let rec = &mut self.records[r];
                if rec.touched & 1 << p == 0 {
                    rec.touched |= 1 << p;
                    queued.push(Tet {
                        rec: r as u32,
                        perm: p,
                    });
                }
            }
        }
        // Old triangles out, new ones in, and only then the vertices
        // no triangle uses any more freed: a vertex whose edge stays
        // crossed keeps its slot and its edge ends.
        let mut detached = std::mem::take(&mut self.detached);
        detached.clear();
        for &t in &queued {
            if self.records[t.rec as usize].tets & 1 << t.perm != 0 {
                detached.push(self.detach_tet(t));
            }
        }
        for &t in &queued {
            self.records[t.rec as usize].touched &= !(1 << t.perm);
            self.add_tet(values, t, iso);
        }
        for pair in &detached {
            self.release(pair);
        }
        self.queued = queued;
        self.detached = detached;
        // Pieces that leave: the other contours at the new cut.
        for &y in &slab.new {
            if y == arc {
                continue;
            }
            let Some(start) =
                path_seed(tree, field, y, iso).and_then(|s| tet_of_edge(field, s.below, s.above))
            else {
                continue;
            };
            let start = self.tet(start.0, start.1);
            if self.records[start.rec as usize].tets & 1 << start.perm == 0 {
                // Not in the slab component after all: never expected.
                return false;
            }
            let removed = self.flood_remove(values, start, iso, left);
            if removed > left {
                return false;
            }
            left -= removed;
        }
        true
    }

    /// The record of vertex `v`, created if absent.
    #[inline]
    fn record(&mut self, v: u32) -> usize {
        let s = self.slot[v as usize] as usize;
        if s < self.records.len() && self.records[s].vertex == v {
            return s;
        }
        let s = self.records.len();
        self.records.push(Record {
            vertex: v,
            tets: 0,
            touched: 0,
            edge: [NONE; 7],
            pair: [NONE; 6],
        });
        self.slot[v as usize] = s as u32;
        s
    }

    fn tet(&mut self, origin: u32, perm: u8) -> Tet {
        Tet {
            rec: self.record(origin) as u32,
            perm,
        }
    }

    /// Corner ids of tetrahedron `t`.
    #[inline]
    fn ids(&self, t: Tet) -> [u32; 4] {
        let o = self.records[t.rec as usize].vertex;
        CUBE_TETRAHEDRA[t.perm as usize].map(|c| o + self.corner_offset[c as usize])
    }

    /// Bit `l`: corner `l` of `t` above `iso`.
    #[inline]
    fn mask<T: Scalar>(&self, values: &[T], t: Tet, iso: Isovalue) -> u8 {
        let ids = self.ids(t);
        let mut mask = 0;
        for (l, &v) in ids.iter().enumerate() {
            mask |= (iso.above_value(values[v as usize].to_f64(), v) as u8) << l;
        }
        mask
    }

    /// The lowest corner of the face neighbour of `t` opposite its corner
    /// `k`, and that neighbour's permutation; None outside the volume.
    #[inline]
    fn neighbour_origin(&self, t: Tet, k: usize) -> Option<(u32, u8)> {
        let (d, p) = TetTables::get().neighbour[t.perm as usize][k];
        let o = self.records[t.rec as usize].vertex;
        let c = self.coords(o);
        let inside = (0..3).all(|i| {
            let x = c[i] as i64 + d[i];
            x >= 0 && x + 1 < self.dims[i] as i64
        });
        inside.then(|| {
            let step = d[0] + self.dims[0] as i64 * (d[1] + self.dims[1] as i64 * d[2]);
            ((o as i64 + step) as u32, p)
        })
    }

    /// The face neighbour of `t` opposite its corner `k` (its record made
    /// if absent), None outside the volume.
    #[inline]
    fn neighbour(&mut self, t: Tet, k: usize) -> Option<Tet> {
        let (origin, p) = self.neighbour_origin(t, k)?;
        Some(self.tet(origin, p))
    }

    /// Adds `t`'s triangles at `iso` (if it crosses), returning its mask.
    fn add_tet<T: Scalar>(&mut self, values: &[T], t: Tet, iso: Isovalue) -> u8 {
        let mask = self.mask(values, t, iso);
        let (tris, count) = &TetTables::get().cases[t.perm as usize][mask as usize];
        if *count == 0 {
            return mask;
        }
        let corners = CUBE_TETRAHEDRA[t.perm as usize];
        let ids = self.ids(t);
        let mut pair = Pair {
            tris: [[NONE; 3]; 2],
            count: *count,
            boundary: false,
            perm: t.perm,
            rec: t.rec,
        };
        for (i, tri) in tris[..*count as usize].iter().enumerate() {
            for (k, &(b, a)) in tri.iter().enumerate() {
                let (lo, hi) = if b < a { (b, a) } else { (a, b) };
                let owner = self.record(ids[lo as usize]);
                let d = (corners[hi as usize] ^ corners[lo as usize]) as usize - 1;
                let mut idx = self.records[owner].edge[d];
                if idx == NONE {
                    let e = (ids[b as usize], ids[a as usize]);
                    let ends = self.edge_ends(values, e);
                    idx = match self.free.pop() {
                        Some(i) => {
                            self.vedge[i as usize] = e;
                            self.ends[i as usize] = ends;
                            i
                        }
                        None => {
                            self.vedge.push(e);
                            self.ends.push(ends);
                            self.refs.push(0);
                            (self.vedge.len() - 1) as u32
                        }
                    };
                    self.records[owner].edge[d] = idx;
                }
                self.refs[idx as usize] += 1;
                pair.tris[i][k] = idx;
            }
        }
        for k in 0..4 {
            if crossed_face(mask, k) && self.neighbour_origin(t, k).is_none() {
                pair.boundary = true;
            }
        }
        self.boundary += pair.boundary as usize;
        self.triangles += pair.count as usize;
        let rec = &mut self.records[t.rec as usize];
        rec.tets |= 1 << t.perm;
        rec.pair[t.perm as usize] = self.pairs.len() as u32;
        self.pairs.push(pair);
        mask
    }

    /// Coordinates of vertex `v`.
    #[inline]
    fn coords(&self, v: u32) -> [usize; 3] {
        let (q, x) = StrengthReducedU32::div_rem(v, self.div_x);
        let (z, y) = StrengthReducedU32::div_rem(q, self.div_y);
        [x as usize, y as usize, z as usize]
    }

    /// Values and gradients at the ends of edge `(below, above)`.
    fn edge_ends<T: Scalar>(&self, values: &[T], (b, a): (u32, u32)) -> EdgeEnds {
        let g = |v: u32| {
            end_gradient(values, self.dims, (v as usize, self.coords(v))).map(|x| x as f32)
        };
        EdgeEnds {
            fb: values[b as usize].to_f64(),
            fa: values[a as usize].to_f64(),
            gb: g(b),
            ga: g(a),
        }
    }

    /// Removes `t` (in the contour) and frees vertices no triangle uses.
    fn remove_tet(&mut self, t: Tet) {
        let pair = self.detach_tet(t);
        self.release(&pair);
    }

    /// Takes `t`'s triangles out of the contour (their vertices stay).
    fn detach_tet(&mut self, t: Tet) -> Pair {
        let rec = &mut self.records[t.rec as usize];
        let i = rec.pair[t.perm as usize] as usize;
        rec.tets &= !(1 << t.perm);
        rec.pair[t.perm as usize] = NONE;
        let pair = self.pairs.swap_remove(i);
        if let Some(moved) = self.pairs.get(i) {
            self.records[moved.rec as usize].pair[moved.perm as usize] = i as u32;
        }
        self.boundary -= pair.boundary as usize;
        self.triangles -= pair.count as usize;
        pair
    }

    /// Drops the uses of a detached pair's vertices, freeing unused ones.
    fn release(&mut self, pair: &Pair) {
        for tri in &pair.tris[..pair.count as usize] {
            for &idx in tri {
                let r = &mut self.refs[idx as usize];
                *r -= 1;
                if *r == 0 {
                    self.free_vertex(idx);
                }
            }
        }
    }

    fn free_vertex(&mut self, idx: u32) {
        let (b, a) = self.vedge[idx as usize];
        let (lo, hi) = (b.min(a), b.max(a));
        let nx = self.dims[0];
        let plane = nx * self.dims[1];
        let (l, h) = (lo as usize, hi as usize);
        let d = (h % nx != l % nx) as usize
            | ((h / nx % self.dims[1] != l / nx % self.dims[1]) as usize) << 1
            | ((h / plane != l / plane) as usize) << 2;
        let owner = self.slot[lo as usize] as usize;
        self.records[owner].edge[d - 1] = NONE;
        self.vedge[idx as usize] = (NONE, NONE);
        self.free.push(idx);
    }

    /// Floods from `start` through the tetrahedra `iso` crosses, adding
    /// those not in the contour yet; false when more than `limit` were
    /// added (or cancelled: Err).
    fn flood_add<T: Scalar>(
        &mut self,
        values: &[T],
        start: Tet,
        iso: Isovalue,
        limit: usize,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, Cancelled> {
        let mut stack = std::mem::take(&mut self.stack);
        stack.clear();
        let mut added = 0usize;
        if self.records[start.rec as usize].tets & 1 << start.perm == 0 {
            self.add_tet(values, start, iso);
            added += 1;
            stack.push(start);
        }
        let mut countdown = 1u32 << 14;
        while let Some(t) = stack.pop() {
            countdown -= 1;
            if countdown == 0 {
                countdown = 1 << 14;
                if cancel() {
                    self.stack = stack;
                    return Err(Cancelled);
                }
                if added > limit {
                    self.stack = stack;
                    return Ok(false);
                }
            }
            let mask = self.mask(values, t, iso);
            for k in 0..4 {
                if !crossed_face(mask, k) {
                    continue;
                }
                if let Some(n) = self.neighbour(t, k)
                    && self.records[n.rec as usize].tets & 1 << n.perm == 0
                {
                    self.add_tet(values, n, iso);
                    added += 1;
                    stack.push(n);
                }
            }
        }
        self.stack = stack;
        Ok(added <= limit)
    }

    /// Floods from `start` through the contour's tetrahedra across faces
    /// `iso` crosses, removing them; returns how many (stops past `limit`).
    fn flood_remove<T: Scalar>(
        &mut self,
        values: &[T],
        start: Tet,
        iso: Isovalue,
        limit: usize,
    ) -> usize {
        let mut stack = std::mem::take(&mut self.stack);
        stack.clear();
        self.remove_tet(start);
        stack.push(start);
        let mut removed = 1;
        while let Some(t) = stack.pop() {
            if removed > limit {
                break;
            }
            let mask = self.mask(values, t, iso);
            for k in 0..4 {
                if !crossed_face(mask, k) {
                    continue;
                }
                if let Some(n) = self.neighbour(t, k)
                    && self.records[n.rec as usize].tets & 1 << n.perm != 0
                {
                    self.remove_tet(n);
                    removed += 1;
                    stack.push(n);
                }
            }
        }
        self.stack = stack;
        removed
    }

    /// The kept contour as a mesh: used vertices numbered in slot order,
    /// positions and normals at the current cut, triangles in pair order.
    /// In parallel; cancellable (the state is not changed).
    fn mesh(&mut self, cancel: &(dyn Fn() -> bool + Sync)) -> Result<ContourMesh, Cancelled> {
        const CHUNK: usize = 1 << 15;
        let n = self.vedge.len();
        // New vertex ids: used slots in order.
        let counts: Vec<u32> = self
            .refs
            .par_chunks(CHUNK)
            .map(|c| c.iter().filter(|&&r| r > 0).count() as u32)
            .collect();
        let mut base = Vec::with_capacity(counts.len() + 1);
        let mut s = 0u32;
        for c in &counts {
            base.push(s);
            s += c;
        }
        let kept = s as usize;
        if cancel() {
            return Err(Cancelled);
        }
        // Only used slots are read back: stale entries need no clearing.
        let mut renumber = std::mem::take(&mut self.renumber);
        renumber.resize(n, NONE);
        let mut gradients = std::mem::take(&mut self.gradients);
        gradients.resize(kept, [0.0; 3]);
        let spare = std::mem::replace(
            &mut self.spare,
            ContourMesh::empty(self.arc, self.iso.value),
        );
        let mut positions = crate::pages::refilled(spare.positions, kept, [0f32; 3]);
        let spacing = self.field.spacing();
        let inverse = spacing.map(f64::recip);
        let iso = self.iso;
        {
            let mut pos_parts = split_lengths(&mut positions, counts.iter().map(|&c| c as usize));
            let mut grad_parts = split_lengths(&mut gradients, counts.iter().map(|&c| c as usize));
            renumber
                .par_chunks_mut(CHUNK)
                .zip(self.refs.par_chunks(CHUNK))
                .zip(self.vedge.par_chunks(CHUNK))
                .zip(self.ends.par_chunks(CHUNK))
                .zip(pos_parts.par_iter_mut())
                .zip(grad_parts.par_iter_mut())
                .enumerate()
                .for_each(|(c, (((((ren, refs), edges), ends), pos), grad))| {
                    let mut w = 0;
                    for (((r, &used), &(b, a)), e) in ren.iter_mut().zip(refs).zip(edges).zip(ends)
                    {
                        if used == 0 {
                            continue;
                        }
                        *r = base[c] + w as u32;
                        let s = edge_fraction(iso.value, e.fb, e.fa);
                        let (cb, ca) = (self.coords(b), self.coords(a));
                        pos[w] = std::array::from_fn(|k| {
                            let (pb, pa) = (cb[k] as f64, ca[k] as f64);
                            ((pb + s * (pa - pb)) * spacing[k]) as f32
                        });
                        grad[w] =
                            downhill_vector(e.gb.map(f64::from), e.ga.map(f64::from), s, inverse);
                        w += 1;
                    }
                });
        }
        if cancel() {
            return Err(Cancelled);
        }
        // Triangles in pair order, renumbered.
        let tri_counts: Vec<usize> = self
            .pairs
            .par_chunks(CHUNK)
            .map(|c| c.iter().map(|p| p.count as usize).sum())
            .collect();
        let total: usize = tri_counts.iter().sum();
        debug_assert_eq!(total, self.triangles, "the running count");
        let mut indices = crate::pages::refilled(spare.indices, 3 * total, 0u32);
        split_lengths(&mut indices, tri_counts.iter().map(|t| 3 * t))
            .into_par_iter()
            .zip(self.pairs.par_chunks(CHUNK))
            .for_each(|(out, pairs)| {
                let mut w = 0;
                for p in pairs {
                    for tri in &p.tris[..p.count as usize] {
                        for &i in tri {
                            out[w] = renumber[i as usize];
                            w += 1;
                        }
                    }
                }
            });
        if cancel() {
            return Err(Cancelled);
        }
        // Area-weighted normals: each thread sums its share of the
        // triangles, then the sums are added.
        let parts = rayon::current_num_threads().clamp(1, 8);
        let per = (total.div_ceil(parts)).max(1) * 3;
        let mut sums = std::mem::take(&mut self.sums);
        sums.resize_with(indices.chunks(per).len(), Vec::new);
        sums.par_iter_mut()
            .zip(indices.par_chunks(per))
            .for_each(|(acc, tris)| {
                acc.clear();
                acc.resize(kept, [0.0; 3]);
                add_area_normals(acc, &positions, tris);
            });
        // The sums added, normalised and compared with the gradient in one
        // pass (in the order the sums were made: the same bits as before).
        let mut normals = crate::pages::refilled(spare.normals, kept, [0f32; 3]);
        normals
            .par_chunks_mut(CHUNK)
            .zip(gradients.par_chunks(CHUNK))
            .enumerate()
            .for_each(|(c, (n, g))| {
                let at = c * CHUNK;
                for other in &sums {
                    for (n, o) in n.iter_mut().zip(&other[at..at + g.len()]) {
                        n[0] += o[0];
                        n[1] += o[1];
                        n[2] += o[2];
                    }
                }
                choose_normals(n, g);
            });
        self.sums = sums;
        self.renumber = renumber;
        self.gradients = gradients;
        Ok(ContourMesh {
            arc: self.arc,
            isovalue: self.iso.value,
            positions,
            normals,
            indices,
            touches_boundary: self.boundary > 0,
            ccw_outward: None,
            bounds: None,
            bands: Vec::new(),
        })
    }
}

/// True when the face of a tetrahedron opposite its corner `k` is crossed
/// (its three corners not all on one side), for the tetrahedron's mask.
#[inline]
fn crossed_face(mask: u8, k: usize) -> bool {
    let others = mask & !(1 << k) & 0xf;
    others != 0 && others != 0xf & !(1 << k)
}

/// The slab component of one step: the arcs of the tree restricted to the
/// values between the two cuts that are reached from the dragged contour,
/// the vertices that change sides, and the arcs spanning each cut.
struct Slab {
    /// Arcs of the component spanning the old cut (the dragged one among
    /// them).
    old: Vec<ArcId>,
    /// Arcs spanning the new cut.
    new: Vec<ArcId>,
    /// Per arc: its regular vertices between the cuts (a range of
    /// `arc_vertices`).
    ranges: Vec<(ArcId, usize, usize)>,
    /// Nodes between the cuts.
    nodes: Vec<NodeId>,
    /// How many vertices change sides.
    flipped: usize,
}

impl Slab {
    /// Walks the tree from `arc` at `from` towards `to`; None when more
    /// than `budget` vertices change sides.
    fn find(
        tree: &ContourTree,
        field: &ScalarField,
        arc: ArcId,
        from: Isovalue,
        to: Isovalue,
        budget: usize,
    ) -> Option<Slab> {
        let (lo, hi, up) = if (from.value, from.tie) <= (to.value, to.tie) {
            (from, to, true)
        } else {
            (to, from, false)
        };
        let above = |cut: Isovalue, v: u32| cut.is_above(field, v);
        // Between the cuts: above the lower, not above the higher.
        let between = |v: u32| above(lo, v) && !above(hi, v);
        let mut slab = Slab {
            old: Vec::new(),
            new: Vec::new(),
            ranges: Vec::new(),
            nodes: Vec::new(),
            flipped: 0,
        };
        let mut seen_arcs: HashSet<u32> = HashSet::new();
        let mut seen_nodes: HashSet<u32> = HashSet::new();
        let mut queue = vec![arc];
        seen_arcs.insert(arc.0);
        while let Some(x) = queue.pop() {
            let a = tree.arc(x);
            let (lv, uv) = (tree.node(a.lower).vertex, tree.node(a.upper).vertex);
            let (spans_lo, spans_hi) = (
                !above(lo, lv) && above(lo, uv),
                !above(hi, lv) && above(hi, uv),
            );
            if spans_lo {
                if up { &mut slab.old } else { &mut slab.new }.push(x);
            }
            if spans_hi {
                if up { &mut slab.new } else { &mut slab.old }.push(x);
            }
            let verts = tree.arc_vertices(x);
            let start = verts.partition_point(|v| !above(lo, v));
            let end = verts.partition_point(|v| !above(hi, v));
            if end > start {
                slab.ranges.push((x, start, end));
                slab.flipped += end - start;
            }
            for node in [a.lower, a.upper] {
                if between(tree.node(node).vertex) && seen_nodes.insert(node.0) {
                    slab.nodes.push(node);
                    slab.flipped += 1;
                    for &y in tree.node_arcs(node) {
                        if seen_arcs.insert(y.0) {
                            queue.push(y);
                        }
                    }
                }
            }
            if slab.flipped > budget {
                return None;
            }
        }
        Some(slab)
    }

    /// Every vertex that changes sides.
    fn vertices<'t>(&'t self, tree: &'t ContourTree) -> impl Iterator<Item = u32> + 't {
        self.ranges
            .iter()
            .flat_map(move |&(x, s, e)| tree.arc_vertices(x).slice(s..e).iter())
            .chain(self.nodes.iter().map(move |&n| tree.node(n).vertex))
    }
}
