//! Cases with a closed-form answer. Each runner takes the solver configuration (a
//! [`Settings`]) and the step `dt`, runs a small world, and returns a [`Measurement`] whose
//! `error` is the absolute difference from the analytic (continuous-time) answer.
//!
//! Set-ups (units m, s, kg, rad; g = 9.81 m/s^2):
//! - free fall: 1 m box from rest at y = 100, 1 s, no ground;
//! - slide to a stop: 1 m box at 5 m/s on flat ground, mu = 0.6 (both bodies);
//! - slope that sticks: gravity tilted by 20 deg (tan = 0.36) with mu = 0.6, 2 s;
//! - slope that slides: gravity tilted by 30 deg, mu = 0.2, 1 s from rest;
//! - bounce: 1 m box dropped from 2 m (bottom to ground), e = 0.8 (both bodies);
//! - head-on: 1 kg at +4 m/s meets 3 kg at -2 m/s, e = 0.5, no gravity;
//! - spin: 2 m x 1 m box of 3 kg, torque 2.5 N m, 1 s, no gravity;
//! - resting stack: 10 boxes of 1 m on the ground, 10 s;
//! - disc that rolls: disc of r = 0.5 m from rest, gravity tilted by 30 deg, mu = 0.5, 1 s;
//! - disc that slides: the same disc with mu = 0.1, 1 s.
//!
//! Coefficients are given to both bodies of a pair, so every mixing rule except `Product`
//! yields the coefficient itself; the expected values use `Settings::*_mixing` to be exact.
//!
//! One concept, the catalogue of closed-form cases (over 600 lines): each case's set-up sits
//! beside the answer it is measured against.

use super::{
    blown_up, integration_step, max_penetration, new_world, run_steps, steps_for, Breakdown,
    Measurement, G,
};
use crate::physics::{vec2, BodyDef, BodyId, Real, Settings, Shape, Vec2, World};

/// A closed-form case: its name, a title for humans, and its runner.
#[derive(Clone, Copy, Debug)]
pub struct ClosedFormCase {
    /// Machine name (matches [`Measurement::case`]).
    pub name: &'static str,
    /// Human title.
    pub title: &'static str,
    /// The set-up, in words.
    pub setup: &'static str,
    /// The expected answer, in words.
    pub expected: &'static str,
    /// The runner.
    pub run: fn(&Settings, Real) -> Measurement,
}

/// Every closed-form case, in report order.
pub fn all() -> Vec<ClosedFormCase> {
    vec![
        ClosedFormCase {
            name: "free_fall",
            title: "Free fall",
            setup: "1 m box from rest at y = 100 m, g = 9.81, no ground, 1 s",
            expected: "y = y0 - g t^2/2 (continuous); semi-implicit Euler gives exactly y0 - g t^2/2 - g t h/2",
            run: free_fall,
        },
        ClosedFormCase {
            name: "slide_to_stop",
            title: "Slide to a stop",
            setup: "1 m box at 5 m/s on flat ground, mu = 0.6 on both bodies",
            expected: "distance v0^2 / (2 mu g), time v0 / (mu g)",
            run: slide_to_stop,
        },
        ClosedFormCase {
            name: "slope_stick",
            title: "Slope that sticks",
            setup: "1 m box on the ground with gravity tilted by 20 deg (tan = 0.364), mu = 0.6, 2 s",
            expected: "no motion (tan theta < mu): drift 0",
            run: slope_stick,
        },
        ClosedFormCase {
            name: "slope_slide",
            title: "Slope that slides",
            setup: "1 m box from rest with gravity tilted by 30 deg, mu = 0.2, 1 s",
            expected: "x = a t^2 / 2 with a = g (sin theta - mu cos theta)",
            run: slope_slide,
        },
        ClosedFormCase {
            name: "bounce",
            title: "Bounce",
            setup: "1 m box dropped from 2 m (bottom to ground), e = 0.8 on both bodies; first rebound apex",
            expected: "rebound height ratio e^2",
            run: bounce,
        },
        ClosedFormCase {
            name: "head_on",
            title: "Head-on collision",
            setup: "1 kg box at +4 m/s meets 3 kg box at -2 m/s, e = 0.5, no gravity, 1 s",
            expected: "momentum conserved; v2' - v1' = e (v1 - v2)",
            run: head_on,
        },
        ClosedFormCase {
            name: "spin",
            title: "Spin under torque",
            setup: "2 m x 1 m box of 3 kg, torque 2.5 N m, no gravity, 1 s (I = 1.25 kg m^2)",
            expected: "omega = tau t / I, I = m (w^2 + h^2) / 12",
            run: spin,
        },
        ClosedFormCase {
            name: "resting_stack",
            title: "Resting stack (10 boxes)",
            setup: "10 boxes of 1 m stacked exactly on the ground (cases::stack), 10 s",
            expected: "top box stays where it was placed (sinking and drift 0)",
            run: resting_stack,
        },
        ClosedFormCase {
            name: "disc_rolls",
            title: "Disc rolls down a slope",
            setup: "disc r = 0.5 m from rest with gravity tilted by 30 deg, mu = 0.5 >= tan(30 deg)/3 = 0.19, 1 s",
            expected: "rolls without slipping: x = a t^2 / 2 with a = (2/3) g sin theta, v = omega r",
            run: disc_rolls,
        },
        ClosedFormCase {
            name: "disc_slides",
            title: "Disc slides down a slope",
            setup: "disc r = 0.5 m from rest with gravity tilted by 30 deg, mu = 0.1 < tan(30 deg)/3, 1 s",
            expected: "slides: x = a t^2 / 2 with a = g (sin theta - mu cos theta); spins up at 2 mu g cos theta / r",
            run: disc_slides,
        },
    ]
}

