//! The stiff and extreme suite. Every case takes the solver configuration, runs at
//! [`DT_60`] (unless the case is about the step itself) and returns a [`Verdict`] with its
//! criterion in words, pass/fail and the measured numbers.

use super::{max_penetration, new_world, run_steps, steps_for, Breakdown, Verdict, DT_60, G};
use crate::measure::cases;
use crate::physics::{
    vec2, BodyDef, BodyId, PhysicsError, Real, Settings, Shape, SolverKind, Vec2, World,
};
use std::time::Instant;

/// A stiff or extreme case: name, title and runner.
#[derive(Clone, Copy, Debug)]
pub struct ExtremeCase {
    /// Machine name (matches [`Verdict::case`]).
    pub name: &'static str,
    /// Human title.
    pub title: &'static str,
    /// The runner.
    pub run: fn(&Settings) -> Verdict,
    /// Too slow for CI in a debug build; run by the report only.
    pub report_only: bool,
}

/// The cases with a criterion, in report order: machine name, title, runner.
#[rustfmt::skip] // a table: one case a line
const CASES: [(&str, &str, fn(&Settings) -> Verdict); 15] = [
    ("stack_20", "Stack of 20, 30 s", stack_20),
    ("stack_50", "Stack of 50, 10 s", stack_50),
    ("pyramid_20", "Pyramid base 20, 30 s", pyramid_20),
    ("pyramid_sleeps", "Pyramid base 20 falls asleep", pyramid_sleeps),
    ("mass_ratio_100", "Mass ratio 100:1", mass_ratio_100),
    ("mass_ratio_1000", "Mass ratio 1000:1", mass_ratio_1000),
    ("deep_overlap", "Deep overlap at spawn", deep_overlap),
    ("bullet", "Bullet 200 m/s vs 0.1 m wall", bullet),
    ("far_from_origin", "Stack at x = 10 km", far_from_origin),
    ("tiny_bodies", "Tiny bodies (1 cm)", tiny_bodies),
    ("large_bodies", "Large body (50 m)", large_bodies),
    ("gravity_flip", "Gravity flipped at 10 g", gravity_flip),
    ("mixed_pile", "Pile of mixed shapes comes to rest", mixed_pile),
    ("huge_dt", "Huge dt (0.1 s)", huge_dt),
    ("non_finite_refused", "NaN / inf refused", non_finite_refused),
];

/// Every case, in report order (`pyramid_100` last, report only).
pub fn all() -> Vec<ExtremeCase> {
    let with_criterion = CASES.iter().map(|&(name, title, run)| ExtremeCase {
        name,
        title,
        run,
        report_only: false,
    });
    with_criterion
        .chain(std::iter::once(ExtremeCase {
            name: "pyramid_100",
            title: "Pyramid base 100 (5,050 boxes)",
            run: pyramid_100,
            report_only: true,
        }))
        .collect()
}

/// Run every case (`with_report_only` adds the pyramid of base 100) with `settings`.
pub fn suite(settings: &Settings, with_report_only: bool) -> Vec<Verdict> {
    all()
        .into_iter()
        .filter(|c| with_report_only || !c.report_only)
        .map(|c| (c.run)(settings))
        .collect()
}

