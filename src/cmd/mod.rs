//! The subcommands of the `tiltbox` binary; each is a thin layer over the library.

#[cfg(all(feature = "net", feature = "tui"))]
pub mod demo;
#[cfg(feature = "net")]
pub mod replay;
#[cfg(feature = "report")]
pub mod report;
#[cfg(feature = "net")]
pub mod serve;
pub mod simulate;
#[cfg(feature = "net")]
mod simulate_scheduled;
