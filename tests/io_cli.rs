//! The input options every subcommand shares, and `flexiso info`.
#![allow(clippy::unwrap_used)]

mod common;
use common::formats::*;

use clap::Parser;
use common::{Run, flexiso};
use flexiso::cli::input::{Endian, InputArgs, default_input};
use flexiso::field::io::NanPolicy;

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    input: InputArgs,
}

fn parse(args: &[&str]) -> InputArgs {
    Cli::try_parse_from(std::iter::once("flexiso").chain(args.iter().copied()))
        .unwrap()
        .input
}

#[test]
fn input_args_parse_raw_layout_and_nan_policy() {
    let a = parse(&[
        "vol.bin", "--dims", "3,4,5", "--type", "uint16", "--endian", "big", "--nan", "max",
    ]);
    assert_eq!(a.input, "vol.bin");
    assert_eq!(a.dims, Some(vec![3, 4, 5]));
    assert_eq!(a.endian, Endian::Big);
    assert_eq!(a.nan, NanPolicy::Max);
    let raw = a.read_options().unwrap().raw.unwrap();
    assert_eq!(raw.dims, [3, 4, 5]);
    assert!(raw.big_endian);
    assert_eq!(parse(&[]), default_input());
    assert!(parse(&["x.raw", "--dims", "3,4,5"]).read_options().is_err());
    assert!(
        parse(&["x.raw", "--dims", "3,4,5", "--type", "cplx"])
            .read_options()
            .is_err()
    );
}

#[test]
fn synthetic_inputs_load_the_built_in_field() {
    let v = InputArgs::from_input("synthetic:6x7x8").load().unwrap();
    assert_eq!(v.field.dims(), [6, 7, 8]);
    let clean = InputArgs::from_input("synthetic:8").load().unwrap();
    let noisy = InputArgs::from_input("synthetic-noisy:8").load().unwrap();
    assert_ne!(clean.field.values(), noisy.field.values());
    assert!(InputArgs::from_input("synthetic:2000").load().is_err()); // 8e9 vertices
}

#[test]
fn raw_file_loads_through_input_args() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("int16", 60);
    let p = write(dir.path(), "v.dat", &encode(&vals, "int16", true));
    let a = parse(&[
        p.to_str().unwrap(),
        "--dims",
        "3,4,5",
        "--type",
        "short",
        "--endian",
        "big",
    ]);
    assert_eq!(as_f64(a.load().unwrap().field.values()), vals);
}

#[test]
fn info_prints_format_dims_type_range_histogram_and_memory() {
    let Some(neghip) = common::dataset("neghip.nrrd") else {
        return;
    };
    let run = flexiso(&["info", neghip.to_str().unwrap()]);
    let (code, out, err) = (run.code, run.stdout, run.stderr);
    assert_eq!(code, 0, "{err}");
    for want in [
        "format:    NRRD (gzip)",
        "dims:      64 x 64 x 64 = 262144 vertices",
        "type:      uint8 (1 byte per value)",
        "spacing:   1 x 1 x 1",
        "range:     0 .. 255",
        "distinct:  256 values",
        "histogram: 10 bins",
        // Counted from the links (no sort): at least the 2242 supernodes.
        "(4220 candidate nodes, 1.6% of the vertices)",
        // The sweeps' peak: the packed order (sized by a counting pass:
        // under a byte per vertex here), 6 and 16 per candidate, just
        // above the grouping's order and 6 (the places and the arcs'
        // vertex lists in 3 bytes each: 1.9 MiB with the lists in 4).
        "contour tree 1.8 MiB at its peak",
        "about 2.1 MiB",
    ] {
        assert!(out.contains(want), "missing '{want}' in\n{out}");
    }
    let bars = out.lines().filter(|l| l.starts_with("  [")).count();
    assert_eq!(bars, 10);
}

#[test]
fn info_on_a_float_field_has_no_distinct_count_and_takes_bins() {
    let run = flexiso(&["info", "synthetic:8", "--bins", "4"]);
    let (code, out) = (run.code, run.stdout);
    assert_eq!(code, 0);
    assert!(
        out.contains("float32") && !out.contains("distinct"),
        "{out}"
    );
    assert_eq!(out.lines().filter(|l| l.starts_with("  [")).count(), 4);
}

#[test]
fn info_on_bad_input_exits_2_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "bad.nrrd",
        b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n123",
    );
    let Run {
        code,
        stdout: out,
        stderr: err,
        ..
    } = flexiso(&["info", p.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: ") && err.contains("bad.nrrd") && err.contains("truncated"),
        "{err}"
    );
    let Run {
        code, stderr: err, ..
    } = flexiso(&["info", "/nonexistent/volume.nrrd"]);
    assert_eq!(code, 2);
    assert!(err.contains("No such file"), "{err}");
}

#[test]
fn info_prints_origin_direction_and_space_and_the_same_as_json() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("uint8", 60);
    let p = write(
        dir.path(),
        "o.nrrd",
        &nrrd(
            "uint8",
            &[5, 4, 3],
            "raw",
            "",
            "space: RAS\nspace directions: (0,2,0) (-3,0,0) (0,0,0.5)\nspace origin: (10,20,30)\n",
            &encode(&vals, "uint8", false),
        ),
    );
    let run = flexiso(&["info", p.to_str().unwrap()]);
    assert!(run.success(), "{}", run.stderr);
    for want in [
        "spacing:   2 x 3 x 0.5",
        "origin:    10 20 30 (RAS space)",
        "direction: (0 1 0) (-1 0 0) (0 0 1)",
    ] {
        assert!(
            run.stdout.contains(want),
            "missing '{want}' in\n{}",
            run.stdout
        );
    }
    let run = flexiso(&["info", p.to_str().unwrap(), "--json"]);
    assert!(run.success(), "{}", run.stderr);
    let json: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(json["origin"], serde_json::json!([10.0, 20.0, 30.0]));
    assert_eq!(json["space"], "RAS");
    assert_eq!(json["dims"], serde_json::json!([5, 4, 3]));
    assert_eq!(json["direction"][1], serde_json::json!([-1.0, 0.0, 0.0]));
    let counts: u64 = json["histogram"]["counts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .sum();
    assert_eq!(counts, 60);
}

#[test]
fn render_without_xdg_runtime_dir_prints_no_error_on_success() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shot.png");
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_flexiso"))
        .args(["render", "synthetic:8", "--size", "32x24", "--out"])
        .arg(&out)
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(out.is_file());
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    assert!(!stderr.contains("error"), "{stderr}");
}

#[test]
fn no_progress_bar_when_standard_error_is_not_a_terminal() {
    // Long enough for several stages to pass the half second on a slow
    // machine; the bar must still not appear in a pipe.
    let run = flexiso(&["tree", "synthetic-noisy:96", "--json", "-"]);
    assert!(run.success(), "{}", run.stderr);
    serde_json::from_slice::<serde_json::Value>(&run.stdout_bytes)
        .expect("stdout is the JSON alone");
    for bad in ['\r', '\u{1b}', '\u{2801}'] {
        assert!(
            !run.stderr.contains(bad),
            "bar drawn into a pipe: {:?}",
            run.stderr
        );
    }
    assert!(!run.stderr.contains('%'), "{}", run.stderr);
    let quiet = flexiso(&["tree", "synthetic-noisy:96", "--json", "-", "-q"]);
    assert!(quiet.success());
    assert_eq!(quiet.stderr, "", "-q: nothing on stderr");
}
