//! The explorer window (eframe + egui): a thin layer over the engine.
//!
//! * [`dataset`]: what one volume's pipeline run made (field, trees,
//!   simplification, layout, curve), shared by every panel.
//! * [`jobs`]: everything off the UI thread, one [`jobs::Job`] state
//!   machine for all of it: the pipeline, contour extraction, all contours
//!   at h, Betti numbers, exports, file dialogs.
//! * [`panels`]: the tree, the curve, the 3D view, the contour list, the
//!   menu and status bars, one per file.
//! * [`selection`]: the shared state the panels talk through.
//! * [`history`]: undo and redo of the scene, one step per gesture.
//! * [`session`]: File > Save/Open session, the unsaved-changes question,
//!   the recovery file.
//! * [`exports`], [`instrument`], [`format`]: File > Export, the frame log
//!   and position dump for scripts, how numbers are written.
//!
//! [`FlexisoApp`] owns them all and wires them together once per frame
//! (this file holds nothing else); no panel reaches into another's fields.
//! Display toggles never trigger recomputation: only opening a file,
//! changing the measure (background jobs) and moving a contour's isovalue
//! (one contour, a few ms) compute.

pub mod context;
pub mod dataset;
pub mod exports;
pub mod format;
pub mod history;
pub mod ids;
pub mod instrument;
pub mod jobs;
pub mod panels;
pub mod selection;
pub mod session;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use egui::{Color32, Key, Modifiers, RichText};

use crate::field::ScalarField;
use crate::field::io::ReadOptions;
use crate::field::source::VolumeSource;
use crate::measure::betti::ContourTopology;
use crate::progress::Progress;
use crate::simplify::{Measure, SimplifiedTree};

use dataset::{DEFAULT_ARCS, Dataset};
use history::History;
use instrument::{FrameLog, UiDump};
use jobs::betti::BettiJob;
use jobs::dialog::{DialogAnswer, DialogJob, DialogKind};
use jobs::export::Exports;
use jobs::isosurface::{AllContours, Scope};
use jobs::preview::{Preview, PreviewState};
use jobs::{Job, JobError, Notify};
use panels::curve::CurvePanel;
use panels::menu::{Action, Menu, Status};
use panels::tree::TreePanel;
use panels::view3d::{SceneKey, SceneMesh, View3d};
use selection::{ContourId, Selection, palette};

pub use jobs::pipeline::Request;
pub use jobs::yield_to_ui;
pub use panels::menu::CONTROLS;

/// How often the window redraws on its own while a job runs.
const PROGRESS_REPAINT: Duration = Duration::from_millis(200);

/// Width of the contour list (points).
const CONTOUR_PANEL_WIDTH: f32 = 270.0;

/// The explorer.
pub struct FlexisoApp {
    pipeline: Job<Dataset>,
    dataset: Option<Dataset>,
    level: Option<SimplifiedTree>,
    measure: Measure,
    selection: Selection,
    global_h: f64,
    show_all: bool,
    all: AllContours,
    tree_panel: TreePanel,
    curve_panel: CurvePanel,
    view3d: View3d,
    menu: Menu,
    error: Option<String>,
    info: Option<String>,
    dialog: DialogJob,
    exports: Exports,
    /// Betti numbers of every superarc's contours (computed after the
    /// dataset is shown), for the tree's tooltips.
    betti: BettiJob,
    pending_screenshot: Option<PathBuf>,
    frame_log: Option<FrameLog>,
    /// UI time of the last frame (ms), shown in the status bar.
    ui_ms: f64,
    ui_dump: Option<UiDump>,
    /// Frames the tree panel has been sized for a full window.
    sized_frames: u32,
    /// Wakes the window when a job ends (None in tests without one).
    notify: Option<Notify>,
    /// The window's context (None in tests built without one).
    ctx: Option<egui::Context>,
    /// Undo and redo of the scene.
    history: History,
    /// What waits for the answer about unsaved changes.
    confirm: Option<session::Pending>,
    /// What to do once the session is saved (the question's "Save").
    after_save: Option<session::Pending>,
    /// The user chose to close the window.
    closing: bool,
    /// Where the session was last saved or opened.
    session_path: Option<PathBuf>,
    /// A session to show once its volume is open.
    pending_session: Option<crate::session::Session>,
    /// The level to show once the measure's simplification arrives.
    pending_step: Option<usize>,
    /// The recovery file, when written.
    recovery: Option<session::Recovery>,
    /// A crashed run's scene, offered.
    recovery_offer: Option<crate::session::Session>,
    /// The session being shown was recovered (saved nowhere).
    recovered: bool,
    /// Slices and the clipping plane (see [`context`]).
    slices: panels::slices::SlicePanel,
    /// A newly opened volume shows its most important branches as
    /// contours (the window; tests start from an empty scene).
    first_screen: bool,
    /// The first screen's contours (id, superarc, isovalue), to frame the
    /// 3D view on once their meshes are in.
    frame_pending: Vec<(ContourId, crate::tree::ArcId, f64)>,
    /// The hover preview of the arc under the pointer.
    preview: Preview,
}

