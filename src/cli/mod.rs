//! The command line: one module per subcommand. Each has an `Args` (clap)
//! and a `run` that returns an error for the binary to print once (exit
//! code 2).
//!
//! Streams: a command's product (a file, or standard output when its path
//! is `-`) is the only thing on standard output when it goes there; the
//! report (statistics, timings) then goes to standard error, and nowhere
//! with `-q` ([`Report`]). Output paths are checked before the work
//! ([`check_output`]). Stages longer than half a second show a progress
//! bar on standard error when it is a terminal ([`bar`]).

use std::io::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

pub mod arcs;
pub mod bar;
pub mod bench;
pub mod bench_engines;
pub mod extract;
pub mod info;
pub mod input;
pub mod open;
pub mod render;
pub mod tree;

/// `--space`: the coordinates a command writes positions in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SpaceArg {
    /// The file's world: origin, direction and spacing, in the space the
    /// file names (LPS, RAS), so the output lines up with the volume in 3D
    /// Slicer, ParaView or ITK-SNAP.
    #[default]
    World,
    /// Voxel indices (i, j, k).
    Index,
}

impl SpaceArg {
    /// The frame the library moves meshes into.
    pub fn frame(self) -> crate::contour::Frame {
        match self {
            SpaceArg::World => crate::contour::Frame::World,
            SpaceArg::Index => crate::contour::Frame::Index,
        }
    }

    /// The position of vertex `v` of `field` in this space.
    pub fn position(self, field: &crate::field::ScalarField, v: u32) -> [f64; 3] {
        match self {
            SpaceArg::World => field.world_position(v),
            SpaceArg::Index => field.coords(v).map(|c| c as f64),
        }
    }

    /// What to name the space in a file: "LPS", "RAS", "unnamed" (world),
    /// or "index".
    pub fn describe(self, field: &crate::field::ScalarField) -> &'static str {
        match self {
            SpaceArg::World => field.geometry().space.name(),
            SpaceArg::Index => "index",
        }
    }
}

static QUIET: AtomicBool = AtomicBool::new(false);

/// `-q`/`--quiet`: no report, no warnings; errors still print.
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// Whether `-q` was given.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// True when the output `path` is standard output: `-`, or one of the
/// names the system gives it (`/dev/stdout`, `/dev/fd/1`,
/// `/proc/self/fd/1`), so that it is written as `-` is (the report on
/// standard error, a reader that stops early not an error).
pub fn is_stdio(path: &Path) -> bool {
    ["-", "/dev/stdout", "/dev/fd/1", "/proc/self/fd/1"]
        .iter()
        .any(|name| path.as_os_str() == *name)
}

/// Where a command's report goes: standard output, or standard error when
/// standard output carries the product, or nowhere with `-q`. A closed
/// stream (`| head`) is ignored: the report is not the product.
#[derive(Clone, Copy, Debug)]
pub struct Report {
    to_stderr: bool,
    quiet: bool,
}

impl Report {
    /// A report for a command whose product goes to standard output when
    /// `product_on_stdout`.
    pub fn new(product_on_stdout: bool) -> Self {
        Report {
            to_stderr: product_on_stdout,
            quiet: quiet(),
        }
    }

    /// Prints one line of the report.
    pub fn line(&self, args: std::fmt::Arguments<'_>) {
        if self.quiet {
            return;
        }
        if self.to_stderr {
            let _ = writeln!(std::io::stderr().lock(), "{args}");
        } else {
            let _ = writeln!(std::io::stdout().lock(), "{args}");
        }
    }

    /// Prints a warning (always on standard error, unless `-q`).
    pub fn warn(&self, warning: &str) {
        if !self.quiet {
            let _ = writeln!(std::io::stderr().lock(), "warning: {warning}");
        }
    }
}

/// `report!(r, "...", args)`: one line of a [`Report`].
#[macro_export]
macro_rules! report {
    ($r:expr, $($t:tt)*) => {
        $r.line(format_args!($($t)*))
    };
}

/// Checks, before any work, that `path` can be written: `-`, or a file
/// (new or not) in a folder that exists. The error says which.
pub fn check_output(path: &Path) -> anyhow::Result<()> {
    if is_stdio(path) {
        return Ok(());
    }
    if path.is_dir() {
        anyhow::bail!("{}: is a folder, not a file to write", path.display());
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        anyhow::bail!(
            "{}: cannot write: the folder {} does not exist",
            path.display(),
            parent.display()
        );
    }
    if let Ok(meta) = std::fs::metadata(path)
        && meta.permissions().readonly()
    {
        anyhow::bail!("{}: cannot write: the file is read-only", path.display());
    }
    Ok(())
}

/// Writes `bytes` to standard output, all at once; a closed pipe is an
/// error (the product did not arrive).
pub fn write_stdout(bytes: &[u8]) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(bytes)
        .and_then(|_| out.flush())
        .map_err(|e| anyhow::anyhow!("standard output: cannot write: {e}"))
}
