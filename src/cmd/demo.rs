//! `tiltbox demo`: the daemon and the text viewer in one process, so that a newcomer sees
//! bricks fall at once. Tilt it from another terminal with `tiltbox-tilt`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;
use tiltbox::client::session::{self, DEFAULT_ENDPOINT};
use tiltbox::client::viewer::{self, ViewOptions};
use tiltbox::service::{Server, ServerConfig, ServerOptions};

/// Arguments of `tiltbox demo`.
#[derive(clap::Args, Debug)]
pub struct DemoArgs {
    /// World name.
    #[arg(long, default_value = tiltbox::protocol::DEFAULT_WORLD)]
    pub world: String,
    /// Scene file (default: the embedded Falling Bricks).
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Where the daemon listens (tiltbox-tilt and other viewers connect there).
    #[arg(long, value_name = "ENDPOINT", default_value = DEFAULT_ENDPOINT)]
    pub listen: String,
    /// Print one line per snapshot instead of drawing (see tiltbox-view --plain).
    #[arg(long)]
    pub plain: bool,
    /// With --plain: one line every N snapshots.
    #[arg(long, value_name = "N", default_value_t = 1, requires = "plain",
          value_parser = clap::value_parser!(u64).range(1..))]
    pub every: u64,
    /// With --plain: stop after N lines.
    #[arg(long, value_name = "N", requires = "plain")]
    pub count: Option<u64>,
    /// Log filter (tracing EnvFilter syntax; RUST_LOG wins) [default: error, warn with --plain].
    #[arg(long, value_name = "FILTER")]
    pub log: Option<String>,
}

/// Run `tiltbox demo`.
pub fn run(args: DemoArgs) -> anyhow::Result<ExitCode> {
    let default_filter = if args.plain {
        "warn,zenoh=error"
    } else {
        "error"
    };
    tiltbox::client::args::init_logging(Some(args.log.as_deref().unwrap_or(default_filter)));
    let mut config = ServerConfig {
        world: args.world.clone(),
        scene: args.scene.clone(),
        ..ServerConfig::default()
    };
    config.zenoh.listen = vec![args.listen.clone()];
    if let Err(e) = config.validate() {
        eprintln!("error: {e}");
        return Ok(ExitCode::from(2));
    }
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let server = match rt.block_on(Server::start(&config, ServerOptions::default())) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: cannot start the daemon: {e}");
            return Ok(ExitCode::from(2));
        }
    };
    let keys = server.keys().clone();
    let endpoints = vec![args.listen.clone()];
    let result = rt.block_on(session::open(&endpoints)).and_then(|session| {
        let opts = ViewOptions {
            endpoint: args.listen.clone(),
            plain: args.plain,
            every: args.every,
            count: args.count,
        };
        let r = viewer::run(rt.handle(), &session, &keys, &opts, &mut std::io::stdout());
        rt.block_on(async {
            let _ = tokio::time::timeout(Duration::from_secs(1), session.close()).await;
        });
        r
    });
    rt.block_on(async {
        let _ = tokio::time::timeout(Duration::from_millis(1900), server.shutdown()).await;
    });
    rt.shutdown_timeout(Duration::from_millis(100));
    result?;
    Ok(ExitCode::SUCCESS)
}
