//! The explorer window (eframe + egui): a thin layer over the engine.
//!
//! * [`pipeline`]: reading, tree and simplification on a worker thread,
//!   with a progress bar and cancellation; errors become messages and the
//!   previous dataset stays.
//! * [`tree_panel`]: the simplified contour tree, markers, global isovalue.
//! * [`curve_panel`]: the simplification curve and the level slider.
//! * [`view3d`]: the selected contours through [`crate::render`].
//! * [`selection`]: the shared state the panels talk through.
//! * [`layout`]: stable x positions of the tree's nodes.
//!
//! [`FlexisoApp`] owns them all and wires them together once per frame;
//! no panel reaches into another's fields. Display toggles never trigger
//! recomputation: only opening a file, changing the measure (background
//! jobs) and moving a contour's isovalue (one contour, a few ms) compute.

pub mod curve_panel;
pub mod layout;
pub mod pipeline;
pub mod selection;
pub mod tree_panel;
pub mod view3d;

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

use egui::{Color32, Key, Modifiers, RichText};
use rayon::prelude::*;

use crate::cli::input::InputArgs;
use crate::contour::{ContourMesh, all_contours};
use crate::field::Isovalue;
use crate::field::ScalarField;
use crate::measure::betti::ContourTopology;
use crate::progress::Progress;
use crate::render::PreparedMesh;
use crate::simplify::{Measure, SimplifiedTree};

use curve_panel::CurvePanel;
use pipeline::{Dataset, Pipeline, Request};
use selection::{PALETTE, Selection};
use tree_panel::{TreePanel, fmt_value};
use view3d::{SceneMesh, View3d};

/// Renderer ids of the "all contours at h" meshes start here (selected
/// contours use small ids).
const ALL_CONTOURS_ID: u64 = 1 << 40;

/// The controls, as the Help menu shows them.
pub const CONTROLS: &str = "\
Tree: click an arc to see its contour (at the isovalue line when the arc \
spans it, else at the arc's middle); shift-click adds one. Drag a marker \
to move its contour's isovalue: past a node it follows the level set (it \
splits going up through a join, contours that meet merge). Drag the \
dashed line to move the isovalue. Wheel zooms, right or middle drag pans, \
double-click resets.
Curve: drag on it, or the slider, to simplify the tree (log-log: arcs \
against feature size).
3D view: drag rotates, wheel zooms, right or middle drag pans, \
double-click fits the contours (again: the volume); click a surface to \
pick it.
Keys: Ctrl+O opens, Delete removes the active contour, Escape clears. \
Drop a volume file on the window to open it.";

/// How often the window redraws on its own while a job runs.
const PROGRESS_REPAINT: Duration = Duration::from_millis(200);

/// How many arcs the tree shows when a dataset opens.
pub const DEFAULT_ARCS: usize = 100;

/// A file dialog's answer, delivered from its thread.
enum Dialog {
    Open(PathBuf),
    ExportContours(PathBuf),
    Screenshot(PathBuf),
    TreeJson(PathBuf),
}

/// Every contour at the global isovalue, one mesh per component,
/// extracted on a worker thread (a whole isosurface of a big volume takes
/// seconds on a small machine; the window keeps drawing meanwhile).
struct AllContours {
    /// (isovalue bits, field) of the meshes shown.
    key: Option<(u64, usize)>,
    /// The key being computed.
    pending: Option<(u64, usize)>,
    meshes: Vec<Arc<ContourMesh>>,
    /// The same, ready for the GPU (one per mesh).
    gpu: Vec<Arc<PreparedMesh>>,
    version: u64,
    millis: f64,
    tx: Sender<IsosurfaceResult>,
    rx: Receiver<IsosurfaceResult>,
}

/// An extraction of every contour at h: its key, the meshes (and the same
/// ready for the GPU), milliseconds.
type IsosurfaceResult = (
    (u64, usize),
    Vec<(Arc<ContourMesh>, Arc<PreparedMesh>)>,
    f64,
);

impl AllContours {
    fn install(&mut self, (key, meshes, millis): IsosurfaceResult) {
        self.pending = None;
        self.key = Some(key);
        (self.meshes, self.gpu) = meshes.into_iter().unzip();
        self.millis = millis;
        self.version += 1;
    }
}

impl Default for AllContours {
    fn default() -> Self {
        let (tx, rx) = channel();
        Self {
            key: None,
            pending: None,
            meshes: Vec::new(),
            gpu: Vec::new(),
            version: 0,
            millis: 0.0,
            tx,
            rx,
        }
    }
}

/// Frame times written with `flexiso open --frame-log FILE`.
struct FrameLog {
    file: std::io::BufWriter<std::fs::File>,
    start: Instant,
    last: Option<Instant>,
}

