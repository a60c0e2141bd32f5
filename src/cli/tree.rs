//! `flexiso tree` (in progress).

/// Arguments of `flexiso tree`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {}

/// Runs `flexiso tree`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("flexiso tree is not implemented yet")
}
