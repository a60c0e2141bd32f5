//! `flexiso bench`: the scaling curve of `--threads` and the `--only`
//! patterns, as a user runs them (small built-in fields, no data needed).
#![allow(clippy::unwrap_used)]

mod common;
use common::flexiso;

/// The data rows (not the header, not the scaling lines) of a bench run.
fn rows(stdout: &str) -> Vec<Vec<String>> {
    stdout
        .lines()
        .skip(1)
        .filter(|l| !l.starts_with(' '))
        .map(|l| l.split_whitespace().map(str::to_owned).collect())
        .collect()
}

/// `flexiso bench EMPTY_DIR ARGS`: the built-in fields only.
fn bench_built_in(args: &[&str]) -> common::Run {
    let empty = tempfile::tempdir().unwrap();
    let dir = empty.path().to_str().unwrap();
    let all: Vec<&str> = ["bench", dir].iter().chain(args).copied().collect();
    flexiso(&all)
}

#[test]
fn threads_give_one_row_per_count_and_the_scaling_curve() {
    // Given unsorted and twice, the counts are run once each, fewest first.
    let run = bench_built_in(&["--smooth", "24", "--synthetic", "20", "--threads", "3,1,3"]);
    assert!(run.success(), "{}", run.stderr);
    let header = run.stdout.lines().next().unwrap();
    assert!(header.ends_with("threads   CPU s blocks"), "{header}");
    let rows = rows(&run.stdout);
    let names: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(
        names,
        [
            "synthetic-24",
            "synthetic-24",
            "synthetic-noisy-20",
            "synthetic-noisy-20"
        ]
    );
    let threads: Vec<&str> = rows.iter().map(|r| r[r.len() - 3].as_str()).collect();
    assert_eq!(threads, ["1", "3", "1", "3"]);
    // Grids this small are never cut (each block at least 16 bands thick).
    let blocks: Vec<&str> = rows.iter().map(|r| r[r.len() - 1].as_str()).collect();
    assert_eq!(blocks, ["1", "1", "1", "1"]);
    // The same tree on every count.
    assert_eq!(rows[0][2], rows[1][2], "superarcs");
    assert_eq!(rows[2][2], rows[3][2], "superarcs");
    for name in ["synthetic-24", "synthetic-noisy-20"] {
        let at = run
            .stdout
            .find(&format!("  scaling of {name} over 1 thread:"))
            .unwrap_or_else(|| panic!("no scaling line for {name}:\n{}", run.stdout));
        let next = run.stdout[at..].lines().nth(1).unwrap();
        assert!(next.trim_start().starts_with("3 threads: total "), "{next}");
        for stage in ["sort", "links", "sweeps", "merge", "augm", "simp", "CPU"] {
            assert!(next.contains(stage), "{stage} missing: {next}");
        }
    }
}

#[test]
fn only_picks_datasets_by_any_of_its_patterns_built_in_fields_too() {
    let run = bench_built_in(&[
        "--smooth",
        "16",
        "--synthetic",
        "16",
        "--only",
        "nothing,noisy",
    ]);
    assert!(run.success(), "{}", run.stderr);
    let names: Vec<String> = rows(&run.stdout)
        .into_iter()
        .map(|r| r[0].clone())
        .collect();
    assert_eq!(names, ["synthetic-noisy-16"]);
    // Without --threads: no thread columns, no scaling line.
    assert!(!run.stdout.contains("scaling"));
    assert!(!run.stdout.lines().next().unwrap().contains("threads"));
}

#[test]
fn zero_threads_is_refused_with_a_clear_error() {
    let run = flexiso(&["bench", "--threads", "0", "--synthetic", "8"]);
    assert!(!run.success());
    assert!(run.stderr.contains("--threads"), "{}", run.stderr);
    assert!(run.stdout.is_empty());
}
