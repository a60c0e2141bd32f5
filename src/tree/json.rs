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

/// Supernode `i` of the tree as a JSON object, an element of `"nodes"`.
pub fn node_json(tree: &ContourTree, field: &ScalarField, i: usize) -> Value {
    let n = tree.nodes()[i];
    json!({
        "vertex": n.vertex,
        "value": field.value(n.vertex),
        "up": n.up,
        "down": n.down,
    })
}

/// Superarc `a` as a JSON object, an element of `"arcs"`.
pub fn arc_json(tree: &ContourTree, a: usize) -> Value {
    let arc = tree.arcs()[a];
    json!({
        "upper": tree.node(arc.upper).vertex,
        "lower": tree.node(arc.lower).vertex,
        "regular_vertices": tree.arc_vertices(ArcId(a as u32)).len(),
    })
}

/// The tree of `field` as a JSON object (`flexiso tree --json` writes the
/// same keys element by element: [`node_json`], [`arc_json`]).
pub fn tree_json(tree: &ContourTree, field: &ScalarField) -> Value {
    let nodes: Vec<Value> = (0..tree.nodes().len())
        .map(|i| node_json(tree, field, i))
        .collect();
    let arcs: Vec<Value> = (0..tree.arcs().len()).map(|a| arc_json(tree, a)).collect();
    json!({
        "format": "flexiso-contour-tree",
        "version": 1,
        "dims": field.dims(),
        "nodes": nodes,
        "arcs": arcs,
    })
}
