//! The hover preview: the contour a click on the hovered arc would select,
//! extracted by a job and drawn dimmed in the 3D view while the pointer
//! stays on the arc. A new hover cancels the extraction in flight; an
//! extraction that runs past [`PREVIEW_BUDGET`] gives up (the preview is
//! skipped, and says so), so a huge contour never keeps a core busy for a
//! glance.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::extraction::extract_mesh;
use super::{Job, JobError, Notify};
use crate::app::ids::prepare;
use crate::contour::FollowerScratch;
use crate::contour::follow::Cancelled;
use crate::field::ScalarField;
use crate::render::PreparedMesh;
use crate::tree::{ArcId, ContourTree};

/// How long a preview may take to extract before it is skipped.
pub const PREVIEW_BUDGET: Duration = Duration::from_millis(400);

/// What a preview is of: (superarc, isovalue bits).
pub type PreviewKey = (ArcId, u64);

/// A preview extraction's outcome.
pub enum Outcome {
    /// The mesh, ready for the GPU (None: no contour there).
    Mesh(Option<Arc<PreparedMesh>>),
    /// Over the budget: not extracted.
    Skipped,
}

/// Where the preview is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PreviewState {
    /// No preview asked for.
    Off,
    /// Being extracted.
    Extracting,
    /// Shown (or nothing to show: no contour there).
    Ready,
    /// Over the budget.
    Skipped,
}

/// The hover preview and its job.
pub struct Preview {
    key: Option<PreviewKey>,
    /// The mesh shown, when ready.
    pub mesh: Option<Arc<PreparedMesh>>,
    /// Bumped when the mesh changes (the 3D view re-uploads).
    pub version: u64,
    /// Where it is.
    pub state: PreviewState,
    job: Job<(PreviewKey, Outcome)>,
    /// The follower's tables, reused between previews.
    scratch: Arc<Mutex<Option<FollowerScratch>>>,
}

impl Preview {
    /// No preview; workers call `notify` when done.
    pub fn new(notify: Option<Notify>) -> Self {
        Self {
            key: None,
            mesh: None,
            version: 0,
            state: PreviewState::Off,
            job: Job::new(notify),
            scratch: Arc::default(),
        }
    }

    /// What the preview is of.
    pub fn key(&self) -> Option<PreviewKey> {
        self.key
    }

    /// Previews the contour of `superarc` at `h` (nothing new when it is
    /// the one shown or coming); the extraction in flight is cancelled.
    pub fn request(
        &mut self,
        field: &Arc<ScalarField>,
        tree: &Arc<ContourTree>,
        superarc: ArcId,
        h: f64,
    ) {
        let key = (superarc, h.to_bits());
        if self.key == Some(key) {
            return;
        }
        self.key = Some(key);
        self.mesh = None;
        self.version += 1;
        self.state = PreviewState::Extracting;
        let (field, tree) = (Arc::clone(field), Arc::clone(tree));
        let pool = Arc::clone(&self.scratch);
        self.job.start("preview", move |p| {
            let t = Instant::now();
            let cancel = || p.is_cancelled() || t.elapsed() > PREVIEW_BUDGET;
            let mut scratch = pool
                .lock()
                .ok()
                .and_then(|mut s| s.take())
                .unwrap_or_default();
            let mesh = extract_mesh(
                &field,
                &tree,
                superarc,
                h,
                &mut scratch,
                None,
                None,
                &cancel,
            );
            if let Ok(mut s) = pool.lock() {
                *s = Some(scratch);
            }
            match mesh {
                Ok(m) => Ok((key, Outcome::Mesh(m.as_ref().and_then(prepare)))),
                Err(Cancelled) if p.is_cancelled() => Err(JobError::Cancelled),
                Err(Cancelled) => Ok((key, Outcome::Skipped)),
            }
        });
    }

    /// No preview (the pointer left the arcs, or a drag began).
    pub fn clear(&mut self) {
        if self.key.is_some() {
            self.job.cancel();
            self.key = None;
            self.mesh = None;
            self.version += 1;
            self.state = PreviewState::Off;
        }
    }

    /// Installs a finished extraction of the preview asked for last; true
    /// if one was installed.
    pub fn poll(&mut self) -> bool {
        match self.job.poll_take() {
            Some(Ok((key, outcome))) if Some(key) == self.key => {
                match outcome {
                    Outcome::Mesh(m) => {
                        self.mesh = m;
                        self.state = PreviewState::Ready;
                    }
                    Outcome::Skipped => self.state = PreviewState::Skipped,
                }
                self.version += 1;
                true
            }
            _ => false,
        }
    }

    /// Blocks until the extraction in flight ends and installs it (tests).
    pub fn wait(&mut self) {
        self.job.wait();
        self.poll();
    }
}
