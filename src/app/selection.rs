//! The selection: the contours the user picked, each the contour of one
//! superarc at one isovalue, with its mesh and measurements. Panels talk
//! through this state: the tree panel adds contours and moves their
//! isovalues, the 3D view draws them, the list edits them.
//!
//! A contour is stored as (original superarc, isovalue): that pair names
//! it at every level of simplification (an arc of a simplified tree is a
//! chain of superarcs, and its contour at h is the contour of the one
//! superarc of the chain spanning h).

use std::sync::Arc;

use egui::Color32;

pub use super::ids::ContourId;
use super::ids::prepare;
use super::jobs::Notify;
use super::jobs::extraction::{Done, Extractions, extract_mesh};

use crate::contour::{ContourMesh, FollowerScratch, MeshTopology};
use crate::field::ScalarField;
use crate::render::PreparedMesh;
use crate::tree::{ArcId, ContourTree};

/// Colour `i` of the shared palette ([`crate::render::PALETTE`]).
pub fn palette(i: usize) -> Color32 {
    let [r, g, b] = crate::render::PALETTE[i % crate::render::PALETTE.len()];
    Color32::from_rgb(r, g, b)
}

/// One selected contour.
#[derive(Clone, Debug)]
pub struct Contour {
    /// Stable id.
    pub id: ContourId,
    /// The superarc whose contour this is.
    pub superarc: ArcId,
    /// The isovalue (the level set at `h + ε`, see [`Isovalue`](crate::field::Isovalue)).
    pub h: f64,
    /// Contours split from one another by dragging through a node share a
    /// group (the first one's id) and move together.
    pub group: ContourId,
    /// Colour in the 3D view and on the tree.
    pub colour: Color32,
    /// Drawn in the 3D view.
    pub visible: bool,
    /// The user's name for it ("brain"); may be empty.
    pub name: String,
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

/// What the user made of one contour: plain data, no mesh (see
/// [`Selection::states`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ContourState {
    /// Its id.
    pub id: ContourId,
    /// The superarc it lies on.
    pub superarc: ArcId,
    /// Its isovalue.
    pub h: f64,
    /// Its group (see [`Contour::group`]).
    pub group: ContourId,
    /// Its colour.
    pub colour: Color32,
    /// Drawn.
    pub visible: bool,
    /// Its name.
    pub name: String,
}

/// The selected contours and the global isovalue.
#[derive(Debug, Default)]
pub struct Selection {
    /// Selected contours, in the order they were picked.
    pub contours: Vec<Contour>,
    /// The contour last picked or dragged (shown highlighted).
    pub active: Option<ContourId>,
    /// Only this contour is drawn, when set.
    pub isolated: Option<ContourId>,
    next_id: u64,
    /// Extraction jobs; without them, contours are extracted at once.
    extractions: Option<Extractions>,
}

impl Selection {
    /// Extracts in background jobs from now on (the window), whose
    /// workers call `notify`; without this call every extraction happens
    /// at once on the caller's thread.
    pub fn extract_in_background(&mut self, notify: Option<Notify>) {
        self.extractions = Some(Extractions::new(notify));
    }

    /// Installs the meshes the jobs have finished; true if any.
    pub fn poll(&mut self) -> bool {
        let Some(e) = &mut self.extractions else {
            return false;
        };
        let mut any = false;
        for d in e.poll() {
            any |= self.install(d);
        }
        any
    }

