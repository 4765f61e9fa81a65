//! Black-box tests of the engine against closed-form answers (issue 2's testing strategy).
//! Each tolerance says where it comes from.
#![cfg(feature = "measure")]

use tiltbox::measure::cases::ground;
use tiltbox::physics::{vec2, BodyDef, BodyId, Real, Settings, Shape, Vec2, World};

const DT: Real = 1.0 / 60.0;

fn both_solvers() -> [(&'static str, Settings); 2] {
    [
        ("sequential", Settings::sequential()),
        ("soft_step", Settings::soft_step()),
    ]
}

fn world(settings: Settings, g: Vec2) -> World {
    World::new(settings, g).expect("valid settings")
}

fn run(w: &mut World, seconds: Real) {
    for _ in 0..(seconds / DT).round() as usize {
        w.step(DT).expect("valid dt");
    }
}

#[test]
fn free_fall_matches_semi_implicit_euler_exactly() {
    for (name, s) in both_solvers() {
        let g = 9.81;
        // The soft step integrates in substeps of h = dt / substeps; the sequential solver in one.
        let h = match s.solver {
            tiltbox::physics::SolverKind::SoftStep => DT / s.substeps as Real,
            tiltbox::physics::SolverKind::Sequential => DT,
        };
        let mut w = world(s, vec2(0.0, -g));
        let id = w
            .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 100.0)))
            .unwrap();
        for n in 1..=120 {
            w.step(DT).unwrap();
            let t = n as Real * DT;
            // Semi-implicit Euler with step h: v = -g t, y = y0 - g t^2/2 - g t h/2.
            let expected_y = 100.0 - 0.5 * g * t * t - 0.5 * g * t * h;
            let b = w.body(id).unwrap();
            // Tolerance: f32 rounding of 120 sums of ~0.3 m against a value of ~100 m:
            // 120 x ulp(100) ~ 1e-3 m at worst; typical error is far below.
            assert!(
                (b.position().y - expected_y).abs() < 1e-3,
                "{name}: step {n}: y {} vs {expected_y}",
                b.position().y
            );
            assert!(
                (b.linear_velocity().y + g * t).abs() < 1e-4,
                "{name}: step {n}: vy {}",
                b.linear_velocity().y
            );
        }
    }
}

#[test]
fn head_on_collision_conserves_momentum_and_obeys_restitution() {
    for (name, s) in both_solvers() {
        let mut w = world(s, Vec2::ZERO);
        let e = 0.5;
        let a = w
            .add_body(
                &BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(-2.0, 0.0))
                    .with_mass(1.0)
                    .with_velocity(vec2(6.0, 0.0))
                    .with_restitution(e)
                    .with_friction(0.0),
            )
            .unwrap();
        let b = w
            .add_body(
                &BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(2.0, 0.0))
                    .with_mass(3.0)
                    .with_velocity(vec2(-2.0, 0.0))
                    .with_restitution(e)
                    .with_friction(0.0),
            )
            .unwrap();
        run(&mut w, 1.5);
        let (va, vb) = (
            w.body(a).unwrap().linear_velocity(),
            w.body(b).unwrap().linear_velocity(),
        );
        // Momentum before: 1 x 6 + 3 x (-2) = 0. Impulses are equal and opposite, so only
        // f32 rounding (~1e-6 relative) can break it.
        let p = 1.0 * va + 3.0 * vb;
        assert!(p.length() < 1e-4, "{name}: momentum {p:?}");
        // Newton's restitution law: separation speed = e x approach speed = 0.5 x 8 = 4 m/s.
        // 2 % allows for the solver's finite iterations on a two-point manifold.
        let separation_speed = vb.x - va.x;
        assert!(
            (separation_speed - 4.0).abs() < 0.08,
            "{name}: separation speed {separation_speed}"
        );
        assert!(
            va.y.abs() < 1e-4 && vb.y.abs() < 1e-4,
            "{name}: no sideways motion"
        );
    }
}

