//! What docs/scenes.md says about settings and `tiltbox simulate` that a user of the binary
//! cannot read in the code, checked on real runs: the soft step's contact stiffness ceiling
//! (a quarter of the substep rate, not lifted by `max_contact_hertz_ratio`), `linear_slop`
//! being a sequential-solver knob only, the solver names a scene file takes, the sequential
//! slop of scenes against the report's, `--seconds` rounding to the nearest step, and when a
//! step takes its workers.
#![cfg(all(feature = "scene", feature = "cli", feature = "measure"))]

use std::process::{Command, Stdio};
use tiltbox::physics::{vec2, BodyDef, Real, Settings, Shape, ShapeFlags, Vec2, WorkerPool, World};
use tiltbox::scene::Scene;

/// A box dropped onto a box resting on the ground: contacts that are made, loaded and
/// settling during the run, so any change to the contact springs shows in the state.
fn stack(settings: &str) -> String {
    format!(
        r#"
name = "two boxes"
gravity = [0, -9.81]
[settings]
{settings}
[[body]]
name = "ground"
static = true
shape = {{ type = "rect", width = 10, height = 1 }}
position = [0, -0.5]
[[body]]
name = "lower"
shape = {{ type = "rect", width = 1, height = 1 }}
position = [0, 0.5]
density = 1
[[body]]
name = "upper"
shape = {{ type = "rect", width = 1, height = 1 }}
position = [0.2, 2.5]
density = 5
"#
    )
}

/// The World's state hash after one second at 60 Hz.
fn hash_after_a_second(settings: &str) -> u64 {
    let scene = Scene::from_toml_str(&stack(settings)).unwrap();
    let (mut world, _) = scene.build_world().unwrap();
    for _ in 0..60 {
        world.step(1.0 / 60.0).unwrap();
    }
    world.state_hash()
}

#[test]
fn contact_hertz_is_capped_at_a_quarter_of_the_substep_rate() {
    // 4 substeps of 1/60 s: 240 Hz, a quarter is 60 Hz. Below the cap the knob works...
    assert_ne!(
        hash_after_a_second("contact_hertz = 30"),
        hash_after_a_second("contact_hertz = 60")
    );
    // ...above it nothing changes, and max_contact_hertz_ratio does not lift the cap.
    let at_cap = hash_after_a_second("contact_hertz = 60");
    assert_eq!(hash_after_a_second("contact_hertz = 120"), at_cap);
    assert_eq!(
        hash_after_a_second("contact_hertz = 120\nmax_contact_hertz_ratio = 1.0"),
        at_cap
    );
    // 8 substeps raise the cap to 120 Hz: now 120 differs from 60.
    assert_ne!(
        hash_after_a_second("substeps = 8\ncontact_hertz = 120"),
        hash_after_a_second("substeps = 8\ncontact_hertz = 60")
    );
}

#[test]
fn linear_slop_moves_only_the_sequential_solver() {
    assert_eq!(
        hash_after_a_second("linear_slop = 0.005"),
        hash_after_a_second("linear_slop = 0.05"),
        "the soft step (load_aware_stiffness off) must not use linear_slop"
    );
    assert_ne!(
        hash_after_a_second("solver = \"sequential\"\nlinear_slop = 0.005"),
        hash_after_a_second("solver = \"sequential\"\nlinear_slop = 0.05"),
    );
}

#[test]
fn scenes_take_soft_step_with_an_underscore_and_say_so() {
    let e = Scene::from_toml_str(&stack("solver = \"soft-step\"")).unwrap_err();
    let e = e.to_string();
    assert!(e.contains("soft-step") && e.contains("soft_step"), "{e}");
    assert!(Scene::from_toml_str(&stack("solver = \"soft_step\"")).is_ok());
}

#[test]
fn a_sequential_scene_uses_5_mm_of_slop_and_the_report_10_mm() {
    let scene = Scene::from_toml_str(&stack("solver = \"sequential\"")).unwrap();
    assert_eq!(scene.settings.linear_slop, 0.005);
    assert!(Settings::default().enable_sleep, "sleep is on in scenes");
    assert!(scene.settings.enable_sleep);
    let report = tiltbox::measure::accuracy::sequential(10);
    assert_eq!(report.linear_slop, 0.01);
}

#[test]
fn seconds_round_to_the_nearest_whole_step() {
    let last_frame = |seconds: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_tiltbox"))
            .args([
                "simulate",
                "config/scenes/falling_bricks.toml",
                "--dt",
                "0.1",
                "--format",
                "jsonl",
                "--seconds",
                seconds,
            ])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdin(Stdio::null())
            .output()
            .unwrap();
        assert!(o.status.success());
        let text = String::from_utf8(o.stdout).unwrap();
        let last: serde_json::Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
        last["frame"].as_u64().unwrap()
    };
    assert_eq!(last_frame("0.26"), 3);
    assert_eq!(last_frame("0.24"), 2);
    assert_eq!(last_frame("0.3"), 3);
}

/// The `workers` row: "a step with fewer than 256 awake bodies (and fewer than 32 with a
/// sensor) runs on one" thread; from either count it takes the workers (counted by the pool).
#[test]
fn a_step_takes_the_workers_from_256_awake_bodies_or_32_with_a_sensor() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scenes.md"))
        .expect("docs/scenes.md");
    assert!(doc.contains(
        "a step with fewer than 256 awake bodies (and fewer than 32 with a sensor) runs on one"
    ));
    let steps_shared = |awake: usize, sensing: usize| {
        let pool = WorkerPool::new(2).expect("two workers");
        let mut w = World::new(Settings::default(), Vec2::ZERO).expect("a world");
        w.share_workers(&pool);
        for i in 0..awake {
            let disc = BodyDef::dynamic(Shape::circle(0.5), vec2(3.0 * i as Real, 0.0));
            w.add_body(&disc).expect("a disc");
        }
        let sensor = ShapeFlags {
            sensor: true,
            ..ShapeFlags::NONE
        };
        for i in 0..sensing {
            let at = vec2(3.0 * i as Real, 10.0);
            let def = BodyDef::fixed(Shape::rect(1.0, 1.0), at).with_flags(sensor);
            w.add_body(&def).expect("a sensor");
        }
        w.step(1.0 / 60.0).expect("a step");
        pool.steps_shared()
    };
    assert_eq!(steps_shared(255, 0), 0, "255 awake bodies");
    assert_eq!(steps_shared(256, 0), 1, "256 awake bodies");
    assert_eq!(steps_shared(0, 31), 0, "31 sensing bodies");
    assert_eq!(steps_shared(0, 32), 1, "32 sensing bodies");
}
