//! `flexiso bench [DIR]`: the engine on every volume of a folder and on a
//! synthetic noisy 256^3 float field, one table row each: stage times, peak
//! memory and bytes per vertex.
//!
//! Peak memory is the process's peak resident set (VmHWM), reset before each
//! dataset through /proc/self/clear_refs; "engine B/vertex" is that peak
//! minus the resident set once the values are loaded, over the vertex count:
//! what the contour tree costs beyond the input.

use crate::field::ScalarField;
use crate::field::io::{ReadOptions, read_volume};
use crate::field::synthetic::Synthetic;
use crate::progress::Progress;
use crate::tree::ContourTree;
use anyhow::Context;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Arguments of `flexiso bench`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// Folder of volumes (every .nrrd/.nhdr/.raw/... in it).
    #[arg(default_value = "../shared/data")]
    pub dir: PathBuf,
    /// Only datasets whose file name contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Size of the synthetic noisy float field (0 to skip it).
    #[arg(long, default_value_t = 256)]
    pub synthetic: usize,
    /// Repetitions per dataset; the fastest is reported.
    #[arg(long, default_value_t = 1)]
    pub repeat: usize,
}

/// One row of the table.
#[derive(Debug, Clone)]
pub struct Row {
    /// Dataset name.
    pub name: String,
    /// Grid dims.
    pub dims: [usize; 3],
    /// Seconds to read the file.
    pub load: Duration,
    /// Stage times.
    pub times: crate::tree::BuildTimes,
    /// Superarcs of the tree.
    pub superarcs: usize,
    /// Peak resident set during the build, bytes.
    pub peak_rss: u64,
    /// Peak minus resident set with the values loaded, bytes.
    pub engine_bytes: u64,
}

/// Runs `flexiso bench`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut inputs: Vec<PathBuf> = std::fs::read_dir(&args.dir)
        .with_context(|| format!("{}: cannot list the folder", args.dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && is_volume(p))
        .filter(|p| {
            args.only.as_deref().is_none_or(|o| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().contains(o))
            })
        })
        .collect();
    inputs.sort_by_key(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0));
    println!("{}", header());
    for path in inputs {
        let t = Instant::now();
        let volume = read_volume(&path, &ReadOptions::default())
            .with_context(|| format!("{}", path.display()))?;
        let load = t.elapsed();
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let row = bench_field(&name, &volume.field, load, args.repeat.max(1));
        println!("{}", format_row(&row));
    }
    if args.synthetic > 0 && args.only.is_none() {
        let n = args.synthetic;
        let t = Instant::now();
        let field = Synthetic::cube(n).with_noise(0.05, 7).generate();
        let row = bench_field(
            &format!("synthetic-noisy-{n}"),
            &field,
            t.elapsed(),
            args.repeat.max(1),
        );
        println!("{}", format_row(&row));
    }
    Ok(())
}

fn is_volume(p: &std::path::Path) -> bool {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    [
        ".nrrd", ".nhdr", ".raw", ".mha", ".mhd", ".vti", ".vtk", ".nii", ".nii.gz",
    ]
    .iter()
    .any(|e| name.ends_with(e))
}

/// Builds the tree of `field` `repeat` times and keeps the fastest run.
pub fn bench_field(name: &str, field: &ScalarField, load: Duration, repeat: usize) -> Row {
    let mut best: Option<Row> = None;
    for _ in 0..repeat {
        reset_peak_rss();
        let base = current_rss();
        let (tree, times) = match ContourTree::from_field(field, &Progress::new()) {
            Ok(t) => t,
            Err(_) => unreachable!("nobody cancels a benchmark"),
        };
        let peak = peak_rss();
        let row = Row {
            name: name.to_owned(),
            dims: field.dims(),
            load,
            times,
            superarcs: tree.arcs().len(),
            peak_rss: peak,
            engine_bytes: peak.saturating_sub(base),
        };
        drop(tree);
        if best
            .as_ref()
            .is_none_or(|b| row.times.total() < b.times.total())
        {
            best = Some(row);
        }
    }
    best.unwrap_or_else(|| unreachable!("repeat >= 1"))
}

/// The table header.
pub fn header() -> String {
    format!(
        "{:<22} {:>13} {:>9} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>7} {:>7} {:>8} {:>7}",
        "dataset",
        "dims",
        "superarcs",
        "load",
        "sort",
        "join",
        "split",
        "merge",
        "augm",
        "total",
        "s/Mvox",
        "peak MiB",
        "B/vert"
    )
}

/// One table line.
pub fn format_row(r: &Row) -> String {
    let n = (r.dims[0] * r.dims[1] * r.dims[2]) as f64;
    let s = |d: Duration| format!("{:.3}", d.as_secs_f64());
    format!(
        "{:<22} {:>13} {:>9} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>7} {:>7.3} {:>8.0} {:>7.1}",
        r.name,
        format!("{}x{}x{}", r.dims[0], r.dims[1], r.dims[2]),
        r.superarcs,
        s(r.load),
        s(r.times.sort),
        s(r.times.join),
        s(r.times.split),
        s(r.times.merge),
        s(r.times.augment),
        s(r.times.total()),
        r.times.total().as_secs_f64() / (n / 1e6),
        r.peak_rss as f64 / (1 << 20) as f64,
        r.engine_bytes as f64 / n,
    )
}

fn status_kib(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        })
        .unwrap_or(0)
}

/// Peak resident set of this process, bytes (0 where /proc is absent).
pub fn peak_rss() -> u64 {
    status_kib("VmHWM:") * 1024
}

/// Current resident set, bytes.
pub fn current_rss() -> u64 {
    status_kib("VmRSS:") * 1024
}

/// Resets the peak resident set to the current one (Linux >= 4.0).
pub fn reset_peak_rss() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}
