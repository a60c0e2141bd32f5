//! A progress bar on standard error for the command line's long stages
//! (reading, the engine's sort, sweeps, merge and augmentation, measures,
//! simplification, extraction, writing), drawn with indicatif.
//!
//! The library knows nothing of it: the engine reports through the plain
//! [`Progress`] (a stage name and a fraction) that the explorer also reads;
//! here a thread polls that state every 50 ms and draws a bar once a stage
//! has run for half a second, so quick commands print nothing. The bar is
//! only drawn when standard error is a terminal and `-q` was not given:
//! piped or redirected output stays exactly the report and the product.
//! [`StageBar::done`] clears the bar before the command prints its next
//! report line, so the two never interleave.

use crate::progress::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal as _;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a stage runs before its bar appears.
pub const SHOW_AFTER: Duration = Duration::from_millis(500);

/// Steps of the drawn bar (the fraction is in [0, 1]).
const STEPS: u64 = 1000;

struct Shared {
    progress: Progress,
    bar: Mutex<Option<ProgressBar>>,
    stop: AtomicBool,
}

/// The engine's [`Progress`] shown as a bar on standard error (see the
/// module doc). Dropping it clears the bar and stops its thread.
pub struct StageBar {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl StageBar {
    /// A bar, drawn only when standard error is a terminal and `-q` is not
    /// set; otherwise the [`Progress`] is still there (the engine needs
    /// one) but nothing polls it.
    pub fn new() -> Self {
        let enabled = !super::quiet() && std::io::stderr().is_terminal();
        Self::with(enabled)
    }

    /// A bar drawn or not, whatever the streams are (for tests).
    pub fn with(enabled: bool) -> Self {
        let shared = Arc::new(Shared {
            progress: Progress::new(),
            bar: Mutex::new(None),
            stop: AtomicBool::new(false),
        });
        let thread = enabled.then(|| {
            let shared = Arc::clone(&shared);
            std::thread::spawn(move || poll(&shared))
        });
        StageBar { shared, thread }
    }

    /// The progress state to hand to the engine.
    pub fn progress(&self) -> &Progress {
        &self.shared.progress
    }

    /// Ends the current stage and starts `name` (a stage the command runs
    /// itself: "reading", "writing", ...).
    pub fn stage(&self, name: &str) {
        self.done();
        self.shared.progress.stage(name);
    }

    /// Ends the current stage: the bar, if drawn, is cleared now, so a
    /// report line can follow.
    pub fn done(&self) {
        if let Ok(mut bar) = self.shared.bar.lock() {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
            self.shared.progress.stage("");
        }
    }
}

impl Default for StageBar {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for StageBar {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        self.done();
    }
}

fn style() -> ProgressStyle {
    ProgressStyle::with_template("{spinner} {msg:<22} [{bar:32}] {percent:>3}%  {elapsed}")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ")
}

/// The polling thread: follows the stage, draws the bar after
/// [`SHOW_AFTER`].
fn poll(shared: &Shared) {
    let mut current = String::new();
    let mut since = Instant::now();
    while !shared.stop.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(50));
        let (stage, fraction) = shared.progress.get();
        let Ok(mut bar) = shared.bar.lock() else {
            return;
        };
        if stage != current {
            current = stage.clone();
            since = Instant::now();
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
        }
        if current.is_empty() {
            continue;
        }
        if bar.is_none() && since.elapsed() >= SHOW_AFTER {
            let b = ProgressBar::with_draw_target(Some(STEPS), ProgressDrawTarget::stderr());
            b.set_style(style());
            b.set_message(current.clone());
            *bar = Some(b);
        }
        if let Some(b) = bar.as_ref() {
            b.set_position((f64::from(fraction) * STEPS as f64) as u64);
            b.tick();
        }
    }
}
