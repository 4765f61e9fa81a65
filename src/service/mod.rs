//! The daemon: one World stepped at a fixed rate on its own thread, served over Zenoh.
//!
//! - [`config`]: `config/server.toml`, flags and embedded defaults.
//! - [`intake`]: what the Zenoh callbacks do with a payload (decode, validate, queue).
//! - [`sim`]: the World and how commands are applied; snapshot deltas; the shared scene view.
//! - [`tick`]: the fixed-rate loop.
//! - [`net`]: the Zenoh session, declarations and shutdown ([`Server`]).
//! - [`mod@bench`]: the `bench-net` measurement.
//! - [`checkpoint`]: the full state in an atomically replaced, versioned file; resume.
//! - [`journal`]: the command journal and deterministic replay.

pub mod bench;
pub mod checkpoint;
pub mod config;
pub mod intake;
pub mod journal;
pub mod net;
pub mod sim;
pub mod tick;

pub use config::{ConfigError, Limits, ServerConfig, ZenohSettings};
pub use intake::{Command, Incoming, SpawnDef};
pub use net::{
    shutdown_worlds, start_worlds, world_configs, PublishHook, Server, ServerOptions, ServiceError,
};
pub use sim::{SceneSource, SceneView, SimState, Simulation, StartError, POSE_EPSILON};
pub use tick::RunSummary;
