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
    ply_bytes_counts(&std::fs::read(path).expect("read ply"))
}

/// [`ply_counts`] of the bytes of a PLY.
fn ply_bytes_counts(bytes: &[u8]) -> (usize, usize) {
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
    // Per vertex: 6 floats, 3 colour bytes, the contour int; per face: the
    // count byte and 3 ints.
    assert_eq!(bytes.len() - end, nv * 31 + nf * 13, "PLY body size");
    for f in 0..nf {
        let at = end + nv * 31 + f * 13;
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
    // Each contour index mapped to its arc (as printed) and isovalue.
    let header = std::fs::read(&ply).expect("ply");
    let header = String::from_utf8_lossy(&header[..header.len().min(1 << 16)]).into_owned();
    let comments: Vec<&str> = header
        .lines()
        .filter(|l| l.starts_with("comment contour "))
        .collect();
    assert_eq!(comments.len(), table.len());
    for (i, (line, r)) in comments.iter().zip(&table).enumerate() {
        let w: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(w[2], i.to_string(), "{line}");
        assert_eq!(w[3], format!("arc_{}", r.arc.replace(':', "_")), "{line}");
        assert_eq!(
            (w[4], w[6], w[7]),
            ("superarc", "isovalue", "0.5"),
            "{line}"
        );
        assert!(w[5].parse::<u32>().is_ok(), "{line}");
    }

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

// ------------------------------------------------------ a CLI that pipes

#[test]
fn tree_json_to_stdout_carries_only_the_json_and_the_report_goes_to_stderr() {
    let o = flexiso(&["tree", "synthetic:12", "--json", "-"]);
    assert!(o.success(), "{}", o.stderr);
    let json: serde_json::Value =
        serde_json::from_str(&o.stdout).expect("stdout is one JSON value");
    assert!(json["nodes"].as_array().is_some_and(|n| !n.is_empty()));
    assert!(
        o.stderr.contains("superarcs:"),
        "report on stderr: {}",
        o.stderr
    );
    assert!(!o.stderr.contains("error"), "{}", o.stderr);
    // -q: nothing but the product.
    let q = flexiso(&["-q", "tree", "synthetic:12", "--json", "-"]);
    assert!(q.success() && q.stderr.is_empty(), "{}", q.stderr);
    assert_eq!(q.stdout, o.stdout);
    // And without -: the report on stdout, as before.
    let plain = flexiso(&["tree", "synthetic:12"]);
    assert!(plain.stdout.contains("superarcs:") && plain.stderr.is_empty());
    // The system's names of standard output are standard output, as `-`
    // is: the JSON alone there, the report on stderr.
    for name in ["/dev/stdout", "/dev/fd/1"] {
        let named = flexiso(&["tree", "synthetic:12", "--json", name]);
        assert!(named.success(), "{name}: {}", named.stderr);
        assert_eq!(named.stdout, o.stdout, "{name}");
        assert!(
            named.stderr.contains("superarcs:"),
            "{name}: {}",
            named.stderr
        );
    }
}

/// `--json` writes its document element by element (a node or an arc at a
/// time); it is the document the library makes whole: the tree with its
/// arcs' Betti numbers, and the collapsed tree.
#[test]
fn tree_json_written_element_by_element_is_the_whole_document() {
    use flexiso::simplify::CollapsedTree;
    use flexiso::tree::ContourTree;
    for input in ["synthetic-noisy:10", "synthetic:14"] {
        let o = flexiso(&["-q", "tree", input, "--json", "-"]);
        assert!(o.success(), "{}", o.stderr);
        let mut written: serde_json::Value = serde_json::from_str(&o.stdout).expect("JSON");
        let volume = flexiso::cli::input::InputArgs::from_input(input)
            .load()
            .expect("a synthetic field");
        let field = volume.field;
        let (tree, _) =
            ContourTree::from_field(&field, &flexiso::progress::Progress::new()).expect("tree");
        let mut whole = flexiso::tree::json::tree_json(&tree, &field);
        flexiso::measure::betti::ContourTopology::new(&tree, &field).add_to_json(&mut whole);
        let collapsed = CollapsedTree::new(&tree, &field);
        whole["collapsed"] = flexiso::simplify::json::collapsed_tree_json(&collapsed, &tree);
        for node in written["nodes"].as_array_mut().expect("nodes") {
            assert!(node["position"].is_array());
            node.as_object_mut().expect("object").remove("position");
        }
        assert!(!whole["arcs"].as_array().expect("arcs").is_empty());
        for key in ["format", "version", "dims", "nodes", "arcs", "collapsed"] {
            assert_eq!(written[key], whole[key], "{input}: {key}");
        }
    }
}

#[test]
fn tree_json_carries_the_source_geometry_and_node_positions() {
    let o = flexiso(&["tree", "synthetic:12", "--json", "-"]);
    assert!(o.success(), "{}", o.stderr);
    let json: serde_json::Value = serde_json::from_str(&o.stdout).expect("JSON");
    assert_eq!(
        json["geometry"]["origin"],
        serde_json::json!([0.0, 0.0, 0.0])
    );
    assert_eq!(
        json["geometry"]["spacing"].as_array().map(Vec::len),
        Some(3)
    );
    assert_eq!(
        json["geometry"]["direction"].as_array().map(Vec::len),
        Some(3)
    );
    assert_eq!(json["geometry"]["positions"], "unnamed");
    assert_eq!(json["source"]["value_type"], "float32");
    for node in json["nodes"].as_array().expect("nodes") {
        let v = node["vertex"].as_u64().expect("vertex") as usize;
        let want = [v % 12, v / 12 % 12, v / 144].map(|c| c as f64);
        let got: Vec<f64> = node["position"]
            .as_array()
            .expect("position")
            .iter()
            .map(|x| x.as_f64().expect("number"))
            .collect();
        // The synthetic field has unit spacing at the origin: world = index.
        assert_eq!(got, want, "node {v}");
    }
    let idx = flexiso(&["tree", "synthetic:12", "--json", "-", "--space", "index"]);
    let json: serde_json::Value = serde_json::from_str(&idx.stdout).expect("JSON");
    assert_eq!(json["geometry"]["positions"], "index");
}

#[test]
fn extract_to_stdout_writes_only_the_mesh() {
    let o = flexiso(&[
        "extract",
        "synthetic:16",
        "--iso",
        "0.5",
        "--out",
        "-",
        "--format",
        "ply",
    ]);
    assert!(o.success(), "{}", o.stderr);
    assert!(o.stdout_bytes.starts_with(b"ply\n"), "a PLY on stdout");
    let (nv, nf) = ply_bytes_counts(&o.stdout_bytes);
    assert!(nv > 0 && nf > 0);
    assert!(
        o.stderr.contains("extract:"),
        "report on stderr: {}",
        o.stderr
    );
    let o = flexiso(&["extract", "synthetic:16", "--iso", "0.5", "--out", "-"]);
    assert_eq!(o.code, 2);
    assert!(o.stderr.contains("--format"), "{}", o.stderr);
}

#[test]
fn an_output_path_that_cannot_be_written_fails_before_the_work_with_one_error() {
    for args in [
        vec![
            "extract",
            "synthetic:16",
            "--iso",
            "0.5",
            "--out",
            "/nonexistent/dir/x.ply",
        ],
        vec!["tree", "synthetic:16", "--json", "/nonexistent/dir/t.json"],
        vec!["render", "synthetic:16", "--out", "/nonexistent/dir/r.png"],
    ] {
        let o = flexiso(&args);
        assert_eq!(o.code, 2, "{args:?}");
        // Nothing was computed: no report line before the error.
        assert!(o.stdout.is_empty(), "{args:?}: {}", o.stdout);
        assert_eq!(
            o.stderr.lines().count(),
            1,
            "{args:?}: one error: {}",
            o.stderr
        );
        assert!(
            o.stderr.contains("does not exist"),
            "{args:?}: {}",
            o.stderr
        );
    }
}

#[test]
fn the_explorer_without_a_display_says_how_to_work_headless() {
    let o = common::flexiso_without_display(&[]);
    assert_eq!(o.code, 2);
    assert_eq!(o.stderr.lines().count(), 1, "{}", o.stderr);
    assert!(
        o.stderr.contains("no display") && o.stderr.contains("flexiso extract"),
        "{}",
        o.stderr
    );
}

#[test]
fn world_coordinates_place_the_mesh_on_the_volume_and_index_on_the_grid() {
    let Some(mha) = common::dataset("formats/real-tools/neghip_oriented_sitk.mha") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let bounds = |space: &str| {
        let out = dir.path().join(format!("{space}.obj"));
        let o = flexiso(&[
            "extract",
            mha.to_str().expect("utf-8"),
            "--iso",
            "100",
            "--space",
            space,
            "--out",
            out.to_str().expect("utf-8"),
        ]);
        assert!(o.success(), "{}", o.stderr);
        let text = std::fs::read_to_string(&out).expect("obj");
        assert!(text.contains(&format!(
            "# space {}",
            if space == "world" { "LPS" } else { "index" }
        )));
        let mut lo = [f64::MAX; 3];
        let mut hi = [f64::MIN; 3];
        for l in text.lines().filter(|l| l.starts_with("v ")) {
            for (k, t) in l.split_whitespace().skip(1).enumerate() {
                let x: f64 = t.parse().expect("number");
                lo[k] = lo[k].min(x);
                hi[k] = hi[k].max(x);
            }
        }
        (lo, hi)
    };
    // Index: inside the grid.
    let (lo, hi) = bounds("index");
    assert!(
        lo.iter().all(|&x| x >= 0.0) && hi.iter().all(|&x| x <= 63.0),
        "{lo:?} {hi:?}"
    );
    // World (LPS, as SimpleITK reports it): axis i runs along -y from 40
    // (63 · 0.9), axis j along +x from -12.5 (63 · 1.1), k along +z from
    // 7.25 (63 · 1.3).
    let (wlo, whi) = bounds("world");
    let eps = 1e-3;
    assert!(
        wlo[0] >= -12.5 - eps && whi[0] <= -12.5 + 69.3 + eps,
        "x {wlo:?} {whi:?}"
    );
    assert!(
        wlo[1] >= 40.0 - 56.7 - eps && whi[1] <= 40.0 + eps,
        "y {wlo:?} {whi:?}"
    );
    assert!(
        wlo[2] >= 7.25 - eps && whi[2] <= 7.25 + 81.9 + eps,
        "z {wlo:?} {whi:?}"
    );
    // The same mesh: index x (axis i) maps to world y = 40 - 0.9 i.
    assert!(
        (whi[1] - (40.0 - 0.9 * lo[0])).abs() < 1e-2,
        "{whi:?} {lo:?}"
    );
    assert!(
        (wlo[0] - (-12.5 + 1.1 * lo[1])).abs() < 1e-2,
        "{wlo:?} {lo:?}"
    );
}

#[test]
fn extract_writes_vtk_polydata_with_the_contour_per_triangle() {
    let dir = tempfile::tempdir().expect("temp dir");
    let vtp = dir.path().join("all.vtp");
    let (_, table) = extract(&[
        "extract",
        "synthetic:24",
        "--iso",
        "0.5",
        "--out",
        vtp.to_str().expect("utf-8"),
    ]);
    let tris: usize = table.iter().map(|r| r.triangles).sum();
    let verts: usize = table.iter().map(|r| r.vertices).sum();
    let text = std::fs::read_to_string(&vtp).expect("vtp");
    assert!(text.starts_with("<?xml") && text.contains("type=\"PolyData\""));
    assert!(
        text.contains(&format!("NumberOfPoints=\"{verts}\""))
            && text.contains(&format!("NumberOfPolys=\"{tris}\"")),
        "counts as printed"
    );
    assert!(text.contains("Name=\"contour\"") && text.contains("Name=\"contour_names\""));
    // Per point the value (the isovalue), per triangle the superarc, per
    // contour its superarc and isovalue as field data: decoded.
    let array = |name: &str| -> Vec<u8> {
        use base64::Engine as _;
        let at = text
            .find(&format!("Name=\"{name}\""))
            .unwrap_or_else(|| panic!("no array {name}"));
        let start = at + text[at..].find('>').expect("tag ends") + 1;
        let end = start + text[start..].find('<').expect("array ends");
        let raw = base64::engine::general_purpose::STANDARD
            .decode(text[start..end].trim())
            .expect("base64");
        let len = u64::from_le_bytes(raw[..8].try_into().expect("header")) as usize;
        assert_eq!(len, raw.len() - 8, "{name}: the header counts the bytes");
        raw[8..].to_vec()
    };
    let values: Vec<f64> = array("value")
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect();
    assert_eq!(values.len(), verts);
    assert!(values.iter().all(|&v| v == 0.5), "every point at h = 0.5");
    let cell_arcs: Vec<i32> = array("arc")
        .chunks_exact(4)
        .map(|b| i32::from_le_bytes(b.try_into().expect("4 bytes")))
        .collect();
    assert_eq!(cell_arcs.len(), tris);
    let field = |name: &str| -> Vec<String> {
        let at = text.find(&format!("Name=\"{name}\"")).expect("field array");
        let start = at + text[at..].find('>').expect("tag ends") + 1;
        let end = start + text[start..].find('<').expect("array ends");
        text[start..end]
            .split_whitespace()
            .map(String::from)
            .collect()
    };
    let isovalues = field("contour_isovalue");
    assert_eq!(isovalues.len(), table.len());
    assert!(
        isovalues.iter().all(|v| v.parse::<f64>() == Ok(0.5)),
        "{isovalues:?}"
    );
    let contour_arcs: Vec<i32> = field("contour_arc")
        .iter()
        .map(|v| v.parse().expect("an arc id"))
        .collect();
    assert_eq!(contour_arcs.len(), table.len());
    let contour_of: Vec<i32> = array("contour")
        .chunks_exact(4)
        .map(|b| i32::from_le_bytes(b.try_into().expect("4 bytes")))
        .collect();
    for (c, a) in contour_of.iter().zip(&cell_arcs) {
        assert_eq!(
            contour_arcs[*c as usize], *a,
            "a triangle's arc is its contour's"
        );
    }
}
