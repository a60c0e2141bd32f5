//! Arcs named on the command line by their two end vertices
//! (`--arc UPPER:LOWER`, mesh vertex ids as `flexiso tree --json` lists
//! them), and the one search that finds such an arc among the superarcs or
//! the arcs of a simplified tree. `extract` and `render` both use it.

use crate::field::ScalarField;
use crate::simplify::{Measure, Simplification, SimplifiedTree};
use crate::tree::{ArcId, ContourTree};
use anyhow::{Context, bail};

/// Parses `UPPER:LOWER` (two vertex ids) for clap.
pub fn parse_arc(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("'{s}' is not UPPER:LOWER (two vertex ids)"))?;
    let id = |t: &str| {
        t.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{t}' is not a vertex id"))
    };
    Ok((id(a)?, id(b)?))
}

/// An arc whose contour may be extracted: its ends (mesh vertices) and the
/// superarcs it stands for, ascending (one for a superarc, a chain for an
/// arc of a simplified tree).
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// The vertex of the upper end.
    pub upper: u32,
    /// The vertex of the lower end.
    pub lower: u32,
    /// The superarcs, ascending in value.
    pub chain: Vec<ArcId>,
}

/// Where [`Target`]s come from: the superarcs of the contour tree, or a
/// simplified tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Arcs {
    /// Every superarc.
    Superarcs,
    /// The arcs left after simplifying to at most this many by a measure.
    Simplified(usize, Measure),
}

impl Arcs {
    /// The arcs of `tree`, in id order.
    pub fn targets(self, tree: &ContourTree, field: &ScalarField) -> anyhow::Result<Vec<Target>> {
        match self {
            Arcs::Superarcs => Ok(tree
                .arcs()
                .iter()
                .enumerate()
                .map(|(a, arc)| Target {
                    upper: tree.node(arc.upper).vertex,
                    lower: tree.node(arc.lower).vertex,
                    chain: vec![ArcId(a as u32)],
                })
                .collect()),
            Arcs::Simplified(0, _) => bail!("--simplify needs at least 1 arc"),
            Arcs::Simplified(n, measure) => {
                let sim = Simplification::new(tree, field, measure);
                let mut level = SimplifiedTree::new(std::sync::Arc::new(sim));
                level.set_level(n);
                Ok(level
                    .arcs()
                    .map(|a| Target {
                        upper: a.upper_vertex,
                        lower: a.lower_vertex,
                        chain: a.chain.to_vec(),
                    })
                    .collect())
            }
        }
    }

    /// The target whose ends are `(upper, lower)`, or an error that says
    /// where to find the ends.
    pub fn find(self, targets: &[Target], (upper, lower): (u32, u32)) -> anyhow::Result<&Target> {
        targets
            .iter()
            .find(|t| t.upper == upper && t.lower == lower)
            .with_context(|| {
                let (which, json) = match self {
                    Arcs::Superarcs => ("superarc", "flexiso tree --json"),
                    Arcs::Simplified(..) => (
                        "arc of the simplified tree",
                        "flexiso tree --json, \"simplified\"",
                    ),
                };
                format!(
                    "no arc runs from vertex {upper} down to vertex {lower}: no {which} has \
                     these ends (ends are critical vertices, the higher first; see {json})"
                )
            })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn arc_ends_parse_with_spaces_and_refuse_garbage() {
        assert_eq!(parse_arc("12:3"), Ok((12, 3)));
        assert_eq!(parse_arc(" 12 : 3 "), Ok((12, 3)));
        assert!(parse_arc("12").unwrap_err().contains("UPPER:LOWER"));
        assert!(
            parse_arc("a:3")
                .unwrap_err()
                .contains("'a' is not a vertex id")
        );
    }
}