impl FlexisoApp {
    /// An explorer with nothing loaded; jobs wake the window through
    /// `notify`.
    fn with_notify(notify: Option<Notify>) -> Self {
        Self {
            pipeline: Job::new(notify.clone()),
            dataset: None,
            level: None,
            measure: Measure::default(),
            selection: Selection::default(),
            global_h: 0.0,
            show_all: false,
            all: AllContours::new(notify.clone()),
            tree_panel: TreePanel::new(),
            curve_panel: CurvePanel::default(),
            view3d: View3d::new(),
            menu: Menu::default(),
            error: None,
            info: None,
            dialog: Job::new(notify.clone()),
            exports: Exports::default(),
            betti: Job::new(notify.clone()),
            pending_screenshot: None,
            frame_log: None,
            ui_ms: 0.0,
            ui_dump: None,
            sized_frames: 0,
            ctx: None,
            history: History::default(),
            confirm: None,
            after_save: None,
            closing: false,
            session_path: None,
            pending_session: None,
            pending_step: None,
            recovery: None,
            recovery_offer: None,
            recovered: false,
            slices: panels::slices::SlicePanel::new(notify.clone()),
            first_screen: false,
            frame_pending: Vec::new(),
            preview: Preview::new(notify.clone()),
            notify,
        }
    }

    /// An explorer with nothing loaded.
    pub fn empty() -> Self {
        Self::with_notify(None)
    }

    /// The window's app: starts `request` in the background at once.
    pub fn new(cc: &eframe::CreationContext<'_>, request: Request) -> Self {
        let ctx = cc.egui_ctx.clone();
        let notify: Notify = Arc::new(move || ctx.request_repaint());
        let mut app = Self::with_notify(Some(Arc::clone(&notify)));
        app.ctx = Some(cc.egui_ctx.clone());
        app.first_screen = true;
        app.selection.extract_in_background(Some(notify));
        app.start(request);
        if let Some(p) = session::Recovery::default_path() {
            app.set_recovery_file(p);
        }
        app
    }

    /// Blocks until the contours being extracted are (tests).
    pub fn wait_for_extractions(&mut self) {
        self.selection.wait_for_extractions();
    }

    /// An explorer on `field`, with the pipeline already run (tests: no
    /// window needed). Contours are extracted in background jobs as in the
    /// window: call [`FlexisoApp::wait_for_extractions`].
    pub fn new_for_test(field: ScalarField) -> Self {
        let mut app = Self::run_for_test(field, false);
        // The interaction tests start from the level of DEFAULT_ARCS arcs
        // and an empty scene, as before the first screen existed.
        if let Some(level) = &mut app.level {
            level.set_level(DEFAULT_ARCS);
        }
        app
    }

    /// An explorer on `field` as the window opens it: the first screen's
    /// level (the curve's widest plateau) and its most important branches
    /// selected as contours (tests).
    pub fn new_for_test_first_screen(field: ScalarField) -> Self {
        Self::run_for_test(field, true)
    }

    fn run_for_test(field: ScalarField, first_screen: bool) -> Self {
        let mut app = Self::empty();
        app.first_screen = first_screen;
        app.selection.extract_in_background(None);
        let result = jobs::pipeline::run(
            Request::Field {
                name: "test".into(),
                field: Arc::new(field),
            },
            app.measure,
            &Progress::new(),
        );
        app.accept(result);
        app
    }

    /// Writes one line per frame to `path`: seconds since start, ms since
    /// the previous frame, ms spent in the UI code, the job stage.
    pub fn set_frame_log(&mut self, path: &std::path::Path) -> std::io::Result<()> {
        self.frame_log = Some(FrameLog::create(path)?);
        Ok(())
    }

    /// Writes, whenever they change, the screen positions (points) of the
    /// tree's arcs and markers and of the panels to `path`, one per line:
    /// `arc ID X Y HEIGHT`, `marker ID X Y`, `curve|tree|view X0 Y0 X1 Y1`, and
    /// `contours N`. For scripts that click with xdotool.
    pub fn set_ui_dump(&mut self, path: PathBuf) {
        self.ui_dump = Some(UiDump::new(path));
    }

