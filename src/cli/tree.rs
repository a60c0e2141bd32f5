//! `flexiso tree INPUT [--json PATH] [--measure M] [--simplify N |
//! --feature-size X]`: the contour tree of a volume, its statistics and the
//! time of each stage; the size after collapsing zero-height arcs;
//! optionally a simplified level; optionally all of it as JSON.
//! `--algorithm raichel-seshadhri` builds the same tree without the global
//! sort; `--count-comparisons` adds the value comparisons per stage.

use super::input::InputArgs;
use super::{Report, SpaceArg};
use crate::progress::Progress;
use crate::report;
use crate::simplify::{CollapsedTree, Measure, Simplification, SimplifiedTree};
use crate::tree::{BuildTimes, ContourTree, raichel_seshadhri};
use anyhow::Context;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `flexiso tree`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// The volume.
    #[command(flatten)]
    pub input: InputArgs,
    /// Write the tree as JSON to this file ("-" for standard output).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Local geometric measure that ranks leaves for simplification.
    #[arg(long, value_parser = super::input::measure_parser(), default_value_t = Measure::Hypervolume)]
    pub measure: Measure,
    /// Simplify to at most N arcs (counted on the collapsed tree).
    #[arg(long, value_name = "N", conflicts_with = "feature_size")]
    pub simplify: Option<usize>,
    /// Simplify by pruning every leaf whose cost is at most X.
    #[arg(long, value_name = "X")]
    pub feature_size: Option<f64>,
    /// Coordinates of the nodes' `position` in the JSON: `world` (the
    /// volume's origin, direction and spacing, in its file's space) or
    /// `index` (voxel indices).
    #[arg(long, value_enum, default_value_t = SpaceArg::World)]
    pub space: SpaceArg,
    /// Lay the simplified level out as the explorer draws it (printed
    /// crossings; with --json, a "layout" object inside "simplified").
    #[arg(long)]
    pub layout: bool,
    /// The engine that builds the tree (both give the same tree).
    #[arg(long, value_enum, default_value_t = Algorithm::CarrSnoeyinkAxen)]
    pub algorithm: Algorithm,
    /// Also count the value comparisons of each stage (in a second build:
    /// the times printed are of the uncounted one).
    #[arg(long)]
    pub count_comparisons: bool,
    /// Cut the volume into N blocks whose join and split trees are
    /// computed in parallel and glued (the same tree for every N; default:
    /// as many as keep every core busy, 1 on two cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub blocks: Option<u32>,
}

/// The contour tree engines.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Algorithm {
    /// Sort, join and split sweeps, merge (Carr, Snoeyink, Axen): the default.
    #[default]
    #[value(alias = "sweep")]
    CarrSnoeyinkAxen,
    /// Painting without the global sort (Raichel, Seshadhri).
    RaichelSeshadhri,
}