/// The explorer.
pub struct FlexisoApp {
    pipeline: Pipeline,
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
    error: Option<String>,
    info: Option<String>,
    dialog_tx: Sender<Dialog>,
    dialog_rx: Receiver<Dialog>,
    /// Exports write on their own threads and report here (a message for
    /// the info line, or an error).
    export_tx: Sender<Result<String, String>>,
    export_rx: Receiver<Result<String, String>>,
    exports_running: usize,
    pending_screenshot: Option<PathBuf>,
    frame_log: Option<FrameLog>,
    /// UI time of the last frame (ms), shown in the status bar.
    ui_ms: f64,
    /// Where to write the screen positions of arcs and markers (scripts).
    ui_dump: Option<(PathBuf, String)>,
    all_checkbox: Option<egui::Rect>,
    /// Frames the tree panel has been sized for a full window.
    sized_frames: u32,
    /// Betti numbers of every superarc's contours (computed after the
    /// dataset is shown, on a worker), for the tree's tooltips.
    betti: Option<Arc<ContourTopology>>,
    betti_rx: Option<Receiver<(usize, Arc<ContourTopology>)>>,
    /// The window's context (None in tests built without one).
    ctx: Option<egui::Context>,
    /// The "Open a path" window and its field.
    path_window: bool,
    path_input: String,
}

impl FlexisoApp {
    /// An explorer with nothing loaded.
    pub fn empty() -> Self {
        let (dialog_tx, dialog_rx) = channel();
        let (export_tx, export_rx) = channel();
        Self {
            pipeline: Pipeline::new(),
            dataset: None,
            level: None,
            measure: Measure::default(),
            selection: Selection::default(),
            global_h: 0.0,
            show_all: false,
            all: AllContours::default(),
            tree_panel: TreePanel::new(),
            curve_panel: CurvePanel::default(),
            view3d: View3d::new(),
            error: None,
            info: None,
            dialog_tx,
            dialog_rx,
            export_tx,
            export_rx,
            exports_running: 0,
            pending_screenshot: None,
            frame_log: None,
            ui_ms: 0.0,
            ui_dump: None,
            all_checkbox: None,
            sized_frames: 0,
            betti: None,
            betti_rx: None,
            ctx: None,
            path_window: false,
            path_input: String::new(),
        }
    }

    /// The window's app: starts `request` in the background at once.
    pub fn new(cc: &eframe::CreationContext<'_>, request: Request) -> Self {
        let mut app = Self::empty();
        app.ctx = Some(cc.egui_ctx.clone());
        let ctx = cc.egui_ctx.clone();
        let notify: Arc<dyn Fn() + Send + Sync> = Arc::new(move || ctx.request_repaint());
        app.pipeline.set_notify(Arc::clone(&notify));
        app.selection
            .set_extractor(selection::Extractor::new(Some(notify)));
        app.start(request);
        app
    }

    /// Blocks until the contours being extracted are (tests).
    pub fn wait_for_extractions(&mut self) {
        self.selection.wait_for_extractions();
    }

