//! The sensor example in docs/scenes.md: it loads, and the events come when its text says.
#![cfg(feature = "scene")]

mod common;

use tiltbox::scene::Scene;

#[test]
fn the_sensor_example_reports_what_docs_scenes_md_says_when_it_says() {
    let text = common::scene::docs_example("## Example with a sensor and events");
    let scene = Scene::from_toml_str(&text).unwrap();
    let (mut world, ids) = scene.build_world().unwrap();
    let (gate, ball) = (ids[1], ids[2]);
    assert!(world.body(gate).unwrap().flags().sensor);
    let mut seen = Vec::new();
    for step in 1..=120 {
        world.step(1.0 / 60.0).unwrap();
        let e = world.events();
        for s in &e.sensor_begin {
            assert_eq!((s.sensor.body, s.visitor.body), (gate, ball));
            seen.push(("enters", step));
        }
        for s in &e.sensor_end {
            assert_eq!((s.sensor.body, s.visitor.body), (gate, ball));
            seen.push(("leaves", step));
        }
        if let Some(h) = e.hits.first() {
            assert_eq!(h.b.body, ball);
            seen.push(("hits", step));
        }
        if !e.contact_begin.is_empty() {
            seen.push(("touches", step));
        }
    }
    // Semi-implicit Euler over the soft step's 4 substeps, from rest: after k steps the ball has
    // fallen g dt^2 k (k + 1/4) / 2: 2 m (bottom to the gate's top) in step 39, 3.5 m (its top to the gate's bottom) in step
    // 51, 7 m (to the floor) in step 72; touching is judged at the start of the next step or
    // the one after (a hit every step the ball still pushes in faster than 1 m/s).
    assert_eq!(seen[0], ("enters", 39), "{seen:?}");
    assert_eq!(seen[1], ("leaves", 51), "{seen:?}");
    assert_eq!(seen[2], ("hits", 72), "{seen:?}");
    let touched = seen.iter().find(|s| s.0 == "touches").expect("touches").1;
    assert!((73..=74).contains(&touched), "{seen:?}");
}

#[test]
fn a_misspelt_flag_is_refused_by_name() {
    let body = r#"
[[body]]
shape = { type = "circle", radius = 0.5 }
position = [0, 1]
density = 1
sensr = true
"#;
    let (_, message) = common::scene::error_for(body);
    assert!(message.contains("sensr"), "{message}");
}
