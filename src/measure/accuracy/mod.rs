//! Accuracy and stability runners: they run cases and return numbers, not documents.
//!
//! Three families, all built from [`crate::physics`] and the set-ups of [`super::cases`]:
//!
//! - [`closed_form`]: cases with an analytic answer (free fall, slide to a stop, slopes, bounce,
//!   head-on collision, spin under torque, resting stack), and [`joint_forms`] for joints
//!   (pendulum period and energy, spring frequency). Each is a function
//!   `fn(&Settings, dt) -> Measurement` giving the error against the closed form.
//! - [`mod@reference`]: cases without a closed form (Falling Bricks, pyramid of base 20), measured
//!   against a reference run of the same solver at a much finer step ([`reference::reference`]).
//! - [`extreme`]: the stiff and extreme suite; each case returns a [`Verdict`] with its
//!   criterion in words, the measured numbers and pass/fail.
//!
//! [`sweep`] runs the first two families over step sizes and solver configurations, timing
//! each run, and the suite over the three named configurations: what the report
//! (`super::report`) then charts and writes.
//!
//! Solver and iteration/substep counts come from the [`Settings`] passed in (with sleeping
//! turned off, see `new_world`; only [`extreme::pyramid_sleeps`] lets bodies sleep); see
//! [`sequential`] and [`soft_step`] for the configurations the sweep uses.

pub mod closed_form;
pub mod extreme;
pub mod joint_forms;
pub mod reference;
pub mod sweep;

use crate::physics::{Real, Settings, SolverKind, World};

/// Standard gravity used throughout (m/s^2).
pub const G: Real = 9.81;

/// The step the stiff and extreme suite runs at (s): 60 Hz, like Box2D's samples.
pub const DT_60: Real = 1.0 / 60.0;

/// One run of a case: the error against the expected answer plus supporting numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Short machine name of the case, e.g. `free_fall`.
    pub case: &'static str,
    /// The headline error (absolute, in `unit`); `f64::NAN` when the run diverged before the
    /// error could be measured.
    pub error: f64,
    /// Unit of `error`, e.g. `m`, `m/s`, `rad/s`, `1` (dimensionless).
    pub unit: &'static str,
    /// What `error` is, in words.
    pub error_meaning: &'static str,
    /// True if anything went non-finite or the run exploded (left its arena or hit the speed cap).
    pub diverged: bool,
    /// Steps taken.
    pub steps: u64,
    /// Supporting numbers: (name, value). Names say their unit.
    pub details: Vec<(&'static str, f64)>,
}

impl Measurement {
    /// The supporting number called `name`, if present.
    pub fn detail(&self, name: &str) -> Option<f64> {
        named(&self.details, name)
    }
}

