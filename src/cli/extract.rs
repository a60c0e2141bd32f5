//! `flexiso extract INPUT --iso H [--arc UPPER:LOWER] [--simplify N
//! --measure M] [--out FILE]`: contours of a volume as triangle meshes.
//!
//! With `--arc` the single contour of that arc at `H` (found from its path
//! seed, single-threaded: the timing is the follower's speed); otherwise
//! every contour at `H`, one object per contour. With `--simplify` the arcs
//! are those of the simplified tree (each a chain of superarcs, searched
//! for the one spanning `H`), so pruned features are left out. The file's
//! extension picks the format (`.ply` binary, `.obj`, `.stl`).
//!
//! Written meshes have no zero-area triangle and no two vertices at one
//! place, even at a data value ([`crate::contour::marching::edge_fraction`]),
//! every closed contour facing
//! out (positive signed volume, [`ContourMesh::orient_outward`]; open ones
//! keep their normals downhill), and positions in world coordinates
//! (`--space world`, the default) or voxel indices (`--space index`).
//!
//! The printout lists every contour, largest first (the file's order):
//! arc, triangles, vertices, area, enclosed volume when closed, Euler
//! characteristic, genus, and the Euler characteristic the tree predicts
//! (Pascucci & Cole-McLaughlin §4, [`ContourTopology`]).

use super::arcs::{Arcs, Target, parse_arc};
use super::input::InputArgs;
use super::{Report, SpaceArg};
use crate::contour::export::{MeshFormat, write_contours_as, write_mesh};
use crate::contour::{self, ContourFollower, ContourMesh, MeshTopology, PathSeed, PathSeeds};
use crate::field::Isovalue;
use crate::measure::betti::ContourTopology;
use crate::report;
use crate::simplify::Measure;
use crate::tree::ContourTree;
use anyhow::{Context, bail};
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `flexiso extract`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// The volume.
    #[command(flatten)]
    pub input: InputArgs,
    /// Isovalue, in the volume's units.
    #[arg(long, value_name = "H", allow_negative_numbers = true)]
    pub iso: f64,
    /// Extract only the contour of the arc between these two critical
    /// vertices (mesh vertex ids, the higher first, as `flexiso tree
    /// --json` lists them; with --simplify, an arc of the simplified tree).
    #[arg(long, value_name = "UPPER:LOWER", value_parser = parse_arc)]
    pub arc: Option<(u32, u32)>,
    /// Simplify the tree to at most N arcs first (pruned features are not
    /// extracted).
    #[arg(long, value_name = "N")]
    pub simplify: Option<usize>,
    /// Local geometric measure that ranks leaves for --simplify.
    #[arg(long, value_parser = super::input::measure_parser(), default_value_t = Measure::Hypervolume)]
    pub measure: Measure,
    /// Mesh file to write: .ply (binary), .obj or .stl; `-` for standard
    /// output (with --format; the printout then goes to standard error).
    /// Without it, only the printout.
    #[arg(long, short, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Mesh format, when --out does not say it by its extension (`-`).
    #[arg(long, value_enum)]
    pub format: Option<FormatArg>,
    /// Coordinates of the mesh file: `world` (the volume's origin,
    /// direction and spacing, in the space its file names: lines up with
    /// the volume in 3D Slicer or ParaView) or `index` (voxel indices).
    #[arg(long, value_enum, default_value_t = SpaceArg::World)]
    pub space: SpaceArg,
}

/// `--format`: a mesh format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    /// Binary little-endian PLY.
    Ply,
    /// Wavefront OBJ.
    Obj,
    /// Binary STL.
    Stl,
    /// VTK XML PolyData.
    Vtp,
}

impl From<FormatArg> for MeshFormat {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Ply => MeshFormat::Ply,
            FormatArg::Obj => MeshFormat::Obj,
            FormatArg::Stl => MeshFormat::Stl,
            FormatArg::Vtp => MeshFormat::Vtp,
        }
    }
}