    /// An explorer on `field`, with the pipeline already run (tests: no
    /// window needed). Contours are extracted on a worker as in the
    /// window: call [`FlexisoApp::wait_for_extractions`].
    pub fn new_for_test(field: ScalarField) -> Self {
        let mut app = Self::empty();
        app.selection.set_extractor(selection::Extractor::new(None));
        let result = pipeline::run(
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
        let mut file = std::io::BufWriter::new(std::fs::File::create(path)?);
        writeln!(file, "t_s\tframe_ms\tui_ms\tstage")?;
        self.frame_log = Some(FrameLog {
            file,
            start: Instant::now(),
            last: None,
        });
        Ok(())
    }

    /// Writes, whenever they change, the screen positions (points) of the
    /// tree's arcs and markers and of the panels to `path`, one per line:
    /// `arc ID X Y HEIGHT`, `marker ID X Y`, `curve|tree|view X0 Y0 X1 Y1`, and
    /// `contours N`. For scripts that click with xdotool.
    pub fn set_ui_dump(&mut self, path: PathBuf) {
        self.ui_dump = Some((path, String::new()));
    }

    fn write_ui_dump(&mut self, view: egui::Rect) {
        let Some((path, last)) = &mut self.ui_dump else {
            return;
        };
        let mut s = String::new();
        let r = |s: &mut String, name: &str, r: egui::Rect| {
            s.push_str(&format!(
                "{name} {:.0} {:.0} {:.0} {:.0}\n",
                r.min.x, r.min.y, r.max.x, r.max.y
            ));
        };
        let d = &self.tree_panel.drawn;
        if let Some(t) = d.rect {
            r(&mut s, "tree", t);
        }
        if let Some(c) = self.curve_panel.plot_rect {
            r(&mut s, "curve", c);
        }
        r(&mut s, "view", view);
        if let Some(c) = self.all_checkbox {
            r(&mut s, "allbox", c);
        }
        s.push_str(&format!("contours {}\n", self.selection.contours.len()));
        for (id, p) in &d.markers {
            s.push_str(&format!("marker {id} {:.0} {:.0}\n", p.x, p.y));
        }
        for ((id, p), h) in d.arcs.iter().zip(&d.arc_heights) {
            s.push_str(&format!("arc {} {:.0} {:.0} {:.0}\n", id.0, p.x, p.y, h));
        }
        if *last != s {
            let _ = std::fs::write(&*path, &s);
            *last = s;
        }
    }

    /// Starts a background job (cancelling the current one).
    pub fn start(&mut self, request: Request) {
        let what = match &request {
            Request::Open(i) => i.input.clone(),
            Request::Field { name, .. } => name.clone(),
            Request::Resimplify { .. } => format!("{} simplification", self.measure),
        };
        self.pipeline.start(request, self.measure, what);
    }

    /// Opens a file (or `synthetic[:N]`) in the background.
    pub fn open(&mut self, input: &str) {
        self.start(Request::Open(InputArgs::from_input(input)));
    }

    /// Blocks until the current job ends and takes its result (tests).
    pub fn wait_for_job(&mut self) {
        if let Some(r) = self.pipeline.wait() {
            self.accept(r);
        }
    }

    /// True while a job runs.
    pub fn busy(&self) -> bool {
        self.pipeline.running().is_some()
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

    /// The global isovalue.
    pub fn global_h(&self) -> f64 {
        self.global_h
    }

    fn accept(&mut self, result: pipeline::JobResult) {
        match result {
            Ok(ds) => {
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
                let mut ds = ds;
                // Made by the job (about as many arcs as before for
                // another measure); reaching a level can replay millions
                // of steps, too slow for the UI thread.
                let level = ds.first_level.take().unwrap_or_else(|| {
                    let mut level = SimplifiedTree::new(Arc::clone(&ds.sim));
                    level.set_level(DEFAULT_ARCS);
                    level
                });
                if !same_field {
                    let (lo, hi) = ds.range;
                    self.global_h = 0.5 * (lo + hi);
                    self.selection.clear();
                    self.all = AllContours::default();
                    let [nx, ny, nz] = ds.field.dims();
                    let [sx, sy, sz] = ds.field.spacing();
                    self.view3d.set_bounds(
                        [0.0; 3],
                        [
                            ((nx - 1) as f64 * sx) as f32,
                            ((ny - 1) as f64 * sy) as f32,
                            ((nz - 1) as f64 * sz) as f32,
                        ],
                    );
                    // Show something at once: the contour of the most
                    // important arc spanning the middle value.
                    self.tree_panel.reset();
                }
                for w in &ds.warnings {
                    eprintln!("warning: {w}");
                }
                self.info = (!ds.warnings.is_empty()).then(|| ds.warnings.join("; "));
                if !same_field {
                    self.start_betti(&ds);
                }
                if let Some(ctx) = &self.ctx {
                    ctx.send_viewport_cmd(egui::ViewportCommand::Title(format!(
                        "flexiso — {}",
                        ds.name
                    )));
                }
                self.level = Some(level);
                self.dataset = Some(ds);
                self.error = None;
            }
            Err(e) if e == "cancelled" => {}
            Err(e) => self.error = Some(e),
        }
    }

    fn start_betti(&mut self, ds: &Dataset) {
        self.betti = None;
        let (tx, rx) = channel();
        self.betti_rx = Some(rx);
        let (tree, field) = (Arc::clone(&ds.tree), Arc::clone(&ds.field));
        let key = Arc::as_ptr(&ds.field) as usize;
        let notify = self.pipeline.notifier();
        let _ = std::thread::Builder::new()
            .name("flexiso-betti".into())
            .spawn(move || {
                pipeline::yield_to_ui();
                let topo = Arc::new(ContourTopology::new(&tree, &field));
                let _ = tx.send((key, topo));
                if let Some(n) = notify {
                    n();
                }
            });
    }

    fn poll_betti(&mut self) {
        let Some(rx) = &self.betti_rx else { return };
        if let Ok((key, topo)) = rx.try_recv() {
            if self
                .dataset
                .as_ref()
                .is_some_and(|d| Arc::as_ptr(&d.field) as usize == key)
            {
                self.betti = Some(topo);
            }
            self.betti_rx = None;
        }
    }

    /// Waits for the Betti numbers of the dataset shown (tests).
    pub fn wait_for_betti(&mut self) -> Option<Arc<ContourTopology>> {
        if let Some(rx) = self.betti_rx.take()
            && let Ok((_, topo)) = rx.recv()
        {
            self.betti = Some(topo);
        }
        self.betti.clone()
    }

    /// Selects the contour of the live arc `arc` (tests; the tree panel
    /// does the same on a click).
    pub fn select_arc(&mut self, arc: crate::simplify::SimplifiedArcId, replace: bool) {
        if let (Some(ds), Some(level)) = (&self.dataset, &self.level) {
            TreePanel::select_arc(ds, level, &mut self.selection, arc, self.global_h, replace);
        }
    }

    fn spawn_dialog(&self, kind: &'static str) {
        let tx = self.dialog_tx.clone();
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
        // rfd's portal backend is thread-safe; the UI keeps running.
        let _ = std::thread::Builder::new()
            .name("flexiso-dialog".into())
            .spawn(move || {
                let mut d = rfd::FileDialog::new();
                if let Some(dir) = start_dir {
                    d = d.set_directory(dir);
                }
                let answer = match kind {
                    "open" => d.set_title("Open a volume").pick_file().map(Dialog::Open),
                    "contours" => d
                        .set_title("Export contours")
                        .add_filter("mesh", &["ply", "obj", "stl"])
                        .set_file_name(format!("{stem}_contours.ply"))
                        .save_file()
                        .map(Dialog::ExportContours),
                    "screenshot" => d
                        .set_title("Save the 3D view")
                        .add_filter("PNG", &["png"])
                        .set_file_name(format!("{stem}.png"))
                        .save_file()
                        .map(Dialog::Screenshot),
                    _ => d
                        .set_title("Export the contour tree")
                        .add_filter("JSON", &["json"])
                        .set_file_name(format!("{stem}_tree.json"))
                        .save_file()
                        .map(Dialog::TreeJson),
                };
                if let Some(a) = answer {
                    let _ = tx.send(a);
                }
            });
    }

    /// Writes the visible selected contours (or, with none selected, the
    /// contours at h shown) to a mesh file.
    pub fn export_contours(&self, path: &std::path::Path) -> anyhow::Result<usize> {
        self.contour_export(path)?()
    }

    /// What [`FlexisoApp::export_contours`] writes, gathered (cheaply, on
    /// the UI thread) into a closure that writes it (anywhere).
    fn contour_export(
        &self,
        path: &std::path::Path,
    ) -> anyhow::Result<impl FnOnce() -> anyhow::Result<usize> + Send + 'static> {
        let mut meshes: Vec<Arc<ContourMesh>> = Vec::new();
        let mut names = Vec::new();
        for c in &self.selection.contours {
            if let Some(m) = &c.mesh
                && self.selection.shown(c)
            {
                meshes.push(Arc::clone(m));
                names.push(format!("contour_{}_h{}", c.id, fmt_value(c.h)));
            }
        }
        if meshes.is_empty() && self.show_all {
            for (i, m) in self.all.meshes.iter().enumerate() {
                meshes.push(Arc::clone(m));
                names.push(format!("component_{i}_h{}", fmt_value(self.global_h)));
            }
        }
        if meshes.is_empty() {
            anyhow::bail!("no contour to export: select one in the tree first");
        }
        let path = path.to_path_buf();
        Ok(move || {
            crate::contour::export::write_contours(&path, &meshes, &names)?;
            Ok(meshes.len())
        })
    }

    /// Writes the tree, the collapsed tree and the level shown as JSON.
    pub fn export_tree_json(&self, path: &std::path::Path) -> anyhow::Result<()> {
        self.tree_export(path)?()
    }

    /// What [`FlexisoApp::export_tree_json`] writes, as a closure.
    fn tree_export(
        &self,
        path: &std::path::Path,
    ) -> anyhow::Result<impl FnOnce() -> anyhow::Result<()> + Send + 'static> {
        let (Some(ds), Some(level)) = (&self.dataset, &self.level) else {
            anyhow::bail!("no dataset loaded");
        };
        let (tree, field, collapsed) = (
            Arc::clone(&ds.tree),
            Arc::clone(&ds.field),
            Arc::clone(&ds.collapsed),
        );
        let level = level.clone();
        let path = path.to_path_buf();
        Ok(move || {
            let mut json = crate::tree::json::tree_json(&tree, &field);
            if let Some(obj) = json.as_object_mut() {
                obj.insert(
                    "collapsed".into(),
                    crate::simplify::json::collapsed_tree_json(&collapsed, &tree),
                );
                obj.insert(
                    "simplified".into(),
                    crate::simplify::json::simplified_tree_json(&level, &tree),
                );
            }
            std::fs::write(&path, serde_json::to_string(&json)?)
                .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
            Ok(())
        })
    }

