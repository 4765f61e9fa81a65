//! `…/build` and `…/remove_joints`: bodies of several shapes and joints added over the wire,
//! all or nothing, through the daemon's own decoding and tick-boundary application; joints in
//! the `…/scene?joints` reply and in events (built, removed, broken, and after a reset).
#![cfg(feature = "net")]
#![allow(clippy::unnecessary_cast)] // Real <-> f32 casts matter with the `f64` feature.

mod common;

use tiltbox::physics::{Real, Vec2};
use tiltbox::protocol::*;
use tiltbox::service::{parse_command, Incoming, SceneSource, ServerConfig, Simulation};

fn bricks() -> (ServerConfig, Simulation) {
    let config = ServerConfig::default();
    let sim = Simulation::new(&config, SceneSource::Embedded).unwrap();
    (config, sim)
}

/// Send a message on `key` as the tick thread applies it; the event it made.
fn send<M: Message>(sim: &mut Simulation, config: &ServerConfig, key: CommandKey, m: &M) -> Event {
    let payload = encode(m).unwrap();
    let command = parse_command(key, &payload, &config.limits);
    sim.apply(Incoming { key, command }).expect("an event")
}

/// The reason a build is refused (panics if it is not).
fn refused(sim: &mut Simulation, config: &ServerConfig, b: &Build) -> String {
    match send(sim, config, CommandKey::Build, b).kind {
        EventKind::Rejected { reason, .. } => reason,
        other => panic!("expected a refusal, got {other:?}"),
    }
}

fn v(x: f32, y: f32) -> Vector {
    Vector::new(x, y)
}

fn body(motion: Motion, at: Vector, parts: Vec<PartSpec>) -> BuildBody {
    BuildBody::new(motion, at, parts)
}

fn rect(w: f32, h: f32, offset: Vector) -> PartSpec {
    PartSpec::at(
        ShapeSpec::Rect {
            width: w,
            height: h,
        },
        offset,
    )
}

fn disc(r: f32) -> PartSpec {
    PartSpec::at(ShapeSpec::Circle { radius: r }, v(0.0, 0.0))
}

fn hinge(a: JointEnd, b: JointEnd, anchor_a: Vector, anchor_b: Vector) -> JointSpec {
    JointSpec::hinge(a, b, anchor_a, anchor_b)
}

/// A pendulum: a static pin at (0, 5) and a 0.2 m disc 1.5 m to its right on a hinge.
fn pendulum() -> Build {
    Build {
        bodies: vec![
            body(
                Motion::Static,
                v(0.0, 5.0),
                vec![rect(0.2, 0.2, v(0.0, 0.0))],
            ),
            body(Motion::Dynamic, v(1.5, 5.0), vec![disc(0.2)]),
        ],
        joints: vec![hinge(
            JointEnd::New(0),
            JointEnd::New(1),
            v(0.0, 0.0),
            v(-1.5, 0.0),
        )],
    }
}

fn position(sim: &Simulation, r: BodyRef) -> Vec2 {
    let id = sim.world().live_id(r.index, r.generation).expect("live");
    sim.world().body(id).unwrap().position()
}

#[test]
fn a_built_pendulum_swings_on_its_hinge_and_is_listed_with_its_joint() {
    let (config, mut sim) = bricks();
    let (bodies_before, joints_before) = (sim.world().body_count(), sim.world().joint_count());
    let ev = send(&mut sim, &config, CommandKey::Build, &pendulum());
    let EventKind::Built { bodies, joints } = ev.kind else {
        panic!("expected Built, got {ev:?}");
    };
    assert_eq!((bodies.len(), joints.len()), (2, 1));
    assert_eq!(sim.world().body_count(), bodies_before + 2);
    assert_eq!(sim.world().joint_count(), joints_before + 1);
    let (pin, bob) = (bodies[0].id, bodies[1].id);
    let j = &joints[0].joint;
    assert_eq!((j.a, j.b), (JointEnd::Live(pin), JointEnd::Live(bob)));
    // The reference angle left out is filled in (0: both unturned).
    assert!(matches!(
        j.kind,
        JointKindSpec::Revolute {
            reference_angle: Some(a),
            ..
        } if a == 0.0
    ));
    // Released level, the bob swings down: a quarter period of a 1.5 m pendulum is about
    // 0.6 s, so by 0.5 s it is well below the pin, and it stays 1.5 m from it. The bound,
    // 5 mm, is the joint drift the stiff suite allows a hinge under a swinging load (its
    // heavy_rope swing bound is 2 % of a 0.7 m link, 14 mm).
    let mut lowest: Real = 5.0;
    for _ in 0..30 {
        sim.step().unwrap();
        let p = position(&sim, bob);
        let r = (p - Vec2::new(0.0, 5.0)).length();
        assert!((r - 1.5).abs() < 5e-3, "bob {r} m from the pin");
        lowest = lowest.min(p.y);
    }
    assert!(
        lowest < 4.0,
        "the bob did not swing down (lowest y {lowest})"
    );
    let listed = sim.scene_with_joints();
    assert_eq!(listed.scene.bodies.len(), bodies_before + 2);
    assert!(listed.joints.iter().any(|i| i.id == joints[0].id));
}

