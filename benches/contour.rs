//! Criterion benches of contour extraction, what a user feels when
//! dragging an isovalue: microseconds to a path seed, triangles per second
//! to follow one contour (single-threaded), seconds to the whole
//! isosurface at one value (every contour: one parallel sweep; following
//! every seed for comparison). Run on the two MRI templates of the shared
//! data folder, on the largest contour among a few isovalues, or on a
//! synthetic cube without them. The quick printout also times the largest
//! contour's cross-sections on the middle slices (what the explorer's
//! slice panel cuts in its job when a slice moves).
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
use flexiso::render::PreparedMesh;
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
        if std::env::var("FLEXISO_BENCH_DRAG").as_deref() == Ok("1") {
            // Only the scripted drags (for profiling).
            // Upwards: the head's outer surface shrinks towards the skull.
            scripted_drag(&name, &tree, &field, iso, seed.arc, 1.0, 20);
            drag_latency(&name, &tree, &field, 250_000..=500_000);
            drag_latency(&name, &tree, &field, 500_000..=1_000_000);
            continue;
        }
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
        section_times(&name, &field, &seed, iso);
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
        serial_vs_parallel(&name, &tree, &field, iso, &seed);
        scripted_drag(&name, &tree, &field, iso, seed.arc, 1.0, 20);
        drag_while_measuring(&name, &tree, &field, iso, &seed);
        drag_latency(&name, &tree, &field, 150_000..=250_000);
        drag_latency(&name, &tree, &field, 500_000..=1_000_000);
    }
}

/// A drag step that resumes while the explorer measures the contour's last
/// mesh (it does so once a drag pauses: [`MeshTopology::measure`] on
/// another thread): new isovalue to mesh ready for upload with the
/// measurement left to run, as before, and cancelled by the new request,
/// as the explorer now does. Median of 3 each, alternated.
fn drag_while_measuring(
    name: &str,
    tree: &ContourTree,
    field: &ScalarField,
    iso: Isovalue,
    seed: &PathSeed,
) {
    use flexiso::contour::MeshTopology;
    use std::sync::atomic::{AtomicBool, Ordering};
    let mut follower = ContourFollower::new(field);
    let last = follower
        .extract_expecting(tree, seed, iso, None, &|| false)
        .expect("not cancelled");
    let triangles = last.num_triangles();
    let (mut left, mut cancelled, mut measuring) = (vec![], vec![], vec![]);
    for round in 0..6 {
        let cancel = round % 2 == 1;
        let stop = AtomicBool::new(false);
        std::thread::scope(|scope| {
            let measurement = scope.spawn(|| {
                let t = Instant::now();
                let done = MeshTopology::measure(&last.positions, &last.indices, &|| {
                    stop.load(Ordering::Relaxed)
                })
                .is_ok();
                (done, t.elapsed().as_secs_f64() * 1e3)
            });
            // The mouse moves on a moment after the measurement began.
            std::thread::sleep(std::time::Duration::from_millis(30));
            let t = Instant::now();
            if cancel {
                stop.store(true, Ordering::Relaxed);
            }
            let m = follower
                .extract_expecting(tree, seed, iso, Some(triangles), &|| false)
                .expect("not cancelled");
            black_box(prepare(&m));
            let step = t.elapsed().as_secs_f64() * 1e3;
            let (done, ms) = measurement.join().expect("measured");
            if cancel {
                cancelled.push(step);
            } else {
                assert!(done, "a measurement left to run finishes");
                left.push(step);
                measuring.push(ms);
            }
        });
    }
    let ((l, _), (c, _), (mm, _)) = (stats(&left), stats(&cancelled), stats(&measuring));
    println!(
        "{name} h = {}: a drag step of the largest contour ({triangles} triangles) resumed while \
         its last mesh is measured ({mm:.0} ms): {l:.0} ms with the measurement left to run, \
         {c:.0} ms with it cancelled by the new request (as the explorer does)",
        iso.value,
    );
}

