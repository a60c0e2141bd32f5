//! Undo and redo of everything the user makes of a scene: which contours,
//! their isovalues, colours, names and visibility, the isolated one, the
//! measure and the level of simplification.
//!
//! The history does not ask the panels to report their edits: once per
//! frame the app hands it a [`Scene`] (plain data, a few bytes per
//! contour) and the history compares it with the last one it kept. A
//! difference seen while the user is still at it (a button held: a marker,
//! a slider or a colour being dragged; a name being typed; a job running)
//! waits; once the gesture ends it becomes one step. So a drag is one step
//! however many frames it took, and no panel can forget to record an edit.
//! Level changes that follow one another within [`MERGE_WINDOW`] (a far
//! level reached over several frames, the slider's arrow keys) merge into
//! one step.
//!
//! "Unsaved changes" is a comparison too: the scene differs from the one
//! last saved (or opened), and has contours worth keeping.

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::ids::ContourId;
use super::selection::ContourState;
use crate::simplify::Measure;

/// Level-only changes closer together than this merge into one step.
pub const MERGE_WINDOW: Duration = Duration::from_millis(600);

/// Steps kept (the oldest are dropped beyond this).
pub const MAX_STEPS: usize = 500;

/// What the user made, as plain data.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The selected contours, in the list's order.
    pub contours: Vec<ContourState>,
    /// The contour shown alone, if any.
    pub isolated: Option<ContourId>,
    /// The measure ranking the leaves.
    pub measure: Measure,
    /// The level of simplification: its step (exact for one measure) and
    /// its number of arcs.
    pub step: usize,
    /// Arcs at that level.
    pub arcs: usize,
}

impl Scene {
    /// What changed from `self` to `next`, for the Edit menu
    /// ("Undo colour of contour 2").
    pub fn describe_change(&self, next: &Scene) -> String {
        if self.measure != next.measure {
            return format!("measure {}", next.measure.name());
        }
        let (a, b) = (&self.contours, &next.contours);
        if b.is_empty() && !a.is_empty() {
            return "clear contours".into();
        }
        if b.len() > a.len() && b.iter().all(|c| a.iter().all(|o| o.id != c.id)) {
            return "new selection".into();
        }
        if b.len() > a.len() {
            return "add contour".into();
        }
        if b.len() < a.len() {
            return "delete contour".into();
        }
        for (o, n) in a.iter().zip(b) {
            if o.id != n.id {
                return "selection".into();
            }
            let what = if o.h != n.h || o.superarc != n.superarc {
                "move"
            } else if o.colour != n.colour {
                "colour of"
            } else if o.name != n.name {
                "name of"
            } else if o.visible != n.visible {
                "visibility of"
            } else {
                continue;
            };
            return format!("{what} contour {}", n.id);
        }
        if self.isolated != next.isolated {
            return "isolate".into();
        }
        if self.step != next.step {
            return "simplification level".into();
        }
        "change".into()
    }

    /// True when the only difference from `next` is the level.
    fn level_only(&self, next: &Scene) -> bool {
        self.contours == next.contours
            && self.isolated == next.isolated
            && self.measure == next.measure
            && self.step != next.step
    }
}

#[derive(Clone, Debug)]
struct Step {
    /// The scene before the change (on the undo stack) or after it (on
    /// the redo stack).
    scene: Scene,
    /// What the change was.
    label: String,
    /// When it was recorded.
    at: Instant,
    level_only: bool,
}

/// The undo and redo stacks of one dataset.
#[derive(Debug, Default)]
pub struct History {
    undo: Vec<Step>,
    redo: Vec<Step>,
    /// The scene as last recorded: what undo returns from.
    current: Option<Scene>,
    /// The scene as last saved or opened.
    saved: Option<Scene>,
}

impl History {
    /// Forgets every step (another dataset): `scene` is the starting
    /// point, saved as it is.
    pub fn reset(&mut self, scene: Scene) {
        self.undo.clear();
        self.redo.clear();
        self.saved = Some(scene.clone());
        self.current = Some(scene);
    }

