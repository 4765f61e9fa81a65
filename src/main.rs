//! `tiltbox`: the daemon and its tools (simulate, report, serve).

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use tiltbox::cli::exit_code;

mod cmd;

/// A 2D rigid-body physics engine served over Eclipse Zenoh.
#[derive(Parser)]
#[command(name = "tiltbox", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

// Parsed once at start-up: the size difference between variants does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
enum Command {
    /// Run the daemon: step a scene at a fixed rate and serve it over Zenoh (the default).
    #[cfg(feature = "net")]
    Serve(cmd::serve::ServeArgs),
    /// Replay a command journal (`serve --record LOG`) and check every frame is bit-identical.
    #[cfg(feature = "net")]
    Replay(cmd::replay::ReplayArgs),
    /// Start the daemon and the text viewer in one process: bricks fall at once.
    #[cfg(all(feature = "net", feature = "tui"))]
    Demo(cmd::demo::DemoArgs),
    /// Step a scene headless and print poses.
    Simulate(cmd::simulate::SimulateArgs),
    /// Regenerate docs/accuracy.md and its charts: error against run time, stiff and extreme cases.
    #[cfg(feature = "report")]
    Report(cmd::report::ReportArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    exit_code(match cli.command {
        #[cfg(feature = "net")]
        None => cmd::serve::run(cmd::serve::ServeArgs::default()),
        #[cfg(not(feature = "net"))]
        None => {
            use clap::CommandFactory;
            let _ = Cli::command().print_help();
            Ok(ExitCode::from(2))
        }
        #[cfg(feature = "net")]
        Some(Command::Serve(args)) => cmd::serve::run(args),
        #[cfg(feature = "net")]
        Some(Command::Replay(args)) => cmd::replay::run(args),
        #[cfg(all(feature = "net", feature = "tui"))]
        Some(Command::Demo(args)) => cmd::demo::run(args),
        Some(Command::Simulate(args)) => cmd::simulate::run(args),
        #[cfg(feature = "report")]
        Some(Command::Report(args)) => cmd::report::run(args),
    })
}