fn verdict(
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

fn gravity() -> Vec2 {
    vec2(0.0, -G)
}

fn pos(w: &World, id: BodyId) -> Vec2 {
    w.body(id).map(|b| b.position()).unwrap_or(Vec2::NAN)
}

fn all_finite(w: &World) -> bool {
    w.bodies().all(|b| b.is_finite())
}

fn max_speed(w: &World) -> f64 {
    w.bodies()
        .map(|b| b.linear_velocity().length() as f64)
        .fold(0.0, f64::max)
}

/// Step `w` for `seconds` at [`DT_60`]: [`run_steps`] counted in seconds.
fn for_seconds(
    w: &mut World,
    seconds: f64,
    breakdown: Breakdown,
    each: impl FnMut(&World, u64),
) -> bool {
    run_steps(w, DT_60, steps_for(seconds, DT_60), breakdown, each)
}

/// What a stack run measured.
struct StackRun {
    /// Largest |x - x0| of the top box at any step (m).
    top_drift: f64,
    /// Top box: start height minus end height (m).
    top_sinking: f64,
    /// Largest |y - y0| of the top box at any step (m).
    top_bob: f64,
    /// Largest |x - x0| of any box at the end (m).
    worst_drift: f64,
    finite: bool,
}

fn run_stack(settings: &Settings, n: usize, x: Real, seconds: f64) -> (StackRun, Vec<Vec2>) {
    run_stack_with(settings, n, x, seconds, true)
}

fn run_stack_with(
    settings: &Settings,
    n: usize,
    x: Real,
    seconds: f64,
    jitter: bool,
) -> (StackRun, Vec<Vec2>) {
    let mut w = new_world(settings, gravity());
    cases::ground(&mut w, x, 40.0, 2.0).unwrap();
    let ids = if jitter {
        cases::jittered_stack(&mut w, n, 1.0, x).unwrap()
    } else {
        cases::stack(&mut w, n, 1.0, x, 0.0).unwrap()
    };
    let start: Vec<Vec2> = ids.iter().map(|&id| pos(&w, id)).collect();
    let top = *ids.last().unwrap();
    let mut top_drift: f64 = 0.0;
    let mut top_bob: f64 = 0.0;
    let finite = for_seconds(&mut w, seconds, Breakdown::NonFinite, |w, _| {
        let d = pos(w, top) - start[n - 1];
        top_drift = top_drift.max(d.x.abs() as f64);
        top_bob = top_bob.max(d.y.abs() as f64);
    });
    let end: Vec<Vec2> = ids.iter().map(|&id| pos(&w, id)).collect();
    let disp: Vec<Vec2> = end.iter().zip(&start).map(|(e, s)| *e - *s).collect();
    let worst_drift = disp.iter().map(|d| d.x.abs() as f64).fold(0.0, f64::max);
    (
        StackRun {
            top_drift,
            top_sinking: -(disp[n - 1].y as f64),
            top_bob,
            worst_drift,
            finite,
        },
        disp,
    )
}

/// Vertical stack of 20 boxes (1 m) for 30 s: top box drift < 2 cm, nothing falls.
pub fn stack_20(settings: &Settings) -> Verdict {
    stack_verdict(
        settings,
        "stack_20",
        20,
        30.0,
        "20 boxes of 1 m (+-1 cm jitter) stand 30 s at 60 Hz: top box drifts < 2 cm sideways and moves < 0.5 m vertically at every step",
        |r| r.top_drift < 0.02 && r.top_bob < 0.5,
    )
}

/// Vertical stack of 50 boxes (1 m) for 10 s: stands.
pub fn stack_50(settings: &Settings) -> Verdict {
    stack_verdict(
        settings,
        "stack_50",
        50,
        10.0,
        "50 boxes of 1 m (+-1 cm jitter) stand 10 s at 60 Hz: top box within 0.5 m of its start (sideways and vertically) at every step, every box within 0.5 m sideways at the end",
        |r| r.worst_drift < 0.5 && r.top_drift < 0.5 && r.top_bob < 0.5,
    )
}

/// A jittered stack of `n` boxes run for `seconds`, judged by `stands` (on top of staying
/// finite); an aligned stack of the same height is measured alongside.
fn stack_verdict(
    settings: &Settings,
    case: &'static str,
    n: usize,
    seconds: f64,
    criterion: &str,
    stands: fn(&StackRun) -> bool,
) -> Verdict {
    let (r, _) = run_stack(settings, n, 0.0, seconds);
    let (aligned, _) = run_stack_with(settings, n, 0.0, seconds, false);
    verdict(
        case,
        criterion.into(),
        r.finite && stands(&r),
        vec![
            ("top drift max (m)", r.top_drift),
            ("top vertical excursion max (m)", r.top_bob),
            ("top sinking at end (m)", r.top_sinking),
            ("worst box drift at end (m)", r.worst_drift),
            ("aligned stack: top drift max (m)", aligned.top_drift),
            ("aligned stack: top vertical excursion max (m)", aligned.top_bob),
        ],
        "the criterion applies to the jittered stack; a perfectly aligned stack (`cases::stack`) is also measured",
    )
}

/// What a pyramid run measured: largest displacement and rotation of any box.
fn run_pyramid(settings: &Settings, base: usize, seconds: f64) -> (f64, f64, bool, f64) {
    let mut w = new_world(settings, gravity());
    cases::ground(&mut w, 0.0, 2.0 * base as Real + 20.0, 2.0).unwrap();
    let ids = cases::pyramid(&mut w, base, 1.0, 0.0, 0.6).unwrap();
    let start: Vec<Vec2> = ids.iter().map(|&id| pos(&w, id)).collect();
    let n = steps_for(seconds, DT_60);
    let t0 = Instant::now();
    let finite = run_steps(&mut w, DT_60, n, Breakdown::NonFinite, |_, _| {});
    let ms = t0.elapsed().as_secs_f64() * 1e3 / n as f64;
    let disp = ids
        .iter()
        .zip(&start)
        .map(|(&id, s)| (pos(&w, id) - *s).length() as f64)
        .fold(0.0, f64::max);
    let rot = ids
        .iter()
        .map(|&id| w.body(id).unwrap().angle().abs() as f64)
        .fold(0.0, f64::max);
    (disp, rot, finite, ms)
}

/// Pyramid of base 20 (210 boxes) for 30 s: intact.
pub fn pyramid_20(settings: &Settings) -> Verdict {
    let (disp, rot, finite, _) = run_pyramid(settings, 20, 30.0);
    verdict(
        "pyramid_20",
        "pyramid of base 20 intact after 30 s at 60 Hz: every box within 0.25 m of its start and turned < 0.1 rad".into(),
        finite && disp < 0.25 && rot < 0.1,
        vec![("largest displacement (m)", disp), ("largest rotation (rad)", rot)],
        "",
    )
}

/// Pyramid of base 20 with sleeping allowed (Box2D's defaults: below 0.05 m/s for 0.5 s):
/// every box asleep within 5 s, and intact.
pub fn pyramid_sleeps(settings: &Settings) -> Verdict {
    let settings = Settings {
        enable_sleep: true,
        ..settings.clone()
    };
    let mut w = World::new(settings.clone(), gravity()).expect("valid settings");
    cases::ground(&mut w, 0.0, 60.0, 2.0).unwrap();
    let ids = cases::pyramid(&mut w, 20, 1.0, 0.0, 0.6).unwrap();
    let start: Vec<Vec2> = ids.iter().map(|&id| pos(&w, id)).collect();
    let mut asleep_at = f64::NAN;
    let ok = for_seconds(&mut w, 5.0, Breakdown::NonFinite, |w, _| {
        if asleep_at.is_nan() && ids.iter().all(|&id| !w.body(id).unwrap().is_awake()) {
            asleep_at = w.time();
        }
    });
    let awake = ids
        .iter()
        .filter(|&&id| w.body(id).unwrap().is_awake())
        .count();
    let disp = ids
        .iter()
        .zip(&start)
        .map(|(&id, s)| (pos(&w, id) - *s).length() as f64)
        .fold(0.0, f64::max);
    verdict(
        "pyramid_sleeps",
        format!(
            "pyramid of base 20 with sleep on (below {} m/s for {} s): all 210 boxes asleep within 5 s, every box within 0.25 m of its start",
            settings.sleep_threshold, settings.time_to_sleep
        ),
        ok && awake == 0 && disp < 0.25,
        vec![
            ("all asleep at (s)", asleep_at),
            ("boxes awake after 5 s", awake as f64),
            ("largest displacement (m)", disp),
        ],
        "",
    )
}

/// Pyramid of base 100 (5,050 boxes), 500 steps at 60 Hz (Box2D's large_pyramid benchmark):
/// measured for the report, no pass criterion.
pub fn pyramid_100(settings: &Settings) -> Verdict {
    let (disp, rot, finite, ms) = run_pyramid(settings, 100, 500.0 / 60.0);
    Verdict {
        case: "pyramid_100",
        criterion:
            "report only: 500 steps at 60 Hz; largest displacement and rotation, time per step"
                .into(),
        passed: finite,
        report_only: true,
        measured: vec![
            ("largest displacement (m)", disp),
            ("largest rotation (rad)", rot),
            ("ms per step", ms),
        ],
        note: "time is wall-clock on the machine that ran it, single thread".into(),
    }
}

/// A 4 m x 1 m box `ratio` times heavier than each of the two 1 m boxes it rests on, 5 s.
fn mass_ratio(settings: &Settings, case: &'static str, ratio: Real) -> Verdict {
    let mut w = new_world(settings, gravity());
    cases::ground(&mut w, 0.0, 40.0, 2.0).unwrap();
    for x in [-1.5, 1.5] {
        w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(x, 0.5)).with_mass(1.0))
            .unwrap();
    }
    let big = w
        .add_body(&BodyDef::dynamic(Shape::rect(4.0, 1.0), vec2(0.0, 1.5)).with_mass(ratio))
        .unwrap();
    let mut pen: f64 = 0.0;
    let mut speed: f64 = 0.0;
    let ok = for_seconds(&mut w, 5.0, Breakdown::BlownUp(100.0), |w, _| {
        pen = pen.max(max_penetration(w));
        speed = speed.max(max_speed(w));
    });
    let p = pos(&w, big);
    let sinking = 1.5 - p.y as f64;
    let slop = settings.linear_slop as f64;
    let passed = ok && pen <= 2.0 * slop && speed < 1.0 && (p.x as f64).abs() < 0.05;
    verdict(
        case,
        format!(
            "{ratio}:1 box on two 1 kg boxes, 5 s: every contact's penetration <= 2 x slop = {} m, \
             no body faster than 1 m/s, heavy box moves < 5 cm sideways",
            super::fmt_num(2.0 * slop)
        ),
        passed,
        vec![
            ("largest penetration (m)", pen),
            ("heavy box sinking (m)", sinking),
            ("largest speed (m/s)", speed),
            ("heavy box drift (m)", p.x as f64),
        ],
        "",
    )
}

