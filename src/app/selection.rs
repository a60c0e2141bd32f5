//! The selection: the contours the user picked, each the contour of one
//! superarc at one isovalue, with its mesh and measurements. Panels talk
//! through this state: the tree panel adds contours and moves their
//! isovalues, the 3D view draws them, the list edits them.
//!
//! A contour is stored as (original superarc, isovalue): that pair names
//! it at every level of simplification (an arc of a simplified tree is a
//! chain of superarcs, and its contour at h is the contour of the one
//! superarc of the chain spanning h).

use std::collections::HashMap;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};

use egui::Color32;

use super::view3d::prepare;

use crate::contour::follow::Cancelled;
use crate::contour::{
    ContourFollower, ContourMesh, FollowerScratch, Isovalue, MeshTopology, path_seed,
};
use crate::field::ScalarField;
use crate::render::PreparedMesh;
use crate::tree::{ArcId, ContourTree};

/// Distinct colours for contours (sRGB).
pub const PALETTE: [Color32; 10] = [
    Color32::from_rgb(228, 115, 51),
    Color32::from_rgb(77, 153, 217),
    Color32::from_rgb(115, 191, 89),
    Color32::from_rgb(217, 89, 140),
    Color32::from_rgb(230, 191, 64),
    Color32::from_rgb(140, 115, 204),
    Color32::from_rgb(89, 191, 191),
    Color32::from_rgb(191, 140, 102),
    Color32::from_rgb(170, 170, 80),
    Color32::from_rgb(200, 120, 220),
];

/// One selected contour.
#[derive(Clone, Debug)]
pub struct Contour {
    /// Stable id (also the renderer's mesh id).
    pub id: u64,
    /// The superarc whose contour this is.
    pub superarc: ArcId,
    /// The isovalue (the level set at `h + ε`, see [`Isovalue`]).
    pub h: f64,
    /// Contours split from one another by dragging through a node share a
    /// group (the first one's id) and move together.
    pub group: u64,
    /// Colour in the 3D view and on the tree.
    pub colour: Color32,
    /// Drawn in the 3D view.
    pub visible: bool,
    /// The extracted mesh (None until extracted, or when the superarc
    /// does not span h).
    pub mesh: Option<Arc<ContourMesh>>,
    /// The same mesh made ready for the GPU (off the UI thread).
    pub gpu: Option<Arc<PreparedMesh>>,
    /// Its measurements.
    pub topology: Option<MeshTopology>,
    /// Bumped whenever the mesh changes (the 3D view re-uploads).
    pub version: u64,
    /// Milliseconds the last extraction took.
    pub extract_ms: f64,
    /// Extraction requests made (the mesh shown answers `done` of them).
    requested: u64,
    done: u64,
}

impl Contour {
    /// True while the mesh shown is older than the isovalue.
    pub fn extracting(&self) -> bool {
        self.done < self.requested
    }

    /// True while the mesh shown waits for its measurements.
    pub fn measuring(&self) -> bool {
        self.mesh.is_some() && self.topology.is_none()
    }
}

/// A contour to extract on the worker.
struct Job {
    id: u64,
    request: u64,
    superarc: ArcId,
    h: f64,
    field: Arc<ScalarField>,
    tree: Arc<ContourTree>,
}

/// A worker's answer: first the mesh, then (unless a newer request for
/// the contour came first) its measurements.
enum Done {
    Mesh {
        id: u64,
        request: u64,
        mesh: Option<Arc<ContourMesh>>,
        gpu: Option<Arc<PreparedMesh>>,
        ms: f64,
    },
    Topology {
        id: u64,
        request: u64,
        topology: MeshTopology,
    },
}

