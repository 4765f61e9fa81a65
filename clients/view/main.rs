//! `tiltbox-view`: draw one world of a tiltbox daemon in the terminal, or print it as text.
//!
//! The binary's entry point only: the flags and the viewer are this directory's library
//! modules, `tiltbox::client::view`.

use clap::Parser;
use std::process::ExitCode;
use std::time::Duration;
use tiltbox::cli::{exit_code, init_logging, runtime};
use tiltbox::client::connect::ConnectArgs;
use tiltbox::client::view::{self, ViewArgs};
use tiltbox::client::{session, ClientError};

/// Draw a tiltbox world in the terminal (braille canvas, status line); q, Esc or Ctrl-C quits.
#[derive(Parser, Debug)]
#[command(name = "tiltbox-view", version, about)]
struct Cli {
    #[command(flatten)]
    connect: ConnectArgs,
    #[command(flatten)]
    view: ViewArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.connect.log.as_deref(), cli.view.default_log());
    exit_code(run(cli).map(|()| ExitCode::SUCCESS).map_err(Into::into))
}

fn run(cli: Cli) -> Result<(), ClientError> {
    let keys = cli.connect.keys()?;
    let endpoints = cli.connect.endpoints()?;
    let rt = runtime()?;
    let session = rt.block_on(session::open(&endpoints))?;
    let mut stdout = std::io::stdout();
    let endpoint = endpoints.join(", ");
    let result = view::run(
        rt.handle(),
        &session,
        &keys,
        &cli.view,
        &endpoint,
        &mut stdout,
    );
    rt.block_on(async {
        let _ = tokio::time::timeout(Duration::from_secs(1), session.close()).await;
    });
    rt.shutdown_timeout(Duration::from_millis(100));
    result
}
