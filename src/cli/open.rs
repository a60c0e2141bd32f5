//! `flexiso open` (in progress).

/// Arguments of `flexiso open`.
#[derive(clap::Args, Debug, Default)]
pub struct Args {}

/// Runs `flexiso open`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("flexiso open is not implemented yet")
}
