//! The explorer's sessions (the format is [`crate::session`]): File >
//! Save session / Open session, the question asked before a scene with
//! unsaved changes is closed (quitting, closing the window, opening
//! another volume), and the recovery file written every few seconds of
//! change and offered at the next start after a crash. The recovery file
//! is written by a [`Job`]: the frame only takes the scene as a session
//! value.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use egui::{Color32, RichText};

use super::FlexisoApp;
use super::history::Scene;
use super::ids::ContourId;
use super::jobs::{Job, JobError};
use super::selection::{ContourState, palette};
use crate::session::{
    CameraState, Session, SessionClip, SessionContour, SessionCutBox, SessionSlices, SessionView,
    format_colour,
};

/// The recovery file is written once the scene has stayed changed this
/// long.
pub const AUTOSAVE_AFTER: Duration = Duration::from_secs(3);

/// What waits for the user's answer about unsaved changes.
#[derive(Clone, Debug, PartialEq)]
pub enum Pending {
    /// Close the window.
    Quit,
    /// Open this volume.
    Open(String),
    /// Open this session.
    OpenSession(PathBuf),
}

/// The recovery file and what was last written to it.
#[derive(Debug)]
pub struct Recovery {
    path: PathBuf,
    written: Option<Scene>,
    changed_at: Option<Instant>,
    /// Its writes and removals, off the UI thread (the write is synced,
    /// [`crate::output::write_whole`], and a slow or stalled disk must not
    /// hold the window): one at a time, in the order asked, the latest
    /// waiting replacing any before it ([`Job::start_latest`]), since each
    /// leaves the file whole.
    job: Job<()>,
    /// The last write failed (and was shown): the next failure is not
    /// shown again until a write succeeds.
    failing: bool,
}

impl Recovery {
    fn write(&mut self, session: Session) {
        let path = self.path.clone();
        self.job.start_latest("recovery file", move |_| {
            if let Some(dir) = path.parent() {
                let _ = std::fs::create_dir_all(dir);
            }
            session.write(&path).map_err(|e| {
                eprintln!("flexiso: cannot write the recovery file: {e}");
                JobError::Write(format!(
                    "the recovery file cannot be written ({e}): save the session to keep \
                     this scene"
                ))
            })
        });
    }

    fn remove(&mut self) {
        let path = self.path.clone();
        self.job.start_latest("recovery file", move |_| {
            let _ = std::fs::remove_file(&path);
            Ok(())
        });
    }

    /// Installs a finished write or removal (and starts the one waiting);
    /// a failure to show, the first of a run of them.
    fn poll(&mut self) -> Option<String> {
        match self.job.poll_take()? {
            Err(JobError::Write(e)) => (!std::mem::replace(&mut self.failing, true)).then_some(e),
            _ => {
                self.failing = false;
                None
            }
        }
    }

    /// Waits, at most `limit`, until every write and removal asked is
    /// done; a failure to show.
    fn finish(&mut self, limit: Duration) -> Option<String> {
        let deadline = Instant::now() + limit;
        let mut failure = None;
        loop {
            // What has finished is installed and what waits is started.
            failure = failure.or(self.poll());
            let left = deadline.saturating_duration_since(Instant::now());
            if !self.job.is_running() || !self.job.wait_for(left) {
                return failure;
            }
        }
    }

    /// The recovery file's usual place: `$XDG_STATE_HOME/flexiso` (or
    /// `~/.local/state/flexiso`), `recovery.json`.
    pub fn default_path() -> Option<PathBuf> {
        let base = std::env::var_os("XDG_STATE_HOME")
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/state")))?;
        Some(base.join("flexiso").join("recovery.json"))
    }
}

