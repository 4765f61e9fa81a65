//! Scene files: the shipped scenes load and build, bad input is refused with messages that
//! name the body, the field and the value, generators lay boxes out as documented, and the
//! Falling Bricks scene comes to rest inside its box.

#![cfg(feature = "scene")]

use std::path::{Path, PathBuf};
use tiltbox::physics::{vec2, MassSpec, Real, Shape, SolverKind, Vec2, World};
use tiltbox::scene::{Colour, Scene, SceneError};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config/scenes")
        .join(name)
}

fn load(name: &str) -> Scene {
    Scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn close(a: Vec2, b: Vec2) -> bool {
    (a - b).length() < 1e-5
}

// ---------------------------------------------------------------- shipped scenes

#[test]
fn falling_bricks_is_a_closed_box_with_six_bricks() {
    let scene = load("falling_bricks.toml");
    assert_eq!(scene.name, "Falling Bricks");
    assert_eq!(scene.gravity, vec2(0.0, -9.81));
    assert_eq!(scene.settings, tiltbox::physics::Settings::default());
    assert_eq!(scene.bodies.len(), 10);
    let walls: Vec<_> = scene.bodies.iter().filter(|b| b.is_static).collect();
    let bricks: Vec<_> = scene.bodies.iter().filter(|b| !b.is_static).collect();
    assert_eq!(walls.len(), 4);
    assert_eq!(bricks.len(), 6);
    for w in &walls {
        assert_eq!(w.def.mass, MassSpec::Static, "{}", w.name);
    }
    // Six different colours, none of them the default grey, and distinct sizes.
    let mut colours: Vec<String> = bricks.iter().map(|b| b.colour.to_string()).collect();
    colours.sort();
    colours.dedup();
    assert_eq!(colours.len(), 6, "{colours:?}");
    assert!(bricks.iter().all(|b| b.colour != Colour::GREY));
    let red = bricks.iter().find(|b| b.name == "red brick").unwrap();
    assert_eq!(red.colour, Colour::new(0xd6, 0x45, 0x41));
    assert_eq!(red.def.shape, Shape::rect(1.6, 0.4));
    assert!(close(red.def.position, vec2(-2.4, 1.2)));
    assert!((red.def.angle - 0.3).abs() < 1e-6);
    assert_eq!(red.def.mass, MassSpec::Density(1.0));
    assert!((red.def.friction - 0.6).abs() < 1e-6);
    // A couple of bricks bounce a little.
    assert!(bricks.iter().filter(|b| b.def.restitution > 0.0).count() >= 2);
    // The compiled-in copy is the file.
    assert_eq!(Scene::embedded_default().unwrap(), scene);
}

#[test]
fn falling_bricks_start_inside_the_box_and_apart() {
    let scene = load("falling_bricks.toml");
    let (mut world, ids) = scene.build_world().unwrap();
    for (body, id) in scene.bodies.iter().zip(&ids) {
        if body.is_static {
            continue;
        }
        let b = world.body(*id).unwrap();
        let aabb = b.shape().aabb(b.transform());
        assert!(
            aabb.min.x > -4.0 && aabb.max.x < 4.0 && aabb.min.y > 0.0 && aabb.max.y < 6.0,
            "{} starts outside the box: {aabb:?}",
            body.name
        );
    }
    // The first step's contacts are found at the initial poses: none may overlap
    // (contacts are speculative, so touching-soon pairs appear with separation > 0).
    world.step(1.0 / 60.0).unwrap();
    for c in world.contacts() {
        for p in &c.points[..c.count] {
            assert!(p.separation > 0.0, "bodies overlap at the start: {c:?}");
        }
    }
}

#[test]
fn stack_is_ten_boxes_on_a_ground() {
    let scene = load("stack.toml");
    assert_eq!(scene.bodies.len(), 11);
    assert!(scene.bodies[0].is_static);
    assert_eq!(scene.bodies[0].name, "ground");
    for (i, b) in scene.bodies[1..].iter().enumerate() {
        assert_eq!(b.name, format!("stack[{i}]"));
        assert!(!b.is_static);
        assert_eq!(b.def.shape, Shape::rect(1.0, 1.0));
        assert!(
            close(b.def.position, vec2(0.0, 0.5 + i as Real)),
            "{}",
            b.name
        );
    }
    let (world, ids) = scene.build_world().unwrap();
    assert_eq!(world.body_count(), 11);
    assert_eq!(ids.len(), 11);
}

#[cfg(feature = "measure")]
#[test]
fn pyramid_is_210_boxes_laid_out_like_cases_pyramid() {
    let scene = load("pyramid.toml");
    assert_eq!(scene.bodies.len(), 211);
    assert!(scene.bodies[0].is_static);
    assert_eq!(scene.bodies.iter().filter(|b| !b.is_static).count(), 210);
    // Same layout as the shared test case (row i has 20 - i boxes, centred on x = 0).
    let mut reference = World::default();
    let ref_ids = tiltbox::measure::cases::pyramid(&mut reference, 20, 1.0, 0.0, 0.6).unwrap();
    for (b, id) in scene.bodies[1..].iter().zip(&ref_ids) {
        let r = reference.body(*id).unwrap();
        assert!(close(b.def.position, r.position()), "{}", b.name);
        assert_eq!(b.def.shape, *r.shape());
    }
    assert_eq!(scene.bodies[1].name, "pyramid[0,0]");
    assert_eq!(scene.bodies[210].name, "pyramid[19,0]");
    assert!(close(scene.bodies[210].def.position, vec2(0.0, 19.5)));
    let (world, ids) = scene.build_world().unwrap();
    assert_eq!((world.body_count(), ids.len()), (211, 211));
}

#[test]
fn build_world_ids_follow_the_bodies() {
    for name in ["falling_bricks.toml", "stack.toml", "pyramid.toml"] {
        let scene = load(name);
        let (world, ids) = scene.build_world().unwrap();
        assert_eq!(world.gravity(), scene.gravity);
        assert_eq!(world.settings(), &scene.settings);
        assert_eq!(ids.len(), scene.bodies.len());
        for (b, id) in scene.bodies.iter().zip(&ids) {
            let body = world.body(*id).unwrap();
            assert_eq!(body.position(), b.def.position, "{name}: {}", b.name);
            assert_eq!(body.angle(), b.def.angle);
            assert_eq!(body.is_static(), b.is_static);
        }
    }
}

// ---------------------------------------------------------------- schema and defaults

const GROUND: &str = r#"
name = "test"

[[body]]
name = "ground"
static = true
shape = { type = "rect", width = 10, height = 1 }
position = [0, -0.5]
"#;

fn with_ground(extra: &str) -> String {
    format!("{GROUND}\n{extra}")
}

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

// ---------------------------------------------------------------- generators

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

// ---------------------------------------------------------------- errors

/// The error for a scene holding a ground (#0) and then `body`.
fn error_for(body: &str) -> (SceneError, String) {
    let e = Scene::from_toml_str(&with_ground(body)).unwrap_err();
    let s = e.to_string();
    (e, s)
}

fn brick(fields: &str) -> String {
    format!(
        "[[body]]\nname = \"brick 3\"\nshape = {{ type = \"rect\", width = 1, height = 0.5 }}\nposition = [0, 1]\n{fields}\n"
    )
}

#[test]
fn negative_friction_names_body_field_and_value() {
    let (e, s) = error_for(&brick("density = 1\nfriction = -1"));
    assert_eq!(s, r#"body "brick 3" (#1): friction = -1: must be >= 0"#);
    match e {
        SceneError::Invalid {
            body, field, value, ..
        } => {
            assert_eq!(body, r#"body "brick 3" (#1)"#);
            assert_eq!(field, "friction");
            assert_eq!(value.as_deref(), Some("-1"));
        }
        other => panic!("expected Invalid, got {other:?}"),
    }
}

#[test]
fn restitution_above_one_is_refused() {
    let (_, s) = error_for(&brick("density = 1\nrestitution = 2"));
    assert_eq!(
        s,
        r#"body "brick 3" (#1): restitution = 2: must be within [0, 1]"#
    );
}

#[test]
fn nan_is_refused_wherever_it_appears() {
    let (_, s) = error_for(&brick("density = nan"));
    assert!(
        s.starts_with(r#"body "brick 3" (#1): density = NaN"#),
        "{s}"
    );
    let (_, s) = error_for(&brick("density = 1\nangle = nan"));
    assert_eq!(
        s,
        r#"body "brick 3" (#1): angle = NaN: must be a finite number"#
    );
    let (_, s) = error_for(
        "[[body]]\nshape = { type = \"rect\", width = 1, height = 1 }\nposition = [nan, 0]\nmass = 1",
    );
    // unnamed: the index names it
    assert_eq!(s, "body #1: position.x = NaN: must be a finite number");
    let e = Scene::from_toml_str("gravity = [0, nan]").unwrap_err();
    assert_eq!(
        e.to_string(),
        "scene: gravity.y = NaN: must be a finite number"
    );
}

#[test]
fn zero_width_is_refused() {
    let (_, s) = error_for(
        "[[body]]\nname = \"flat\"\nshape = { type = \"rect\", width = 0, height = 1 }\nposition = [0, 1]\ndensity = 1",
    );
    assert_eq!(s, r#"body "flat" (#1): shape.width = 0: must be > 0"#);
}

#[test]
fn density_and_mass_together_are_refused() {
    let (_, s) = error_for(&brick("density = 1\nmass = 2"));
    assert!(
        s.starts_with(r#"body "brick 3" (#1): density = 1: give exactly one of density"#),
        "{s}"
    );
    assert!(s.contains("mass = 2"), "{s}");
    let (_, s) = error_for(&brick(""));
    assert!(
        s.starts_with(r#"body "brick 3" (#1): density: missing"#),
        "{s}"
    );
}

#[test]
fn static_bodies_take_no_density_mass_or_velocity() {
    let (_, s) = error_for(&brick("static = true\ndensity = 1"));
    assert!(
        s.starts_with(r#"body "brick 3" (#1): density = 1: a static body has neither"#),
        "{s}"
    );
    let (_, s) = error_for(&brick("static = true\nmass = 5"));
    assert!(s.starts_with(r#"body "brick 3" (#1): mass = 5"#), "{s}");
    let (_, s) = error_for(&brick("static = true\nvelocity = [1, 0]"));
    assert!(
        s.starts_with(r#"body "brick 3" (#1): velocity = [1, 0]: a static body does not move"#),
        "{s}"
    );
}

#[test]
fn malformed_colour_names_the_value() {
    let (_, s) = error_for(&brick("density = 1\ncolour = \"#12345\""));
    assert!(
        s.starts_with(r##"body "brick 3" (#1): colour = "#12345": expected "#rrggbb""##),
        "{s}"
    );
    let (_, s) = error_for(&brick("density = 1\ncolour = \"red\""));
    assert!(s.contains(r#"colour = "red""#), "{s}");
}

#[test]
fn unknown_field_names_the_body_its_line_and_the_field() {
    let (e, s) = error_for(&brick("density = 1\nfrction = 0.5"));
    assert!(
        matches!(e, SceneError::Parse { entry: Some(_), .. }),
        "{e:?}"
    );
    // The [[body]] header of "brick 3" is on line 10 of the document (GROUND takes 9).
    assert!(
        s.starts_with(r#"body "brick 3" (#1) at line 10: unknown field `frction`"#),
        "{s}"
    );
    // A wrong type is reported the same way.
    let (_, s) = error_for(&brick("density = \"heavy\""));
    assert!(
        s.starts_with(r#"body "brick 3" (#1) at line 10: density: invalid type"#),
        "{s}"
    );
    // ... and a field inside the shape.
    let (_, s) = error_for(
        "[[body]]\nname = \"cube\"\nshape = { type = \"rect\", width = 1, height = 1, depth = 1 }\nposition = [0, 1]\ndensity = 1",
    );
    assert!(s.starts_with(r#"body "cube" (#1) at line 10: "#), "{s}");
    assert!(s.contains("depth"), "{s}");
}

#[test]
fn unknown_top_level_keys_and_bad_toml_report_line_and_column() {
    let e = Scene::from_toml_str("name = \"x\"\ngravty = [0, -1]\n").unwrap_err();
    let s = e.to_string();
    assert!(matches!(e, SceneError::Parse { entry: None, .. }));
    assert!(
        s.contains("line 2, column 1") && s.contains("gravty"),
        "{s}"
    );
    let e = Scene::from_toml_str("name = \"x\"\n[[body]\n").unwrap_err();
    let s = e.to_string();
    assert!(s.contains("line 2"), "{s}");
}

#[test]
fn settings_are_validated_by_the_engine() {
    let e = Scene::from_toml_str("[settings]\nsubsteps = 0\n").unwrap_err();
    assert_eq!(
        e.to_string(),
        "[settings]: substeps = 0: must be within 1..=64"
    );
    let e = Scene::from_toml_str("[settings]\nsubstep = 4\n").unwrap_err();
    let s = e.to_string();
    assert!(s.contains("substep") && s.contains("line 2"), "{s}");
}

#[test]
fn generator_errors_name_the_generator_and_field() {
    let e = Scene::from_toml_str("[[stack]]\ncount = 0\nsize = 1\n").unwrap_err();
    assert_eq!(e.to_string(), "[[stack]] #0: count = 0: must be >= 1");
    let e = Scene::from_toml_str(
        "[[stack]]\ncount = 1\nsize = 1\n[[pyramid]]\nname = \"p\"\nbase = 2\nsize = -1\n",
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        r#"pyramid "p" ([[pyramid]] #0): size = -1: must be > 0"#
    );
    let e = Scene::from_toml_str("[[stack]]\ncount = 2\nsize = 1\ngap = -0.5\n").unwrap_err();
    assert_eq!(e.to_string(), "[[stack]] #0: gap = -0.5: must be >= 0");
    let e = Scene::from_toml_str("[[pyramid]]\nbase = 2\nsize = 1\nheight = 3\n").unwrap_err();
    let s = e.to_string();
    assert!(
        s.starts_with("[[pyramid]] #0 at line 1: unknown field `height`"),
        "{s}"
    );
    // A typo that would need millions of boxes is refused before any is made.
    let e = Scene::from_toml_str("[[pyramid]]\nbase = 10000\nsize = 1\n").unwrap_err();
    assert!(
        e.to_string().starts_with("scene: bodies = 50005000:"),
        "{e}"
    );
}

#[test]
fn missing_file_names_the_path_and_the_os_error() {
    let path = Path::new("/nonexistent/scene.toml");
    let e = Scene::load(path).unwrap_err();
    match &e {
        SceneError::Io { path: p, source } => {
            assert_eq!(p, path);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected Io, got {other:?}"),
    }
    assert!(e.to_string().contains("/nonexistent/scene.toml"));
}

// ---------------------------------------------------------------- physics

/// Falling Bricks, 10 s at 60 Hz with the default (soft-step) settings: every brick ends at
/// rest inside the box.
///
/// Tolerances: the bricks fall at most ~4.6 m and land within ~1 s; by 10 s a resting
/// contact under the soft-step solver only carries solver noise (observed ~1e-4 m/s), so
/// 0.05 m/s and 0.05 rad/s say "at rest" with a wide margin while a brick still sliding,
/// rocking or bouncing fails. "Inside" is checked on the centre against the inner walls
/// (x in (-4, 4), y in (0, 6)) and on the brick's bounding box with 0.02 m of slack for
/// the allowed contact penetration (linear slop 0.005 m plus soft-contact give).
#[test]
fn falling_bricks_come_to_rest_inside_the_box() {
    assert_settles_inside_the_box(load("falling_bricks.toml"));
}

/// The same without sleeping, so a brick that the engine would leave jittering cannot pass
/// by being put to sleep (sleep zeroes the velocity of resting islands).
#[test]
fn falling_bricks_come_to_rest_inside_the_box_without_sleep() {
    let mut scene = load("falling_bricks.toml");
    scene.settings.enable_sleep = false;
    assert_settles_inside_the_box(scene);
}

fn assert_settles_inside_the_box(scene: Scene) {
    let (mut world, ids) = scene.build_world().unwrap();
    for _ in 0..600 {
        world.step(1.0 / 60.0).unwrap();
    }
    let mut report = String::new();
    for (body, id) in scene.bodies.iter().zip(&ids) {
        if body.is_static {
            continue;
        }
        let b = world.body(*id).unwrap();
        let p = b.position();
        let speed = b.linear_velocity().length();
        let spin = b.angular_velocity().abs();
        let aabb = b.shape().aabb(b.transform());
        report.push_str(&format!(
            "{}: p = {p:?}, speed = {speed}, spin = {spin}, aabb = {aabb:?}\n",
            body.name
        ));
        assert!(b.is_finite(), "{report}");
        assert!(
            p.x > -4.0 && p.x < 4.0 && p.y > 0.0 && p.y < 6.0,
            "centre outside:\n{report}"
        );
        assert!(
            aabb.min.x > -4.02 && aabb.max.x < 4.02 && aabb.min.y > -0.02 && aabb.max.y < 6.02,
            "sticks out of the box:\n{report}"
        );
        assert!(speed < 0.05, "not at rest:\n{report}");
        assert!(spin < 0.05, "still turning:\n{report}");
    }
    // Every brick fell: none is still near its starting height unless resting on another.
    let mut lowest = Real::INFINITY;
    for (body, id) in scene.bodies.iter().zip(&ids) {
        if !body.is_static {
            lowest = lowest.min(world.body(*id).unwrap().position().y);
        }
    }
    assert!(lowest < 0.5, "no brick reached the floor:\n{report}");
}

#[test]
fn the_example_in_docs_scenes_md_loads() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scenes.md"))
        .unwrap();
    let start = doc.find("```toml\n").expect("a toml example") + "```toml\n".len();
    let end = start + doc[start..].find("```").unwrap();
    let scene = Scene::from_toml_str(&doc[start..end]).unwrap();
    assert_eq!(scene.name, "Bricks on a shelf");
    assert_eq!(scene.settings.solver, SolverKind::Sequential);
    // ground + brick + 5 stacked + 3 + 2 + 1 in the pyramid
    assert_eq!(scene.bodies.len(), 13);
    let names: Vec<&str> = scene.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(&names[..3], ["ground", "red brick", "stack[0]"]);
    assert_eq!(names[7], "small[0,0]");
    // The comments' claims: stack boxes at y = 0.25, ..., 2.25; pyramid centred on x = -6.
    assert!(close(scene.bodies[6].def.position, vec2(4.0, 2.25)));
    assert!(close(scene.bodies[12].def.position, vec2(-6.0, 2.5)));
    scene.build_world().unwrap();
}

// ---------------------------------------------------------------- circles, capsules, polygons

fn shaped(name: &str, shape: &str, fields: &str) -> String {
    format!("[[body]]\nname = \"{name}\"\nshape = {shape}\n{fields}\n")
}

/// The one body after the ground, or the error's message.
fn parse_body(body: &str) -> Result<tiltbox::scene::SceneBody, String> {
    Scene::from_toml_str(&with_ground(body))
        .map(|mut s| s.bodies.remove(1))
        .map_err(|e| e.to_string())
}

#[test]
fn circle_is_read_and_its_mass_is_density_times_pi_r_squared() {
    let b = parse_body(&shaped(
        "ball",
        "{ type = \"circle\", radius = 0.5 }",
        "position = [1, 2]\ndensity = 3",
    ))
    .unwrap();
    assert_eq!(b.def.shape, Shape::Circle { radius: 0.5 });
    assert_eq!(b.def.position, vec2(1.0, 2.0));
    let mut world = World::default();
    let id = world.add_body(&b.def).unwrap();
    let expected = std::f64::consts::PI * 0.25 * 3.0;
    let mass = world.body(id).unwrap().mass() as f64;
    assert!((mass - expected).abs() < 1e-5, "{mass} vs {expected}");
}

#[test]
fn capsule_length_is_end_to_end_along_x() {
    let b = parse_body(&shaped(
        "pill",
        "{ type = \"capsule\", length = 3, radius = 0.5 }",
        "position = [0, 2]\nangle = 0.25\nmass = 2",
    ))
    .unwrap();
    assert_eq!(b.def.shape, Shape::capsule(3.0, 0.5));
    assert_eq!(
        b.def.shape,
        Shape::Capsule {
            half_length: 1.0,
            radius: 0.5
        }
    );
    // Capsules and circles sit on their position: no centroid shift, whatever the angle.
    assert_eq!(b.def.position, vec2(0.0, 2.0));
    assert_eq!(b.def.angle, 0.25);
    assert_eq!(b.def.mass, MassSpec::Mass(2.0));
}

#[test]
fn polygon_is_recentred_on_its_centroid_and_the_body_moved_there() {
    // Right triangle (0,0), (3,0), (0,2): centroid (1, 2/3), area 3.
    let b = parse_body(&shaped(
        "wedge",
        "{ type = \"polygon\", vertices = [[0, 0], [3, 0], [0, 2]] }",
        "position = [10, 0]\ndensity = 2",
    ))
    .unwrap();
    assert!(
        close(b.def.position, vec2(11.0, 2.0 / 3.0)),
        "{:?}",
        b.def.position
    );
    let Shape::Polygon(p) = &b.def.shape else {
        panic!("expected a polygon, got {:?}", b.def.shape)
    };
    let expected = [
        vec2(-1.0, -2.0 / 3.0),
        vec2(2.0, -2.0 / 3.0),
        vec2(-1.0, 4.0 / 3.0),
    ];
    assert_eq!(p.vertices().len(), 3);
    for (v, e) in p.vertices().iter().zip(expected) {
        assert!(close(*v, e), "{v:?} vs {e:?}");
    }
    // The same polygon as the engine builds from those points.
    let (reference, _) =
        tiltbox::physics::Polygon::new(&[vec2(0.0, 0.0), vec2(3.0, 0.0), vec2(0.0, 2.0)]).unwrap();
    assert_eq!(b.def.shape, Shape::from(reference));
    // mass = density x area = 2 x 3.
    let mut world = World::default();
    let id = world.add_body(&b.def).unwrap();
    assert!((world.body(id).unwrap().mass() - 6.0).abs() < 1e-4);

    // Turned a quarter turn counter-clockwise, the centroid turns with the body:
    // position + R(pi/2) (1, 2/3) = (10 - 2/3, 1).
    let b = parse_body(&shaped(
        "wedge",
        "{ type = \"polygon\", vertices = [[0, 0], [3, 0], [0, 2]] }",
        "position = [10, 0]\nangle = 1.5707963267948966\ndensity = 2",
    ))
    .unwrap();
    assert!(
        close(b.def.position, vec2(10.0 - 2.0 / 3.0, 1.0)),
        "{:?}",
        b.def.position
    );
    // A polygon centred on its position stays there.
    let b = parse_body(&shaped(
        "square",
        "{ type = \"polygon\", vertices = [[-1, -1], [1, -1], [1, 1], [-1, 1]] }",
        "position = [4, 5]\nangle = 0.7\ndensity = 1",
    ))
    .unwrap();
    assert!(
        close(b.def.position, vec2(4.0, 5.0)),
        "{:?}",
        b.def.position
    );
}

#[test]
fn static_polygon_builds_into_a_world_where_its_vertices_were_given() {
    let scene = Scene::from_toml_str(&shaped(
        "ramp",
        "{ type = \"polygon\", vertices = [[0, 0], [4, 0], [4, 1]] }",
        "position = [-2, 0]\nstatic = true",
    ))
    .unwrap();
    let (world, ids) = scene.build_world().unwrap();
    let body = world.body(ids[0]).unwrap();
    assert!(body.is_static());
    // World-space vertices are the ones written plus position.
    let aabb = body.shape().aabb(body.transform());
    assert!(close(aabb.min, vec2(-2.0, 0.0)), "{aabb:?}");
    assert!(close(aabb.max, vec2(2.0, 1.0)), "{aabb:?}");
}

#[test]
fn clockwise_polygon_names_the_vertex_and_its_value() {
    let e = Scene::from_toml_str(&with_ground(&shaped(
        "wedge",
        "{ type = \"polygon\", vertices = [[0, 0], [0, 1], [1, 0.5]] }",
        "position = [0, 1]\ndensity = 1",
    )))
    .unwrap_err();
    let s = e.to_string();
    assert!(
        s.starts_with(r#"body "wedge" (#1): shape.vertices[1] = [0, 1]: turns clockwise"#),
        "{s}"
    );
    assert!(s.contains("counter-clockwise"), "{s}");
    match e {
        SceneError::Invalid { field, value, .. } => {
            assert_eq!(field, "shape.vertices[1]");
            assert_eq!(value.as_deref(), Some("[0, 1]"));
        }
        other => panic!("expected Invalid, got {other:?}"),
    }
    // A dent (a reflex corner) in an otherwise counter-clockwise list.
    let s = parse_body(&shaped(
        "dent",
        "{ type = \"polygon\", vertices = [[0, 0], [2, 0], [1, 0.5], [2, 2], [0, 2]] }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert!(
        s.starts_with(r#"body "dent" (#1): shape.vertices[2] = [1, 0.5]: turns clockwise"#),
        "{s}"
    );
}

#[test]
fn polygon_vertex_count_must_be_3_to_8() {
    let s = parse_body(&shaped(
        "stick",
        "{ type = \"polygon\", vertices = [[0, 0], [1, 0]] }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert!(
        s.starts_with(r#"body "stick" (#1): shape.vertices: must hold 3 to 8 points, got 2"#),
        "{s}"
    );
    let nine: Vec<String> = (0..9)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 9.0;
            format!("[{}, {}]", a.cos(), a.sin())
        })
        .collect();
    let s = parse_body(&shaped(
        "nonagon",
        &format!("{{ type = \"polygon\", vertices = [{}] }}", nine.join(", ")),
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert!(
        s.starts_with(r#"body "nonagon" (#1): shape.vertices: must hold 3 to 8 points, got 9"#),
        "{s}"
    );
    // A vertex that is not a pair is named with its index.
    let s = parse_body(&shaped(
        "odd",
        "{ type = \"polygon\", vertices = [[0, 0], [1, 0, 2], [0, 1]] }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(
        s,
        r#"body "odd" (#1): shape.vertices[1] = [1, 0, 2]: must be a pair [x, y] (metres)"#
    );
}

#[test]
fn nan_vertex_is_refused_naming_the_vertex() {
    let s = parse_body(&shaped(
        "bad",
        "{ type = \"polygon\", vertices = [[0, 0], [1, nan], [0, 1]] }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(
        s,
        r#"body "bad" (#1): shape.vertices[1] = [1, NaN]: coordinates must be finite numbers"#
    );
    let s = parse_body(&shaped(
        "far",
        "{ type = \"polygon\", vertices = [[0, 0], [inf, 0], [0, 1]] }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert!(s.contains("shape.vertices[1] = [inf, 0]"), "{s}");
}

#[test]
fn polygon_position_and_angle_errors_show_the_value_written() {
    let s = parse_body(&shaped(
        "tri",
        "{ type = \"polygon\", vertices = [[0, 0], [1, 0], [0, 1]] }",
        "position = [0, nan]\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(
        s,
        r#"body "tri" (#1): position.y = NaN: must be a finite number"#
    );
    let s = parse_body(&shaped(
        "tri",
        "{ type = \"polygon\", vertices = [[0, 0], [1, 0], [0, 1]] }",
        "position = [0, 1]\nangle = inf\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(
        s,
        r#"body "tri" (#1): angle = inf: must be a finite number"#
    );
}

#[test]
fn capsule_no_longer_than_its_ends_is_refused() {
    let s = parse_body(&shaped(
        "pill",
        "{ type = \"capsule\", length = 1, radius = 0.5 }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert!(
        s.starts_with(
            r#"body "pill" (#1): shape.length = 1: must be more than twice shape.radius = 0.5"#
        ),
        "{s}"
    );
    let s = parse_body(&shaped(
        "pill",
        "{ type = \"capsule\", length = 0.4, radius = 0.5 }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert!(s.contains("shape.length = 0.4"), "{s}");
    let s = parse_body(&shaped(
        "pill",
        "{ type = \"capsule\", length = -2, radius = 0.5 }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(s, r#"body "pill" (#1): shape.length = -2: must be > 0"#);
    // The fields are the capsule's own: a rect's width is unknown there.
    let s = parse_body(&shaped(
        "pill",
        "{ type = \"capsule\", width = 2, radius = 0.5 }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert!(s.contains("width") && s.contains("length"), "{s}");
}

#[test]
fn negative_or_nan_radius_is_refused() {
    let s = parse_body(&shaped(
        "ball",
        "{ type = \"circle\", radius = -0.5 }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(s, r#"body "ball" (#1): shape.radius = -0.5: must be > 0"#);
    let s = parse_body(&shaped(
        "ball",
        "{ type = \"circle\", radius = nan }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(
        s,
        r#"body "ball" (#1): shape.radius = NaN: must be a finite number"#
    );
    let s = parse_body(&shaped(
        "pill",
        "{ type = \"capsule\", length = 2, radius = -0.1 }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(s, r#"body "pill" (#1): shape.radius = -0.1: must be > 0"#);
}

#[test]
fn unknown_shape_type_lists_the_known_ones() {
    let s = parse_body(&shaped(
        "blob",
        "{ type = \"ellipse\", radius = 1 }",
        "position = [0, 1]\ndensity = 1",
    ))
    .unwrap_err();
    assert!(
        s.starts_with(r#"body "blob" (#1) at line 10: shape"#),
        "{s}"
    );
    for kind in ["rect", "circle", "capsule", "polygon"] {
        assert!(s.contains(kind), "{s}");
    }
}

// ---------------------------------------------------------------- shapes.toml

/// Inner walls of shapes.toml's open box: x in (-5, 5), floor top at y = 0.
const SHAPES_INNER_X: Real = 5.0;

#[test]
fn shapes_is_a_box_holding_a_varied_pile() {
    let scene = load("shapes.toml");
    assert_eq!(scene.name, "Shapes");
    let walls: Vec<_> = scene.bodies.iter().filter(|b| b.is_static).collect();
    let pile: Vec<_> = scene.bodies.iter().filter(|b| !b.is_static).collect();
    assert_eq!(walls.len(), 3);
    assert!((15..=25).contains(&pile.len()), "{}", pile.len());
    let count = |pred: &dyn Fn(&Shape) -> bool| pile.iter().filter(|b| pred(&b.def.shape)).count();
    let sides =
        |n: usize| move |s: &Shape| matches!(s, Shape::Polygon(p) if p.vertices().len() == n);
    assert!(count(&|s| matches!(s, Shape::Circle { .. })) >= 3);
    assert!(count(&|s| matches!(s, Shape::Capsule { .. })) >= 3);
    assert!(count(&sides(3)) >= 3);
    assert!(count(&sides(6)) >= 2);
    assert!(count(&|s| matches!(s, Shape::Rect { .. })) >= 2);
    // The documented off-centre example: vertices (0,0), (1,0), (0,0.8) at (2, 2).
    let tri = pile.iter().find(|b| b.name == "right triangle").unwrap();
    assert!(close(
        tri.def.position,
        vec2(2.0 + 1.0 / 3.0, 2.0 + 0.8 / 3.0)
    ));

    // Everything starts inside the box, and nothing overlaps: the first step's contacts are
    // found at the initial poses (speculative, so near pairs appear with separation > 0).
    let (mut world, ids) = scene.build_world().unwrap();
    for (body, id) in scene.bodies.iter().zip(&ids) {
        let b = world.body(*id).unwrap();
        assert_eq!(b.position(), body.def.position, "{}", body.name);
        assert_eq!(b.shape(), &body.def.shape, "{}", body.name);
        if body.is_static {
            continue;
        }
        let aabb = b.shape().aabb(b.transform());
        assert!(
            aabb.min.x > -SHAPES_INNER_X && aabb.max.x < SHAPES_INNER_X && aabb.min.y > 0.0,
            "{} starts outside the box: {aabb:?}",
            body.name
        );
    }
    world.step(1.0 / 60.0).unwrap();
    for c in world.contacts() {
        for p in &c.points[..c.count] {
            assert!(p.separation > 0.0, "bodies overlap at the start: {c:?}");
        }
    }
}

/// What a run of shapes.toml measured.
struct PileRun {
    /// Deepest overlap of any contact over the whole run, m (>= 0).
    max_overlap_ever: Real,
    /// Deepest overlap of any contact at the end, m (>= 0).
    max_overlap_end: Real,
    /// Fastest body at the end, m/s, and its name.
    max_speed_end: (Real, String),
    /// Largest spin x bounding radius at the end, m/s, and the body's name.
    max_spin_end: (Real, String),
    /// One line per dynamic body at the end.
    report: String,
}

/// Step shapes.toml for 10 s at 60 Hz, checking every step that each body's bounding box
/// stays inside the box (0.02 m of slack for contact give) and that nothing turns non-finite.
fn run_pile(scene: &Scene) -> PileRun {
    let (mut world, ids) = scene.build_world().unwrap();
    let deepest = |world: &World| {
        world
            .contacts()
            .flat_map(|c| c.points.into_iter().take(c.count))
            .fold(0.0 as Real, |m, p| m.max(-p.separation))
    };
    let mut max_overlap_ever: Real = 0.0;
    for frame in 1..=600 {
        world.step(1.0 / 60.0).unwrap();
        max_overlap_ever = max_overlap_ever.max(deepest(&world));
        for (body, id) in scene.bodies.iter().zip(&ids) {
            let b = world.body(*id).unwrap();
            assert!(b.is_finite(), "{} at frame {frame}", body.name);
            if body.is_static {
                continue;
            }
            let aabb = b.shape().aabb(b.transform());
            assert!(
                aabb.min.x > -SHAPES_INNER_X - 0.02
                    && aabb.max.x < SHAPES_INNER_X + 0.02
                    && aabb.min.y > -0.02,
                "{} left the box at frame {frame}: {aabb:?}",
                body.name
            );
        }
    }
    let mut run = PileRun {
        max_overlap_ever,
        max_overlap_end: deepest(&world),
        max_speed_end: (0.0, String::new()),
        max_spin_end: (0.0, String::new()),
        report: String::new(),
    };
    for (body, id) in scene.bodies.iter().zip(&ids) {
        if body.is_static {
            continue;
        }
        let b = world.body(*id).unwrap();
        let speed = b.linear_velocity().length();
        let spin = b.angular_velocity().abs() * b.shape().bounding_radius();
        run.report.push_str(&format!(
            "{}: p = {:?}, speed = {speed}, spin x radius = {spin}, awake = {}\n",
            body.name,
            b.position(),
            b.is_awake()
        ));
        if speed > run.max_speed_end.0 {
            run.max_speed_end = (speed, body.name.clone());
        }
        if spin > run.max_spin_end.0 {
            run.max_spin_end = (spin, body.name.clone());
        }
    }
    run
}

/// shapes.toml, 10 s at 60 Hz with its own (default, soft-step, sleep on) settings: the pile
/// settles inside the box without bodies sinking into each other.
///
/// Tolerances: 2 cm of overlap is four times the linear slop (0.005 m) and well under the
/// smallest body (a 0.25 m pebble), so a body sinking into another fails while soft-contact
/// give under load passes; 0.05 m/s (linear speed, and spin x bounding radius, the engine's own
/// sleep measure) says "at rest" while a ball still rolling across the floor fails.
#[test]
fn shapes_pile_settles_inside_the_box() {
    assert_pile_settled(run_pile(&load("shapes.toml")));
}

fn assert_pile_settled(run: PileRun) {
    let r = &run.report;
    assert!(
        run.max_overlap_end < 0.02,
        "overlap {} m at the end:\n{r}",
        run.max_overlap_end
    );
    assert!(
        run.max_overlap_ever < 0.02,
        "overlap {} m during the run:\n{r}",
        run.max_overlap_ever
    );
    assert!(
        run.max_speed_end.0 < 0.05,
        "{} still moves at {} m/s:\n{r}",
        run.max_speed_end.1,
        run.max_speed_end.0
    );
    assert!(
        run.max_spin_end.0 < 0.05,
        "{} still turns at {} m/s at its rim:\n{r}",
        run.max_spin_end.1,
        run.max_spin_end.0
    );
    eprintln!(
        "shapes.toml after 10 s: max overlap {} m (end), {} m (whole run); max speed {} m/s ({}); max spin x radius {} m/s ({})",
        run.max_overlap_end,
        run.max_overlap_ever,
        run.max_speed_end.0,
        run.max_speed_end.1,
        run.max_spin_end.0,
        run.max_spin_end.1
    );
}

/// The same without sleeping, so a ball still rolling cannot pass by being put to sleep.
#[test]
fn shapes_pile_settles_inside_the_box_without_sleep() {
    let mut scene = load("shapes.toml");
    scene.settings.enable_sleep = false;
    assert_pile_settled(run_pile(&scene));
}

#[test]
fn the_shapes_example_in_docs_scenes_md_loads() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scenes.md"))
        .unwrap();
    let at = doc.find("## Example with shapes").expect("the section");
    let start = at + doc[at..].find("```toml\n").expect("a toml example") + "```toml\n".len();
    let end = start + doc[start..].find("```").unwrap();
    let scene = Scene::from_toml_str(&doc[start..end]).unwrap();
    assert_eq!(scene.name, "One of each");
    let kinds: Vec<&str> = scene.bodies[3..]
        .iter()
        .map(|b| b.def.shape.kind())
        .collect();
    assert_eq!(kinds, ["circle", "capsule", "polygon", "polygon"]);
    // The comments' claims.
    let ball = &scene.bodies[3];
    let (world, ids) = scene.build_world().unwrap();
    let mass = world.body(ids[3]).unwrap().mass();
    assert!((mass - 0.785).abs() < 1e-3, "{}: {mass}", ball.name);
    assert_eq!(scene.bodies[4].def.shape, Shape::capsule(1.2, 0.2));
    assert!(close(scene.bodies[5].def.position, vec2(1.0, 1.0)));
    assert!(close(
        scene.bodies[6].def.position,
        vec2(3.0 + 1.0 / 3.0, 0.5 + 0.8 / 3.0)
    ));
}

#[test]
fn the_example_in_the_scene_module_docs_loads() {
    let src =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/scene/mod.rs"))
            .unwrap();
    let text: String = src
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| l.strip_prefix(' ').unwrap_or(l))
        .skip_while(|l| *l != "```toml")
        .skip(1)
        .take_while(|l| *l != "```")
        .map(|l| format!("{l}\n"))
        .collect();
    let scene = Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let wedge = scene.bodies.iter().find(|b| b.name == "wedge").unwrap();
    assert!(close(
        wedge.def.position,
        vec2(2.0 + 1.0 / 3.0, 3.0 + 1.0 / 3.0)
    ));
    scene.build_world().unwrap();
}
