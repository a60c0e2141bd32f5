//! The background pipeline: reading a volume, building its contour tree and
//! simplification on a worker thread, so the window never blocks.
//!
//! One job at a time is *current*: starting another cancels the previous
//! one through its [`Progress`] (the engine polls it; between stages the
//! worker checks it too) and the late result of a cancelled job is
//! dropped by its job number. The UI polls [`Pipeline::poll`] each frame and
//! draws [`Pipeline::running`]'s stage and fraction as a progress bar.
//!
//! [`run`] is the same computation on the calling thread, for tests.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

use crate::cli::input::InputArgs;
use crate::field::ScalarField;
use crate::progress::Progress;
use crate::simplify::{CollapsedTree, Measure, Simplification, SimplifiedTree};
use crate::tree::ContourTree;

use super::layout::TreeLayout;

/// Wall-clock times of the pipeline's stages.
#[derive(Clone, Copy, Debug, Default)]
pub struct StageTimes {
    /// Reading (or generating) the volume.
    pub load: Duration,
    /// Building the contour tree.
    pub tree: Duration,
    /// Collapsing, measuring and the whole pruning sequence.
    pub simplify: Duration,
    /// The branch layout of the tree panel.
    pub layout: Duration,
}

impl StageTimes {
    /// Sum of the stages.
    pub fn total(&self) -> Duration {
        self.load + self.tree + self.simplify + self.layout
    }
}

/// Everything the explorer shows about one volume, immutable once made.
#[derive(Clone)]
pub struct Dataset {
    /// What the user opened (file name, or "synthetic").
    pub name: String,
    /// The file, when there is one.
    pub path: Option<PathBuf>,
    /// Format description.
    pub format: String,
    /// The field.
    pub field: Arc<ScalarField>,
    /// Its smallest and largest value (computed once: a scan of the
    /// values is too slow for every frame of a big volume).
    pub range: (f64, f64),
    /// Its contour tree.
    pub tree: Arc<ContourTree>,
    /// The collapsed tree (kept so another measure needs no field pass).
    pub collapsed: Arc<CollapsedTree>,
    /// The pruning sequence under the current measure.
    pub sim: Arc<Simplification>,
    /// Where the tree panel draws each node.
    pub layout: Arc<TreeLayout>,
    /// The simplification curve as drawn (log10 feature size, log10 arcs;
    /// decimated).
    pub curve: Arc<Vec<[f64; 2]>>,
    /// The level to show first, made here because reaching it can replay
    /// millions of steps; the explorer takes it (so clones stay cheap).
    pub first_level: Option<SimplifiedTree>,
    /// Stage times.
    pub times: StageTimes,
    /// Reader warnings.
    pub warnings: Vec<String>,
}

/// What a job computes.
pub enum Request {
    /// Read a volume (a file or `synthetic[:N]`, see [`InputArgs`]).
    Open(InputArgs),
    /// Use a field already in memory (tests, the built-in default).
    Field {
        /// Shown as the dataset's name.
        name: String,
        /// The field.
        field: Arc<ScalarField>,
    },
    /// Recompute only the simplification of a dataset with another
    /// measure, its first level showing about `arcs` arcs.
    Resimplify {
        /// The dataset.
        dataset: Box<Dataset>,
        /// Arcs to show at first (those shown before).
        arcs: usize,
    },
}

/// A job's result: the dataset, or a message for the user.
pub type JobResult = Result<Dataset, String>;

/// Runs a request on the calling thread.
pub fn run(request: Request, measure: Measure, progress: &Progress) -> JobResult {
    let cancelled = || "cancelled".to_string();
    let t = Instant::now();
    let (name, path, format, field, warnings) = match request {
        Request::Resimplify { dataset: ds, arcs } => {
            progress.stage("simplify");
            let t = Instant::now();
            let sim = Arc::new(Simplification::from_collapsed(&ds.collapsed, measure));
            let simplify = t.elapsed();
            progress.stage("layout");
            let t = Instant::now();
            let (layout, curve, first_level) = views(&sim, arcs);
            let mut times = ds.times;
            times.simplify = simplify;
            times.layout = t.elapsed();
            return Ok(Dataset {
                sim,
                layout,
                curve,
                first_level,
                times,
                ..*ds
            });
        }
        Request::Field { name, field } => (name, None, "in memory".to_string(), field, Vec::new()),
        Request::Open(input) => {
            progress.stage("read");
            let volume = input.load().map_err(|e| format!("{e:#}"))?;
            let name = volume
                .path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| input.input.clone());
            let path = input
                .synthetic()
                .ok()
                .flatten()
                .is_none()
                .then(|| volume.path.clone());
            (
                name,
                path,
                volume.format,
                Arc::new(volume.field),
                volume.warnings,
            )
        }
    };
    let load = t.elapsed();
    if progress.is_cancelled() {
        return Err(cancelled());
    }
    if field.dims().iter().any(|&d| d < 2) {
        return Err(format!(
            "{name}: a {:?} grid has no tetrahedra; the explorer needs a 3D volume \
             (every axis at least 2 samples)",
            field.dims()
        ));
    }
    let t = Instant::now();
    let (tree, _) = ContourTree::from_field(&field, progress).map_err(|_| cancelled())?;
    let tree_time = t.elapsed();
    if progress.is_cancelled() {
        return Err(cancelled());
    }
    progress.stage("simplify");
    let t = Instant::now();
    let collapsed = CollapsedTree::new(&tree, &field);
    let sim = Arc::new(Simplification::from_collapsed(&collapsed, measure));
    let simplify = t.elapsed();
    if progress.is_cancelled() {
        return Err(cancelled());
    }
    progress.stage("layout");
    let t = Instant::now();
    let (layout, curve, first_level) = views(&sim, super::DEFAULT_ARCS);
    let times = StageTimes {
        load,
        tree: tree_time,
        simplify,
        layout: t.elapsed(),
    };
    let range = field.range();
    Ok(Dataset {
        name,
        path,
        format,
        range,
        field,
        tree: Arc::new(tree),
        collapsed: Arc::new(collapsed),
        sim,
        layout,
        curve,
        first_level,
        times,
        warnings,
    })
}

