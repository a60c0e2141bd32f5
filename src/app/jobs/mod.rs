//! Background work, one state machine for all of it.
//!
//! Every computation the explorer does off the UI thread (the pipeline,
//! contour extraction and its measurements, every contour at h, Betti
//! numbers, exports, file dialogs) is a [`Job`]: `Idle`, then `Running`
//! (with its stage, fraction and cancel flag in a shared [`Progress`]),
//! then `Ready` with its value or `Failed` with a [`JobError`]. A job runs
//! on its own thread, sends its outcome over a channel and wakes the
//! window (`notify`); the frame only polls. Starting a job while one runs
//! cancels the running one ([`Job::start`]) or queues the new work behind
//! it, the latest replacing any queued before ([`Job::start_latest`]: a
//! dragged contour re-extracts at most once at a time, at the newest
//! value). A late outcome of a cancelled run is recognised by its number
//! and dropped, so cancellation is a state, never a message to compare.

pub mod betti;
pub mod dialog;
pub mod export;
pub mod extraction;
pub mod isosurface;
pub mod pipeline;
pub mod preview;

use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Instant;

use crate::progress::Progress;

/// Called from a worker when its outcome is sent (egui: request a repaint).
pub type Notify = Arc<dyn Fn() + Send + Sync>;

/// Why a job produced no value.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum JobError {
    /// The user (or a newer job) cancelled it: not an error to show.
    #[error("cancelled")]
    Cancelled,
    /// The operating system refused a worker thread.
    #[error("cannot start a worker thread: {0}")]
    NoThread(String),
    /// The input cannot be used (unreadable file, a 2D grid, ...).
    #[error("{0}")]
    Input(String),
    /// An export or screenshot could not be written.
    #[error("{0}")]
    Write(String),
}

/// A job in flight.
#[derive(Debug)]
pub struct Running {
    /// What it is, for the progress bar ("synthetic:64", "export").
    pub what: String,
    /// Its stage, fraction and cancel flag, shared with the worker.
    pub progress: Arc<Progress>,
    /// When it started.
    pub started: Instant,
    /// Its number: outcomes of other numbers are stale.
    run: u64,
}

/// Where a job is.
#[derive(Debug, Default)]
pub enum JobState<T> {
    /// Nothing started, or the last outcome taken.
    #[default]
    Idle,
    /// Working.
    Running(Running),
    /// Done, with its value.
    Ready(T),
    /// Done, without a value.
    Failed(JobError),
}

/// Work that runs on its own thread once started.
type Work<T> = Box<dyn FnOnce(&Progress) -> Result<T, JobError> + Send>;

/// A background job (see the module documentation).
pub struct Job<T> {
    state: JobState<T>,
    tx: Sender<(u64, Result<T, JobError>)>,
    rx: Receiver<(u64, Result<T, JobError>)>,
    next_run: u64,
    /// Work waiting for the running one to end ([`Job::start_latest`]).
    queued: Option<(String, Work<T>)>,
    notify: Option<Notify>,
    /// False: work runs at once on the caller's thread (tests).
    threaded: bool,
}

impl<T> std::fmt::Debug for Job<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let state = match &self.state {
            JobState::Idle => "idle",
            JobState::Running(_) => "running",
            JobState::Ready(_) => "ready",
            JobState::Failed(_) => "failed",
        };
        write!(f, "Job({state})")
    }
}

impl<T: Send + 'static> Default for Job<T> {
    fn default() -> Self {
        Self::new(None)
    }
}

