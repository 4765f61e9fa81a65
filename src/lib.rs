//! tiltbox: a 2D rigid-body physics engine written from scratch, served as a daemon over
//! Eclipse Zenoh.
//!
//! - [`physics`]: the engine (no async, no network).
pub mod accuracy;
pub mod cases;
#[cfg(all(feature = "net", feature = "cli"))]
pub mod client;
pub mod physics;
#[cfg(feature = "net")]
pub mod protocol;
#[cfg(feature = "report")]
pub mod report;
#[cfg(feature = "scene")]
pub mod scene;
#[cfg(feature = "net")]
pub mod service;