    /// Exports the contours as File > Export does: gathered now, written
    /// on another thread (a whole isosurface is tens of megabytes), the
    /// outcome in the info line.
    pub fn start_contour_export(&mut self, p: PathBuf) {
        match self.contour_export(&p) {
            Ok(write) => self.export_in_background(move || match write() {
                Ok(n) => Ok(format!("wrote {n} contour(s) to {}", p.display())),
                Err(e) => Err(format!("{e:#}")),
            }),
            Err(e) => self.error = Some(format!("{e:#}")),
        }
    }

    /// Exports the tree as JSON as File > Export does, on another thread.
    pub fn start_tree_export(&mut self, p: PathBuf) {
        match self.tree_export(&p) {
            Ok(write) => self.export_in_background(move || match write() {
                Ok(()) => Ok(format!("wrote {}", p.display())),
                Err(e) => Err(format!("{e:#}")),
            }),
            Err(e) => self.error = Some(format!("{e:#}")),
        }
    }

    /// The info line (what the last action did), if any.
    pub fn info(&self) -> Option<&str> {
        self.info.as_deref()
    }

    /// Runs an export's writing on its own thread; its outcome shows in
    /// the info line when done.
    fn export_in_background(
        &mut self,
        write: impl FnOnce() -> Result<String, String> + Send + 'static,
    ) {
        let tx = self.export_tx.clone();
        let ctx = self.ctx.clone();
        self.exports_running += 1;
        self.info = Some("writing…".into());
        let spawned = std::thread::Builder::new()
            .name("flexiso-export".into())
            .spawn(move || {
                let _ = tx.send(write());
                if let Some(ctx) = ctx {
                    ctx.request_repaint();
                }
            });
        if let Err(e) = spawned {
            self.exports_running -= 1;
            self.error = Some(format!("cannot start the export: {e}"));
        }
    }

