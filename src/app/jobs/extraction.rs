//! Contour extraction and measurement, as jobs: one extraction and one
//! measurement per contour at a time, each [`Job::start_latest`], so while
//! an isovalue is dragged the values asked for meanwhile collapse into the
//! newest one and a contour of millions of triangles lags behind the
//! pointer instead of freezing the window. A mesh is installed as soon as
//! it is extracted; its measurements (topology, area, volume: several
//! times the extraction's cost) start only when no newer extraction of the
//! contour is waiting, so dragging shows new meshes at extraction speed.
//! Every answer carries its request number; the selection drops answers
//! older than what it shows.
//!
//! **Dragging.** Once a contour's size is known and it is small enough
//! that a kept step beats the parallel sweep ([`kept_limit`], at most
//! [`KEPT_TRIANGLES`]), its next request starts a [`DraggedContour`] kept
//! for the contour last dragged, and the requests after that move it at
//! the cost of what changed (the same mesh, see [`crate::contour::drag`]):
//! on colin27_ch2 a 156k-triangle contour's step takes 7 ms instead of 30,
//! a 229k-326k-triangle one's 15 ms instead of 21. Larger contours (an
//! 854k-triangle one: 32 ms a step instead of 45 kept; the head, 5.4 M
//! triangles) are extracted afresh by the parallel sweep, which is faster
//! there. A refused step (the change as large as the contour, or
//! a contour not reached through the slab between the two cuts) starts
//! afresh.
//!
//! **Kept ahead.** A contour small enough to keep extracted
//! afresh (a click, its size unknown until then) is then kept at its
//! isovalue by a background job, so that the first step of a drag that
//! follows also costs only what changed: on colin27_ch2 an 854k-triangle
//! contour's first step cost 150-250 ms (following it and keeping it),
//! and became a step of 45-85 ms (800 ms and 156-325 ms in the window
//! without a GPU), when contours of that size were still kept. The job
//! gives up as soon as a newer request for the contour comes (that
//! request then keeps it itself, as before) or the contour is removed; it
//! holds the cores only while the user has not moved yet.
//!
//! **Spares.** A kept contour's step writes its mesh, and its GPU form,
//! into the arrays of one it made two steps before, once the window and
//! the measurement have let that one go ([`DraggedContour::recycle`],
//! [`PreparedMesh::new_reusing`]): fresh arrays are fresh pages, which
//! the kernel faults in and zeroes at every step, and this program returns
//! freed arrays to the system at once ([`crate::pages::return_freed_arrays`]).
//! An 854k-triangle contour's step and preparation took 77-84 ms that way
//! and 52-61 ms with spares (median of 20 steps, `FLEXISO_BENCH_DRAG=1
//! FLEXISO_BENCH_QUICK=1 cargo bench --bench contour`, 2 cores). A drag
//! step of a contour too large to keep (the head) is written into a
//! spare's arrays by the parallel sweep in the same way
//! ([`ContourFollower::recycle`]): on colin27_ch2's head (5.4 M triangles)
//! about 130 MB of fresh pages per step less. At most [`SPARES`] meshes of
//! each kind are held, the one on screen among them: after a drag of the
//! head, one spare mesh and GPU form (about 190 MB) stay until the
//! contour is removed.
//!
//! **Spares ahead.** A contour too large to keep, extracted afresh (a
//! click on the head), is handed to the spares like a drag step's, and a
//! background job then makes one spare mesh and GPU form of its size with
//! a quarter more room, pages touched ([`ContourMesh::spare`],
//! [`PreparedMesh::spare`]), while the hand has not moved yet: the first
//! step of a drag writes into those, the second into the click's. Before,
//! the first two steps of a drag of the head faulted in fresh pages (290
//! and 170 ms against 125-140 for the others, `FLEXISO_BENCH_DRAG=1
//! FLEXISO_BENCH_QUICK=1 cargo bench --bench contour`; fresh pages are
//! dear on these virtual machines, which hand freed memory back to their
//! host). The spares of a removed contour go with it.

use std::collections::{HashMap, VecDeque};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use super::{Job, JobError, Notify};
use crate::app::ids::ContourId;
use crate::app::ids::{prepare, prepare_reusing};
use crate::contour::drag::{kept_limit, step_budget};
use crate::contour::follow::Cancelled;
use crate::contour::{
    ContourFollower, ContourMesh, DraggedContour, FollowerScratch, MeshTopology, path_seed,
};
use crate::field::{Isovalue, ScalarField};
use crate::render::PreparedMesh;
use crate::tree::{ArcId, ContourTree};