/// The largest contour's cross-sections on the middle slice of each axis
/// (what the explorer's slice panel cuts when a slice moves): best of 5,
/// on every core (`axis_section` goes parallel for big meshes).
fn section_times(name: &str, field: &ScalarField, seed: &PathSeed, iso: Isovalue) {
    let mesh = ContourFollower::new(field).follow(seed, iso);
    let dims = field.dims();
    let spacing = field.spacing();
    let ms: Vec<f64> = (0..3)
        .map(|a| {
            let at = ((dims[a] / 2) as f64 * spacing[a]) as f32;
            1e3 * best_of(5, || {
                black_box(flexiso::contour::section::axis_section(
                    &mesh.positions,
                    &mesh.indices,
                    a,
                    at,
                ));
            })
        })
        .collect();
    println!(
        "{name} h = {}: cross-sections of the largest contour ({} triangles) on the middle \
         slices: x {:.1} ms, y {:.1} ms, z {:.1} ms ({} threads)",
        iso.value,
        mesh.indices.len() / 3,
        ms[0],
        ms[1],
        ms[2],
        rayon::current_num_threads()
    );
}

/// CPU seconds of the whole process so far (every thread), if known: on a
/// shared machine, what the parallel work itself cost.
fn process_cpu() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i)?.parse::<f64>().ok();
    // utime and stime, fields 14 and 15 (11 and 12 after the name).
    Some((ticks(11)? + ticks(12)?) / 100.0)
}

/// The mesh made ready for the GPU, as the explorer's worker does.
fn prepare(mesh: &flexiso::contour::ContourMesh) -> flexiso::render::PreparedMesh {
    let (p, n, i) = (&mesh.positions, &mesh.normals, &mesh.indices);
    flexiso::render::PreparedMesh::new_known(p, n, i, mesh.into(), Default::default())
        .expect("a contour is a valid mesh")
}

/// The largest contour followed on one thread and extracted on every core
/// (in the same run: the machine is shared), and the time from the new
/// isovalue to the mesh ready for upload (seed, extraction, preparation).
fn serial_vs_parallel(
    name: &str,
    tree: &ContourTree,
    field: &ScalarField,
    iso: Isovalue,
    seed: &PathSeed,
) {
    let seeds = PathSeeds::new();
    let mut serial = ContourFollower::new(field);
    let mut parallel = ContourFollower::new(field);
    let mut triangles = 0;
    let t_serial = best_of(5, || {
        triangles = black_box(serial.follow(seed, iso)).num_triangles();
    });
    let cpu0 = process_cpu();
    let t_parallel = best_of(5, || {
        black_box(
            parallel
                .extract(tree, seed, iso, &|| false)
                .expect("not cancelled"),
        );
    });
    let cpu_parallel = cpu0
        .zip(process_cpu())
        .map_or(f64::NAN, |(a, b)| (b - a) / 5.0);
    let cpu0 = process_cpu();
    let m = parallel
        .extract(tree, seed, iso, &|| false)
        .expect("not cancelled");
    let cpu1 = process_cpu();
    for _ in 0..4 {
        black_box(prepare(&m));
    }
    let cpu_prepare = cpu1
        .zip(process_cpu())
        .map_or(f64::NAN, |(a, b)| (b - a) / 4.0);
    let _ = cpu0;
    let p = prepare(&m);
    let draws = match p.corners() {
        flexiso::render::geometry::Corners::Short { runs, .. } => runs.len(),
        flexiso::render::geometry::Corners::Long(_) => 1,
    };
    println!(
        "{name} h = {}: the largest contour on the GPU: {:.1} MB ({} vertices, {} draws of \
         16-bit index runs; {:.1} MB as 24-byte vertices and 32-bit indices)",
        iso.value,
        p.gpu_bytes() as f64 / 1e6,
        p.num_vertices(),
        draws,
        (24 * m.positions.len() + 4 * m.indices.len()) as f64 / 1e6,
    );
    // New isovalue to mesh ready for upload (best of 5) and the preparation
    // alone: with its size unknown (a first click: the flood tried first up
    // to the serial limit) or known (as in a drag, straight to the sweep).
    let mut ready = |expected: Option<usize>| {
        let mut t_prepare = f64::INFINITY;
        let t_ready = best_of(5, || {
            let s = seeds.seed(tree, field, seed.arc, iso).expect("spans");
            let m = parallel
                .extract_expecting(tree, &s, iso, expected, &|| false)
                .expect("not cancelled");
            let t = Instant::now();
            black_box(prepare(&m));
            t_prepare = t_prepare.min(t.elapsed().as_secs_f64());
        });
        (t_ready, t_prepare)
    };
    let (t_ready, t_prepare) = ready(None);
    let (t_ready_known, t_prepare_known) = ready(Some(triangles));
    println!(
        "{name} h = {}: the largest contour ({triangles} triangles), new isovalue to mesh \
         ready for upload with its size known (as in a drag): {:.0} ms (of which preparing it \
         {:.0} ms)",
        iso.value,
        t_ready_known * 1e3,
        t_prepare_known * 1e3,
    );
    println!(
        "{name} h = {}: the largest contour ({triangles} triangles): following it {:.0} ms \
         (one thread), extracting it {:.0} ms ({} threads, {:.1}x); new isovalue to mesh \
         ready for upload, its size unknown, {:.0} ms (of which preparing it {:.0} ms); CPU \
         time (all threads) of one extraction {:.0} ms, of one preparation {:.0} ms",
        iso.value,
        t_serial * 1e3,
        t_parallel * 1e3,
        rayon::current_num_threads(),
        t_serial / t_parallel,
        t_ready * 1e3,
        t_prepare * 1e3,
        cpu_parallel * 1e3,
        cpu_prepare * 1e3,
    );
}