/// Mass ratio 100:1.
pub fn mass_ratio_100(settings: &Settings) -> Verdict {
    mass_ratio(settings, "mass_ratio_100", 100.0)
}

/// Mass ratio 1000:1.
pub fn mass_ratio_1000(settings: &Settings) -> Verdict {
    mass_ratio(settings, "mass_ratio_1000", 1000.0)
}

/// Inside a closed 10 m x 10 m box: two pairs of 1 m boxes spawned half inside each other
/// (one side by side, one on top of the other), one box half inside the floor, one half inside
/// the left wall. Run 3 s.
pub fn deep_overlap(settings: &Settings) -> Verdict {
    let mut w = new_world(settings, gravity());
    cases::closed_box(&mut w, 10.0, 10.0, 0.5).unwrap();
    let spots = [
        vec2(-2.5, 0.5),
        vec2(-2.0, 0.5), // side by side, 0.5 m overlap
        vec2(2.5, 0.5),
        vec2(2.5, 1.0),  // on top, 0.5 m overlap
        vec2(0.0, 0.0),  // half inside the floor
        vec2(-5.0, 0.5), // half inside the left wall
    ];
    let ids: Vec<BodyId> = spots
        .iter()
        .map(|&p| {
            w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), p))
                .unwrap()
        })
        .collect();
    let mut speed: f64 = 0.0;
    let mut outside: f64 = 0.0;
    let ok = for_seconds(&mut w, 3.0, Breakdown::BlownUp(100.0), |w, _| {
        speed = speed.max(max_speed(w));
        for &id in &ids {
            outside = outside.max(outside_box(pos(w, id), 10.0, 10.0, 0.0));
        }
    });
    let pen = max_penetration(&w);
    let slop = settings.linear_slop as f64;
    // At the end every box must be fully inside, give or take the allowed overlap.
    let still_in_wall = ids
        .iter()
        .map(|&id| outside_box(pos(&w, id), 10.0, 10.0, 0.5 - 2.0 * slop))
        .fold(0.0, f64::max);
    let cap = settings.max_push_out_speed as f64;
    let passed =
        ok && speed <= 1.1 * cap && pen <= 2.0 * slop && outside == 0.0 && still_in_wall == 0.0;
    verdict(
        "deep_overlap",
        format!(
            "boxes spawned 0.5 m inside each other / the floor / a wall: peak speed <= 1.1 x push-out cap ({cap} m/s), \
             penetration after 3 s <= 2 x slop = {} m, no box centre ever beyond a wall surface, every box clear of the walls at the end",
            super::fmt_num(2.0 * slop)
        ),
        passed,
        vec![
            ("peak speed (m/s)", speed),
            ("penetration after 3 s (m)", pen),
            ("worst excursion of a centre beyond a wall (m)", outside),
            ("overlap with a wall at the end (m)", still_in_wall),
        ],
        if settings.solver == SolverKind::Sequential {
            "the sequential solver has no push-out cap: its Baumgarte bias is 0.2/dt x depth"
        } else {
            ""
        },
    )
}

