//! `flexiso extract` end to end on the synthetic scene: the binary writes
//! PLY, OBJ and STL files whose counts match its printout, extracts one
//! arc or a simplified tree's contours, and refuses bad requests with exit
//! code 2 and a message that says what to do.

mod common;

use common::flexiso;
use std::path::Path;

/// One row of the printout's table.
#[derive(Debug)]
struct Row {
    arc: String,
    triangles: usize,
    vertices: usize,
    euler: i64,
    predicted: i64,
}

/// The table rows of a run's printout.
fn rows(out: &str) -> Vec<Row> {
    out.lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            if f.len() != 8 || !f[0].contains(':') || f[1].parse::<usize>().is_err() {
                return None;
            }
            Some(Row {
                arc: f[0].to_owned(),
                triangles: f[1].parse().ok()?,
                vertices: f[2].parse().ok()?,
                euler: f[5].parse().ok()?,
                predicted: f[7].parse().ok()?,
            })
        })
        .collect()
}

fn extract(args: &[&str]) -> (String, Vec<Row>) {
    let o = flexiso(args);
    assert!(o.success(), "flexiso {args:?} failed: {}", o.stderr);
    let out = o.stdout.clone();
    let r = rows(&out);
    (out, r)
}

/// (vertices, faces) of a binary PLY, checking the body's size.
fn ply_counts(path: &Path) -> (usize, usize) {
    let bytes = std::fs::read(path).expect("read ply");
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .expect("PLY header")
        + 11;
    let header = std::str::from_utf8(&bytes[..end]).expect("ASCII header");
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n"));
    let count = |what: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {what} ")))
            .and_then(|n| n.trim().parse().ok())
            .expect("element count")
    };
    let (nv, nf) = (count("vertex"), count("face"));
    // 6 floats per vertex; per face: count byte, 3 ints, contour int.
    assert_eq!(bytes.len() - end, nv * 24 + nf * 17, "PLY body size");
    for f in 0..nf {
        let at = end + nv * 24 + f * 17;
        assert_eq!(bytes[at], 3, "triangles only");
        for k in 0..3 {
            let i = at + 1 + 4 * k;
            let v = i32::from_le_bytes(bytes[i..i + 4].try_into().expect("4 bytes"));
            assert!((0..nv as i32).contains(&v), "index in range");
        }
    }
    (nv, nf)
}

/// (objects, vertices, normals, faces) of an OBJ.
fn obj_counts(path: &Path) -> (usize, usize, usize, usize) {
    let text = std::fs::read_to_string(path).expect("read obj");
    let n = |p: &str| text.lines().filter(|l| l.starts_with(p)).count();
    let nv = n("v ");
    for l in text.lines().filter(|l| l.starts_with("f ")) {
        for corner in l.split_whitespace().skip(1) {
            let v: usize = corner
                .split('/')
                .next()
                .and_then(|s| s.parse().ok())
                .expect("vertex index");
            assert!((1..=nv).contains(&v), "1-based index in range");
        }
    }
    (n("o "), nv, n("vn "), n("f "))
}

/// Triangles of a binary STL, checking the file's size.
fn stl_triangles(path: &Path) -> usize {
    let bytes = std::fs::read(path).expect("read stl");
    let n = u32::from_le_bytes(bytes[80..84].try_into().expect("4 bytes")) as usize;
    assert_eq!(bytes.len(), 84 + 50 * n, "STL size");
    n
}

#[test]
fn extract_writes_ply_obj_and_stl_matching_the_printout() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = |name: &str| dir.path().join(name);
    let s = |p: &Path| p.to_str().expect("utf-8 path").to_owned();
    let (ply, obj, stl) = (path("all.ply"), path("all.obj"), path("all.STL"));
    let (out, table) = extract(&["extract", "synthetic:32", "--iso", "0.5", "--out", &s(&ply)]);
    assert!(table.len() >= 2, "several contours at 0.5: {out}");
    let tris: usize = table.iter().map(|r| r.triangles).sum();
    let verts: usize = table.iter().map(|r| r.vertices).sum();
    for r in &table {
        assert_eq!(r.euler, r.predicted, "tree predicts χ of {}", r.arc);
    }
    assert_eq!(ply_counts(&ply), (verts, tris));

    let (_, again) = extract(&["extract", "synthetic:32", "--iso", "0.5", "-o", &s(&obj)]);
    assert_eq!(again.len(), table.len(), "deterministic");
    assert_eq!(obj_counts(&obj), (table.len(), verts, verts, tris));

    extract(&["extract", "synthetic:32", "--iso", "0.5", "--out", &s(&stl)]);
    assert_eq!(stl_triangles(&stl), tris);
}

