//! `flexiso bench [DIR]`: the engine on every volume of a folder, on the
//! smooth built-in field (`--smooth N`) and on a synthetic noisy 256^3
//! float field, one table row each: stage times, peak
//! memory and bytes per vertex. The join and split sweeps run in parallel,
//! so their columns overlap in the total.
//!
//! Peak memory is the process's peak resident set (VmHWM), reset before each
//! dataset through /proc/self/clear_refs; "engine B/vertex" is that peak
//! minus the resident set once the values are loaded, over the vertex count:
//! what the contour tree costs beyond the input. Before each build the
//! allocator hands its free pages back ([`crate::pages::trim_freed`]): pages
//! an earlier build or repeat freed but kept would be reused unseen and
//! lower the figure by up to 1.5 bytes per vertex (colin27_ch2 read 8.3 or
//! 9.8 by which repeat was fastest), so the figure is close to what a fresh
//! process pays.
//!
//! After the tree come the columns of simplification: arcs left once
//! zero-height arcs are collapsed, seconds to the measures (hypervolume)
//! plus the whole pruning sequence, and the slowest of a series of level
//! changes (full tree, 100 arcs, random levels, back), in milliseconds.
//!
//! `--threads 1,2,4,...` runs every dataset once per thread count, each in
//! a pool of that many threads (the engine picks its blocks for the pool,
//! as it would on a machine with that many cores), adds the CPU time of
//! the process (all threads) and the blocks the sweeps ran in (the
//! engine gives blocks up on a few cores where they do not pay:
//! [`crate::tree::blocks::pay`]) to each row, and ends each dataset with its
//! scaling curve: the speed-up of the total, and of each stage, over the
//! first thread count. That is the curve issue 13 asks for on 16 cores,
//! in one command.

use crate::field::ScalarField;
use crate::field::io::{ReadOptions, read_volume};
use crate::field::synthetic::Synthetic;
use crate::progress::Progress;
use crate::simplify::{CollapsedTree, Measure, Simplification, SimplifiedTree};
use crate::tree::ContourTree;
use anyhow::Context;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Arguments of `flexiso bench`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// Folder of volumes (every .nrrd/.nhdr/.raw/... in it).
    #[arg(default_value = "../shared/data")]
    pub dir: PathBuf,
    /// Only datasets whose name contains one of these (comma-separated;
    /// the built-in fields are `synthetic-N` and `synthetic-noisy-N`).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Size of the synthetic noisy float field (0 to skip it).
    #[arg(long, default_value_t = 256)]
    pub synthetic: usize,
    /// Size of the smooth built-in field (`synthetic:N`, Gaussian blobs:
    /// long superarcs) to bench too (0 to skip it).
    #[arg(long, default_value_t = 0)]
    pub smooth: usize,
    /// Repetitions per dataset; the fastest is reported.
    #[arg(long, default_value_t = 1)]
    pub repeat: usize,
    /// `raichel-seshadhri`: compare the two engines instead (times and
    /// value comparisons, on the experiment's families and the volumes).
    #[arg(long, value_enum, default_value_t = super::tree::Algorithm::CarrSnoeyinkAxen)]
    pub algorithm: super::tree::Algorithm,
    /// Thread counts to run each dataset with, e.g. `1,2,4,8,16`: one row
    /// per count and the scaling curve (speed-up over the first count).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Vec<u16>,
    /// Edge lengths of the experiment's families (with --algorithm).
    #[arg(long, value_delimiter = ',', default_value = "32,64,128")]
    pub families: Vec<usize>,
    /// Also write the comparison's rows to this CSV file (with --algorithm).
    #[arg(long, value_name = "PATH")]
    pub csv: Option<PathBuf>,
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
    /// Arcs after collapsing zero-height arcs.
    pub collapsed: usize,
    /// Seconds to collapse, measure and compute the pruning sequence.
    pub simplification: Duration,
    /// Slowest single level change.
    pub level_change: Duration,
    /// Threads of the pool it ran in.
    pub threads: usize,
    /// CPU time of the whole process (every thread) during the build and
    /// the simplification.
    pub cpu: Duration,
}

