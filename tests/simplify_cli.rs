//! `flexiso tree --measure M --simplify N | --feature-size X --json PATH`:
//! the JSON carries the perturbed tree, the collapsed tree and the
//! simplified level with its curve, consistently.

mod common;

use common::flexiso;
use serde_json::Value;
use std::collections::HashSet;

fn tree_json(args: &[&str]) -> Value {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("tree.json");
    let path_arg = path.to_str().expect("utf-8 path");
    let mut all = vec!["tree", "synthetic-noisy:20", "--json", path_arg];
    all.extend_from_slice(args);
    let out = flexiso(&all);
    assert!(out.success(), "{}", out.stderr);
    let stdout = &out.stdout;
    assert!(stdout.contains("collapsed arcs:"), "{stdout}");
    serde_json::from_str(&std::fs::read_to_string(&path).expect("json written"))
        .expect("valid JSON")
}

fn pair(v: &Value) -> (u64, u64) {
    let a = v.as_array().expect("pair");
    (a[0].as_u64().expect("id"), a[1].as_u64().expect("id"))
}

#[test]
fn simplified_tree_json_is_consistent_with_the_perturbed_tree() {
    for (measure, limit) in [("height", 3usize), ("volume", 7), ("hypervolume", 12)] {
        let json = tree_json(&["--measure", measure, "--simplify", &limit.to_string()]);
        let perturbed: HashSet<(u64, u64)> = json["arcs"]
            .as_array()
            .expect("arcs")
            .iter()
            .map(|a| {
                (
                    a["upper"].as_u64().expect("u"),
                    a["lower"].as_u64().expect("l"),
                )
            })
            .collect();
        let collapsed = json["collapsed"]["arcs"]
            .as_array()
            .expect("collapsed arcs");
        assert!(!collapsed.is_empty() && collapsed.len() <= perturbed.len());
        let s = &json["simplified"];
        assert_eq!(s["measure"], measure);
        let arcs = s["arcs"].as_array().expect("simplified arcs");
        assert!(
            !arcs.is_empty() && arcs.len() <= limit,
            "{measure}: {}",
            arcs.len()
        );
        for a in arcs {
            assert!(a["up_cost"].is_number() && a["down_cost"].is_number());
            let chain: Vec<(u64, u64)> = a["original_arcs"]
                .as_array()
                .expect("chain")
                .iter()
                .map(pair)
                .collect();
            assert!(!chain.is_empty() && chain.iter().all(|e| perturbed.contains(e)));
        }
        let curve: Vec<(u64, f64)> = s["curve"]
            .as_array()
            .expect("curve")
            .iter()
            .map(|p| (p[0].as_u64().expect("arcs"), p[1].as_f64().expect("size")))
            .collect();
        assert_eq!(curve[0], (collapsed.len() as u64, 0.0));
        for w in curve.windows(2) {
            assert!(w[1].0 < w[0].0 && w[1].1 >= w[0].1, "{w:?}");
        }
    }
}

#[test]
fn feature_size_zero_keeps_the_collapsed_tree() {
    let json = tree_json(&["--feature-size", "0"]);
    assert_eq!(
        json["simplified"]["arcs"].as_array().map(Vec::len),
        json["collapsed"]["arcs"].as_array().map(Vec::len)
    );
}