/// `Motion::Sleeping` (appended variant 3) builds a body asleep: it hangs where it is put
/// until a falling disc reaches it, and a moving one is refused naming the motion.
#[test]
fn a_body_built_sleeping_hangs_until_something_reaches_it() {
    let (config, mut sim) = bricks();
    let hanging = body(
        Motion::Sleeping,
        v(50.0, 20.0),
        vec![rect(1.0, 1.0, v(0.0, 0.0))],
    );
    let build = Build {
        // The disc's bottom is 2 m above the box: it arrives after about 0.64 s (38 steps).
        bodies: vec![
            hanging.clone(),
            body(Motion::Dynamic, v(50.0, 22.7), vec![disc(0.2)]),
        ],
        joints: Vec::new(),
    };
    let EventKind::Built { bodies, .. } = send(&mut sim, &config, CommandKey::Build, &build).kind
    else {
        panic!("expected Built");
    };
    let (boxed, disc) = (bodies[0].id, bodies[1].id);
    // docs/protocol.md: version, two bodies, no name, motion 3.
    assert_eq!(encode(&build).unwrap()[..4], [1, 2, 0, 3]);
    for _ in 0..30 {
        sim.step().unwrap();
    }
    assert_eq!(position(&sim, boxed), Vec2::new(50.0, 20.0));
    assert!(position(&sim, disc).y < 22.0, "the disc falls");
    for _ in 0..60 {
        sim.step().unwrap();
    }
    // Reached at 0.64 s, the box falls with the disc for most of the next 0.86 s.
    assert!(
        position(&sim, boxed).y < 19.5,
        "{}",
        position(&sim, boxed).y
    );
    let moving = Build {
        bodies: vec![BuildBody {
            velocity: v(1.0, 0.0),
            ..hanging
        }],
        joints: Vec::new(),
    };
    let reason = refused(&mut sim, &config, &moving);
    assert!(
        reason.contains("motion = Sleeping with velocity = [1, 0], angular_velocity = 0"),
        "{reason}"
    );
}

#[test]
fn a_body_of_several_shapes_has_the_mass_of_its_parts_and_is_described_as_a_compound() {
    let (config, mut sim) = bricks();
    // An L: a 1 x 0.25 bar and a 0.25 x 0.75 post standing on its right end.
    let l = body(
        Motion::Dynamic,
        v(0.0, 3.0),
        vec![
            rect(1.0, 0.25, v(0.0, 0.0)),
            PartSpec {
                density: 2.0,
                ..rect(0.25, 0.75, v(0.375, 0.5))
            },
        ],
    );
    let ev = send(
        &mut sim,
        &config,
        CommandKey::Build,
        &Build {
            bodies: vec![l],
            joints: Vec::new(),
        },
    );
    let EventKind::Built { bodies, .. } = ev.kind else {
        panic!("expected Built, got {ev:?}");
    };
    let info = &bodies[0];
    // Mass: 1 x 0.25 x 1 + 0.25 x 0.75 x 2 = 0.625 kg.
    assert!((info.mass - 0.625).abs() < 1e-5, "mass {}", info.mass);
    // The origin is the first part's centre, as sent.
    assert_eq!((info.position.x, info.position.y), (0.0, 3.0));
    let ShapeSpec::Compound { parts } = &info.shape else {
        panic!("expected a compound, got {:?}", info.shape);
    };
    assert_eq!(parts.len(), 2);
    assert_eq!((parts[1].offset.x, parts[1].offset.y), (0.375, 0.5));
    // Its centre of mass: (0.25 x 0 + 0.375 x 0.375, 0.25 x 0 + 0.375 x 0.5) / 0.625.
    let id = sim
        .world()
        .live_id(info.id.index, info.id.generation)
        .unwrap();
    let c = sim.world().body(id).unwrap().center_of_mass();
    assert!(
        (c.x - 0.225).abs() < 1e-5 && (c.y - 3.3).abs() < 1e-5,
        "{c:?}"
    );
}