/// Runs `flexiso tree`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(path) = &args.json {
        super::check_output(path)?;
    }
    let r = Report::new(args.json.as_deref().is_some_and(super::is_stdio));
    let bar = super::bar::StageBar::new();
    let t = Instant::now();
    bar.stage("reading");
    let volume = args.input.load()?;
    bar.done();
    for w in &volume.warnings {
        r.warn(w);
    }
    let load = t.elapsed();
    let field = &volume.field;
    let cancelled = |_: crate::progress::Cancelled| anyhow::anyhow!("cancelled");
    let (tree, timing) = match args.algorithm {
        Algorithm::CarrSnoeyinkAxen => {
            let (tree, times) = match args.blocks {
                Some(b) => ContourTree::from_field_in_blocks(field, b as usize, bar.progress()),
                None => ContourTree::from_field(field, bar.progress()),
            }
            .map_err(|e| anyhow::anyhow!("{e}"))?;
            (tree, Timing::Engine(times))
        }
        Algorithm::RaichelSeshadhri => {
            let (tree, stats) =
                raichel_seshadhri::from_field(field, false, bar.progress()).map_err(cancelled)?;
            (tree, Timing::Painting(stats))
        }
    };
    bar.done();
    let [x, y, z] = field.dims();
    let (lo, hi) = field.range();
    let (maxima, minima, joins, splits) = tree.kind_counts();
    report!(
        r,
        "input:          {} ({})",
        volume.path.display(),
        volume.format
    );
    report!(
        r,
        "dims:           {x} x {y} x {z} = {} vertices, {}, values {lo} .. {hi}",
        field.len(),
        field.values().type_name()
    );
    report!(r, "maxima:         {maxima}");
    report!(r, "minima:         {minima}");
    report!(r, "join saddles:   {joins}");
    report!(r, "split saddles:  {splits}");
    report!(r, "supernodes:     {}", tree.nodes().len());
    report!(r, "superarcs:      {}", tree.arcs().len());
    // Collapsing and measuring a tree of tens of millions of superarcs
    // may not fit beside it: then only the tree is reported, unless more
    // was asked for.
    let wants_more = args.simplify.is_some() || args.feature_size.is_some() || args.json.is_some();
    let t = Instant::now();
    let collapsed = match crate::simplify::memory::check_collapse(tree.arcs().len()) {
        Ok(()) => {
            // Measured only where something reads the measures.
            bar.stage("measures");
            let (arcs, collapsed) = if wants_more {
                let collapsed = CollapsedTree::new(&tree, field);
                (collapsed.num_arcs(), Some(collapsed))
            } else {
                (CollapsedTree::count_arcs(&tree, field), None)
            };
            bar.done();
            report!(r, "collapsed arcs: {arcs} (zero-height arcs contracted)");
            collapsed
        }
        Err(e) if !wants_more => {
            report!(r, "collapsed arcs: not computed: {e}");
            None
        }
        Err(e) => anyhow::bail!("{e}"),
    };
    let collapse = t.elapsed();
    let level = match (
        &collapsed,
        args.simplify.is_some() || args.feature_size.is_some(),
    ) {
        (Some(collapsed), true) => {
            crate::simplify::memory::check_simplification(collapsed.num_arcs())?;
            let t = Instant::now();
            bar.stage("simplification");
            let sim = Simplification::from_collapsed(collapsed, args.measure);
            let sequence = t.elapsed();
            let mut level = SimplifiedTree::new(std::sync::Arc::new(sim));
            if let Some(n) = args.simplify {
                level.set_level(n);
            } else if let Some(x) = args.feature_size {
                level.set_feature_size(x);
            }
            bar.done();
            report!(
                r,
                "simplified:     {} arcs by {} (feature size {}, {} of {} steps; measures and collapse {:.3} s, pruning sequence {:.3} s)",
                level.num_arcs(),
                args.measure,
                level.feature_size(),
                level.step(),
                level.simplification().steps().len(),
                collapse.as_secs_f64(),
                sequence.as_secs_f64(),
            );
            Some(level)
        }
        _ => None,
    };
    let layout = match (&level, args.layout) {
        (Some(level), true) => {
            let t = Instant::now();
            let drawn =
                crate::simplify::layout::TreeLayout::new(level.simplification()).level(level);
            report!(
                r,
                "layout:         {} nodes, {} arcs, {} crossings ({:.3} s)",
                drawn.nodes.len(),
                drawn.arcs.len(),
                drawn.crossings(),
                t.elapsed().as_secs_f64()
            );
            Some(drawn)
        }
        (None, true) => anyhow::bail!(
            "--layout lays out a simplified level: add --simplify N or --feature-size X"
        ),
        _ => None,
    };
    let s = |d: std::time::Duration| d.as_secs_f64();
    match timing {
        Timing::Engine(times) => report!(
            r,
            "time (s):       load {:.3}  sort {:.3}  links {:.3}  join {:.3}  split {:.3} (in parallel{}: {:.3})  merge {:.3}  augment {:.3}  total {:.3} (without load)",
            s(load),
            s(times.sort),
            s(times.links),
            s(times.join),
            s(times.split),
            match times.blocks {
                0 | 1 => String::new(),
                b => format!(", in {b} blocks"),
            },
            s(times.sweeps),
            s(times.merge),
            s(times.augment),
            s(times.total()),
        ),
        Timing::Painting(stats) => {
            let times = stats.times;
            report!(
                r,
                "time (s):       load {:.3}  links {:.3}  paint join {:.3}  split {:.3} (in parallel: {:.3})  merge {:.3}  numbering {:.3}  locate {:.3}  arc sort {:.3}  total {:.3} (without load; {} critical vertices painted)",
                s(load),
                s(times.links),
                s(times.join),
                s(times.split),
                s(times.paint),
                s(times.merge),
                s(times.number),
                s(times.locate),
                s(times.arc_sort),
                s(times.total()),
                stats.critical,
            );
        }
    }
    if args.count_comparisons {
        print_comparisons(&r, field, args.algorithm)?;
    }
    if let Some(path) = &args.json {
        bar.stage("writing");
        let simplified = level.as_ref().map(|level| {
            let mut simplified = crate::simplify::json::simplified_tree_json(level, &tree);
            if let (Some(drawn), Some(o)) = (&layout, simplified.as_object_mut()) {
                o.insert("layout".into(), drawn.to_json(level.simplification()));
            }
            simplified
        });
        let g = field.geometry();
        let position = |v: u32| serde_json::json!(args.space.position(field, v));
        let topology = crate::measure::betti::ContourTopology::new(&tree, field);
        let parts = crate::simplify::json::TreeDocument {
            position: Some(&position),
            topology: Some(&topology),
            more: vec![
                (
                    "source",
                    serde_json::json!({
                        "file": volume.path.display().to_string(),
                        "format": volume.format,
                        "value_type": volume.scalar_type.name(),
                    }),
                ),
                (
                    "geometry",
                    serde_json::json!({
                        "spacing": field.spacing(),
                        "origin": g.origin,
                        "direction": g.direction,
                        "space": g.space.name(),
                        "positions": args.space.describe(field),
                    }),
                ),
            ],
            collapsed: collapsed.as_ref(),
            // Only with the collapsed tree, as before.
            simplified: simplified.filter(|_| collapsed.is_some()),
            ..crate::simplify::json::TreeDocument::of(&tree, field)
        };
        if super::is_stdio(path) {
            let mut out = std::io::BufWriter::new(std::io::stdout().lock());
            match parts
                .write(&mut out)
                .and_then(|_| out.write_all(b"\n"))
                .and_then(|_| out.flush())
            {
                // The reader stopped reading (`| head`): it has what it
                // wanted.
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {}
                written => {
                    written.map_err(|e| anyhow::anyhow!("standard output: cannot write: {e}"))?
                }
            }
        } else {
            parts
                .write_file(path)
                .with_context(|| format!("{}: cannot write", path.display()))?;
        }
        bar.done();
    }
    Ok(())
}