/// The number called `name` in a list of (name, value).
fn named(numbers: &[(&'static str, f64)], name: &str) -> Option<f64> {
    numbers.iter().find(|(n, _)| *n == name).map(|&(_, v)| v)
}

/// How a stiff or extreme case came out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The criterion held.
    Passed,
    /// The criterion did not hold.
    Failed,
    /// Measured for the report, with no criterion.
    ReportOnly,
}

/// The outcome of one stiff or extreme case.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    /// Short machine name, e.g. `stack_20`.
    pub case: &'static str,
    /// The pass criterion, in words.
    pub criterion: String,
    /// Whether the criterion held. Report-only cases always pass.
    pub passed: bool,
    /// True for cases measured for the report with no pass criterion (pyramid of base 100).
    pub report_only: bool,
    /// Measured numbers: (name, value). Names say their unit.
    pub measured: Vec<(&'static str, f64)>,
    /// Anything else worth saying (e.g. the f32 spacing at the coordinates used).
    pub note: String,
}

impl Verdict {
    /// The measured number called `name`, if present.
    pub fn value(&self, name: &str) -> Option<f64> {
        named(&self.measured, name)
    }

    /// Passed, failed, or measured for the report only.
    pub fn outcome(&self) -> Outcome {
        match (self.report_only, self.passed) {
            (true, _) => Outcome::ReportOnly,
            (false, true) => Outcome::Passed,
            (false, false) => Outcome::Failed,
        }
    }

    /// The measured numbers as `name<between>value` texts ([`fmt_num`]).
    pub fn measured_texts(&self, between: &str) -> Vec<String> {
        self.measured
            .iter()
            .map(|(n, v)| format!("{n}{between}{}", fmt_num(*v)))
            .collect()
    }

    /// One line: case, PASS/FAIL, measured numbers, criterion.
    pub fn summary(&self) -> String {
        let status = match self.outcome() {
            Outcome::ReportOnly => "REPORT",
            Outcome::Passed => "PASS",
            Outcome::Failed => "FAIL",
        };
        format!(
            "{}: {status} [{}] (criterion: {})",
            self.case,
            self.measured_texts(" = ").join(", "),
            self.criterion
        )
    }
}

/// `x` with 3-4 significant digits, in plain or scientific notation as fits: the one number
/// format of verdicts, criteria and the report.
pub fn fmt_num(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if a == 0.0 {
        "0".to_string()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{x:.2e}")
    } else if a >= 100.0 {
        format!("{x:.1}")
    } else if a >= 1.0 {
        format!("{x:.3}")
    } else {
        format!("{x:.4}")
    }
}

/// The sequential (appendix / box2d-lite) solver with `iterations` iterations.
pub fn sequential(iterations: u32) -> Settings {
    Settings {
        iterations,
        ..Settings::sequential()
    }
}

/// The soft-step solver with `substeps` substeps, other settings at their defaults.
pub fn soft_step(substeps: u32) -> Settings {
    Settings {
        substeps,
        ..Settings::soft_step()
    }
}

/// A short label for a solver configuration, e.g. `sequential, 10 it` or `soft step, 4 sub`.
pub fn config_label(settings: &Settings) -> String {
    match settings.solver {
        SolverKind::Sequential => format!("sequential, {} it", settings.iterations),
        SolverKind::SoftStep => format!("soft step, {} sub", settings.substeps),
    }
}

/// The integration step the solver actually takes for a step of `dt`: dt for the sequential
/// solver, dt / substeps for the soft step.
pub fn integration_step(settings: &Settings, dt: Real) -> f64 {
    match settings.solver {
        SolverKind::Sequential => dt as f64,
        SolverKind::SoftStep => dt as f64 / settings.substeps.max(1) as f64,
    }
}

/// Number of steps of `dt` that make `seconds` (rounded to the nearest step).
pub fn steps_for(seconds: f64, dt: Real) -> u64 {
    (seconds / dt as f64).round().max(1.0) as u64
}

/// A world with `settings` and `gravity`, with sleeping turned off.
///
/// Every runner measures with `enable_sleep = false`: a sleeping body can neither drift, sink
/// nor blow up, so a measurement would stop the moment its bodies fall asleep (Box2D's
/// benchmarks run with sleep off too). [`extreme::pyramid_sleeps`] checks sleeping itself.
///
/// # Panics
/// If `settings` or `gravity` fail validation: the runners are measurement tools and are only
/// ever given valid configurations.
pub(crate) fn new_world(settings: &Settings, gravity: crate::physics::Vec2) -> World {
    let settings = Settings {
        enable_sleep: false,
        ..settings.clone()
    };
    World::new(settings, gravity).expect("accuracy runners need valid settings")
}

/// True if any body is non-finite, farther than `arena` metres from the origin, or moving at
/// (nearly) the engine's speed cap: the run blew up.
pub(crate) fn blown_up(world: &World, arena: f64) -> bool {
    let cap = 0.99 * world.settings().max_linear_speed as f64;
    world.bodies().any(|b| {
        !b.is_finite()
            || (b.position().length() as f64) > arena
            || (b.linear_velocity().length() as f64) >= cap
    })
}

/// What ends a run early: the step after which the world counts as broken.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Breakdown {
    /// Any body holds a non-finite number.
    NonFinite,
    /// [`blown_up`]: non-finite, farther than this many metres from the origin, or at the
    /// speed cap.
    BlownUp(f64),
}

/// Step `world` `n` times by `dt`, calling `each(world, k)` after step `k` (from 0), until a
/// step fails or the world breaks down as `breakdown` says; true when all `n` steps ran.
pub(crate) fn run_steps(
    world: &mut World,
    dt: Real,
    n: u64,
    breakdown: Breakdown,
    mut each: impl FnMut(&World, u64),
) -> bool {
    for k in 0..n {
        let broken = world.step(dt).is_err()
            || match breakdown {
                Breakdown::NonFinite => !world.bodies().all(|b| b.is_finite()),
                Breakdown::BlownUp(arena) => blown_up(world, arena),
            };
        if broken {
            return false;
        }
        each(world, k);
    }
    true
}

/// Deepest overlap among the current contacts (m, >= 0; 0 with no contact).
pub fn max_penetration(world: &World) -> f64 {
    world
        .contacts()
        .flat_map(|c| {
            let n = c.count;
            c.points.into_iter().take(n)
        })
        .map(|p| -(p.separation as f64))
        .fold(0.0, f64::max)
}

/// Total mechanical energy (J): kinetic plus potential relative to y = 0 (or the origin, for
/// tilted gravity).
pub(crate) fn energy(world: &World) -> f64 {
    world.kinetic_energy() as f64 + world.potential_energy() as f64
}