impl<T: Send + 'static> Job<T> {
    /// An idle job whose workers call `notify` when they finish.
    pub fn new(notify: Option<Notify>) -> Self {
        let (tx, rx) = channel();
        Self {
            state: JobState::Idle,
            tx,
            rx,
            next_run: 0,
            queued: None,
            notify,
            threaded: true,
        }
    }

    /// A job whose work runs at once on the calling thread (tests that
    /// need no worker).
    pub fn inline() -> Self {
        Self {
            threaded: false,
            ..Self::new(None)
        }
    }

    /// Where the job is.
    pub fn state(&self) -> &JobState<T> {
        &self.state
    }

    /// The run in flight.
    pub fn running(&self) -> Option<&Running> {
        match &self.state {
            JobState::Running(r) => Some(r),
            _ => None,
        }
    }

    /// True while running (or with work queued).
    pub fn is_running(&self) -> bool {
        matches!(self.state, JobState::Running(_)) || self.queued.is_some()
    }

    /// The value of the last run, while not taken.
    pub fn ready(&self) -> Option<&T> {
        match &self.state {
            JobState::Ready(v) => Some(v),
            _ => None,
        }
    }

    /// Starts `work`, cancelling the run in flight (its outcome will be
    /// dropped) and any queued work.
    pub fn start(
        &mut self,
        what: impl Into<String>,
        work: impl FnOnce(&Progress) -> Result<T, JobError> + Send + 'static,
    ) {
        self.cancel();
        self.spawn(what.into(), Box::new(work));
    }

    /// Starts `work` now when idle; otherwise queues it behind the run in
    /// flight, replacing anything queued before (the latest wins).
    pub fn start_latest(
        &mut self,
        what: impl Into<String>,
        work: impl FnOnce(&Progress) -> Result<T, JobError> + Send + 'static,
    ) {
        if matches!(self.state, JobState::Running(_)) {
            self.queued = Some((what.into(), Box::new(work)));
        } else {
            self.spawn(what.into(), Box::new(work));
        }
    }

    fn spawn(&mut self, what: String, work: Work<T>) {
        self.next_run += 1;
        let run = self.next_run;
        let progress = Arc::new(Progress::new());
        progress.stage("starting");
        self.state = JobState::Running(Running {
            what,
            progress: Arc::clone(&progress),
            started: Instant::now(),
            run,
        });
        if !self.threaded {
            let outcome = work(&progress);
            let _ = self.tx.send((run, outcome));
            return;
        }
        let tx = self.tx.clone();
        let notify = self.notify.clone();
        let spawned = std::thread::Builder::new()
            .name("flexiso-job".into())
            .spawn(move || {
                yield_to_ui();
                let outcome = work(&progress);
                // The receiver is gone only when the app has closed.
                let _ = tx.send((run, outcome));
                if let Some(n) = notify {
                    n();
                }
            });
        if let Err(e) = spawned {
            let _ = self.tx.send((run, Err(JobError::NoThread(e.to_string()))));
        }
    }

    /// Cancels the run in flight and the queued work; the job is idle.
    pub fn cancel(&mut self) {
        self.queued = None;
        if let JobState::Running(r) = &self.state {
            r.progress.cancel();
            self.state = JobState::Idle;
        }
    }

    /// Installs an outcome that has arrived; true when the run finished
    /// now (it is then `Ready` or `Failed`, and queued work has started).
    pub fn poll(&mut self) -> bool {
        let mut finished = false;
        while let Ok((run, outcome)) = self.rx.try_recv() {
            finished |= self.install(run, outcome);
        }
        finished
    }

    fn install(&mut self, run: u64, outcome: Result<T, JobError>) -> bool {
        match &self.state {
            JobState::Running(r) if r.run == run => {
                self.state = match outcome {
                    Ok(v) => JobState::Ready(v),
                    Err(e) => JobState::Failed(e),
                };
                true
            }
            // A cancelled or replaced run's late outcome.
            _ => false,
        }
    }

    /// The outcome of the finished run, once (the job becomes idle, or
    /// runs the queued work).
    pub fn take(&mut self) -> Option<Result<T, JobError>> {
        let outcome = match std::mem::take(&mut self.state) {
            JobState::Ready(v) => Some(Ok(v)),
            JobState::Failed(e) => Some(Err(e)),
            other => {
                self.state = other;
                None
            }
        };
        if outcome.is_some()
            && let Some((what, work)) = self.queued.take()
        {
            self.spawn(what, work);
        }
        outcome
    }

    /// [`Job::poll`] then [`Job::take`].
    pub fn poll_take(&mut self) -> Option<Result<T, JobError>> {
        self.poll();
        self.take()
    }

    /// Blocks until the run in flight ends (tests); false when none was
    /// running or the worker vanished.
    pub fn wait(&mut self) -> bool {
        self.wait_until(None)
    }

    /// [`Job::wait`], for `limit` at most: false also when it ran out.
    pub fn wait_for(&mut self, limit: std::time::Duration) -> bool {
        self.wait_until(Instant::now().checked_add(limit))
    }

    fn wait_until(&mut self, deadline: Option<Instant>) -> bool {
        while let JobState::Running(r) = &self.state {
            let run = r.run;
            let received = match deadline {
                None => self.rx.recv().ok(),
                Some(d) => self
                    .rx
                    .recv_timeout(d.saturating_duration_since(Instant::now()))
                    .ok(),
            };
            match received {
                Some((r, outcome)) => {
                    if r == run {
                        self.install(r, outcome);
                        return true;
                    }
                }
                None => return false,
            }
        }
        false
    }
}