/// The measurement of a case: its words (name, unit, what the error means), the world it ran
/// in, whether it diverged, the error and the numbers behind it.
fn finish(
    (case, unit, error_meaning): (&'static str, &'static str, &'static str),
    world: &World,
    diverged: bool,
    error: f64,
    details: Vec<(&'static str, f64)>,
) -> Measurement {
    let diverged = diverged || !error.is_finite();
    Measurement {
        case,
        error: if diverged && !error.is_finite() {
            f64::NAN
        } else {
            error
        },
        unit,
        error_meaning,
        diverged,
        steps: world.step_count(),
        details,
    }
}

/// A body that started at rest and accelerated uniformly at `a` (m/s^2) for `t` s covered
/// `x` (m): the measurement of `case` with error |x - a t^2/2|, its supporting numbers first,
/// then `more`.
#[allow(clippy::too_many_arguments)] // the case's words, its world and its numbers
fn uniformly_accelerated(
    case: &'static str,
    error_meaning: &'static str,
    world: &World,
    diverged: bool,
    x: f64,
    a: f64,
    t: f64,
    more: Vec<(&'static str, f64)>,
) -> Measurement {
    let expected = 0.5 * a * t * t;
    let mut details = vec![
        ("x (m)", x),
        ("expected x (m)", expected),
        ("measured a = 2x/t^2 (m/s^2)", 2.0 * x / (t * t)),
        ("expected a (m/s^2)", a),
    ];
    details.extend(more);
    finish(
        (case, "m", error_meaning),
        world,
        diverged,
        (x - expected).abs(),
        details,
    )
}

fn pos(world: &World, id: BodyId) -> Vec2 {
    world.body(id).map(|b| b.position()).unwrap_or(Vec2::NAN)
}

fn vel(world: &World, id: BodyId) -> Vec2 {
    world
        .body(id)
        .map(|b| b.linear_velocity())
        .unwrap_or(Vec2::NAN)
}

/// A long static floor (top at y = 0) with the given friction and restitution.
fn floor(world: &mut World, friction: Real, restitution: Real) -> BodyId {
    world
        .add_body(
            &BodyDef::fixed(Shape::rect(400.0, 2.0), vec2(0.0, -1.0))
                .with_friction(friction)
                .with_restitution(restitution),
        )
        .expect("valid floor")
}

/// Free fall for 1 s from rest. Error: |y - (y0 - g t^2/2)| (m). Details include the error
/// against semi-implicit Euler's exact discrete answer y0 - g t^2/2 - g t h/2 (h = the
/// integration step, dt / substeps for the soft step), which should be f32 rounding only.
pub fn free_fall(settings: &Settings, dt: Real) -> Measurement {
    let y0 = 100.0;
    let mut w = new_world(settings, vec2(0.0, -G));
    let id = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, y0)))
        .unwrap();
    let n = steps_for(1.0, dt);
    let diverged = !run_steps(&mut w, dt, n, Breakdown::BlownUp(1e4), |_, _| {});
    let t = n as f64 * dt as f64;
    let g = G as f64;
    let h = integration_step(settings, dt);
    let y = pos(&w, id).y as f64;
    let continuous = y0 as f64 - 0.5 * g * t * t;
    let discrete = continuous - 0.5 * g * t * h;
    finish(
        ("free_fall", "m", "|y - (y0 - g t^2/2)| at t = 1 s"),
        &w,
        diverged,
        (y - continuous).abs(),
        vec![
            ("error vs discrete exact form (m)", (y - discrete).abs()),
            (
                "predicted discretisation error g t h/2 (m)",
                0.5 * g * t * h,
            ),
            ("y (m)", y),
        ],
    )
}

