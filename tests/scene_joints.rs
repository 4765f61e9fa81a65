//! `[[joint]]` and `[[rope]]` tables: the example in docs/scenes.md loads, builds and behaves as
//! its comments say, and bad joint tables are refused naming the table, the field and the value.
#![cfg(feature = "scene")]

mod common;

use tiltbox::physics::Vec2;
use tiltbox::scene::Scene;

fn joints_example() -> String {
    common::scene::docs_example("## Example with joints")
}

#[test]
fn the_joints_example_in_docs_scenes_md_loads_and_hangs_as_it_says() {
    let scene = Scene::from_toml_str(&joints_example()).unwrap();
    assert_eq!(
        scene.bodies.len(),
        3 + 10,
        "three bodies and ten links, links last"
    );
    assert_eq!(scene.bodies[3].name, "rope[0]");
    assert_eq!(
        scene.joints.len(),
        1 + 11,
        "the hinge; ten links' joints and the weight's"
    );
    let (mut world, ids) = scene.build_world().unwrap();
    assert_eq!(world.joint_count(), 12);
    for _ in 0..240 {
        world.step(1.0 / 60.0).unwrap();
    }
    // The door swings down onto its limit, -1.2 rad (the 60 Hz joint gives 1e-3 rad under
    // its weight; bound 0.01 rad).
    let door = world.body(ids[1]).unwrap();
    assert!(
        (door.angle() + 1.2).abs() < 0.01,
        "door at {}",
        door.angle()
    );
    // The hinge holds the door's end at the wall's face.
    let hinge_end = door.transform().apply(Vec2::new(-1.0, 0.0));
    assert!(
        (hinge_end - Vec2::new(0.1, 3.0)).length() < 5e-3,
        "{hinge_end}"
    );
    // The rope holds the weight where it was laid: each of its 11 joints gives at most
    // W / (m_eff (2 pi 60)^2) with W the 1.19 kg below it and m_eff at least half a link's
    // 62.5 g, 2.6 mm; bound 3 cm down, 1 mm sideways.
    let weight = world.body(ids[2]).unwrap().position();
    assert!(
        (weight.x - 5.0).abs() < 1e-3 && weight.y < 0.0 && weight.y > -0.03,
        "{weight}"
    );
}

fn refused(text: &str) -> String {
    Scene::from_toml_str(text).unwrap_err().to_string()
}

const BODIES: &str = r#"
[[body]]
name = "ground"
static = true
shape = { type = "rect", width = 10, height = 1 }
position = [0, -0.5]
[[body]]
name = "box"
shape = { type = "rect", width = 1, height = 1 }
position = [0, 2]
density = 1
"#;

#[test]
fn bad_joint_tables_are_refused_naming_the_table_the_field_and_the_value() {
    let joint = |rest: &str| format!("{BODIES}\n[[joint]]\nname = \"j\"\n{rest}\n");
    let cases: [(&str, &[&str]); 8] = [
        (
            "type = \"revolute\"\nb = \"lid\"",
            &["joint \"j\"", "b = \"lid\"", "names no body"],
        ),
        (
            "type = \"hinge\"\nb = \"box\"",
            &["type = \"hinge\"", "revolute, prismatic"],
        ),
        (
            "type = \"revolute\"\na = \"box\"\nb = \"box\"",
            &["b = \"box\"", "two different bodies"],
        ),
        (
            "type = \"revolute\"\nb = \"ground\"",
            &["at least one dynamic body"],
        ),
        (
            "type = \"weld\"\nb = \"box\"\nlimit = [0, 1]",
            &["limit", "does not apply to a weld joint"],
        ),
        (
            "type = \"revolute\"\nb = \"box\"\nlimit = [1, -1]",
            &["limit.lower = 1", "limit.upper = -1"],
        ),
        ("type = \"prismatic\"\nb = \"box\"", &["axis", "required"]),
        (
            "type = \"revolute\"\nb = \"box\"\nanchor = [0, 0]\nanchor_a = [1, 0]",
            &["anchor", "not both"],
        ),
    ];
    for (rest, expected) in cases {
        let message = refused(&joint(rest));
        for part in expected {
            assert!(
                message.contains(part),
                "{rest:?}: {message:?} lacks {part:?}"
            );
        }
    }
    let rope = format!("{BODIES}\n[[rope]]\nfrom = [0, 5]\nto = [3, 5]\nlinks = 0\n");
    let message = refused(&rope);
    assert!(
        message.contains("[[rope]] #0") && message.contains("links = 0"),
        "{message}"
    );
    let rope = format!("{BODIES}\n[[rope]]\nfrom = [0, 5]\nto = [0, 5]\nlinks = 3\n");
    assert!(
        refused(&rope).contains("two different"),
        "{}",
        refused(&rope)
    );
}
