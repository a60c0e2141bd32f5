//! Criterion benches of contour extraction, what a user feels when
//! dragging an isovalue: microseconds to a path seed, triangles per second
//! to follow one contour (single-threaded), seconds to the whole
//! isosurface at one value (every contour: one parallel sweep; following
//! every seed for comparison). Run on the two MRI templates of the shared
//! data folder, on the largest contour among a few isovalues, or on a
//! synthetic cube without them.
//!
//! `cargo bench --bench contour` (set `FLEXISO_BENCH_VOLUMES=colin27_ch2`
//! to bench only some of them). Before criterion's statistics it prints
//! the best of several runs of each, which on a loaded machine is the
//! fairer number; `FLEXISO_BENCH_QUICK=1` prints only that.

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{Criterion, Throughput, criterion_group};
use flexiso::contour::oracle::all_contours_by_following;
use flexiso::contour::{ContourFollower, PathSeed, PathSeeds, all_contours, global::spanning_arcs};
use flexiso::field::io::{ReadOptions, read_volume};
use flexiso::field::synthetic::Synthetic;
use flexiso::field::{Isovalue, ScalarField};
use flexiso::progress::Progress;
use flexiso::tree::ContourTree;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

fn volumes() -> Vec<(String, ScalarField)> {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    let wanted = std::env::var("FLEXISO_BENCH_VOLUMES")
        .unwrap_or_else(|_| "colin27_ch2,colin27_ch2better".to_owned());
    let mut out = Vec::new();
    for name in wanted.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if let Ok(v) = read_volume(&data.join(format!("{name}.nrrd")), &ReadOptions::default()) {
            out.push((name.to_owned(), v.field));
        }
    }
    if out.is_empty() {
        out.push(("synthetic-128".to_owned(), Synthetic::cube(128).generate()));
    }
    out
}

/// The isovalue (among a few across the range) with the largest single
/// contour, and that contour's seed and size.
fn largest_contour(tree: &ContourTree, field: &ScalarField) -> (Isovalue, PathSeed, usize) {
    let (lo, hi) = field.range();
    let mut best: Option<(Isovalue, PathSeed, usize)> = None;
    let seeds = PathSeeds::new();
    for k in 1..=6 {
        let iso = Isovalue::new((lo + (hi - lo) * k as f64 / 8.0).round());
        for c in all_contours(tree, field, iso) {
            if best.as_ref().is_none_or(|b| c.num_triangles() > b.2) {
                let seed = seeds.seed(tree, field, c.arc, iso).expect("spans");
                best = Some((iso, seed, c.num_triangles()));
            }
        }
    }
    best.expect("some contour")
}

fn contour(c: &mut Criterion) {
    for (name, field) in volumes() {
        let t = Instant::now();
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
        let (iso, seed, triangles) = largest_contour(&tree, &field);
        let spanning = spanning_arcs(&tree, &field, iso);
        eprintln!(
            "{name}: {} vertices, {} superarcs; largest contour at h = {}: {triangles} \
             triangles; {} contours there (setup {:.1} s)",
            field.len(),
            tree.arcs().len(),
            iso.value,
            spanning.len(),
            t.elapsed().as_secs_f64()
        );
        let mut g = c.benchmark_group(&name);
        g.sample_size(10);
        g.throughput(Throughput::Elements(spanning.len() as u64));
        g.bench_function("path seeds of every contour at h", |b| {
            let seeds = PathSeeds::new();
            b.iter(|| {
                for &a in &spanning {
                    black_box(seeds.seed(&tree, &field, a, iso));
                }
            })
        });
        g.throughput(Throughput::Elements(triangles as u64));
        g.bench_function("follow the largest contour (triangles, one thread)", |b| {
            let mut follower = ContourFollower::new(&field);
            b.iter(|| black_box(follower.follow(&seed, iso)))
        });
        g.bench_function("all contours at h (triangles of the largest)", |b| {
            b.iter(|| black_box(all_contours(&tree, &field, iso)))
        });
        g.finish();
    }
}

