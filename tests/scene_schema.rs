//! The scene schema: what a body or a table leaves out gets the documented default, every
//! field is read, bodies keep file order across generators, and the stack and pyramid
//! generators lay boxes out as documented.

#![cfg(feature = "scene")]

mod common;

use common::scene::*;
use tiltbox::physics::{vec2, MassSpec, Real, Shape, SolverKind, Vec2};
use tiltbox::scene::{Colour, Scene};

#[test]
fn defaults_fill_what_a_body_leaves_out() {
    let scene = Scene::from_toml_str(&with_ground(
        r#"
[[body]]
shape = { type = "rect", width = 2, height = 1 }
position = [1, 2]
mass = 3
"#,
    ))
    .unwrap();
    assert_eq!(scene.gravity, vec2(0.0, -9.81));
    let b = &scene.bodies[1];
    assert_eq!(b.name, "body 1");
    assert_eq!(b.def.mass, MassSpec::Mass(3.0));
    assert_eq!(b.def.angle, 0.0);
    assert_eq!(b.def.linear_velocity, Vec2::ZERO);
    assert_eq!(b.def.angular_velocity, 0.0);
    assert!((b.def.friction - 0.6).abs() < 1e-6);
    assert_eq!(b.def.restitution, 0.0);
    assert_eq!(b.colour, Colour::GREY);
    assert!(!b.is_static);
    assert!(b.def.awake);
}

/// `awake = false` creates bodies asleep (a `[[body]]` and a generator's boxes): they hang
/// where the file puts them, under gravity, until something reaches them.
#[test]
fn awake_false_creates_bodies_asleep_until_reached() {
    let scene = Scene::from_toml_str(&with_ground(
        r#"
[[body]]
name = "hanging"
shape = { type = "rect", width = 1, height = 1 }
position = [-5, 4]
density = 1
awake = false

[[pyramid]]
base = 3
size = 1
base_y = 2
awake = false

[[body]]
name = "ball"
shape = { type = "circle", radius = 0.25 }
position = [0, 7.5]
density = 1
"#,
    ))
    .unwrap();
    let asleep: Vec<bool> = scene.bodies.iter().map(|b| !b.def.awake).collect();
    assert_eq!(
        asleep,
        [false, true, true, true, true, true, true, true, false]
    );
    let (mut world, ids) = scene.build_world().unwrap();
    for _ in 0..30 {
        world.step(1.0 / 60.0).unwrap();
    }
    // The ball (2.25 m above the pyramid's top box, whose top is at y = 5 m) has not reached
    // it in half a second of fall (1.23 m): nothing else moved.
    for (b, id) in scene.bodies.iter().zip(&ids).take(8) {
        assert_eq!(
            world.body(*id).unwrap().position(),
            b.def.position,
            "{}",
            b.name
        );
    }
    for _ in 0..90 {
        world.step(1.0 / 60.0).unwrap();
    }
    // The ball reached the pyramid's top box, and the pyramid (created asleep, one island of
    // touching boxes) woke whole: 2 m above the ground, it falls. The hanging box, 5 m to the
    // side, still hangs.
    let top = world.body(ids[7]).unwrap();
    assert!(top.position().y < scene.bodies[7].def.position.y - 1.0);
    let hanging = world.body(ids[1]).unwrap();
    assert_eq!(hanging.position(), vec2(-5.0, 4.0));
    assert!(!hanging.is_awake());
}

