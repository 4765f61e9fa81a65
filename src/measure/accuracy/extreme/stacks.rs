//! Stacks and pyramids: tall stacks with and without jitter, pyramids that stand and fall
//! asleep, the large pyramid timed for the report, and a stack far from the origin.

use super::{for_seconds, gravity, pos, verdict};
use crate::measure::accuracy::{new_world, run_steps, steps_for, Breakdown, Verdict, DT_60};
use crate::measure::cases;
use crate::physics::{Real, Settings, Vec2, World};
use std::time::Instant;

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
