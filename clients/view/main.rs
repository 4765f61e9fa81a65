//! `tiltbox-view`: draw one world of a tiltbox daemon in the terminal, or print it as text.
//!
//! A thin program: flags, a Zenoh session, then `tiltbox::client::viewer::run`.

use clap::Parser;
use std::process::ExitCode;
use tiltbox::client::args::{init_logging, ConnectArgs};
use tiltbox::client::viewer::{self, ViewOptions};
use tiltbox::client::{session, ClientError};

/// Draw a tiltbox world in the terminal (braille canvas, status line); q, Esc or Ctrl-C quits.
#[derive(Parser, Debug)]
#[command(name = "tiltbox-view", version, about)]
struct Cli {
    #[command(flatten)]
    connect: ConnectArgs,
    /// Print one line per snapshot instead: "frame time id:x,y,angle ..." (no control codes).
    #[arg(long)]
    plain: bool,
    /// With --plain: one line every N snapshots, listing what moved since the previous line.
    #[arg(long, value_name = "N", default_value_t = 1, requires = "plain",
          value_parser = clap::value_parser!(u64).range(1..))]
    every: u64,
    /// With --plain: stop after N lines.
    #[arg(long, value_name = "N", requires = "plain")]
    count: Option<u64>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.connect.log.as_deref().or(Some(if cli.plain {
        "warn,zenoh=error"
    } else {
        "error"
    })));
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(ClientError::Usage(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

fn run(cli: Cli) -> Result<(), ClientError> {
    let keys = cli.connect.keys()?;
    let endpoints = cli.connect.endpoints()?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let session = rt.block_on(session::open(&endpoints))?;
    let opts = ViewOptions {
        endpoint: endpoints.join(", "),
        plain: cli.plain,
        every: cli.every,
        count: cli.count,
    };
    let mut stdout = std::io::stdout();
    let result = viewer::run(rt.handle(), &session, &keys, &opts, &mut stdout);
    rt.block_on(async {
        let _ = tokio::time::timeout(std::time::Duration::from_secs(1), session.close()).await;
    });
    rt.shutdown_timeout(std::time::Duration::from_millis(100));
    result
}
