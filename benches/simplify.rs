//! Criterion benches of simplification, what a user feels after the tree
//! is built: seconds to the whole pruning sequence (measures, collapse of
//! zero-height arcs, leaf pruning), and milliseconds to move the level
//! slider. Run on the two MRI templates of the shared data folder (the
//! largest trees we have), or on a noisy synthetic cube without it.
//!
//! `cargo bench --bench simplify`

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use flexiso::field::ScalarField;
use flexiso::field::io::{ReadOptions, read_volume};
use flexiso::field::synthetic::Synthetic;
use flexiso::measure::geometric::ArcRegions;
use flexiso::progress::Progress;
use flexiso::simplify::{CollapsedTree, Measure, Simplification, SimplifiedTree};
use flexiso::tree::ContourTree;
use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

fn volumes() -> Vec<(String, ScalarField)> {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    let mut out = Vec::new();
    for name in ["colin27_ch2", "colin27_ch2better"] {
        if let Ok(v) = read_volume(&data.join(format!("{name}.nrrd")), &ReadOptions::default()) {
            out.push((name.to_owned(), v.field));
        }
    }
    if out.is_empty() {
        out.push((
            "synthetic-noisy-96".to_owned(),
            Synthetic::cube(96).with_noise(0.05, 3).generate(),
        ));
    }
    out
}

fn simplify(c: &mut Criterion) {
    for (name, field) in volumes() {
        let t = Instant::now();
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
        let collapsed = CollapsedTree::new(&tree, &field);
        eprintln!(
            "{name}: {} vertices, tree built in {:.1} s, {} superarcs, {} arcs collapsed",
            field.len(),
            t.elapsed().as_secs_f64(),
            tree.arcs().len(),
            collapsed.num_arcs()
        );
        let mut g = c.benchmark_group(&name);
        g.sample_size(10);
        g.bench_function("measures (Algorithm 1)", |b| {
            b.iter(|| black_box(ArcRegions::new(&tree, &field)))
        });
        g.bench_function("measures + collapse + pruning sequence", |b| {
            b.iter(|| black_box(Simplification::new(&tree, &field, Measure::Hypervolume)))
        });
        g.bench_function("pruning sequence (collapsed tree given)", |b| {
            b.iter(|| {
                black_box(Simplification::from_collapsed(
                    &collapsed,
                    Measure::Hypervolume,
                ))
            })
        });
        let sim = Arc::new(Simplification::from_collapsed(
            &collapsed,
            Measure::Hypervolume,
        ));
        let steps = sim.steps().len();
        let mut level = SimplifiedTree::new(sim.clone());
        // The worst slider move: the whole tree to one arc and back.
        g.bench_function("level change, full tree <-> simplest", |b| {
            let mut up = true;
            b.iter(|| {
                level.set_step(if up { steps } else { 0 });
                up = !up;
                black_box(level.num_arcs())
            })
        });
        g.bench_function("level change, by feature size (10 jumps)", |b| {
            let curve = sim.curve();
            b.iter(|| {
                for i in 0..10 {
                    let k = (i * 7919 * 104729) % curve.len();
                    level.set_feature_size(curve[k].feature_size);
                }
                black_box(level.num_arcs())
            })
        });
        g.finish();
    }
}

criterion_group!(benches, simplify);
criterion_main!(benches);