/// How far a box centre `p` is outside the inner region of a closed box (inner `width` x
/// `height`, floor at 0), inset by `inset` (half the body's size); 0 if inside.
fn outside_box(p: Vec2, width: f64, height: f64, inset: f64) -> f64 {
    let (x, y) = (p.x as f64, p.y as f64);
    if !x.is_finite() || !y.is_finite() {
        return f64::INFINITY;
    }
    let half = 0.5 * width - inset;
    [x.abs() - half, inset - y, y - (height - inset)]
        .into_iter()
        .fold(0.0, f64::max)
}

/// A 0.1 m bullet at 200 m/s against a static 0.1 m x 4 m wall, 30 steps at 60 Hz, once per
/// shape kind: box, disc, capsule (spinning end over end) and triangle.
pub fn bullet(settings: &Settings) -> Verdict {
    let triangle =
        crate::physics::Polygon::new(&[vec2(-0.05, -0.05), vec2(0.05, 0.0), vec2(-0.05, 0.05)])
            .map(|(p, _)| Shape::from(p))
            .unwrap_or(Shape::rect(0.1, 0.1));
    let kinds = [
        (Shape::rect(0.1, 0.1), 0.0),
        (Shape::circle(0.05), 0.0),
        (Shape::capsule(0.1, 0.02), 40.0),
        (triangle, 0.0),
    ];
    let mut ok = true;
    let mut worst_x = f64::NEG_INFINITY;
    let mut measured = Vec::new();
    for (shape, spin) in kinds {
        let (finite, max_x) = fire_bullet(settings, shape.clone(), spin);
        ok &= finite;
        worst_x = worst_x.max(max_x);
        let name = match shape.kind() {
            "rect" => "largest x of box centre (m)",
            "circle" => "largest x of disc centre (m)",
            "capsule" => "largest x of capsule centre (m)",
            _ => "largest x of triangle centre (m)",
        };
        measured.push((name, max_x));
    }
    // The bullet's centre must stay on the near side of the wall's centre line.
    let passed = ok && worst_x < 0.0;
    verdict(
        "bullet",
        "0.1 m bullets (box, disc, spinning capsule, triangle) at 200 m/s (3.3 m per step) vs a 0.1 m wall centred on x = 0, 30 steps: every bullet's centre stays at x < 0 (near face at x = -0.05)".into(),
        passed,
        measured,
        "",
    )
}

