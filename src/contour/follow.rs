//! Contour following: from a [`PathSeed`], a flood through the tetrahedra
//! of the Freudenthal triangulation that the isovalue crosses, across
//! their shared crossed faces, emitting one or two triangles per
//! tetrahedron (marching tetrahedra).
//!
//! **Tetrahedra.** Tetrahedron `(o, p)` is the one of permutation `p` (an
//! index into [`CUBE_TETRAHEDRA`]) in the cube whose lowest corner is
//! vertex `o`; it is the monotone lattice path `o, o+e_i, o+e_i+e_j,
//! o+(1,1,1)` for the axis order `(i, j, k)`. Its face opposite path vertex
//! 1 or 2 is shared with the tetrahedron of the same cube whose order swaps
//! the two neighbouring axes; the face opposite `o` with the tetrahedron of
//! cube `o+e_i` and order `(j, k, i)`; the face opposite the far corner
//! with cube `o-e_k` and order `(k, i, j)` (Kuhn's reflection rule). So the
//! flood needs no stored adjacency.
//!
//! **Costs.** Everything the flood touches is sized to the contour: a
//! record per mesh vertex it touches (visited tetrahedra of that vertex's
//! cube, contour vertices on that vertex's 7 edges), found through a slot
//! array over the volume that is allocated once per follower and never
//! cleared (see [`ContourFollower`]). Dense slots instead of hash tables
//! keep the flood's spatial locality: neighbouring tetrahedra hit
//! neighbouring memory, where a hash scatters them.
//!
//! **On every core.** The flood is one thread's walk: fine for the small
//! contours most picks and drags touch, but a head or brain surface of an
//! MRI holds millions of triangles. [`ContourFollower::extract`] floods
//! for at most [`serial_limit`] triangles and then hands the contour to
//! the parallel sweep (`super::sweep`, [`contour_by_sweep`]); past a
//! quarter of that limit the sweep already runs on the other cores,
//! raced against the flood (whichever finishes first stops the other, see
//! `ContourFollower::race`), so the flood's time before it gives up is
//! not all lost. The sweep: every cube
//! layer of the volume marched on all cores, each vertex given its side of
//! the contour by the tree ([`CutSides`](super::seed::CutSides)), so only
//! this contour's tetrahedra are crossed. The same case tables, edge
//! interpolation and vertex sharing make it the same mesh, vertices and
//! triangles renumbered; [`ContourFollower::follow`], the flood alone,
//! stays as the tests' oracle. Both stop when a cancel check says a newer
//! request superseded them ([`Cancelled`]), returning nothing partial.
//!
//! **Normals** come from the field's gradient (central differences,
//! interpolated along the crossed edge), falling back to the area-weighted
//! triangle normal where the gradient vanishes or disagrees with the
//! triangles' winding (see [`gradient_normals`]).

pub use super::marching::{Cancelled, IdBuildHasher, IdHasher, gradient_normals, vertex_normals};
use super::marching::{TetTables, corner, edge_fraction};
use super::sweep::{SweepScratch, contour_by_sweep};
use super::{ContourMesh, PathSeed};
use crate::field::Isovalue;
use crate::field::{Scalar, ScalarField};
use crate::mesh::CUBE_TETRAHEDRA;
use crate::tree::ContourTree;

/// One tetrahedron waiting in the flood: cube origin (id and coordinates)
/// and permutation.
#[derive(Clone, Copy, Debug)]
struct TetRef {
    origin: u32,
    xyz: [u32; 3],
    perm: u8,
    /// The record of `origin` (made when the tetrahedron was queued).
    rec: u32,
}

/// The fewest triangles [`ContourFollower::extract`] lets the serial
/// flood emit before it hands the contour to the parallel sweep.
pub const SERIAL_TRIANGLES: usize = 60_000;

