//! The stiff and extreme suite. Every case takes the solver configuration, runs at
//! [`DT_60`] (unless the case is about the step itself) and returns a [`Verdict`] with its
//! criterion in words, pass/fail and the measured numbers.

//!
//! - `stacks.rs`: stacks and pyramids, and a stack far from the origin;
//! - `contacts.rs`: mass ratios, deep overlap and overlap recovery, bullets and fast spinners,
//!   a pile of mixed shapes;
//! - `limits.rs`: tiny and large bodies, gravity flips, a huge step, non-finite input;
//! - `terrain.rs`: sliding across a tiled floor, as boxes and as a chain; rolling down a chain;
//! - `motion.rs`: contacts that move: kinematic carriers and pushers, rolling, bouncing;
//! - `joints.rs`: a hanging chain, a heavy block on a light rope, a slack bridge;
//! - `machines.rs`: motors and bodies of several shapes: Box2D's tumbler and spinner, a car,
//!   a pile of ragdolls.

mod contacts;
mod joints;
mod limits;
mod machines;
mod motion;
mod stacks;
mod terrain;

pub use contacts::{
    box_pile, bullet, deep_overlap, fast_spinners, mass_ratio_100, mass_ratio_1000, mixed_pile,
    overlap_recovery,
};
pub use joints::{bridge, hanging_chain, heavy_rope};
pub use limits::{gravity_flip, huge_dt, large_bodies, non_finite_refused, tiny_bodies};
pub use machines::{car, ragdoll_pile, spinner, tumbler};
pub use motion::{kinematic_carrier, kinematic_pusher, restitution_drop, rolling_disc};
pub use stacks::{
    far_from_origin, pyramid_100, pyramid_134, pyramid_20, pyramid_200, pyramid_30, pyramid_sleeps,
    real_spacing, stack_20, stack_50,
};
pub use terrain::{chain_slope, tiled_floor_boxes, tiled_floor_chain};

use super::{run_steps, steps_for, Breakdown, Verdict, DT_60, G};
use crate::physics::{vec2, BodyId, Settings, Vec2, World};

/// A runner of the suite: the solver configuration in, the case's [`Verdict`] out.
pub type Runner = fn(&Settings) -> Verdict;

/// A stiff or extreme case: name, title and runner.
#[derive(Clone, Copy, Debug)]
pub struct ExtremeCase {
    /// Machine name (matches [`Verdict::case`]).
    pub name: &'static str,
    /// Human title.
    pub title: &'static str,
    /// The runner.
    pub run: Runner,
    /// Too slow for CI in a debug build; run by the report only.
    pub report_only: bool,
}

/// A case CI runs.
const fn case(name: &'static str, title: &'static str, run: Runner) -> ExtremeCase {
    ExtremeCase {
        name,
        title,
        run,
        report_only: false,
    }
}

/// A case run by the report only: too slow for CI in a debug build (the large pyramids).
const fn report_case(name: &'static str, title: &'static str, run: Runner) -> ExtremeCase {
    ExtremeCase {
        report_only: true,
        ..case(name, title, run)
    }
}

