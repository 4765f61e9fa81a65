//! `tiltbox report` (placeholder until its issue lands).

use std::process::ExitCode;

/// Arguments of `tiltbox report`.
#[derive(clap::Args, Default, Debug)]
pub struct ReportArgs {}

/// Run `tiltbox report`.
pub fn run(_args: ReportArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("tiltbox report is not built yet")
}
