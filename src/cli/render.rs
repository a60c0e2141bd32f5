//! `flexiso render`: contours of a volume drawn offscreen into a PNG, with
//! the same renderer as the explorer's 3D view (no window needed; works on
//! software adapters).
//!
//! What is drawn: with `--arc UPPER:LOWER` the single contour of that
//! superarc at `--iso` (default: the middle of the arc's value range);
//! otherwise every contour at `--iso` (default: the middle of the value
//! range), each in its own colour. With `--session S.json`, the session's
//! visible contours in their colours, from its camera, with its slices,
//! clipping plane and cut-away box, a legend of the contours' names (unless the
//! session's view switches it off, or `--no-legend`) and each contour's
//! name beside it when the session's view shows labels (unless
//! `--no-labels`): the explorer's picture of that scene.

use std::path::PathBuf;

use anyhow::{Context, bail};

use super::arcs::{Arcs, Target, parse_arc};
use super::input::InputArgs;
use crate::contour;
use crate::field::Isovalue;
use crate::render::{Camera, HeadlessMesh};
use crate::tree::ContourTree;

/// Arguments of `flexiso render`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// The volume.
    #[command(flatten)]
    pub input: InputArgs,
    /// Where to write the PNG (`-`: standard output).
    #[arg(long, short, value_name = "PNG", default_value = "flexiso.png")]
    pub out: PathBuf,
    /// Isovalue (default: the middle of the arc's or the volume's range).
    #[arg(long, value_name = "H")]
    pub iso: Option<f64>,
    /// Draw only the contour of the superarc between these two critical
    /// vertices (mesh vertex ids, as `flexiso tree --json` lists them).
    #[arg(long, value_name = "UPPER:LOWER", value_parser = parse_arc)]
    pub arc: Option<(u32, u32)>,
    /// Image size in pixels.
    #[arg(long, value_name = "WxH", value_parser = parse_size, default_value = "1024x768")]
    pub size: Option<(u32, u32)>,
    /// Camera angle around the vertical (z) axis, degrees.
    #[arg(long, default_value_t = -60.0, allow_negative_numbers = true)]
    pub yaw: f32,
    /// Camera elevation, degrees.
    #[arg(long, default_value_t = 25.0, allow_negative_numbers = true)]
    pub pitch: f32,
    /// Draw this session's scene (its volume replaces INPUT; --iso and
    /// --arc do not apply; its camera replaces --yaw and --pitch).
    #[arg(long, value_name = "JSON", conflicts_with_all = ["iso", "arc"])]
    pub session: Option<PathBuf>,
    /// Leave out the legend a session's picture carries.
    #[arg(long)]
    pub no_legend: bool,
    /// Leave out the contours' name labels a session's picture carries
    /// (when its view shows them).
    #[arg(long)]
    pub no_labels: bool,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WxH (e.g. 1024x768)"))?;
    let n = |t: &str| match t.trim().parse::<u32>() {
        Ok(v) if (1..=16384).contains(&v) => Ok(v),
        _ => Err(format!("'{t}' is not a size between 1 and 16384")),
    };
    Ok((n(w)?, n(h)?))
}

/// A triangle mesh to draw.
struct Surface {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

/// Gives the process a private `XDG_RUNTIME_DIR` when it has none (or not
/// an absolute path), before any thread starts. wgpu's Vulkan and GL
/// back-ends load libwayland-client, which prints "error: XDG_RUNTIME_DIR
/// is invalid or not set in the environment." on standard error when it
/// looks for a compositor's socket there: on a successful headless render
/// that line is noise (and scares users). The folder is
/// `$TMPDIR/flexiso-runtime-UID`, mode 0700, made once and reused; it holds
/// no socket, so the lookup simply finds no compositor.
pub fn ensure_runtime_dir() {
    let valid = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| {
        std::path::Path::new(&d).is_absolute() && std::path::Path::new(&d).is_dir()
    });
    if valid {
        return;
    }
    if let Some(dir) = private_runtime_dir() {
        // SAFETY: called first thing in `run`, before this process starts
        // any thread (the engine's pool, the renderer's), so nothing reads
        // the environment concurrently.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", dir) };
    }
}