/// Runs `flexiso extract`.
pub fn run(args: Args) -> anyhow::Result<()> {
    // Check what is cheap to check before the expensive work.
    let format = match (&args.out, args.format) {
        (None, _) => None,
        (Some(_), Some(f)) => Some(MeshFormat::from(f)),
        (Some(out), None) if super::is_stdio(out) => {
            bail!("--out - needs --format ply, obj, stl or vtp");
        }
        (Some(out), None) => Some(MeshFormat::from_path(out).with_context(|| {
            format!(
                "{}: unknown mesh format; use a .ply, .obj, .stl or .vtp file name, or --format",
                out.display()
            )
        })?),
    };
    if let Some(out) = &args.out {
        super::check_output(out)?;
    }
    let r = Report::new(args.out.as_deref().is_some_and(super::is_stdio));
    if !args.iso.is_finite() {
        bail!("--iso must be a finite number");
    }
    let bar = super::bar::StageBar::new();
    let t = Instant::now();
    bar.stage("reading");
    let volume = args.input.load()?;
    bar.done();
    let load = t.elapsed().as_secs_f64();
    let field = &volume.field;
    for w in &volume.warnings {
        r.warn(w);
    }
    let (lo, hi) = field.range();
    let h = args.iso;
    if !(lo..=hi).contains(&h) {
        bail!("--iso {h} is outside the volume's range [{lo}, {hi}]");
    }
    let [x, y, z] = field.dims();
    report!(
        r,
        "input:    {} ({}), {x} x {y} x {z}, values {lo} .. {hi} (load {load:.3} s)",
        volume.path.display(),
        volume.format
    );

    let t = Instant::now();
    let (tree, _) =
        ContourTree::from_field(field, bar.progress()).map_err(|e| anyhow::anyhow!("{e}"))?;
    let arcs = match args.simplify {
        Some(n) => Arcs::Simplified(n, args.measure),
        None => Arcs::Superarcs,
    };
    bar.stage(if args.simplify.is_some() {
        "simplification"
    } else {
        "arcs"
    });
    let targets = arcs.targets(&tree, field)?;
    bar.done();
    report!(
        r,
        "tree:     {} superarcs{} ({:.3} s)",
        tree.arcs().len(),
        match args.simplify {
            Some(_) => format!(", simplified to {} arcs by {}", targets.len(), args.measure),
            None => String::new(),
        },
        t.elapsed().as_secs_f64()
    );

    let iso = Isovalue::new(h);
    let path_seeds = PathSeeds::new();
    let t = Instant::now();
    let (found, seeds): (Vec<&Target>, Vec<PathSeed>) = match args.arc {
        Some((upper, lower)) => {
            let target = arcs.find(&targets, (upper, lower))?;
            let (top, bottom) = (field.value(upper), field.value(lower));
            let seed = path_seeds
                .seed_in_chain(&tree, field, &target.chain, iso)
                .with_context(|| {
                    format!(
                        "arc {upper}:{lower} has no contour at h = {h}: its contours span \
                         [{bottom}, {top}) (h = {top} is the next arc's)"
                    )
                })?;
            (vec![target], vec![seed])
        }
        None => targets
            .iter()
            .filter_map(|t| {
                let seed = path_seeds.seed_in_chain(&tree, field, &t.chain, iso)?;
                Some((t, seed))
            })
            .unzip(),
    };
    let seeding = t.elapsed().as_secs_f64();
    let t = Instant::now();
    bar.stage("extraction");
    let meshes = match seeds.as_slice() {
        // One contour on every core when it is large (the follower hands a
        // large one to the parallel sweep; see ContourFollower::extract).
        [seed] => vec![
            ContourFollower::new(field)
                .extract(&tree, seed, iso, &|| false)
                .unwrap_or_else(|_| ContourMesh::empty(seed.arc, iso.value)),
        ],
        _ => contour::contours_through(&tree, field, &seeds, iso),
    };
    let extract = t.elapsed().as_secs_f64();
    bar.done();
    let mut contours: Vec<(&Target, ContourMesh)> = found.into_iter().zip(meshes).collect();
    report!(
        r,
        "seeds:    {} of {} arcs span h, found in {seeding:.4} s ({:.2} us per arc tested)",
        seeds.len(),
        targets.len(),
        seeding * 1e6 / targets.len().max(1) as f64
    );
    contours.retain(|(_, m)| m.num_triangles() > 0);
    // What is written: closed contours facing out.
    bar.stage("orient");
    contours
        .par_iter_mut()
        .for_each(|(_, m)| m.orient_outward());
    bar.done();
    contours.sort_by_key(|(t, m)| (std::cmp::Reverse(m.num_triangles()), t.lower, t.upper));
    let triangles: usize = contours.iter().map(|(_, m)| m.num_triangles()).sum();
    report!(
        r,
        "extract:  h = {h}: {} contour(s), {triangles} triangles in {extract:.4} s ({:.2} M triangles/s{})",
        contours.len(),
        triangles as f64 / extract.max(1e-9) / 1e6,
        if seeds.len() == 1 {
            format!(", {} threads", rayon::current_num_threads())
        } else {
            String::new()
        }
    );

    let t = Instant::now();
    bar.stage("measures");
    let betti = ContourTopology::new(&tree, field);
    let topo: Vec<MeshTopology> = contours
        .par_iter()
        .map(|(_, m)| MeshTopology::of(&m.positions, &m.indices))
        .collect();
    bar.done();
    report!(
        r,
        "measure:  {:.3} s (Betti numbers of every superarc, topology of every contour)",
        t.elapsed().as_secs_f64()
    );
    report!(
        r,
        "{:>23} {:>10} {:>10} {:>14} {:>14} {:>6} {:>6} {:>12}",
        "arc",
        "triangles",
        "vertices",
        "area",
        "volume",
        "euler",
        "genus",
        "euler (tree)"
    );
    for ((target, mesh), t) in contours.iter().zip(&topo) {
        let predicted = betti.at(mesh.arc, field, iso);
        let volume = if t.is_closed() {
            format!("{:.6}", t.volume)
        } else {
            "open".to_string()
        };
        report!(
            r,
            "{:>23} {:>10} {:>10} {:>14.6} {:>14} {:>6} {:>6} {:>12}",
            format!("{}:{}", target.upper, target.lower),
            t.triangles,
            t.vertices,
            t.area,
            volume,
            t.euler,
            t.genus(),
            predicted.euler
        );
    }

    if let (Some(out), Some(format)) = (&args.out, format) {
        let t = Instant::now();
        bar.stage("writing");
        let names: Vec<String> = contours
            .iter()
            .map(|(t, _)| format!("arc_{}_{}", t.upper, t.lower))
            .collect();
        let mut meshes: Vec<ContourMesh> = contours.into_iter().map(|(_, m)| m).collect();
        for m in &mut meshes {
            m.to_frame(field, args.space.frame());
        }
        let note = format!(
            "space {}; flexiso extract --iso {h}",
            args.space.describe(field)
        );
        if super::is_stdio(out) {
            let mut bytes = Vec::new();
            write_mesh(&mut bytes, format, &meshes, &names, &note)
                .context("cannot encode the mesh")?;
            super::write_stdout(&bytes)?;
        } else {
            write_contours_as(out, format, &meshes, &names, &note)?;
        }
        bar.done();
        report!(
            r,
            "wrote:    {} ({} object(s), {:.3} s)",
            out.display(),
            meshes.len(),
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
