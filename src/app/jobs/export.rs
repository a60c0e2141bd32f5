//! Exports (contour meshes, the tree as JSON, the 3D view as PNG): what to
//! write is gathered cheaply on the UI thread, then written by a job of
//! its own (a whole isosurface is tens of megabytes); several may run at
//! once. Each outcome is a line for the info bar or a [`JobError::Write`].

use super::{Job, JobError, Notify};

/// The exports in flight.
#[derive(Default)]
pub struct Exports {
    running: Vec<Job<String>>,
}

impl Exports {
    /// Starts writing: `write` returns the message to show.
    pub fn start(
        &mut self,
        notify: Option<Notify>,
        write: impl FnOnce() -> Result<String, String> + Send + 'static,
    ) {
        let mut job = Job::new(notify);
        job.start("export", move |_| write().map_err(JobError::Write));
        self.running.push(job);
    }

    /// True while any export runs.
    pub fn busy(&self) -> bool {
        !self.running.is_empty()
    }

    /// The outcomes of the exports that have finished, in start order.
    pub fn poll(&mut self) -> Vec<Result<String, JobError>> {
        let mut done = Vec::new();
        self.running.retain_mut(|job| match job.poll_take() {
            Some(outcome) => {
                done.push(outcome);
                false
            }
            None => true,
        });
        done
    }

    /// Waits for every export in flight (tests) and returns the outcomes.
    pub fn wait(&mut self) -> Vec<Result<String, JobError>> {
        for job in &mut self.running {
            job.wait();
        }
        self.poll()
    }
}