#[test]
fn three_stacked_bodies_carry_their_weight() {
    // Ground + boxes of 1, 2 and 3 kg stacked: at rest each contact carries the weight above it,
    // so the impulse over one step is (mass above) x g x dt.
    for (name, s) in both_solvers() {
        let g = 10.0;
        let mut w = world(s, vec2(0.0, -g));
        let ground_id = ground(&mut w, 0.0, 20.0, 1.0).unwrap();
        let ids: Vec<BodyId> = [1.0, 2.0, 3.0]
            .iter()
            .enumerate()
            .map(|(i, &m)| {
                w.add_body(
                    &BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5 + i as Real))
                        .with_mass(m),
                )
                .unwrap()
            })
            .collect();
        run(&mut w, 3.0);
        let load = |lower: BodyId, upper: BodyId| -> Real {
            w.contacts()
                .filter(|c| {
                    (c.body_a == lower && c.body_b == upper)
                        || (c.body_a == upper && c.body_b == lower)
                })
                .flat_map(|c| c.points.into_iter().take(c.count))
                .map(|p| p.normal_impulse)
                .sum()
        };
        // 1 % covers the residual motion of a settled soft stack.
        for (lower, upper, mass_above) in [
            (ground_id, ids[0], 6.0),
            (ids[0], ids[1], 5.0),
            (ids[1], ids[2], 3.0),
        ] {
            let expected = mass_above * g * DT;
            let got = load(lower, upper);
            assert!(
                (got - expected).abs() < 0.01 * expected,
                "{name}: contact under {upper}: {got} vs {expected}"
            );
        }
        for id in &ids {
            assert!(
                w.body(*id).unwrap().linear_velocity().length() < 0.01,
                "{name}: stack at rest"
            );
        }
    }
}

#[test]
fn sliding_box_stops_within_five_percent_of_v0_squared_over_2_mu_g() {
    for (name, s) in both_solvers() {
        let (g, mu, v0): (Real, Real, Real) = (10.0, 0.5, 4.0);
        let mut w = world(s, vec2(0.0, -g));
        let floor = w
            .add_body(&BodyDef::fixed(Shape::rect(100.0, 1.0), vec2(0.0, -0.5)).with_friction(mu))
            .unwrap();
        let _ = floor;
        // Settle first, then launch, so the distance counts sliding only.
        let id = w
            .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)).with_friction(mu))
            .unwrap();
        run(&mut w, 0.5);
        let x0 = w.body(id).unwrap().position().x;
        w.set_velocity(id, vec2(v0, 0.0), 0.0).unwrap();
        run(&mut w, 2.0);
        let b = w.body(id).unwrap();
        let d = b.position().x - x0;
        let expected = v0 * v0 / (2.0 * mu * g); // 1.6 m (mixing sqrt(mu mu) = mu)
        assert!(b.linear_velocity().length() < 1e-3, "{name}: stopped");
        assert!(
            (d - expected).abs() < 0.05 * expected,
            "{name}: slid {d} m, expected {expected}"
        );
    }
}

/// A box on flat ground with gravity tilted by theta: the same as a slope of angle theta.
fn slope(settings: Settings, theta: Real, mu: Real) -> (World, BodyId) {
    let g: Real = 10.0;
    let mut w = world(settings, vec2(g * theta.sin(), -g * theta.cos()));
    w.add_body(&BodyDef::fixed(Shape::rect(200.0, 1.0), vec2(0.0, -0.5)).with_friction(mu))
        .unwrap();
    let id = w
        .add_body(&BodyDef::dynamic(Shape::rect(0.5, 0.5), vec2(-50.0, 0.25)).with_friction(mu))
        .unwrap();
    (w, id)
}

