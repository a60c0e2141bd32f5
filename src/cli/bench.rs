//! `flexiso bench` (in progress).

/// Arguments of `flexiso bench`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {}

/// Runs `flexiso bench`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("flexiso bench is not implemented yet")
}