/// Extracts contours on a worker thread, newest request per contour only:
/// while an isovalue is dragged, requests that a newer one has replaced
/// are skipped, so a contour of millions of triangles lags behind the
/// pointer instead of freezing the window. A mesh is sent as soon as it
/// is extracted; its measurements (topology, area, volume: several times
/// the extraction's cost) follow when no newer request is waiting, so
/// dragging shows new meshes at extraction speed.
pub struct Extractor {
    tx: Sender<Job>,
    rx: Receiver<Done>,
    /// The newest request sent per contour: an extraction whose request
    /// is no longer the newest stops (the follower asks while it floods).
    newest: Arc<Mutex<HashMap<u64, u64>>>,
}

impl std::fmt::Debug for Extractor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Extractor")
    }
}

impl Extractor {
    /// Starts the worker; `notify` is called after each answer (egui:
    /// request a repaint).
    pub fn new(notify: Option<Arc<dyn Fn() + Send + Sync>>) -> Self {
        let (tx, jobs) = channel::<Job>();
        let (done_tx, rx) = channel::<Done>();
        let newest: Arc<Mutex<HashMap<u64, u64>>> = Arc::default();
        let sent = Arc::clone(&newest);
        let _ = std::thread::Builder::new()
            .name("flexiso-extract".into())
            .spawn(move || {
                let send = |d: Done| {
                    let ok = done_tx.send(d).is_ok();
                    if let Some(n) = &notify {
                        n();
                    }
                    ok
                };
                // Newest request per contour, and meshes still to measure.
                let mut latest: HashMap<u64, Job> = HashMap::new();
                let mut to_measure: Vec<(u64, u64, Arc<ContourMesh>)> = Vec::new();
                // The follower's tables, kept from one job to the next,
                // and the size of each contour's last mesh (the follower
                // takes a large one straight to the parallel sweep).
                let mut scratch = FollowerScratch::default();
                let mut sizes: HashMap<u64, usize> = HashMap::new();
                loop {
                    if latest.is_empty() && to_measure.is_empty() {
                        match jobs.recv() {
                            Ok(j) => {
                                latest.insert(j.id, j);
                            }
                            Err(_) => return,
                        }
                    }
                    while let Ok(j) = jobs.try_recv() {
                        latest.insert(j.id, j);
                    }
                    if !latest.is_empty() {
                        to_measure.retain(|(id, _, _)| !latest.contains_key(id));
                        let mut batch: Vec<Job> = latest.drain().map(|(_, j)| j).collect();
                        batch.sort_by_key(|j| j.id);
                        for j in batch {
                            let t = std::time::Instant::now();
                            // Superseded: a newer request for this contour
                            // waits in the channel (a poisoned lock cancels
                            // nothing).
                            let (id, request) = (j.id, j.request);
                            let cancel = || {
                                sent.lock()
                                    .is_ok_and(|m| m.get(&id).is_some_and(|&r| r != request))
                            };
                            let Ok(mesh) = extract_mesh(
                                &j.field,
                                &j.tree,
                                j.superarc,
                                j.h,
                                &mut scratch,
                                sizes.get(&j.id).copied(),
                                &cancel,
                            ) else {
                                // Nothing sent: the old mesh stays drawn
                                // until the newer request's is complete.
                                continue;
                            };
                            if let Some(m) = &mesh {
                                sizes.insert(j.id, m.num_triangles());
                            }
                            let mesh = mesh.map(Arc::new);
                            let ms = t.elapsed().as_secs_f64() * 1e3;
                            let gpu = mesh.as_deref().and_then(prepare);
                            if let Some(m) = &mesh {
                                to_measure.push((j.id, j.request, Arc::clone(m)));
                            }
                            let done = Done::Mesh {
                                id: j.id,
                                request: j.request,
                                mesh,
                                gpu,
                                ms,
                            };
                            if !send(done) {
                                return;
                            }
                        }
                        // New requests first: they may make these stale.
                        continue;
                    }
                    if let Some((id, request, mesh)) = to_measure.pop() {
                        let topology = MeshTopology::of(&mesh.positions, &mesh.indices);
                        if !send(Done::Topology {
                            id,
                            request,
                            topology,
                        }) {
                            return;
                        }
                    }
                }
            });
        Self { tx, rx, newest }
    }
}

