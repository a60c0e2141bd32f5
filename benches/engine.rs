//! Criterion benches of the contour tree stages on mid-size volumes: the
//! synthetic scene (noisy, 96^3 float32) and, when the shared data folder is
//! there, neghip and hydrogen_atom (uint8 scans).

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]
use criterion::{Criterion, criterion_group, criterion_main};
use flexiso::field::ScalarField;
use flexiso::field::io::{ReadOptions, read_volume};
use flexiso::field::synthetic::Synthetic;
use flexiso::progress::Progress;
use flexiso::tree::ContourTree;
use flexiso::tree::sweep::{count_candidates, join_tree, link_codes};
use std::hint::black_box;
use std::path::Path;

fn volumes() -> Vec<(String, ScalarField)> {
    let mut out = vec![(
        "synthetic-noisy-96".to_owned(),
        Synthetic::cube(96).with_noise(0.05, 3).generate(),
    )];
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    for name in ["neghip", "hydrogen_atom"] {
        if let Ok(v) = read_volume(&data.join(format!("{name}.nrrd")), &ReadOptions::default()) {
            out.push((name.to_owned(), v.field));
        }
    }
    out
}

fn stages(c: &mut Criterion) {
    for (name, field) in volumes() {
        let mut g = c.benchmark_group(&name);
        g.sample_size(10);
        g.bench_function("sort", |b| b.iter(|| black_box(field.vertex_order())));
        let order = field.vertex_order();
        let mesh = field.mesh();
        flexiso::with_values!(field.values(), v => {
            g.bench_function("link codes", |b| {
                b.iter(|| black_box(link_codes(&mesh, v.as_slice())))
            });
            let codes = link_codes(&mesh, v.as_slice());
            let candidates = count_candidates(&codes);
            g.bench_function("join sweep", |b| {
                b.iter(|| {
                    black_box(join_tree(
                        &mesh,
                        v.as_slice(),
                        &codes,
                        candidates,
                        &order,
                        &Progress::new(),
                    ))
                })
            });
        });
        g.bench_function("tree (all stages)", |b| {
            b.iter(|| black_box(ContourTree::from_field(&field, &Progress::new())))
        });
        g.finish();
    }
}

criterion_group!(benches, stages);
criterion_main!(benches);