/// How many triangles the serial flood emits, for a contour of unknown
/// size, before it hands over to the parallel sweep, for a volume of
/// `voxels` on `threads` cores: where following and sweeping for a contour
/// of that size cost the same ([`FOLLOW_NS`]), so a contour of any size
/// costs at most twice the cheaper way (what it would cost were its size
/// known), or 1.5 times with the sweep raced against the flood past a
/// quarter of the limit. About 235k triangles for colin27 (7.1 M voxels)
/// on 2 cores, 22k (raised to [`SERIAL_TRIANGLES`]) on 16.
pub fn serial_limit(voxels: usize, threads: usize) -> usize {
    if threads < 2 {
        return usize::MAX;
    }
    // Following t triangles, F t, against sweeping for them, (V v + S t) / P.
    let even = SWEEP_VOXEL_NS * voxels as f64 / (FOLLOW_NS * threads as f64 - SWEEP_TRIANGLE_NS);
    (even as usize).max(SERIAL_TRIANGLES)
}

/// What following a contour and sweeping for it cost, in nanoseconds of
/// CPU. Measured on colin27_ch2 (2026-12-05, session 24, release, 2
/// threads, `FLEXISO_BENCH_QUICK=1 cargo bench --bench contour`, steps of
/// a 156k- and an 854k-triangle contour, their preparation taken off):
/// following costs 109-113 ns per triangle on one thread; the sweep, which
/// marches the contour alone (its vertices' sides from the tree), about
/// 5.3 ns per voxel plus 62 ns per triangle of the contour, spread over the
/// cores (23.5 ms of wall time at 156k triangles, 45 ms at 854k). Until
/// then 115, 11 and 41 (session 22's sweep, before its passes moved fewer
/// bytes): a limit of 410k triangles on colin27 where these give 235k.
const FOLLOW_NS: f64 = 111.0;
/// See [`FOLLOW_NS`].
const SWEEP_VOXEL_NS: f64 = 5.3;
/// See [`FOLLOW_NS`].
const SWEEP_TRIANGLE_NS: f64 = 62.0;

/// Extractions ([`ContourFollower::extract_expecting`]) running in this
/// process: the flood races the sweep only when it runs alone, since the
/// race spends cores on work that may be thrown away (the first screen's
/// six contours, extracted at once, would each start a sweep).
static RUNNING: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Counts one extraction in [`RUNNING`] while it lives.
struct Running;

impl Running {
    /// Counted in; true when no other extraction runs.
    fn enter() -> (Self, bool) {
        let before = RUNNING.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        (Running, before == 0)
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        RUNNING.fetch_sub(1, std::sync::atomic::Ordering::Relaxed);
    }
}

/// Tetrahedra the flood visits between two cancel checks.
const CHECK_EVERY: u32 = 1 << 14;

/// Marks an edge without a contour vertex yet.
const NO_VERTEX: u32 = u32::MAX;

/// What the flood knows about one mesh vertex `v` it has touched: which
/// tetrahedra of the cube whose lowest corner is `v` it has visited, and
/// the contour vertex on each of the 7 mesh edges `(v, v + d)`, `d` a
/// non-zero 0/1 offset (every edge of the Freudenthal mesh is one of these
/// for exactly one `v`, its lower-coordinate end).
#[derive(Clone, Copy, Debug)]
struct VertexRecord {
    vertex: u32,
    /// Bit `p`: tetrahedron of permutation `p` visited.
    tets: u8,
    /// Contour vertex on the edge of offset (bit mask) `d`, at `edge[d - 1]`.
    edge: [u32; 7],
}

/// Extracts single contours from path seeds. Keep one per thread and reuse
/// it: its tables keep their memory between extractions.
///
/// **Memory:** 4 bytes per volume vertex (the record slots, allocated on
/// the first extraction, zero pages the system commits only where
/// contours pass) plus 36 bytes per mesh vertex the contour touches.
/// **Never cleared:** a slot is valid only when the record it points to
/// names its vertex back (the sparse-set trick of Briggs & Torczon), so
/// forgetting the last contour is truncating the record list, O(1).
pub struct ContourFollower<'f> {
    field: &'f ScalarField,
    dims: [usize; 3],
    /// Id offset of each cube corner (bit mask).
    corner_offset: [u32; 8],
    spacing: [f64; 3],
    /// Per volume vertex: index of its record in `records`, if valid.
    slot: Vec<u32>,
    records: Vec<VertexRecord>,
    /// Tetrahedra waiting, depth first: the last queued, a neighbour of
    /// the one just done, comes next while its memory is still in cache
    /// (measured faster than breadth first).
    stack: Vec<TetRef>,
    /// Per contour vertex of the last contour: its mesh edge (below,
    /// above) and where on it, for the gradient normals.
    vertex_edges: Vec<(u32, u32, f32)>,
    /// The parallel sweep's tables (see [`ContourFollower::extract`]).
    sweep: SweepScratch,
    /// A mesh for the next sweep to write into
    /// ([`ContourFollower::recycle`]).
    spare: Option<ContourMesh>,
    /// Triangles the serial flood of [`ContourFollower::extract`] may
    /// emit; None: [`serial_limit`] of the field and the thread pool.
    serial_limit: Option<usize>,
    /// Race the flood against the sweep even while other extractions run
    /// (see [`RUNNING`]; for tests).
    race_always: bool,
}