#[test]
fn box_on_a_slope_sticks_when_tan_theta_is_below_mu() {
    for (name, s) in both_solvers() {
        let (mut w, id) = slope(s, (20.0 as Real).to_radians(), 0.6); // tan 20 deg = 0.36 < 0.6
        let x0 = w.body(id).unwrap().position().x;
        run(&mut w, 3.0);
        let drift = (w.body(id).unwrap().position().x - x0).abs();
        // Static friction holds exactly in theory; 2 mm allows for the contact settling.
        assert!(drift < 0.002, "{name}: crept {drift} m");
    }
}

#[test]
fn box_on_a_slope_slides_with_a_equal_g_sin_minus_mu_cos() {
    for (name, s) in both_solvers() {
        let theta = (40.0 as Real).to_radians(); // tan 40 deg = 0.84 > 0.3
        let mu = 0.3;
        let (mut w, id) = slope(s, theta, mu);
        run(&mut w, 0.5);
        let v1 = w.body(id).unwrap().linear_velocity().x;
        run(&mut w, 1.0);
        let v2 = w.body(id).unwrap().linear_velocity().x;
        let a = (v2 - v1) / 1.0;
        let expected = 10.0 * (theta.sin() - mu * theta.cos()); // 4.13 m/s^2
                                                                // 2 %: velocity differences over 60 steps; kinetic friction is exact in the model.
        assert!(
            (a - expected).abs() < 0.02 * expected,
            "{name}: a = {a}, expected {expected}"
        );
    }
}

#[test]
fn torque_spins_a_box_at_omega_equal_tau_t_over_i() {
    for (name, s) in both_solvers() {
        let mut w = world(s, Vec2::ZERO);
        let id = w
            .add_body(&BodyDef::dynamic(Shape::rect(2.0, 1.0), Vec2::ZERO).with_mass(3.0))
            .unwrap();
        let tau = 1.5;
        for _ in 0..60 {
            w.apply_torque(id, tau).unwrap(); // forces and torques are cleared after every step
            w.step(DT).unwrap();
        }
        let inertia = 3.0 * (2.0 * 2.0 + 1.0 * 1.0) / 12.0; // m (w^2 + h^2) / 12 = 1.25
        let expected = tau * 1.0 / inertia;
        let omega = w.body(id).unwrap().angular_velocity();
        assert!(
            (omega - expected).abs() < 1e-4,
            "{name}: omega {omega} vs {expected}"
        );
        assert!(
            w.body(id).unwrap().torque() == 0.0,
            "torque cleared after the step"
        );
    }
}

#[test]
fn resting_box_does_not_sink_below_the_slop() {
    for (name, s) in both_solvers() {
        let slop = s.linear_slop;
        let mut w = world(s, vec2(0.0, -9.81));
        ground(&mut w, 0.0, 20.0, 1.0).unwrap();
        let id = w
            .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)))
            .unwrap();
        run(&mut w, 3.0);
        let sink = 0.5 - w.body(id).unwrap().position().y;
        assert!(sink <= slop + 1e-4, "{name}: sank {sink} m, slop {slop}");
        assert!(sink > -1e-4, "{name}: floats {sink}");
    }
}

/// A stack of `n` 1 m boxes with deterministic +-1 cm sideways jitter (so a solver cannot pass
/// by symmetry alone). Returns the top box's horizontal drift after `seconds`. Sleep is off:
/// a sleeping stack cannot drift, and this measures the solver.
fn stack_drift(settings: Settings, n: usize, seconds: Real) -> Real {
    let mut w = world(
        Settings {
            enable_sleep: false,
            ..settings
        },
        vec2(0.0, -10.0),
    );
    ground(&mut w, 0.0, 100.0, 2.0).unwrap();
    let ids: Vec<BodyId> = (0..n)
        .map(|i| {
            let jitter = 0.01 * (i as Real * 2.3).sin();
            w.add_body(&BodyDef::dynamic(
                Shape::rect(1.0, 1.0),
                vec2(jitter, 0.5 + i as Real),
            ))
            .unwrap()
        })
        .collect();
    let top = *ids.last().unwrap();
    let x0 = w.body(top).unwrap().position().x;
    run(&mut w, seconds);
    (w.body(top).unwrap().position().x - x0).abs()
}

