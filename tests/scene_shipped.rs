//! The shipped scene files: Falling Bricks, the stack, the pyramid and the shapes pile load
//! and build as documented (the examples in docs/scenes.md and the scene module's docs load
//! too), and Falling Bricks and the shapes pile come to rest inside their boxes.

#![cfg(feature = "scene")]

mod common;

use common::scene::*;
use tiltbox::physics::{vec2, MassSpec, Real, Shape, SolverKind, World};
use tiltbox::scene::{Colour, Scene};

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
    assert_no_overlap_after_one_step(&mut world);
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
    let scene = Scene::from_toml_str(&docs_example("\n## Example\n")).unwrap();
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
    assert_no_overlap_after_one_step(&mut world);
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
    let scene = Scene::from_toml_str(&docs_example("## Example with shapes")).unwrap();
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
    let src = common::read_repo_file("src/scene/mod.rs");
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

/// The first step's contacts are found at the initial poses: none may overlap (contacts are
/// speculative, so touching-soon pairs appear with separation > 0).
fn assert_no_overlap_after_one_step(world: &mut World) {
    world.step(1.0 / 60.0).unwrap();
    for c in world.contacts() {
        for p in &c.points[..c.count] {
            assert!(p.separation > 0.0, "bodies overlap at the start: {c:?}");
        }
    }
}