/// The selected contours and the global isovalue.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    /// Selected contours, in the order they were picked.
    pub contours: Vec<Contour>,
    /// The contour last picked or dragged (shown highlighted).
    pub active: Option<u64>,
    /// Only this contour is drawn, when set.
    pub isolated: Option<u64>,
    next_id: u64,
    /// Extraction worker; without one, contours are extracted at once.
    extractor: Option<std::rc::Rc<Extractor>>,
}

impl Selection {
    /// Extracts on a worker from now on (the window); without this call
    /// every extraction happens at once on the caller's thread.
    pub fn set_extractor(&mut self, e: Extractor) {
        self.extractor = Some(std::rc::Rc::new(e));
    }

    /// Installs the meshes the worker has finished; true if any.
    pub fn poll(&mut self) -> bool {
        let Some(e) = self.extractor.clone() else {
            return false;
        };
        let mut any = false;
        while let Ok(d) = e.rx.try_recv() {
            any |= self.install(d);
        }
        any
    }

    /// Blocks until every requested extraction is installed and measured
    /// (tests).
    pub fn wait_for_extractions(&mut self) {
        let Some(e) = self.extractor.clone() else {
            return;
        };
        while self
            .contours
            .iter()
            .any(|c| c.extracting() || c.measuring())
        {
            match e.rx.recv_timeout(std::time::Duration::from_secs(60)) {
                Ok(d) => {
                    self.install(d);
                }
                Err(_) => return,
            }
        }
    }

    /// Number of contours whose mesh is being extracted.
    pub fn extracting(&self) -> usize {
        self.contours.iter().filter(|c| c.extracting()).count()
    }

    fn install(&mut self, d: Done) -> bool {
        match d {
            Done::Mesh {
                id,
                request,
                mesh,
                gpu,
                ms,
            } => {
                let Some(c) = self.get_mut(id) else {
                    return false;
                };
                // An older answer than one installed: drop it.
                if request <= c.done {
                    return false;
                }
                c.done = request;
                c.mesh = mesh;
                c.gpu = gpu;
                c.topology = None;
                c.version += 1;
                c.extract_ms = ms;
                true
            }
            Done::Topology {
                id,
                request,
                topology,
            } => match self.get_mut(id) {
                // Only the measurements of the mesh shown.
                Some(c) if c.done == request => {
                    c.topology = Some(topology);
                    true
                }
                _ => false,
            },
        }
    }

    /// Extracts `c` (at once, or by the worker).
    fn request(&self, field: &Arc<ScalarField>, tree: &Arc<ContourTree>, c: &mut Contour) {
        c.requested += 1;
        match &self.extractor {
            Some(e) => {
                if let Ok(mut m) = e.newest.lock() {
                    m.insert(c.id, c.requested);
                }
                let job = Job {
                    id: c.id,
                    request: c.requested,
                    superarc: c.superarc,
                    h: c.h,
                    field: Arc::clone(field),
                    tree: Arc::clone(tree),
                };
                if e.tx.send(job).is_err() {
                    extract(field, tree, c);
                }
            }
            None => extract(field, tree, c),
        }
    }
    /// The contour with this id.
    pub fn get(&self, id: u64) -> Option<&Contour> {
        self.contours.iter().find(|c| c.id == id)
    }

    /// The contour with this id, mutably.
    pub fn get_mut(&mut self, id: u64) -> Option<&mut Contour> {
        self.contours.iter_mut().find(|c| c.id == id)
    }