/// Lowers the calling thread's scheduling priority (nice 10, Linux), so
/// that the UI thread, which only draws, gets a core whenever it wants one
/// while the engine's threads fill the rest: the window keeps drawing at
/// full rate on a machine with as few cores as the engine has threads.
/// Called first thing on every background thread of the explorer (jobs and
/// the engine's rayon workers).
pub fn yield_to_ui() {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority only reads its integer arguments; `who = 0` on
    // Linux names the calling thread (nice is per thread there).
    unsafe {
        libc::setpriority(libc::PRIO_PROCESS, 0, 10);
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn a_job_runs_to_ready_and_its_value_is_taken_once() {
        let mut job: Job<u32> = Job::new(None);
        assert!(matches!(job.state(), JobState::Idle));
        job.start("sum", |_| Ok(2 + 2));
        assert!(job.is_running());
        assert!(job.wait());
        assert_eq!(job.ready(), Some(&4));
        assert_eq!(job.take(), Some(Ok(4)));
        assert_eq!(job.take(), None);
        assert!(matches!(job.state(), JobState::Idle));
    }

    #[test]
    fn a_cancelled_run_never_delivers_and_a_restart_replaces_it() {
        let mut job: Job<u32> = Job::new(None);
        let (go_tx, go_rx) = channel::<()>();
        job.start("slow", move |p| {
            let _ = go_rx.recv();
            if p.is_cancelled() {
                Err(JobError::Cancelled)
            } else {
                Ok(1)
            }
        });
        job.start("fast", |_| Ok(2));
        let _ = go_tx.send(());
        assert!(job.wait());
        assert_eq!(job.take(), Some(Ok(2)));
        std::thread::sleep(std::time::Duration::from_millis(50));
        assert!(!job.poll(), "the first run's late outcome is dropped");
        job.start("again", |_| Ok(3));
        job.cancel();
        assert!(matches!(job.state(), JobState::Idle));
    }

    #[test]
    fn latest_work_waits_for_the_run_in_flight_and_replaces_older_queued_work() {
        let mut job: Job<u32> = Job::new(None);
        let (go_tx, go_rx) = channel::<()>();
        job.start_latest("first", move |_| {
            let _ = go_rx.recv();
            Ok(1)
        });
        job.start_latest("second", |_| Ok(2));
        job.start_latest("third", |_| Ok(3));
        let _ = go_tx.send(());
        assert!(job.wait());
        assert_eq!(job.take(), Some(Ok(1)));
        assert!(job.wait(), "the queued work started on take");
        assert_eq!(job.take(), Some(Ok(3)), "only the latest queued work ran");
        assert!(!job.is_running());
    }

    #[test]
    fn a_bounded_wait_gives_up_then_sees_the_run_end() {
        let mut job: Job<u32> = Job::new(None);
        let (go_tx, go_rx) = channel::<()>();
        job.start("held", move |_| {
            let _ = go_rx.recv();
            Ok(7)
        });
        let limit = std::time::Duration::from_millis(50);
        assert!(!job.wait_for(limit), "the run is held: the wait gives up");
        assert!(job.is_running());
        let _ = go_tx.send(());
        assert!(job.wait_for(std::time::Duration::from_secs(30)));
        assert_eq!(job.take(), Some(Ok(7)));
        assert!(!job.wait_for(limit), "nothing running");
    }
}