    /// Installs the outcomes of finished exports.
    fn poll_exports(&mut self) {
        while let Ok(r) = self.export_rx.try_recv() {
            self.export_done(r);
        }
    }

    fn export_done(&mut self, outcome: Result<String, String>) {
        self.exports_running = self.exports_running.saturating_sub(1);
        match outcome {
            Ok(msg) => self.info = Some(msg),
            Err(e) => self.error = Some(e),
        }
    }

    /// Waits for the exports in flight (tests).
    pub fn wait_for_exports(&mut self) {
        while self.exports_running > 0 {
            match self.export_rx.recv_timeout(Duration::from_secs(60)) {
                Ok(r) => self.export_done(r),
                Err(_) => return,
            }
        }
    }

    fn handle_dialogs(&mut self) {
        while let Ok(d) = self.dialog_rx.try_recv() {
            match d {
                Dialog::Open(p) => self.open(&p.to_string_lossy()),
                Dialog::ExportContours(p) => self.start_contour_export(p),
                Dialog::TreeJson(p) => self.start_tree_export(p),
                Dialog::Screenshot(p) => self.pending_screenshot = Some(p),
            }
        }
    }

    fn handle_input(&mut self, ui: &mut egui::Ui) {
        if ui.input_mut(|i| i.consume_key(Modifiers::COMMAND, Key::O)) {
            self.spawn_dialog("open");
        }
        let typing = ui.ctx().egui_wants_keyboard_input();
        if !typing {
            if ui.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Delete)) {
                if let Some(id) = self.selection.active {
                    self.selection.remove(id);
                } else if let Some(last) = self.selection.contours.last().map(|c| c.id) {
                    self.selection.remove(last);
                }
            }
            if ui.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Escape)) {
                self.selection.clear();
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
            self.open(&p.to_string_lossy());
        }
    }

    fn update_all_contours(&mut self, ctx: &egui::Context, pointer_down: bool) {
        while let Ok(result) = self.all.rx.try_recv() {
            if self.all.pending == Some(result.0) {
                self.all.install(result);
            }
        }
        let Some(ds) = &self.dataset else { return };
        if !self.show_all {
            return;
        }
        let key = (self.global_h.to_bits(), Arc::as_ptr(&ds.field) as usize);
        // Recompute when the line is let go, not on every drag frame, and
        // one extraction at a time (the latest value wins).
        if self.all.key == Some(key) || self.all.pending.is_some() || pointer_down {
            return;
        }
        self.all.pending = Some(key);
        let (tree, field, h) = (Arc::clone(&ds.tree), Arc::clone(&ds.field), self.global_h);
        let tx = self.all.tx.clone();
        let ctx = ctx.clone();
        let _ = std::thread::Builder::new()
            .name("flexiso-isosurface".into())
            .spawn(move || {
                pipeline::yield_to_ui();
                let t = Instant::now();
                let meshes: Vec<_> = all_contours(&tree, &field, Isovalue::new(h))
                    .into_par_iter()
                    .filter(|m| !m.indices.is_empty())
                    .filter_map(|m| Some((view3d::prepare(&m)?, m)))
                    .map(|(gpu, m)| (Arc::new(m), gpu))
                    .collect();
                let _ = tx.send((key, meshes, t.elapsed().as_secs_f64() * 1e3));
                ctx.request_repaint();
            });
    }

    /// Waits for the "all contours at h" extraction in flight (tests).
    pub fn wait_for_all_contours(&mut self, ctx: &egui::Context) {
        if self.all.pending.is_none() {
            return;
        }
        if let Ok(result) = self.all.rx.recv() {
            self.all.install(result);
        }
        self.update_all_contours(ctx, false);
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

    fn scene(&self) -> Vec<SceneMesh> {
        let mut scene = Vec::new();
        for c in &self.selection.contours {
            if let Some(m) = &c.gpu {
                scene.push(SceneMesh {
                    id: c.id,
                    mesh: Arc::clone(m),
                    version: c.version,
                    colour: c.colour,
                    visible: self.selection.shown(c),
                    highlighted: self.selection.active == Some(c.id),
                });
            }
        }
        if self.show_all {
            let faded = !self.selection.contours.is_empty();
            for (i, m) in self.all.gpu.iter().enumerate() {
                let c = PALETTE[i % PALETTE.len()];
                scene.push(SceneMesh {
                    id: ALL_CONTOURS_ID + i as u64,
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

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("Open…  (Ctrl+O)").clicked() {
                    self.spawn_dialog("open");
                }
                if ui.button("Open the built-in dataset").clicked() {
                    self.open("synthetic");
                }
                // Without a desktop portal or GTK the dialog cannot show:
                // a typed path always works.
                if ui.button("Open a path…").clicked() {
                    self.path_window = true;
                }
                ui.separator();
                if ui.button("Export contours (PLY/OBJ/STL)…").clicked() {
                    self.spawn_dialog("contours");
                }
                if ui.button("Save 3D view as PNG…").clicked() {
                    self.spawn_dialog("screenshot");
                }
                if ui.button("Export tree as JSON…").clicked() {
                    self.spawn_dialog("tree");
                }
                ui.separator();
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("Help", |ui| {
                ui.label(CONTROLS);
            });
            ui.separator();
            let mut measure = self.measure;
            egui::ComboBox::from_label("measure")
                .selected_text(measure.name())
                .show_ui(ui, |ui| {
                    for m in Measure::ALL {
                        ui.selectable_value(&mut measure, m, m.name());
                    }
                });
            self.set_measure(measure);
            ui.separator();
            if let Some(ds) = &self.dataset {
                let (lo, hi) = ds.range;
                ui.add(
                    egui::Slider::new(&mut self.global_h, lo..=hi)
                        .text("isovalue")
                        .custom_formatter(|v, _| fmt_value(v)),
                );
                let r = ui.checkbox(&mut self.show_all, "all contours at h");
                self.all_checkbox = Some(r.rect);
            }
        });
    }

    fn path_window(&mut self, ctx: &egui::Context) {
        if !self.path_window {
            return;
        }
        let mut open = true;
        let mut go = false;
        egui::Window::new("Open a volume")
            .open(&mut open)
            .collapsible(false)
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    let label = ui.label("Path:");
                    let r = ui
                        .add(
                            egui::TextEdit::singleline(&mut self.path_input)
                                .hint_text("file, folder or synthetic:N")
                                .desired_width(320.0),
                        )
                        .labelled_by(label.id);
                    go |= r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
                });
                go |= ui.button("Open path").clicked();
            });
        if go && !self.path_input.trim().is_empty() {
            let p = self.path_input.trim().to_string();
            self.open(&p);
            open = false;
        }
        self.path_window = open;
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            if let Some(r) = self.pipeline.running() {
                let (stage, f) = r.progress.get();
                ui.add(egui::ProgressBar::new(f).desired_width(220.0).text(format!(
                    "{}: {stage} {:.0}%",
                    r.what,
                    100.0 * f
                )));
                ui.label(format!("{:.1} s", r.started.elapsed().as_secs_f64()));
                if ui.button("Cancel").clicked() {
                    self.pipeline.cancel();
                }
                ui.separator();
            }
            match (&self.dataset, &self.level) {
                (Some(ds), Some(level)) => {
                    let [x, y, z] = ds.field.dims();
                    let (lo, hi) = ds.range;
                    let t = ds.times;
                    ui.label(RichText::new(&ds.name).strong());
                    ui.label(format!(
                        "{x}×{y}×{z} {}  values {} .. {}",
                        ds.field.values().type_name(),
                        fmt_value(lo),
                        fmt_value(hi)
                    ));
                    ui.separator();
                    ui.label(format!(
                        "superarcs {}  collapsed {}  shown {}",
                        ds.tree.arcs().len(),
                        ds.sim.base_arcs(),
                        level.num_arcs()
                    ));
                    ui.separator();
                    ui.label(format!(
                        "read {:.2} s  tree {:.2} s  simplify {:.2} s",
                        t.load.as_secs_f64(),
                        t.tree.as_secs_f64(),
                        (t.simplify + t.layout).as_secs_f64()
                    ));
                    ui.separator();
                    ui.label(format!(
                        "ui {:.1} ms  3D {:.1} ms",
                        self.ui_ms, self.view3d.last_render_ms
                    ));
                    let n = self.selection.extracting();
                    if n > 0 {
                        ui.spinner();
                        ui.label(format!("extracting {n} contour(s)"));
                    }
                    if self.all.pending.is_some() {
                        ui.spinner();
                        ui.label("extracting all contours at h…");
                    } else if self.show_all {
                        ui.label(format!(
                            "{} contours at h ({:.0} ms)",
                            self.all.meshes.len(),
                            self.all.millis
                        ));
                    }
                }
                _ => {
                    if self.pipeline.running().is_none() {
                        ui.label("no dataset: File > Open (Ctrl+O) or drop a file");
                    }
                }
            }
        });
    }

    fn selection_list(&mut self, ui: &mut egui::Ui) {
        ui.heading("Contours");
        if self.selection.contours.is_empty() {
            ui.label("Click an arc in the tree (shift-click adds), or a surface.");
            ui.label("Drag a marker to move its isovalue.");
            return;
        }
        ui.horizontal(|ui| {
            if ui.button("Clear (Esc)").clicked() {
                self.selection.clear();
            }
            if self.selection.isolated.is_some() && ui.button("Show all").clicked() {
                self.selection.isolated = None;
            }
        });
        let tree = self.dataset.as_ref().map(|d| Arc::clone(&d.tree));
        let mut remove = None;
        egui::ScrollArea::vertical().show(ui, |ui| {
            for c in &mut self.selection.contours {
                let active = self.selection.active == Some(c.id);
                egui::Frame::group(ui.style())
                    .stroke(egui::Stroke::new(
                        if active { 2.0 } else { 1.0 },
                        if active {
                            c.colour
                        } else {
                            Color32::from_gray(70)
                        },
                    ))
                    .show(ui, |ui| {
                        ui.horizontal(|ui| {
                            ui.color_edit_button_srgba(&mut c.colour);
                            let arc = tree.as_ref().map(|t| {
                                let a = t.arc(c.superarc);
                                format!("{}:{}", t.node(a.upper).vertex, t.node(a.lower).vertex)
                            });
                            if ui
                                .selectable_label(
                                    active,
                                    format!("#{}  h = {}", c.id, fmt_value(c.h)),
                                )
                                .on_hover_text(format!(
                                    "superarc {} (vertices upper:lower)",
                                    arc.unwrap_or_default()
                                ))
                                .clicked()
                            {
                                self.selection.active = Some(c.id);
                            }
                        });
                        ui.horizontal(|ui| {
                            ui.checkbox(&mut c.visible, "visible");
                            let iso = self.selection.isolated == Some(c.id);
                            if ui.selectable_label(iso, "isolate").clicked() {
                                self.selection.isolated = if iso { None } else { Some(c.id) };
                            }
                            if ui.button("delete").clicked() {
                                remove = Some(c.id);
                            }
                        });
                        match &c.topology {
                            Some(t) => {
                                ui.label(format!(
                                    "{} triangles, area {}",
                                    t.triangles,
                                    fmt_value(t.area)
                                ));
                                ui.label(format!(
                                    "{}  genus {}{}",
                                    if t.is_closed() {
                                        format!("volume {}", fmt_value(t.volume))
                                    } else {
                                        format!("open ({} boundary loops)", t.boundary_loops)
                                    },
                                    t.genus(),
                                    if t.components > 1 {
                                        format!(", {} components", t.components)
                                    } else {
                                        String::new()
                                    }
                                ));
                                ui.label(
                                    RichText::new(if c.extracting() {
                                        "extracting…".to_string()
                                    } else {
                                        format!("extracted in {:.1} ms", c.extract_ms)
                                    })
                                    .weak(),
                                );
                            }
                            None if c.extracting() => {
                                ui.horizontal(|ui| {
                                    ui.spinner();
                                    ui.label("extracting…");
                                });
                            }
                            None if c.mesh.is_some() => {
                                let n = c.mesh.as_ref().map_or(0, |m| m.num_triangles());
                                ui.label(format!("{n} triangles"));
                                ui.horizontal(|ui| {
                                    ui.spinner();
                                    ui.label(format!(
                                        "measuring… (extracted in {:.1} ms)",
                                        c.extract_ms
                                    ));
                                });
                            }
                            None => {
                                ui.label("no contour at this value");
                            }
                        }
                    });
            }
        });
        if let Some(id) = remove {
            self.selection.remove(id);
        }
    }

    fn save_screenshot(&mut self, rs: Option<&egui_wgpu::RenderState>) {
        let Some(path) = self.pending_screenshot.take() else {
            return;
        };
        let image = rs
            .ok_or_else(|| anyhow::anyhow!("no GPU render state"))
            .and_then(|rs| self.view3d.read_image(rs));
        match image {
            // PNG encoding takes tens of milliseconds: not on this thread.
            Ok(img) => self.export_in_background(move || match img.save(&path) {
                Ok(()) => Ok(format!("saved {}", path.display())),
                Err(e) => Err(format!("screenshot: {}: {e}", path.display())),
            }),
            Err(e) => self.error = Some(format!("screenshot: {e:#}")),
        }
    }

    /// Saves the 3D view at the next frame (tests, scripts).
    pub fn request_screenshot(&mut self, path: PathBuf) {
        self.pending_screenshot = Some(path);
    }
}

