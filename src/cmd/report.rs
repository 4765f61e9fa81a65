//! `tiltbox report`: regenerate `docs/accuracy.md` and its charts (error against run time for
//! every accuracy case, and the stiff and extreme suite for both solvers).

use std::path::PathBuf;
use std::process::ExitCode;
use tiltbox::cli::Failure;
use tiltbox::measure::report::{generate, ReportOptions};

/// Arguments of `tiltbox report`.
#[derive(clap::Args, Default, Debug)]
pub struct ReportArgs {
    /// Directory for accuracy.md (charts go to <out>/img/).
    #[arg(long, default_value = "docs")]
    pub out: Option<PathBuf>,
    /// Short sweep (3 step sizes, 3 configurations, no repeats): a quick look, not for committing.
    #[arg(long)]
    pub quick: bool,
}

/// Run `tiltbox report`.
pub fn run(args: ReportArgs) -> Result<ExitCode, Failure> {
    if cfg!(debug_assertions) {
        eprintln!("note: this is a debug build; timings will be slow and unrepresentative (use --release)");
    }
    let options = ReportOptions {
        out: args.out.unwrap_or_else(|| PathBuf::from("docs")),
        quick: args.quick,
    };
    let report =
        generate(&options, &mut |what| eprintln!("report: {what}")).map_err(anyhow::Error::from)?;
    for (name, suite) in [
        ("soft step", &report.suite.soft_step),
        ("sequential", &report.suite.sequential),
        ("soft step, adaptive off", &report.suite.soft_step_fixed),
    ] {
        for v in suite {
            eprintln!("{name}: {}", v.summary());
        }
    }
    println!(
        "wrote {} and {} charts in {} ({:.0} s)",
        options.out.join("accuracy.md").display(),
        report.sweeps.len(),
        options.out.join("img").display(),
        report.seconds
    );
    Ok(ExitCode::SUCCESS)
}
