//! `parts` in scene files: the example in docs/scenes.md loads, weighs and behaves as its
//! comments say, parts inherit the body's material unless they give their own, polygon parts
//! are placed at their centroids, and bad parts are refused naming the body, the part and the
//! field.
#![cfg(feature = "scene")]

mod common;

use tiltbox::physics::{Real, Vec2};
use tiltbox::scene::Scene;

const PI: Real = std::f64::consts::PI as Real;

fn parts_example() -> String {
    common::scene::docs_example("## Example with parts")
}

#[test]
fn the_parts_example_in_docs_scenes_md_loads_and_rests_as_it_says() {
    let scene = Scene::from_toml_str(&parts_example()).unwrap();
    let (mut world, ids) = scene.build_world().unwrap();
    let body = |w: &tiltbox::physics::World, i: usize| w.body(ids[i]).unwrap().clone();
    // Masses: the dumbbell 1 x (2 x 0.1) + 2 x pi 0.3^2; the L 2 x 1 + 3 x 0.75 (the part's own
    // density); the post 1 x 0.4 + 1 x 0.2 (the body's density inherited).
    let dumbbell = 0.2 + 2.0 * PI * 0.09;
    assert!(
        (body(&world, 1).mass() - dumbbell).abs() < 1e-5,
        "{}",
        body(&world, 1).mass()
    );
    assert!(
        (body(&world, 2).mass() - 4.25).abs() < 1e-5,
        "{}",
        body(&world, 2).mass()
    );
    assert!(
        (body(&world, 3).mass() - 0.6).abs() < 1e-5,
        "{}",
        body(&world, 3).mass()
    );
    // The L's part has its own friction, the dumbbell's discs the body's.
    assert_eq!(body(&world, 2).parts()[0].friction, 0.9);
    assert_eq!(body(&world, 1).parts()[1].friction, 0.6);
    // Origins as written, the post's centre of mass 0.183 m right of its origin.
    assert_eq!(body(&world, 3).position(), Vec2::new(4.0, 1.2));
    assert!((body(&world, 3).local_center().x - 0.2 * 0.55 / 0.6).abs() < 1e-5);
    for _ in 0..180 {
        world.step(1.0 / 60.0).unwrap();
    }
    // At rest after 3 s: the dumbbell on its discs (bar centre at the discs' radius, 0.3 m),
    // the L on its bar (0.25 m), the post upright; bounds 1 cm and 0.02 rad, the contacts'
    // give under gravity being a few mm.
    for (i, y) in [(1, 0.3), (2, 0.25), (3, 1.2)] {
        let b = body(&world, i);
        assert!(
            (b.position().y - y).abs() < 0.01,
            "{}: {:?}",
            i,
            b.position()
        );
        assert!(b.angle().abs() < 0.02, "{}: {}", i, b.angle());
    }
}

#[test]
fn a_polygon_part_sits_at_its_centroid_and_bad_parts_are_refused_by_name() {
    let text = r#"
        [[body]]
        name = "cart"
        shape = { type = "rect", width = 2, height = 0.5 }
        position = [0, 1]
        density = 1
        parts = [{ shape = { type = "polygon", vertices = [[0, 0], [1, 0], [0, 1]] }, offset = [2, 0] }]
    "#;
    let scene = Scene::from_toml_str(text).unwrap();
    let part = &scene.bodies[0].def.parts[0];
    // The triangle's centroid (1/3, 1/3) from the offset (2, 0).
    assert!((part.offset - Vec2::new(2.0 + 1.0 / 3.0, 1.0 / 3.0)).length() < 1e-6);

    let refused = |part: &str, wanted: &[&str]| {
        let text = format!(
            "[[body]]\nname = \"cart\"\nshape = {{ type = \"rect\", width = 2, height = 0.5 }}\n\
             position = [0, 1]\ndensity = 1\nparts = [{{ shape = {{ type = \"circle\", radius = 0.2 }} }}, {part}]\n"
        );
        let e = Scene::from_toml_str(&text).unwrap_err().to_string();
        for w in wanted {
            assert!(e.contains(w), "{e:?} lacks {w:?}");
        }
    };
    refused(
        r#"{ shape = { type = "circle", radius = -1 } }"#,
        &["body \"cart\"", "parts[1].shape.radius", "-1"],
    );
    refused(
        r#"{ shape = { type = "circle", radius = 1 }, density = 0 }"#,
        &["parts[1].density", "0"],
    );
    refused(
        r#"{ shape = { type = "circle", radius = 1 }, friction = -2 }"#,
        &["parts[1].friction", "-2"],
    );
    refused(
        r#"{ shape = { type = "chain", points = [[0, 0], [1, 0]] } }"#,
        &["parts[1].shape.type", "chain"],
    );
    refused(
        r#"{ shape = { type = "segment", a = [0, 0], b = [1, 0] } }"#,
        &["mass", "segment"],
    );
    refused(
        r##"{ shape = { type = "circle", radius = 1 }, colour = "#ff0000" }"##,
        &["colour"],
    );
}
