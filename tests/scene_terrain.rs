//! Scene files with terrain and motion (issue 17): `chain` and `segment` shapes, kinematic
//! bodies, what they refuse, and the shipped `config/scenes/terrain.toml`.
#![cfg(feature = "scene")]

use tiltbox::physics::{vec2, MassSpec, Real, Shape, Vec2};
use tiltbox::scene::Scene;

fn load(text: &str) -> Scene {
    Scene::from_toml_str(text).unwrap_or_else(|e| panic!("{e}"))
}

fn refusal(text: &str) -> String {
    Scene::from_toml_str(text).unwrap_err().to_string()
}

#[test]
fn a_chain_becomes_one_static_body_per_piece_with_its_neighbours() {
    let scene = load(
        r#"
        [[body]]
        name = "ground"
        shape = { type = "chain", points = [[0, 0], [1, 0], [2, 0.5]], loop = true, one_sided = true }
        position = [10, 1]
        friction = 0.2
        "#,
    );
    assert_eq!(scene.bodies.len(), 3);
    assert_eq!(scene.bodies[0].name, "ground[0]");
    for b in &scene.bodies {
        assert!(b.is_static);
        assert_eq!(b.def.mass, MassSpec::Static);
        assert_eq!(b.def.friction, 0.2);
    }
    // Piece 2 closes the loop: from (2, 0.5) back to (0, 0), around position (10, 1).
    let b = &scene.bodies[2];
    let Shape::Segment(s) = &b.def.shape else {
        panic!("{:?}", b.def.shape)
    };
    let world = |v: Vec2| b.def.position + v;
    assert!((world(s.a) - vec2(12.0, 1.5)).length() < 1e-6);
    assert!((world(s.b) - vec2(10.0, 1.0)).length() < 1e-6);
    assert!((world(s.next.unwrap()) - vec2(11.0, 1.0)).length() < 1e-6);
    assert!((world(s.prev.unwrap()) - vec2(11.0, 1.0)).length() < 1e-6);
    assert!(s.one_sided);
    // And the world it builds holds a body on it.
    let (mut world, _) = scene.build_world().unwrap();
    assert_eq!(world.body_count(), 3);
    world.step(1.0 / 60.0).unwrap();
}

#[test]
fn segments_are_static_unless_kinematic_and_kinematic_bodies_keep_their_velocity() {
    let scene = load(
        r#"
        [[body]]
        shape = { type = "segment", a = [-1, 0], b = [1, 0], radius = 0.05 }
        position = [0, 0]

        [[body]]
        name = "paddle"
        kinematic = true
        shape = { type = "segment", a = [-1, 0], b = [1, 0] }
        position = [0, 2]
        velocity = [0.5, 0]
        angular_velocity = 1.0
        "#,
    );
    assert_eq!(scene.bodies[0].def.mass, MassSpec::Static);
    assert!(scene.bodies[0].is_static);
    let paddle = &scene.bodies[1];
    assert_eq!(paddle.def.mass, MassSpec::Kinematic);
    assert!(!paddle.is_static);
    let (mut world, ids) = scene.build_world().unwrap();
    for _ in 0..60 {
        world.step(1.0 / 60.0).unwrap();
    }
    let p = world.body(ids[1]).unwrap();
    // 1 s at 0.5 m/s and 1 rad/s: exact up to f32 sums of 60 steps.
    assert!((p.position().x - 0.5).abs() < 1e-4, "{}", p.position().x);
    assert!((p.angle() - 1.0).abs() < 1e-4, "{}", p.angle());
    assert!(p.is_kinematic());
}

#[test]
fn bad_terrain_is_refused_naming_field_and_value() {
    let cases: [(&str, &[&str]); 6] = [
        (
            r#"[[body]]
            shape = { type = "chain", points = [[0, 0], [1]] }
            position = [0, 0]"#,
            &["shape.points[1]", "[1]", "pair"],
        ),
        (
            r#"[[body]]
            shape = { type = "chain", points = [[0, 0], [1, 0]] }
            position = [0, 0]
            density = 2.0"#,
            &["density", "2", "static terrain"],
        ),
        (
            r#"[[body]]
            shape = { type = "chain", points = [[0, 0], [1, 0], [1, 0]] }
            position = [0, 0]"#,
            &["shape.points[2]", "apart"],
        ),
        (
            r#"[[body]]
            shape = { type = "segment", a = [0, 0], b = [1, 0] }
            position = [0, 0]
            density = 1.0"#,
            &["mass", "static or kinematic"],
        ),
        (
            r#"[[body]]
            shape = { type = "rect", width = 1, height = 1 }
            position = [0, 0]
            static = true
            kinematic = true"#,
            &["kinematic", "not both"],
        ),
        (
            r#"[[body]]
            shape = { type = "rect", width = 1, height = 1 }
            position = [0, 0]
            kinematic = true
            mass = 3.0"#,
            &["mass", "3", "kinematic"],
        ),
    ];
    for (text, words) in cases {
        let e = refusal(text);
        for w in words {
            assert!(e.contains(w), "{e:?} should contain {w:?}");
        }
    }
}

/// The shipped terrain scene: hills as one one-sided chain, a turning kinematic paddle, and
/// bodies that stay inside the box for 20 s with nothing blowing up.
#[test]
fn the_terrain_scene_keeps_its_bodies_in_the_box() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("config/scenes/terrain.toml"),
    )
    .unwrap();
    let scene = load(&text);
    let chain = scene
        .bodies
        .iter()
        .filter(|b| b.name.starts_with("hills["))
        .count();
    assert_eq!(chain, 16);
    let paddle = scene
        .bodies
        .iter()
        .position(|b| b.name == "paddle")
        .unwrap();
    assert_eq!(scene.bodies[paddle].def.mass, MassSpec::Kinematic);
    let (mut world, ids) = scene.build_world().unwrap();
    let dynamic: Vec<_> = scene.dynamic_bodies().map(|(i, _)| ids[i]).collect();
    for _ in 0..1200 {
        world.step(1.0 / 60.0).unwrap();
        for &id in &dynamic {
            let p = world.body(id).unwrap().position();
            // Inside the inner box, 8 m x 6 m with its floor at 0 (centres, so with room).
            assert!(p.x.abs() < 4.0 && p.y > 0.0 && p.y < 6.0, "{id} at {p:?}");
        }
    }
    // The paddle turned 0.6 rad/s x 20 s, unslowed by what it hit.
    let turned: Real = world.body(ids[paddle]).unwrap().angle();
    assert!((turned - 12.0).abs() < 1e-3, "{turned}");
}

/// The terrain examples in docs/scenes.md load as written.
#[test]
fn the_terrain_examples_in_docs_scenes_md_load() {
    let doc = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scenes.md"),
    )
    .unwrap();
    let at = doc
        .find("### Terrain: segments and chains")
        .expect("the section");
    let start = at + doc[at..].find("```text\n").unwrap() + "```text\n".len();
    let end = start + doc[start..].find("```").unwrap();
    let lines: Vec<&str> = doc[start..end].lines().collect();
    assert_eq!(lines.len(), 3);
    let counts: Vec<usize> = lines
        .iter()
        .map(|line| {
            load(&format!("[[body]]\n{line}\nposition = [0, 0]\n"))
                .bodies
                .len()
        })
        .collect();
    // A segment, a chain of 4 points (3 pieces), a loop of 4 points (4 pieces).
    assert_eq!(counts, [1, 3, 4]);
}
