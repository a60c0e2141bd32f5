//! The collapsed and simplified trees as JSON, added next to the keys of
//! [`crate::tree::json::tree_json`] by `flexiso tree`:
//!
//! `"collapsed": {"nodes":[{"vertex","value","up","down"}...],
//!                "arcs":[{"upper","lower","original_arcs":[[U,L],...]}...]}`
//!
//! `"simplified": {"measure","steps","feature_size","nodes":[...],
//!                 "arcs":[{"upper","lower","up_cost","down_cost",
//!                          "original_arcs":[[U,L],...]}...],
//!                 "curve":[[ARCS, FEATURE_SIZE],...]}`
//!
//! All ids are mesh vertex ids; a node of the collapsed tree is named by
//! the lowest supernode of its group. `original_arcs` lists the superarcs of
//! the perturbed tree (the top-level `"arcs"`) the arc stands for,
//! ascending. Lists are sorted (nodes by vertex order, arcs by lower then
//! upper node) so the output is deterministic. The curve keeps, for each
//! feature size, the simplest level that has it (the corners of the
//! staircase), from the full tree to the last level.

use super::{CollapsedTree, SimplifiedArcId, SimplifiedTree};
use crate::field::ScalarField;
use crate::measure::betti::ContourTopology;
use crate::tree::json::{arc_json, node_json};
use crate::tree::{ArcId, ContourTree};
use serde_json::{Value, json};
use std::io::Write;
use std::path::Path;

fn original_arcs(tree: &ContourTree, chain: &[ArcId]) -> Value {
    chain
        .iter()
        .map(|&e| {
            let arc = tree.arc(e);
            json!([tree.node(arc.upper).vertex, tree.node(arc.lower).vertex])
        })
        .collect()
}

/// Node `v` of the collapsed tree as JSON, an element of its `"nodes"`.
pub fn collapsed_node_json(collapsed: &CollapsedTree, v: u32) -> Value {
    let (up, down) = collapsed.node_degree(v);
    json!({
        "vertex": collapsed.node_vertex(v),
        "value": collapsed.node_value(v),
        "up": up,
        "down": down,
    })
}

/// Arc `a` of the collapsed tree as JSON, an element of its `"arcs"`.
pub fn collapsed_arc_json(collapsed: &CollapsedTree, tree: &ContourTree, a: u32) -> Value {
    let (u, l) = collapsed.arc(a);
    json!({
        "upper": collapsed.node_vertex(u),
        "lower": collapsed.node_vertex(l),
        "original_arcs": original_arcs(tree, collapsed.chain(a)),
    })
}

/// The collapsed tree (zero-height arcs contracted) as JSON (`flexiso tree
/// --json` writes the same keys element by element:
/// [`collapsed_node_json`], [`collapsed_arc_json`]).
pub fn collapsed_tree_json(collapsed: &CollapsedTree, tree: &ContourTree) -> Value {
    let nodes: Vec<Value> = (0..collapsed.num_nodes() as u32)
        .map(|v| collapsed_node_json(collapsed, v))
        .collect();
    let arcs: Vec<Value> = (0..collapsed.num_arcs() as u32)
        .map(|a| collapsed_arc_json(collapsed, tree, a))
        .collect();
    json!({
        "perturbed_arcs": collapsed.perturbed_arcs(),
        "nodes": nodes,
        "arcs": arcs,
    })
}

/// One level of a simplification as JSON, with the simplification curve.
pub fn simplified_tree_json(level: &SimplifiedTree, tree: &ContourTree) -> Value {
    let sim = level.simplification();
    let nodes: Vec<Value> = level
        .nodes()
        .into_iter()
        .map(|v| {
            let (up, down) = level.degree(v);
            json!({
                "vertex": sim.node_vertex(v),
                "value": sim.node_value(v),
                "up": up,
                "down": down,
            })
        })
        .collect();
    let mut arc_ids = level.arc_ids().to_vec();
    arc_ids.sort_unstable_by_key(|&a| {
        (
            sim.lower(SimplifiedArcId(a)),
            sim.upper(SimplifiedArcId(a)),
            a,
        )
    });
    let arcs: Vec<Value> = arc_ids
        .iter()
        .map(|&a| {
            let arc = level.arc(SimplifiedArcId(a));
            json!({
                "upper": arc.upper_vertex,
                "lower": arc.lower_vertex,
                "up_cost": arc.up_cost,
                "down_cost": arc.down_cost,
                "original_arcs": original_arcs(tree, arc.chain),
            })
        })
        .collect();
    json!({
        "measure": sim.measure().name(),
        "steps": level.step(),
        "feature_size": level.feature_size(),
        "nodes": nodes,
        "arcs": arcs,
        "curve": curve_json(sim.curve()),
    })
}

