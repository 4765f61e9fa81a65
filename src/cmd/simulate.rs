//! `tiltbox simulate` (placeholder until its issue lands).

use std::process::ExitCode;

/// Arguments of `tiltbox simulate`.
#[derive(clap::Args, Default, Debug)]
pub struct SimulateArgs {}

/// Run `tiltbox simulate`.
pub fn run(_args: SimulateArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("tiltbox simulate is not built yet")
}
