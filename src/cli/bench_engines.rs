//! `flexiso bench --algorithm raichel-seshadhri`: the two engines side by
//! side, on the volumes of a folder and on the experiment's families
//! ([`crate::tree::raichel_seshadhri::families`]), one row each: the
//! fastest of `--repeat` uncounted builds of each engine (both measured in
//! the same run, alternately, so the ratio survives a noisy machine), then one counted
//! build of each for the value comparisons, next to n log2 n. With `--csv`
//! the rows also go to a file, for the README's plot
//! (scripts/raichel_seshadhri_plot.py).

use crate::field::ScalarField;
use crate::field::io::{ReadOptions, read_volume};
use crate::progress::Progress;
use crate::tree::ContourTree;
use crate::tree::raichel_seshadhri::{self, count, families};
use anyhow::Context;
use std::io::Write;
use std::path::PathBuf;

/// One row: a field and both engines on it.
struct Row {
    family: &'static str,
    name: String,
    n: usize,
    nodes: usize,
    engine_s: f64,
    rs_s: f64,
    engine_cmp: u64,
    rs: raichel_seshadhri::Comparisons,
    /// Σ log2 ℓ_v over the supernodes (the paper's bound less N).
    shape: f64,
}

/// Nobody cancels a benchmark; a volume too large for memory stops it.
fn never<T>(e: impl std::fmt::Display) -> T {
    panic!("{e}")
}

fn measure(family: &'static str, name: &str, field: &ScalarField, repeat: usize) -> Row {
    // The engines alternate, so that a burst of load on the shared
    // machine hits both; each keeps its fastest run.
    let (mut engine_s, mut rs_s) = (f64::INFINITY, f64::INFINITY);
    let (mut nodes, mut shape) = (0, 0.0);
    for i in 0..repeat.max(1) {
        let (tree, times) = ContourTree::from_field(field, &Progress::new()).unwrap_or_else(never);
        engine_s = engine_s.min(times.total().as_secs_f64());
        if i == 0 {
            (nodes, shape) = (tree.nodes().len(), raichel_seshadhri::shape_term(&tree));
        }
        drop(tree);
        let (_, stats) =
            raichel_seshadhri::from_field(field, false, &Progress::new()).unwrap_or_else(never);
        rs_s = rs_s.min(stats.times.total().as_secs_f64());
    }
    let (_, engine) = count::engine_comparisons(field, &Progress::new()).unwrap_or_else(never);
    let (_, stats) =
        raichel_seshadhri::from_field(field, true, &Progress::new()).unwrap_or_else(never);
    Row {
        family,
        name: name.to_owned(),
        n: field.len(),
        nodes,
        engine_s,
        rs_s,
        engine_cmp: engine.total(),
        rs: stats.comparisons,
        shape,
    }
}

fn print_header() {
    println!(
        "{:<26} {:>10} {:>9} {:>8} {:>8} {:>6} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8} {:>7}",
        "field",
        "vertices",
        "nodes",
        "CSA s",
        "RS s",
        "RS/CSA",
        "nlog2n/n",
        "CSA cmp/n",
        "RS cmp/n",
        "RS tree/n",
        "RS sort/n",
        "Σlogℓ/n",
        "RS<sort"
    );
}

fn print_row(r: &Row) {
    let n = r.n as f64;
    let nlogn = n * n.log2();
    println!(
        "{:<26} {:>10} {:>9} {:>8.3} {:>8.3} {:>6.2} {:>9.2} {:>9.2} {:>9.2} {:>9.2} {:>9.2} {:>8.3} {:>7}",
        r.name,
        r.n,
        r.nodes,
        r.engine_s,
        r.rs_s,
        r.rs_s / r.engine_s,
        n.log2(),
        r.engine_cmp as f64 / n,
        r.rs.total() as f64 / n,
        r.rs.tree() as f64 / n,
        (r.rs.number + r.rs.arc_sort) as f64 / n,
        r.shape / n,
        if (r.rs.total() as f64) < nlogn {
            "yes"
        } else {
            "no"
        },
    );
}

/// What to compare: the shared volumes of `dir` (those whose name
/// contains `only`, if given), each timed `repeat` times.
pub struct Volumes<'a> {
    /// The folder of volumes.
    pub dir: &'a std::path::Path,
    /// Only the volumes whose file name contains one of these.
    pub only: &'a [String],
    /// Runs per volume (the fastest is kept).
    pub repeat: usize,
}

/// Runs the comparison; `sizes` are the families' edge lengths.
pub fn run(args: &Volumes<'_>, sizes: &[usize], csv: Option<&PathBuf>) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    print_header();
    for &s in sizes {
        for (family, field) in [
            ("short-and-fat", families::short_and_fat(s)),
            ("tall-and-thin", families::tall_and_thin(s)),
        ] {
            let r = measure(family, &format!("{family}-{s}"), &field, args.repeat);
            print_row(&r);
            rows.push(r);
        }
    }
    if args.dir.is_dir() {
        let mut inputs: Vec<PathBuf> = std::fs::read_dir(args.dir)
            .with_context(|| format!("{}: cannot list the folder", args.dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "nrrd"))
            .filter(|p| {
                p.file_name()
                    .is_some_and(|n| super::bench::wanted(args.only, &n.to_string_lossy()))
            })
            .collect();
        inputs.sort_by_key(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0));
        for path in inputs {
            let volume = read_volume(&path, &ReadOptions::default())
                .with_context(|| format!("{}", path.display()))?;
            let name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let r = measure("volume", &name, &volume.field, args.repeat);
            print_row(&r);
            rows.push(r);
        }
    }
    if let Some(path) = csv {
        crate::output::write_whole(path, |f| write_csv(f, &rows))
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(())
}

/// The rows as CSV, a header first.
fn write_csv(f: &mut dyn Write, rows: &[Row]) -> std::io::Result<()> {
    writeln!(
        f,
        "family,name,vertices,nodes,csa_s,rs_s,csa_comparisons,rs_links,rs_paint,rs_number,rs_locate,rs_arc_sort,shape_term"
    )?;
    for r in rows {
        writeln!(
            f,
            "{},{},{},{},{:.4},{:.4},{},{},{},{},{},{},{:.1}",
            r.family,
            r.name,
            r.n,
            r.nodes,
            r.engine_s,
            r.rs_s,
            r.engine_cmp,
            r.rs.links,
            r.rs.paint,
            r.rs.number,
            r.rs.locate,
            r.rs.arc_sort,
            r.shape
        )?;
    }
    Ok(())
}