#[test]
fn ten_box_stack_stands_ten_seconds_with_top_drift_under_1_cm() {
    for (name, s) in both_solvers() {
        let drift = stack_drift(s, 10, 10.0);
        assert!(drift < 0.01, "{name}: top drifted {drift} m");
    }
}

#[test]
fn warm_starting_and_accumulated_impulses_each_help() {
    // Sequential solver, 10 iterations: the 10-stack stands with both; without either it falls.
    let full = stack_drift(Settings::sequential(), 10, 10.0);
    let no_warm = stack_drift(
        Settings {
            warm_starting: false,
            ..Settings::sequential()
        },
        10,
        10.0,
    );
    let no_accumulate = stack_drift(
        Settings {
            accumulate_impulses: false,
            ..Settings::sequential()
        },
        10,
        10.0,
    );
    assert!(full < 0.01, "with both: {full}");
    assert!(
        no_warm > 10.0 * full.max(0.001),
        "without warm starting: {no_warm} vs {full}"
    );
    assert!(
        no_accumulate > 10.0 * full.max(0.001),
        "without accumulation: {no_accumulate} vs {full}"
    );
    // And fewer iterations reach the same error with warm starting than without.
    let iterations_needed = |warm: bool| {
        [2u32, 4, 8, 16, 32, 64, 128]
            .into_iter()
            .find(|&it| {
                stack_drift(
                    Settings {
                        iterations: it,
                        warm_starting: warm,
                        ..Settings::sequential()
                    },
                    10,
                    5.0,
                ) < 0.01
            })
            .unwrap_or(u32::MAX)
    };
    let (with, without) = (iterations_needed(true), iterations_needed(false));
    assert!(
        with < without,
        "iterations to stand: {with} with warm starting, {without} without"
    );
}

#[test]
fn bad_input_is_refused_with_the_field_and_value_and_nothing_changes() {
    let mut w = World::default();
    let ok = BodyDef::dynamic(Shape::rect(1.0, 1.0), Vec2::ZERO);
    let cases: Vec<(BodyDef, &str)> = vec![
        (
            BodyDef {
                position: vec2(Real::NAN, 0.0),
                ..ok.clone()
            },
            "position.x",
        ),
        (
            BodyDef {
                linear_velocity: vec2(0.0, Real::INFINITY),
                ..ok.clone()
            },
            "velocity.y",
        ),
        (ok.clone().with_density(-1.0), "density"),
        (ok.clone().with_mass(0.0), "mass"),
        (ok.clone().with_friction(-0.1), "friction"),
        (ok.clone().with_restitution(1.5), "restitution"),
        (
            BodyDef {
                shape: Shape::rect(-1.0, 1.0),
                ..ok.clone()
            },
            "shape.width",
        ),
        (ok.clone().with_angle(Real::NAN), "angle"),
        (
            ok.clone().with_awake(false).with_velocity(vec2(0.5, 0.0)),
            "awake = false is refused: a body created asleep must be at rest, and this one \
             moves: velocity (0.5, 0) m/s",
        ),
        (
            ok.clone().with_awake(false).with_angular_velocity(2.0),
            "angular_velocity 2 rad/s",
        ),
        (
            BodyDef::fixed(Shape::rect(1.0, 1.0), Vec2::ZERO).with_awake(false),
            "awake = false is refused: only a dynamic body sleeps",
        ),
        (
            BodyDef::kinematic(Shape::rect(1.0, 1.0), Vec2::ZERO, Vec2::ZERO).with_awake(false),
            "awake = false is refused: only a dynamic body sleeps",
        ),
    ];
    for (def, field) in cases {
        let err = w.add_body(&def).unwrap_err().to_string();
        assert!(err.contains(field), "{err} should name {field}");
    }
    assert_eq!(w.body_count(), 0, "nothing half-added");
    let id = w.add_body(&ok).unwrap();
    assert!(w
        .set_gravity(vec2(Real::NAN, 0.0))
        .unwrap_err()
        .to_string()
        .contains("gravity.x"));
    assert_eq!(w.gravity(), vec2(0.0, -9.81), "gravity unchanged");
    assert!(w
        .apply_force(id, vec2(0.0, Real::INFINITY))
        .unwrap_err()
        .to_string()
        .contains("force.y"));
    assert!(w
        .apply_torque(id, Real::NAN)
        .unwrap_err()
        .to_string()
        .contains("torque"));
    assert!(w.step(0.0).unwrap_err().to_string().contains("dt"));
    assert!(w.step(Real::NAN).unwrap_err().to_string().contains("dt"));
    w.remove_body(id).unwrap();
    assert!(w.remove_body(id).is_err(), "stale id refused");
    assert!(w.body(id).is_none());
    let id2 = w.add_body(&ok).unwrap();
    assert_eq!(id2.index(), id.index(), "slot reused");
    assert_ne!(id2, id, "but never the id");
}

