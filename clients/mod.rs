//! The clients, `tiltbox-tilt` and `tiltbox-view` (and the viewer of `tiltbox demo`), as a
//! library: one directory per client under `clients/`, holding its binary's `main.rs` (flags
//! only) beside its modules, one per concept. Everything worth testing is reachable from
//! tests as `tiltbox::client::…`.
//!
//! - [`tilt`]: the tilt source: keyboard, sweep, stdin and IIO sources, and the publisher;
//! - [`view`]: the viewer: its copy of the world, the drawing, the terminal and plain loops;
//! - [`connect`]: the flags every client takes to find its daemon and world;
//! - [`session`]: opening a Zenoh session towards a daemon, watching its liveliness token;
//! - `web` (feature `web`): the `tiltbox-web` gateway, its page and its WebSocket wire.
//!
//! Logging, the runtime, signals and exit codes are the plumbing every binary shares,
//! [`crate::cli`]. The module needs the `net` and `cli` features (Zenoh, clap, serde_json);
//! drawing and the keyboard need `tui`.

pub mod connect;
pub mod session;
pub mod tilt;
pub mod view;
#[cfg(feature = "web")]
pub mod web;

/// What can go wrong in a client.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// Zenoh refused something (opening the session, declaring, putting).
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// A bad option value; the message names the flag and the value.
    #[error("{0}")]
    Usage(String),
    /// A terminal or file error.
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

impl ClientError {
    pub(crate) fn zenoh(what: &str) -> impl FnOnce(zenoh::Error) -> ClientError + '_ {
        move |e| ClientError::Zenoh(format!("{what}: {e}"))
    }
}

impl From<ClientError> for crate::cli::Failure {
    /// A bad flag is a usage error (exit 2); anything else a failure (exit 1).
    fn from(e: ClientError) -> crate::cli::Failure {
        match e {
            ClientError::Usage(message) => crate::cli::Failure::Usage(message),
            other => crate::cli::Failure::Failed(other.into()),
        }
    }
}
