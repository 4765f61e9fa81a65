//! `--accuracy OUT.csv`: the peers' points for the work-precision charts of `tiltbox report`.
//!
//! Each case is built from the same `BodyDef`s in every engine (tiltbox with its defaults,
//! Box2D v3 of this build, rapier2d) and run at every step of the report's sweep (1/30 to 1/960 s)
//! with 4 substeps, sleep off, g = 9.81 m/s^2 as in `tiltbox::measure::accuracy`:
//!
//! - `pyramid_20` (`accuracy::scenes`' Pyramid20: ground 100 m x 2 m, pyramid of base 20):
//!   RMS over bodies and the sample times 0.5, 1, 2 s of the distance to a reference run of the
//!   SAME engine at dt = 1/960 s with 16 substeps (rapier: 16 solver iterations), as the report
//!   compares tiltbox with its own reference;
//! - `resting_stack` (`accuracy::closed_form::resting_stack`: 10 boxes of 1 m on the ground,
//!   10 s): how far the top box ends up from where it was placed;
//! - `stack_20` (`accuracy::extreme::stack_20`'s jittered stack: 20 boxes, +-1 cm, 30 s): the
//!   largest sideways drift of the top box at any step;
//! - `mass_ratio_100`, `mass_ratio_1000` (`accuracy::extreme::mass_ratio_*`: a 4 m x 1 m box of
//!   100 or 1000 kg on two 1 kg boxes, 5 s): the deepest overlap at any step, measured the same
//!   way in every engine from the bodies' poses (the separating-axis overlap of each pair of
//!   boxes after each step), not from each engine's contact points, whose age differs (each
//!   engine reports the overlap it found at the start of its step); the deepest contact-reported
//!   overlap is printed to stderr beside it as a cross-check;
//! - `pendulum_period` (`accuracy::joint_forms::pendulum_period`: a disc of r = 0.1 m 1 m
//!   below a free hinge to the world, released at 0.1 rad, 10 s): |T - closed form| (s), T the
//!   mean period of the disc's x. The report's other joint cases (the pendulum's energy, a
//!   distance spring's frequency) need velocities or a distance spring, which the peers'
//!   adapters do not carry: tiltbox alone on those charts.
//!
//! Run time: the whole run (building included, as the report times tiltbox), the minimum over
//! up to 3 runs within 2 s, per simulated second.

use crate::{box2d, Engine, Rapier, Tiltbox};
use std::io::{self, Write};
use std::path::Path;
use std::time::Instant;
use tiltbox::measure::accuracy::joint_forms::{self, mean_period};
use tiltbox::measure::accuracy::{reference::ReferenceCase, steps_for, G};
use tiltbox::measure::cases::{Setup, SetupJoint};
use tiltbox::physics::{BodyDef, MassSpec, Real, Settings, Shape, Vec2};