#[test]
fn impulses_and_forces_follow_newton() {
    let mut w = world(Settings::default(), Vec2::ZERO);
    let id = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), Vec2::ZERO).with_mass(2.0))
        .unwrap();
    w.apply_impulse(id, vec2(4.0, 0.0)).unwrap(); // v = P / m = 2 m/s
    assert!((w.body(id).unwrap().linear_velocity().x - 2.0).abs() < 1e-6);
    // Impulse off-centre: w = (r x P) / I with r = (0, 0.5), P = (1, 0): r x P = -0.5; I = 2 x 2 / 12.
    w.apply_impulse_at(id, vec2(1.0, 0.0), vec2(0.0, 0.5))
        .unwrap();
    assert!((w.body(id).unwrap().angular_velocity() - (-0.5 / (2.0 * 2.0 / 12.0))).abs() < 1e-5);
    // A force F for one step adds F dt / m.
    let v0 = w.body(id).unwrap().linear_velocity();
    w.apply_force(id, vec2(0.0, 6.0)).unwrap();
    w.step(DT).unwrap();
    assert!((w.body(id).unwrap().linear_velocity().y - (v0.y + 6.0 * DT / 2.0)).abs() < 1e-6);
    assert_eq!(
        w.body(id).unwrap().force(),
        Vec2::ZERO,
        "forces cleared after the step"
    );
}

/// Three rows of boxes on the ground, left to settle (some asleep): the World to remove from.
fn rows_of_boxes() -> (World, Vec<BodyId>) {
    let mut w = world(Settings::default(), vec2(0.0, -10.0));
    ground(&mut w, 0.0, 40.0, 1.0).unwrap();
    let mut ids = Vec::new();
    for row in 0..3 {
        for col in 0..8 {
            let p = vec2(col as Real * 3.0 - 10.0, 0.5 + row as Real * 1.0);
            let def = BodyDef::dynamic(Shape::rect(1.0, 1.0), p);
            ids.push(w.add_body(&def).unwrap());
        }
    }
    run(&mut w, 3.0);
    (w, ids)
}