/// Slide to a stop from 5 m/s on flat ground, mu = 0.6. Error: |d - v0^2/(2 mu g)| (m).
pub fn slide_to_stop(settings: &Settings, dt: Real) -> Measurement {
    let (v0, mu) = (5.0 as Real, 0.6 as Real);
    let mu_mixed = settings.friction_mixing.mix(mu, mu) as f64;
    let g = G as f64;
    let d_expected = (v0 as f64).powi(2) / (2.0 * mu_mixed * g);
    let t_expected = v0 as f64 / (mu_mixed * g);
    let mut w = new_world(settings, vec2(0.0, -G));
    floor(&mut w, mu, 0.0);
    let id = w
        .add_body(
            &BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5))
                .with_friction(mu)
                .with_velocity(vec2(v0, 0.0)),
        )
        .unwrap();
    let n = steps_for(t_expected + 1.0, dt);
    let mut stop_time = f64::NAN;
    let mut max_tilt: f64 = 0.0;
    let diverged = !run_steps(&mut w, dt, n, Breakdown::BlownUp(1e3), |w, _| {
        let b = w.body(id).unwrap();
        max_tilt = max_tilt.max(b.angle().abs() as f64);
        if stop_time.is_nan() && b.linear_velocity().x.abs() < 1e-3 {
            stop_time = w.time();
        }
    });
    let d = pos(&w, id).x as f64;
    finish(
        ("slide_to_stop", "m", "|stopping distance - v0^2/(2 mu g)|"),
        &w,
        diverged,
        (d - d_expected).abs(),
        vec![
            ("distance (m)", d),
            ("expected distance (m)", d_expected),
            ("stop time (s)", stop_time),
            ("expected stop time (s)", t_expected),
            ("max tilt (rad)", max_tilt),
        ],
    )
}

/// Gravity of magnitude g tilted by `theta`: the ground behaves like a slope rising to -x.
fn tilted(theta: Real) -> Vec2 {
    vec2(G * theta.sin(), -G * theta.cos())
}

/// A 1 m box of friction `mu` at rest on a floor of friction `mu`, gravity tilted by `theta`
/// (rad), run `seconds`: the world, the box, and whether the run diverged.
fn box_on_slope(
    settings: &Settings,
    dt: Real,
    theta: Real,
    mu: Real,
    seconds: f64,
) -> (World, BodyId, bool) {
    let mut w = new_world(settings, tilted(theta));
    floor(&mut w, mu, 0.0);
    let id = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)).with_friction(mu))
        .unwrap();
    let n = steps_for(seconds, dt);
    let diverged = !run_steps(&mut w, dt, n, Breakdown::BlownUp(1e3), |_, _| {});
    (w, id, diverged)
}

/// A box resting on a 20 deg "slope" (tilted gravity), mu = 0.6 > tan 20 deg = 0.364, for 2 s.
/// Error: drift along the slope (m); expected 0.
pub fn slope_stick(settings: &Settings, dt: Real) -> Measurement {
    let theta = (20.0 as Real).to_radians();
    let mu = 0.6;
    let (w, id, diverged) = box_on_slope(settings, dt, theta, mu, 2.0);
    let p = pos(&w, id);
    finish(
        (
            "slope_stick",
            "m",
            "drift along the slope after 2 s (expected 0)",
        ),
        &w,
        diverged,
        (p.x as f64).abs(),
        vec![
            ("drift (m)", p.x as f64),
            ("sinking (m)", 0.5 - p.y as f64),
            (
                "mixed mu",
                settings.friction_mixing.mix(mu as Real, mu as Real) as f64,
            ),
            ("tan theta", theta.tan() as f64),
        ],
    )
}

