//! Ragdolls as Box2D's `human.c` lays them out: the bones' mass against the capsules' and
//! feet's areas, a ragdoll dropped on the ground comes to rest within its limits with its
//! joints closed, all-or-nothing adding, and `[[ragdoll]]` in scene files.

#[cfg(feature = "scene")]
mod common;

use tiltbox::physics::ragdoll::{add_ragdoll, ragdoll, RagdollDef};
use tiltbox::physics::{vec2, BodyDef, JointKind, Real, Shape, World};

const PI: Real = std::f64::consts::PI as Real;

fn def(scale: Real) -> RagdollDef {
    RagdollDef {
        position: vec2(0.0, 0.0),
        scale,
        friction_torque: 0.05,
        hertz: 0.0,
        damping_ratio: 0.5,
        group: -1,
    }
}

/// human.c's capsules (half the distance between the ends, radius; m at scale 1) and its foot
/// grown by its 1.5 cm rounding: area 4 l r + pi r^2 each, the foot's by the shoelace formula.
fn human_area() -> Real {
    let capsules = [
        (0.02, 0.095),
        (0.135, 0.09),
        (0.0385, 0.075),
        (0.125, 0.06),
        (0.14, 0.045),
        (0.125, 0.06),
        (0.14, 0.045),
        (0.125, 0.035),
        (0.125, 0.03),
        (0.125, 0.035),
        (0.125, 0.03),
    ];
    let bones: Real = capsules
        .iter()
        .map(|&(l, r)| 4.0 * l * r + PI * r * r)
        .sum();
    let foot = [
        (-0.045, -0.2),
        (0.125, -0.2),
        (0.125, -0.145),
        (-0.045, -0.125),
    ];
    let shoelace: Real = (0..4)
        .map(|i| {
            let (a, b) = (foot[i], foot[(i + 1) % 4]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum();
    bones + 2.0 * 0.5 * shoelace
}

#[test]
fn a_ragdoll_weighs_its_capsules_and_feet_and_scales_by_area() {
    let bones = ragdoll(&def(1.0));
    assert_eq!(bones.len(), 11);
    assert_eq!(bones.iter().filter(|b| b.joint.is_some()).count(), 10);
    let feet: Vec<_> = bones.iter().filter(|b| !b.def.parts.is_empty()).collect();
    assert_eq!(feet.len(), 2, "the lower legs have a foot each");
    let mut w = World::default();
    let ids = add_ragdoll(&mut w, &def(1.0)).unwrap();
    let mass: Real = ids.iter().map(|&id| w.body(id).unwrap().mass()).sum();
    assert!(
        (mass - human_area()).abs() < 1e-4,
        "{mass} vs {}",
        human_area()
    );
    assert_eq!(w.joint_count(), 10);
    let small = add_ragdoll(
        &mut w,
        &RagdollDef {
            position: vec2(5.0, 0.0),
            ..def(0.5)
        },
    )
    .unwrap();
    let half: Real = small.iter().map(|&id| w.body(id).unwrap().mass()).sum();
    assert!(
        (half - 0.25 * mass).abs() < 1e-5,
        "{half} vs a quarter of {mass}"
    );
}

#[test]
fn a_dropped_ragdoll_comes_to_rest_within_its_limits_with_its_joints_closed() {
    // Dropped 1 m onto the ground, 4 s: at rest (every bone under 1 cm/s), every hinge within
    // its limits give or take 0.02 rad (one ragdoll's own weight bends a limit by under 0.01
    // rad), every joint's anchors within 5 mm (one slop), no bone below the ground.
    let mut w = World::default();
    w.add_body(&BodyDef::fixed(Shape::rect(20.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    let ids = add_ragdoll(
        &mut w,
        &RagdollDef {
            position: vec2(0.0, 1.0),
            ..def(1.0)
        },
    )
    .unwrap();
    for _ in 0..240 {
        w.step(1.0 / 60.0).unwrap();
    }
    for &id in &ids {
        let b = w.body(id).unwrap();
        assert!(
            b.linear_velocity().length() < 0.01,
            "{:?}",
            b.linear_velocity()
        );
        assert!(b.position().y > 0.0);
    }
    for j in w.joints() {
        let d = j.def();
        let JointKind::Revolute(r) = &d.kind else {
            panic!("hinges only")
        };
        let limit = r.limit.expect("every hinge is limited");
        let angle = w.body(d.body_b).unwrap().angle()
            - w.body(d.body_a.unwrap()).unwrap().angle()
            - r.reference_angle.unwrap();
        assert!(
            angle >= limit.lower - 0.02 && angle <= limit.upper + 0.02,
            "{angle} outside [{}, {}]",
            limit.lower,
            limit.upper
        );
        let pa = w
            .body(d.body_a.unwrap())
            .unwrap()
            .transform()
            .apply(d.anchor_a);
        let pb = w.body(d.body_b).unwrap().transform().apply(d.anchor_b);
        assert!((pa - pb).length() < 0.005, "{}", (pa - pb).length());
    }
}

#[test]
fn a_ragdoll_that_cannot_be_added_adds_nothing() {
    let mut w = World::default();
    let bad = RagdollDef {
        position: vec2(Real::NAN, 0.0),
        ..def(1.0)
    };
    assert!(add_ragdoll(&mut w, &bad).is_err());
    assert_eq!((w.body_count(), w.joint_count()), (0, 0));
}

#[cfg(feature = "scene")]
#[test]
fn ragdoll_tables_in_scene_files_build_named_bones_and_refuse_bad_values() {
    use tiltbox::scene::Scene;
    let text = "[[ragdoll]]\nname = \"bob\"\nposition = [0, 0]\n\n[[ragdoll]]\nposition = [2, 0]\nscale = 0.5\n";
    let scene = Scene::from_toml_str(text).unwrap();
    assert_eq!(scene.bodies.len(), 22);
    assert_eq!(scene.joints.len(), 20);
    assert_eq!(scene.bodies[0].name, "bob.hip");
    assert_eq!(scene.bodies[11].name, "ragdoll 1.hip");
    // Each ragdoll its own group, so two never share one.
    assert_eq!(scene.bodies[0].def.filter.group, -1);
    assert_eq!(scene.bodies[11].def.filter.group, -2);
    let (world, _) = scene.build_world().unwrap();
    assert_eq!(world.joint_count(), 20);
    for (bad, field) in [
        ("scale = 0", "scale"),
        ("friction_torque = -1", "friction_torque"),
        ("hertz = nan", "hertz"),
    ] {
        let text = format!("[[ragdoll]]\nposition = [0, 0]\n{bad}\n");
        let e = Scene::from_toml_str(&text).unwrap_err().to_string();
        assert!(e.contains("[[ragdoll]] #0") && e.contains(field), "{e}");
    }
}

#[cfg(feature = "scene")]
#[test]
fn the_ragdoll_in_docs_scenes_md_is_as_tall_and_heavy_as_it_says() {
    // "1.59 m tall at scale 1 (density 1: 0.39 kg)", and the example's soles at y = 0.
    let doc = common::read_repo_file("docs/scenes.md");
    assert!(doc.contains("1.59 m tall at scale 1 (density 1: 0.39 kg)"));
    let example = common::scene::docs_example("### `[[ragdoll]]`");
    let scene = tiltbox::scene::Scene::from_toml_str(&example).unwrap();
    let (w, ids) = scene.build_world().unwrap();
    let mass: Real = ids.iter().map(|&id| w.body(id).unwrap().mass()).sum();
    assert!((mass - 0.39).abs() < 0.005, "{mass}");
    let head = w.body(ids[2]).unwrap();
    let Shape::Capsule {
        half_length,
        radius,
    } = *head.shape()
    else {
        panic!("the head is a capsule")
    };
    let top = head.position().y + half_length + radius;
    assert!((top - 1.59).abs() < 0.005, "{top}");
}

/// Three ragdolls dropped in a heap, checkpointed as they land (joints and contacts both in
/// the constraint graph, their colours part of the solver's history) and after they fell
/// asleep, resume bit-identically for 2 s each.
#[test]
fn a_checkpointed_heap_of_ragdolls_resumes_bit_identically() {
    let mut w = World::new(Default::default(), vec2(0.0, -10.0)).unwrap();
    w.add_body(&BodyDef::fixed(Shape::rect(20.0, 1.0), vec2(0.0, -0.5)))
        .unwrap();
    for k in 0..3 {
        let at = vec2(0.2 * k as Real, 1.2 + 0.5 * k as Real);
        let d = RagdollDef {
            position: at,
            group: -(k + 1),
            ..def(1.0)
        };
        add_ragdoll(&mut w, &d).unwrap();
    }
    for checkpoint in [40, 400] {
        while w.step_count() < checkpoint {
            w.step(1.0 / 60.0).unwrap();
        }
        assert!(w.contact_count() > 10 && w.joint_count() == 30);
        let mut copy = World::import_state(&w.export_state()).unwrap();
        let mut a = w.clone();
        for frame in 0..120 {
            a.step(1.0 / 60.0).unwrap();
            copy.step(1.0 / 60.0).unwrap();
            assert_eq!(
                a.state_hash(),
                copy.state_hash(),
                "step {checkpoint} + {frame}"
            );
        }
    }
}