#[test]
fn a_build_with_any_fault_is_refused_whole_naming_it() {
    let (config, mut sim) = bricks();
    let (n, j) = (sim.world().body_count(), sim.world().joint_count());
    let cases: Vec<(Build, &str)> = vec![
        (
            Build {
                joints: vec![hinge(
                    JointEnd::New(0),
                    JointEnd::New(5),
                    v(0.0, 0.0),
                    v(0.0, 0.0),
                )],
                ..pendulum()
            },
            "joints[0]: b = new body 5: the build has 2 bodies",
        ),
        (
            Build {
                joints: vec![hinge(
                    JointEnd::New(1),
                    JointEnd::World,
                    v(0.0, 0.0),
                    v(0.0, 0.0),
                )],
                ..pendulum()
            },
            "joints[0]: b = world",
        ),
        (
            Build {
                joints: vec![hinge(
                    JointEnd::New(1),
                    JointEnd::New(1),
                    v(0.0, 0.0),
                    v(0.0, 0.0),
                )],
                ..pendulum()
            },
            "joints[0]: a and b are the same body",
        ),
        (
            Build {
                joints: vec![hinge(
                    JointEnd::World,
                    JointEnd::New(0),
                    v(0.0, 0.0),
                    v(0.0, 0.0),
                )],
                ..pendulum()
            },
            "joints[0]: neither a nor b is a dynamic body",
        ),
        (
            Build {
                joints: vec![hinge(
                    JointEnd::Live(BodyRef {
                        index: 999,
                        generation: 0,
                    }),
                    JointEnd::New(1),
                    v(0.0, 0.0),
                    v(0.0, 0.0),
                )],
                ..pendulum()
            },
            "joints[0]: a: no body with id 999v0",
        ),
        (
            Build {
                joints: vec![JointSpec {
                    kind: JointKindSpec::Revolute {
                        reference_angle: None,
                        limit: Some(LimitSpec {
                            lower: 1.0,
                            upper: -1.0,
                        }),
                        motor: None,
                        spring: None,
                    },
                    ..pendulum().joints[0].clone()
                }],
                ..pendulum()
            },
            "joints[0]: limit",
        ),
        (
            Build {
                joints: vec![JointSpec {
                    anchor_b: v(f32::NAN, 0.0),
                    ..pendulum().joints[0].clone()
                }],
                ..pendulum()
            },
            "joints[0]: anchor_b.x must be a finite number, got NaN",
        ),
        (
            Build {
                bodies: vec![body(Motion::Dynamic, v(0.0, 3.0), Vec::new())],
                joints: Vec::new(),
            },
            "bodies[0]: parts is empty",
        ),
        (
            Build {
                bodies: vec![body(
                    Motion::Dynamic,
                    v(0.0, 3.0),
                    vec![PartSpec {
                        density: -1.0,
                        ..disc(0.2)
                    }],
                )],
                joints: Vec::new(),
            },
            "bodies[0]: parts[0]: density = -1 is out of range",
        ),
        (
            Build {
                bodies: vec![body(
                    Motion::Dynamic,
                    v(0.0, 3.0),
                    vec![disc(0.2), rect(0.5, 0.5, v(f32::INFINITY, 0.0))],
                )],
                joints: Vec::new(),
            },
            "bodies[0]: parts[1]: offset.x must be a finite number, got inf",
        ),
        (
            Build {
                bodies: Vec::new(),
                joints: Vec::new(),
            },
            "bodies and joints are both empty",
        ),
    ];
    for (b, want) in cases {
        let reason = refused(&mut sim, &config, &b);
        assert!(reason.contains(want), "{want:?} not in {reason:?}");
        assert_eq!(sim.world().body_count(), n, "a refused build added bodies");
        assert_eq!(sim.world().joint_count(), j, "a refused build added joints");
    }
}