/// A box sliding from rest down a 30 deg "slope" with mu = 0.2, 1 s.
/// Error: |x - a t^2/2| (m) with a = g (sin theta - mu cos theta).
pub fn slope_slide(settings: &Settings, dt: Real) -> Measurement {
    let theta = (30.0 as Real).to_radians();
    let mu = 0.2;
    let mu_mixed = settings.friction_mixing.mix(mu, mu) as f64;
    let (s, c) = ((theta as f64).sin(), (theta as f64).cos());
    let a = G as f64 * (s - mu_mixed * c);
    let (w, id, diverged) = box_on_slope(settings, dt, theta, mu, 1.0);
    let t = w.time();
    let x = pos(&w, id).x as f64;
    let speed = vel(&w, id).x as f64;
    uniformly_accelerated(
        "slope_slide",
        "|x - a t^2/2| at t = 1 s",
        &w,
        diverged,
        x,
        a,
        t,
        vec![("speed at 1 s (m/s)", speed)],
    )
}

/// A 1 m box dropped from 2 m (bottom to ground), e = 0.8 on both bodies.
/// Error: |h1/h0 - e^2| (dimensionless) for the first rebound.
pub fn bounce(settings: &Settings, dt: Real) -> Measurement {
    let e = 0.8;
    let e_mixed = settings.restitution_mixing.mix(e, e) as f64;
    let h0 = 2.0;
    let mut w = new_world(settings, vec2(0.0, -G));
    floor(&mut w, 0.6, e);
    let id = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, h0 + 0.5)).with_restitution(e))
        .unwrap();
    // Falling 2 m takes 0.64 s, rising 1.28 m takes 0.51 s: 2 s is plenty.
    let n = steps_for(2.0, dt);
    let mut phase = 0; // 0 falling, 1 rising after the first impact, 2 done
    let mut apex = f64::NAN;
    let mut impact_speed = f64::NAN;
    let mut last_vy = 0.0f64;
    let diverged = !run_steps(&mut w, dt, n, Breakdown::BlownUp(1e3), |w, _| {
        let b = w.body(id).unwrap();
        let vy = b.linear_velocity().y as f64;
        let bottom = b.position().y as f64 - 0.5;
        match phase {
            0 if vy > 0.0 => {
                impact_speed = -last_vy;
                phase = 1;
                apex = bottom;
            }
            1 => {
                apex = apex.max(bottom);
                if vy <= 0.0 {
                    phase = 2;
                }
            }
            _ => {}
        }
        last_vy = vy;
    });
    let ratio = apex / h0 as f64;
    let mut m = finish(
        ("bounce", "1", "|rebound height / drop height - e^2|"),
        &w,
        diverged,
        (ratio - e_mixed * e_mixed).abs(),
        vec![
            ("rebound ratio", ratio),
            ("expected ratio e^2", e_mixed * e_mixed),
            ("speed the step before impact (m/s)", impact_speed),
            (
                "expected impact speed (m/s)",
                (2.0 * G as f64 * h0 as f64).sqrt(),
            ),
        ],
    );
    if phase == 0 {
        // Never bounced: the error is the whole expected ratio.
        m.error = e_mixed * e_mixed;
    }
    m
}