/// One bullet of `shape` spinning at `spin` rad/s: (stayed finite, largest x of its centre).
fn fire_bullet(settings: &Settings, shape: Shape, spin: Real) -> (bool, f64) {
    let mut w = new_world(settings, gravity());
    w.add_body(&BodyDef::fixed(Shape::rect(0.1, 4.0), vec2(0.0, 0.0)))
        .unwrap();
    let b = w
        .add_body(
            &BodyDef::dynamic(shape, vec2(-4.0, 0.0))
                .with_velocity(vec2(200.0, 0.0))
                .with_angular_velocity(spin),
        )
        .unwrap();
    let mut max_x = f64::NEG_INFINITY;
    let finite = run_steps(&mut w, DT_60, 30, Breakdown::NonFinite, |w, _| {
        max_x = max_x.max(pos(w, b).x as f64);
    });
    if finite {
        (true, max_x)
    } else {
        (false, f64::NAN)
    }
}

/// Spacing between adjacent [`Real`] values at `x` (m): the position resolution there.
pub fn real_spacing(x: Real) -> f64 {
    let next = Real::from_bits(x.to_bits() + 1);
    (next - x) as f64
}

/// The same 10-box stack at x = 10 km and at the origin, 10 s: every box's displacement
/// matches within 1 cm.
pub fn far_from_origin(settings: &Settings) -> Verdict {
    let far: Real = 10_000.0;
    let (a, da) = run_stack(settings, 10, 0.0, 10.0);
    let (b, db) = run_stack(settings, 10, far, 10.0);
    let diff = da
        .iter()
        .zip(&db)
        .map(|(p, q)| (*p - *q).length() as f64)
        .fold(0.0, f64::max);
    let spacing = real_spacing(far);
    let passed = a.finite && b.finite && diff < 0.01;
    verdict(
        "far_from_origin",
        "10-box stack (+-1 cm jitter) at x = 10 km vs at the origin, 10 s: every box's displacement agrees within 1 cm".into(),
        passed,
        vec![
            ("largest displacement difference (m)", diff),
            ("top drift at origin (m)", a.top_drift),
            ("top drift at 10 km (m)", b.top_drift),
            ("position spacing at 10 km (m)", spacing),
        ],
        format!(
            "{} position spacing is {:.3e} m at 10 km and {:.3e} m at 1e7 m (f32: ~1 mm and 1 m; the `f64` feature: ~2e-12 m and ~2e-9 m); motion smaller than half the spacing per step is lost",
            std::any::type_name::<Real>(),
            spacing,
            real_spacing(1.0e7)
        ),
    )
}