#[test]
fn compounds_nest_one_level_only_and_hold_at_most_sixteen_parts() {
    let inner = ShapeSpec::Compound {
        parts: vec![PartShape {
            shape: ShapeSpec::Circle { radius: 0.2 },
            offset: v(0.0, 0.0),
            angle: 0.0,
        }],
    };
    let nested = ShapeSpec::Compound {
        parts: vec![PartShape {
            shape: inner,
            offset: v(0.0, 0.0),
            angle: 0.0,
        }],
    };
    let spawn = Spawn {
        bodies: vec![SpawnBody::at(nested, v(0.0, 3.0))],
    };
    let err = decode::<Spawn>(&encode(&spawn).unwrap()).unwrap_err();
    assert!(
        err.to_string()
            .contains("a compound's part is itself a compound"),
        "{err}"
    );
    let many = Build {
        bodies: vec![body(Motion::Dynamic, v(0.0, 3.0), vec![disc(0.1); 17])],
        joints: Vec::new(),
    };
    let err = decode::<Build>(&encode(&many).unwrap()).unwrap_err();
    assert!(err.to_string().contains("more than 16 parts"), "{err}");
    // A flat compound is a shape for descriptions, spawned on …/build only.
    let (config, mut sim) = bricks();
    let flat = ShapeSpec::Compound {
        parts: vec![PartShape {
            shape: ShapeSpec::Circle { radius: 0.2 },
            offset: v(0.0, 0.0),
            angle: 0.0,
        }],
    };
    let ev = send(
        &mut sim,
        &config,
        CommandKey::Spawn,
        &Spawn {
            bodies: vec![SpawnBody::at(flat, v(0.0, 3.0))],
        },
    );
    let EventKind::Rejected { reason, .. } = ev.kind else {
        panic!("{ev:?}");
    };
    assert!(reason.contains("is built on …/build"), "{reason}");
}

#[test]
fn joints_are_removed_by_id_and_a_drag_hands_joint_is_not_a_clients_to_remove() {
    let (config, mut sim) = bricks();
    let EventKind::Built { bodies, joints } =
        send(&mut sim, &config, CommandKey::Build, &pendulum()).kind
    else {
        panic!()
    };
    let bob = bodies[1].id;
    let hand = Drag::Grab {
        hand: 7,
        id: bob,
        point: v(1.5, 5.0),
    };
    assert!(
        send_quiet(&mut sim, &config, CommandKey::Drag, &hand).is_none(),
        "the grab is accepted"
    );
    let hand_joint = sim
        .world()
        .joints()
        .map(|j| j.id())
        .find(|id| id.index() != joints[0].id.index)
        .expect("the hand's joint");
    let hand_ref = JointRef {
        index: hand_joint.index(),
        generation: hand_joint.generation(),
    };
    let ev = send(
        &mut sim,
        &config,
        CommandKey::RemoveJoints,
        &RemoveJoints {
            ids: vec![joints[0].id, hand_ref],
        },
    );
    let EventKind::Rejected { reason, .. } = ev.kind else {
        panic!("{ev:?}")
    };
    assert!(reason.starts_with("ids[1]: no joint"), "{reason}");
    assert_eq!(sim.world().joint_count(), 2, "nothing removed");
    let ev = send(
        &mut sim,
        &config,
        CommandKey::RemoveJoints,
        &RemoveJoints {
            ids: vec![joints[0].id],
        },
    );
    assert_eq!(
        ev.kind,
        EventKind::JointsRemoved {
            ids: vec![joints[0].id]
        }
    );
    assert_eq!(sim.world().joint_count(), 1);
    assert!(
        sim.scene_with_joints().joints.is_empty(),
        "hands are never listed"
    );
}

/// Send as the tick thread applies it; the event it made, if any.
fn send_quiet<M: Message>(
    sim: &mut Simulation,
    config: &ServerConfig,
    key: CommandKey,
    m: &M,
) -> Option<EventKind> {
    let payload = encode(m).unwrap();
    let command = parse_command(key, &payload, &config.limits);
    sim.apply(Incoming { key, command }).map(|e| e.kind)
}