/// The corners of the staircase: point 0, and the last point of each
/// feature size.
fn curve_json(curve: &[super::CurvePoint]) -> Value {
    curve
        .iter()
        .enumerate()
        .filter(|&(k, p)| {
            k == 0
                || curve
                    .get(k + 1)
                    .is_none_or(|q| q.feature_size != p.feature_size)
        })
        .map(|(_, p)| json!([p.arcs, p.feature_size]))
        .collect()
}

/// The whole document `flexiso tree --json` and the explorer's tree
/// export write: the tree ([`crate::tree::json`]), then `more` keys (the
/// CLI's `source` and `geometry`), and `collapsed` and `simplified` where
/// given, written element by element: a node or an arc is made, written
/// and dropped, so that the output of millions of arcs takes no more
/// memory than one (a whole JSON value of white noise's 3.9 M superarcs
/// took more than a 23 GiB machine has; 3.4 GB for `synthetic-noisy:128`,
/// whose document is 184 MB).
pub struct TreeDocument<'a> {
    /// The tree.
    pub tree: &'a ContourTree,
    /// Its field.
    pub field: &'a ScalarField,
    /// A `position` added to each node, from its vertex (the CLI's).
    pub position: Option<&'a dyn Fn(u32) -> Value>,
    /// The arcs' Betti numbers ([`ContourTopology::add_to_arc_json`]).
    pub topology: Option<&'a ContourTopology>,
    /// Keys written after `arcs`, in their order.
    pub more: Vec<(&'static str, Value)>,
    /// The collapsed tree ([`collapsed_tree_json`]'s keys).
    pub collapsed: Option<&'a CollapsedTree>,
    /// A level of its simplification ([`simplified_tree_json`]), written
    /// after `collapsed`.
    pub simplified: Option<Value>,
}

