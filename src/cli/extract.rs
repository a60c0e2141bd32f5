//! `flexiso extract` (in progress).

/// Arguments of `flexiso extract`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {}

/// Runs `flexiso extract`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("flexiso extract is not implemented yet")
}
