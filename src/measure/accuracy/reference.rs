//! Cases without a closed form (Falling Bricks, a pyramid), measured against a reference run
//! of the same solver.
//!
//! A run records every dynamic body's position at fixed sample times, the deepest overlap seen
//! at any step, and the energy drift. [`compare`] turns a run and a reference run into a
//! [`Measurement`]: the error is the RMS, over bodies and sample times, of the distance between
//! the run's and the reference's positions.
//!
//! The reference ([`reference()`]) is the same solver at dt = 1/960 s (1/60 / 16) with many
//! iterations (sequential: 100) or substeps (soft step: 16).

use super::{blown_up, energy, max_penetration, new_world, steps_for, Measurement, G};
use crate::measure::cases;
use crate::physics::{vec2, BodyId, Real, Settings, SolverKind, Vec2, World};

/// A case with no closed form, measured against a reference run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceCase {
    /// A closed box of 4 walls (10 m x 10 m inside) with 6 differently sized bricks dropped in.
    FallingBricks,
    /// A pyramid of base 20 (210 boxes of 1 m) on the ground.
    Pyramid20,
}

impl ReferenceCase {
    /// Both cases, in report order.
    pub const ALL: [ReferenceCase; 2] = [ReferenceCase::FallingBricks, ReferenceCase::Pyramid20];

    /// Machine name.
    pub fn name(self) -> &'static str {
        match self {
            ReferenceCase::FallingBricks => "falling_bricks",
            ReferenceCase::Pyramid20 => "pyramid_20",
        }
    }

    /// Human title.
    pub fn title(self) -> &'static str {
        match self {
            ReferenceCase::FallingBricks => "Falling Bricks",
            ReferenceCase::Pyramid20 => "Pyramid, base 20",
        }
    }

    /// The set-up, in words.
    pub fn setup(self) -> &'static str {
        match self {
            ReferenceCase::FallingBricks => {
                "closed box of 4 static walls (10 m x 10 m inside, 0.5 m thick) with 6 bricks \
                 (0.3-2 m, restitution 0-0.3) dropped from 3-8.5 m at different angles, 3 s"
            }
            ReferenceCase::Pyramid20 => {
                "pyramid of base 20 (210 boxes of 1 m, friction 0.6) on the ground, 2 s"
            }
        }
    }

    /// Times at which positions are sampled (s); the last one is the run's length.
    pub fn sample_times(self) -> &'static [f64] {
        match self {
            ReferenceCase::FallingBricks => &[0.5, 1.0, 2.0, 3.0],
            ReferenceCase::Pyramid20 => &[0.5, 1.0, 2.0],
        }
    }

    /// Build the set-up (from [`cases`]); returns the world and the dynamic bodies to track.
    pub fn build(self, settings: &Settings) -> (World, Vec<BodyId>) {
        let mut w = new_world(settings, vec2(0.0, -G));
        let ids = match self {
            ReferenceCase::FallingBricks => cases::falling_bricks(&mut w).unwrap(),
            ReferenceCase::Pyramid20 => {
                cases::ground(&mut w, 0.0, 100.0, 2.0).unwrap();
                cases::pyramid(&mut w, 20, 1.0, 0.0, 0.6).unwrap()
            }
        };
        (w, ids)
    }

    /// Size of the region the case lives in (m): beyond it the run has blown up.
    fn arena(self) -> f64 {
        match self {
            ReferenceCase::FallingBricks => 20.0,
            ReferenceCase::Pyramid20 => 100.0,
        }
    }
}

/// What one run of a reference case recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceRun {
    /// Which case.
    pub case: ReferenceCase,
    /// Positions of the tracked bodies at each of `case.sample_times()` (fewer if diverged).
    pub samples: Vec<Vec<Vec2>>,
    /// Deepest overlap seen at any step (m).
    pub max_penetration: f64,
    /// (E_end - E_start) / E_start, with E = kinetic + potential above the floor.
    pub energy_drift: f64,
    /// True if the run went non-finite or left the arena.
    pub diverged: bool,
    /// Steps taken.
    pub steps: u64,
}

/// Run `case` with `settings` at `dt` and record it.
pub fn run(case: ReferenceCase, settings: &Settings, dt: Real) -> ReferenceRun {
    let (mut w, ids) = case.build(settings);
    let e0 = energy(&w);
    let mut samples = Vec::new();
    let mut max_pen: f64 = 0.0;
    let mut diverged = false;
    let mut done = 0u64;
    'outer: for &t in case.sample_times() {
        let target = steps_for(t, dt);
        while done < target {
            if w.step(dt).is_err() || blown_up(&w, case.arena()) {
                diverged = true;
                break 'outer;
            }
            done += 1;
            max_pen = max_pen.max(max_penetration(&w));
        }
        samples.push(
            ids.iter()
                .map(|&id| w.body(id).unwrap().position())
                .collect(),
        );
    }
    let e1 = energy(&w);
    ReferenceRun {
        case,
        samples,
        max_penetration: max_pen,
        energy_drift: if e0 != 0.0 { (e1 - e0) / e0.abs() } else { 0.0 },
        diverged,
        steps: w.step_count(),
    }
}

/// The reference configuration for `settings`' solver: dt = 1/960 s with 100 iterations
/// (sequential) or 16 substeps (soft step); every other setting unchanged.
pub fn reference(settings: &Settings) -> (Settings, Real) {
    let mut s = settings.clone();
    match s.solver {
        SolverKind::Sequential => s.iterations = 100,
        SolverKind::SoftStep => s.substeps = 16,
    }
    (s, 1.0 / 960.0)
}

/// The reference run of `case` for `settings`' solver.
pub fn reference_run(case: ReferenceCase, settings: &Settings) -> ReferenceRun {
    let (s, dt) = reference(settings);
    run(case, &s, dt)
}

/// Compare a run with its reference. Error: RMS position difference (m) over all tracked
/// bodies and sample times.
pub fn compare(run: &ReferenceRun, reference: &ReferenceRun) -> Measurement {
    let mut sum = 0.0f64;
    let mut count = 0usize;
    let mut worst: f64 = 0.0;
    for (a, b) in run.samples.iter().zip(&reference.samples) {
        for (p, q) in a.iter().zip(b) {
            let d = (*p - *q).length() as f64;
            sum += d * d;
            count += 1;
            worst = worst.max(d);
        }
    }
    let complete = run.samples.len() == run.case.sample_times().len();
    let diverged = run.diverged || !complete || !sum.is_finite();
    let rms = if count > 0 && !diverged {
        (sum / count as f64).sqrt()
    } else {
        f64::NAN
    };
    Measurement {
        case: run.case.name(),
        error: rms,
        unit: "m",
        error_meaning: "RMS position difference from the reference run at the sample times",
        diverged,
        steps: run.steps,
        details: vec![
            ("largest position difference (m)", worst),
            ("largest penetration (m)", run.max_penetration),
            ("energy drift (relative)", run.energy_drift),
            (
                "reference largest penetration (m)",
                reference.max_penetration,
            ),
            ("reference energy drift (relative)", reference.energy_drift),
        ],
    }
}