    /// Looks at this frame's scene: a change becomes a step unless the
    /// user is `busy` (still dragging or typing). True if it did.
    pub fn observe(&mut self, scene: Scene, busy: bool, now: Instant) -> bool {
        let Some(current) = &self.current else {
            self.reset(scene);
            return false;
        };
        if *current == scene || busy {
            return false;
        }
        let level_only = current.level_only(&scene);
        let label = current.describe_change(&scene);
        self.redo.clear();
        let merge = level_only
            && self
                .undo
                .last()
                .is_some_and(|s| s.level_only && now.duration_since(s.at) < MERGE_WINDOW);
        if merge {
            if let Some(s) = self.undo.last_mut() {
                s.at = now;
            }
        } else {
            let before = self.current.take().unwrap_or_else(|| scene.clone());
            self.undo.push(Step {
                scene: before,
                label,
                at: now,
                level_only,
            });
            if self.undo.len() > MAX_STEPS {
                self.undo.remove(0);
            }
        }
        self.current = Some(scene);
        true
    }

    /// The scene as last recorded (what Escape returns to mid-drag).
    pub fn current(&self) -> Option<&Scene> {
        self.current.as_ref()
    }

    /// Steps back: the scene to show, which is now the current one.
    pub fn undo(&mut self) -> Option<Scene> {
        let step = self.undo.pop()?;
        let now = self.current.replace(step.scene.clone())?;
        self.redo.push(Step {
            scene: now,
            ..step.clone()
        });
        Some(step.scene)
    }

    /// Steps forward again: the scene to show.
    pub fn redo(&mut self) -> Option<Scene> {
        let step = self.redo.pop()?;
        let now = self.current.replace(step.scene.clone())?;
        self.undo.push(Step {
            scene: now,
            ..step.clone()
        });
        Some(step.scene)
    }

    /// What undo would undo ("move contour 2").
    pub fn undo_label(&self) -> Option<&str> {
        self.undo.last().map(|s| s.label.as_str())
    }

    /// What redo would redo.
    pub fn redo_label(&self) -> Option<&str> {
        self.redo.last().map(|s| s.label.as_str())
    }

    /// Forgets the saved scene: the current one is unsaved (a recovered
    /// scene).
    pub fn forget_saved(&mut self) {
        self.saved = None;
    }

    /// Marks the current scene as saved.
    pub fn mark_saved(&mut self) {
        self.saved = self.current.clone();
    }

    /// True when the scene has contours and differs from the one last
    /// saved or opened: closing it would lose something.
    pub fn unsaved(&self) -> bool {
        match (&self.current, &self.saved) {
            (Some(c), saved) => !c.contours.is_empty() && saved.as_ref() != Some(c),
            (None, _) => false,
        }
    }
}

// The app's side: what the scene is now, and putting one back.
impl super::FlexisoApp {
    /// The scene as the user sees it now (None before a dataset).
    pub(super) fn scene_now(&self) -> Option<Scene> {
        let level = self.level.as_ref()?;
        self.dataset.as_ref()?;
        Some(Scene {
            contours: self.selection.states(),
            isolated: self.selection.isolated,
            measure: self.measure,
            step: level.step(),
            arcs: level.num_arcs(),
        })
    }

    /// Shows `scene` (undo, redo, Escape mid-drag, sessions): the
    /// contours at once (extracted in the background), the level at once,
    /// another measure once its simplification is recomputed.
    pub(super) fn apply_scene(&mut self, scene: &Scene) {
        let Some(ds) = &self.dataset else { return };
        let (field, tree) = (Arc::clone(&ds.field), Arc::clone(&ds.tree));
        self.selection
            .restore(&field, &tree, &scene.contours, scene.isolated);
        if scene.measure != self.measure {
            self.set_measure(scene.measure);
            // The steps of a simplification are deterministic: the same
            // step of a recomputed one is the same level.
            self.pending_step = Some(scene.step);
        } else if let Some(level) = &mut self.level
            && level.step() != scene.step
        {
            level.set_step(scene.step);
        }
    }

    /// Undoes the last change to the scene.
    pub fn undo(&mut self) {
        if let Some(s) = self.history.undo() {
            self.apply_scene(&s);
        }
    }