/// Three 1 cm boxes stacked on the ground, 5 s.
pub fn tiny_bodies(settings: &Settings) -> Verdict {
    let size: Real = 0.01;
    let mut w = new_world(settings, gravity());
    cases::ground(&mut w, 0.0, 10.0, 1.0).unwrap();
    let ids = cases::jittered_stack(&mut w, 3, size, 0.0).unwrap();
    let top = ids[2];
    let p0 = pos(&w, top);
    let mut drift: f64 = 0.0;
    let ok = for_seconds(&mut w, 5.0, Breakdown::BlownUp(100.0), |w, _| {
        drift = drift.max((pos(w, top).x - p0.x).abs() as f64);
    });
    let sinking = (p0.y - pos(&w, top).y) as f64;
    let speed = max_speed(&w);
    let slop = settings.linear_slop as f64;
    let passed = ok && drift < 0.1 * size as f64 && sinking < 3.0 * slop && speed < 0.01;
    verdict(
        "tiny_bodies",
        format!(
            "3 stacked 1 cm boxes (+-0.1 mm jitter), 5 s: top drift < 1 mm (10 % of size), top sinks < 3 x slop = {} m, speeds < 1 cm/s at the end",
            super::fmt_num(3.0 * slop)
        ),
        passed,
        vec![
            ("top drift max (m)", drift),
            ("top sinking (m)", sinking),
            ("speed at end (m/s)", speed),
        ],
        "Box2D advises moving bodies above ~1 cm; the slop (5-10 mm) is comparable to the body",
    )
}

/// A dynamic 50 m x 5 m slab resting on the ground with a 1 m box on top, 5 s.
pub fn large_bodies(settings: &Settings) -> Verdict {
    let mut w = new_world(settings, gravity());
    cases::ground(&mut w, 0.0, 100.0, 2.0).unwrap();
    let slab = w
        .add_body(&BodyDef::dynamic(Shape::rect(50.0, 5.0), vec2(0.0, 2.5)))
        .unwrap();
    let small = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(10.0, 5.5)))
        .unwrap();
    let mut pen: f64 = 0.0;
    let ok = for_seconds(&mut w, 5.0, Breakdown::BlownUp(1000.0), |w, _| {
        pen = pen.max(max_penetration(w));
    });
    let s = pos(&w, slab);
    let b = pos(&w, small);
    let tilt = w.body(slab).unwrap().angle().abs() as f64;
    let drift = ((b.x - 10.0) as f64).abs();
    let slop = settings.linear_slop as f64;
    let passed = ok && pen <= 2.0 * slop && tilt < 1e-3 && drift < 0.01;
    verdict(
        "large_bodies",
        format!(
            "50 m x 5 m dynamic slab on the ground with a 1 m box on it, 5 s: penetration <= 2 x slop = {} m, \
             slab turns < 1 mrad, box drifts < 1 cm",
            super::fmt_num(2.0 * slop)
        ),
        passed,
        vec![
            ("largest penetration (m)", pen),
            ("slab sinking (m)", 2.5 - s.y as f64),
            ("slab tilt (rad)", tilt),
            ("box drift (m)", drift),
        ],
        "Box2D advises moving bodies up to ~10 m and statics up to 50 m",
    )
}