/// The record of vertex `v`, created if the flood has not touched `v` yet.
#[inline(always)]
fn record(slot: &mut [u32], records: &mut Vec<VertexRecord>, v: u32) -> usize {
    let s = slot[v as usize] as usize;
    if s < records.len() && records[s].vertex == v {
        return s;
    }
    let s = records.len();
    records.push(VertexRecord {
        vertex: v,
        tets: 0,
        edge: [NO_VERTEX; 7],
    });
    slot[v as usize] = s as u32;
    s
}

/// The tables of a [`ContourFollower`] without its field: a thread that
/// extracts contours of whichever field its jobs name keeps one, so that
/// each new follower finds its memory already committed (a fresh slot
/// table costs a page fault per 4 KiB the contour touches, as much as
/// following a large contour itself).
#[derive(Default)]
pub struct FollowerScratch {
    slot: Vec<u32>,
    records: Vec<VertexRecord>,
    stack: Vec<TetRef>,
    vertex_edges: Vec<(u32, u32, f32)>,
    sweep: SweepScratch,
}

impl<'f> ContourFollower<'f> {
    /// A follower for `field` that starts with the tables of an earlier
    /// one (any field: slots are only trusted when their record names them
    /// back, see the type's doc).
    pub fn with_scratch(field: &'f ScalarField, scratch: FollowerScratch) -> Self {
        let mut f = Self::new(field);
        let FollowerScratch {
            slot,
            mut records,
            mut stack,
            mut vertex_edges,
            sweep,
        } = scratch;
        records.clear();
        stack.clear();
        vertex_edges.clear();
        (f.slot, f.records, f.stack, f.vertex_edges) = (slot, records, stack, vertex_edges);
        f.sweep = sweep;
        f
    }

    /// Hands the follower a mesh it made earlier that no one needs any
    /// more: the next extraction that goes to the parallel sweep writes its
    /// mesh into that one's arrays (a fresh array is fresh pages, which the
    /// kernel faults in and zeroes; on a head's contour about 130 MB per
    /// drag step). An extraction that does not use it lets it go.
    pub fn recycle(&mut self, spare: ContourMesh) {
        self.spare = Some(spare);
    }

    /// Gives the tables back for the next follower.
    pub fn into_scratch(self) -> FollowerScratch {
        FollowerScratch {
            slot: self.slot,
            records: self.records,
            stack: self.stack,
            vertex_edges: self.vertex_edges,
            sweep: self.sweep,
        }
    }

    /// A follower for `field`.
    pub fn new(field: &'f ScalarField) -> Self {
        let dims = field.dims();
        let (sy, sz) = (dims[0] as u32, (dims[0] * dims[1]) as u32);
        let corner_offset = std::array::from_fn(|m| {
            (m as u32 & 1) + sy * (m as u32 >> 1 & 1) + sz * (m as u32 >> 2 & 1)
        });
        Self {
            field,
            dims,
            corner_offset,
            spacing: field.spacing(),
            slot: Vec::new(),
            records: Vec::new(),
            stack: Vec::new(),
            vertex_edges: Vec::new(),
            sweep: SweepScratch::default(),
            spare: None,
            serial_limit: None,
            race_always: false,
        }
    }

    /// Sets how many triangles the serial flood of
    /// [`ContourFollower::extract`] may emit before the parallel sweep
    /// takes over (default [`serial_limit`] of the field and the thread
    /// pool; 0 sends every contour to the sweep, `usize::MAX` none: for
    /// tests and benchmarks).
    pub fn with_serial_limit(mut self, triangles: usize) -> Self {
        self.serial_limit = Some(triangles);
        self
    }

