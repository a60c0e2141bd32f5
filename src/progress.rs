//! Progress reporting and cancellation for long computations.
//!
//! The engine runs on a worker thread; the UI reads the stage and fraction
//! from here to draw its progress bar, and sets the cancel flag when the
//! user opens another file. Engine loops poll [`Progress::check`] every few
//! hundred thousand vertices, so cancelling takes milliseconds.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use thiserror::Error;

/// The computation was cancelled by the user.
#[derive(Debug, Error, Clone, Copy, PartialEq, Eq)]
#[error("cancelled")]
pub struct Cancelled;

/// Shared progress state of one job.
#[derive(Debug, Default)]
pub struct Progress {
    stage: Mutex<String>,
    fraction_bits: AtomicU32,
    cancel: AtomicBool,
}

impl Progress {
    /// A fresh progress state.
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts a new stage at fraction 0.
    pub fn stage(&self, name: &str) {
        if let Ok(mut s) = self.stage.lock() {
            s.clear();
            s.push_str(name);
        }
        self.set_fraction(0.0);
    }

    /// Sets the fraction of the current stage done, in [0, 1].
    pub fn set_fraction(&self, f: f32) {
        self.fraction_bits
            .store(f.clamp(0.0, 1.0).to_bits(), Ordering::Relaxed);
    }

    /// The current stage name and fraction.
    pub fn get(&self) -> (String, f32) {
        let stage = self.stage.lock().map(|s| s.clone()).unwrap_or_default();
        (
            stage,
            f32::from_bits(self.fraction_bits.load(Ordering::Relaxed)),
        )
    }

    /// Asks the computation to stop.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// True once cancelled.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// Records progress `done / total` and fails if cancelled.
    pub fn check(&self, done: usize, total: usize) -> Result<(), Cancelled> {
        if total > 0 {
            self.set_fraction(done as f32 / total as f32);
        }
        if self.is_cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }
}
