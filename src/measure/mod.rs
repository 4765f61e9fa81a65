//! Measurement: tools about the engine, not the engine (feature `measure`, in the default set;
//! the engine-only build, `--no-default-features`, leaves all of it out).
//!
//! - [`cases`]: every set-up the tests, runners, report and benchmarks build (grounds, stacks,
//!   pyramids, closed boxes, Falling Bricks, mixed shapes, the benchmark scenes).
//! - [`accuracy`]: runners that run a case and return numbers (closed forms, reference runs,
//!   the stiff and extreme suite) and the sweeps over step sizes and configurations.
//! - [`machine`]: the CPU a measurement ran on.
//! - `report` (feature `report`): charts and `docs/accuracy.md` from what the sweeps return.
//!
//! The side-by-side comparison with Box2D v3 and rapier2d is its own crate, `benchmarks/vs-peers`, built
//! on [`cases::benchmark_setups`].

pub mod accuracy;
pub mod cases;
pub mod machine;
#[cfg(feature = "report")]
pub mod report;
