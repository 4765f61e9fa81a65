//! Collision filters (Box2D's category, mask and group) through the API, a change of filter on
//! a resting body, checkpoints and scene files.

use tiltbox::physics::{vec2, BodyDef, Filter, Real, Shape, World};

const DT: Real = 1.0 / 60.0;

/// A ground whose top is at y = 0 and a 1 m box resting on it, with `filter`.
fn box_on_ground(filter: Filter) -> (World, tiltbox::physics::BodyId) {
    let mut w = World::default();
    w.add_body(&BodyDef::fixed(Shape::rect(20.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    let b = w
        .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)).with_filter(filter))
        .unwrap();
    (w, b)
}

fn height_after(w: &mut World, b: tiltbox::physics::BodyId, steps: usize) -> Real {
    for _ in 0..steps {
        w.step(DT).unwrap();
    }
    w.body(b).unwrap().position().y
}

#[test]
fn a_mask_without_the_grounds_category_falls_through_it_and_the_default_rests() {
    // Resting: the centre stays at 0.5 m within the contact's give (a few mm). Filtered out:
    // free fall, g t^2 / 2 = 4.9 m in 1 s.
    let (mut w, b) = box_on_ground(Filter::DEFAULT);
    assert!((height_after(&mut w, b, 60) - 0.5).abs() < 0.01);
    let ghost = Filter {
        mask: !1,
        category: 2,
        group: 0,
    };
    let (mut w, b) = box_on_ground(ghost);
    assert!(height_after(&mut w, b, 60) < -4.0);
    // The other way round: the ground's mask leaves the box's category out.
    let mut w = World::default();
    let ground = Filter {
        mask: 1,
        ..Filter::DEFAULT
    };
    w.add_body(&BodyDef::fixed(Shape::rect(20.0, 1.0), vec2(0.0, -0.5)).with_filter(ground))
        .unwrap();
    let b = w
        .add_body(
            &BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)).with_filter(Filter {
                category: 4,
                ..Filter::DEFAULT
            }),
        )
        .unwrap();
    assert!(height_after(&mut w, b, 60) < -4.0);
}

#[test]
fn a_shared_negative_group_never_collides_and_a_positive_one_always_does() {
    // Two boxes dropped onto each other, with a mask that would refuse them: a positive
    // shared group makes them collide (the upper one rests on the lower), a negative one
    // lets it fall through onto the ground.
    for (group, lands_on_top) in [(5, true), (-5, false)] {
        let mut w = World::default();
        w.add_body(&BodyDef::fixed(Shape::rect(20.0, 1.0), vec2(0.0, -0.5)))
            .unwrap();
        let f = Filter {
            category: 2,
            mask: !2,
            group,
        };
        w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 0.5)).with_filter(f))
            .unwrap();
        let upper = w
            .add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.0, 2.0)).with_filter(f))
            .unwrap();
        let y = height_after(&mut w, upper, 120);
        let expected = if lands_on_top { 1.5 } else { 0.5 };
        assert!(
            (y - expected).abs() < 0.02,
            "group {group}: upper box at {y}"
        );
    }
}

#[test]
fn changing_a_resting_bodys_filter_wakes_it_and_ends_its_contacts() {
    let (mut w, b) = box_on_ground(Filter::DEFAULT);
    for _ in 0..240 {
        w.step(DT).unwrap();
    }
    assert!(!w.body(b).unwrap().is_awake(), "rests and sleeps first");
    let ghost = Filter {
        mask: 0,
        ..Filter::DEFAULT
    };
    w.set_filter(b, ghost).unwrap();
    assert!(w.body(b).unwrap().is_awake());
    assert_eq!(w.body(b).unwrap().filter(), ghost);
    w.step(DT).unwrap();
    assert_eq!(
        w.contact_count(),
        0,
        "the contact ended with the new filter"
    );
    assert!(height_after(&mut w, b, 30) < 0.0, "and it falls");
    // A checkpoint keeps the filter: the copy steps identically.
    let mut copy = World::import_state(&w.export_state()).unwrap();
    assert_eq!(copy.body(b).unwrap().filter(), ghost);
    for _ in 0..30 {
        w.step(DT).unwrap();
        copy.step(DT).unwrap();
        assert_eq!(w.state_hash(), copy.state_hash());
    }
}

#[cfg(feature = "scene")]
#[test]
fn scene_files_take_filters_and_refuse_bad_bits_by_name() {
    use tiltbox::scene::Scene;
    let scene = |filter: &str| {
        format!(
            r#"
[[body]]
name = "ground"
static = true
shape = {{ type = "rect", width = 20, height = 1 }}
position = [0, -0.5]
[[body]]
name = "ghost"
shape = {{ type = "rect", width = 1, height = 1 }}
position = [0, 0.5]
density = 1
filter = {filter}
"#
        )
    };
    let s = Scene::from_toml_str(&scene(
        r#"{ category = 2, mask = "0xFFFF_FFFF_FFFF_FFFC", group = -1 }"#,
    ))
    .unwrap();
    let f = s.bodies[1].def.filter;
    assert_eq!((f.category, f.mask, f.group), (2, !3, -1));
    assert_eq!(s.bodies[0].def.filter, Filter::DEFAULT);
    let (mut w, ids) = s.build_world().unwrap();
    assert!(
        height_after(&mut w, ids[1], 60) < -4.0,
        "mask leaves the ground out"
    );
    let all = Scene::from_toml_str(&scene(r#"{ mask = "all" }"#)).unwrap();
    assert_eq!(all.bodies[1].def.filter, Filter::DEFAULT);
    for (bad, field) in [
        (r#"{ mask = -3 }"#, "filter.mask = -3"),
        (
            r#"{ category = "twelve" }"#,
            r#"filter.category = "twelve""#,
        ),
    ] {
        let message = Scene::from_toml_str(&scene(bad)).unwrap_err().to_string();
        assert!(
            message.contains("body \"ghost\"") && message.contains(field),
            "{message}"
        );
    }
}