impl FlexisoApp {
    /// The scene shown as a session; `session_path` is where it will be
    /// written (a volume file is spelt relative to it when it can be).
    pub fn session(&self, session_path: &Path) -> Option<Session> {
        let ds = self.dataset.as_ref()?;
        let level = self.level.as_ref()?;
        let volume = match &ds.path {
            Some(p) => Session::spell_volume(p, session_path),
            None => ds.name.clone(),
        };
        let c = self.view3d.camera;
        let contours = self
            .selection
            .contours
            .iter()
            .map(|k| {
                let a = ds.tree.arc(k.superarc);
                let [r, g, b, _] = k.colour.to_array();
                SessionContour {
                    superarc: [ds.tree.node(a.upper).vertex, ds.tree.node(a.lower).vertex],
                    isovalue: k.h,
                    color: format_colour([r, g, b]),
                    name: k.name.clone(),
                    visible: k.visible,
                }
            })
            .collect();
        Some(Session {
            volume,
            dims: Some(ds.field.dims()),
            measure: self.measure.name().into(),
            arcs_shown: Some(level.num_arcs()),
            camera: Some(CameraState {
                target: c.target.into(),
                distance: c.distance,
                yaw: c.yaw,
                pitch: c.pitch,
                fov_y: c.fov_y,
            }),
            contours,
            slices: {
                let sl = &self.slices.slices;
                let a: [Option<usize>; 3] =
                    std::array::from_fn(|i| sl.on[i].then_some(sl.index[i]));
                a.iter()
                    .any(Option::is_some)
                    .then(|| SessionSlices::from_array(a))
            },
            clip: {
                let c = &self.slices.clip;
                c.on.then(|| SessionClip {
                    axis: ["x", "y", "z"][c.axis.min(2)].into(),
                    at: c.at,
                    keep: if c.keep_below { "below" } else { "above" }.into(),
                })
            },
            cut_box: {
                let b = &self.slices.cut_box;
                b.on.then_some(SessionCutBox {
                    min: b.lo,
                    max: b.hi,
                })
            },
            view: {
                let v = self.menu.view;
                Some(SessionView {
                    labels: v.labels,
                    legend: v.legend,
                    triad: v.triad,
                    slices_panel: v.slices_panel,
                })
            },
            ..Session::default()
        })
    }

    /// Shows the session's slices, clip and view switches (view state:
    /// absent ones are switched off or take their defaults).
    fn apply_view_state(&mut self, s: &Session) {
        if let Some(ds) = &self.dataset {
            self.slices.set_field(&ds.field);
        }
        let slices = s.slices.unwrap_or_default().as_array();
        for (a, i) in slices.iter().enumerate() {
            self.slices.slices.on[a] = i.is_some();
            if let Some(i) = i {
                self.slices.slices.index[a] = *i;
            }
        }
        let clip = &mut self.slices.clip;
        clip.on = false;
        if let Some(c) = &s.clip {
            match c.axis_index() {
                Some(axis) => {
                    clip.on = true;
                    clip.axis = axis;
                    clip.at = if c.at.is_finite() {
                        c.at.clamp(0.0, 1.0)
                    } else {
                        0.5
                    };
                    clip.keep_below = c.keep_below();
                }
                None => {
                    self.error = Some(format!(
                        "session: clip axis '{}' is not x, y or z; no clipping plane",
                        c.axis
                    ))
                }
            }
        }
        let cut = &mut self.slices.cut_box;
        cut.on = s.cut_box.is_some();
        if let Some(b) = &s.cut_box {
            let d = SessionCutBox::default();
            let f = |v: f32, dv: f32| if v.is_finite() { v.clamp(0.0, 1.0) } else { dv };
            cut.lo = std::array::from_fn(|i| f(b.min[i], d.min[i]));
            cut.hi = std::array::from_fn(|i| f(b.max[i], d.max[i]));
        }
        let v = s.view.unwrap_or_default();
        let view = &mut self.menu.view;
        view.labels = v.labels;
        view.legend = v.legend;
        view.triad = v.triad;
        view.slices_panel = v.slices_panel;
    }