/// The stage times of either engine.
enum Timing {
    Engine(BuildTimes),
    Painting(raichel_seshadhri::Stats),
}

/// Builds the tree again through a counting order and prints the value
/// comparisons per stage, next to n log2 n.
fn print_comparisons(
    r: &Report,
    field: &crate::field::ScalarField,
    algorithm: Algorithm,
) -> anyhow::Result<()> {
    let n = field.len() as f64;
    let n_log_n = n * n.max(1.0).log2();
    let m = |c: u64| c as f64 / 1e6;
    match algorithm {
        Algorithm::CarrSnoeyinkAxen => {
            let (_, c) = raichel_seshadhri::count::engine_comparisons(field, &Progress::new())
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            report!(
                r,
                "comparisons (M): sort {:.3} ({})  links and sweeps {:.3}  total {:.3} = {:.2} per vertex; a comparison sort: n log2 n = {:.3}",
                m(c.sort),
                c.sort_kind,
                m(c.sweeps),
                m(c.total()),
                c.total() as f64 / n,
                n_log_n / 1e6,
            );
        }
        Algorithm::RaichelSeshadhri => {
            let (_, stats) = raichel_seshadhri::from_field(field, true, &Progress::new())
                .map_err(|_| anyhow::anyhow!("cancelled"))?;
            let c = stats.comparisons;
            report!(
                r,
                "comparisons (M): links {:.3}  painting {:.3}  numbering {:.3}  locate {:.3}  arc sort {:.3}  total {:.3} = {:.2} per vertex (tree without augmentation {:.3}); n log2 n = {:.3}",
                m(c.links),
                m(c.paint),
                m(c.number),
                m(c.locate),
                m(c.arc_sort),
                m(c.total()),
                c.total() as f64 / n,
                m(c.tree()),
                n_log_n / 1e6,
            );
        }
    }
    Ok(())
}