/// A scripted drag of `steps` steps of one value unit along `arc` from
/// `iso` (towards the arc's farther end, turning back at its chain's
/// end): per step, the new isovalue to the mesh ready for upload, by the
/// serial follower and by the parallel extraction, and with a GPU the
/// frames the upload takes within the
/// explorer's per-frame budget.
fn scripted_drag(
    name: &str,
    tree: &ContourTree,
    field: &ScalarField,
    iso: Isovalue,
    arc: flexiso::tree::ArcId,
    dir: f64,
    steps: usize,
) {
    // The marker moves along the arc's chain at a simplification level of
    // 100 arcs (by volume), as in the explorer: past the tree's many small
    // nodes the contour stays the same structure's.
    let start = arc;
    let chain = chain_at_100_arcs(tree, field, arc);
    let gpu = flexiso::render::headless::Gpu::new().ok();
    let mut renderer = gpu.as_ref().map(|g| g.renderer());
    let budget = flexiso::app::panels::view3d::UPLOAD_BUDGET;
    let mut serial = ContourFollower::new(field);
    let mut parallel = ContourFollower::new(field);
    let (mut ser, mut par, mut frames, mut upload) = (vec![], vec![], vec![], vec![]);
    let mut sizes = (usize::MAX, 0);
    let mut last = None;
    let mut old_meshes = std::collections::VecDeque::new();
    let mut old_gpu = std::collections::VecDeque::new();
    // The click that showed the contour, its size unknown (in the
    // explorer a drag starts from a contour on screen, its size known),
    // and the spare mesh and GPU form the explorer makes after it, while
    // the hand has not moved yet, for the first step to write into.
    let t = Instant::now();
    let mut first_gpu = None;
    let click = flexiso::contour::path_seed_in_chain(tree, field, &chain, iso).map(|seed| {
        let m = parallel
            .extract_expecting(tree, &seed, iso, None, &|| false)
            .expect("not cancelled");
        old_gpu.push_back(std::sync::Arc::new(prepare(&m)));
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let (v, n) = (m.positions.len(), m.num_triangles());
        parallel.recycle(flexiso::contour::ContourMesh::spare(m.arc, v, n));
        first_gpu = Some(flexiso::render::PreparedMesh::spare(v, n));
        last = Some(n);
        old_meshes.push_back(m);
        ms
    });
    // At an end of the chain the drag turns back, as a hand does.
    let (mut at, mut way, mut turns) = (iso.value, dir, 0);
    for _ in 1..=steps {
        let mut found = None;
        for _ in 0..2 {
            let iso = Isovalue::new(at + way);
            found = flexiso::contour::path_seed_in_chain(tree, field, &chain, iso);
            if found.is_some() {
                break;
            }
            way = -way;
            turns += 1;
        }
        let Some(seed) = found else {
            break;
        };
        at += way;
        let iso = Isovalue::new(at);
        let arc = seed.arc;
        let t = Instant::now();
        let m = serial.follow(&seed, iso);
        black_box(prepare(&m));
        ser.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        let seed = flexiso::contour::path_seed_in_chain(tree, field, &chain, iso).expect("spans");
        debug_assert_eq!(seed.arc, arc);
        // As the explorer's worker: the last step's size as the hint, the
        // mesh and GPU form of two steps before recycled (the window holds
        // the last one).
        if old_meshes.len() == 2
            && let Some(spare) = old_meshes.pop_front()
        {
            parallel.recycle(spare);
        }
        let m = parallel
            .extract_expecting(tree, &seed, iso, last, &|| false)
            .expect("not cancelled");
        last = Some(m.num_triangles());
        let spare_gpu = (old_gpu.len() == 2)
            .then(|| old_gpu.pop_front())
            .flatten()
            .and_then(|g| std::sync::Arc::try_unwrap(g).ok())
            .or_else(|| first_gpu.take())
            .unwrap_or_default();
        let (p, n, i) = (&m.positions, &m.normals, &m.indices);
        let prepared = std::sync::Arc::new(
            flexiso::render::PreparedMesh::new_known(p, n, i, (&m).into(), spare_gpu)
                .expect("a contour is a valid mesh"),
        );
        par.push(t.elapsed().as_secs_f64() * 1e3);
        old_gpu.push_back(std::sync::Arc::clone(&prepared));
        sizes = (
            sizes.0.min(m.num_triangles()),
            sizes.1.max(m.num_triangles()),
        );
        if let (Some(g), Some(r)) = (&gpu, &mut renderer) {
            r.set_prepared_mesh(&g.device, 1, prepared).expect("upload");
            let mut n = 0;
            let mut slowest = 0f64;
            loop {
                let t = Instant::now();
                let more = r.upload_pending(&g.device, &g.queue, budget);
                let _ = g.device.poll(wgpu::PollType::wait_indefinitely());
                slowest = slowest.max(t.elapsed().as_secs_f64() * 1e3);
                n += 1;
                if !more {
                    break;
                }
            }
            frames.push(n as f64);
            upload.push(slowest);
        }
        old_meshes.push_back(m);
    }
    incremental_drag(name, tree, field, &chain, iso, dir, steps);
    println!(
        "{name}: scripted drag, parallel steps in ms: {}",
        par.iter()
            .map(|t| format!("{t:.0}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let ((sm, sw), (pm, pw)) = (stats(&ser), stats(&par));
    let ((fm, fw), (um, uw)) = (stats(&frames), stats(&upload));
    println!(
        "{name}: scripted drag of {} steps of {dir:+} from h = {} from arc {start:?} \
         ({turns} turns at the chain's ends; {}..{} triangles): the click before it (size \
         unknown) {:.0} ms; new isovalue to mesh ready for upload, median / worst step: \
         serial {sm:.0} / {sw:.0} ms, parallel {pm:.0} / {pw:.0} ms; upload in {fm} / {fw} \
         frames of at most {} MiB, slowest frame's copy {um:.1} / {uw:.1} ms",
        par.len(),
        iso.value,
        sizes.0,
        sizes.1,
        click.unwrap_or(f64::NAN),
        budget >> 20,
    );
}

/// The chain of superarcs that `arc` belongs to at the simplification
/// level of 100 arcs (by volume), as the explorer's marker moves along it.
fn chain_at_100_arcs(
    tree: &ContourTree,
    field: &ScalarField,
    arc: flexiso::tree::ArcId,
) -> Vec<flexiso::tree::ArcId> {
    let sim = std::sync::Arc::new(flexiso::simplify::Simplification::new(
        tree,
        field,
        flexiso::simplify::Measure::Volume,
    ));
    let mut level = flexiso::simplify::SimplifiedTree::new(sim);
    level.set_level(100);
    match level.live_arc_of(arc) {
        Some(a) => level.arc(a).chain.to_vec(),
        None => vec![arc],
    }
}

/// Median and largest of `v` (NaN when empty).
fn stats(v: &[f64]) -> (f64, f64) {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    (
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN),
        v.last().copied().unwrap_or(f64::NAN),
    )
}

/// A drag of `steps` steps of `delta` along `chain` from `iso` by
/// [`DraggedContour`], turning back at the chain's ends: each step from
/// the last mesh, at the cost of the change, written into the arrays of
/// the mesh two steps before as the explorer does. Prints the cost of starting (following the contour once and
/// keeping it) and, per step, new isovalue to mesh ready for upload
/// (step and preparation), median and worst; checks each mesh's size
/// against the parallel extraction's.
fn incremental_drag(
    name: &str,
    tree: &ContourTree,
    field: &ScalarField,
    chain: &[flexiso::tree::ArcId],
    iso: Isovalue,
    delta: f64,
    steps: usize,
) {
    use flexiso::contour::DraggedContour;
    use flexiso::contour::drag::step_budget;
    let Some(seed) = flexiso::contour::path_seed_in_chain(tree, field, chain, iso) else {
        return;
    };
    let shared = std::sync::Arc::new(field.clone());
    let t = Instant::now();
    let Some((mut dragged, first)) =
        DraggedContour::start(&shared, &seed, iso, &|| false).expect("not cancelled")
    else {
        return;
    };
    let start = t.elapsed().as_secs_f64() * 1e3;
    let mut check = ContourFollower::new(field);
    let (mut times, mut step_only, mut refused) = (vec![], vec![], 0);
    let mut sizes = (first.num_triangles(), first.num_triangles());
    // As the explorer does: a step's mesh is written into the arrays of
    // the one two steps before, once that is let go (`Spares`).
    let mut spares = std::collections::VecDeque::from([(first, PreparedMesh::default())]);
    let cpu0 = process_cpu();
    // At an end of the chain the drag turns back, as a hand does.
    let (mut at, mut dir, mut turns) = (iso.value, delta, 0);
    for k in 1..=steps {
        let mut seed = None;
        for _ in 0..2 {
            let iso = Isovalue::new(at + dir);
            seed = flexiso::contour::path_seed_in_chain(tree, field, chain, iso);
            if seed.is_some() {
                break;
            }
            dir = -dir;
            turns += 1;
        }
        let Some(seed) = seed else {
            break;
        };
        at += dir;
        let iso = Isovalue::new(at);
        let spare = if spares.len() >= 2 {
            spares.pop_front()
        } else {
            None
        };
        let spare_gpu = spare.map_or_else(PreparedMesh::default, |(m, p)| {
            dragged.recycle(m);
            p
        });
        let t = Instant::now();
        let budget = step_budget(dragged.num_triangles());
        let mesh = match dragged
            .step(tree, seed.arc, iso, budget, &|| false)
            .expect("not cancelled")
        {
            Ok(m) => m,
            Err(_) => {
                refused += 1;
                let (d, m) = DraggedContour::start(&shared, &seed, iso, &|| false)
                    .expect("not cancelled")
                    .expect("spans");
                dragged = d;
                m
            }
        };
        let s = t.elapsed().as_secs_f64() * 1e3;
        let gpu =
            PreparedMesh::new_reusing(&mesh.positions, &mesh.normals, &mesh.indices, spare_gpu)
                .expect("a contour is a valid mesh");
        times.push(t.elapsed().as_secs_f64() * 1e3);
        step_only.push(s);
        sizes = (
            sizes.0.min(mesh.num_triangles()),
            sizes.1.max(mesh.num_triangles()),
        );
        if k == 1 || k == steps {
            let want = check
                .extract(tree, &seed, iso, &|| false)
                .expect("not cancelled");
            assert_eq!(
                (mesh.num_triangles(), mesh.positions.len()),
                (want.num_triangles(), want.positions.len()),
                "the dragged contour is the extracted one"
            );
        }
        spares.push_back((mesh, gpu));
    }
    let cpu = cpu0
        .zip(process_cpu())
        .map_or(f64::NAN, |(a, b)| (b - a) * 1e3 / times.len().max(1) as f64);
    let ((m, w), (sm, sw)) = (stats(&times), stats(&step_only));
    println!(
        "{name}: incremental drag of {} steps of {delta:+} from h = {} ({turns} turns at the \
         chain's ends; {}..{} triangles): \
         start {start:.0} ms; new isovalue to mesh ready for upload, median / worst step \
         {m:.0} / {w:.0} ms (the step alone {sm:.0} / {sw:.0} ms; CPU per step, all threads, \
         with the checks {cpu:.0} ms); {refused} steps refused and restarted",
        times.len(),
        iso.value,
        sizes.0,
        sizes.1,
    );
}

/// What dragging a contour's isovalue costs before the new mesh can be
/// drawn: a contour of about 200k triangles (the largest spanning arc at
/// the first isovalue, from the top, that has one of 150k to 250k) moved by
/// steps down its arc: path seed, following, and the upload to the GPU
/// (headless wgpu, software Vulkan here), then one 1280×800 render.
fn drag_latency(
    name: &str,
    tree: &ContourTree,
    field: &ScalarField,
    band: std::ops::RangeInclusive<usize>,
) {
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
            if band.contains(&n) {
                found = Some((arc, iso.value));
                break 'search;
            }
        }
    }
    let Some((arc, h)) = found else {
        println!("{name}: no contour of {band:?} triangles at the isovalues tried");
        return;
    };
    let gpu = flexiso::render::headless::Gpu::new().ok();
    let mut renderer = gpu.as_ref().map(|g| g.renderer());
    let mut worst = (0f64, 0f64, 0f64, 0usize, 0usize);
    // Five drag steps down the arc, towards its lower end.
    let bottom = field.value(tree.node(tree.arc(arc).lower).vertex);
    let mut last = None;
    let mut oracle = ContourFollower::new(field);
    let mut sweep = ContourFollower::new(field).with_serial_limit(0);
    let (mut worst_serial, mut worst_sweep) = (0f64, 0f64);
    let mut click = (f64::NAN, f64::NAN);
    // As the explorer's worker does for a contour too large to keep, a
    // step's mesh and GPU form go into the arrays of those two steps
    // before, once the window has let them go; the first step after the
    // click into the spares made after it (`Ahead::Spares`).
    let kept = flexiso::app::jobs::extraction::kept_triangles(field.len());
    let mut old = std::collections::VecDeque::new();
    let mut ahead = None;
    for step in 0..5 {
        let iso = Isovalue::new(h - (h - bottom) * step as f64 / 6.0);
        let spare = if old.len() == 2 {
            old.pop_front()
                .map(|(m, g)| (m, std::sync::Arc::try_unwrap(g).unwrap_or_default()))
        } else {
            ahead.take()
        };
        let spare_gpu = spare.map_or_else(Default::default, |(mesh, gpu)| {
            follower.recycle(mesh);
            gpu
        });
        let t = Instant::now();
        let Some(seed) = seeds.seed(tree, field, arc, iso) else {
            break;
        };
        let mesh = follower
            .extract_expecting(tree, &seed, iso, last, &|| false)
            .expect("not cancelled");
        last = Some(mesh.num_triangles());
        // As the explorer's worker does: the mesh is made ready for the
        // GPU on the extracting thread, the UI thread only copies it.
        let (p, n, i) = (&mesh.positions, &mesh.normals, &mesh.indices);
        let prepared = std::sync::Arc::new(
            flexiso::render::PreparedMesh::new_known(p, n, i, (&mesh).into(), spare_gpu)
                .expect("a contour is a valid mesh"),
        );
        let extract = t.elapsed().as_secs_f64() * 1e3;
        // The same step by the serial follower and by the sweep alone.
        let t = Instant::now();
        black_box(prepare(&oracle.follow(&seed, iso)));
        worst_serial = worst_serial.max(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        let swept = sweep
            .extract(tree, &seed, iso, &|| false)
            .expect("not cancelled");
        black_box(prepare(&swept));
        worst_sweep = worst_sweep.max(t.elapsed().as_secs_f64() * 1e3);
        let (mut upload, mut render, mut frames) = (0.0, 0.0, 0);
        if let (Some(g), Some(r)) = (&gpu, &mut renderer) {
            let t = Instant::now();
            r.set_prepared_mesh(&g.device, 1, std::sync::Arc::clone(&prepared))
                .expect("upload");
            frames = 1;
            while r.upload_pending(
                &g.device,
                &g.queue,
                flexiso::app::panels::view3d::UPLOAD_BUDGET,
            ) {
                frames += 1;
            }
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
        if step == 0 {
            // The click: its size unknown.
            click = (extract, upload);
            let (v, t) = (mesh.positions.len(), mesh.num_triangles());
            if t > kept {
                ahead = Some((
                    flexiso::contour::ContourMesh::spare(mesh.arc, v, t),
                    flexiso::render::PreparedMesh::spare(v, t),
                ));
            }
        } else if extract + upload > worst.0 + worst.1 {
            worst = (extract, upload, render, mesh.num_triangles(), frames);
        }
        old.push_back((mesh, prepared));
    }
    // Steps of one value unit down the arc's chain (100-arc level, by
    // volume), as a mouse drag makes them.
    let chain = chain_at_100_arcs(tree, field, arc);
    let ends = (
        field.value(tree.node(tree.arc(chain[0]).lower).vertex),
        field.value(tree.node(tree.arc(chain[chain.len() - 1]).upper).vertex),
    );
    let dir = if h - ends.0 > ends.1 - h { -1.0 } else { 1.0 };
    // The same drag kept and extracted afresh on every core: the explorer
    // keeps contours of up to `kept` triangles.
    scripted_drag(name, tree, field, Isovalue::new(h), arc, dir, 20);
    println!(
        "{name}: the explorer drags a contour of {} triangles {} (kept up to {kept} triangles here)",
        worst.3,
        if worst.3 <= kept {
            "kept"
        } else {
            "afresh (the scripted drag's parallel steps)"
        }
    );
    println!(
        "{name}: dragging a contour of {} triangles (arc {:?}, from h = {h} down its arc): \
         the click (size unknown) {:.1} ms + upload {:.1} ms; \
         worst of 4 steps after it (arrays of two steps before recycled), extraction (and preparation) {:.1} ms + upload {:.1} ms ({} frames) = {:.1} ms; \
         its render {:.1} ms ({}); worst step extraction and preparation by the serial \
         follower {:.1} ms, by the sweep {:.1} ms",
        worst.3,
        arc,
        click.0,
        click.1,
        worst.0,
        worst.1,
        worst.4,
        worst.0 + worst.1,
        worst.2,
        gpu.as_ref()
            .map_or("no GPU adapter".into(), |g| g.describe()),
        worst_serial,
        worst_sweep,
    );
}

criterion_group!(benches, contour);

fn main() {
    // As the program does: large freed arrays go back to the system at
    // once, so a fresh array is fresh pages (see `pages`).
    flexiso::pages::return_freed_arrays();
    quick();
    if std::env::var("FLEXISO_BENCH_QUICK").as_deref() == Ok("1") {
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