    /// Saves the session to `path`; the error is shown and returned.
    pub fn save_session(&mut self, path: &Path) -> Result<(), String> {
        let Some(s) = self.session(path) else {
            let e = "nothing to save: no volume is open".to_string();
            self.error = Some(e.clone());
            return Err(e);
        };
        match s.write(path) {
            Ok(()) => {
                self.history.mark_saved();
                self.session_path = Some(path.to_path_buf());
                self.info = Some(format!(
                    "session saved to {} ({} contours)",
                    path.display(),
                    s.contours.len()
                ));
                if let Some(then) = self.after_save.take() {
                    self.proceed(then);
                }
                Ok(())
            }
            Err(e) => {
                self.after_save = None;
                self.error = Some(format!("cannot save the session: {e}"));
                Err(e.to_string())
            }
        }
    }

    /// Opens the session at `path`: its volume in the background (unless
    /// it is the one shown), then its scene.
    pub fn open_session(&mut self, path: &Path) {
        match Session::read(path) {
            Ok(s) => {
                self.session_path = Some(path.to_path_buf());
                self.show_session(s, path);
            }
            Err(e) => self.error = Some(format!("cannot open the session: {e}")),
        }
    }

    /// Shows session `s` read from `path`: at once when its volume is
    /// the one shown, else once the volume is open (under the session's
    /// measure).
    fn show_session(&mut self, s: Session, path: &Path) {
        let input = s.volume_input(path);
        let same = self.dataset.as_ref().is_some_and(|ds| match &ds.path {
            Some(p) => same_file(p, Path::new(&input)),
            None => ds.name == input,
        });
        if same {
            self.apply_session(&s);
        } else {
            if let Some(m) = s.measure() {
                self.measure = m;
            }
            self.pending_session = Some(s);
            self.open(&input);
        }
    }

    /// Shows session `s` on the dataset shown: the measure, the level,
    /// the camera and every contour that can be placed; the others are
    /// listed in the info line.
    pub(super) fn apply_session(&mut self, s: &Session) {
        let Some(ds) = &self.dataset else { return };
        let placed = s.place(&ds.tree, &ds.field);
        let contours: Vec<ContourState> = placed
            .contours
            .iter()
            .enumerate()
            .map(|(i, c)| ContourState {
                id: ContourId(i as u64),
                superarc: c.superarc,
                h: c.isovalue,
                group: ContourId(i as u64),
                colour: c
                    .colour
                    .map_or(palette(i), |[r, g, b]| Color32::from_rgb(r, g, b)),
                visible: c.visible,
                name: c.name.clone(),
            })
            .collect();
        let level = self.level.as_ref();
        let mut step = level.map_or(0, |l| l.step());
        if let (Some(arcs), Some(l)) = (s.arcs_shown, level) {
            step = l.simplification().steps_for_arcs(arcs);
        }
        let scene = Scene {
            contours,
            isolated: None,
            measure: s.measure().unwrap_or(self.measure),
            step,
            arcs: s.arcs_shown.unwrap_or(0),
        };
        // The selection starts afresh: ids from 0, no old extractions.
        self.selection.clear();
        self.apply_scene(&scene);
        if let Some(c) = s.camera {
            let cam = &mut self.view3d.camera;
            cam.target = c.target.into();
            cam.distance = c.distance.max(1e-6);
            cam.yaw = c.yaw;
            cam.pitch = c.pitch;
            cam.fov_y = c.fov_y;
        }
        self.apply_view_state(s);
        let n = placed.contours.len();
        self.info = Some(if placed.problems.is_empty() {
            format!("session opened: {n} contours")
        } else {
            format!(
                "session opened with {n} of {} contours: {}",
                s.contours.len(),
                placed.problems.join("; ")
            )
        });
        // Saved as opened (a measure still being recomputed joins the
        // saved scene when it arrives, see `accept`).
        self.history.reset(scene);
        if std::mem::take(&mut self.recovered) {
            // A recovered scene is saved nowhere yet.
            self.history.forget_saved();
        }
    }

