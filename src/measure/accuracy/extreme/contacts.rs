//! Hard contacts: heavy on light (mass ratios), bodies spawned inside each other, bullets
//! against a thin wall, and a pile of every shape kind that must come to rest.

use super::{for_seconds, gravity, max_speed, outside_box, pos, verdict};
use crate::measure::accuracy::{
    fmt_num, max_penetration, new_world, run_steps, steps_for, Breakdown, Verdict, DT_60,
};
use crate::measure::cases;
use crate::physics::{vec2, BodyDef, BodyId, Real, Settings, Shape, SolverKind};

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
            fmt_num(2.0 * slop)
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
            fmt_num(2.0 * slop)
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
            fmt_num(2.0 * slop)
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
