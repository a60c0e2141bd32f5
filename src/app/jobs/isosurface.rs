//! "All contours at h": the contours at the global isovalue, extracted by
//! a job (a whole isosurface of a big volume takes seconds on a small
//! machine; the window keeps drawing meanwhile). By default one contour
//! per arc of the *shown* (simplified) tree that spans h, the contour the
//! tree's arc stands for ([`Scope::Arcs`]: what the tree shows is what
//! the view shows); optionally every component of the level set
//! ([`Scope::Every`], noise included). One extraction at a time; a value
//! asked for while one runs is extracted when it ends (the latest value
//! wins).

use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use super::extraction::extract_mesh;
use super::{Job, Notify};
use crate::app::ids::prepare;
use crate::contour::{ContourMesh, FollowerScratch, all_contours};
use crate::field::Isovalue;
use crate::field::ScalarField;
use crate::render::PreparedMesh;
use crate::tree::ContourTree;

/// What an extraction is of: (isovalue bits, field pointer, scope: 0 for
/// every component, else 1 + the level's step).
pub type Key = (u64, usize, u64);

/// Which contours at h.
pub enum Scope {
    /// Every component of the level set.
    Every,
    /// The contours of these superarcs (one per arc of the shown tree
    /// spanning h), at the level after `step` steps.
    Arcs {
        /// The level's step (tells levels apart).
        step: usize,
        /// The superarcs.
        superarcs: Vec<crate::tree::ArcId>,
    },
}

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

    /// The key of the contours at `h` of `field` in scope `step` (None:
    /// every component; see [`Key`]).
    pub fn key_of(field: &Arc<ScalarField>, h: f64, step: Option<usize>) -> Key {
        (
            h.to_bits(),
            Arc::as_ptr(field) as usize,
            step.map_or(0, |s| s as u64 + 1),
        )
    }

    /// True when the contours of `key` are neither shown nor coming and
    /// no extraction runs (a request would start one).
    pub fn wants(&self, key: Key) -> bool {
        self.key != Some(key) && self.pending.is_none()
    }

    /// Starts extracting the contours at `h` in `scope` unless they are
    /// shown or one extraction already runs.
    pub fn request(
        &mut self,
        tree: &Arc<ContourTree>,
        field: &Arc<ScalarField>,
        h: f64,
        scope: Scope,
    ) {
        let step = match &scope {
            Scope::Every => None,
            Scope::Arcs { step, .. } => Some(*step),
        };
        let key = Self::key_of(field, h, step);
        if !self.wants(key) {
            return;
        }
        self.pending = Some(key);
        let (tree, field) = (Arc::clone(tree), Arc::clone(field));
        self.job.start("all contours at h", move |_| {
            let t = Instant::now();
            let contours = match scope {
                Scope::Every => all_contours(&tree, &field, Isovalue::new(h)),
                Scope::Arcs { superarcs, .. } => superarcs
                    .into_par_iter()
                    // One follower's tables per worker thread, reused.
                    .map_init(FollowerScratch::default, |scratch, s| {
                        extract_mesh(&field, &tree, s, h, scratch, None, None, &|| false)
                            .ok()
                            .flatten()
                    })
                    .flatten()
                    .collect(),
            };
            let meshes: Vec<_> = contours
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
