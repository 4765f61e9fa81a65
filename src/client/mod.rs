//! Library side of the two terminal clients, `tiltbox-tilt` and `tiltbox-view` (and of
//! `tiltbox demo`). The binaries in `clients/` only parse flags and call in here, so that
//! everything worth testing is reachable from tests.
//!
//! - [`session`]: opening a Zenoh session towards a daemon, watching its liveliness token.
//! - [`world`]: the viewer's copy of a world: `…/scene`, then snapshots and events.
//! - [`plain`]: the `--plain` text line per snapshot, and its parser.
//! - [`tilt`]: the tilt sources (sweep, stdin JSON, Linux IIO, keyboard state) and the
//!   publisher loop.
//! - `render` (feature `tui`): the pure drawing function, scene to ratatui buffer.
//! - `viewer` (feature `tui`): the terminal loop of `tiltbox-view`.
//! - [`args`]: the flags shared by both clients, and logging.
//! - `web` (feature `web`): the `tiltbox-web` gateway, its page and its WebSocket wire.
//!
//! The module needs the `net` and `cli` features (Zenoh, clap, serde_json).

pub mod args;
pub mod plain;
#[cfg(feature = "tui")]
pub mod render;
pub mod session;
pub mod tilt;
#[cfg(feature = "tui")]
pub mod viewer;
#[cfg(feature = "web")]
pub mod web;
pub mod world;

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