#[test]
fn removing_bodies_together_equals_removing_them_one_by_one() {
    // Every third box (bottom, middle and top rows): the boxes above a removed bottom box
    // fall, and must do so the same way whichever call removed it.
    let (mut together, ids) = rows_of_boxes();
    let mut one_by_one = together.clone();
    let doomed: Vec<BodyId> = ids.iter().copied().step_by(3).collect();
    let removed = together.remove_bodies(&doomed).unwrap();
    assert_eq!(removed.len(), doomed.len());
    assert!(
        removed.iter().zip(&doomed).all(|(b, &id)| b.id() == id),
        "in the order given"
    );
    for &id in &doomed {
        one_by_one.remove_body(id).unwrap();
    }
    assert_eq!(together.body_count(), 1 + 24 - doomed.len());
    assert!(doomed.iter().all(|&id| together.body(id).is_none()));
    let top_before: Real = together.bodies().map(|b| b.position().y).sum();
    run(&mut together, 2.0);
    run(&mut one_by_one, 2.0);
    assert_eq!(together.state_hash(), one_by_one.state_hash());
    // Something did fall (the boxes above removed ones), so the comparison covered motion.
    let top_after: Real = together.bodies().map(|b| b.position().y).sum();
    assert!(top_before - top_after > 0.5, "{top_before} -> {top_after}");
}

#[test]
fn a_bad_list_of_bodies_removes_nothing() {
    let (mut w, ids) = rows_of_boxes();
    let hash = w.state_hash();
    let err = w.remove_bodies(&[ids[0], ids[5], ids[0]]).unwrap_err();
    assert!(err.to_string().contains("listed twice"), "{err}");
    let stale = w.remove_body(ids[7]).map(|b| b.id()).unwrap();
    let hash_after_one = w.state_hash();
    assert_ne!(hash, hash_after_one);
    let err = w.remove_bodies(&[ids[1], stale]).unwrap_err();
    assert!(err.to_string().contains("no body with id"), "{err}");
    assert_eq!(w.state_hash(), hash_after_one, "nothing half-removed");
    assert!(w.body(ids[0]).is_some() && w.body(ids[1]).is_some());
    // A live id is found from its two numbers, a stale one is not.
    assert_eq!(w.live_id(ids[1].index(), ids[1].generation()), Some(ids[1]));
    assert_eq!(w.live_id(stale.index(), stale.generation()), None);
}

/// `World::set_workers` takes 1 to 64 threads and refuses the rest with the field, the value
/// and the range, changing nothing; a World of 3 workers steps a pyramid of 465 boxes (some
/// 1,400 contacts: enough for every stage to be shared) to the same state as one of 1, as its
/// settings say.
#[test]
fn workers_are_checked_and_change_no_result() {
    use tiltbox::physics::PhysicsError;
    let pyramid = |workers: u32| {
        let mut w = World::new(Settings::default(), Vec2::new(0.0, -10.0)).unwrap();
        w.add_body(&BodyDef::fixed(
            Shape::rect(60.0, 1.0),
            Vec2::new(0.0, -0.5),
        ))
        .unwrap();
        for row in 0..30 {
            for i in 0..30 - row {
                let x = -(29 - row) as Real * 0.5 + i as Real;
                let at = Vec2::new(x, 0.5 + row as Real);
                w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), at))
                    .unwrap();
            }
        }
        w.set_workers(workers).unwrap();
        w
    };
    let mut w = pyramid(1);
    for bad in [0, 65] {
        let e = w.set_workers(bad).unwrap_err();
        assert!(
            matches!(
                e,
                PhysicsError::OutOfRange {
                    field: "workers",
                    ..
                }
            ),
            "{e}"
        );
        assert_eq!(
            e.to_string(),
            format!("workers = {bad} is out of range: must be within 1..=64")
        );
        assert_eq!(w.settings().workers, 1, "nothing changed");
    }
    let mut three = pyramid(3);
    assert_eq!(three.settings().workers, 3);
    for _ in 0..120 {
        w.step(1.0 / 60.0).unwrap();
        three.step(1.0 / 60.0).unwrap();
    }
    assert_eq!(w.state_hash(), three.state_hash());
    let top = w.bodies().map(|b| b.position().y).fold(0.0, Real::max);
    assert!(
        (top - 29.5).abs() < 0.05,
        "the pyramid stands: top at {top} m"
    );
}
