//! The daemon: one World stepped at a fixed rate on its own thread, served over Zenoh.
//!
//! - `config`: `config/server.toml`, flags and embedded defaults ([`ServerConfig`]).
//! - `wire`: the one boundary between wire messages and the engine: a command payload
//!   decoded and every field validated ([`parse_command`]), engine shapes and bodies in
//!   their wire form ([`BodyMeta`]).
//! - `command`: validated commands ([`Command`]) and the channel that carries them from the
//!   Zenoh callbacks to the tick thread ([`Intake`]).
//! - `sim`: the World and everything the daemon keeps about it ([`Simulation`]): applying
//!   commands, snapshot deltas, the full state for late joiners, recovery from engine
//!   failures.
//! - `tick`: the fixed-rate loop ([`run_loop`], [`Outputs`]); `scene_query`: late joiners'
//!   `…/scene` queries, answered by the tick thread only when one waits; `world_query`:
//!   `…/query` rays, points and boxes, answered the same way.
//! - `net`: the Zenoh session, declarations and shutdown ([`Server`]).
//! - `bench`: the `bench-net` measurement ([`bench_net`]).
//! - [`checkpoint`] and [`journal`]: the daemon's files (checkpoints and resume; the command
//!   journal and deterministic replay), whose errors are [`FileError`]s.
//! - [`timeline`]: commands scheduled at simulated times for `tiltbox simulate`, validated
//!   and applied as the daemon's are.

mod bench;
pub mod checkpoint;
mod command;
mod config;
mod files;
pub mod journal;
mod net;
mod scene_query;
mod sim;
mod tick;
pub mod timeline;
mod wire;
mod world_query;

pub use bench::{bench_net, gas_scene, BenchReport};
pub use command::{Command, DroppedCounts, Incoming, Intake, SpawnDef};
pub use config::{ConfigError, Limits, ServerConfig, ZenohSettings};
pub use files::FileError;
pub use net::{
    shutdown_worlds, start_worlds, world_configs, PublishHook, Server, ServerOptions, ServiceError,
};
pub use sim::{SceneSource, SimState, Simulation, StartError, MAX_PHYSICS_EVENTS};
pub use tick::{run as run_loop, Outputs, Recording, RunSummary, TickConfig};
pub use wire::{check_query, parse_command, BodyMeta};
pub use world_query::{MAX_HITS, MAX_PENDING};
