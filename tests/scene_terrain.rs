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

/// docs/scenes.md's one-sided rule: the side is the body's centre's, decided at every step. A
/// disc whose centre starts 1 cm below a one-sided floor gets no contact from it and falls
/// through freely (free fall as the soft step's substeps of dt / 4 integrate it, to 1e-4 m),
/// though most of it overlaps the floor; one overlapping it 1 cm with its centre above is
/// pushed out to rest on top. A chain cannot be kinematic.
#[test]
fn a_body_whose_centre_has_crossed_a_one_sided_floor_falls_through_it() {
    let scene = load(
        r#"
        [[body]]
        name = "floor"
        shape = { type = "chain", points = [[-4, 0], [4, 0]], one_sided = true }
        position = [0, 0]

        [[body]]
        name = "behind"
        shape = { type = "circle", radius = 0.25 }
        position = [-2, -0.01]
        density = 1

        [[body]]
        name = "in front"
        shape = { type = "circle", radius = 0.25 }
        position = [2, 0.24]
        density = 1
        "#,
    );
    let (mut world, ids) = scene.build_world().unwrap();
    let (dt, g): (Real, Real) = (1.0 / 60.0, 9.81);
    let h = dt / scene.settings.substeps as Real;
    for k in 1..=60 {
        world.step(dt).unwrap();
        let t = k as Real * dt;
        let behind = world.body(ids[1]).unwrap().position();
        let free_fall = -0.01 - g * t * (t + h) / 2.0;
        assert!(
            (behind.y - free_fall).abs() < 1e-4 && behind.x == -2.0,
            "step {k}: behind at {behind:?}, free fall {free_fall}"
        );
    }
    let front = world.body(ids[2]).unwrap().position();
    assert!((front.y - 0.25).abs() < 0.005, "in front at {front:?}");
    let e = refusal(
        r#"[[body]]
        shape = { type = "chain", points = [[0, 0], [1, 0]], one_sided = true }
        position = [0, 0]
        kinematic = true"#,
    );
    assert!(
        e.contains("kinematic") && e.contains("static terrain"),
        "{e}"
    );
}

/// docs/scenes.md: a kinematic body turns about its body position. A rectangle about its
/// `position`; a segment about the `position` its `a` and `b` are given from (a gate hinged at
/// `a = [0, 0]`: after a quarter turn its end `b = [4, 0]` stands at (0, 4)); a polygon about
/// its centre of mass, the vertices' centroid (docs' triangle at [10, 0]: (11, 2/3)).
#[test]
fn a_kinematic_body_turns_about_its_body_position() {
    let scene = load(
        r#"
        [[body]]
        name = "bar"
        kinematic = true
        shape = { type = "rect", width = 2, height = 0.2 }
        position = [-5, 1]
        angular_velocity = 1.5707963

        [[body]]
        name = "gate"
        kinematic = true
        shape = { type = "segment", a = [0, 0], b = [4, 0] }
        position = [0, 0]
        angular_velocity = 1.5707963

        [[body]]
        name = "wedge"
        kinematic = true
        shape = { type = "polygon", vertices = [[0, 0], [3, 0], [0, 2]] }
        position = [10, 0]
        angular_velocity = 1.5707963
        "#,
    );
    let (mut world, ids) = scene.build_world().unwrap();
    for _ in 0..60 {
        world.step(1.0 / 60.0).unwrap();
    }
    // 1 s at the angular velocity given (pi / 2 rad/s): a quarter turn.
    let quarter = Real::acos(0.0);
    for (i, centre) in [vec2(-5.0, 1.0), vec2(0.0, 0.0), vec2(11.0, 2.0 / 3.0)]
        .into_iter()
        .enumerate()
    {
        let b = world.body(ids[i]).unwrap();
        assert!(
            (b.position() - centre).length() < 1e-5,
            "{i}: {:?}",
            b.position()
        );
        assert!((b.angle() - quarter).abs() < 1e-5, "{i}: {}", b.angle());
    }
    let gate = world.body(ids[1]).unwrap();
    let Shape::Segment(s) = gate.shape() else {
        panic!("{:?}", gate.shape())
    };
    let (sin, cos) = gate.angle().sin_cos();
    let end = gate.position() + vec2(cos * s.b.x - sin * s.b.y, sin * s.b.x + cos * s.b.y);
    assert!((end - vec2(0.0, 4.0)).length() < 1e-4, "b at {end:?}");
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
