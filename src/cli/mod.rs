//! The command line: one module per subcommand. Each has an `Args` (clap)
//! and a `run` that returns an error for the binary to print (exit code 2).

pub mod bench;
pub mod bench_engines;
pub mod extract;
pub mod info;
pub mod input;
pub mod open;
pub mod render;
pub mod tree;
