//! The playground scenes (`config/scenes/bridge.toml`, `car.toml`, `ragdoll.toml`, `rope.toml`,
//! `cradle.toml`), each in the Falling Bricks box: they load, and 20 s with the defaults keep
//! every body inside the box and every joint together; each does what its comment says.
#![cfg(feature = "scene")]

mod common;

use common::scene::load;
use tiltbox::physics::{BodyId, JointKind, Real, Vec2, World};

const DT: Real = 1.0 / 60.0;

/// The widest distance between the two anchors of a joint that holds them together (m; a wheel
/// or prismatic joint lets them travel apart along its axis).
fn widest_gap(w: &World) -> Real {
    let at = |id: Option<BodyId>, p: Vec2| match id.and_then(|id| w.body(id)) {
        Some(b) => b.transform().apply(p),
        None => p,
    };
    w.joints()
        .filter(|j| !matches!(j.def().kind, JointKind::Wheel(_) | JointKind::Prismatic(_)))
        .map(|j| {
            let d = j.def();
            (at(d.body_a, d.anchor_a) - at(Some(d.body_b), d.anchor_b)).length()
        })
        .fold(0.0, Real::max)
}

/// Steps `scene` for `seconds`, checking at every step that every dynamic body's centre stays
/// inside the box (x in (-4, 4), y in (0, 6): the box's inner walls) and every joint within
/// 5 cm (a tenth of the smallest link; the soft joints give millimetres under these loads).
fn run(name: &str, seconds: Real) -> (World, Vec<BodyId>, tiltbox::scene::Scene) {
    let scene = load(name);
    let (mut w, ids) = scene
        .build_world()
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let steps = (seconds / DT) as usize;
    let mut widest: Real = 0.0;
    for k in 0..steps {
        w.step(DT).unwrap();
        widest = widest.max(widest_gap(&w));
        for b in w.bodies().filter(|b| !b.is_static() && !b.is_kinematic()) {
            let p = b.center_of_mass();
            assert!(
                b.is_finite() && p.x > -4.0 && p.x < 4.0 && p.y > 0.0 && p.y < 6.0,
                "{name}: body {} at {p} after step {k}",
                b.id()
            );
        }
    }
    assert!(widest < 0.05, "{name}: a joint opened {widest} m");
    (w, ids, scene)
}

fn index(scene: &tiltbox::scene::Scene, name: &str) -> usize {
    scene
        .bodies
        .iter()
        .position(|b| b.name == name)
        .expect(name)
}

#[test]
fn the_bridge_holds_its_bricks_above_the_floor() {
    let (w, ids, scene) = run("bridge.toml", 20.0);
    // The planks hang 3 m up; loaded, the middle sags but stays well clear of the floor.
    let middle = w.body(ids[index(&scene, "plank[8]")]).unwrap().position();
    assert!(middle.y > 1.5 && middle.y < 3.0, "middle plank at {middle}");
    for name in ["red brick", "blue ball", "green brick"] {
        let y = w.body(ids[index(&scene, name)]).unwrap().position().y;
        assert!(y > 1.0, "{name} fell through the bridge to {y}");
    }
}

#[test]
fn the_car_drives_over_the_hills() {
    let (w, ids, scene) = run("car.toml", 12.0);
    // The motor turns the rear wheel clockwise: the car crosses from x = -2 over three hills to
    // the right wall and rests against it, wheels down (its chassis turned less than 1.2 rad:
    // leaning on the wall, not overturned).
    let chassis = w.body(ids[index(&scene, "chassis")]).unwrap();
    let (x, angle) = (chassis.position().x, chassis.angle());
    assert!(
        x > 2.5 && angle.abs() < 1.2,
        "chassis at x = {x}, turned {angle} rad"
    );
}

#[test]
fn the_ragdolls_stay_in_one_piece() {
    run("ragdoll.toml", 20.0);
}

#[test]
fn the_weight_swings_into_the_column() {
    let (w, ids, scene) = run("rope.toml", 10.0);
    // The rope is 3.54 m from (0, 6): swinging right, the weight's bottom passes x = 1 at
    // 2.25 m, below the top of the column (2.5 m), so it knocks the top box off.
    let top = w.body(ids[index(&scene, "column[4]")]).unwrap().position();
    assert!(
        (top.x - 1.0).abs() > 0.2 || top.y < 2.0,
        "the column stood: top at {top}"
    );
}

#[test]
fn the_cradle_passes_the_swing_to_the_last_ball() {
    let scene = load("cradle.toml");
    let (mut w, ids) = scene.build_world().unwrap();
    let last = ids[index(&scene, "ball 5")];
    // Ball 1 falls from 0.9 rad on a 3 m string: it strikes at sqrt(2 g L (1 - cos 0.9)) =
    // 4.0 m/s. Ideal cradles pass it all to ball 5; a solver that solves the row's contacts
    // one after another passes most of it: on the sequential solver, which the scene asks
    // for, ball 5 rises at least half of ball 1's drop (3 (1 - cos 0.9) = 1.14 m).
    // (It strikes after a quarter swing, 0.9 s; ball 5 rises for another.)
    let mut highest = Real::MIN;
    for _ in 0..150 {
        w.step(DT).unwrap();
        highest = highest.max(w.body(last).unwrap().position().y);
    }
    let drop = 3.0 * (1.0 - (0.9 as Real).cos());
    assert!(
        highest - 3.0 > 0.5 * drop,
        "ball 5 rose {} of {drop}",
        highest - 3.0
    );
}