/// What a case's error is.
#[derive(Clone, Copy)]
enum Error {
    /// RMS distance to the engine's own reference run at these times (s).
    Rms(&'static [f64]),
    /// |top body's end position - start position|.
    TopDisplacement,
    /// Largest |x - x0| of the top body over every step.
    TopDrift,
    /// Deepest overlap between two boxes (separating-axis test on the poses) over every step.
    MaxPenetration,
    /// |T - T_closed_form| (s), T the mean period of the first dynamic body's x.
    Period(f64),
}

struct Case {
    name: &'static str,
    setup: Setup,
    seconds: f64,
    error: Error,
}

fn setup(name: &'static str, bodies: Vec<BodyDef>) -> Setup {
    Setup {
        name,
        gravity: Vec2::new(0.0, -G),
        bodies,
        steps: 0,
        sleep: false,
        warm_up: 0,
        driver: None,
        spawner: None,
        joints: Vec::new(),
    }
}

fn ground(width: Real) -> BodyDef {
    BodyDef::fixed(Shape::rect(width, 2.0), Vec2::new(0.0, -1.0))
}

fn cases() -> Vec<Case> {
    // Pyramid of base 20, as `cases::pyramid(w, 20, 1.0, 0.0, 0.6)` on a 100 m ground.
    let mut pyramid = vec![ground(100.0)];
    for row in 0..20 {
        let count = 20 - row;
        let x0 = -0.5 * (count as Real - 1.0);
        for j in 0..count {
            pyramid.push(
                BodyDef::dynamic(
                    Shape::rect(1.0, 1.0),
                    Vec2::new(x0 + j as Real, 0.5 + row as Real),
                )
                .with_friction(0.6),
            );
        }
    }
    // `cases::stack(w, 10, 1.0, 0.0, 0.0)` on a 40 m ground.
    let mut stack10 = vec![ground(40.0)];
    for i in 0..10 {
        stack10.push(BodyDef::dynamic(
            Shape::rect(1.0, 1.0),
            Vec2::new(0.0, 0.5 + i as Real),
        ));
    }
    // `extreme::jittered_stack(w, 20, 1.0, 0.0)`: the same +-1 cm pattern.
    let mut stack20 = vec![ground(40.0)];
    for i in 0..20usize {
        let jitter = 0.01 * (((i * 7919) % 11) as Real / 5.0 - 1.0);
        stack20.push(BodyDef::dynamic(
            Shape::rect(1.0, 1.0),
            Vec2::new(jitter, 0.5 + i as Real),
        ));
    }
    let ratio = |r: Real| {
        let mut b = vec![ground(40.0)];
        for x in [-1.5, 1.5] {
            b.push(BodyDef::dynamic(Shape::rect(1.0, 1.0), Vec2::new(x, 0.5)).with_mass(1.0));
        }
        b.push(BodyDef::dynamic(Shape::rect(4.0, 1.0), Vec2::new(0.0, 1.5)).with_mass(r));
        b
    };
    let pyramid_times = ReferenceCase::Pyramid20.sample_times();
    // `joint_forms::pendulum_period`: a disc of r = 0.1 m hung 1 m below a free hinge to the
    // world, released at 0.1 rad.
    let (l, r, a0): (Real, Real, Real) = (1.0, 0.1, 0.1);
    let centre = Vec2::new(l * a0.sin(), -l * a0.cos());
    let mut pendulum = setup(
        "pendulum_period",
        vec![BodyDef::dynamic(Shape::circle(r), centre).with_friction(0.0)],
    );
    pendulum
        .joints
        .push(SetupJoint::hinge(None, 0, Vec2::ZERO, -centre));
    let period = joint_forms::pendulum_period_closed_form(l as f64, r as f64, a0 as f64);
    vec![
        Case {
            name: "pyramid_20",
            setup: setup("pyramid_20", pyramid),
            seconds: *pyramid_times.last().unwrap(),
            error: Error::Rms(pyramid_times),
        },
        Case {
            name: "resting_stack",
            setup: setup("resting_stack", stack10),
            seconds: 10.0,
            error: Error::TopDisplacement,
        },
        Case {
            name: "stack_20",
            setup: setup("stack_20", stack20),
            seconds: 30.0,
            error: Error::TopDrift,
        },
        Case {
            name: "mass_ratio_100",
            setup: setup("mass_ratio_100", ratio(100.0)),
            seconds: 5.0,
            error: Error::MaxPenetration,
        },
        Case {
            name: "mass_ratio_1000",
            setup: setup("mass_ratio_1000", ratio(1000.0)),
            seconds: 5.0,
            error: Error::MaxPenetration,
        },
        Case {
            name: "pendulum_period",
            setup: pendulum,
            seconds: 10.0,
            error: Error::Period(period),
        },
    ]
}

#[derive(Clone, Copy, PartialEq)]
enum Which {
    Tiltbox,
    Box2d,
    Rapier,
}

impl Which {
    fn label(self) -> &'static str {
        match self {
            Which::Tiltbox => "tiltbox",
            Which::Box2d => box2d::LABEL,
            Which::Rapier => "rapier2d",
        }
    }
    fn build(self, setup: &Setup, dt: f32, substeps: u32) -> Box<dyn Engine> {
        match self {
            Which::Tiltbox => Box::new(Tiltbox::with_settings(
                setup,
                Settings {
                    substeps,
                    ..Settings::default()
                },
                dt,
            )),
            Which::Box2d => Box::new(box2d::Box2d::with_step(setup, dt, substeps as i32)),
            Which::Rapier => Box::new(Rapier::with_step(setup, dt, substeps as usize)),
        }
    }
}

/// What one run recorded.
struct Record {
    /// Dynamic bodies' positions at the sample times (for `Error::Rms`).
    samples: Vec<Vec<[f32; 2]>>,
    top_displacement: f64,
    top_drift: f64,
    penetration: f64,
    /// The deepest overlap the engine's own contact points reported (cross-check).
    contact_penetration: f64,
    /// The first dynamic body's x after every step, with the time (s).
    xs: Vec<(f64, f64)>,
    diverged: bool,
}

/// A box: centre, angle, half extents.
type Boxed = ([f32; 2], f32, [f32; 2]);