/// A worker's answer for one contour.
pub enum Done {
    /// The mesh of request `request` (None: the superarc does not span h).
    Mesh {
        /// The contour.
        id: ContourId,
        /// The request answered.
        request: u64,
        /// The mesh.
        mesh: Option<Arc<ContourMesh>>,
        /// The same ready for the GPU.
        gpu: Option<Arc<PreparedMesh>>,
        /// Milliseconds the extraction took.
        ms: f64,
    },
    /// The measurements of the mesh of request `request`.
    Topology {
        /// The contour.
        id: ContourId,
        /// The request whose mesh was measured.
        request: u64,
        /// Its measurements.
        topology: MeshTopology,
    },
}

/// Contours of at most this many triangles may be dragged by a kept
/// [`DraggedContour`] (it holds about 65 bytes per triangle); those the
/// parallel sweep extracts afresh faster ([`kept_limit`]) and all larger
/// ones are extracted afresh at every step. Measured on colin27_ch2
/// (`cargo bench --bench contour`, 2 cores), a kept contour's step with
/// its GPU preparation against extracting afresh: 7 ms against 30 at 156k
/// triangles; 65 ms against 124 and 83 at 854k; 132 / 186 ms (median /
/// worst) against 231 and 135 at 1.4-1.8 M; 1008 ms against 341 at 5.4 M
/// (every vertex moves at every step; see `contour::drag` for why the
/// flood's order is not the cause). Since the sweep's passes moved fewer
/// bytes and its arrays are recycled, 15 ms against 21 at 229k-326k and
/// 45 against 32 at 802k-881k (session 25): the limit is now the volume's
/// [`kept_limit`], about 460k triangles there.
pub const KEPT_TRIANGLES: usize = 1_000_000;

/// The most triangles a contour of a volume of `voxels` kept for dragging
/// has: where a kept step stops beating the parallel sweep on this
/// machine's cores ([`kept_limit`]), at most [`KEPT_TRIANGLES`].
pub fn kept_triangles(voxels: usize) -> usize {
    kept_limit(voxels, rayon::current_num_threads(), KEPT_TRIANGLES)
}

/// Volumes of at most this many vertices keep a dragged contour: it holds
/// 4 bytes per vertex of the volume (its slot table) while kept.
const KEPT_VOLUME: usize = 1 << 26;

/// Meshes the spares hold, the newest among them (see the module
/// documentation).
const SPARES: usize = 2;

/// The kept contour's last meshes and their GPU forms, newest last.
#[derive(Default)]
struct Spares {
    meshes: VecDeque<Arc<ContourMesh>>,
    gpu: VecDeque<Arc<PreparedMesh>>,
    /// Meshes and GPU forms taken out so far.
    taken: usize,
    /// The contour whose meshes these are (its removal lets them go).
    owner: Option<ContourId>,
}

impl Spares {
    /// The oldest mesh no one else holds any more, taken out.
    fn mesh(&mut self) -> Option<ContourMesh> {
        let i = self.meshes.iter().position(|m| Arc::strong_count(m) == 1)?;
        let m = Arc::try_unwrap(self.meshes.remove(i)?).ok();
        self.taken += m.is_some() as usize;
        m
    }

    /// The oldest GPU form no one else holds any more, taken out.
    fn gpu(&mut self) -> Option<PreparedMesh> {
        let i = self.gpu.iter().position(|m| Arc::strong_count(m) == 1)?;
        let m = Arc::try_unwrap(self.gpu.remove(i)?).ok();
        self.taken += m.is_some() as usize;
        m
    }

    /// Remembers a mesh of contour `owner` just handed out; the oldest
    /// beyond [`SPARES`] go.
    fn hand(&mut self, owner: ContourId, mesh: &Arc<ContourMesh>, gpu: Option<&Arc<PreparedMesh>>) {
        self.owner = Some(owner);
        self.meshes.push_back(Arc::clone(mesh));
        self.gpu.extend(gpu.cloned());
        while self.meshes.len() > SPARES {
            self.meshes.pop_front();
        }
        while self.gpu.len() > SPARES {
            self.gpu.pop_front();
        }
    }
}

/// The contour last dragged, kept between its requests.
struct Kept {
    id: ContourId,
    /// The field it was made from (a new volume's contours never match).
    field: Arc<ScalarField>,
    contour: DraggedContour,
}