/// Runs `flexiso bench`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if args.algorithm == super::tree::Algorithm::RaichelSeshadhri {
        let volumes = super::bench_engines::Volumes {
            dir: &args.dir,
            only: &args.only,
            repeat: args.repeat,
        };
        return super::bench_engines::run(&volumes, &args.families, args.csv.as_ref());
    }
    let mut inputs: Vec<PathBuf> = std::fs::read_dir(&args.dir)
        .with_context(|| format!("{}: cannot list the folder", args.dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && is_volume(p))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| wanted(&args.only, &n.to_string_lossy()))
        })
        .collect();
    inputs.sort_by_key(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0));
    let pools = pools(&args.threads)?;
    println!("{}", header(!pools.is_empty()));
    for path in inputs {
        let t = Instant::now();
        let volume = read_volume(&path, &ReadOptions::default())
            .with_context(|| format!("{}", path.display()))?;
        let load = t.elapsed();
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        bench_in_pools(&name, &volume.field, load, args.repeat, &pools);
    }
    let synthetic = [
        (args.smooth, "synthetic", None),
        (args.synthetic, "synthetic-noisy", Some((0.05, 7))),
    ];
    for (n, name, noise) in synthetic {
        let name = format!("{name}-{n}");
        if n == 0 || !wanted(&args.only, &name) {
            continue;
        }
        let t = Instant::now();
        let field = match noise {
            Some((amount, seed)) => Synthetic::cube(n).with_noise(amount, seed),
            None => Synthetic::cube(n),
        }
        .generate();
        bench_in_pools(&name, &field, t.elapsed(), args.repeat, &pools);
    }
    Ok(())
}

/// True if a dataset of this name is benched: no `--only`, or one of its
/// patterns in the name.
pub(super) fn wanted(only: &[String], name: &str) -> bool {
    only.is_empty() || only.iter().any(|o| name.contains(o.as_str()))
}

/// A thread pool per `--threads` count, fewest threads first (none: the
/// global pool).
fn pools(threads: &[u16]) -> anyhow::Result<Vec<rayon::ThreadPool>> {
    let mut threads = threads.to_vec();
    threads.sort_unstable();
    threads.dedup();
    threads
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t.into())
                .build()
                .with_context(|| format!("cannot start a pool of {t} threads"))
        })
        .collect()
}

/// One row per pool (or one in the global pool), then the scaling curve.
/// Each row is the fastest of `repeat` builds, as without pools.
fn bench_in_pools(
    name: &str,
    field: &ScalarField,
    load: Duration,
    repeat: usize,
    pools: &[rayon::ThreadPool],
) {
    if pools.is_empty() {
        println!(
            "{}",
            format_row(&bench_field(name, field, load, repeat.max(1)), false)
        );
        return;
    }
    // A first build untimed, so that the first count's row does not pay
    // alone for the memory the process takes from the system.
    let _ = bench_field(name, field, load, 1);
    let rows: Vec<Row> = pools
        .iter()
        .map(|pool| {
            let row = pool.install(|| bench_field(name, field, load, repeat.max(1)));
            println!("{}", format_row(&row, true));
            row
        })
        .collect();
    println!("{}", scaling(&rows));
}

/// The speed-up of each row over the first, total and per stage: one line
/// per dataset, e.g. `  scaling of tooth over 1 thread: 2 threads 1.92x (sort
/// 1.97, links 1.99, ...)`.
pub fn scaling(rows: &[Row]) -> String {
    let Some(first) = rows.first() else {
        return String::new();
    };
    let stages = |r: &Row| {
        let t = &r.times;
        [
            ("sort", t.sort),
            ("links", t.links),
            ("sweeps", t.sweeps.saturating_sub(t.links)),
            ("merge", t.merge),
            ("augm", t.augment),
            ("simp", r.simplification),
        ]
    };
    let ratio = |a: Duration, b: Duration| a.as_secs_f64() / b.as_secs_f64().max(1e-9);
    let mut out = format!(
        "  scaling of {} over {} thread{}:",
        first.name,
        first.threads,
        if first.threads == 1 { "" } else { "s" }
    );
    for r in &rows[1..] {
        let parts: Vec<String> = stages(first)
            .iter()
            .zip(stages(r))
            .map(|((stage, a), (_, b))| format!("{stage} {:.2}", ratio(*a, b)))
            .collect();
        out += &format!(
            "\n    {:>3} threads: total {:.2}x ({}), CPU {:.2}x",
            r.threads,
            ratio(first.times.total(), r.times.total()),
            parts.join(", "),
            ratio(r.cpu, first.cpu),
        );
    }
    out
}

