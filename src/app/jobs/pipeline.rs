//! The pipeline job: reading a volume, building its contour tree and
//! simplification on a worker thread, so the window never blocks.
//!
//! One pipeline run is current at a time (a [`super::Job`]): opening
//! another volume cancels the previous run through its [`Progress`] (the
//! engine polls it; between stages [`run`] checks it too). [`run`] is the
//! whole computation on the calling thread, for tests.

use std::sync::Arc;
use std::time::Instant;

use crate::field::ScalarField;
use crate::field::source::VolumeSource;
use crate::progress::Progress;
use crate::simplify::{CollapsedTree, Measure, Simplification};
use crate::tree::{BuildError, ContourTree};

use super::JobError;
use crate::app::dataset::{Dataset, StageTimes, views};

/// What a job computes.
pub enum Request {
    /// Read a volume (a file or a synthetic field).
    Open(VolumeSource),
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

impl Request {
    /// What the progress bar calls it.
    pub fn describe(&self, measure: Measure) -> String {
        match self {
            Request::Open(source) => source.spelling(),
            Request::Field { name, .. } => name.clone(),
            Request::Resimplify { .. } => format!("{measure} simplification"),
        }
    }
}

/// A pipeline run's outcome.
pub type JobResult = Result<Dataset, JobError>;

/// Runs a request on the calling thread.
pub fn run(request: Request, measure: Measure, progress: &Progress) -> JobResult {
    let t = Instant::now();
    let (name, path, format, field, warnings) = match request {
        Request::Resimplify { dataset: ds, arcs } => {
            progress.stage("simplify");
            let t = Instant::now();
            let sim = Arc::new(Simplification::from_collapsed(&ds.collapsed, measure));
            let simplify = t.elapsed();
            progress.stage("layout");
            let t = Instant::now();
            let v = views(&sim, Some(arcs), ds.range);
            let mut times = ds.times;
            times.simplify = simplify;
            times.layout = t.elapsed();
            return Ok(Dataset {
                sim,
                layout: v.layout,
                curve: v.curve,
                first_level: Some(v.level),
                first_screen: v.features,
                times,
                ..*ds
            });
        }
        Request::Field { name, field } => (name, None, "in memory".to_string(), field, Vec::new()),
        Request::Open(source) => {
            progress.stage("read");
            let volume = source.load().map_err(|e| JobError::Input(e.to_string()))?;
            let name = volume
                .path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| source.spelling());
            let path = source.path().map(|_| volume.path.clone());
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
        return Err(JobError::Cancelled);
    }
    if field.dims().iter().any(|&d| d < 2) {
        return Err(JobError::Input(format!(
            "{name}: a {:?} grid has no tetrahedra; the explorer needs a 3D volume \
             (every axis at least 2 samples)",
            field.dims()
        )));
    }
    let t = Instant::now();
    let (tree, _) = ContourTree::from_field(&field, progress).map_err(|e| match e {
        BuildError::Cancelled => JobError::Cancelled,
        e => JobError::Input(format!("{name}: {e}")),
    })?;
    let tree_time = t.elapsed();
    if progress.is_cancelled() {
        return Err(JobError::Cancelled);
    }
    progress.stage("simplify");
    let t = Instant::now();
    let too_big = |e: crate::simplify::memory::OutOfMemory| JobError::Input(format!("{name}: {e}"));
    crate::simplify::memory::check_collapse(tree.arcs().len()).map_err(too_big)?;
    let collapsed = CollapsedTree::new(&tree, &field);
    crate::simplify::memory::check_simplification(collapsed.num_arcs()).map_err(too_big)?;
    let sim = Arc::new(Simplification::from_collapsed(&collapsed, measure));
    let simplify = t.elapsed();
    if progress.is_cancelled() {
        return Err(JobError::Cancelled);
    }
    progress.stage("layout");
    let t = Instant::now();
    let range = field.range();
    let v = views(&sim, None, range);
    let times = StageTimes {
        load,
        tree: tree_time,
        simplify,
        layout: t.elapsed(),
    };
    Ok(Dataset {
        name,
        path,
        format,
        range,
        field,
        tree: Arc::new(tree),
        collapsed: Arc::new(collapsed),
        sim,
        layout: v.layout,
        curve: v.curve,
        first_level: Some(v.level),
        first_screen: v.features,
        times,
        warnings,
    })
}
