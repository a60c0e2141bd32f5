//! `flexiso info`: what a volume file holds (format, grid, type, spacing,
//! origin and direction in the world, value range, a histogram, the number
//! of distinct values for integer data) and the memory its contour tree
//! will need.

use super::input::InputArgs;
use crate::field::ScalarField;
use crate::field::io::Volume;
use crate::field::{Scalar, Values};
use std::fmt::Write as _;

/// Arguments of `flexiso info`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// The volume.
    #[command(flatten)]
    pub input: InputArgs,
    /// Number of histogram bins.
    #[arg(long, default_value_t = 10)]
    pub bins: usize,
    /// Print the same as one JSON object (on standard output).
    #[arg(long)]
    pub json: bool,
}

/// Runs `flexiso info`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let volume = args.input.load()?;
    let bins = args.bins.clamp(1, 1000);
    if args.json {
        let mut text = serde_json::to_string_pretty(&report_json(&volume, bins))?;
        text.push('\n');
        return super::write_stdout(text.as_bytes());
    }
    if !super::quiet() {
        super::write_stdout(report(&volume, bins).as_bytes())?;
    }
    Ok(())
}

/// What [`report`] says, as JSON: `file`, `format`, `dims`, `type`,
/// `file_type`, `spacing`, `origin`, `direction` (per axis), `space`,
/// `range`, `distinct` (integers), `histogram` (`edges`, `counts`),
/// `candidates` (candidate nodes of the tree engine), `memory_bytes`
/// (values and the engine's peak), `warnings`.
pub fn report_json(volume: &Volume, bins: usize) -> serde_json::Value {
    let f = &volume.field;
    let v = f.values();
    let (lo, hi) = f.range();
    let bins = if hi > lo { bins } else { 1 };
    let counts = histogram(v, lo, hi, bins);
    let width = (hi - lo) / bins as f64;
    let edges: Vec<f64> = (0..=bins)
        .map(|i| if i == bins { hi } else { lo + width * i as f64 })
        .collect();
    let g = f.geometry();
    let n = f.len() as u64;
    let (candidates, blocks, tree) = tree_memory(f);
    serde_json::json!({
        "file": volume.path.display().to_string(),
        "format": volume.format,
        "dims": f.dims(),
        "vertices": n,
        "type": v.type_name(),
        "file_type": volume.scalar_type.name(),
        "spacing": f.spacing(),
        "origin": g.origin,
        "direction": g.direction,
        "space": g.space.name(),
        "range": [lo, hi],
        "distinct": distinct(v),
        "histogram": { "edges": edges, "counts": counts },
        "candidates": candidates,
        "blocks": blocks,
        "memory_bytes": n * v.bytes_per_value() as u64 + tree,
        "warnings": volume.warnings,
    })
}

fn bytes(k: usize) -> String {
    if k == 1 {
        "1 byte".into()
    } else {
        format!("{k} bytes")
    }
}

fn mib(bytes: u64) -> String {
    if bytes < 100 << 10 {
        return format!("{:.1} KiB", bytes as f64 / 1024.0);
    }
    let m = bytes as f64 / (1u64 << 20) as f64;
    if m >= 10.0 {
        format!("{m:.0} MiB")
    } else {
        format!("{m:.1} MiB")
    }
}

