//! The contour tree as JSON, in the documented exchange format:
//!
//! `{"format":"flexiso-contour-tree","version":1,"dims":[X,Y,Z],
//!   "nodes":[{"vertex":ID,"value":V,"up":U,"down":D},...],
//!   "arcs":[{"upper":ID,"lower":ID,"regular_vertices":K},...]}`
//!
//! Ids are vertex ids (x + X*(y + Y*z)); `upper` is the end higher in the
//! vertex order; values are in the file's units. Other modules add keys
//! (simplified tree, Betti numbers) next to these.

use super::{ArcId, ContourTree};
use crate::field::ScalarField;
use serde_json::{Value, json};

/// The tree of `field` as a JSON object.
pub fn tree_json(tree: &ContourTree, field: &ScalarField) -> Value {
    let nodes: Vec<Value> = tree
        .nodes()
        .iter()
        .map(|n| {
            json!({
                "vertex": n.vertex,
                "value": field.value(n.vertex),
                "up": n.up,
                "down": n.down,
            })
        })
        .collect();
    let arcs: Vec<Value> = tree
        .arcs()
        .iter()
        .enumerate()
        .map(|(a, arc)| {
            json!({
                "upper": tree.node(arc.upper).vertex,
                "lower": tree.node(arc.lower).vertex,
                "regular_vertices": tree.arc_vertices(ArcId(a as u32)).len(),
            })
        })
        .collect();
    json!({
        "format": "flexiso-contour-tree",
        "version": 1,
        "dims": field.dims(),
        "nodes": nodes,
        "arcs": arcs,
    })
}