#[test]
fn a_joint_weaker_than_its_load_breaks_and_is_reported_with_the_force() {
    let (config, mut sim) = bricks();
    // A 1 kg box (1 x 1 at density 1) hangs from a static pin by a hinge that holds 5 N:
    // its weight, 9.81 N, breaks it in the first step.
    let b = Build {
        bodies: vec![
            body(
                Motion::Static,
                v(0.0, 5.5),
                vec![rect(0.2, 0.2, v(0.0, 0.0))],
            ),
            body(
                Motion::Dynamic,
                v(0.0, 4.5),
                vec![rect(1.0, 1.0, v(0.0, 0.0))],
            ),
        ],
        joints: vec![JointSpec {
            break_force: Some(5.0),
            ..hinge(
                JointEnd::New(0),
                JointEnd::New(1),
                v(0.0, -0.5),
                v(0.0, 0.5),
            )
        }],
    };
    let EventKind::Built { joints, .. } = send(&mut sim, &config, CommandKey::Build, &b).kind
    else {
        panic!()
    };
    sim.step().unwrap();
    let events = sim.physics_events();
    let broken = events
        .iter()
        .find_map(|e| match &e.kind {
            EventKind::JointsBroken { joints } => Some(joints.clone()),
            _ => None,
        })
        .expect("a JointsBroken event");
    assert_eq!(broken.len(), 1);
    assert_eq!(broken[0].id, joints[0].id);
    // The force that broke it: above the 5 N break force, at most the weight (9.81 N) and
    // the pull that stops the box's first step of fall.
    assert!(
        broken[0].force > 5.0 && broken[0].force < 2.0 * 9.81,
        "force {}",
        broken[0].force
    );
    assert_eq!(sim.world().joint_count(), 0);
}

#[test]
fn a_reset_to_a_scene_with_joints_is_followed_by_its_joints() {
    let config = ServerConfig::default();
    let path = common::repo_path("config/scenes/rope.toml");
    let mut sim = Simulation::new(&config, SceneSource::File(path)).unwrap();
    let joints = sim.scene_with_joints().joints;
    assert!(joints.len() >= 12, "the rope's links");
    sim.step().unwrap();
    assert!(
        sim.physics_events().is_empty(),
        "nothing to announce before a reset"
    );
    let ev = send(&mut sim, &config, CommandKey::Reset, &Reset);
    assert!(matches!(ev.kind, EventKind::Reset { .. }));
    sim.step().unwrap();
    let events = sim.physics_events();
    let built = &events[0];
    assert_eq!(built.frame, ev.frame, "in the reset's frame");
    let EventKind::Built {
        bodies,
        joints: after,
    } = &built.kind
    else {
        panic!("{built:?}")
    };
    assert!(bodies.is_empty());
    assert_eq!(after.len(), joints.len());
}

#[test]
fn a_checkpoint_keeps_built_compounds_and_joints_and_restores_to_the_same_steps() {
    use tiltbox::service::checkpoint;
    let (config, mut sim) = bricks();
    let l = body(
        Motion::Dynamic,
        v(-2.0, 4.0),
        vec![
            rect(1.0, 0.25, v(0.0, 0.0)),
            rect(0.25, 0.75, v(0.375, 0.5)),
        ],
    );
    let mut b = pendulum();
    b.bodies.push(l);
    b.joints.push(hinge(
        JointEnd::World,
        JointEnd::New(2),
        v(-2.0, 4.5),
        v(0.0, 0.5),
    ));
    let ev = send(&mut sim, &config, CommandKey::Build, &b);
    assert!(matches!(ev.kind, EventKind::Built { .. }), "{ev:?}");
    for _ in 0..10 {
        sim.step().unwrap();
    }
    let bytes = checkpoint::encode(&sim.export_state()).unwrap();
    let state = checkpoint::decode(&bytes).unwrap();
    let mut back = Simulation::restore(&config, SceneSource::Embedded, state).unwrap();
    assert_eq!(back.scene_with_joints(), sim.scene_with_joints());
    for _ in 0..60 {
        sim.step().unwrap();
        back.step().unwrap();
    }
    assert_eq!(back.world().state_hash(), sim.world().state_hash());
    let listed = back.scene_with_joints();
    assert_eq!(listed.joints.len(), 2);
    assert!(listed
        .scene
        .bodies
        .iter()
        .any(|b| matches!(&b.shape, ShapeSpec::Compound { parts } if parts.len() == 2)));
}
