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

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use super::{Job, JobError, Notify};
use crate::app::ids::ContourId;
use crate::app::ids::prepare;
use crate::contour::follow::Cancelled;
use crate::contour::{ContourFollower, ContourMesh, FollowerScratch, MeshTopology, path_seed};
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

/// An extraction's value: the request, the mesh, its GPU form, ms.
type Extracted = (
    u64,
    Option<Arc<ContourMesh>>,
    Option<Arc<PreparedMesh>>,
    f64,
);

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
    /// one straight to the parallel sweep.
    sizes: Arc<Mutex<HashMap<ContourId, usize>>>,
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
        }
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
                let expected = sizes.lock().ok().and_then(|m| m.get(&id).copied());
                // Superseded: a newer request for this contour is queued.
                let cancel = || newest.load(Ordering::Relaxed) != request;
                let mesh =
                    extract_mesh(&field, &tree, superarc, h, &mut scratch, expected, &cancel);
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
                let gpu = mesh.as_deref().and_then(prepare);
                Ok((request, mesh, gpu, ms))
            });
    }

    /// Forgets contour `id` (removed): its late answers are dropped.
    pub fn forget(&mut self, id: ContourId) {
        self.extract.remove(&id);
        self.measure.remove(&id);
        self.to_measure.remove(&id);
        self.newest.remove(&id);
    }

    /// Forgets every contour.
    pub fn clear(&mut self) {
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
        for (&id, job) in &mut self.extract {
            if let Some(Ok((request, mesh, gpu, ms))) = job.poll_take() {
                if let Some(m) = &mesh {
                    self.to_measure.insert(id, (request, Arc::clone(m)));
                }
                done.push(Done::Mesh {
                    id,
                    request,
                    mesh,
                    gpu,
                    ms,
                });
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
        !self.to_measure.is_empty()
    }
}

/// The contour of `superarc` at `h` (None when the superarc does not span
/// h).
pub fn extract_mesh(
    field: &ScalarField,
    tree: &ContourTree,
    superarc: ArcId,
    h: f64,
    scratch: &mut FollowerScratch,
    expected: Option<usize>,
    cancel: &(dyn Fn() -> bool + Sync),
) -> Result<Option<ContourMesh>, Cancelled> {
    let iso = Isovalue::new(h);
    let Some(seed) = path_seed(tree, field, superarc, iso) else {
        return Ok(None);
    };
    // On every core for a large contour (see ContourFollower::extract).
    let mut follower = ContourFollower::with_scratch(field, std::mem::take(scratch));
    let mesh = follower.extract_expecting(&seed, iso, expected, cancel);
    *scratch = follower.into_scratch();
    mesh.map(Some)
}
