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
use crate::tree::{ArcId, ContourTree};
use serde_json::{Value, json};

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