/// What the panels draw of a simplification: the tree layout, the curve,
/// and the level of about `arcs` arcs.
fn views(
    sim: &Arc<Simplification>,
    arcs: usize,
) -> (Arc<TreeLayout>, Arc<Vec<[f64; 2]>>, Option<SimplifiedTree>) {
    let layout = Arc::new(TreeLayout::new(sim));
    let curve = Arc::new(super::curve_panel::drawn_curve(sim));
    let mut level = SimplifiedTree::new(Arc::clone(sim));
    level.set_level(arcs);
    (layout, curve, Some(level))
}

/// The job in flight.
pub struct Running {
    /// Its number.
    pub job: u64,
    /// What it is doing ("read", "sort", "join", ..., "simplify").
    pub progress: Arc<Progress>,
    /// What the user asked for, for the progress bar.
    pub what: String,
    /// When it started.
    pub started: Instant,
}

/// The worker side of the explorer: at most one current job.
pub struct Pipeline {
    tx: Sender<(u64, JobResult)>,
    rx: Receiver<(u64, JobResult)>,
    next_job: u64,
    running: Option<Running>,
    /// Called when a result arrives (e.g. request a repaint).
    notify: Option<Arc<dyn Fn() + Send + Sync>>,
}

impl Default for Pipeline {
    fn default() -> Self {
        Self::new()
    }
}

impl Pipeline {
    /// No job yet.
    pub fn new() -> Self {
        let (tx, rx) = channel();
        Self {
            tx,
            rx,
            next_job: 0,
            running: None,
            notify: None,
        }
    }

    /// Calls `f` from the worker when a job ends (egui: request a repaint).
    pub fn set_notify(&mut self, f: Arc<dyn Fn() + Send + Sync>) {
        self.notify = Some(f);
    }

    /// The function set by [`Pipeline::set_notify`], for other workers.
    pub fn notifier(&self) -> Option<Arc<dyn Fn() + Send + Sync>> {
        self.notify.clone()
    }

    /// Starts `request` on a worker thread, cancelling the current job.
    pub fn start(&mut self, request: Request, measure: Measure, what: String) {
        self.cancel();
        self.next_job += 1;
        let job = self.next_job;
        let progress = Arc::new(Progress::new());
        progress.stage("starting");
        let tx = self.tx.clone();
        let p = Arc::clone(&progress);
        let notify = self.notify.clone();
        let spawned = std::thread::Builder::new()
            .name(format!("flexiso-job-{job}"))
            .spawn(move || {
                yield_to_ui();
                let result = run(request, measure, &p);
                // The receiver is gone only when the app has closed.
                let _ = tx.send((job, result));
                if let Some(n) = notify {
                    n();
                }
            });
        match spawned {
            Ok(_) => {
                self.running = Some(Running {
                    job,
                    progress,
                    what,
                    started: Instant::now(),
                })
            }
            Err(e) => {
                let _ = self
                    .tx
                    .send((job, Err(format!("cannot start a worker thread: {e}"))));
                self.running = Some(Running {
                    job,
                    progress,
                    what,
                    started: Instant::now(),
                });
            }
        }
    }

    /// Cancels the current job, if any (its result will be dropped).
    pub fn cancel(&mut self) {
        if let Some(r) = self.running.take() {
            r.progress.cancel();
        }
    }

    /// The job in flight.
    pub fn running(&self) -> Option<&Running> {
        self.running.as_ref()
    }

    /// The result of the current job, once it has arrived (results of
    /// cancelled jobs are dropped here).
    pub fn poll(&mut self) -> Option<JobResult> {
        while let Ok((job, result)) = self.rx.try_recv() {
            if self.running.as_ref().is_some_and(|r| r.job == job) {
                self.running = None;
                return Some(result);
            }
        }
        None
    }

    /// Blocks until the current job ends (tests); None when there is none.
    pub fn wait(&mut self) -> Option<JobResult> {
        let job = self.running.as_ref()?.job;
        while let Ok((j, result)) = self.rx.recv() {
            if j == job {
                self.running = None;
                return Some(result);
            }
        }
        None
    }
}

/// Lowers the calling thread's scheduling priority (nice 10, Linux), so
/// that the UI thread, which only draws, gets a core whenever it wants one
/// while the engine's threads fill the rest: the window keeps drawing at
/// full rate on a machine with as few cores as the engine has threads.
/// Called first thing on every background thread of the explorer (jobs,
/// extractions, the engine's rayon workers).
pub fn yield_to_ui() {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority only reads its integer arguments; `who = 0` on
    // Linux names the calling thread (nice is per thread there).
    unsafe {
        libc::setpriority(libc::PRIO_PROCESS, 0, 10);
    }
}