#[test]
fn extract_one_arc_gives_the_same_contour_as_all() {
    let (_, table) = extract(&["extract", "synthetic:32", "--iso", "0.5"]);
    let first = &table[0];
    let (_, one) = extract(&[
        "extract",
        "synthetic:32",
        "--iso",
        "0.5",
        "--arc",
        &first.arc,
    ]);
    assert_eq!(one.len(), 1);
    assert_eq!(
        (one[0].triangles, one[0].vertices, one[0].euler),
        (first.triangles, first.vertices, first.euler)
    );
}

#[test]
fn extract_from_a_simplified_tree_keeps_at_most_its_arcs() {
    let (_, all) = extract(&["extract", "synthetic-noisy:24", "--iso", "0.4"]);
    let (out, few) = extract(&[
        "extract",
        "synthetic-noisy:24",
        "--iso",
        "0.4",
        "--simplify",
        "4",
        "--measure",
        "volume",
    ]);
    assert!(out.contains("simplified to"), "{out}");
    assert!(!few.is_empty() && few.len() <= 4, "{out}");
    assert!(few.len() <= all.len());
}

#[test]
fn bad_requests_exit_with_code_2_and_say_why() {
    let dir = tempfile::tempdir().expect("temp dir");
    let bad = dir.path().join("mesh.xyz");
    let cases: [(Vec<&str>, &str); 5] = [
        (
            vec![
                "extract",
                "synthetic:16",
                "--iso",
                "0.5",
                "--out",
                bad.to_str().expect("utf-8"),
            ],
            "unknown mesh format",
        ),
        (
            vec!["extract", "synthetic:16", "--iso", "7"],
            "outside the volume's range",
        ),
        (
            vec!["extract", "synthetic:16", "--iso", "0.5", "--arc", "1:2"],
            "no arc runs from vertex 1 down to vertex 2",
        ),
        (
            vec!["extract", "synthetic:16", "--iso", "0.5", "--arc", "12"],
            "UPPER:LOWER",
        ),
        (vec!["extract", "synthetic:16"], "--iso"),
    ];
    for (args, message) in cases {
        let o = flexiso(&args);
        assert_eq!(o.code, 2, "{args:?}: {}", o.stderr);
        assert!(
            o.stderr.contains(message),
            "{args:?}: expected '{message}' in: {}",
            o.stderr
        );
    }
    assert!(!bad.exists(), "nothing written on error");
}

#[test]
fn tree_json_has_betti_numbers_per_arc() {
    let dir = tempfile::tempdir().expect("temp dir");
    let json_path = dir.path().join("tree.json");
    let o = flexiso(&[
        "tree",
        "synthetic:24",
        "--json",
        json_path.to_str().expect("utf-8"),
    ]);
    assert!(o.success(), "{}", o.stderr);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_path).expect("json")).expect("parse");
    let arcs = json["arcs"].as_array().expect("arcs");
    assert!(!arcs.is_empty());
    for arc in arcs {
        let b: Vec<i64> = arc["betti"]
            .as_array()
            .expect("betti per arc")
            .iter()
            .map(|x| x.as_i64().expect("integer"))
            .collect();
        let euler = arc["euler"].as_i64().expect("euler");
        assert_eq!(b.len(), 3);
        assert_eq!(b[0], 1, "one contour per arc point");
        assert_eq!(b[0] - b[1] + b[2], euler, "χ = β0 - β1 + β2");
    }
}