#[cfg(target_os = "linux")]
fn private_runtime_dir() -> Option<PathBuf> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    // SAFETY: getuid has no preconditions and cannot fail.
    let uid = unsafe { libc::getuid() };
    let dir = std::env::temp_dir().join(format!("flexiso-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let meta = std::fs::symlink_metadata(&dir).ok()?;
    let ours = meta.is_dir() && meta.uid() == uid && meta.permissions().mode() & 0o077 == 0;
    ours.then_some(dir)
}

#[cfg(not(target_os = "linux"))]
fn private_runtime_dir() -> Option<PathBuf> {
    None
}

/// Runs `flexiso render`.
pub fn run(args: Args) -> anyhow::Result<()> {
    ensure_runtime_dir();
    let (width, height) = args.size.unwrap_or((1024, 768));
    super::check_output(&args.out)?;
    // The report goes to standard error: the picture is the product.
    let r = super::Report::new(true);
    let bar = super::bar::StageBar::new();
    let session = match &args.session {
        Some(p) => Some((crate::session::Session::read(p)?, p.clone())),
        None => None,
    };
    let volume = match &session {
        Some((s, p)) => crate::field::source::VolumeSource::parse(
            &s.volume_input(p),
            crate::field::io::ReadOptions::default(),
        )?
        .load()?,
        None => {
            bar.stage("reading");
            let v = args.input.load()?;
            bar.done();
            v
        }
    };
    let field = &volume.field;
    for w in &volume.warnings {
        r.warn(w);
    }
    let (tree, _) =
        ContourTree::from_field(field, bar.progress()).map_err(|e| anyhow::anyhow!("{e}"))?;
    bar.done();

    let (lo, hi) = field.range();
    let mut colours = Vec::new();
    let mut names = Vec::new();
    let surfaces = if let Some((s, _)) = &session {
        let placed = s.place(&tree, field);
        for p in &placed.problems {
            r.warn(p);
        }
        let mut surfaces = Vec::new();
        for (i, c) in placed
            .contours
            .iter()
            .enumerate()
            .filter(|(_, c)| c.visible)
        {
            let iso = Isovalue::new(c.isovalue);
            let Some(seed) = contour::path_seed_in_chain(&tree, field, &[c.superarc], iso) else {
                continue;
            };
            surfaces.push(surface(
                contour::ContourFollower::new(field).follow(&seed, iso),
            ));
            names.push(if c.name.trim().is_empty() {
                format!("contour {i}")
            } else {
                c.name.clone()
            });
            colours.push(match c.colour {
                Some(rgb) => rgb.map(|v| f32::from(v) / 255.0),
                None => {
                    let [r, g, b, _] = crate::render::palette_rgba(i);
                    [r, g, b]
                }
            });
        }
        surfaces
    } else {
        match args.arc {
            Some(ends) => {
                let targets = Arcs::Superarcs.targets(&tree, field)?;
                let target = Arcs::Superarcs.find(&targets, ends)?;
                let (upper, lower) = ends;
                let (top, bottom) = (field.value(upper), field.value(lower));
                let h = args.iso.unwrap_or(0.5 * (top + bottom));
                if !(bottom..=top).contains(&h) {
                    bail!(
                        "--iso {h} is outside the arc's range [{bottom}, {top}]: its contour \
                     exists only for values in that range"
                    );
                }
                crate::report!(r, "arc {upper}:{lower} at h = {h}");
                arc_contour(field, &tree, target, h)?
            }
            None => {
                let h = args.iso.unwrap_or(0.5 * (lo + hi));
                if !(lo..=hi).contains(&h) {
                    bail!("--iso {h} is outside the volume's range [{lo}, {hi}]");
                }
                crate::report!(r, "all contours at h = {h}");
                all_contours(field, &tree, h)?
            }
        }
    };
    let triangles: usize = surfaces.iter().map(|s| s.indices.len() / 3).sum();
    crate::report!(r, "{} contour(s), {triangles} triangles", surfaces.len());

    // The grid frame, placed in the world as the window places it.
    let bounds = crate::render::grid_bounds(field.dims(), field.spacing());
    let placement = crate::render::placement(field);
    let meshes: Vec<HeadlessMesh<'_>> = surfaces
        .iter()
        .enumerate()
        .map(|(i, s)| HeadlessMesh {
            positions: &s.positions,
            normals: &s.normals,
            indices: &s.indices,
            colour: match colours.get(i) {
                Some(&[r, g, b]) => [r, g, b, 1.0],
                None => crate::render::palette_rgba(i),
            },
        })
        .collect();
    let mut camera = Camera {
        yaw: args.yaw.to_radians(),
        pitch: args.pitch.to_radians(),
        ..Camera::default()
    };
    let placed = crate::render::placed_box(placement, bounds.0, bounds.1);
    camera.fit(placed.0, placed.1);
    if let Some(c) = session.as_ref().and_then(|(s, _)| s.camera) {
        // Fitted first for the scene's radius (near and far planes), as
        // the explorer's camera is.
        camera.target = c.target.into();
        camera.distance = c.distance.max(1e-6);
        camera.yaw = c.yaw;
        camera.pitch = c.pitch;
        camera.fov_y = c.fov_y;
    }
    let mut scene = crate::render::HeadlessScene {
        meshes,
        bounds: Some(bounds),
        camera: Some(camera),
        placement: Some(placement),
        ..Default::default()
    };
    let mut legend = Vec::new();
    let mut labels = Vec::new();
    if let Some((s, _)) = &session {
        let rgb = |i: usize| {
            let [r, g, b, _] = scene.meshes[i].colour;
            [r, g, b].map(|c| (c * 255.0).round() as u8)
        };
        let spacing = field.spacing();
        for (axis, index) in s.slices.unwrap_or_default().as_array().iter().enumerate() {
            let Some(index) = *index else { continue };
            let slice = crate::field::slice::Slice::of(field, axis, index);
            let at = slice.position(spacing);
            let segments: Vec<Vec<[[f32; 2]; 2]>> = surfaces
                .iter()
                .map(|m| contour::section::axis_section(&m.positions, &m.indices, axis, at))
                .collect();
            let sections: Vec<crate::render::overlay::Section<'_>> = segments
                .iter()
                .enumerate()
                .map(|(i, segs)| crate::render::overlay::Section {
                    segments: segs,
                    colour: rgb(i),
                })
                .collect();
            let longest = slice.width.max(slice.height).max(1);
            let upscale = 512usize.div_ceil(longest).clamp(1, 4) as u32;
            let image = crate::render::overlay::slice_image(
                &slice,
                spacing,
                upscale,
                &sections,
                (upscale as f32).max(2.0),
            );
            scene.slices.push(crate::render::SliceQuad {
                corners: slice.corners(spacing),
                image: std::sync::Arc::new(image),
            });
        }
        if let Some(c) = &s.clip {
            let axis = c
                .axis_index()
                .with_context(|| format!("session: clip axis '{}' is not x, y or z", c.axis))?;
            let at = bounds.0[axis] + c.at.clamp(0.0, 1.0) * (bounds.1[axis] - bounds.0[axis]);
            scene.clip = Some(crate::render::ClipPlane::axis(axis, at, c.keep_below()));
        }
        if let Some(b) = &s.cut_box {
            let (lo, hi) = b.world(bounds.0, bounds.1);
            scene.cut_box = Some(crate::render::CutBox { lo, hi });
        }
        if !args.no_labels && s.view.unwrap_or_default().labels {
            let camera = scene.camera.unwrap_or_default();
            let vp = camera.view_proj(width as f32 / height.max(1) as f32) * placement;
            labels = surfaces
                .iter()
                .enumerate()
                .filter_map(|(i, m)| {
                    let anchor =
                        crate::render::label_anchor(&m.positions, scene.clip, scene.cut_box)?;
                    Some(crate::render::overlay::ImageLabel {
                        text: names[i].clone(),
                        colour: rgb(i),
                        at: crate::render::overlay::project_to_image(vp, anchor, width, height)?,
                    })
                })
                .collect();
        }
        if !args.no_legend && s.view.unwrap_or_default().legend {
            legend = names
                .iter()
                .enumerate()
                .map(|(i, n)| crate::render::overlay::LegendEntry {
                    name: n.clone(),
                    colour: rgb(i),
                })
                .collect();
        }
    }
    let mut img =
        crate::render::render_scene_to_image(&scene, width, height).context("rendering failed")?;
    crate::render::overlay::draw_labels(&mut img, &labels);
    crate::render::overlay::draw_legend(&mut img, &legend);
    if super::is_stdio(&args.out) {
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .context("cannot encode the PNG")?;
        super::write_stdout(&png)?;
    } else {
        crate::output::save_image(&args.out, &img)
            .with_context(|| format!("{}: cannot write", args.out.display()))?;
    }
    crate::report!(r, "wrote {} ({width}x{height})", args.out.display());
    Ok(())
}

/// The contour of one arc at `h`.
fn arc_contour(
    field: &crate::field::ScalarField,
    tree: &ContourTree,
    target: &Target,
    h: f64,
) -> anyhow::Result<Vec<Surface>> {
    let iso = Isovalue::new(h);
    let seed = contour::path_seed_in_chain(tree, field, &target.chain, iso).with_context(|| {
        format!("the arc has no contour at h = {h} (it spans h only strictly inside its range)")
    })?;
    let mesh = contour::ContourFollower::new(field).follow(&seed, iso);
    Ok(vec![surface(mesh)])
}

/// Every contour at `h`, one per spanning superarc, by arc id.
fn all_contours(
    field: &crate::field::ScalarField,
    tree: &ContourTree,
    h: f64,
) -> anyhow::Result<Vec<Surface>> {
    Ok(contour::all_contours(tree, field, Isovalue::new(h))
        .into_iter()
        .filter(|m| !m.indices.is_empty())
        .map(surface)
        .collect())
}

fn surface(m: contour::ContourMesh) -> Surface {
    Surface {
        positions: m.positions,
        normals: m.normals,
        indices: m.indices,
    }
}