/// Every case, in report order (the report-only cases last). One row a case, kept as a
/// table.
#[rustfmt::skip]
const CASES: [ExtremeCase; 36] = [
    case("stack_20", "Stack of 20, 30 s", stack_20),
    case("stack_50", "Stack of 50, 10 s", stack_50),
    case("pyramid_20", "Pyramid base 20, 30 s", pyramid_20),
    case("pyramid_30", "Symmetric pyramid base 30, 20 s", pyramid_30),
    case("pyramid_sleeps", "Pyramid base 20 falls asleep", pyramid_sleeps),
    case("mass_ratio_100", "Mass ratio 100:1", mass_ratio_100),
    case("mass_ratio_1000", "Mass ratio 1000:1", mass_ratio_1000),
    case("deep_overlap", "Deep overlap at spawn", deep_overlap),
    case("bullet", "Bullet 200 m/s vs 0.1 m wall", bullet),
    case("far_from_origin", "Stack at x = 10 km", far_from_origin),
    case("tiny_bodies", "Tiny bodies (1 cm)", tiny_bodies),
    case("large_bodies", "Large body (50 m)", large_bodies),
    case("gravity_flip", "Gravity flipped at 10 g", gravity_flip),
    case("mixed_pile", "Pile of mixed shapes comes to rest", mixed_pile),
    case("huge_dt", "Huge dt (0.1 s)", huge_dt),
    case("tiled_floor_boxes", "Slide across a tiled floor (tiles as boxes)", tiled_floor_boxes),
    case("tiled_floor_chain", "Slide across a tiled floor (one chain)", tiled_floor_chain),
    case("non_finite_refused", "NaN / inf refused", non_finite_refused),
    case("box_pile", "Pile of 2,000 boxes comes to rest (six nudges)", box_pile),
    case("kinematic_carrier", "A box carried by a moving platform", kinematic_carrier),
    case("kinematic_pusher", "A moving wall pushes 64 boxes", kinematic_pusher),
    case("rolling_disc", "A disc rolling at up to 20 m/s", rolling_disc),
    case("restitution_drop", "Discs dropped 2 m rebound at e x impact", restitution_drop),
    case("overlap_recovery", "Boxes placed 25 % inside one another", overlap_recovery),
    case("fast_spinners", "Skinny bodies at 100 m/s, spinning, onto thin statics", fast_spinners),
    case("chain_slope", "A disc rolling down a slope of chain pieces", chain_slope),
    case("pyramid_200", "Pyramid base 200 (20,100 boxes) holds its top", pyramid_200),
    case("hanging_chain", "A 50-link chain hangs by its joints' give", hanging_chain),
    case("heavy_rope", "A 900 kg block on 0.5 kg links (1,800:1)", heavy_rope),
    case("bridge", "A slack 100-plank bridge hangs as a catenary", bridge),
    case("tumbler", "A 4,000 kg drum tumbles 2,025 boxes of 62.5 g", tumbler),
    case("spinner", "A paddle of unlimited torque stirs 6,076 bodies", spinner),
    case("car", "A car on wheel joints drives over hills", car),
    case("ragdoll_pile", "A pile of 30 ragdolls (Box2D's human.c)", ragdoll_pile),
    report_case("pyramid_134", "Pyramid base 134 (9,045 boxes) stands", pyramid_134),
    report_case("pyramid_100", "Pyramid base 100 (5,050 boxes)", pyramid_100),
];

/// Every case, in report order (the report-only cases last).
pub fn all() -> &'static [ExtremeCase] {
    &CASES
}

/// Run every case (`with_report_only` adds the report-only pyramids) with `settings`.
pub fn suite(settings: &Settings, with_report_only: bool) -> Vec<Verdict> {
    all()
        .iter()
        .filter(|c| with_report_only || !c.report_only)
        .map(|c| (c.run)(settings))
        .collect()
}

pub(super) fn verdict(
    case: &'static str,
    criterion: String,
    passed: bool,
    measured: Vec<(&'static str, f64)>,
    note: impl Into<String>,
) -> Verdict {
    Verdict {
        case,
        criterion,
        passed,
        report_only: false,
        measured,
        note: note.into(),
    }
}

/// Step `w` for `seconds` at [`DT_60`], calling `each(w, k)` after step `k`, until the world
/// breaks down as `breakdown` says ([`run_steps`]); true when every step ran.
pub(super) fn run_60hz(
    w: &mut World,
    seconds: f64,
    breakdown: Breakdown,
    each: impl FnMut(&World, u64),
) -> bool {
    run_steps(w, DT_60, steps_for(seconds, DT_60), breakdown, each)
}

/// The verdict of a report-only case: measured for the report (too slow for CI), its times
/// wall-clock.
pub(super) fn report_verdict(
    case: &'static str,
    criterion: &str,
    passed: bool,
    measured: Vec<(&'static str, f64)>,
) -> Verdict {
    Verdict {
        report_only: true,
        ..verdict(
            case,
            criterion.into(),
            passed,
            measured,
            "time is wall-clock on the machine that ran it, single thread",
        )
    }
}

pub(super) fn gravity() -> Vec2 {
    vec2(0.0, -G)
}

pub(super) fn pos(w: &World, id: BodyId) -> Vec2 {
    w.body(id).map(|b| b.position()).unwrap_or(Vec2::NAN)
}

pub(super) fn all_finite(w: &World) -> bool {
    w.bodies().all(|b| b.is_finite())
}

pub(super) fn max_speed(w: &World) -> f64 {
    w.bodies()
        .map(|b| b.linear_velocity().length() as f64)
        .fold(0.0, f64::max)
}

/// How far a box centre `p` is outside the inner region of a closed box (inner `width` x
/// `height`, floor at 0), inset by `inset` (half the body's size); 0 if inside.
pub(super) fn outside_box(p: Vec2, width: f64, height: f64, inset: f64) -> f64 {
    let (x, y) = (p.x as f64, p.y as f64);
    if !x.is_finite() || !y.is_finite() {
        return f64::INFINITY;
    }
    let half = 0.5 * width - inset;
    [x.abs() - half, inset - y, y - (height - inset)]
        .into_iter()
        .fold(0.0, f64::max)
}
