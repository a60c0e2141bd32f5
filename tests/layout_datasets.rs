//! The tree layout on every volume of the shared data folder, under every
//! measure, at every level from 10 to 200 arcs: no arc runs along another,
//! at most one crossing per 20 arcs shown (except the pairs listed in
//! `BELOW_FLOOR`), and the crossing counts printed
//! (`cargo test --release --test layout_datasets -- --nocapture`).

mod common;

use flexiso::field::io::{ReadOptions, read_volume};
use flexiso::progress::Progress;
use flexiso::simplify::layout::TreeLayout;
use flexiso::simplify::{CollapsedTree, Measure, Simplification, SimplifiedTree};
use flexiso::tree::ContourTree;
use std::sync::Arc;

/// The levels checked: every level of the sequence with 10 to 200 arcs.
const FEWEST: usize = 10;
const MOST: usize = 200;

/// (volume, measure) pairs that miss the floor at some levels, held to
/// one crossing per 3 arcs instead (a guard against regressions), the
/// levels missing the floor printed. None now: before children were
/// sided by their own direction, 18 of the 48 pairs were listed here
/// (worst 0.30 crossings per arc, tooth, with 3 crossings at 10 arcs);
/// boston_teapot under volume left when children reaching back learned
/// to jump past their passers, bonsai under hypervolume when passers
/// learned "coarse levels first" (the layout's module doc).
const BELOW_FLOOR: &[(&str, &str)] = &[];

/// Per level checked: (arcs, crossings), after asserting no overlaps.
fn check_levels(name: &str, sim: &Arc<Simplification>) -> Vec<(usize, usize)> {
    let layout = TreeLayout::new(sim);
    let mut level = SimplifiedTree::new(Arc::clone(sim));
    let mut out = Vec::new();
    let last = sim.steps().len();
    for step in (0..=last).rev() {
        level.set_step(step);
        let arcs = level.num_arcs();
        if arcs < FEWEST {
            continue;
        }
        if arcs > MOST {
            break;
        }
        let drawn = layout.level(&level);
        assert_eq!(
            drawn.overlaps(),
            0,
            "{name} {}: arcs run along each other at {arcs} arcs",
            sim.measure()
        );
        out.push((arcs, drawn.crossings()));
    }
    out
}

#[test]
fn every_volume_is_drawn_with_at_most_one_crossing_per_20_arcs_at_10_to_200_arcs() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("data folder lists")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".nrrd"))
        .collect();
    names.sort();
    let mut failures = Vec::new();
    for name in &names {
        let volume = read_volume(&dir.join(name), &ReadOptions::default()).expect("readable");
        let field = &volume.field;
        let (tree, _) = ContourTree::from_field(field, &Progress::new()).expect("not cancelled");
        let collapsed = CollapsedTree::new(&tree, field);
        drop(tree);
        for measure in Measure::ALL {
            let sim = Arc::new(Simplification::from_collapsed(&collapsed, measure));
            let levels = check_levels(name, &sim);
            let worst = levels
                .iter()
                .map(|&(a, c)| c as f64 / a as f64)
                .fold(0.0, f64::max);
            let total: usize = levels.iter().map(|l| l.1).sum();
            let at = |n: usize| {
                levels
                    .iter()
                    .rev()
                    .find(|l| l.0 <= n)
                    .map_or("-".to_string(), |l| format!("{}@{}", l.1, l.0))
            };
            eprintln!(
                "{name:24} {:12} {} levels, {total} crossings in all, worst {worst:.3}/arc; at 10 {} 50 {} 100 {} 200 {}",
                measure.name(),
                levels.len(),
                at(10),
                at(50),
                at(100),
                at(200),
            );
            let excepted = BELOW_FLOOR.contains(&(name.as_str(), measure.name()));
            let missed: Vec<String> = levels
                .iter()
                .filter(|&&(arcs, crossings)| crossings * 20 > arcs)
                .map(|&(arcs, crossings)| format!("{crossings}@{arcs}"))
                .collect();
            if !missed.is_empty() {
                eprintln!(
                    "    floor missed at {} levels: {}",
                    missed.len(),
                    missed.join(" ")
                );
            }
            for &(arcs, crossings) in &levels {
                let bound = if excepted { arcs / 3 } else { arcs / 20 };
                if crossings > bound {
                    failures.push(format!(
                        "{name} {measure}: {crossings} crossings at {arcs} arcs"
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "more than one crossing per 20 arcs:\n{}",
        failures.join("\n")
    );
}
