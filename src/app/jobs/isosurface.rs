//! "All contours at h": every contour at the global isovalue, one mesh per
//! component, extracted by a job (a whole isosurface of a big volume takes
//! seconds on a small machine; the window keeps drawing meanwhile). One
//! extraction at a time; a value asked for while one runs is extracted
//! when it ends (the latest value wins).

use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use super::{Job, Notify};
use crate::app::ids::prepare;
use crate::contour::{ContourMesh, all_contours};
use crate::field::Isovalue;
use crate::field::ScalarField;
use crate::render::PreparedMesh;
use crate::tree::ContourTree;

/// What an extraction is of: (isovalue bits, field pointer).
pub type Key = (u64, usize);

/// An extraction's outcome: its key, the meshes (each with the same ready
/// for the GPU), milliseconds.
pub struct Isosurface {
    key: Key,
    meshes: Vec<(Arc<ContourMesh>, Arc<PreparedMesh>)>,
    millis: f64,
}

/// The meshes shown and the job making the next ones.
pub struct AllContours {
    /// Key of the meshes shown.
    key: Option<Key>,
    /// Key being extracted.
    pending: Option<Key>,
    /// The meshes shown.
    pub meshes: Vec<Arc<ContourMesh>>,
    /// The same, ready for the GPU (one per mesh).
    pub gpu: Vec<Arc<PreparedMesh>>,
    /// Bumped when the meshes change (the 3D view re-uploads).
    pub version: u64,
    /// Milliseconds the extraction shown took.
    pub millis: f64,
    job: Job<Isosurface>,
}

impl AllContours {
    /// Nothing extracted; workers call `notify` when done.
    pub fn new(notify: Option<Notify>) -> Self {
        Self {
            key: None,
            pending: None,
            meshes: Vec::new(),
            gpu: Vec::new(),
            version: 0,
            millis: 0.0,
            job: Job::new(notify),
        }
    }

    /// True while an extraction runs.
    pub fn extracting(&self) -> bool {
        self.pending.is_some()
    }

    /// True once meshes for some value are shown or coming.
    pub fn started(&self) -> bool {
        self.key.is_some() || self.pending.is_some()
    }

    /// Installs a finished extraction; true if one was installed.
    pub fn poll(&mut self) -> bool {
        match self.job.poll_take() {
            Some(Ok(iso)) => {
                self.install(iso);
                true
            }
            Some(Err(_)) => {
                self.pending = None;
                false
            }
            None => false,
        }
    }

    fn install(&mut self, iso: Isosurface) {
        self.pending = None;
        self.key = Some(iso.key);
        (self.meshes, self.gpu) = iso.meshes.into_iter().unzip();
        self.millis = iso.millis;
        self.version += 1;
    }

    /// Starts extracting the contours at `h` unless they are shown or
    /// one extraction already runs.
    pub fn request(&mut self, tree: &Arc<ContourTree>, field: &Arc<ScalarField>, h: f64) {
        let key = (h.to_bits(), Arc::as_ptr(field) as usize);
        if self.key == Some(key) || self.pending.is_some() {
            return;
        }
        self.pending = Some(key);
        let (tree, field) = (Arc::clone(tree), Arc::clone(field));
        self.job.start("all contours at h", move |_| {
            let t = Instant::now();
            let meshes: Vec<_> = all_contours(&tree, &field, Isovalue::new(h))
                .into_par_iter()
                .filter(|m| !m.indices.is_empty())
                .filter_map(|m| Some((prepare(&m)?, m)))
                .map(|(gpu, m)| (Arc::new(m), gpu))
                .collect();
            Ok(Isosurface {
                key,
                meshes,
                millis: t.elapsed().as_secs_f64() * 1e3,
            })
        });
    }

    /// Waits for the extraction in flight and installs it (tests).
    pub fn wait(&mut self) {
        if self.pending.is_some() {
            self.job.wait();
            self.poll();
        }
    }
}
