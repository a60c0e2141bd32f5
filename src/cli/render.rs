//! `flexiso render` (in progress).

/// Arguments of `flexiso render`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {}

/// Runs `flexiso render`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("flexiso render is not implemented yet")
}