/// The text `flexiso info` prints for `volume`, with a histogram of `bins`
/// bins.
pub fn report(volume: &Volume, bins: usize) -> String {
    let f = &volume.field;
    let v = f.values();
    let [x, y, z] = f.dims();
    let [sx, sy, sz] = f.spacing();
    let (lo, hi) = f.range();
    let n = f.len();
    let mut out = String::new();
    let _ = writeln!(out, "file:      {}", volume.path.display());
    let _ = writeln!(out, "format:    {}", volume.format);
    let _ = writeln!(out, "dims:      {x} x {y} x {z} = {n} vertices");
    let stored = v.type_name();
    let file_type = volume.scalar_type.name();
    if stored == file_type {
        let _ = writeln!(
            out,
            "type:      {stored} ({} per value)",
            bytes(v.bytes_per_value())
        );
    } else {
        let _ = writeln!(
            out,
            "type:      {stored} ({} per value; {file_type} in the file)",
            bytes(v.bytes_per_value())
        );
    }
    let _ = writeln!(out, "spacing:   {sx} x {sy} x {sz}");
    let g = f.geometry();
    let [ox, oy, oz] = g.origin;
    let _ = writeln!(out, "origin:    {ox} {oy} {oz} ({} space)", g.space);
    let axes: Vec<String> = g
        .direction
        .iter()
        .map(|d| format!("({} {} {})", num(d[0]), num(d[1]), num(d[2])))
        .collect();
    let _ = writeln!(
        out,
        "direction: {} (the world directions of the i, j, k axes)",
        axes.join(" ")
    );
    let _ = writeln!(out, "range:     {lo} .. {hi}");
    if let Some(d) = distinct(v) {
        let _ = writeln!(out, "distinct:  {d} value{}", if d == 1 { "" } else { "s" });
    }
    // Constant data: one bin says it all.
    let bins = if hi > lo { bins } else { 1 };
    let counts = histogram(v, lo, hi, bins);
    let _ = writeln!(out, "histogram: {bins} bins");
    let peak = counts.iter().copied().max().unwrap_or(1).max(1);
    let width = (hi - lo) / bins as f64;
    for (i, c) in counts.iter().enumerate() {
        let a = lo + width * i as f64;
        let b = if i + 1 == bins { hi } else { a + width };
        let bar = "#".repeat(((*c as f64 / peak as f64) * 40.0).ceil() as usize);
        let close = if i + 1 == bins { ']' } else { ')' };
        let _ = writeln!(
            out,
            "  [{:>10}, {:>10}{close} {c:>12} {bar}",
            num(a),
            num(b)
        );
    }
    let values = (n * v.bytes_per_value()) as u64;
    let (candidates, blocks, tree) = tree_memory(f);
    let blocked = if blocks > 1 {
        format!(", joined and split in {blocks} blocks")
    } else {
        String::new()
    };
    let _ = writeln!(
        out,
        "memory:    values {} + contour tree {} at its peak ({candidates} candidate nodes, {:.1}% of the vertices{blocked}) = about {}",
        mib(values),
        mib(tree),
        candidates as f64 * 100.0 / n.max(1) as f64,
        mib(values + tree)
    );
    for w in &volume.warnings {
        let _ = writeln!(out, "warning:   {w}");
    }
    out
}

/// The candidate nodes of the field (its link classification, without the
/// sort), the blocks the build would sweep in on this machine, and the
/// peak bytes the tree engine will hold beyond the values.
fn tree_memory(f: &ScalarField) -> (usize, usize, u64) {
    use crate::mesh::Mesh as _;
    use crate::tree::blocks;
    let mesh = f.mesh();
    let n = f.len();
    let census =
        crate::with_values!(f.values(), v => crate::tree::sweep::census_of(&mesh, v.as_slice()));
    let candidates = census.candidates;
    let counting = crate::field::sorts_by_counting(f.values());
    let remade = crate::tree::order_at_merge(n, census, counting);
    let order_bytes = crate::field::order_bytes(f.values());
    let span = mesh.edge_span();
    let blocks = blocks::chosen_blocks(n, span, candidates);
    let band = blocks::band_vertices(&blocks::even_cuts(n, blocks), n, span);
    let available = crate::field::io::available_memory();
    let (peak, in_blocks) =
        crate::tree::peak_bytes_in_blocks(n, census, order_bytes, remade, band, available);
    let blocks = if in_blocks { blocks } else { 1 };
    (candidates, blocks, peak)
}

/// A bin edge: integral values without decimals, others with four.
fn num(x: f64) -> String {
    if x.fract() == 0.0 {
        format!("{x}")
    } else {
        format!("{x:.4}")
    }
}

/// Counts per bin of equal width over [lo, hi] (one bin when constant).
pub fn histogram(values: &Values, lo: f64, hi: f64, bins: usize) -> Vec<u64> {
    fn go<T: Scalar>(v: &[T], lo: f64, hi: f64, bins: usize) -> Vec<u64> {
        let mut counts = vec![0u64; bins];
        let scale = if hi > lo {
            bins as f64 / (hi - lo)
        } else {
            0.0
        };
        for x in v {
            let b = ((x.to_f64() - lo) * scale) as usize;
            counts[b.min(bins - 1)] += 1;
        }
        counts
    }
    crate::with_values!(values, v => go(v, lo, hi, bins.max(1)))
}

/// Number of distinct values of integer data (`None` for floats).
pub fn distinct(values: &Values) -> Option<usize> {
    fn table<T: Copy>(v: &[T], size: usize, index: impl Fn(T) -> usize) -> usize {
        let mut seen = vec![false; size];
        for &x in v {
            seen[index(x)] = true;
        }
        seen.iter().filter(|s| **s).count()
    }
    fn sorted<T: Copy + Ord>(v: &[T]) -> usize {
        let mut s = v.to_vec();
        s.sort_unstable();
        s.dedup();
        s.len()
    }
    Some(match values {
        Values::U8(v) => table(v, 256, |x| x as usize),
        Values::I8(v) => table(v, 256, |x| (x as i16 + 128) as usize),
        Values::U16(v) => table(v, 1 << 16, |x| x as usize),
        Values::I16(v) => table(v, 1 << 16, |x| (x as i32 + 32768) as usize),
        Values::U32(v) => sorted(v),
        Values::I32(v) => sorted(v),
        Values::F32(_) | Values::F64(_) => return None,
    })
}