#[test]
fn every_field_is_read() {
    let scene = Scene::from_toml_str(
        r##"
name = "all"
gravity = [1.5, -3]

[settings]
solver = "sequential"
iterations = 20

[[body]]
name = "b"
shape = { type = "rect", width = 0.5, height = 0.25 }
position = [1, 2]
angle = 0.5
velocity = [3, -4]
angular_velocity = 2
density = 2.5
friction = 0.3
restitution = 0.5
color = "#0A0b0C"
"##,
    )
    .unwrap();
    assert_eq!(scene.name, "all");
    assert_eq!(scene.gravity, vec2(1.5, -3.0));
    assert_eq!(scene.settings.solver, SolverKind::Sequential);
    assert_eq!(scene.settings.iterations, 20);
    // The rest of [settings] keeps its defaults.
    assert_eq!(
        scene.settings.substeps,
        tiltbox::physics::Settings::default().substeps
    );
    let b = &scene.bodies[0];
    assert_eq!(b.def.shape, Shape::rect(0.5, 0.25));
    assert_eq!(b.def.position, vec2(1.0, 2.0));
    assert_eq!(b.def.angle, 0.5);
    assert_eq!(b.def.linear_velocity, vec2(3.0, -4.0));
    assert_eq!(b.def.angular_velocity, 2.0);
    assert_eq!(b.def.mass, MassSpec::Density(2.5));
    assert!((b.def.friction - 0.3).abs() < 1e-6);
    assert_eq!(b.def.restitution, 0.5);
    assert_eq!(b.colour, Colour::new(10, 11, 12));
    assert_eq!(b.colour.to_string(), "#0a0b0c");
}

#[test]
fn bodies_keep_file_order_across_generators() {
    let scene = Scene::from_toml_str(
        r#"
[[stack]]
count = 2
size = 1

[[body]]
name = "after"
static = true
shape = { type = "rect", width = 1, height = 1 }
position = [5, 5]

[[pyramid]]
base = 2
size = 1
name = "p"
"#,
    )
    .unwrap();
    let names: Vec<&str> = scene.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(
        names,
        ["stack[0]", "stack[1]", "after", "p[0,0]", "p[0,1]", "p[1,0]"]
    );
}

#[test]
fn stack_generator_places_boxes_as_documented() {
    let scene = Scene::from_toml_str(
        r##"
[[stack]]
name = "tower"
count = 4
size = 0.5
x = 3
base_y = 2
gap = 0.1
density = 2
friction = 0.4
restitution = 0.1
colour = "#112233"
"##,
    )
    .unwrap();
    assert_eq!(scene.bodies.len(), 4);
    for (i, b) in scene.bodies.iter().enumerate() {
        // y_i = base_y + size/2 + i (size + gap)
        let y = 2.0 + 0.25 + i as Real * 0.6;
        assert!(
            close(b.def.position, vec2(3.0, y)),
            "{}: {:?}",
            b.name,
            b.def.position
        );
        assert_eq!(b.name, format!("tower[{i}]"));
        assert_eq!(b.def.shape, Shape::rect(0.5, 0.5));
        assert_eq!(b.def.mass, MassSpec::Density(2.0));
        assert!((b.def.friction - 0.4).abs() < 1e-6);
        assert!((b.def.restitution - 0.1).abs() < 1e-6);
        assert_eq!(b.colour, Colour::new(0x11, 0x22, 0x33));
        assert!(!b.is_static);
    }
}

#[test]
fn pyramid_generator_places_boxes_as_documented() {
    let scene = Scene::from_toml_str(
        r#"
[[pyramid]]
base = 3
size = 2
x = 1
base_y = -1
"#,
    )
    .unwrap();
    // Row r has base - r boxes of side size, centred on x, at y = base_y + (r + 1/2) size.
    let expected = [
        ("pyramid[0,0]", -1.0, 0.0),
        ("pyramid[0,1]", 1.0, 0.0),
        ("pyramid[0,2]", 3.0, 0.0),
        ("pyramid[1,0]", 0.0, 2.0),
        ("pyramid[1,1]", 2.0, 2.0),
        ("pyramid[2,0]", 1.0, 4.0),
    ];
    assert_eq!(scene.bodies.len(), expected.len());
    for (b, (name, x, y)) in scene.bodies.iter().zip(expected) {
        assert_eq!(b.name, name);
        assert!(
            close(b.def.position, vec2(x, y)),
            "{name}: {:?}",
            b.def.position
        );
        assert_eq!(b.def.shape, Shape::rect(2.0, 2.0));
        assert_eq!(b.def.mass, MassSpec::Density(1.0));
        assert!((b.def.friction - 0.6).abs() < 1e-6);
        assert_eq!(b.colour, Colour::GREY);
    }
}