impl eframe::App for FlexisoApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let t0 = Instant::now();
        if let Some(r) = self.pipeline.poll() {
            self.accept(r);
        }
        self.handle_dialogs();
        self.poll_exports();
        self.poll_betti();
        self.selection.poll();
        self.handle_input(ui);
        let rs = frame.wgpu_render_state().cloned();
        let pointer_down = ui.input(|i| i.pointer.any_down());
        self.update_all_contours(&ui.ctx().clone(), pointer_down);

        egui::Panel::top("menu").show(ui, |ui| {
            self.menu_bar(ui);
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
        });
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
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
        tree.show(ui, |ui| {
            let (Some(ds), Some(level)) = (&self.dataset, &mut self.level) else {
                ui.label("Loading…");
                return;
            };
            let curve_h = 210.0f32.min(ui.available_height() * 0.4);
            let tree_h = (ui.available_height() - curve_h - 8.0).max(100.0);
            let w = ui.available_width();
            ui.allocate_ui(egui::vec2(w, tree_h), |ui| {
                self.tree_panel.betti = self.betti.clone();
                self.tree_panel
                    .ui(ui, ds, level, &mut self.selection, &mut self.global_h);
            });
            ui.separator();
            self.curve_panel.ui(ui, level, &ds.curve);
        });
        egui::Panel::right("selection")
            .resizable(true)
            .default_size(250.0)
            .show(ui, |ui| self.selection_list(ui));
        let mut view_rect = egui::Rect::NOTHING;
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| {
                view_rect = ui.available_rect_before_wrap();
                let scene = self.scene();
                let ev = self.view3d.ui(ui, rs.as_ref(), &scene);
                if let Some((id, shift)) = ev.picked {
                    if id >= ALL_CONTOURS_ID {
                        let i = (id - ALL_CONTOURS_ID) as usize;
                        if let (Some(ds), Some(m)) = (&self.dataset, self.all.meshes.get(i)) {
                            self.selection
                                .add(&ds.field, &ds.tree, m.arc, self.global_h, !shift);
                        }
                    } else {
                        self.selection.active = Some(id);
                    }
                }
            });
        self.path_window(&ui.ctx().clone());
        self.save_screenshot(rs.as_ref());
        self.write_ui_dump(view_rect);

        if self.show_all && self.all.key.is_none() && self.all.pending.is_none() {
            // Just switched on: extract at the next frame.
            ui.ctx().request_repaint();
        }
        if self.pipeline.running().is_some() {
            // Animate the progress bar, at a rate that leaves the cores to
            // the job: without a GPU every frame is rasterised on the CPU.
            // Input still repaints at once (and the UI thread outranks the
            // job's threads, see pipeline::yield_to_ui).
            ui.ctx().request_repaint_after(PROGRESS_REPAINT);
        }
        self.ui_ms = t0.elapsed().as_secs_f64() * 1e3;
        if let Some(log) = &mut self.frame_log {
            let now = Instant::now();
            let frame_ms = log
                .last
                .map(|l| (now - l).as_secs_f64() * 1e3)
                .unwrap_or(0.0);
            log.last = Some(now);
            let stage = self
                .pipeline
                .running()
                .map(|r| r.progress.get().0)
                .unwrap_or_else(|| "idle".into());
            let _ = writeln!(
                log.file,
                "{:.3}\t{frame_ms:.2}\t{:.2}\t{stage}",
                (now - log.start).as_secs_f64(),
                self.ui_ms
            );
            let _ = log.file.flush();
        }
    }
}