/// An extraction's value: the request, the mesh, its GPU form, ms, and
/// what to make ahead for a drag when it was extracted afresh.
type Extracted = (
    u64,
    Option<Arc<ContourMesh>>,
    Option<Arc<PreparedMesh>>,
    f64,
    Option<Ahead>,
);

/// What a contour just extracted afresh (a click) gets ready, in the
/// background, for a drag that may follow (see the module documentation).
enum Ahead {
    /// Small enough to keep: the contour kept at its isovalue.
    Keep(KeepAhead),
    /// Larger: a spare mesh and GPU form of its size, pages touched, for
    /// the first drag step to write into.
    Spares {
        arc: ArcId,
        vertices: usize,
        triangles: usize,
    },
}

/// A contour to keep for dragging at the isovalue it was just extracted
/// at (see the module documentation).
struct KeepAhead {
    field: Arc<ScalarField>,
    tree: Arc<ContourTree>,
    superarc: ArcId,
    h: f64,
}

/// The extraction and measurement jobs of every contour.
pub struct Extractions {
    notify: Option<Notify>,
    extract: HashMap<ContourId, Job<Extracted>>,
    measure: HashMap<ContourId, Job<(u64, MeshTopology)>>,
    /// Meshes waiting to be measured once their contour's extractions end.
    to_measure: HashMap<ContourId, (u64, Arc<ContourMesh>)>,
    /// The follower's per-vertex tables, reused between jobs.
    scratch: Arc<Mutex<Vec<FollowerScratch>>>,
    /// The newest request per contour: an extraction whose request is no
    /// longer the newest stops inside the flood (newest isovalue wins).
    newest: HashMap<ContourId, Arc<AtomicU64>>,
    /// Triangles of each contour's last mesh: the follower takes a large
    /// one straight to the parallel sweep, a smaller one is dragged by the
    /// contour kept in `kept`.
    sizes: Arc<Mutex<HashMap<ContourId, usize>>>,
    /// The contour last dragged (see the module documentation).
    kept: Arc<Mutex<Option<Kept>>>,
    /// Its last meshes, whose arrays its next steps reuse.
    spares: Arc<Mutex<Spares>>,
    /// Keeps the contour last extracted afresh, or makes spares for it
    /// (see the module documentation); it tells no one when done.
    keep_ahead: Job<()>,
    /// The most triangles a contour kept for dragging has: the volume's
    /// [`kept_limit`] when None (set in tests).
    kept_triangles: Option<usize>,
}

impl std::fmt::Debug for Extractions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Extractions({} running)", self.extract.len())
    }
}

impl Extractions {
    /// No job yet; workers call `notify` after each answer.
    pub fn new(notify: Option<Notify>) -> Self {
        Self {
            notify,
            extract: HashMap::new(),
            measure: HashMap::new(),
            to_measure: HashMap::new(),
            scratch: Arc::new(Mutex::new(Vec::new())),
            newest: HashMap::new(),
            sizes: Arc::default(),
            kept: Arc::default(),
            spares: Arc::default(),
            keep_ahead: Job::new(None),
            kept_triangles: None,
        }
    }

    /// The most triangles a contour of `field` kept for dragging has
    /// ([`kept_triangles`], unless a test set it).
    fn kept_triangles(&self, field: &ScalarField) -> usize {
        self.kept_triangles
            .unwrap_or_else(|| kept_triangles(field.len()))
    }