    /// Races the flood against the sweep (see `ContourFollower::race`)
    /// even while other extractions run in this process, where by default
    /// it races only when alone (for tests, which run side by side).
    pub fn racing_always(mut self) -> Self {
        self.race_always = true;
        self
    }

    /// The contour through `seed` at `iso`, followed on this thread: the
    /// serial flood, the oracle [`ContourFollower::extract`] is tested
    /// against. An edge that `iso` does not cross, or a 2D grid, gives an
    /// empty mesh.
    pub fn follow(&mut self, seed: &PathSeed, iso: Isovalue) -> ContourMesh {
        match self.follow_within(seed, iso, usize::MAX, &|| false) {
            Ok(Some(mesh)) => mesh,
            // Neither a limit nor a cancel check to stop it.
            _ => ContourMesh::empty(seed.arc, iso.value),
        }
    }

    /// The contour through `seed` at `iso` on every core, the same mesh as
    /// [`ContourFollower::follow`] gives (the same oriented triangles on
    /// the same shared vertices; vertices and triangles possibly in
    /// another order), or [`Cancelled`] soon after `cancel` answers true.
    /// `tree` is the augmented contour tree of the field (the seed's).
    ///
    /// A small contour is followed on this thread; one that grows past
    /// [`serial_limit`] is handed to the parallel sweep, which marches
    /// every cube layer of the volume on all cores, each vertex given its
    /// side of this contour by the tree (see `super::sweep`). So the cost
    /// is the flood's for small contours and, for large ones, a pass over
    /// the volume plus the contour's triangles spread over the cores.
    /// Between a quarter of the limit and the limit the sweep runs beside
    /// the flood, and the first to finish gives the mesh.
    /// `cancel` is asked every few thousand tetrahedra of the flood,
    /// between the sweep's phases and before each of its planes; it
    /// must be cheap (an atomic load), and may be asked from any thread.
    /// A cancel seen by one side of the race while the other finishes
    /// still gives that whole mesh.
    pub fn extract(
        &mut self,
        tree: &ContourTree,
        seed: &PathSeed,
        iso: Isovalue,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<ContourMesh, Cancelled> {
        self.extract_expecting(tree, seed, iso, None, cancel)
    }

    /// [`ContourFollower::extract`] told how many triangles the contour
    /// had a moment ago (the last drag step): one large enough that the
    /// sweep is the cheaper way (past [`serial_limit`]) goes straight to the
    /// sweep. Only the path taken depends on `expected`, never the mesh.
    pub fn extract_expecting(
        &mut self,
        tree: &ContourTree,
        seed: &PathSeed,
        iso: Isovalue,
        expected: Option<usize>,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<ContourMesh, Cancelled> {
        if cancel() {
            return Err(Cancelled);
        }
        let threads = rayon::current_num_threads();
        let limit = match self.serial_limit {
            _ if threads < 2 => usize::MAX,
            Some(l) => l,
            None => serial_limit(self.field.len(), threads),
        };
        // How far to flood first (None: straight to the sweep).
        let flood = match expected {
            Some(e) if e > limit => None,
            _ => Some(limit),
        };
        let mut spare = self.spare.take();
        let (_running, only) = Running::enter();
        if let Some(limit) = flood {
            // Alone while most contours end (no sweep is started for
            // them), then raced against the sweep up to the limit when no
            // other extraction needs the cores.
            let before_race = (limit / 4).min(SERIAL_TRIANGLES);
            let mut out = ContourMesh::empty(seed.arc, iso.value);
            if self.flood_into(seed, iso, &mut out, false, before_race, cancel)? {
                self.add_normals(&mut out);
                return Ok(out);
            }
            if limit > before_race && (only || self.race_always) {
                let spare = spare.take();
                if let Some(mesh) = self.race(tree, seed, iso, out, limit, spare, cancel)? {
                    return Ok(mesh);
                }
            } else if self.flood_into(seed, iso, &mut out, true, limit, cancel)? {
                self.add_normals(&mut out);
                return Ok(out);
            }
        }
        self.reset();
        let spare = spare.unwrap_or_else(|| ContourMesh::empty(seed.arc, iso.value));
        match contour_by_sweep(self.field, tree, seed, iso, &mut self.sweep, spare, cancel)? {
            Some(mesh) => Ok(mesh),
            // Beyond the sweep's u32 ids: the flood has no such limit.
            None => Ok(self
                .follow_within(seed, iso, usize::MAX, cancel)?
                .unwrap_or_else(|| ContourMesh::empty(seed.arc, iso.value))),
        }
    }

    /// The flood that has emitted `out` (more than a quarter of `limit`
    /// triangles, fewer than `limit`) raced against the parallel sweep for
    /// the same contour: the flood goes on on this thread while the sweep
    /// starts on the others; whichever finishes first stops the other at
    /// its next cancel check, and a flood past `limit` gives its thread
    /// to the sweep. A contour between the two limits costs the flood's
    /// time, with a core kept busy beside it; a larger one costs the flood
    /// up to the limit plus what remains of the sweep, spread over every
    /// core, where before the sweep started only then: half the flood's
    /// time saved, so a contour of any size costs at most 1.5 times the
    /// cheaper way (twice before). None: neither gave the contour (past
    /// the limit, and the sweep's u32 ids too few), to be followed whole.
    #[allow(clippy::too_many_arguments)]
    fn race(
        &mut self,
        tree: &ContourTree,
        seed: &PathSeed,
        iso: Isovalue,
        mut out: ContourMesh,
        limit: usize,
        spare: Option<ContourMesh>,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<Option<ContourMesh>, Cancelled> {
        use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
        let field = self.field;
        let mut scratch = std::mem::take(&mut self.sweep);
        let spare = spare.unwrap_or_else(|| ContourMesh::empty(seed.arc, iso.value));
        let (flooded, swept) = (AtomicBool::new(false), AtomicBool::new(false));
        let (by_flood, by_sweep) = rayon::join(
            || {
                let stop = || cancel() || swept.load(Relaxed);
                let done = self.flood_into(seed, iso, &mut out, true, limit, &stop)?;
                if done {
                    flooded.store(true, Relaxed);
                    self.add_normals(&mut out);
                }
                Ok::<_, Cancelled>(done)
            },
            || {
                let stop = || cancel() || flooded.load(Relaxed);
                let mesh = contour_by_sweep(field, tree, seed, iso, &mut scratch, spare, &stop);
                if matches!(mesh, Ok(Some(_))) {
                    swept.store(true, Relaxed);
                }
                mesh
            },
        );
        self.sweep = scratch;
        match (by_flood, by_sweep) {
            (_, Ok(Some(mesh))) => Ok(Some(mesh)),
            (Ok(true), _) => Ok(Some(out)),
            // Past the limit, and too large for the sweep.
            (Ok(false), Ok(None)) => Ok(None),
            // Neither finished, nor stopped the other: the caller's cancel.
            _ => Err(Cancelled),
        }
    }

    /// The serial flood, given up (`Ok(None)`) once it has emitted more
    /// than `limit` triangles, cancelled when `cancel` says so.
    fn follow_within(
        &mut self,
        seed: &PathSeed,
        iso: Isovalue,
        limit: usize,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<Option<ContourMesh>, Cancelled> {
        let mut out = ContourMesh::empty(seed.arc, iso.value);
        if !self.flood_into(seed, iso, &mut out, false, limit, cancel)? {
            return Ok(None);
        }
        self.add_normals(&mut out);
        Ok(Some(out))
    }

    /// Floods from the seed into `out` (`resume`: on from where the last
    /// flood into `out` stopped at its limit), false once `out` holds
    /// more than `limit` triangles (then `out` is partial and the flood
    /// can resume).
    fn flood_into(
        &mut self,
        seed: &PathSeed,
        iso: Isovalue,
        out: &mut ContourMesh,
        resume: bool,
        limit: usize,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, Cancelled> {
        if self.dims.iter().any(|&d| d < 2) {
            return Ok(true);
        }
        if self.slot.len() != self.field.len() {
            // Zeroed memory: the system hands out pages lazily. (A table of
            // another field's size is dropped rather than resized: resizing
            // would copy it.)
            self.slot = Vec::new();
            self.slot = vec![0; self.field.len()];
        }
        let field = self.field;
        crate::with_values!(field.values(), v => {
            self.flood(v.as_slice(), seed, iso, out, resume, limit, cancel)
        })
    }

    /// The vertex normals of the flood's whole contour `out`.
    fn add_normals(&self, out: &mut ContourMesh) {
        if self.dims.iter().any(|&d| d < 2) {
            return;
        }
        crate::with_values!(self.field.values(), v => {
            out.normals = gradient_normals(
                v.as_slice(),
                self.dims,
                self.spacing,
                &self.vertex_edges,
                &out.positions,
                &out.indices,
            );
        });
    }

    /// Forgets the last contour: O(1), but gives back memory when the last
    /// contour was far larger than the one before (so one huge contour
    /// does not keep its tables alive for every later small one).
    fn reset(&mut self) {
        let r = self.records.len();
        if self.records.capacity() > 1 << 16 && self.records.capacity() > 8 * r {
            self.records.shrink_to(2 * r);
        }
        self.records.clear();
        self.stack.clear();
        self.vertex_edges.clear();
    }

    /// The tetrahedron holding edge `(a, b)`, if any.
    fn tet_of_edge(&self, a: u32, b: u32) -> Option<TetRef> {
        let (origin, perm) = tet_of_edge(self.field, a, b)?;
        let xyz = self.field.coords(origin).map(|c| c as u32);
        Some(TetRef {
            origin,
            xyz,
            perm,
            rec: 0,
        })
    }

    /// Floods from the seed into `out` (`resume`: on with the tetrahedra
    /// still waiting); false when more than `limit` triangles came out
    /// (then `out` is partial, the waiting tetrahedra kept).
    #[allow(clippy::too_many_arguments)]
    fn flood<T: Scalar>(
        &mut self,
        values: &[T],
        seed: &PathSeed,
        iso: Isovalue,
        out: &mut ContourMesh,
        resume: bool,
        limit: usize,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, Cancelled> {
        if !resume {
            self.reset();
            let Some(mut start) = self.tet_of_edge(seed.below, seed.above) else {
                return Ok(true);
            };
            let r = record(&mut self.slot, &mut self.records, start.origin);
            self.records[r].tets |= 1 << start.perm;
            start.rec = r as u32;
            self.stack.push(start);
        }
        let index_limit = limit.saturating_mul(3);
        let mut countdown = CHECK_EVERY;
        let tables = TetTables::get();
        let Self {
            slot,
            records,
            stack,
            corner_offset,
            vertex_edges,
            ..
        } = self;
        let [nx, ny, nz] = self.dims.map(|d| d as i64 - 1);
        let spacing = self.spacing;
        let sy = self.dims[0] as u32;
        let sz = sy * self.dims[1] as u32;
        loop {
            countdown -= 1;
            if countdown == 0 {
                countdown = CHECK_EVERY;
                if cancel() {
                    return Err(Cancelled);
                }
                if out.indices.len() > index_limit {
                    return Ok(false);
                }
            }
            let Some(t) = stack.pop() else {
                break;
            };
            let corners = CUBE_TETRAHEDRA[t.perm as usize];
            let ids = corners.map(|c| t.origin + corner_offset[c as usize]);
            let vals = ids.map(|v| values[v as usize].to_f64());
            let mut mask = 0u8;
            for l in 0..4 {
                mask |= (iso.above_value(vals[l], ids[l]) as u8) << l;
            }
            let (tris, count) = &tables.cases[t.perm as usize][mask as usize];
            // Records of the corners that own edges of the tetrahedron
            // (local 0, 1, 2: an edge's lower end is never the last
            // corner), looked up once per tetrahedron.
            let mut rec = [t.rec as usize, usize::MAX, usize::MAX];
            let mut rec_of = |l: usize, slot: &mut [u32], records: &mut Vec<VertexRecord>| {
                if rec[l] == usize::MAX {
                    rec[l] = record(slot, records, ids[l]);
                }
                rec[l]
            };
            for tri in &tris[..*count as usize] {
                for &(b, a) in tri {
                    // The tetrahedron is a monotone lattice path, so of two
                    // of its corners the earlier is a subset (bit mask) of
                    // the later: the edge's lower-coordinate end.
                    let (lo, hi) = if b < a { (b, a) } else { (a, b) };
                    let (clo, chi) = (corners[lo as usize], corners[hi as usize]);
                    let owner = rec_of(lo as usize, slot, records);
                    let d = (chi ^ clo) as usize - 1;
                    let mut idx = records[owner].edge[d];
                    if idx == NO_VERTEX {
                        idx = out.positions.len() as u32;
                        records[owner].edge[d] = idx;
                        let (fb, fa) = (vals[b as usize], vals[a as usize]);
                        // fa > fb or (equal values, ids ordered), kept
                        // inside the edge (the vertex order's perturbation).
                        let s = edge_fraction(iso.value, fb, fa);
                        let (cb, ca) = (corner(corners[b as usize]), corner(corners[a as usize]));
                        out.positions.push(std::array::from_fn(|k| {
                            let base = t.xyz[k] as f64 + cb[k] as f64;
                            ((base + s * (ca[k] - cb[k]) as f64) * spacing[k]) as f32
                        }));
                        vertex_edges.push((ids[b as usize], ids[a as usize], s as f32));
                    }
                    out.indices.push(idx);
                }
            }
            // Flood across the crossed faces: those whose three corners
            // are not all on one side.
            for k in 0..4 {
                let others = mask & !(1 << k) & 0xf;
                if others == 0 || others == 0xf & !(1 << k) {
                    continue;
                }
                let (d, p) = tables.neighbour[t.perm as usize][k];
                let x = [
                    t.xyz[0] as i64 + d[0],
                    t.xyz[1] as i64 + d[1],
                    t.xyz[2] as i64 + d[2],
                ];
                if x[0] < 0 || x[1] < 0 || x[2] < 0 || x[0] >= nx || x[1] >= ny || x[2] >= nz {
                    out.touches_boundary = true;
                    continue;
                }
                let origin = x[0] as u32 + sy * x[1] as u32 + sz * x[2] as u32;
                // Faces 1, 2: the same cube; face 0: the cube of corner 1.
                let r = match k {
                    1 | 2 => rec_of(0, slot, records),
                    0 => rec_of(1, slot, records),
                    _ => record(slot, records, origin),
                };
                if records[r].tets & (1 << p) == 0 {
                    records[r].tets |= 1 << p;
                    stack.push(TetRef {
                        origin,
                        xyz: [x[0] as u32, x[1] as u32, x[2] as u32],
                        perm: p,
                        rec: r as u32,
                    });
                }
            }
        }
        Ok(out.indices.len() <= index_limit)
    }
}

/// A tetrahedron holding mesh edge `(a, b)`, if any: the id of its cube's
/// lowest corner and its permutation.
pub(super) fn tet_of_edge(field: &ScalarField, a: u32, b: u32) -> Option<(u32, u8)> {
    let dims = field.dims();
    let (ca, cb) = (field.coords(a), field.coords(b));
    for (p, t) in CUBE_TETRAHEDRA.iter().enumerate() {
        for &ma in t {
            // Cube origin if `a` is corner `ma`.
            let o: [i64; 3] = std::array::from_fn(|k| ca[k] as i64 - corner(ma)[k]);
            let inside = (0..3).all(|k| o[k] >= 0 && o[k] + 1 < dims[k] as i64);
            if !inside {
                continue;
            }
            let rel: [i64; 3] = std::array::from_fn(|k| cb[k] as i64 - o[k]);
            if rel.iter().any(|&r| !(0..=1).contains(&r)) {
                continue;
            }
            let mb = (rel[0] | rel[1] << 1 | rel[2] << 2) as u8;
            if mb != ma && t.contains(&mb) {
                let origin = (o[0] + dims[0] as i64 * (o[1] + dims[1] as i64 * o[2])) as u32;
                return Some((origin, p as u8));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_neighbours_share_the_face() {
        let t = TetTables::get();
        for (p, tet) in CUBE_TETRAHEDRA.iter().enumerate() {
            let own = tet.map(corner);
            for k in 0..4 {
                let (d, q) = t.neighbour[p][k];
                let theirs = CUBE_TETRAHEDRA[q as usize].map(|m| {
                    let c = corner(m);
                    [c[0] + d[0], c[1] + d[1], c[2] + d[2]]
                });
                for (l, v) in own.iter().enumerate() {
                    if l != k {
                        assert!(theirs.contains(v), "perm {p} face {k}");
                    }
                }
                assert!(
                    !theirs.contains(&own[k]),
                    "perm {p} face {k}: the same tetrahedron"
                );
            }
        }
    }
}
