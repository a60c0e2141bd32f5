//! The flexiso program: the explorer window, and the same engine headless.

use clap::{Parser, Subcommand};
use flexiso::cli;

/// Explore 3D scalar volumes through their contour tree.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
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

fn main() {
    let cli = Cli::parse();
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