    /// Adds the contour of `superarc` at `h`, extracted at once; returns
    /// its id. With `replace`, the previous selection is cleared first.
    pub fn add(
        &mut self,
        field: &Arc<ScalarField>,
        tree: &Arc<ContourTree>,
        superarc: ArcId,
        h: f64,
        replace: bool,
    ) -> u64 {
        if replace {
            self.clear();
        }
        // The same contour twice would only hide itself.
        if let Some(c) = self
            .contours
            .iter()
            .find(|c| c.superarc == superarc && c.h == h)
        {
            let id = c.id;
            self.active = Some(id);
            return id;
        }
        let id = self.next_id;
        self.next_id += 1;
        let used: Vec<Color32> = self.contours.iter().map(|c| c.colour).collect();
        let colour = PALETTE
            .iter()
            .copied()
            .find(|c| !used.contains(c))
            .unwrap_or(PALETTE[id as usize % PALETTE.len()]);
        let mut c = Contour {
            id,
            group: id,
            superarc,
            h,
            colour,
            visible: true,
            mesh: None,
            gpu: None,
            topology: None,
            version: 0,
            extract_ms: 0.0,
            requested: 0,
            done: 0,
        };
        self.request(field, tree, &mut c);
        self.contours.push(c);
        self.active = Some(id);
        id
    }

    /// Moves contour `id` to `(superarc, h)` and re-extracts it.
    pub fn move_to(
        &mut self,
        field: &Arc<ScalarField>,
        tree: &Arc<ContourTree>,
        id: u64,
        superarc: ArcId,
        h: f64,
    ) {
        let Some(i) = self.contours.iter().position(|c| c.id == id) else {
            return;
        };
        let mut c = self.contours[i].clone();
        if c.superarc != superarc || c.h != h {
            c.superarc = superarc;
            c.h = h;
            self.request(field, tree, &mut c);
            self.contours[i] = c;
        }
    }

    /// Puts the contours of `group` at `positions` (superarc, isovalue):
    /// contour `lead` takes the first, the other members the next ones,
    /// new members (same colour) any extra, and members left over are
    /// removed (contours that met at a node merged). Only contours that
    /// moved are re-extracted.
    pub fn set_group(
        &mut self,
        field: &Arc<ScalarField>,
        tree: &Arc<ContourTree>,
        lead: u64,
        positions: &[(ArcId, f64)],
    ) {
        let Some(group) = self.get(lead).map(|c| c.group) else {
            return;
        };
        if positions.is_empty() {
            return;
        }
        let mut members: Vec<u64> = vec![lead];
        members.extend(
            self.contours
                .iter()
                .filter(|c| c.group == group && c.id != lead)
                .map(|c| c.id),
        );
        for (i, &(superarc, h)) in positions.iter().enumerate() {
            match members.get(i) {
                Some(&id) => self.move_to(field, tree, id, superarc, h),
                None => {
                    let colour = self.get(lead).map(|c| c.colour);
                    let id = self.add(field, tree, superarc, h, false);
                    if let Some(c) = self.get_mut(id) {
                        c.group = group;
                        if let Some(col) = colour {
                            c.colour = col;
                        }
                    }
                }
            }
        }
        for &id in members.iter().skip(positions.len()) {
            self.remove(id);
        }
        self.active = Some(lead);
    }

    /// Removes contour `id`.
    pub fn remove(&mut self, id: u64) {
        self.contours.retain(|c| c.id != id);
        if self.active == Some(id) {
            self.active = None;
        }
        if self.isolated == Some(id) {
            self.isolated = None;
        }
    }

    /// Removes every contour.
    pub fn clear(&mut self) {
        self.contours.clear();
        self.active = None;
        self.isolated = None;
    }

    /// True when contour `c` is drawn (visible, and not hidden by an
    /// isolated other one).
    pub fn shown(&self, c: &Contour) -> bool {
        c.visible && self.isolated.is_none_or(|i| i == c.id)
    }
}