impl TreeDocument<'_> {
    /// A document of the tree alone.
    pub fn of<'a>(tree: &'a ContourTree, field: &'a ScalarField) -> TreeDocument<'a> {
        TreeDocument {
            tree,
            field,
            position: None,
            topology: None,
            more: Vec::new(),
            collapsed: None,
            simplified: None,
        }
    }

    /// Writes the JSON object: `format`, `version`, `dims`, `nodes`,
    /// `arcs`, the `more` keys, `collapsed` and `simplified`.
    pub fn write(&self, w: &mut impl Write) -> std::io::Result<()> {
        let (tree, field) = (self.tree, self.field);
        w.write_all(br#"{"format":"flexiso-contour-tree","version":1,"dims":"#)?;
        write_json(w, &json!(field.dims()))?;
        w.write_all(br#","nodes":"#)?;
        write_array(w, tree.nodes().len(), |i| {
            let mut node = node_json(tree, field, i);
            if let Some(position) = self.position {
                node["position"] = position(tree.nodes()[i].vertex);
            }
            node
        })?;
        w.write_all(br#","arcs":"#)?;
        write_array(w, tree.arcs().len(), |a| {
            let mut arc = arc_json(tree, a);
            if let Some(topology) = self.topology {
                topology.add_to_arc_json(a, &mut arc);
            }
            arc
        })?;
        for (key, value) in &self.more {
            w.write_all(b",")?;
            write_json(w, &json!(key))?;
            w.write_all(b":")?;
            write_json(w, value)?;
        }
        if let Some(collapsed) = self.collapsed {
            w.write_all(br#","collapsed":{"perturbed_arcs":"#)?;
            write_json(w, &json!(collapsed.perturbed_arcs()))?;
            w.write_all(br#","nodes":"#)?;
            write_array(w, collapsed.num_nodes(), |v| {
                collapsed_node_json(collapsed, v as u32)
            })?;
            w.write_all(br#","arcs":"#)?;
            write_array(w, collapsed.num_arcs(), |a| {
                collapsed_arc_json(collapsed, tree, a as u32)
            })?;
            w.write_all(b"}")?;
        }
        if let Some(simplified) = &self.simplified {
            w.write_all(br#","simplified":"#)?;
            write_json(w, simplified)?;
        }
        w.write_all(b"}")
    }

    /// Writes the document to `path`, whole or not at all
    /// ([`crate::output::write_whole`]).
    pub fn write_file(&self, path: &Path) -> std::io::Result<()> {
        crate::output::write_whole(path, |mut out| self.write(&mut out))
    }
}

/// A JSON array of `len` elements, each made by `element` and written
/// before the next is made.
fn write_array<W: Write>(
    w: &mut W,
    len: usize,
    element: impl Fn(usize) -> Value,
) -> std::io::Result<()> {
    w.write_all(b"[")?;
    for i in 0..len {
        if i > 0 {
            w.write_all(b",")?;
        }
        write_json(w, &element(i))?;
    }
    w.write_all(b"]")
}

fn write_json<W: Write>(w: &mut W, value: &Value) -> std::io::Result<()> {
    serde_json::to_writer(w, value).map_err(std::io::Error::from)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::simplify::{Measure, Simplification};
    use std::sync::Arc;

    /// Written element by element, the document is the whole JSON value,
    /// byte for byte, with and without the optional parts.
    #[test]
    fn the_document_written_element_by_element_is_the_whole_value() {
        for (noise, seed) in [(0.0, 1), (0.3, 2)] {
            let field = Synthetic {
                noise,
                seed,
                ..Synthetic::cube(9)
            }
            .generate();
            let (tree, _) =
                ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
            let collapsed = CollapsedTree::new(&tree, &field);
            let sim = Arc::new(Simplification::new(&tree, &field, Measure::Volume));
            let mut level = SimplifiedTree::new(Arc::clone(&sim));
            level.set_step(sim.steps().len() / 2);
            let topology = ContourTopology::new(&tree, &field);
            let position = |v: u32| json!([v, 1]);

            let mut whole = crate::tree::json::tree_json(&tree, &field);
            topology.add_to_json(&mut whole);
            for node in whole["nodes"].as_array_mut().unwrap() {
                let v = node["vertex"].as_u64().unwrap() as u32;
                node["position"] = position(v);
            }
            whole["more"] = json!({"a": 1});
            whole["collapsed"] = collapsed_tree_json(&collapsed, &tree);
            whole["simplified"] = simplified_tree_json(&level, &tree);
            let document = TreeDocument {
                position: Some(&position),
                topology: Some(&topology),
                more: vec![("more", json!({"a": 1}))],
                collapsed: Some(&collapsed),
                simplified: Some(simplified_tree_json(&level, &tree)),
                ..TreeDocument::of(&tree, &field)
            };
            let mut written = Vec::new();
            document.write(&mut written).unwrap();
            assert_eq!(String::from_utf8(written).unwrap(), whole.to_string());

            let mut written = Vec::new();
            TreeDocument::of(&tree, &field).write(&mut written).unwrap();
            let alone = crate::tree::json::tree_json(&tree, &field);
            assert_eq!(String::from_utf8(written).unwrap(), alone.to_string());
        }
    }

    /// A file is written whole or not at all: a folder that does not exist
    /// is an error, and no partial file is left beside the target.
    #[test]
    fn a_document_file_is_written_whole() {
        let field = Synthetic::cube(6).generate();
        let (tree, _) = ContourTree::from_field(&field, &crate::progress::Progress::new()).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tree.json");
        std::fs::write(&path, "old").unwrap();
        TreeDocument::of(&tree, &field).write_file(&path).unwrap();
        let written: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        assert_eq!(written, crate::tree::json::tree_json(&tree, &field));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let missing = dir.path().join("no_such_dir").join("tree.json");
        assert!(
            TreeDocument::of(&tree, &field)
                .write_file(&missing)
                .is_err()
        );
    }
}