    /// Extracts the contour of `superarc` at `h` as request `request` of
    /// contour `id` (after the one in flight, if any).
    pub fn request(
        &mut self,
        id: ContourId,
        request: u64,
        field: &Arc<ScalarField>,
        tree: &Arc<ContourTree>,
        superarc: ArcId,
        h: f64,
    ) {
        self.to_measure.remove(&id);
        // A measurement of the last mesh stops: the new one is measured
        // when it arrives, and the extraction needs the cores now.
        if let Some(job) = self.measure.get_mut(&id) {
            job.cancel();
        }
        let (field, tree) = (Arc::clone(field), Arc::clone(tree));
        let pool = Arc::clone(&self.scratch);
        let notify = self.notify.clone();
        let newest = Arc::clone(self.newest.entry(id).or_default());
        newest.store(request, Ordering::Relaxed);
        let sizes = Arc::clone(&self.sizes);
        let kept = Arc::clone(&self.kept);
        let kept_triangles = self.kept_triangles(&field);
        let spares = Arc::clone(&self.spares);
        self.extract
            .entry(id)
            .or_insert_with(|| Job::new(notify))
            .start_latest("extract", move |_| {
                let t = std::time::Instant::now();
                let mut scratch = pool
                    .lock()
                    .ok()
                    .and_then(|mut p| p.pop())
                    .unwrap_or_default();
                let mut expected = sizes.lock().ok().and_then(|m| m.get(&id).copied());
                // A click: the contour's size unknown until now.
                let click = expected.is_none();
                // Superseded: a newer request for this contour is queued.
                let cancel = || newest.load(Ordering::Relaxed) != request;
                let (mesh, afresh, recycled) = match drag_step(
                    &kept,
                    &spares,
                    id,
                    &field,
                    &tree,
                    superarc,
                    h,
                    &mut expected,
                    kept_triangles,
                    &cancel,
                ) {
                    Some(mesh) => (mesh, false, true),
                    None => {
                        // A drag step of a contour too large to keep: into
                        // a spare's arrays, as a kept contour's step.
                        let large = expected.is_some_and(|e| e > kept_triangles);
                        let spare = large
                            .then(|| spares.lock().ok().and_then(|mut s| s.mesh()))
                            .flatten();
                        let mesh = extract_mesh(
                            &field,
                            &tree,
                            superarc,
                            h,
                            &mut scratch,
                            expected,
                            spare,
                            &cancel,
                        );
                        (mesh, true, large)
                    }
                };
                if let Ok(mut p) = pool.lock() {
                    p.push(scratch);
                }
                // Nothing is sent for a cancelled run: the old mesh stays
                // drawn until the newer request's is complete.
                let mesh = mesh.map_err(|Cancelled| JobError::Cancelled)?;
                if let (Some(m), Ok(mut s)) = (&mesh, sizes.lock()) {
                    s.insert(id, m.num_triangles());
                }
                let mesh = mesh.map(Arc::new);
                let ms = t.elapsed().as_secs_f64() * 1e3;
                // A contour too large to keep is dragged through the
                // spares: its click's mesh among them.
                let large = |m: &ContourMesh| m.num_triangles() > kept_triangles;
                let gpu = match &mesh {
                    Some(m) if recycled || large(m) => {
                        let spare = spares.lock().ok().and_then(|mut s| s.gpu());
                        let gpu = prepare_reusing(m, spare.unwrap_or_default());
                        if let Ok(mut s) = spares.lock() {
                            s.hand(id, m, gpu.as_ref());
                        }
                        gpu
                    }
                    _ => mesh.as_deref().and_then(prepare),
                };
                let ahead = match mesh.as_deref() {
                    Some(m) if click && large(m) => Some(Ahead::Spares {
                        arc: superarc,
                        vertices: m.positions.len(),
                        triangles: m.num_triangles(),
                    }),
                    Some(m) if afresh && !large(m) && field.len() <= KEPT_VOLUME => {
                        Some(Ahead::Keep(KeepAhead {
                            field,
                            tree,
                            superarc,
                            h,
                        }))
                    }
                    _ => None,
                };
                Ok((request, mesh, gpu, ms, ahead))
            });
    }

    /// Keeps contour `id` at the isovalue of request `request`, in the
    /// background, unless a newer request or its removal comes first.
    fn keep_ahead(&mut self, id: ContourId, request: u64, ahead: KeepAhead) {
        let kept = Arc::clone(&self.kept);
        let kept_triangles = self.kept_triangles(&ahead.field);
        let Some(newest) = self.newest.get(&id).map(Arc::clone) else {
            return;
        };
        self.keep_ahead.start("keep for dragging", move |progress| {
            let stale = || progress.is_cancelled() || newest.load(Ordering::Relaxed) != request;
            let KeepAhead {
                field,
                tree,
                superarc,
                h,
            } = ahead;
            let iso = Isovalue::new(h);
            let Some(seed) = path_seed(&tree, &field, superarc, iso) else {
                return Ok(());
            };
            // Its mesh is the one just extracted: only the state is made.
            if let Ok(Some(contour)) =
                DraggedContour::keep(&field, &seed, iso, kept_triangles, &stale)
                && let Ok(mut slot) = kept.lock()
                // Asked under the lock: `forget` cancels, then empties the
                // slot under it, so a removed contour is never left kept.
                && !stale()
            {
                *slot = Some(Kept { id, field, contour });
            }
            Ok(())
        });
    }