/// Twenty boxes of mixed sizes in a closed 10 m box; gravity 10 g, flipped up/down every
/// second for 10 s.
pub fn gravity_flip(settings: &Settings) -> Verdict {
    let mut w = new_world(settings, vec2(0.0, -10.0 * G));
    cases::closed_box(&mut w, 10.0, 10.0, 0.5).unwrap();
    let mut ids = Vec::new();
    for i in 0..20 {
        let size = 0.3 + 0.9 * ((i * 7) % 10) as Real / 9.0;
        let x = -3.75 + 2.5 * (i % 4) as Real;
        let y = 1.0 + 1.8 * (i / 4) as Real;
        ids.push(
            w.add_body(&BodyDef::dynamic(Shape::rect(size, size), vec2(x, y)))
                .unwrap(),
        );
    }
    let mut inside_wall: f64 = 0.0;
    let mut speed: f64 = 0.0;
    let mut pen: f64 = 0.0;
    let mut ok = true;
    let per_second = steps_for(1.0, DT_60);
    for s in 0..10 {
        let sign = if s % 2 == 0 { -1.0 } else { 1.0 };
        w.set_gravity(vec2(0.0, sign * 10.0 * G)).unwrap();
        ok = run_steps(&mut w, DT_60, per_second, Breakdown::NonFinite, |w, _| {
            speed = speed.max(max_speed(w));
            pen = pen.max(max_penetration(w));
            for &id in &ids {
                inside_wall = inside_wall.max(outside_box(pos(w, id), 10.0, 10.0, 0.0));
            }
        });
        if !ok {
            break;
        }
    }
    // A centre past a wall's mid-plane (0.25 m into a 0.5 m wall) is pushed out on the far
    // side: that is leaving the box. At the end every centre must be back inside.
    let at_end = ids
        .iter()
        .map(|&id| outside_box(pos(&w, id), 10.0, 10.0, 0.0))
        .fold(0.0, f64::max);
    let passed = ok && inside_wall < 0.25 && at_end == 0.0;
    verdict(
        "gravity_flip",
        "20 boxes (0.3-1.2 m) in a closed 10 m box with 0.5 m walls, gravity 10 g flipped every 1 s for 10 s: \
         no box centre ever past a wall's mid-plane (0.25 m into the wall), every centre inside at the end, all finite"
            .into(),
        passed,
        vec![
            ("deepest centre beyond an inner wall surface (m)", inside_wall),
            ("centre outside at the end (m)", at_end),
            ("largest speed (m/s)", speed),
            ("largest penetration (m)", pen),
        ],
        "",
    )
}

/// Falling Bricks plus a 5-box stack stepped at dt = 0.1 s for 100 steps (10 s).
pub fn huge_dt(settings: &Settings) -> Verdict {
    let mut w = new_world(settings, gravity());
    let mut ids = cases::falling_bricks(&mut w).unwrap();
    ids.extend(cases::stack(&mut w, 5, 0.8, -3.8, 0.0).unwrap());
    let dt: Real = 0.1;
    let mut outside: f64 = 0.0;
    let mut speed: f64 = 0.0;
    let ok = run_steps(&mut w, dt, 100, Breakdown::NonFinite, |w, _| {
        speed = speed.max(max_speed(w));
        for &id in &ids {
            outside = outside.max(outside_box(pos(w, id), 10.0, 10.0, 0.0));
        }
    });
    let cap = settings.max_linear_speed as f64;
    let passed = ok && speed < 0.99 * cap;
    verdict(
        "huge_dt",
        "Falling Bricks + a 5-box stack at dt = 0.1 s for 100 steps: every number stays finite and no body reaches the speed cap".into(),
        passed,
        vec![
            ("largest speed (m/s)", speed),
            ("worst excursion outside the box (m)", outside),
        ],
        "leaving the box at dt = 0.1 s is measured but not part of the criterion",
    )
}

