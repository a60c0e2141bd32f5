//! `flexiso tree INPUT [--json PATH]`: the contour tree of a volume, its
//! statistics and the time of each stage; optionally the tree as JSON.

use super::input::InputArgs;
use crate::progress::Progress;
use crate::tree::ContourTree;
use anyhow::Context;
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
}

/// Runs `flexiso tree`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let t = Instant::now();
    let volume = args.input.load()?;
    let load = t.elapsed();
    let field = &volume.field;
    let (tree, times) = ContourTree::from_field(field, &Progress::new())
        .map_err(|_| anyhow::anyhow!("cancelled"))?;
    let [x, y, z] = field.dims();
    let (lo, hi) = field.range();
    let (maxima, minima, joins, splits) = tree.kind_counts();
    println!(
        "input:          {} ({})",
        volume.path.display(),
        volume.format
    );
    println!(
        "dims:           {x} x {y} x {z} = {} vertices, {}, values {lo} .. {hi}",
        field.len(),
        field.values().type_name()
    );
    println!("maxima:         {maxima}");
    println!("minima:         {minima}");
    println!("join saddles:   {joins}");
    println!("split saddles:  {splits}");
    println!("supernodes:     {}", tree.nodes().len());
    println!("superarcs:      {}", tree.arcs().len());
    let s = |d: std::time::Duration| d.as_secs_f64();
    println!(
        "time (s):       load {:.3}  sort {:.3}  join {:.3}  split {:.3} (in parallel: {:.3})  merge {:.3}  augment {:.3}  total {:.3} (without load)",
        s(load),
        s(times.sort),
        s(times.join),
        s(times.split),
        s(times.sweeps),
        s(times.merge),
        s(times.augment),
        s(times.total()),
    );
    if let Some(path) = &args.json {
        let json = crate::tree::json::tree_json(&tree, field);
        let text = serde_json::to_string(&json)?;
        if path.as_os_str() == "-" {
            println!("{text}");
        } else {
            std::fs::write(path, text)
                .with_context(|| format!("{}: cannot write", path.display()))?;
        }
    }
    Ok(())
}