    /// Makes a spare mesh and GPU form for the first drag step of contour
    /// `id`, a contour too large to keep (see the module documentation),
    /// in the background unless it is removed first. Offered even when a
    /// drag has begun meanwhile: a later step writes into it.
    fn spares_ahead(&mut self, id: ContourId, arc: ArcId, vertices: usize, triangles: usize) {
        let spares = Arc::clone(&self.spares);
        self.keep_ahead
            .start("spares for dragging", move |progress| {
                let mesh = Arc::new(ContourMesh::spare(arc, vertices, triangles));
                if progress.is_cancelled() {
                    return Ok(());
                }
                let gpu = Arc::new(PreparedMesh::spare(vertices, triangles));
                if let Ok(mut s) = spares.lock()
                // Asked under the lock: `forget` cancels, then empties the
                // spares under it.
                && !progress.is_cancelled()
                {
                    s.hand(id, &mesh, Some(&gpu));
                }
                Ok(())
            });
    }

    /// Forgets contour `id` (removed): its late answers are dropped.
    pub fn forget(&mut self, id: ContourId) {
        self.keep_ahead.cancel();
        if let Ok(mut k) = self.kept.lock()
            && k.as_ref().is_some_and(|k| k.id == id)
        {
            *k = None;
        }
        if let Ok(mut s) = self.spares.lock()
            && s.owner == Some(id)
        {
            *s = Spares::default();
        }
        self.extract.remove(&id);
        self.measure.remove(&id);
        self.to_measure.remove(&id);
        self.newest.remove(&id);
    }

    /// Forgets every contour.
    pub fn clear(&mut self) {
        self.keep_ahead.cancel();
        if let Ok(mut k) = self.kept.lock() {
            *k = None;
        }
        if let Ok(mut s) = self.spares.lock() {
            *s = Spares::default();
        }
        self.extract.clear();
        self.measure.clear();
        self.to_measure.clear();
        self.newest.clear();
    }

    /// True while contour `id` has an extraction running or queued.
    pub fn extracting(&self, id: ContourId) -> bool {
        self.extract.get(&id).is_some_and(Job::is_running)
    }

    /// The answers that have arrived, and measurements started for meshes
    /// whose contour has no newer extraction waiting.
    pub fn poll(&mut self) -> Vec<Done> {
        let mut done = Vec::new();
        let mut ahead = Vec::new();
        self.keep_ahead.poll_take();
        for (&id, job) in &mut self.extract {
            if let Some(Ok((request, mesh, gpu, ms, keep))) = job.poll_take() {
                if let Some(m) = &mesh {
                    self.to_measure.insert(id, (request, Arc::clone(m)));
                }
                ahead.extend(keep.map(|k| (id, request, k)));
                done.push(Done::Mesh {
                    id,
                    request,
                    mesh,
                    gpu,
                    ms,
                });
            }
        }
        for (id, request, k) in ahead {
            match k {
                Ahead::Keep(k) => self.keep_ahead(id, request, k),
                Ahead::Spares {
                    arc,
                    vertices,
                    triangles,
                } => self.spares_ahead(id, arc, vertices, triangles),
            }
        }
        for (&id, job) in &mut self.measure {
            if let Some(Ok((request, topology))) = job.poll_take() {
                done.push(Done::Topology {
                    id,
                    request,
                    topology,
                });
            }
        }
        let idle: Vec<ContourId> = self
            .to_measure
            .keys()
            .copied()
            .filter(|id| !self.extracting(*id))
            .collect();
        for id in idle {
            if let Some((request, mesh)) = self.to_measure.remove(&id) {
                let notify = self.notify.clone();
                self.measure
                    .entry(id)
                    .or_insert_with(|| Job::new(notify))
                    .start_latest("measure", move |progress| {
                        let cancel = || progress.is_cancelled();
                        MeshTopology::measure(&mesh.positions, &mesh.indices, &cancel)
                            .map(|topology| (request, topology))
                            .map_err(|_| JobError::Cancelled)
                    });
            }
        }
        done
    }

    /// True while anything runs or waits to be measured.
    pub fn busy(&self) -> bool {
        !self.to_measure.is_empty()
            || self.extract.values().any(Job::is_running)
            || self.measure.values().any(Job::is_running)
    }

    /// Blocks until one job in flight answers (tests); false when none runs.
    pub fn wait_one(&mut self) -> bool {
        if let Some(job) = self.extract.values_mut().find(|j| j.is_running()) {
            job.wait();
            return true;
        }
        if let Some(job) = self.measure.values_mut().find(|j| j.is_running()) {
            job.wait();
            return true;
        }
        if self.keep_ahead.is_running() {
            self.keep_ahead.wait();
            return true;
        }
        !self.to_measure.is_empty()
    }
}