    /// Shows session `s` on the volume shown, whatever volume it names
    /// (tests: a field made in the test has no file to name).
    pub fn apply_session_for_test(&mut self, s: &Session) {
        self.apply_session(s);
    }

    /// Opens a volume, asking first when the scene has unsaved changes.
    pub(super) fn request(&mut self, what: Pending) {
        if self.history.unsaved() {
            self.confirm = Some(what);
        } else {
            self.proceed(what);
        }
    }

    /// Does what waited for an answer.
    pub(super) fn proceed(&mut self, what: Pending) {
        match what {
            Pending::Quit => {
                self.closing = true;
                self.remove_recovery();
                if let Some(ctx) = &self.ctx {
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            }
            Pending::Open(input) => self.open(&input),
            Pending::OpenSession(p) => self.open_session(&p),
        }
    }

    /// Saves where the session was last saved or opened, else asks where.
    pub(super) fn save_session_here_or_ask(&mut self) {
        match self.session_path.clone() {
            Some(p) => {
                let _ = self.save_session(&p);
            }
            None => self.spawn_dialog(super::jobs::dialog::DialogKind::SaveSession),
        }
    }

    /// The question about unsaved changes, while one is pending: Save,
    /// Discard or Cancel. Escape or a click outside cancels.
    pub(super) fn confirm_modal(&mut self, ctx: &egui::Context) {
        let Some(what) = self.confirm.clone() else {
            return;
        };
        let doing = match &what {
            Pending::Quit => "Quit".to_string(),
            Pending::Open(p) => format!("Open {p}"),
            Pending::OpenSession(p) => format!("Open session {}", p.display()),
        };
        let n = self.selection.contours.len();
        let mut answer = None;
        let r = egui::Modal::new(egui::Id::unique("unsaved changes")).show(ctx, |ui| {
            ui.set_max_width(380.0);
            ui.heading("Unsaved changes");
            ui.label(format!(
                "The scene ({n} contour{}) has changes that are not saved in a session.",
                if n == 1 { "" } else { "s" }
            ));
            ui.label(RichText::new(format!("{doing} anyway?")).weak());
            ui.separator();
            ui.horizontal(|ui| {
                if ui.button("Save session…").clicked() {
                    answer = Some(0);
                }
                if ui.button("Discard changes").clicked() {
                    answer = Some(1);
                }
                if ui.button("Cancel").clicked() {
                    answer = Some(2);
                }
            });
        });
        if r.should_close() && answer.is_none() {
            answer = Some(2);
        }
        match answer {
            Some(0) => {
                self.confirm = None;
                self.after_save = Some(what);
                self.save_session_here_or_ask();
            }
            Some(1) => {
                self.confirm = None;
                self.proceed(what);
            }
            Some(_) => self.confirm = None,
            None => {}
        }
    }

    /// What the unsaved-changes question is about, while it is asked.
    pub fn confirming(&self) -> Option<&Pending> {
        self.confirm.as_ref()
    }

    /// True once the user chose to close the window.
    pub fn closing(&self) -> bool {
        self.closing
    }

    /// The window's close button: asks first when there are unsaved
    /// changes.
    pub(super) fn intercept_close(&mut self, ctx: &egui::Context) {
        if ctx.input(|i| i.viewport().close_requested()) && !self.closing {
            if self.history.unsaved() {
                ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
                self.confirm = Some(Pending::Quit);
            } else {
                self.remove_recovery();
            }
        }
    }

    /// Writes the recovery file to `path` every few seconds of change
    /// from now on; a file already there (a run that crashed) is offered.
    pub fn set_recovery_file(&mut self, path: PathBuf) {
        self.recovery_offer = None;
        // A plain file only: reading a named pipe or a device would wait.
        if path.is_file() {
            match Session::read(&path) {
                Ok(s) if !s.contours.is_empty() => {
                    self.recovery_offer = Some(s);
                }
                Ok(_) => {}
                Err(e) => eprintln!("flexiso: ignoring the recovery file: {e}"),
            }
        }
        self.recovery = Some(Recovery {
            path,
            written: None,
            changed_at: None,
            job: Job::new(self.notify.clone()),
            failing: false,
        });
    }

    /// True while the recovery of a crashed run is offered.
    pub fn recovery_offered(&self) -> bool {
        self.recovery_offer.is_some()
    }

    /// Removes the recovery file, after any write still under way; waits
    /// for it (a second at most), since the program may be closing.
    fn remove_recovery(&mut self) {
        if let Some(r) = &mut self.recovery {
            r.remove();
            r.finish(Duration::from_secs(1));
        }
    }

    /// Writes the recovery file once the scene has stayed changed for
    /// [`AUTOSAVE_AFTER`]; removes it when nothing is unsaved. Shows a
    /// failed write.
    pub(super) fn autosave(&mut self, now: Instant) {
        // A write that failed is shown, as an error: the scene is not kept
        // against a crash until a write succeeds.
        if let Some(e) = self.recovery.as_mut().and_then(Recovery::poll) {
            self.error = Some(e);
        }
        if self.recovery_offer.is_some() {
            return; // The old file waits for the user's answer.
        }
        let scene = self.scene_now();
        let unsaved = self.history.unsaved();
        let Some(r) = &mut self.recovery else { return };
        if scene == r.written {
            r.changed_at = None;
            return;
        }
        let since = *r.changed_at.get_or_insert(now);
        if now.duration_since(since) < AUTOSAVE_AFTER {
            return;
        }
        let path = r.path.clone();
        r.written = scene;
        r.changed_at = None;
        if !unsaved {
            r.remove();
            return;
        }
        // The session is taken here (a small value); encoding and the
        // synced write happen on the job's thread.
        if let Some(s) = self.session(&path)
            && let Some(r) = &mut self.recovery
        {
            r.write(s);
        }
    }

    /// Writes the recovery file now if the scene changed, and waits for
    /// the write (tests).
    pub fn autosave_now(&mut self) {
        self.autosave_later();
        if let Some(e) = self
            .recovery
            .as_mut()
            .and_then(|r| r.finish(Duration::from_secs(10)))
        {
            self.error = Some(e);
        }
    }

    /// Asks for the recovery file to be written now if the scene changed,
    /// as the frame does after [`AUTOSAVE_AFTER`], and returns at once
    /// (tests).
    pub fn autosave_later(&mut self) {
        if let Some(r) = &mut self.recovery {
            r.changed_at = Some(Instant::now() - AUTOSAVE_AFTER);
        }
        self.autosave(Instant::now());
    }

    /// The offer to recover the scene of a run that crashed.
    pub(super) fn recovery_modal(&mut self, ctx: &egui::Context) {
        let Some(s) = &self.recovery_offer else {
            return;
        };
        let (n, volume) = (s.contours.len(), s.volume.clone());
        let mut answer = None;
        egui::Modal::new(egui::Id::unique("recovery")).show(ctx, |ui| {
            ui.set_max_width(420.0);
            ui.heading("Recover the last scene?");
            ui.label(format!(
                "flexiso did not close cleanly. A scene of {n} contour{} on {volume} was saved a few seconds before.",
                if n == 1 { "" } else { "s" }
            ));
            ui.horizontal(|ui| {
                if ui.button("Recover").clicked() {
                    answer = Some(true);
                }
                if ui.button("Discard").clicked() {
                    answer = Some(false);
                }
            });
        });
        match answer {
            Some(true) => {
                if let (Some(s), Some(r)) = (self.recovery_offer.take(), &self.recovery) {
                    let p = r.path.clone();
                    // Not saved anywhere yet: the scene stays "unsaved".
                    self.session_path = None;
                    self.recovered = true;
                    self.show_session(s, &p);
                }
            }
            Some(false) => {
                self.recovery_offer = None;
                self.remove_recovery();
            }
            None => {}
        }
    }
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}
