//! The flexiso program: the explorer window, and the same engine headless.

use clap::{Parser, Subcommand};
use flexiso::cli;

/// Explore 3D scalar volumes through their contour tree.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Print nothing but errors (and the product, where it goes to
    /// standard output).
    #[arg(short, long, global = true)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Open the explorer window on a volume (or the built-in dataset).
    Open(cli::open::Args),
    /// Compute the contour tree and print its statistics (and JSON).
    Tree(cli::tree::Args),
    /// Extract contours as triangle meshes (PLY, OBJ, STL).
    Extract(cli::extract::Args),
    /// Render contours offscreen to a PNG.
    Render(cli::render::Args),
    /// Print what a volume file holds.
    Info(cli::info::Args),
    /// Benchmark the engine on every volume in a folder.
    Bench(cli::bench::Args),
}

/// Where the explorer cannot open a window, what to do instead.
const NO_DISPLAY: &str = "no display to open the explorer's window on (neither DISPLAY nor \
WAYLAND_DISPLAY is set). Without a window use the headless commands: flexiso info FILE, \
flexiso tree FILE --json -, flexiso extract FILE --iso H --out mesh.ply, flexiso render FILE \
--out shot.png (flexiso --help lists them); or run the window under Xvfb (xvfb-run flexiso)";

/// True where a window cannot open: Linux and the BSDs without an X11 or
/// Wayland display named in the environment.
fn no_display() -> bool {
    cfg!(all(unix, not(target_os = "macos")))
        && std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty())
        && std::env::var_os("WAYLAND_DISPLAY").is_none_or(|d| d.is_empty())
}

fn main() {
    flexiso::pages::return_freed_arrays();
    let cli = Cli::parse();
    cli::set_quiet(cli.quiet);
    if matches!(cli.command, None | Some(Command::Open(_))) && no_display() {
        eprintln!("error: {NO_DISPLAY}");
        std::process::exit(2);
    }
    let result = match cli.command {
        None => cli::open::run(cli::open::Args::default()),
        Some(Command::Open(a)) => cli::open::run(a),
        Some(Command::Tree(a)) => cli::tree::run(a),
        Some(Command::Extract(a)) => cli::extract::run(a),
        Some(Command::Render(a)) => cli::render::run(a),
        Some(Command::Info(a)) => cli::info::run(a),
        Some(Command::Bench(a)) => cli::bench::run(a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(2);
    }
}
