//! Tiny and large bodies, gravity flips, a huge step and non-finite input.

use super::*;
use crate::measure::accuracy::{max_penetration, new_world, steps_for, Verdict, DT_60, G};
use crate::measure::accuracy::{run_steps, Breakdown};
use crate::measure::cases;
use crate::physics::{vec2, BodyDef, PhysicsError, Real, Settings, Shape, Vec2, World};

/// Three 1 cm boxes stacked on the ground, 5 s.
pub fn tiny_bodies(settings: &Settings) -> Verdict {
    let size: Real = 0.01;
    let mut w = new_world(settings, gravity());
    cases::ground(&mut w, 0.0, 10.0, 1.0).unwrap();
    let ids = cases::jittered_stack(&mut w, 3, size, 0.0).unwrap();
    let top = ids[2];
    let p0 = pos(&w, top);
    let mut drift: f64 = 0.0;
    let ok = run_60hz(&mut w, 5.0, Breakdown::BlownUp(100.0), |w, _| {
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
            crate::measure::accuracy::fmt_num(3.0 * slop)
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
    let ok = run_60hz(&mut w, 5.0, Breakdown::BlownUp(1000.0), |w, _| {
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
            crate::measure::accuracy::fmt_num(2.0 * slop)
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
    let per_second = steps_for(1.0, DT_60);
    let mut ok = true;
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