/// The contour of `superarc` at `h` by the contour kept for dragging
/// (see the module documentation): moved there if it is `id`'s, else
/// started there, when `id`'s last mesh had at most `kept_triangles`
/// (`expected`). None when this is not the way (no size known, a large
/// contour or volume, a 2D grid, or a contour that proved larger than the
/// limit while it was being kept: `expected` then says so): then
/// [`extract_mesh`].
#[allow(clippy::too_many_arguments)]
fn drag_step(
    kept: &Mutex<Option<Kept>>,
    spares: &Mutex<Spares>,
    id: ContourId,
    field: &Arc<ScalarField>,
    tree: &ContourTree,
    superarc: ArcId,
    h: f64,
    expected: &mut Option<usize>,
    kept_triangles: usize,
    cancel: &(dyn Fn() -> bool + Sync),
) -> Option<Result<Option<ContourMesh>, Cancelled>> {
    let small = expected.is_some_and(|n| n <= kept_triangles) && field.len() <= KEPT_VOLUME;
    // Taken out while it moves (the lock is not held meanwhile: other
    // contours' jobs look at it too); another contour's is left alone.
    let ours = kept.lock().ok().and_then(|mut slot| {
        let is_ours = slot
            .as_ref()
            .is_some_and(|k| k.id == id && Arc::ptr_eq(&k.field, field));
        if is_ours { slot.take() } else { None }
    });
    if !small {
        // Grown past the limit: let it go.
        return None;
    }
    let keep = |k: Kept| {
        if let Ok(mut slot) = kept.lock() {
            *slot = Some(k);
        }
    };
    let iso = Isovalue::new(h);
    if let Some(mut k) = ours {
        if let Some(spare) = spares.lock().ok().and_then(|mut s| s.mesh()) {
            k.contour.recycle(spare);
        }
        let budget = step_budget(k.contour.num_triangles());
        match k.contour.step(tree, superarc, iso, budget, cancel) {
            Ok(Ok(mesh)) => {
                keep(k);
                return Some(Ok(Some(mesh)));
            }
            // Whole, at the old cut or the new one.
            Err(Cancelled) => {
                keep(k);
                return Some(Err(Cancelled));
            }
            // Too large a change, or another part of the tree: afresh.
            Ok(Err(_refused)) => {}
        }
    }
    let Some(seed) = path_seed(tree, field, superarc, iso) else {
        return Some(Ok(None));
    };
    // A jump to a contour too large to keep (the head, from a structure
    // inside it) gives up after about a million tetrahedra and is
    // extracted afresh, instead of flooding and keeping all of it.
    match DraggedContour::start_within(field, &seed, iso, kept_triangles, cancel) {
        Ok(Some((contour, mesh))) => {
            keep(Kept {
                id,
                field: Arc::clone(field),
                contour,
            });
            Some(Ok(Some(mesh)))
        }
        Ok(None) => {
            // Given up past the limit (or no contour to keep): at least
            // that large, which sends it to the sweep sooner.
            *expected = expected.map(|n| n.max(kept_triangles + 1));
            None
        }
        Err(c) => Some(Err(c)),
    }
}