/// Every API entry point that takes a number, given NaN or infinity: all must be refused.
pub fn non_finite_refused(settings: &Settings) -> Verdict {
    let mut w = new_world(settings, gravity());
    let id = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), Vec2::ZERO))
        .unwrap();
    let nan = Real::NAN;
    let inf = Real::INFINITY;
    let box1 = || BodyDef::dynamic(Shape::rect(1.0, 1.0), Vec2::ZERO);
    let mut attempts: Vec<(&str, Result<(), PhysicsError>)> = vec![
        (
            "World::new gravity NaN",
            World::new(settings.clone(), vec2(nan, 0.0)).map(|_| ()),
        ),
        (
            "World::new contact_hertz inf",
            World::new(
                Settings {
                    contact_hertz: inf,
                    ..settings.clone()
                },
                gravity(),
            )
            .map(|_| ()),
        ),
        (
            "add_body position NaN",
            w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(nan, 0.0)))
                .map(|_| ()),
        ),
        (
            "add_body velocity inf",
            w.add_body(&box1().with_velocity(vec2(0.0, inf)))
                .map(|_| ()),
        ),
        (
            "add_body angle NaN",
            w.add_body(&box1().with_angle(nan)).map(|_| ()),
        ),
        (
            "add_body size inf",
            w.add_body(&BodyDef::dynamic(Shape::rect(inf, 1.0), Vec2::ZERO))
                .map(|_| ()),
        ),
        (
            "add_body density NaN",
            w.add_body(&box1().with_density(nan)).map(|_| ()),
        ),
        (
            "add_body friction inf",
            w.add_body(&box1().with_friction(inf)).map(|_| ()),
        ),
        ("step dt NaN", w.step(nan)),
        ("step dt inf", w.step(inf)),
        ("set_gravity inf", w.set_gravity(vec2(inf, 0.0))),
        ("apply_force NaN", w.apply_force(id, vec2(nan, 0.0))),
        ("apply_torque inf", w.apply_torque(id, inf)),
        ("apply_impulse NaN", w.apply_impulse(id, vec2(0.0, nan))),
        ("set_velocity inf", w.set_velocity(id, vec2(inf, 0.0), 0.0)),
    ];
    attempts.push((
        "set_settings max_push_out_speed NaN",
        w.set_settings(Settings {
            max_push_out_speed: nan,
            ..settings.clone()
        }),
    ));
    let accepted: Vec<&str> = attempts
        .iter()
        .filter(|(_, r)| r.is_ok())
        .map(|(n, _)| *n)
        .collect();
    let still_finite = w.step(DT_60).is_ok() && all_finite(&w) && w.body_count() == 1;
    let passed = accepted.is_empty() && still_finite;
    verdict(
        "non_finite_refused",
        format!(
            "{} calls given NaN or inf (World::new, add_body, step, set_gravity, forces, impulses, velocities, settings) all return an error and leave the world unchanged",
            attempts.len()
        ),
        passed,
        vec![
            ("calls tried", attempts.len() as f64),
            ("calls accepted", accepted.len() as f64),
        ],
        if accepted.is_empty() {
            String::new()
        } else {
            format!("accepted: {}", accepted.join(", "))
        },
    )
}

/// 60 bodies of five kinds (circles, capsules, triangles, hexagons, boxes; [`cases::mixed_shape`])
/// dropped in a 10 m x 10 m box with random spins, 10 s at 60 Hz, sleeping off.
pub fn mixed_pile(settings: &Settings) -> Verdict {
    let mut w = new_world(settings, gravity());
    cases::closed_box(&mut w, 10.0, 10.0, 0.5).unwrap();
    let mut ids = Vec::new();
    for i in 0..60 {
        let (col, row) = ((i % 10) as Real, (i / 10) as Real);
        let x = -4.5 + col + 0.05 * row;
        let y = 0.6 + 1.1 * row;
        let spin = 3.0 * (((i * 13) % 7) as Real / 3.0 - 1.0);
        let def = BodyDef::dynamic(cases::mixed_shape(i), vec2(x, y))
            .with_angle(0.3 * i as Real)
            .with_angular_velocity(spin);
        ids.push(w.add_body(&def).unwrap());
    }
    let mut outside: f64 = 0.0;
    let mut pen_late: f64 = 0.0;
    let mut speed_late: f64 = 0.0;
    let mut spin_late: f64 = 0.0;
    let n = steps_for(10.0, DT_60);
    let ok = run_steps(&mut w, DT_60, n, Breakdown::NonFinite, |w, k| {
        for &id in &ids {
            outside = outside.max(outside_box(pos(w, id), 10.0, 10.0, 0.0));
        }
        // The last second: the pile should be at rest.
        if k >= n - steps_for(1.0, DT_60) {
            pen_late = pen_late.max(max_penetration(w));
            speed_late = speed_late.max(max_speed(w));
            spin_late = spin_late.max(
                w.bodies()
                    .map(|b| b.angular_velocity().abs() as f64)
                    .fold(0.0, f64::max),
            );
        }
    });
    let slop = settings.linear_slop as f64;
    let passed =
        ok && outside == 0.0 && speed_late < 0.05 && spin_late < 0.2 && pen_late <= 2.0 * slop;
    verdict(
        "mixed_pile",
        format!(
            "60 mixed shapes (circles, capsules, triangles, hexagons, boxes) dropped in a 10 m box come to rest within 9 s: over the last second every centre slower than 0.05 m/s, every spin below 0.2 rad/s, overlap at most 2 x slop ({} m), nobody outside the box",
            super::fmt_num(2.0 * slop)
        ),
        passed,
        vec![
            ("max speed, last second (m/s)", speed_late),
            ("max spin, last second (rad/s)", spin_late),
            ("max overlap, last second (m)", pen_late),
            ("furthest outside the box (m)", outside),
        ],
        "sleeping is off, so resting means the solver holds the pile still, not that it was put to sleep",
    )
}
