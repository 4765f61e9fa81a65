//! `tiltbox demo`: the daemon and the viewer in one process, so that a newcomer sees bricks
//! fall at once. Its keys drive the world as `tiltbox-view --control` does (arrows and
//! p/u/l/r/f/d tilt as in `tiltbox-tilt`, space drops a brick, R resets); `tiltbox-tilt` from
//! another terminal works too. The front end is the viewer's own (`tiltbox::client::view`),
//! with the same flags as `tiltbox-view`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;
use tiltbox::cli::{init_logging, runtime, Failure};
use tiltbox::client::session::{self, DEFAULT_ENDPOINT};
use tiltbox::client::view::{self, ViewArgs};
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
    /// How the world is shown.
    #[command(flatten)]
    pub view: ViewArgs,
    /// Log filter (tracing EnvFilter syntax; RUST_LOG wins) [default: error, warn with --plain].
    #[arg(long, value_name = "FILTER")]
    pub log: Option<String>,
}

/// Run `tiltbox demo`.
pub fn run(args: DemoArgs) -> Result<ExitCode, Failure> {
    init_logging(args.log.as_deref(), args.view.default_log());
    let mut config = ServerConfig {
        world: args.world.clone(),
        scene: args.scene.clone(),
        ..ServerConfig::default()
    };
    config.zenoh.listen = vec![args.listen.clone()];
    config.validate().map_err(Failure::usage)?;
    let rt = runtime().map_err(anyhow::Error::from)?;
    let server = rt
        .block_on(Server::start(&config, ServerOptions::default()))
        .map_err(|e| Failure::Usage(format!("cannot start the daemon: {e}")))?;
    let keys = server.keys().clone();
    let endpoints = vec![args.listen.clone()];
    // the demo's keys always drive the world (it is the demo's own daemon)
    let view_args = ViewArgs {
        control: !args.view.plain,
        ..args.view.clone()
    };
    let result = rt.block_on(session::open(&endpoints)).and_then(|session| {
        let shown = view::run(
            rt.handle(),
            &session,
            &keys,
            &view_args,
            &args.listen,
            &mut std::io::stdout(),
        );
        rt.block_on(async {
            let _ = tokio::time::timeout(Duration::from_secs(1), session.close()).await;
        });
        shown
    });
    rt.block_on(async {
        let _ = tokio::time::timeout(Duration::from_millis(1900), server.shutdown()).await;
    });
    rt.shutdown_timeout(Duration::from_millis(100));
    result.map_err(|e| Failure::Failed(e.into()))?;
    Ok(ExitCode::SUCCESS)
}
