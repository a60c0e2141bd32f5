//! What the explorer shows about one volume: the [`Dataset`] a pipeline
//! run makes, immutable once made and shared by every panel, and the
//! views of a simplification the panels draw (tree layout, curve, first
//! level), computed with it off the UI thread.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use crate::field::ScalarField;
use crate::simplify::layout::TreeLayout;
use crate::simplify::overview::{Feature, first_screen_step, important_branches};
use crate::simplify::{CollapsedTree, Simplification, SimplifiedTree};
use crate::tree::ContourTree;

/// How many arcs the tree shows when no better level is known (a level
/// asked for by a session; the first screen takes the curve's widest
/// plateau instead, [`crate::simplify::overview::first_screen_step`]).
pub const DEFAULT_ARCS: usize = 100;

/// How many branches the first screen shows as contours at most.
pub const FIRST_SCREEN_BRANCHES: usize = 6;

/// Wall-clock times of the pipeline's stages.
#[derive(Clone, Copy, Debug, Default)]
pub struct StageTimes {
    /// Reading (or generating) the volume.
    pub load: Duration,
    /// Building the contour tree.
    pub tree: Duration,
    /// Collapsing, measuring and the whole pruning sequence.
    pub simplify: Duration,
    /// The branch layout of the tree panel.
    pub layout: Duration,
}

impl StageTimes {
    /// Sum of the stages.
    pub fn total(&self) -> Duration {
        self.load + self.tree + self.simplify + self.layout
    }
}

/// Everything the explorer shows about one volume, immutable once made.
#[derive(Clone)]
pub struct Dataset {
    /// What the user opened (file name, or "synthetic").
    pub name: String,
    /// The file, when there is one.
    pub path: Option<PathBuf>,
    /// Format description.
    pub format: String,
    /// The field.
    pub field: Arc<ScalarField>,
    /// Its smallest and largest value (computed once: a scan of the
    /// values is too slow for every frame of a big volume).
    pub range: (f64, f64),
    /// Its contour tree.
    pub tree: Arc<ContourTree>,
    /// The collapsed tree (kept so another measure needs no field pass).
    pub collapsed: Arc<CollapsedTree>,
    /// The pruning sequence under the current measure.
    pub sim: Arc<Simplification>,
    /// Where the tree panel draws each node.
    pub layout: Arc<TreeLayout>,
    /// The simplification curve as drawn (log10 feature size, log10 arcs;
    /// decimated).
    pub curve: Arc<Vec<[f64; 2]>>,
    /// The level to show first, made here because reaching it can replay
    /// millions of steps; the explorer takes it (so clones stay cheap).
    pub first_level: Option<SimplifiedTree>,
    /// The most important branches at `first_level`, each with its
    /// representative contour: what the first screen shows.
    pub first_screen: Vec<Feature>,
    /// Stage times.
    pub times: StageTimes,
    /// Reader warnings.
    pub warnings: Vec<String>,
}

/// What the panels draw of a simplification.
pub struct Views {
    /// The tree layout.
    pub layout: Arc<TreeLayout>,
    /// The curve as drawn.
    pub curve: Arc<Vec<[f64; 2]>>,
    /// The level to show first.
    pub level: SimplifiedTree,
    /// The branches to show as contours there.
    pub features: Vec<Feature>,
}

/// What the panels draw of a simplification: the tree layout, the curve,
/// the level of about `arcs` arcs (None: the first screen's, at the
/// curve's widest plateau) and its most important branches (`range`: the
/// field's values).
pub fn views(sim: &Arc<Simplification>, arcs: Option<usize>, range: (f64, f64)) -> Views {
    let layout = Arc::new(TreeLayout::new(sim));
    let curve = Arc::new(drawn_curve(sim));
    let mut level = SimplifiedTree::new(Arc::clone(sim));
    match arcs {
        Some(n) => level.set_level(n),
        None => level.set_step(first_screen_step(sim)),
    }
    let features = important_branches(&level, layout.branches(), range, FIRST_SCREEN_BRANCHES);
    Views {
        layout,
        curve,
        level,
        features,
    }
}

/// The curve of `sim` as the panel draws it: log10 feature size against
/// log10 arcs, decimated to [`CURVE_RESOLUTION`] (computed with the
/// simplification, off the UI thread: a curve has a point per step).
pub fn drawn_curve(sim: &Simplification) -> Vec<[f64; 2]> {
    decimate(
        sim.curve()
            .iter()
            .filter(|p| p.feature_size > 0.0 && p.arcs > 0)
            .map(|p| [p.feature_size.log10(), (p.arcs as f64).log10()]),
        CURVE_RESOLUTION,
    )
}

/// Decades below which two points of the curve are drawn as one: a
/// fifth of a pixel at the panel's usual size (7 decades over ~450 px).
const CURVE_RESOLUTION: f64 = 0.003;

/// The points of a polyline that are more than `eps` away (in x or y)
/// from the last point kept, plus the last: a curve of millions of
/// steps (one per pruned arc) becomes a few thousand points that draw
/// the same, so the UI thread does not tessellate millions each frame.
fn decimate(points: impl Iterator<Item = [f64; 2]>, eps: f64) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::new();
    let mut last_dropped = None;
    for p in points {
        match out.last() {
            Some(q) if (p[0] - q[0]).abs() <= eps && (p[1] - q[1]).abs() <= eps => {
                last_dropped = Some(p);
            }
            _ => {
                out.push(p);
                last_dropped = None;
            }
        }
    }
    out.extend(last_dropped);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_the_ends_and_every_point_stays_close() {
        // A staircase like a simplification curve: 200k steps.
        let curve: Vec<[f64; 2]> = (1..200_000u32)
            .map(|i| {
                let arcs = f64::from(200_000 - i);
                let feature = f64::from(i / 7 + 1).powf(1.3);
                [feature.log10(), arcs.log10()]
            })
            .collect();
        let eps = 0.003;
        let kept = decimate(curve.iter().copied(), eps);
        assert!(kept.len() < 10_000, "{} points kept", kept.len());
        assert_eq!(kept.first(), curve.first());
        assert_eq!(kept.last(), curve.last());
        // Every original point lies within eps of the last point kept at
        // or before it.
        let mut k = 0;
        for p in &curve {
            while k + 1 < kept.len() && kept[k + 1] == *p {
                k += 1;
            }
            if kept[k] != *p {
                let q = kept[k];
                assert!((p[0] - q[0]).abs() <= eps && (p[1] - q[1]).abs() <= eps);
            }
        }
        assert!(decimate(std::iter::empty(), eps).is_empty());
        assert_eq!(decimate([[1.0, 1.0]].into_iter(), eps), vec![[1.0, 1.0]]);
    }
}