    fn write_ui_dump(&mut self, view: egui::Rect) {
        let Some(dump) = &mut self.ui_dump else {
            return;
        };
        let d = &self.tree_panel.drawn;
        if let Some(t) = d.rect {
            dump.rect("tree", t);
        }
        if let Some(c) = self.curve_panel.plot_rect {
            dump.rect("curve", c);
        }
        dump.rect("view", view);
        if let Some(c) = self.menu.all_checkbox {
            dump.rect("allbox", c);
        }
        dump.line(format_args!("contours {}", self.selection.contours.len()));
        for (id, p) in &d.markers {
            dump.line(format_args!("marker {id} {:.0} {:.0}", p.x, p.y));
        }
        for ((id, p), h) in d.arcs.iter().zip(&d.arc_heights) {
            dump.line(format_args!("arc {} {:.0} {:.0} {:.0}", id.0, p.x, p.y, h));
        }
        dump.flush();
    }

    /// Starts a background job (cancelling the current one).
    pub fn start(&mut self, request: Request) {
        let what = request.describe(self.measure);
        let measure = self.measure;
        self.pipeline
            .start(what, move |p| jobs::pipeline::run(request, measure, p));
    }

    /// Opens a file (or `synthetic[:N]`) in the background.
    pub fn open(&mut self, input: &str) {
        match VolumeSource::parse(input, ReadOptions::default()) {
            Ok(source) => self.start(Request::Open(source)),
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    /// Blocks until the current job ends and takes its result (tests).
    pub fn wait_for_job(&mut self) {
        self.pipeline.wait();
        if let Some(r) = self.pipeline.take() {
            self.accept(r);
        }
    }

    /// True while a job runs.
    pub fn busy(&self) -> bool {
        self.pipeline.is_running()
    }

    /// The dataset shown.
    pub fn dataset(&self) -> Option<&Dataset> {
        self.dataset.as_ref()
    }

    /// The level of simplification shown.
    pub fn level(&self) -> Option<&SimplifiedTree> {
        self.level.as_ref()
    }

    /// The selection.
    pub fn selection(&self) -> &Selection {
        &self.selection
    }

    /// The selection, to edit as the contour list does (tests: the
    /// colour picker is hard to drive).
    pub fn selection_mut(&mut self) -> &mut Selection {
        &mut self.selection
    }

    /// The 3D view's camera, to move (tests, scripts).
    pub fn camera_mut(&mut self) -> &mut crate::render::Camera {
        &mut self.view3d.camera
    }

    /// The tree panel (what it drew last frame).
    pub fn tree_panel(&self) -> &TreePanel {
        &self.tree_panel
    }

    /// The curve panel.
    pub fn curve_panel(&self) -> &CurvePanel {
        &self.curve_panel
    }

    /// The curve panel, to change its settings (tests).
    pub fn curve_panel_mut(&mut self) -> &mut CurvePanel {
        &mut self.curve_panel
    }

    /// The 3D view.
    pub fn view3d(&self) -> &View3d {
        &self.view3d
    }

    /// The error message shown, if any.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// The info line (what the last action did), if any.
    pub fn info(&self) -> Option<&str> {
        self.info.as_deref()
    }

    /// The global isovalue.
    pub fn global_h(&self) -> f64 {
        self.global_h
    }

    /// Installs a pipeline run's outcome: a new dataset (or a new
    /// simplification of the one shown), or its error.
    fn accept(&mut self, result: jobs::pipeline::JobResult) {
        let mut ds = match result {
            Ok(ds) => ds,
            Err(JobError::Cancelled) => return,
            Err(e) => {
                self.error = Some(e.to_string());
                self.pending_session = None;
                self.pending_step = None;
                return;
            }
        };
        let t = ds.times;
        eprintln!(
            "flexiso: {} ready in {:.2} s (read {:.2}, tree {:.2}, simplify {:.2}, layout {:.2})",
            ds.name,
            t.total().as_secs_f64(),
            t.load.as_secs_f64(),
            t.tree.as_secs_f64(),
            t.simplify.as_secs_f64(),
            t.layout.as_secs_f64()
        );
        let same_field = self
            .dataset
            .as_ref()
            .is_some_and(|old| Arc::ptr_eq(&old.field, &ds.field));
        // Made by the job (about as many arcs as before for another
        // measure); reaching a level can replay millions of steps, too
        // slow for the UI thread.
        let level = ds.first_level.take().unwrap_or_else(|| {
            let mut level = SimplifiedTree::new(Arc::clone(&ds.sim));
            level.set_level(DEFAULT_ARCS);
            level
        });
        if !same_field {
            let (lo, hi) = ds.range;
            self.global_h = 0.5 * (lo + hi);
            self.selection.clear();
            self.all = AllContours::new(self.notify.clone());
            self.preview = Preview::new(self.notify.clone());
            self.frame_pending.clear();
            let (min, max) = crate::render::grid_bounds(ds.field.dims(), ds.field.spacing());
            self.view3d
                .set_placement(crate::render::placement(&ds.field));
            self.view3d.set_bounds(min, max);
            self.tree_panel.reset();
            jobs::betti::start(&mut self.betti, &ds);
        }
        for w in &ds.warnings {
            eprintln!("warning: {w}");
        }
        self.info = (!ds.warnings.is_empty()).then(|| ds.warnings.join("; "));
        if let Some(ctx) = &self.ctx {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(format!(
                "flexiso — {}",
                ds.name
            )));
        }
        self.level = Some(level);
        self.dataset = Some(ds);
        self.error = None;
        if !same_field {
            // Another volume: the old steps do not apply to it.
            self.history = History::default();
            if self.pending_session.is_none() {
                self.session_path = None;
            }
        } else if let (Some(step), Some(level)) = (self.pending_step.take(), &mut self.level) {
            level.set_step(step);
        }
        if let Some(s) = self.pending_session.take() {
            self.apply_session(&s);
        } else if !same_field && self.first_screen {
            self.show_first_screen();
            // What the program chose is not the user's work: closing the
            // first screen unchanged asks nothing.
            if let Some(scene) = self.scene_now() {
                self.history.observe(scene, false, Instant::now());
                self.history.mark_saved();
            }
        }
    }

    /// Selects the first screen's contours: the most important branches
    /// of the level shown, each in its own colour at its representative
    /// isovalue ([`crate::simplify::overview`]); the 3D view frames them
    /// once their meshes arrive.
    fn show_first_screen(&mut self) {
        let (Some(ds), Some(level)) = (&self.dataset, &self.level) else {
            return;
        };
        let mut ids = Vec::new();
        for f in &ds.first_screen {
            let la = level.arc(f.arc);
            let iso = crate::field::Isovalue::new(f.h);
            if let Some(seed) =
                crate::contour::path_seed_in_chain(&ds.tree, &ds.field, la.chain, iso)
            {
                let id = self
                    .selection
                    .add(&ds.field, &ds.tree, seed.arc, f.h, false);
                ids.push((id, seed.arc, f.h));
            }
        }
        self.selection.active = None;
        self.frame_pending = ids;
    }

    /// Frames the 3D view on the first screen's contours once every one
    /// of them has its mesh (or has none).
    fn frame_first_screen(&mut self) {
        if self.frame_pending.is_empty() {
            return;
        }
        let contours: Vec<&selection::Contour> = self
            .frame_pending
            .iter()
            .filter_map(|&(id, s, h)| {
                self.selection
                    .get(id)
                    .filter(|c| c.superarc == s && c.h == h)
            })
            .collect();
        // The user changed the scene meanwhile (ids restart after a
        // clear): the view is theirs, not the first screen's.
        if contours.len() != self.frame_pending.len() {
            self.frame_pending.clear();
            return;
        }
        if contours.iter().any(|c| c.extracting()) {
            return;
        }
        let mut lo = glam::Vec3::splat(f32::INFINITY);
        let mut hi = glam::Vec3::splat(f32::NEG_INFINITY);
        for m in contours.iter().filter_map(|c| c.gpu.as_ref()) {
            lo = lo.min(m.bbox.0);
            hi = hi.max(m.bbox.1);
        }
        if lo.cmple(hi).all() {
            self.view3d.fit_to(lo.to_array(), hi.to_array());
        }
        self.frame_pending.clear();
    }

    /// The first screen's contours still to be framed (tests).
    pub fn framing_pending(&self) -> bool {
        !self.frame_pending.is_empty()
    }

    /// The hover preview (tests).
    pub fn preview(&self) -> &Preview {
        &self.preview
    }

    /// Waits for the hover preview in flight (tests).
    pub fn wait_for_preview(&mut self) {
        self.preview.wait();
    }

    /// Keeps the hover preview on the arc under the pointer: the contour a
    /// click there would select, extracted by a job; none while dragging
    /// or when no arc is hovered.
    fn update_preview(&mut self, pointer_down: bool) {
        self.preview.poll();
        let hovered = self.tree_panel.hovered.filter(|_| !pointer_down);
        let (Some(ds), Some(level), Some(arc)) = (&self.dataset, &self.level, hovered) else {
            self.preview.clear();
            self.tree_panel.preview_note = None;
            return;
        };
        match TreePanel::contour_of_arc(ds, level, arc, self.global_h) {
            Some((s, h)) => self.preview.request(&ds.field, &ds.tree, s, h),
            None => self.preview.clear(),
        }
        self.tree_panel.preview_note = match self.preview.state {
            PreviewState::Off => None,
            PreviewState::Extracting => Some("preview: extracting…".into()),
            PreviewState::Ready if self.preview.mesh.is_some() => {
                Some("preview: dimmed in the 3D view".into())
            }
            PreviewState::Ready => Some("preview: no contour there".into()),
            PreviewState::Skipped => Some(format!(
                "preview skipped: the contour takes over {} ms to extract",
                jobs::preview::PREVIEW_BUDGET.as_millis()
            )),
        };
    }

    /// The Betti numbers of the dataset shown, once computed.
    fn betti(&self) -> Option<Arc<ContourTopology>> {
        self.dataset
            .as_ref()
            .and_then(|ds| jobs::betti::of(&self.betti, ds))
    }

    /// Waits for the Betti numbers of the dataset shown (tests).
    pub fn wait_for_betti(&mut self) -> Option<Arc<ContourTopology>> {
        self.betti.wait();
        self.betti.poll();
        self.betti()
    }

    /// Selects the contour of the live arc `arc` (tests; the tree panel
    /// does the same on a click).
    pub fn select_arc(&mut self, arc: crate::simplify::SimplifiedArcId, replace: bool) {
        if let (Some(ds), Some(level)) = (&self.dataset, &self.level) {
            TreePanel::select_arc(ds, level, &mut self.selection, arc, self.global_h, replace);
        }
    }

    fn spawn_dialog(&mut self, kind: DialogKind) {
        let start_dir = self
            .dataset
            .as_ref()
            .and_then(|d| d.path.as_ref())
            .and_then(|p| p.parent().map(|p| p.to_path_buf()));
        let stem = self
            .dataset
            .as_ref()
            .map(|d| d.name.split('.').next().unwrap_or("flexiso").to_string())
            .unwrap_or_else(|| "flexiso".into());
        jobs::dialog::spawn(&mut self.dialog, kind, start_dir, stem);
    }

    fn handle_dialogs(&mut self) {
        match self.dialog.poll_take() {
            Some(Ok(DialogAnswer::Chosen((kind, p)))) => self.chosen(kind, p),
            Some(Ok(DialogAnswer::Unavailable(kind))) => self.menu.ask_path(kind),
            Some(Ok(DialogAnswer::Cancelled)) => self.after_save = None,
            Some(Err(e)) => self.error = Some(format!("file dialog: {e}")),
            None => {}
        }
    }

    /// A path chosen in a dialog or typed for one.
    fn chosen(&mut self, kind: DialogKind, p: PathBuf) {
        match kind {
            DialogKind::Open => self.request(session::Pending::Open(p.to_string_lossy().into())),
            DialogKind::ExportContours => self.start_contour_export(p),
            DialogKind::TreeJson => self.start_tree_export(p),
            DialogKind::Screenshot => self.pending_screenshot = Some(p),
            DialogKind::SaveSession => {
                let _ = self.save_session(&p);
            }
            DialogKind::OpenSession => self.request(session::Pending::OpenSession(p)),
        }
    }

    fn act(&mut self, action: Action) {
        match action {
            Action::Dialog(kind) => self.spawn_dialog(kind),
            Action::Open(input) => self.request(session::Pending::Open(input)),
            Action::SetMeasure(m) => self.set_measure(m),
            Action::CancelJob => self.pipeline.cancel(),
            Action::Path(kind, p) => self.chosen(kind, PathBuf::from(p)),
            Action::Undo => self.undo(),
            Action::Redo => self.redo(),
            Action::ClearContours => self.selection.clear(),
            Action::SaveSession => self.save_session_here_or_ask(),
            Action::Quit => self.request(session::Pending::Quit),
            Action::Preset(p) => self.set_view_preset(p),
        }
    }

    fn handle_input(&mut self, ui: &mut egui::Ui) {
        if ui.input_mut(|i| i.consume_key(Modifiers::COMMAND, Key::O)) {
            self.spawn_dialog(DialogKind::Open);
        }
        if ui.input_mut(|i| i.consume_key(Modifiers::COMMAND, Key::S)) {
            self.save_session_here_or_ask();
        }
        let typing = ui.ctx().egui_wants_keyboard_input();
        if !typing && self.confirm.is_none() {
            // Shift+Z first: consume_key(COMMAND, Z) ignores shift.
            let redo = ui.input_mut(|i| {
                i.consume_key(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z)
                    || i.consume_key(Modifiers::COMMAND, Key::Y)
            });
            if redo {
                self.redo();
            } else if ui.input_mut(|i| i.consume_key(Modifiers::COMMAND, Key::Z)) {
                self.undo();
            }
        }
        if !typing {
            if ui.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Delete)) {
                if let Some(id) = self.selection.active {
                    self.selection.remove(id);
                } else if let Some(last) = self.selection.contours.last().map(|c| c.id) {
                    self.selection.remove(last);
                }
            }
            // Escape closes popups (egui does) and cancels a drag; it
            // never clears the scene (Edit > Clear contours does).
            if ui.input(|i| i.key_pressed(Key::Escape) && i.pointer.any_down()) {
                self.cancel_drag(&ui.ctx().clone());
            }
        }
        let dropped: Vec<PathBuf> = ui.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        if let Some(p) = dropped.first() {
            self.request(session::Pending::Open(p.to_string_lossy().into()));
        }
    }

    /// Keeps "all contours at h" current: a new extraction when the value
    /// is let go (not on every drag frame), one at a time.
    fn update_all_contours(&mut self, pointer_down: bool) {
        self.all.poll();
        let Some(ds) = &self.dataset else { return };
        if !self.show_all || pointer_down {
            return;
        }
        let h = self.global_h;
        let scope = match &self.level {
            Some(level) if !self.menu.every_component => {
                let key = AllContours::key_of(&ds.field, h, Some(level.step()));
                if !self.all.wants(key) {
                    return;
                }
                Scope::Arcs {
                    step: level.step(),
                    superarcs: spanning_superarcs(ds, level, h),
                }
            }
            _ => Scope::Every,
        };
        self.all.request(&ds.tree, &ds.field, h, scope);
    }

    /// "All contours at h" shows every component of the level set (true)
    /// or one contour per arc of the shown tree spanning h (false, the
    /// default).
    pub fn set_every_component(&mut self, on: bool) {
        self.menu.every_component = on;
    }

    /// Waits for the "all contours at h" extraction in flight (tests).
    pub fn wait_for_all_contours(&mut self, _ctx: &egui::Context) {
        self.all.wait();
        self.update_all_contours(false);
    }

    /// The superarcs of the contours "all contours at h" shows (tests).
    pub fn all_contour_arcs(&self) -> Vec<crate::tree::ArcId> {
        self.all.meshes.iter().map(|m| m.arc).collect()
    }

    /// Number of contours shown by "all contours at h".
    pub fn all_contours_shown(&self) -> usize {
        if self.show_all {
            self.all.meshes.len()
        } else {
            0
        }
    }

    /// Ranks the tree's leaves by another measure: the simplification is
    /// recomputed in the background from the collapsed tree (the field is
    /// not read again); the selection stays.
    pub fn set_measure(&mut self, measure: Measure) {
        if measure == self.measure {
            return;
        }
        self.measure = measure;
        if let Some(ds) = &self.dataset {
            let arcs = self.level.as_ref().map_or(DEFAULT_ARCS, |l| l.num_arcs());
            self.start(Request::Resimplify {
                dataset: Box::new(ds.clone()),
                arcs,
            });
        }
    }

    /// The measure ranking the leaves.
    pub fn measure(&self) -> Measure {
        self.measure
    }

    /// Moves to the simplest level with at most `arcs` arcs (tests,
    /// scripts; the curve panel does this on a drag).
    pub fn set_level_arcs(&mut self, arcs: usize) {
        if let Some(level) = &mut self.level {
            level.set_level(arcs);
        }
    }

    /// Switches "all contours at h" on or off.
    pub fn set_show_all(&mut self, on: bool) {
        self.show_all = on;
    }

    /// What the 3D view draws: the selected contours, and every contour
    /// at h (faded while contours are selected).
    fn scene(&self) -> Vec<SceneMesh> {
        let mut scene = Vec::new();
        for c in &self.selection.contours {
            if let Some(m) = &c.gpu {
                scene.push(SceneMesh {
                    key: SceneKey::Contour(c.id),
                    mesh: Arc::clone(m),
                    version: c.version,
                    colour: c.colour,
                    visible: self.selection.shown(c),
                    highlighted: self.selection.active == Some(c.id),
                });
            }
        }
        if let Some(m) = &self.preview.mesh {
            scene.push(SceneMesh {
                key: SceneKey::Preview,
                mesh: Arc::clone(m),
                version: self.preview.version,
                colour: Color32::from_rgba_unmultiplied(235, 235, 235, 90),
                visible: true,
                highlighted: false,
            });
        }
        if self.show_all {
            let faded = !self.selection.contours.is_empty();
            for (i, m) in self.all.gpu.iter().enumerate() {
                // A selected contour at h is this very surface: its faded
                // copy would stay (and catch clicks) after it is hidden.
                let arc = self.all.meshes.get(i).map(|m| m.arc);
                if self
                    .selection
                    .contours
                    .iter()
                    .any(|c| Some(c.superarc) == arc && c.h == self.global_h)
                {
                    continue;
                }
                let c = palette(i);
                scene.push(SceneMesh {
                    key: SceneKey::AtH(i),
                    mesh: Arc::clone(m),
                    version: self.all.version,
                    colour: if faded { c.gamma_multiply(0.35) } else { c },
                    visible: true,
                    highlighted: false,
                });
            }
        }
        scene
    }

    /// A surface picked in the 3D view: a selected contour becomes the
    /// active one; a contour at h is selected.
    fn picked(&mut self, key: SceneKey, shift: bool) {
        match key {
            SceneKey::Contour(id) => self.selection.active = Some(id),
            SceneKey::Preview => {}
            SceneKey::AtH(i) => {
                if let (Some(ds), Some(m)) = (&self.dataset, self.all.meshes.get(i)) {
                    self.selection
                        .add(&ds.field, &ds.tree, m.arc, self.global_h, !shift);
                }
            }
        }
    }

    /// The menu bar, with the error or info line below it.
    fn top_panel(&mut self, ui: &mut egui::Ui) {
        self.menu.edit = panels::menu::EditState {
            undo: self.history.undo_label().map(str::to_string),
            redo: self.history.redo_label().map(str::to_string),
            contours: self.selection.contours.len(),
        };
        let actions = self.menu.ui(
            ui,
            self.measure,
            self.dataset.as_ref(),
            &mut self.global_h,
            &mut self.show_all,
        );
        for a in actions {
            self.act(a);
        }
        if let Some(e) = self.error.clone() {
            ui.horizontal(|ui| {
                ui.label(RichText::new(format!("Error: {e}")).color(Color32::LIGHT_RED));
                if ui.small_button("dismiss").clicked() {
                    self.error = None;
                }
            });
        } else if let Some(i) = self.info.clone() {
            ui.horizontal(|ui| {
                ui.label(RichText::new(i).weak());
                if ui.small_button("ok").clicked() {
                    self.info = None;
                }
            });
        }
    }

    fn status_panel(&mut self, ui: &mut egui::Ui) {
        let status = Status {
            running: self.pipeline.running(),
            shown: self.dataset.as_ref().zip(self.level.as_ref()),
            ui_ms: self.ui_ms,
            render_ms: self.view3d.last_render_ms,
            extracting: self.selection.extracting(),
            all: (
                self.show_all,
                // Done only once the meshes are on screen (uploaded); just
                // switched on, the extraction is about to start.
                self.all.extracting()
                    || (self.show_all && (!self.all.started() || self.view3d.uploading)),
                self.all.meshes.len(),
                self.all.millis,
            ),
        };
        if let Some(a) = panels::menu::status_bar(ui, &status) {
            self.act(a);
        }
    }

    /// The left panel: the tree above the curve.
    fn tree_and_curve(&mut self, ui: &mut egui::Ui) {
        let betti = self.betti();
        let (Some(ds), Some(level)) = (&self.dataset, &mut self.level) else {
            ui.label("Loading…");
            return;
        };
        let curve_h = 210.0f32.min(ui.available_height() * 0.4);
        let tree_h = (ui.available_height() - curve_h - 8.0).max(100.0);
        let w = ui.available_width();
        ui.allocate_ui(egui::vec2(w, tree_h), |ui| {
            self.tree_panel.betti = betti;
            self.tree_panel
                .ui(ui, ds, level, &mut self.selection, &mut self.global_h);
        });
        ui.separator();
        self.curve_panel.ui(ui, level, &ds.curve);
    }

    /// Waits for the "all contours at h" meshes to be uploaded (tests with
    /// a renderer): true when none is pending.
    pub fn all_contours_on_screen(&self) -> bool {
        !self.all.extracting() && !self.view3d.uploading
    }
}

