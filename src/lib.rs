//! tiltbox: a 2D rigid-body physics engine written from scratch, served as a daemon over
//! Eclipse Zenoh.
//!
//! - [`physics`]: the engine (no async, no network); all that `--no-default-features` builds.
//! - `scene` (feature `scene`): TOML scene files to Worlds.
//! - `protocol` (feature `net`): the wire messages and key expressions.
//! - `service` (feature `net`): the daemon.
//! - `cli` (feature `cli`): what every binary shares: logging, runtime, signals, exit codes.
//! - `client` (features `net` and `cli`): the clients, one directory each under `clients/`.
//! - `measure` (feature `measure`): set-ups, accuracy runners and the report.
#[cfg(feature = "cli")]
pub mod cli;
#[cfg(all(feature = "net", feature = "cli"))]
#[path = "../clients/mod.rs"]
pub mod client;
#[cfg(feature = "measure")]
pub mod measure;
pub mod physics;
#[cfg(feature = "net")]
pub mod protocol;
#[cfg(feature = "scene")]
pub mod scene;
#[cfg(feature = "net")]
pub mod service;
