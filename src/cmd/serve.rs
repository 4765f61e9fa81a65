//! `tiltbox serve` (placeholder until its issue lands).

use std::process::ExitCode;

/// Arguments of `tiltbox serve`.
#[derive(clap::Args, Default, Debug)]
pub struct ServeArgs {}

/// Run `tiltbox serve`.
pub fn run(_args: ServeArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("tiltbox serve is not built yet")
}