/// The contour of `superarc` at `h` (None when the superarc does not span
/// h), written into `spare`'s arrays when it goes to the parallel sweep
/// ([`ContourFollower::recycle`]).
#[allow(clippy::too_many_arguments)]
pub fn extract_mesh(
    field: &ScalarField,
    tree: &ContourTree,
    superarc: ArcId,
    h: f64,
    scratch: &mut FollowerScratch,
    expected: Option<usize>,
    spare: Option<ContourMesh>,
    cancel: &(dyn Fn() -> bool + Sync),
) -> Result<Option<ContourMesh>, Cancelled> {
    let iso = Isovalue::new(h);
    let Some(seed) = path_seed(tree, field, superarc, iso) else {
        return Ok(None);
    };
    // On every core for a large contour (see ContourFollower::extract).
    let mut follower = ContourFollower::with_scratch(field, std::mem::take(scratch));
    if let Some(spare) = spare {
        follower.recycle(spare);
    }
    let mesh = follower.extract_expecting(tree, &seed, iso, expected, cancel);
    *scratch = follower.into_scratch();
    mesh.map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::progress::Progress;

    type Scene = (Arc<ScalarField>, Arc<ContourTree>, ArcId, f64, f64);

    /// The synthetic cube of side 24, its tree, and its arc spanning the
    /// widest range of values with that range's ends.
    fn cube_and_its_longest_arc() -> Scene {
        let field = Arc::new(Synthetic::cube(24).generate());
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
        let (arc, lo, hi) = (0..tree.arcs().len() as u32)
            .map(|a| {
                let e = tree.arc(ArcId(a));
                let value = |n| field.value(tree.node(n).vertex);
                (ArcId(a), value(e.lower), value(e.upper))
            })
            .max_by(|x, y| (x.2 - x.1).total_cmp(&(y.2 - y.1)))
            .expect("arcs");
        (field, Arc::new(tree), arc, lo, hi)
    }

    /// The mesh answering request `request`, once every job (extraction,
    /// measurement, keeping ahead) is done.
    fn answer(jobs: &mut Extractions, request: u64) -> Arc<ContourMesh> {
        let mut mesh = None;
        while jobs.wait_one() {
            for d in jobs.poll() {
                if let Done::Mesh {
                    request: r,
                    mesh: m,
                    ..
                } = d
                    && r == request
                {
                    mesh = Some(m.expect("the arc spans h"));
                }
            }
        }
        mesh.expect("the request answered")
    }

    /// Jobs that keep a dragged contour of up to [`KEPT_TRIANGLES`]
    /// triangles whatever this machine's cores: on 8 or more,
    /// [`kept_limit`] keeps none of the test cube's contours, which the
    /// parallel sweep extracts faster there.
    fn keeping_jobs() -> Extractions {
        let mut jobs = Extractions::new(None);
        jobs.kept_triangles = Some(KEPT_TRIANGLES);
        jobs
    }

    /// The contour of `arc` at `h` extracted afresh, with nothing kept.
    fn afresh(field: &ScalarField, tree: &ContourTree, arc: ArcId, h: f64) -> ContourMesh {
        let mut scratch = FollowerScratch::default();
        extract_mesh(field, tree, arc, h, &mut scratch, None, None, &|| false)
            .expect("not cancelled")
            .expect("the arc spans h")
    }

    /// Requests along an arc, as a drag makes them: the first (its size
    /// unknown) is extracted afresh and then kept ahead at its isovalue,
    /// every later one is answered by the contour kept for dragging; each
    /// gives the mesh extracted afresh (the same oriented triangles on the
    /// same vertices), and forgetting the contour lets the kept one go.
    #[test]
    fn a_dragged_contour_is_kept_and_gives_the_mesh_extracted_afresh() {
        let (field, tree, arc, lo, hi) = cube_and_its_longest_arc();
        let mut jobs = keeping_jobs();
        let id = ContourId(7);
        let steps = 6u64;
        for k in 0..steps {
            let h = lo + (hi - lo) * (0.3 + 0.4 * k as f64 / steps as f64);
            jobs.request(id, k + 1, &field, &tree, arc, h);
            let mesh = answer(&mut jobs, k + 1);
            let fresh = afresh(&field, &tree, arc, h);
            assert!(fresh.num_triangles() > 0);
            assert_eq!(
                mesh.triangle_soup(),
                fresh.triangle_soup(),
                "step {k}: the same triangles"
            );
            assert_eq!(mesh.positions.len(), fresh.positions.len(), "step {k}");
            let kept = jobs
                .kept
                .lock()
                .expect("not poisoned")
                .as_ref()
                .map(|k| (k.id, k.contour.isovalue().value));
            assert_eq!(
                kept,
                Some((id, Isovalue::new(h).value)),
                "step {k}: the contour kept (ahead, after the first)"
            );
        }
        // From the third request on (at the latest), each step's mesh and
        // GPU form were made in the arrays of earlier ones, let go by
        // then: the meshes compared above came out of recycled arrays.
        let taken = jobs.spares.lock().expect("not poisoned").taken;
        let steps = steps as usize;
        assert!(
            (2 * (steps - 2)..=2 * (steps - 1)).contains(&taken),
            "{taken} spares taken"
        );
        jobs.forget(id);
        assert!(jobs.kept.lock().expect("not poisoned").is_none());
        assert!(jobs.spares.lock().expect("not poisoned").meshes.is_empty());
    }

    /// A contour too large to keep (the limit lowered to 10 triangles):
    /// after the click its mesh and a spare made ahead, with room, wait in
    /// the spares; the first drag step takes the spare (the click's mesh
    /// is on screen), every step gives the mesh extracted afresh and
    /// nothing is kept, and removing the contour lets the spares go.
    #[test]
    fn a_contour_too_large_to_keep_is_dragged_through_spares_made_ahead() {
        let (field, tree, arc, lo, hi) = cube_and_its_longest_arc();
        let mut jobs = Extractions::new(None);
        jobs.kept_triangles = Some(10);
        let id = ContourId(5);
        // What the window shows: the newest mesh.
        let mut shown: Option<Arc<ContourMesh>> = None;
        let mut click = None;
        for k in 0..4u64 {
            let h = lo + (hi - lo) * (0.3 + 0.1 * k as f64);
            jobs.request(id, k + 1, &field, &tree, arc, h);
            let mesh = shown.insert(answer(&mut jobs, k + 1));
            let fresh = afresh(&field, &tree, arc, h);
            assert!(fresh.num_triangles() > 10);
            assert_eq!(mesh.triangle_soup(), fresh.triangle_soup(), "step {k}");
            assert!(
                jobs.kept.lock().expect("not poisoned").is_none(),
                "step {k}"
            );
            let spares = jobs.spares.lock().expect("not poisoned");
            assert_eq!(spares.owner, Some(id));
            let room = |m: &ContourMesh| m.positions.len() >= fresh.positions.len() * 5 / 4;
            if k == 0 {
                // The click's mesh, then the spare made ahead.
                assert_eq!(spares.meshes.len(), 2);
                assert!(Arc::ptr_eq(&spares.meshes[0], mesh));
                assert!(room(&spares.meshes[1]));
                assert!(spares.meshes[1].indices.len() >= 3 * fresh.num_triangles() * 5 / 4);
                assert_eq!(spares.gpu.len(), 2);
                assert_eq!(spares.taken, 0);
                click = Some(Arc::clone(mesh));
            } else {
                // Spares taken: the one made ahead by the first step,
                // while the click's mesh was on screen.
                assert!(
                    spares.taken >= 2 * k as usize - 1,
                    "step {k}: {}",
                    spares.taken
                );
                if let Some(click) = click.take() {
                    assert!(Arc::ptr_eq(&spares.meshes[0], &click), "the click's left");
                }
            }
        }
        jobs.forget(id);
        let spares = jobs.spares.lock().expect("not poisoned");
        assert!(spares.meshes.is_empty() && spares.gpu.is_empty());
    }

    /// A contour removed while it is being kept ahead, or asked for again
    /// meanwhile, is never left kept by that job: the slot ends empty, or
    /// holds the newer request's contour.
    #[test]
    fn keeping_ahead_gives_way_to_removal_and_newer_requests() {
        let field = Arc::new(Synthetic::cube(32).generate());
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
        let tree = Arc::new(tree);
        let arc = (0..tree.arcs().len() as u32)
            .map(ArcId)
            .max_by(|&x, &y| {
                let span = |a: ArcId| {
                    let e = tree.arc(a);
                    field.value(tree.node(e.upper).vertex) - field.value(tree.node(e.lower).vertex)
                };
                span(x).total_cmp(&span(y))
            })
            .expect("arcs");
        let e = tree.arc(arc);
        let (lo, hi) = (
            field.value(tree.node(e.lower).vertex),
            field.value(tree.node(e.upper).vertex),
        );
        let h = lo + 0.5 * (hi - lo);
        let id = ContourId(3);
        let first_mesh = |jobs: &mut Extractions, request: u64| loop {
            assert!(jobs.wait_one(), "an extraction in flight");
            if jobs
                .poll()
                .iter()
                .any(|d| matches!(d, Done::Mesh { request: r, .. } if *r == request))
            {
                break;
            }
        };
        for _ in 0..5 {
            // Removed right after its mesh arrived (the keeping job has
            // just started, or has finished).
            let mut jobs = keeping_jobs();
            jobs.request(id, 1, &field, &tree, arc, h);
            first_mesh(&mut jobs, 1);
            jobs.forget(id);
            while jobs.wait_one() {
                jobs.poll();
            }
            assert!(jobs.kept.lock().expect("not poisoned").is_none());
            // Asked for again at once: whatever is kept is the contour
            // at the newer request's isovalue.
            let h2 = lo + 0.55 * (hi - lo);
            let mut jobs = keeping_jobs();
            jobs.request(id, 1, &field, &tree, arc, h);
            first_mesh(&mut jobs, 1);
            jobs.request(id, 2, &field, &tree, arc, h2);
            while jobs.wait_one() {
                jobs.poll();
            }
            let kept = jobs
                .kept
                .lock()
                .expect("not poisoned")
                .as_ref()
                .map(|k| k.contour.isovalue().value);
            assert_eq!(kept, Some(Isovalue::new(h2).value));
        }
    }
}