/// The contour of `superarc` at `h` (None when the superarc does not span
/// h).
fn extract_mesh(
    field: &ScalarField,
    tree: &ContourTree,
    superarc: ArcId,
    h: f64,
    scratch: &mut FollowerScratch,
    expected: Option<usize>,
    cancel: &(dyn Fn() -> bool + Sync),
) -> Result<Option<ContourMesh>, Cancelled> {
    let iso = Isovalue::new(h);
    let Some(seed) = path_seed(tree, field, superarc, iso) else {
        return Ok(None);
    };
    // On every core for a large contour (see ContourFollower::extract).
    let mut follower = ContourFollower::with_scratch(field, std::mem::take(scratch));
    let mesh = follower.extract_expecting(&seed, iso, expected, cancel);
    *scratch = follower.into_scratch();
    mesh.map(Some)
}

/// Extracts the contour of `c.superarc` at `c.h` into `c`, at once.
pub fn extract(field: &ScalarField, tree: &ContourTree, c: &mut Contour) {
    let t = std::time::Instant::now();
    let mesh = extract_mesh(
        field,
        tree,
        c.superarc,
        c.h,
        &mut FollowerScratch::default(),
        None,
        &|| false,
    )
    .unwrap_or(None);
    c.extract_ms = t.elapsed().as_secs_f64() * 1e3;
    c.topology = mesh
        .as_ref()
        .map(|m| MeshTopology::of(&m.positions, &m.indices));
    c.gpu = mesh.as_ref().and_then(prepare);
    c.mesh = mesh.map(Arc::new);
    c.version += 1;
    c.done = c.requested;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::progress::Progress;

    fn dataset() -> (Arc<ScalarField>, Arc<ContourTree>, ArcId, f64) {
        let field = Arc::new(Synthetic::cube(24).generate());
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
        // The longest-lived arc, at its middle.
        let (arc, h) = (0..tree.arcs().len() as u32)
            .map(|a| {
                let e = tree.arc(ArcId(a));
                let (lo, hi) = (
                    field.value(tree.node(e.lower).vertex),
                    field.value(tree.node(e.upper).vertex),
                );
                (ArcId(a), lo, hi)
            })
            .max_by(|x, y| (x.2 - x.1).total_cmp(&(y.2 - y.1)))
            .map(|(a, lo, hi)| (a, 0.5 * (lo + hi)))
            .expect("arcs");
        (field, Arc::new(tree), arc, h)
    }

    #[test]
    fn the_worker_sends_the_mesh_then_its_measurements() {
        let (field, tree, arc, h) = dataset();
        let mut s = Selection::default();
        s.set_extractor(Extractor::new(None));
        let id = s.add(&field, &tree, arc, h, true);
        s.wait_for_extractions();
        let c = s.get(id).expect("selected");
        let mesh = c.mesh.as_ref().expect("a mesh");
        assert!(mesh.num_triangles() > 0);
        assert_eq!(
            c.topology.as_ref(),
            Some(&MeshTopology::of(&mesh.positions, &mesh.indices)),
            "the measurements of the mesh shown"
        );
    }

    #[test]
    fn measurements_of_an_older_mesh_are_dropped() {
        let (field, tree, arc, h) = dataset();
        let mut s = Selection::default();
        let id = s.add(&field, &tree, arc, h, true);
        let before = s.get(id).and_then(|c| c.topology.clone());
        assert!(before.is_some(), "extracted and measured at once");
        let stale = Done::Topology {
            id,
            request: 0,
            topology: MeshTopology::default(),
        };
        assert!(!s.install(stale));
        assert_eq!(s.get(id).and_then(|c| c.topology.clone()), before);
        // A newer mesh clears the measurements until its own arrive.
        let newer = Done::Mesh {
            id,
            request: 2,
            mesh: s.get(id).and_then(|c| c.mesh.clone()),
            gpu: s.get(id).and_then(|c| c.gpu.clone()),
            ms: 1.0,
        };
        assert!(s.install(newer));
        assert!(s.get(id).is_some_and(Contour::measuring));
    }
}