/// Head-on: 1 kg at +4 m/s meets 3 kg at -2 m/s, e = 0.5, no gravity, 1 s.
/// Error: |(v2' - v1') - e (v1 - v2)| (m/s); momentum error in the details.
pub fn head_on(settings: &Settings, dt: Real) -> Measurement {
    let (m1, m2) = (1.0 as Real, 3.0 as Real);
    let (v1, v2) = (4.0 as Real, -2.0 as Real);
    let e = 0.5;
    let e_mixed = settings.restitution_mixing.mix(e, e) as f64;
    let mut w = new_world(settings, Vec2::ZERO);
    let a = w
        .add_body(
            &BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(-2.0, 0.0))
                .with_mass(m1)
                .with_velocity(vec2(v1, 0.0))
                .with_restitution(e),
        )
        .unwrap();
    let b = w
        .add_body(
            &BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(2.0, 0.0))
                .with_mass(m2)
                .with_velocity(vec2(v2, 0.0))
                .with_restitution(e),
        )
        .unwrap();
    // The 3 m gap closes at 6 m/s in 0.5 s.
    let n = steps_for(1.0, dt);
    let diverged = !run_steps(&mut w, dt, n, Breakdown::BlownUp(1e3), |_, _| {});
    let (u1, u2) = (vel(&w, a), vel(&w, b));
    let (m1, m2, v1, v2) = (m1 as f64, m2 as f64, v1 as f64, v2 as f64);
    let p0 = m1 * v1 + m2 * v2;
    let p1 = m1 * u1.x as f64 + m2 * u2.x as f64;
    let law = (u2.x - u1.x) as f64 - e_mixed * (v1 - v2);
    let expected_v1 = (p0 - m2 * e_mixed * (v1 - v2)) / (m1 + m2);
    let expected_v2 = (p0 + m1 * e_mixed * (v1 - v2)) / (m1 + m2);
    finish(
        ("head_on", "m/s", "|(v2' - v1') - e (v1 - v2)|"),
        &w,
        diverged,
        law.abs(),
        vec![
            ("momentum error (kg m/s)", (p1 - p0).abs()),
            ("v1' (m/s)", u1.x as f64),
            ("expected v1' (m/s)", expected_v1),
            ("v2' (m/s)", u2.x as f64),
            ("expected v2' (m/s)", expected_v2),
            (
                "spin after (rad/s)",
                w.body(a).unwrap().angular_velocity().abs() as f64
                    + w.body(b).unwrap().angular_velocity().abs() as f64,
            ),
        ],
    )
}

/// A 2 m x 1 m box of 3 kg spun by a constant 2.5 N m torque for 1 s, no gravity.
/// Error: |omega - tau t / I| (rad/s), I = m (w^2 + h^2) / 12 = 1.25 kg m^2.
pub fn spin(settings: &Settings, dt: Real) -> Measurement {
    let (m, wd, ht, tau) = (3.0 as Real, 2.0 as Real, 1.0 as Real, 2.5 as Real);
    let inertia = (m * (wd * wd + ht * ht) / 12.0) as f64;
    let mut w = new_world(settings, Vec2::ZERO);
    let id = w
        .add_body(&BodyDef::dynamic(Shape::rect(wd, ht), Vec2::ZERO).with_mass(m))
        .unwrap();
    let n = steps_for(1.0, dt);
    let mut diverged = false;
    for _ in 0..n {
        if w.apply_torque(id, tau).is_err() || w.step(dt).is_err() || blown_up(&w, 1e3) {
            diverged = true;
            break;
        }
    }
    let t = w.time();
    let b = w.body(id).unwrap();
    let omega = b.angular_velocity() as f64;
    let expected = tau as f64 * t / inertia;
    finish(
        ("spin", "rad/s", "|omega - tau t / I| at t = 1 s"),
        &w,
        diverged,
        (omega - expected).abs(),
        vec![
            ("omega (rad/s)", omega),
            ("expected omega (rad/s)", expected),
            ("angle (rad)", b.angle() as f64),
            ("continuous angle tau t^2/(2I) (rad)", 0.5 * expected * t),
            ("drift of centre (m)", b.position().length() as f64),
        ],
    )
}