/// How deep two boxes overlap (m): the smallest overlap of their projections over the four
/// axes of the separating-axis test, 0 if they are apart.
fn box_overlap(a: Boxed, b: Boxed) -> f64 {
    let axes = |angle: f32| {
        let (s, c) = (angle as f64).sin_cos();
        [[c, s], [-s, c]]
    };
    let (ua, ub) = (axes(a.1), axes(b.1));
    let radius = |u: [f64; 2], ax: [[f64; 2]; 2], h: [f32; 2]| {
        h[0] as f64 * (ax[0][0] * u[0] + ax[0][1] * u[1]).abs()
            + h[1] as f64 * (ax[1][0] * u[0] + ax[1][1] * u[1]).abs()
    };
    let d = [(b.0[0] - a.0[0]) as f64, (b.0[1] - a.0[1]) as f64];
    let mut depth = f64::INFINITY;
    for u in ua.into_iter().chain(ub) {
        let gap = (d[0] * u[0] + d[1] * u[1]).abs();
        depth = depth.min(radius(u, ua, a.2) + radius(u, ub, b.2) - gap);
    }
    depth.max(0.0)
}

/// The deepest overlap between any two boxes of `case` (statics from the set-up, dynamics from
/// the engine).
fn deepest_box_overlap(case: &Case, engine: &dyn Engine) -> f64 {
    let half = |d: &BodyDef| match d.shape {
        Shape::Rect { half_extents: h } => Some([h.x as f32, h.y as f32]),
        _ => None,
    };
    let mut boxes: Vec<Boxed> = Vec::new();
    let mut dynamic = engine.dynamic_bodies().into_iter();
    for d in &case.setup.bodies {
        let pose = if d.mass == MassSpec::Static {
            ([d.position.x as f32, d.position.y as f32], d.angle as f32)
        } else {
            match dynamic.next() {
                Some(b) => (b.position, b.angle),
                None => return f64::NAN,
            }
        };
        if let Some(h) = half(d) {
            boxes.push((pose.0, pose.1, h));
        }
    }
    let mut deepest = 0.0f64;
    for i in 0..boxes.len() {
        for j in i + 1..boxes.len() {
            deepest = deepest.max(box_overlap(boxes[i], boxes[j]));
        }
    }
    deepest
}

fn simulate(which: Which, case: &Case, dt: f32, substeps: u32) -> Record {
    let mut e = which.build(&case.setup, dt, substeps);
    let start = e.dynamic_bodies();
    let top0 = start.last().map(|b| b.position).unwrap_or([0.0; 2]);
    let times: &[f64] = match case.error {
        Error::Rms(t) => t,
        _ => &[],
    };
    let per_step = matches!(case.error, Error::TopDrift | Error::MaxPenetration);
    let mut r = Record {
        samples: Vec::new(),
        top_displacement: 0.0,
        top_drift: 0.0,
        penetration: 0.0,
        contact_penetration: 0.0,
        xs: Vec::new(),
        diverged: false,
    };
    let total = steps_for(case.seconds, dt as _);
    let mut next = 0;
    for done in 1..=total {
        e.step();
        if matches!(case.error, Error::Period(_)) {
            if let Some(b) = e.dynamic_bodies().first() {
                r.xs.push((done as f64 * dt as f64, b.position[0] as f64));
            }
        }
        if per_step {
            if matches!(case.error, Error::MaxPenetration) {
                r.penetration = r.penetration.max(deepest_box_overlap(case, e.as_ref()));
                r.contact_penetration = r.contact_penetration.max(e.max_penetration());
            } else if let Some(top) = e.dynamic_bodies().last() {
                r.top_drift = r.top_drift.max((top.position[0] - top0[0]).abs() as f64);
            }
        }
        if next < times.len() && done == steps_for(times[next], dt as _) {
            r.samples
                .push(e.dynamic_bodies().iter().map(|b| b.position).collect());
            next += 1;
        }
    }
    let end = e.dynamic_bodies();
    r.diverged = end.iter().any(|b| {
        !(b.position[0].is_finite() && b.position[1].is_finite())
            || b.position[0].abs() > 1e3
            || b.position[1].abs() > 1e3
    });
    if let Some(top) = end.last() {
        let (dx, dy) = (top.position[0] - top0[0], top.position[1] - top0[1]);
        r.top_displacement = ((dx * dx + dy * dy) as f64).sqrt();
    }
    r
}

fn rms(run: &Record, reference: &Record) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (a, b) in run.samples.iter().zip(&reference.samples) {
        for (p, q) in a.iter().zip(b) {
            let d2 = ((p[0] - q[0]) as f64).powi(2) + ((p[1] - q[1]) as f64).powi(2);
            sum += d2;
            n += 1;
        }
    }
    if n == 0 || run.samples.len() != reference.samples.len() {
        f64::NAN
    } else {
        (sum / n as f64).sqrt()
    }
}