/// CPU time of this process so far, every thread (zero where unknown).
pub fn process_cpu() -> Duration {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: getrusage writes the struct it is given.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } == 0 {
            let t = |tv: libc::timeval| {
                Duration::from_secs(tv.tv_sec as u64) + Duration::from_micros(tv.tv_usec as u64)
            };
            return t(usage.ru_utime) + t(usage.ru_stime);
        }
    }
    Duration::ZERO
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
        crate::pages::trim_freed();
        reset_peak_rss();
        let base = current_rss();
        let cpu = process_cpu();
        let (tree, times) = match ContourTree::from_field(field, &Progress::new()) {
            Ok(t) => t,
            // Nobody cancels a benchmark; a volume too large stops it.
            Err(e) => panic!("{name}: {e}"),
        };
        let peak = peak_rss();
        let (collapsed, simplification, level_change) = simplification_times(&tree, field);
        let cpu = process_cpu().saturating_sub(cpu);
        let row = Row {
            name: name.to_owned(),
            dims: field.dims(),
            load,
            times,
            superarcs: tree.arcs().len(),
            peak_rss: peak,
            engine_bytes: peak.saturating_sub(base),
            collapsed,
            simplification,
            level_change,
            threads: rayon::current_num_threads(),
            cpu,
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

/// Collapse, measures and pruning sequence (hypervolume), then the slowest
/// of a series of level changes: what a user feels when moving the slider.
fn simplification_times(tree: &ContourTree, field: &ScalarField) -> (usize, Duration, Duration) {
    let t = Instant::now();
    let collapsed = CollapsedTree::new(tree, field);
    let sim = Simplification::from_collapsed(&collapsed, Measure::Hypervolume);
    let sequence = t.elapsed();
    let arcs = collapsed.num_arcs();
    drop(collapsed);
    let mut level = SimplifiedTree::new(Arc::new(sim));
    // A fixed pseudo-random walk over levels, always through the extremes.
    let mut targets = vec![arcs, 100, arcs, 1, 100];
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    for _ in 0..20 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        targets.push(1 + (x % arcs.max(1) as u64) as usize);
    }
    targets.push(arcs);
    let mut slowest = Duration::ZERO;
    for n in targets {
        let t = Instant::now();
        level.set_level(n);
        slowest = slowest.max(t.elapsed());
    }
    (arcs, sequence, slowest)
}

/// The table header; `threads`: with the columns of `--threads`.
pub fn header(threads: bool) -> String {
    let head = format!(
        "{:<22} {:>13} {:>9} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>7} {:>7} {:>8} {:>7} {:>9} {:>6} {:>8}",
        "dataset",
        "dims",
        "superarcs",
        "load",
        "sort",
        "links",
        "join",
        "split",
        "merge",
        "augm",
        "total",
        "s/Mvox",
        "peak MiB",
        "B/vert",
        "collapsed",
        "simp",
        "level ms"
    );
    if threads {
        format!("{head} {:>7} {:>7} {:>6}", "threads", "CPU s", "blocks")
    } else {
        head
    }
}

/// One table line; `threads`: with the columns of `--threads`.
pub fn format_row(r: &Row, threads: bool) -> String {
    let n = (r.dims[0] * r.dims[1] * r.dims[2]) as f64;
    let s = |d: Duration| format!("{:.3}", d.as_secs_f64());
    let row = format!(
        "{:<22} {:>13} {:>9} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>7} {:>7.3} {:>8.0} {:>7.1} {:>9} {:>6} {:>8.3}",
        r.name,
        format!("{}x{}x{}", r.dims[0], r.dims[1], r.dims[2]),
        r.superarcs,
        s(r.load),
        s(r.times.sort),
        s(r.times.links),
        s(r.times.join),
        s(r.times.split),
        s(r.times.merge),
        s(r.times.augment),
        s(r.times.total()),
        r.times.total().as_secs_f64() / (n / 1e6),
        r.peak_rss as f64 / (1 << 20) as f64,
        r.engine_bytes as f64 / n,
        r.collapsed,
        s(r.simplification),
        r.level_change.as_secs_f64() * 1e3,
    );
    if threads {
        format!(
            "{row} {:>7} {:>7.2} {:>6}",
            r.threads,
            r.cpu.as_secs_f64(),
            r.times.blocks
        )
    } else {
        row
    }
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