/// Best wall time of `runs` calls of `f`, seconds.
fn best_of(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Nanoseconds this thread has run on a CPU (Linux schedstat), if known:
/// on a loaded machine, the time the work itself took.
fn thread_cpu_ns() -> Option<u64> {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// The best-of-N printout.
fn quick() {
    for (name, field) in volumes() {
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
        let (iso, seed, triangles) = largest_contour(&tree, &field);
        let spanning = spanning_arcs(&tree, &field, iso);
        let seeds = PathSeeds::new();
        let t_seed = best_of(20, || {
            for &a in &spanning {
                black_box(seeds.seed(&tree, &field, a, iso));
            }
        }) / spanning.len().max(1) as f64;
        let mut follower = ContourFollower::new(&field);
        let mut cpu = f64::INFINITY;
        let t_follow = best_of(7, || {
            let c = thread_cpu_ns();
            black_box(follower.follow(&seed, iso));
            if let (Some(a), Some(b)) = (c, thread_cpu_ns()) {
                cpu = cpu.min((b - a) as f64 * 1e-9);
            }
        });
        let t_all = best_of(7, || {
            black_box(all_contours(&tree, &field, iso));
        });
        let t_followed = best_of(3, || {
            black_box(all_contours_by_following(&tree, &field, iso));
        });
        println!(
            "{name} h = {}: seed {:.2} us; largest contour {triangles} triangles in {:.3} s \
             ({:.2} M triangles/s, one thread; on the CPU {:.3} s, {:.2} M/s); \
             all {} contours in {:.3} s ({} threads; {:.3} s following each seed)",
            iso.value,
            t_seed * 1e6,
            t_follow,
            triangles as f64 / t_follow / 1e6,
            cpu,
            triangles as f64 / cpu / 1e6,
            spanning.len(),
            t_all,
            rayon::current_num_threads(),
            t_followed
        );
        drag_latency(&name, &tree, &field);
    }
}

/// What dragging a contour's isovalue costs before the new mesh can be
/// drawn: a contour of about 200k triangles (the largest spanning arc at
/// the first isovalue, from the top, that has one of 150k to 250k) moved by
/// steps down its arc: path seed, following, and the upload to the GPU
/// (headless wgpu, software Vulkan here), then one 1280×800 render.
fn drag_latency(name: &str, tree: &ContourTree, field: &ScalarField) {
    let (lo, hi) = field.range();
    let seeds = PathSeeds::new();
    let mut follower = ContourFollower::new(field);
    let mut found = None;
    'search: for k in (1..64).rev() {
        let iso = Isovalue::new((lo + (hi - lo) * k as f64 / 64.0).round());
        for arc in spanning_arcs(tree, field, iso) {
            let Some(seed) = seeds.seed(tree, field, arc, iso) else {
                continue;
            };
            let n = follower.follow(&seed, iso).num_triangles();
            if (150_000..=250_000).contains(&n) {
                found = Some((arc, iso.value));
                break 'search;
            }
        }
    }
    let Some((arc, h)) = found else {
        println!("{name}: no contour of 150k-250k triangles at the isovalues tried");
        return;
    };
    let gpu = flexiso::render::headless::Gpu::new().ok();
    let mut renderer = gpu.as_ref().map(|g| g.renderer());
    let mut worst = (0f64, 0f64, 0f64, 0usize);
    // Five drag steps down the arc, towards its lower end.
    let bottom = field.value(tree.node(tree.arc(arc).lower).vertex);
    for step in 0..5 {
        let iso = Isovalue::new(h - (h - bottom) * step as f64 / 6.0);
        let t = Instant::now();
        let Some(seed) = seeds.seed(tree, field, arc, iso) else {
            break;
        };
        let mesh = follower.follow(&seed, iso);
        // As the explorer's worker does: the mesh is made ready for the
        // GPU on the extracting thread, the UI thread only copies it.
        let prepared =
            flexiso::render::PreparedMesh::new(&mesh.positions, &mesh.normals, &mesh.indices)
                .expect("a contour is a valid mesh");
        let extract = t.elapsed().as_secs_f64() * 1e3;
        let (mut upload, mut render) = (0.0, 0.0);
        if let (Some(g), Some(r)) = (&gpu, &mut renderer) {
            let t = Instant::now();
            r.set_prepared_mesh(&g.device, 1, std::sync::Arc::new(prepared))
                .expect("upload");
            assert!(
                !r.upload_pending(
                    &g.device,
                    &g.queue,
                    flexiso::app::panels::view3d::UPLOAD_BUDGET
                ),
                "one frame's budget"
            );
            let _ = g.device.poll(wgpu::PollType::wait_indefinitely());
            upload = t.elapsed().as_secs_f64() * 1e3;
            let mut camera = flexiso::render::Camera::default();
            if let Some((a, b)) = r.visible_bounds() {
                camera.fit(a, b);
            }
            let t = Instant::now();
            r.render(&g.device, &g.queue, &camera, 1280, 800);
            let _ = g.device.poll(wgpu::PollType::wait_indefinitely());
            render = t.elapsed().as_secs_f64() * 1e3;
        }
        if extract + upload > worst.0 + worst.1 {
            worst = (extract, upload, render, mesh.num_triangles());
        }
    }
    println!(
        "{name}: dragging a contour of {} triangles (arc {:?}, from h = {h} down its arc): \
         worst step extraction (and preparation) {:.1} ms + upload {:.1} ms = {:.1} ms; its render {:.1} ms ({})",
        worst.3,
        arc,
        worst.0,
        worst.1,
        worst.0 + worst.1,
        worst.2,
        gpu.as_ref()
            .map_or("no GPU adapter".into(), |g| g.describe())
    );
}

criterion_group!(benches, contour);

fn main() {
    quick();
    if std::env::var("FLEXISO_BENCH_QUICK").as_deref() == Ok("1") {
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