    /// Redoes the last change undone.
    pub fn redo(&mut self) {
        if let Some(s) = self.history.redo() {
            self.apply_scene(&s);
        }
    }

    /// What undo would undo, if anything.
    pub fn undo_label(&self) -> Option<&str> {
        self.history.undo_label()
    }

    /// True when closing the scene would lose contours not saved.
    pub fn unsaved_changes(&self) -> bool {
        self.history.unsaved()
    }

    /// Escape mid-drag: the scene goes back to where the drag began and
    /// the drag ends.
    pub(super) fn cancel_drag(&mut self, ctx: &egui::Context) {
        ctx.stop_dragging();
        if let Some(s) = self.history.current().cloned()
            && self.scene_now().as_ref() != Some(&s)
        {
            self.apply_scene(&s);
        }
    }

    /// Records this frame's scene (see the module doc); `busy` while a
    /// button is held or text typed.
    pub(super) fn track_history(&mut self, busy: bool) {
        if self.pipeline.is_running() || self.pending_step.is_some() {
            return;
        }
        if let Some(s) = self.scene_now() {
            self.history.observe(s, busy, Instant::now());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::ArcId;
    use egui::Color32;

    fn scene(hs: &[f64], step: usize) -> Scene {
        Scene {
            contours: hs
                .iter()
                .enumerate()
                .map(|(i, &h)| ContourState {
                    id: ContourId(i as u64),
                    superarc: ArcId(0),
                    h,
                    group: ContourId(i as u64),
                    colour: Color32::RED,
                    visible: true,
                    name: String::new(),
                })
                .collect(),
            isolated: None,
            measure: Measure::default(),
            step,
            arcs: 100 - step,
        }
    }

    #[test]
    fn a_change_made_while_busy_becomes_one_step_when_the_gesture_ends() {
        let t = Instant::now();
        let mut h = History::default();
        h.reset(scene(&[1.0], 0));
        for v in [1.1, 1.2, 1.3] {
            assert!(!h.observe(scene(&[v], 0), true, t));
        }
        assert!(h.observe(scene(&[1.3], 0), false, t));
        assert_eq!(h.undo_label(), Some("move contour 0"));
        assert_eq!(h.undo(), Some(scene(&[1.0], 0)));
        assert_eq!(h.undo(), None, "one step for the whole drag");
        assert_eq!(h.redo(), Some(scene(&[1.3], 0)));
        assert_eq!(h.redo(), None);
    }

    #[test]
    fn a_new_change_drops_the_redo_steps() {
        let t = Instant::now();
        let mut h = History::default();
        h.reset(scene(&[], 0));
        h.observe(scene(&[1.0], 0), false, t);
        h.undo();
        h.observe(scene(&[2.0], 0), false, t);
        assert_eq!(h.redo(), None);
        assert_eq!(h.undo(), Some(scene(&[], 0)));
    }

    #[test]
    fn level_changes_in_quick_succession_merge() {
        let t = Instant::now();
        let mut h = History::default();
        h.reset(scene(&[1.0], 0));
        h.observe(scene(&[1.0], 5), false, t);
        h.observe(scene(&[1.0], 9), false, t + Duration::from_millis(100));
        h.observe(scene(&[1.0], 12), false, t + Duration::from_secs(5));
        assert_eq!(h.undo(), Some(scene(&[1.0], 9)));
        assert_eq!(h.undo(), Some(scene(&[1.0], 0)));
        assert_eq!(h.undo(), None);
    }

    #[test]
    fn unsaved_means_contours_that_differ_from_the_saved_scene() {
        let t = Instant::now();
        let mut h = History::default();
        h.reset(scene(&[], 0));
        assert!(!h.unsaved());
        h.observe(scene(&[1.0], 0), false, t);
        assert!(h.unsaved());
        h.mark_saved();
        assert!(!h.unsaved());
        h.observe(scene(&[2.0], 0), false, t);
        assert!(h.unsaved());
        h.undo();
        assert!(!h.unsaved(), "back to the saved scene");
    }
}
