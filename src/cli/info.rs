//! `flexiso info` (in progress).

/// Arguments of `flexiso info`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {}

/// Runs `flexiso info`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("flexiso info is not implemented yet")
}
