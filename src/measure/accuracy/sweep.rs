//! Sweeps: every closed-form and reference case over step sizes and solver configurations,
//! each run timed, and the stiff and extreme suite over the three named configurations. This is
//! the running half of the report; `measure::report` charts and writes what it returns.
//! Everything is single-threaded so timings are not disturbed.

use super::{
    closed_form, config_label, extreme, reference, sequential, soft_step, Measurement, Verdict,
};
use crate::physics::{Real, Settings, SolverKind};
use std::time::Instant;

/// One run of the sweep.
#[derive(Clone, Debug)]
pub struct Point {
    /// Step (s).
    pub dt: Real,
    /// What the run measured.
    pub measurement: Measurement,
    /// Minimum over the timed runs of wall-clock time per step (ms).
    pub ms_per_step: f64,
}

impl Point {
    /// Run time per simulated second (ms): ms per step / dt.
    pub fn ms_per_sim_second(&self) -> f64 {
        self.ms_per_step / self.dt as f64
    }
}

/// The runs of one solver configuration over the step sizes.
#[derive(Clone, Debug)]
pub struct Curve {
    /// e.g. `soft step, 4 sub`.
    pub label: String,
    /// The configuration.
    pub settings: Settings,
    /// One point per step size, largest step first.
    pub points: Vec<Point>,
}

/// Everything measured for one case.
#[derive(Clone, Debug)]
pub struct CaseSweep {
    /// Machine name (chart file name).
    pub name: &'static str,
    /// Human title.
    pub title: &'static str,
    /// Set-up, in words.
    pub setup: String,
    /// Expected answer, in words.
    pub expected: String,
    /// Unit of the error.
    pub unit: &'static str,
    /// What the error is.
    pub error_meaning: &'static str,
    /// One curve per solver configuration.
    pub curves: Vec<Curve>,
}

/// Step sizes swept (s).
pub fn step_sizes(quick: bool) -> Vec<Real> {
    let hz: &[Real] = if quick {
        &[30.0, 120.0, 480.0]
    } else {
        &[30.0, 60.0, 120.0, 240.0, 480.0, 960.0]
    };
    hz.iter().map(|f| 1.0 / f).collect()
}

/// Solver configurations swept: sequential 4/10/30 iterations, soft step 1/2/4/8 substeps.
pub fn configurations(quick: bool) -> Vec<Settings> {
    if quick {
        vec![sequential(10), soft_step(1), soft_step(4)]
    } else {
        vec![
            sequential(4),
            sequential(10),
            sequential(30),
            soft_step(1),
            soft_step(2),
            soft_step(4),
            soft_step(8),
        ]
    }
}

/// Run `f` once as a warm-up (its result is kept), then time it again until `repeats` timed
/// runs are done or 2 s have been spent; returns the result and the minimum time (ms).
fn timed(repeats: usize, mut f: impl FnMut() -> Measurement) -> (Measurement, f64) {
    let t = Instant::now();
    let m = f();
    let mut best = t.elapsed().as_secs_f64();
    let budget = Instant::now();
    for i in 0..repeats {
        if i > 0 && budget.elapsed().as_secs_f64() > 2.0 {
            break;
        }
        let t = Instant::now();
        let _ = std::hint::black_box(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    (m, best * 1e3)
}

/// Timed runs per point: 5, or 1 for a quick sweep.
pub fn repeats(quick: bool) -> usize {
    if quick {
        1
    } else {
        5
    }
}

/// Sweep one closed-form case over every configuration and step size.
pub fn sweep_closed(case: &closed_form::ClosedFormCase, quick: bool) -> CaseSweep {
    let mut curves = Vec::new();
    let mut first: Option<Measurement> = None;
    for settings in configurations(quick) {
        let points = step_sizes(quick)
            .into_iter()
            .map(|dt| {
                let (m, ms) = timed(repeats(quick), || (case.run)(&settings, dt));
                let ms_per_step = ms / m.steps.max(1) as f64;
                Point {
                    dt,
                    measurement: m,
                    ms_per_step,
                }
            })
            .collect::<Vec<_>>();
        if first.is_none() {
            first = points.first().map(|p| p.measurement.clone());
        }
        curves.push(Curve {
            label: config_label(&settings),
            settings,
            points,
        });
    }
    let first = first.expect("at least one run");
    CaseSweep {
        name: case.name,
        title: case.title,
        setup: case.setup.to_string(),
        expected: case.expected.to_string(),
        unit: first.unit,
        error_meaning: first.error_meaning,
        curves,
    }
}

/// Sweep one reference case: a reference run per solver, then every configuration and step
/// size.
pub fn sweep_reference(case: reference::ReferenceCase, quick: bool) -> CaseSweep {
    let refs = [
        (
            SolverKind::Sequential,
            reference::reference_run(case, &Settings::sequential()),
        ),
        (
            SolverKind::SoftStep,
            reference::reference_run(case, &Settings::soft_step()),
        ),
    ];
    let mut curves = Vec::new();
    let mut meaning = "";
    for settings in configurations(quick) {
        let reference = &refs
            .iter()
            .find(|(k, _)| *k == settings.solver)
            .expect("a reference per solver")
            .1;
        let points = step_sizes(quick)
            .into_iter()
            .map(|dt| {
                let (m, ms) = timed(repeats(quick), || {
                    reference::compare(&reference::run(case, &settings, dt), reference)
                });
                meaning = m.error_meaning;
                let ms_per_step = ms / m.steps.max(1) as f64;
                Point {
                    dt,
                    measurement: m,
                    ms_per_step,
                }
            })
            .collect();
        curves.push(Curve {
            label: config_label(&settings),
            settings,
            points,
        });
    }
    let (rs, rdt) = reference::reference(&Settings::sequential());
    let (fs, _) = reference::reference(&Settings::soft_step());
    CaseSweep {
        name: case.name(),
        title: case.title(),
        setup: case.setup().to_string(),
        expected: format!(
            "no closed form: compared with the same solver at dt = 1/{:.0} s with {} iterations (sequential) or {} substeps (soft step), positions sampled at t = {} s",
            1.0 / rdt,
            rs.iterations,
            fs.substeps,
            case
                .sample_times()
                .iter()
                .map(|t| format!("{t}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        unit: "m",
        error_meaning: meaning,
        curves,
    }
}

/// The stiff and extreme suite for both solvers at their defaults and for the soft step with
/// adaptive stiffness off (every island on the base settings, as before issue 12).
#[derive(Clone, Debug)]
pub struct SuiteResults {
    /// `Settings::soft_step()`.
    pub soft_step: Vec<Verdict>,
    /// `Settings::sequential()`.
    pub sequential: Vec<Verdict>,
    /// `Settings::soft_step()` with `adaptive_stiffness` off: fixed settings for every island,
    /// to show what adaptive stiffness buys.
    pub soft_step_fixed: Vec<Verdict>,
}

/// Run the suite for the three configurations (with the report-only pyramid of base 100).
pub fn run_suite() -> SuiteResults {
    SuiteResults {
        soft_step: extreme::suite(&Settings::soft_step(), true),
        sequential: extreme::suite(&Settings::sequential(), true),
        soft_step_fixed: extreme::suite(
            &Settings {
                adaptive_stiffness: false,
                ..Settings::soft_step()
            },
            true,
        ),
    }
}
