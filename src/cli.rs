//! What every command-line program of tiltbox shares (`tiltbox` and its subcommands, the
//! clients): logging to stderr, the tokio runtime, waiting for Ctrl-C or SIGTERM, and how a
//! run ends: a usage error (a bad flag, config value or input file) exits 2, any other
//! failure 1, each printed once as `error: ...`.

use std::io::IsTerminal;
use std::process::ExitCode;

/// Log to stderr with `filter` (tracing's `EnvFilter` syntax), or `default` when `None`;
/// `RUST_LOG` wins over both. Colours only when stderr is a terminal, so logs piped to a
/// file or another program are plain text.
pub fn init_logging(filter: Option<&str>, default: &str) {
    use tracing_subscriber::EnvFilter;
    let filter = EnvFilter::try_from_default_env()
        .or_else(|_| EnvFilter::try_new(filter.unwrap_or(default)))
        .unwrap_or_else(|_| EnvFilter::new("info"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(std::io::stderr().is_terminal())
        .with_writer(std::io::stderr)
        .try_init();
}

/// The runtime every networked program runs on: multi-threaded (Zenoh panics on a
/// current-thread runtime), two workers.
#[cfg(feature = "net")]
pub fn runtime() -> std::io::Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
}

/// Returns on Ctrl-C or (on Unix) SIGTERM.
#[cfg(feature = "net")]
pub async fn wait_for_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{signal, SignalKind};
        if let Ok(mut term) = signal(SignalKind::terminate()) {
            tokio::select! {
                _ = tokio::signal::ctrl_c() => {}
                _ = term.recv() => {}
            }
            return;
        }
    }
    let _ = tokio::signal::ctrl_c().await;
}

/// Why a run stopped before its work was done.
#[derive(Debug, thiserror::Error)]
pub enum Failure {
    /// What was asked cannot be done as asked: a bad flag, config value or input file. The
    /// message names it and its value. Exit code 2.
    #[error("{0}")]
    Usage(String),
    /// Anything else (the network, the terminal, a file that cannot be written). Exit code 1.
    #[error(transparent)]
    Failed(#[from] anyhow::Error),
}

impl Failure {
    /// A [`Failure::Usage`] from anything that says what is wrong.
    pub fn usage(e: impl std::fmt::Display) -> Failure {
        Failure::Usage(e.to_string())
    }
}

/// The process's exit code for a run: its own code when it finished, else 2 for a usage
/// error and 1 for any other failure, printed once on stderr as `error: ...` (with its causes).
pub fn exit_code(result: Result<ExitCode, Failure>) -> ExitCode {
    match result {
        Ok(code) => code,
        Err(Failure::Usage(message)) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
        Err(Failure::Failed(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}