impl eframe::App for FlexisoApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let t0 = Instant::now();
        self.intercept_close(&ui.ctx().clone());
        if let Some(r) = self.pipeline.poll_take() {
            self.accept(r);
        }
        self.handle_dialogs();
        self.poll_exports();
        self.betti.poll();
        self.selection.poll();
        self.frame_first_screen();
        self.handle_input(ui);
        let rs = frame.wgpu_render_state().cloned();
        let pointer_down = ui.input(|i| i.pointer.any_down());
        self.update_all_contours(pointer_down);

        egui::Panel::top("menu").show(ui, |ui| self.top_panel(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status_panel(ui));
        // The window may start small before the window manager sizes it;
        // egui keeps the panel's first size, so size it once the window is.
        let screen_w = ui.ctx().content_rect().width();
        let mut tree = egui::Panel::left("tree").resizable(true).min_size(260.0);
        if self.sized_frames < 3 {
            tree = tree.exact_size((0.38 * screen_w).clamp(300.0, 760.0));
            if screen_w >= 900.0 && self.dataset.is_some() {
                self.sized_frames += 1;
            }
        }
        tree.show(ui, |ui| self.tree_and_curve(ui));
        self.update_preview(pointer_down || self.tree_panel.dragging());
        // A fixed width: the 3D view does not move as the list's text
        // changes.
        egui::Panel::right("selection")
            .resizable(false)
            .exact_size(CONTOUR_PANEL_WIDTH)
            .show(ui, |ui| {
                let tree = self.dataset.as_ref().map(|d| Arc::clone(&d.tree));
                let layout = self.dataset.as_ref().map(|d| Arc::clone(&d.layout));
                let go_to = panels::contour_list::ui(
                    ui,
                    &mut self.selection,
                    tree.as_deref(),
                    self.level.as_ref(),
                    layout.as_deref().map(|l| l.branches()),
                );
                if let (Some(step), Some(level)) = (go_to, &self.level) {
                    let sim = Arc::clone(level.simplification());
                    self.curve_panel.go_to_step(step, &sim);
                }
            });
        let mut view_rect = egui::Rect::NOTHING;
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| {
                self.slice_panel(ui);
                view_rect = ui.available_rect_before_wrap();
                self.update_context();
                let scene = self.scene();
                let ev = self.view3d.ui(ui, rs.as_ref(), &scene);
                if let Some((key, shift)) = ev.picked {
                    self.picked(key, shift);
                }
            });
        if let Some(a) = self.menu.path_window(&ui.ctx().clone()) {
            self.act(a);
        }
        self.confirm_modal(&ui.ctx().clone());
        self.recovery_modal(&ui.ctx().clone());
        let busy = ui.input(|i| i.pointer.any_down()) || ui.ctx().egui_wants_keyboard_input();
        self.track_history(busy);
        self.autosave(t0);
        self.save_screenshot(rs.as_ref());
        self.write_ui_dump(view_rect);

        if self.show_all && !self.all.started() {
            // Just switched on: extract at the next frame.
            ui.ctx().request_repaint();
        }
        if self.pipeline.is_running() {
            // Animate the progress bar, at a rate that leaves the cores to
            // the job: without a GPU every frame is rasterised on the CPU.
            // Input still repaints at once (and the UI thread outranks the
            // job's threads, see jobs::yield_to_ui).
            ui.ctx().request_repaint_after(PROGRESS_REPAINT);
        }
        self.ui_ms = t0.elapsed().as_secs_f64() * 1e3;
        if let Some(log) = &mut self.frame_log {
            let stage = self
                .pipeline
                .running()
                .map(|r| r.progress.get().0)
                .unwrap_or_else(|| "idle".into());
            log.frame(self.ui_ms, &stage);
        }
    }
}

/// The superarcs whose contours at `h` the arcs of `level` spanning `h`
/// stand for, one per arc, sorted.
fn spanning_superarcs(ds: &Dataset, level: &SimplifiedTree, h: f64) -> Vec<crate::tree::ArcId> {
    let sim = level.simplification();
    let iso = crate::field::Isovalue::new(h);
    let mut out: Vec<crate::tree::ArcId> = level
        .arcs()
        .filter(|a| {
            let (vu, vl) = (sim.node_value(a.upper), sim.node_value(a.lower));
            vl <= h && h < vu
        })
        .filter_map(|a| crate::contour::path_seed_in_chain(&ds.tree, &ds.field, a.chain, iso))
        .map(|s| s.arc)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}