    /// Blocks until every requested extraction is installed and measured
    /// (tests).
    pub fn wait_for_extractions(&mut self) {
        loop {
            self.poll();
            let pending = self
                .contours
                .iter()
                .any(|c| c.extracting() || c.measuring());
            let Some(e) = &mut self.extractions else {
                return;
            };
            if !pending || !e.wait_one() {
                self.poll();
                return;
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

    /// Extracts `c` (at once, or by a job).
    fn request(&mut self, field: &Arc<ScalarField>, tree: &Arc<ContourTree>, c: &mut Contour) {
        c.requested += 1;
        match &mut self.extractions {
            Some(e) => e.request(c.id, c.requested, field, tree, c.superarc, c.h),
            None => extract(field, tree, c),
        }
    }
    /// The contour with this id.
    pub fn get(&self, id: ContourId) -> Option<&Contour> {
        self.contours.iter().find(|c| c.id == id)
    }

    /// The contour with this id, mutably.
    pub fn get_mut(&mut self, id: ContourId) -> Option<&mut Contour> {
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
    ) -> ContourId {
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
        let id = ContourId(self.next_id);
        self.next_id += 1;
        let used: Vec<Color32> = self.contours.iter().map(|c| c.colour).collect();
        let colour = (0..crate::render::PALETTE.len())
            .map(palette)
            .find(|c| !used.contains(c))
            .unwrap_or(palette(id.0 as usize));
        let mut c = Contour {
            id,
            group: id,
            superarc,
            h,
            colour,
            visible: true,
            name: String::new(),
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
        id: ContourId,
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
    /// new members any extra (each in a colour of its own, so the pieces
    /// of a split tell apart in the view and on the tree), and members
    /// left over are removed (contours that met at a node merged). Only
    /// contours that moved are re-extracted.
    pub fn set_group(
        &mut self,
        field: &Arc<ScalarField>,
        tree: &Arc<ContourTree>,
        lead: ContourId,
        positions: &[(ArcId, f64)],
    ) {
        let Some(group) = self.get(lead).map(|c| c.group) else {
            return;
        };
        if positions.is_empty() {
            return;
        }
        let mut members: Vec<ContourId> = vec![lead];
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
                    // add() gives it the first palette colour no contour
                    // has.
                    let id = self.add(field, tree, superarc, h, false);
                    if let Some(c) = self.get_mut(id) {
                        c.group = group;
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
    pub fn remove(&mut self, id: ContourId) {
        self.contours.retain(|c| c.id != id);
        if let Some(e) = &mut self.extractions {
            e.forget(id);
        }
        if self.active == Some(id) {
            self.active = None;
        }
        if self.isolated == Some(id) {
            self.isolated = None;
        }
    }

    /// Removes every contour; the next one picked is numbered 0 again
    /// (its extraction jobs are gone with the old ones).
    pub fn clear(&mut self) {
        self.contours.clear();
        if let Some(e) = &mut self.extractions {
            e.clear();
        }
        self.active = None;
        self.isolated = None;
        self.next_id = 0;
    }

    /// What the user made of each contour, as plain data (for undo and
    /// sessions), in the list's order.
    pub fn states(&self) -> Vec<ContourState> {
        self.contours
            .iter()
            .map(|c| ContourState {
                id: c.id,
                superarc: c.superarc,
                h: c.h,
                group: c.group,
                colour: c.colour,
                visible: c.visible,
                name: c.name.clone(),
            })
            .collect()
    }

    /// Makes the selection `states` (undo, redo, sessions): contours with
    /// the same id keep their mesh unless they moved; the others are
    /// extracted; contours not in `states` are removed.
    pub fn restore(
        &mut self,
        field: &Arc<ScalarField>,
        tree: &Arc<ContourTree>,
        states: &[ContourState],
        isolated: Option<ContourId>,
    ) {
        let gone: Vec<ContourId> = self
            .contours
            .iter()
            .map(|c| c.id)
            .filter(|id| states.iter().all(|s| s.id != *id))
            .collect();
        for id in gone {
            self.remove(id);
        }
        let mut old = std::mem::take(&mut self.contours);
        for s in states {
            let mut c = match old.iter().position(|c| c.id == s.id) {
                Some(i) => old.swap_remove(i),
                None => Contour {
                    id: s.id,
                    group: s.group,
                    superarc: s.superarc,
                    h: s.h,
                    colour: s.colour,
                    visible: s.visible,
                    name: String::new(),
                    mesh: None,
                    gpu: None,
                    topology: None,
                    version: 0,
                    extract_ms: 0.0,
                    requested: 0,
                    done: 0,
                },
            };
            let moved = c.requested == 0 || c.superarc != s.superarc || c.h != s.h;
            c.superarc = s.superarc;
            c.h = s.h;
            c.group = s.group;
            c.colour = s.colour;
            c.visible = s.visible;
            c.name = s.name.clone();
            if moved {
                self.request(field, tree, &mut c);
            }
            self.contours.push(c);
            self.next_id = self.next_id.max(s.id.0 + 1);
        }
        self.isolated = isolated.filter(|i| self.get(*i).is_some());
        if self.active.is_some_and(|a| self.get(a).is_none()) {
            self.active = None;
        }
    }

    /// True when contour `c` is drawn (visible, and not hidden by an
    /// isolated other one).
    pub fn shown(&self, c: &Contour) -> bool {
        c.visible && self.isolated.is_none_or(|i| i == c.id)
    }
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
        s.extract_in_background(None);
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