/// The step sizes of the report's sweep (`tiltbox::report::step_sizes`), in Hz.
fn step_hz(quick: bool) -> &'static [f64] {
    if quick {
        &[30.0, 120.0, 480.0]
    } else {
        &[30.0, 60.0, 120.0, 240.0, 480.0, 960.0]
    }
}

/// Run every case in every engine over the sweep and write `engine,case,dt,error,cpu_ms_per_simulated_s`.
pub fn write_csv(out: &Path, quick: bool) -> io::Result<()> {
    let mut rows = Vec::new();
    for case in cases() {
        for which in [Which::Box2d, Which::Rapier, Which::Tiltbox] {
            let reference = matches!(case.error, Error::Rms(_)).then(|| {
                eprintln!(
                    "{} {}: reference run (dt 1/960, 16 substeps)",
                    which.label(),
                    case.name
                );
                simulate(which, &case, 1.0 / 960.0, 16)
            });
            for &hz in step_hz(quick) {
                let dt = (1.0 / hz) as f32;
                let t = Instant::now();
                let rec = simulate(which, &case, dt, 4);
                let mut best = t.elapsed().as_secs_f64();
                let budget = Instant::now();
                for _ in 0..2 {
                    if budget.elapsed().as_secs_f64() > 2.0 {
                        break;
                    }
                    let t = Instant::now();
                    std::hint::black_box(simulate(which, &case, dt, 4).penetration);
                    best = best.min(t.elapsed().as_secs_f64());
                }
                let error = if rec.diverged {
                    f64::NAN
                } else {
                    match case.error {
                        Error::Rms(_) => rms(&rec, reference.as_ref().expect("a reference")),
                        Error::TopDisplacement => rec.top_displacement,
                        Error::TopDrift => rec.top_drift,
                        Error::MaxPenetration => rec.penetration,
                        Error::Period(expected) => (mean_period(&rec.xs) - expected).abs(),
                    }
                };
                let simulated = steps_for(case.seconds, dt as _) as f64 * dt as f64;
                let ms = best * 1e3 / simulated;
                eprintln!(
                    "{} {} dt 1/{hz}: error {error:.3e}{}, {ms:.2} ms per simulated s",
                    which.label(),
                    case.name,
                    if matches!(case.error, Error::MaxPenetration) {
                        format!(" (contact points: {:.3e})", rec.contact_penetration)
                    } else {
                        String::new()
                    }
                );
                rows.push(format!(
                    "{},{},{},{:e},{:.4}",
                    which.label(),
                    case.name,
                    dt,
                    error,
                    ms
                ));
            }
        }
    }
    let date = std::process::Command::new("date")
        .args(["-u", "+%Y-%m-%d %H:%M UTC"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let mut f = std::fs::File::create(out)?;
    writeln!(
        f,
        "# Peers' work-precision points for `tiltbox report`, written by benchmarks/vs-peers:"
    )?;
    writeln!(
        f,
        "#   cd benchmarks/vs-peers && cargo run --release -- --accuracy {}{}",
        out.display(),
        if quick { " --quick" } else { "" }
    )?;
    writeln!(
        f,
        "# {date}; {}; load average {}; Box2D v3 {} ({}), rapier2d {}, tiltbox Settings::default()",
        crate::machine(),
        std::fs::read_to_string("/proc/loadavg")
            .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
            .unwrap_or_default(),
        box2d::version(),
        box2d::LABEL,
        rapier2d::VERSION,
    )?;
    writeln!(
        f,
        "# Every engine: 4 substeps (rapier: solver iterations), sleep off, g = 9.81; error as in \
         tiltbox::measure::accuracy (pyramid_20: RMS distance (m) to the same engine at dt 1/960 with 16 \
         substeps at t = 0.5, 1, 2 s; resting_stack: top box displacement after 10 s (m); \
         stack_20: jittered 20-stack's largest top drift over 30 s (m); mass_ratio_*: deepest \
         overlap of two boxes over 5 s, separating-axis test on the poses after each step (m); \
         pendulum_period: |T - closed form| (s) over 10 s, a disc on a free hinge to the world); cpu_ms_per_simulated_s: min of up to 3 whole runs, single thread"
    )?;
    writeln!(f, "engine,case,dt,error,cpu_ms_per_simulated_s")?;
    for r in rows {
        writeln!(f, "{r}")?;
    }
    Ok(())
}