/// 10 boxes of 1 m stacked on the ground, 10 s. Error: displacement of the top box (m).
pub fn resting_stack(settings: &Settings, dt: Real) -> Measurement {
    let mut w = new_world(settings, vec2(0.0, -G));
    crate::measure::cases::ground(&mut w, 0.0, 40.0, 2.0).unwrap();
    let ids = crate::measure::cases::stack(&mut w, 10, 1.0, 0.0, 0.0).unwrap();
    let top = *ids.last().unwrap();
    let p0 = pos(&w, top);
    let n = steps_for(10.0, dt);
    let mut max_drift: f64 = 0.0;
    let diverged = !run_steps(&mut w, dt, n, Breakdown::BlownUp(1e3), |w, _| {
        max_drift = max_drift.max((pos(w, top).x - p0.x).abs() as f64);
    });
    let p = pos(&w, top);
    finish(
        (
            "resting_stack",
            "m",
            "|top box position - where it was placed| after 10 s",
        ),
        &w,
        diverged,
        (p - p0).length() as f64,
        vec![
            ("top sinking (m)", (p0.y - p.y) as f64),
            ("top drift (m)", (p.x - p0.x) as f64),
            ("largest top drift during run (m)", max_drift),
            ("penetration at end (m)", max_penetration(&w)),
        ],
    )
}

/// A disc of radius 0.5 m on a 30 deg "slope" (tilted gravity) with friction `mu`, run 1 s
/// from rest: (world, disc id, measured x, v, omega, t).
fn disc_on_slope(settings: &Settings, dt: Real, mu: Real) -> (World, bool, f64, f64, f64, f64) {
    let theta = (30.0 as Real).to_radians();
    let mut w = new_world(settings, tilted(theta));
    floor(&mut w, mu, 0.0);
    let id = w
        .add_body(&BodyDef::dynamic(Shape::circle(DISC_R), vec2(0.0, DISC_R)).with_friction(mu))
        .unwrap();
    let n = steps_for(1.0, dt);
    let diverged = !run_steps(&mut w, dt, n, Breakdown::BlownUp(1e3), |_, _| {});
    let x = pos(&w, id).x as f64;
    let v = vel(&w, id).x as f64;
    let omega = w.body(id).map_or(f64::NAN, |b| b.angular_velocity() as f64);
    let t = w.time();
    (w, diverged, x, v, omega, t)
}

/// Radius of the rolling and sliding disc (m).
const DISC_R: Real = 0.5;

/// Rolling without slipping (mu = 0.5 >= tan theta / 3): a solid disc (I = m r^2 / 2)
/// accelerates at a = g sin theta / (1 + I / (m r^2)) = (2/3) g sin theta, and its contact
/// point stays at rest: v + omega r = 0 (it spins clockwise while moving to +x).
/// Error: |x - a t^2/2| at t = 1 s (m).
pub fn disc_rolls(settings: &Settings, dt: Real) -> Measurement {
    let theta = (30.0f64).to_radians();
    let a = 2.0 / 3.0 * G as f64 * theta.sin();
    let (w, diverged, x, v, omega, t) = disc_on_slope(settings, dt, 0.5);
    uniformly_accelerated(
        "disc_rolls",
        "|x - a t^2/2| at t = 1 s, a = (2/3) g sin theta",
        &w,
        diverged,
        x,
        a,
        t,
        vec![
            ("slip speed v + omega r (m/s)", v + omega * DISC_R as f64),
            ("speed at 1 s (m/s)", v),
        ],
    )
}

/// Sliding (mu = 0.1 < tan theta / 3): the centre accelerates at g (sin theta - mu cos theta)
/// while kinetic friction mu m g cos theta spins the disc up at alpha = 2 mu g cos theta / r.
/// Error: |x - a t^2/2| at t = 1 s (m); the spin error is a detail.
pub fn disc_slides(settings: &Settings, dt: Real) -> Measurement {
    let theta = (30.0f64).to_radians();
    let mu = 0.1;
    let mu_mixed = settings.friction_mixing.mix(mu, mu) as f64;
    let a = G as f64 * (theta.sin() - mu_mixed * theta.cos());
    let alpha = 2.0 * mu_mixed * G as f64 * theta.cos() / DISC_R as f64;
    let (w, diverged, x, v, omega, t) = disc_on_slope(settings, dt, mu);
    uniformly_accelerated(
        "disc_slides",
        "|x - a t^2/2| at t = 1 s, a = g (sin theta - mu cos theta)",
        &w,
        diverged,
        x,
        a,
        t,
        vec![
            ("spin |omega| at 1 s (rad/s)", omega.abs()),
            ("expected spin alpha t (rad/s)", alpha * t),
            ("slip speed v + omega r (m/s)", v + omega * DISC_R as f64),
        ],
    )
}
