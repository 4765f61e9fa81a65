//! Hostile input: random bytes, mutated valid payloads and edge-value fields fed to every
//! decoder and through the daemon's whole command path (intake parse -> Simulation::apply ->
//! step) of an in-process Simulation. Nothing may panic, the World may never hold a NaN or an
//! infinity, and nothing may grow without bound. Deterministic (fixed seeds), a few seconds.
#![cfg(feature = "net")]

mod common;

use common::rng::Rng;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::sync_channel;
use std::sync::Arc;
use tiltbox::protocol::*;
use tiltbox::service::{
    parse_command, Incoming, Intake, Limits, SceneSource, ServerConfig, Simulation,
};

/// Floats that break careless code.
const EDGE: [f32; 16] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    1e-38,
    1e-45,
    -1e-45,
    3.4e38,
    -3.4e38,
    1e30,
    999.9,
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    1e-7,
];

fn edgy(rng: &mut Rng) -> f32 {
    if rng.next() % 3 == 0 {
        rng.pick(&EDGE)
    } else {
        (rng.next() % 2000) as f32 / 100.0 - 10.0
    }
}

/// Mostly within `lo..hi`, sometimes an edge value: most spawns pass, so the World fills up.
fn field(rng: &mut Rng, lo: f32, hi: f32) -> f32 {
    if rng.next() % 40 == 0 {
        rng.pick(&EDGE)
    } else {
        lo + (hi - lo) * (rng.next() % 10_000) as f32 / 10_000.0
    }
}

/// A convex polygon of `n` vertices on a circle of radius `r` around (`ox`, `oy`) (off the
/// spawn position, so the daemon moves the body to the centroid).
fn ring(n: usize, r: f32, ox: f32, oy: f32, a0: f32) -> Vec<Vector> {
    (0..n)
        .map(|k| {
            let a = a0 + k as f32 * std::f32::consts::TAU / n.max(1) as f32;
            Vector::new(ox + r * a.cos(), oy + r * a.sin())
        })
        .collect()
}

/// Any of the four shape kinds, mostly valid, sometimes broken: sizes at edge values, a
/// capsule no longer than its ends, polygons with too few or too many vertices, clockwise,
/// dented, with a repeated vertex or a non-finite coordinate.
fn shape(rng: &mut Rng) -> ShapeSpec {
    match rng.next() % 4 {
        0 => ShapeSpec::Rect {
            width: field(rng, 0.01, 3.0),
            height: field(rng, 0.01, 3.0),
        },
        1 => ShapeSpec::Circle {
            radius: field(rng, 0.005, 1.5),
        },
        // length from 0.05 to 3 m, radius up to 0.6 m: about one in five is too short
        2 => ShapeSpec::Capsule {
            length: field(rng, 0.05, 3.0),
            radius: field(rng, 0.005, 0.6),
        },
        _ => {
            let n = rng.pick(&[3usize, 3, 4, 5, 6, 7, 8, 8, 0, 2, 9, 40]);
            let (ox, oy) = (field(rng, -2.0, 2.0), field(rng, -2.0, 2.0));
            let mut vertices = ring(n, field(rng, 0.02, 1.5), ox, oy, field(rng, 0.0, 6.3));
            if n >= 3 {
                match rng.next() % 10 {
                    0 => vertices.reverse(),                // clockwise
                    1 => vertices[1] = Vector::new(ox, oy), // a dent at the centre
                    2 => vertices[2] = vertices[1],         // repeated
                    3 => vertices[0].x = rng.pick(&EDGE),
                    _ => {}
                }
            }
            ShapeSpec::Polygon { vertices }
        }
    }
}

fn body(rng: &mut Rng) -> SpawnBody {
    let name_len = rng.pick(&[0usize, 3, 40, 0, 3, 40, 65, 5000]);
    SpawnBody {
        name: if rng.next() % 2 == 0 {
            None
        } else {
            Some("n".repeat(name_len))
        },
        shape: shape(rng),
        position: Vector::new(field(rng, -8.0, 8.0), field(rng, -1.0, 30.0)),
        angle: field(rng, -7.0, 7.0),
        velocity: Vector::new(field(rng, -70.0, 70.0), field(rng, -70.0, 70.0)),
        angular_velocity: field(rng, -100.0, 100.0),
        density: field(rng, 0.01, 1000.0),
        friction: field(rng, 0.0, 3.0),
        restitution: field(rng, 0.0, 1.0),
        colour: Colour::default(),
    }
}

/// A well-formed message for `key`, with edge values in its fields.
fn valid(rng: &mut Rng, key: CommandKey) -> Vec<u8> {
    match key {
        CommandKey::Gravity => encode(&SetGravity {
            x: edgy(rng),
            y: edgy(rng),
        }),
        CommandKey::Tilt => match rng.next() % 3 {
            0 => encode(&Tilt::Orientation(Orientation::Portrait)),
            _ => encode(&Tilt::Accelerometer {
                x: edgy(rng),
                y: edgy(rng),
                z: edgy(rng),
            }),
        },
        CommandKey::Spawn => {
            let n = rng.pick(&[0usize, 1, 1, 2, 5, 70]);
            encode(&Spawn {
                bodies: (0..n).map(|_| body(rng)).collect(),
            })
        }
        CommandKey::Remove => {
            let n = rng.pick(&[0usize, 1, 2, 3]);
            encode(&Remove {
                ids: (0..n)
                    .map(|_| BodyRef {
                        index: rng.pick(&[0u32, 1, 5, 40, 41, u32::MAX]),
                        generation: rng.pick(&[0u32, 1, u32::MAX]),
                    })
                    .collect(),
            })
        }
        CommandKey::Reset => encode(&Reset),
        CommandKey::Velocity => encode(&SetVelocity {
            id: BodyRef {
                index: rng.pick(&[0u32, 1, 5, 40, u32::MAX]),
                generation: rng.pick(&[0u32, 1, u32::MAX]),
            },
            velocity: Vector::new(edgy(rng), edgy(rng)),
            angular_velocity: edgy(rng),
        }),
        CommandKey::Drag => {
            let hand = rng.pick(&[0u64, 1, 7, u64::MAX]);
            let at = Vector::new(edgy(rng), edgy(rng));
            encode(&match rng.next() % 3 {
                0 => Drag::Grab {
                    hand,
                    id: BodyRef {
                        index: rng.pick(&[0u32, 1, 5, 40, u32::MAX]),
                        generation: rng.pick(&[0u32, 1, u32::MAX]),
                    },
                    point: at,
                },
                1 => Drag::Move { hand, target: at },
                _ => Drag::Release { hand },
            })
        }
        CommandKey::Build => encode(&build(rng)),
        CommandKey::RemoveJoints => encode(&RemoveJoints {
            ids: (0..rng.pick(&[0usize, 1, 2]))
                .map(|_| JointRef {
                    index: rng.pick(&[0u32, 1, 5, u32::MAX]),
                    generation: rng.pick(&[0u32, 1, u32::MAX]),
                })
                .collect(),
        }),
    }
    .unwrap()
}

/// A build of up to three bodies of up to three parts each and up to three joints, with edge
/// values in its fields and ends that may name nothing.
fn build(rng: &mut Rng) -> Build {
    let motions = [
        Motion::Dynamic,
        Motion::Dynamic,
        Motion::Static,
        Motion::Kinematic,
        Motion::Sleeping,
    ];
    let bodies: Vec<BuildBody> = (0..rng.pick(&[0usize, 1, 2, 3]))
        .map(|_| {
            let b = body(rng);
            let parts = (0..rng.pick(&[0usize, 1, 2, 3]))
                .map(|_| PartSpec {
                    place: PartShape {
                        shape: shape(rng),
                        offset: Vector::new(field(rng, -2.0, 2.0), field(rng, -2.0, 2.0)),
                        angle: field(rng, -7.0, 7.0),
                    },
                    density: field(rng, 0.01, 1000.0),
                    friction: field(rng, 0.0, 3.0),
                    restitution: field(rng, 0.0, 1.0),
                    filter: FilterSpec {
                        category: rng.next(),
                        mask: rng.next(),
                        group: rng.pick(&[0i32, -1, 1, i32::MIN]),
                    },
                    sensor: rng.next() % 4 == 0,
                    contact_events: rng.next() % 2 == 0,
                    hit_events: rng.next() % 2 == 0,
                })
                .collect();
            BuildBody {
                name: b.name,
                motion: rng.pick(&motions),
                position: b.position,
                angle: b.angle,
                velocity: b.velocity,
                angular_velocity: b.angular_velocity,
                colour: b.colour,
                parts,
            }
        })
        .collect();
    let end = |rng: &mut Rng| match rng.next() % 3 {
        0 => JointEnd::World,
        1 => JointEnd::New(rng.pick(&[0u32, 1, 2, 7])),
        _ => JointEnd::Live(BodyRef {
            index: rng.pick(&[0u32, 1, 5, 40]),
            generation: 0,
        }),
    };
    let joints = (0..rng.pick(&[0usize, 1, 2, 3]))
        .map(|_| {
            let (a, b) = (end(rng), end(rng));
            let kind = match rng.next() % 4 {
                0 => JointKindSpec::Revolute {
                    reference_angle: None,
                    limit: Some(LimitSpec {
                        lower: edgy(rng),
                        upper: edgy(rng),
                    }),
                    motor: Some(MotorSpec {
                        speed: edgy(rng),
                        max: edgy(rng),
                    }),
                    spring: None,
                },
                1 => JointKindSpec::Distance {
                    length: Some(edgy(rng)),
                    spring: Some(SpringSpec {
                        hertz: edgy(rng),
                        damping_ratio: edgy(rng),
                    }),
                    limit: None,
                },
                2 => JointKindSpec::Wheel {
                    axis: Vector::new(edgy(rng), edgy(rng)),
                    spring: None,
                    limit: None,
                    motor: None,
                },
                _ => JointKindSpec::Weld {
                    reference_angle: Some(edgy(rng)),
                    linear_hertz: edgy(rng),
                    linear_damping_ratio: edgy(rng),
                    angular_hertz: edgy(rng),
                    angular_damping_ratio: edgy(rng),
                },
            };
            JointSpec {
                a,
                b,
                anchor_a: Vector::new(edgy(rng), edgy(rng)),
                anchor_b: Vector::new(field(rng, -1.0, 1.0), field(rng, -1.0, 1.0)),
                kind,
                collide_connected: rng.next() % 2 == 0,
                break_force: if rng.next() % 2 == 0 {
                    None
                } else {
                    Some(edgy(rng))
                },
                break_torque: None,
            }
        })
        .collect();
    Build { bodies, joints }
}

/// Random bytes, or a valid payload mutated.
fn hostile(rng: &mut Rng, key: CommandKey) -> Vec<u8> {
    if rng.next() % 5 == 0 {
        let n = rng.pick(&[0usize, 1, 2, 5, 17, 64, 300]);
        return (0..n).map(|_| rng.next() as u8).collect();
    }
    let mut p = valid(rng, key);
    for _ in 0..1 + rng.below(3) {
        let n = p.len();
        match rng.next() % 8 {
            0 if n > 0 => {
                let i = rng.below(n);
                p[i] ^= 1 << rng.below(8);
            }
            1 if n > 0 => {
                let i = rng.below(n);
                p[i] = rng.pick(&[0u8, 0x7f, 0x80, 0xff]);
            }
            2 => p.truncate(rng.below(n + 1)),
            3 => p.extend((0..rng.below(16)).map(|_| rng.next() as u8)),
            4 if n > 0 => {
                let i = rng.below(n);
                p.insert(i, rng.next() as u8);
            }
            5 if n >= 4 => {
                let i = rng.below(n - 3);
                p[i..i + 4].copy_from_slice(&rng.pick(&EDGE).to_le_bytes());
            }
            6 if n > 1 => {
                // a huge varint length prefix
                let i = 1 + rng.below(n - 1);
                p.splice(i..i, [0xff, 0xff, 0xff, 0xff, 0x0f]);
            }
            _ if n > 0 => p[0] = rng.pick(&[0u8, 1, 2, 255]), // protocol version byte
            _ => {}
        }
    }
    p
}

fn assert_sane(sim: &Simulation, limits: &Limits, at: usize) {
    let w = sim.world();
    assert!(
        w.body_count() <= limits.max_bodies as usize,
        "{} bodies",
        w.body_count()
    );
    let g = w.gravity();
    assert!(g.x.is_finite() && g.y.is_finite(), "gravity {g:?} at {at}");
    assert!(
        g.length() as f64 <= limits.max_gravity as f64 * 1.0001,
        "gravity {g:?}"
    );
    for b in w.bodies() {
        let v = [
            b.position().x,
            b.position().y,
            b.angle(),
            b.linear_velocity().x,
            b.linear_velocity().y,
            b.angular_velocity(),
        ];
        assert!(
            v.iter().all(|x| x.is_finite()),
            "body {} not finite at command {at}: {v:?}",
            b.id()
        );
    }
}

#[test]
fn every_decoder_survives_random_and_mutated_bytes() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    for i in 0..20_000 {
        let key = CommandKey::ALL[i % CommandKey::ALL.len()];
        let p = hostile(&mut rng, key);
        // command decoders, and the daemon-side messages clients decode
        let _ = decode::<SetGravity>(&p);
        let _ = decode::<Tilt>(&p);
        let _ = decode::<Spawn>(&p);
        let _ = decode::<Remove>(&p);
        let _ = decode::<Reset>(&p);
        let _ = decode_frame(&p);
        let _ = SnapshotDecoder::new().decode(&p);
        let _ = decode::<Event>(&p);
        let _ = decode::<SceneState>(&p);
        let _ = decode::<Stats>(&p);
    }
}

#[test]
fn the_command_path_never_panics_never_holds_nan_and_stays_bounded() {
    let mut config = ServerConfig::default();
    config.limits.max_bodies = 250;
    config.limits.max_spawns_per_second = 1000; // let the storm reach the body limit
    let limits = config.limits.clone();
    let mut sim = Simulation::new(&config, SceneSource::Embedded).unwrap();
    let mut rng = Rng(0xdead_beef_cafe_f00d);
    let (mut accepted, mut rejected) = (0u64, 0u64);
    let mut max_event = 0usize;
    let mut most_bodies = 0usize;
    for i in 0..12_000 {
        // weight towards spawns: they are what can grow
        let key = rng.pick(&[
            CommandKey::Spawn,
            CommandKey::Spawn,
            CommandKey::Spawn,
            CommandKey::Gravity,
            CommandKey::Tilt,
            CommandKey::Remove,
            CommandKey::Reset,
        ]);
        let key = if key == CommandKey::Reset && rng.next() % 200 != 0 {
            CommandKey::Tilt
        } else {
            key
        };
        let p = if rng.next() % 2 == 0 {
            valid(&mut rng, key)
        } else {
            hostile(&mut rng, key)
        };
        let command = parse_command(key, &p, &limits);
        if command.is_ok() {
            accepted += 1;
        }
        if let Some(ev) = sim.apply(Incoming { key, command }) {
            if matches!(ev.kind, EventKind::Rejected { .. }) {
                rejected += 1;
            }
            max_event = max_event.max(encode(&ev).unwrap().len());
        }
        if i % 4 == 0 {
            sim.step().unwrap();
            sim.snapshot_into(&mut Vec::new());
            assert_sane(&sim, &limits, i);
            most_bodies = most_bodies.max(sim.world().body_count());
        }
    }
    assert_sane(&sim, &limits, usize::MAX);
    let _ = encode(&sim.scene_state()).unwrap();
    assert!(accepted > 3000 && rejected > 3000, "{accepted} {rejected}");
    // the storm reached the body limit, and the limit held
    assert!(most_bodies >= 240, "at most {most_bodies} bodies");
    assert_eq!(sim.rejected(), rejected);
    // a rejection echoes the key and a reason, never the payload: events stay small
    assert!(max_event < 400_000, "largest event {max_event} bytes");
}

/// Every field of every shape kind set to every edge value, spawned (with a body origin
/// and angle that are edge values too) through parse -> apply -> step: each is refused or
/// accepted, nothing panics, an accepted body is where its shape says and stays finite.
#[test]
fn every_shape_kind_with_edge_values_in_every_field_is_refused_or_simulated() {
    let mut config = ServerConfig::default();
    config.limits.max_bodies = 5000;
    config.limits.max_spawns_per_second = 1_000_000;
    let limits = config.limits.clone();
    let mut sim = Simulation::new(&config, SceneSource::Embedded).unwrap();
    let base: [ShapeSpec; 5] = [
        ShapeSpec::Rect {
            width: 0.5,
            height: 0.25,
        },
        ShapeSpec::Circle { radius: 0.2 },
        ShapeSpec::Capsule {
            length: 0.8,
            radius: 0.15,
        },
        ShapeSpec::Polygon {
            vertices: ring(5, 0.3, 0.4, -0.2, 0.1),
        },
        // Never spawned (a spawn is dynamic, segments are terrain): always refused.
        ShapeSpec::Segment {
            a: Vector::new(-0.5, 0.0),
            b: Vector::new(0.5, 0.1),
            radius: 0.05,
            prev: None,
            next: Some(Vector::new(1.0, 0.0)),
            one_sided: true,
        },
    ];
    // (shape, which f32 of it to replace): rect 2, circle 1, capsule 2, polygon 10, segment 5
    let fields = |s: &ShapeSpec| match s {
        ShapeSpec::Rect { .. } | ShapeSpec::Capsule { .. } => 2,
        ShapeSpec::Circle { .. } => 1,
        ShapeSpec::Polygon { vertices } => 2 * vertices.len(),
        ShapeSpec::Segment { .. } => 5,
        ShapeSpec::Compound { .. } => 0,
    };
    let set = |s: &mut ShapeSpec, i: usize, v: f32| match s {
        ShapeSpec::Rect { width, height } => *[width, height][i] = v,
        ShapeSpec::Circle { radius } => *radius = v,
        ShapeSpec::Capsule { length, radius } => *[length, radius][i] = v,
        ShapeSpec::Polygon { vertices } => {
            let p = &mut vertices[i / 2];
            *[&mut p.x, &mut p.y][i % 2] = v;
        }
        ShapeSpec::Segment { a, b, radius, .. } => {
            *[&mut a.x, &mut a.y, &mut b.x, &mut b.y, radius][i] = v
        }
        ShapeSpec::Compound { .. } => {}
    };
    let (mut accepted, mut refused, mut spawns) = (0, 0, 0);
    for shape in &base {
        for i in 0..fields(shape) {
            for &v in &EDGE {
                let mut s = shape.clone();
                set(&mut s, i, v);
                let b = SpawnBody {
                    name: None,
                    shape: s,
                    // mostly plain places and angles, now and then an edge one
                    position: Vector::new(
                        [0.0, 2.5, -2.5, 1.0, 999.9][spawns % 5],
                        [3.0, 1.0, 5.0][spawns % 3],
                    ),
                    angle: [0.0, 0.7, -2.0, 1.3, 2.9, 1e4, f32::NAN][spawns % 7],
                    velocity: Vector::default(),
                    angular_velocity: 0.0,
                    density: 1.0,
                    friction: 0.5,
                    restitution: 0.2,
                    colour: Colour::default(),
                };
                let p = encode(&Spawn {
                    bodies: vec![b.clone()],
                })
                .unwrap();
                let command = parse_command(CommandKey::Spawn, &p, &limits);
                let count = sim.world().body_count();
                let ev = sim.apply(Incoming {
                    key: CommandKey::Spawn,
                    command,
                });
                spawns += 1;
                match ev.map(|e| e.kind) {
                    Some(EventKind::Added { bodies }) => {
                        accepted += 1;
                        assert_eq!(sim.world().body_count(), count + 1);
                        let info = &bodies[0];
                        assert!(info.position.x.is_finite() && info.position.y.is_finite());
                        assert!(info.position.x.abs() <= limits.max_coordinate);
                        let ev = Event {
                            frame: 0,
                            kind: EventKind::Added { bodies },
                        };
                        assert_eq!(decode::<Event>(&encode(&ev).unwrap()).unwrap(), ev);
                    }
                    Some(EventKind::Rejected { reason, .. }) => {
                        refused += 1;
                        if std::env::var_os("TILTBOX_SHOW_REFUSALS").is_some() {
                            eprintln!("{reason}");
                        }
                        assert_eq!(sim.world().body_count(), count, "half-applied: {reason}");
                        assert!(reason.starts_with("bodies[0]: "), "{reason}");
                        // a refusal quotes a value or a count, whichever field it names
                        assert!(
                            reason.chars().any(|c| c.is_ascii_digit())
                                || reason.contains("NaN")
                                || reason.contains("inf"),
                            "{reason}"
                        );
                    }
                    other => panic!("{b:?}: {other:?}"),
                }
                sim.step().unwrap();
                sim.snapshot_into(&mut Vec::new());
                assert_sane(&sim, &limits, spawns);
            }
        }
    }
    for _ in 0..120 {
        sim.step().unwrap();
    }
    assert_sane(&sim, &limits, usize::MAX);
    let state = sim.scene_state();
    assert_eq!(
        decode::<SceneState>(&encode(&state).unwrap()).unwrap(),
        state
    );
    eprintln!("{spawns} edge spawns: {accepted} accepted, {refused} refused");
    assert!(accepted > 20 && refused > 100, "{accepted} {refused}");
}

#[test]
fn the_intake_channel_is_bounded_under_a_flood() {
    let (tx, rx) = sync_channel::<Incoming>(16);
    let dropped: Arc<[AtomicU64; CommandKey::ALL.len()]> = Arc::new(Default::default());
    let intake = Intake::new(tx, Limits::default(), dropped.clone());
    let mut rng = Rng(42);
    for i in 0..5_000 {
        let key = CommandKey::ALL[i % CommandKey::ALL.len()];
        intake.handle(key, &hostile(&mut rng, key));
    }
    let queued = rx.try_iter().count();
    let dropped: u64 = dropped.iter().map(|d| d.load(Ordering::Relaxed)).sum();
    assert_eq!(queued, 16);
    assert_eq!(dropped, 5_000 - 16);
    // every sample handed over is counted as received: queued + dropped
    assert_eq!(intake.received().load(Ordering::Relaxed), 5_000);
    // oversized payloads are refused before decoding
    let big = vec![0u8; Limits::default().max_payload_bytes as usize + 1];
    let e = parse_command(CommandKey::Spawn, &big, &Limits::default()).unwrap_err();
    assert!(e.contains("max_payload_bytes"));
}

/// Defence in depth: should the engine ever fail (here provoked by loosening the friction
/// limit so an absurd coefficient gets in), the guarded step the tick loop uses reloads the
/// scene instead of panicking the daemon or serving NaN.
#[test]
fn an_engine_failure_resets_the_world_instead_of_killing_the_daemon() {
    let mut config = ServerConfig::default();
    config.limits.max_friction = 3.0e38;
    let mut sim = Simulation::new(&config, SceneSource::Embedded).unwrap();
    let mut b = SpawnBody {
        name: None,
        shape: ShapeSpec::Rect {
            width: 1.1,
            height: 2.3,
        },
        position: Vector::new(0.0, 1.0),
        angle: -3.99,
        velocity: Vector::new(-11.9, 10.9),
        angular_velocity: -9.4,
        density: 224.0,
        friction: 2.2e38,
        restitution: 0.16,
        colour: Colour::default(),
    };
    let mut resets = 0;
    for i in 0..400 {
        if i % 20 == 0 {
            b.position.x = (i % 7) as f32 - 3.0;
            let p = encode(&Spawn {
                bodies: vec![b.clone()],
            })
            .unwrap();
            let command = parse_command(CommandKey::Spawn, &p, &config.limits);
            let _ = sim.apply(Incoming {
                key: CommandKey::Spawn,
                command,
            });
        }
        let (_, event) = sim.step_guarded().unwrap();
        if let Some(Event {
            kind: EventKind::Reset { .. },
            ..
        }) = event
        {
            resets += 1;
        }
        assert_sane(&sim, &config.limits, i);
    }
    assert_eq!(sim.frame(), 400, "frames stay consecutive");
    eprintln!("engine failures recovered from: {resets}");
}

/// Every refusal of a limited number names the limit a user can change and its real value:
/// a friction past the daemon's limit is never refused with the engine's wider range (a user
/// told [0, 1000] would try 500 and be refused again), and gravity and tilt name
/// `limits.max_gravity` as every other limit names its key.
#[test]
fn limit_refusals_name_the_real_limit_and_its_key() {
    let limits = Limits::default();
    for friction in [10.5, 500.0, 1000.0, 1001.0, 1e30] {
        let body = SpawnBody {
            friction,
            ..SpawnBody::at(ShapeSpec::Circle { radius: 0.5 }, Vector::new(0.0, 2.0))
        };
        let payload = encode(&Spawn { bodies: vec![body] }).unwrap();
        let e = parse_command(CommandKey::Spawn, &payload, &limits).unwrap_err();
        assert_eq!(
            e,
            format!(
                "bodies[0]: friction = {friction} is out of range: must be within [0, 10] (limits.max_friction)"
            )
        );
    }
    let gravity = encode(&SetGravity { x: 0.0, y: -101.0 }).unwrap();
    let e = parse_command(CommandKey::Gravity, &gravity, &limits).unwrap_err();
    assert_eq!(
        e,
        "|gravity| = 101 is out of range: must be <= 100 m/s^2 (limits.max_gravity)"
    );
    let tilt = encode(&Tilt::Accelerometer {
        x: 0.0,
        y: -101.0,
        z: 0.0,
    })
    .unwrap();
    let e = parse_command(CommandKey::Tilt, &tilt, &limits).unwrap_err();
    assert!(
        e.ends_with("must be <= 100 m/s^2 (limits.max_gravity)"),
        "{e}"
    );
    // A daemon limit above the engine's own is refused at start, so the two never disagree.
    let mut config = ServerConfig::default();
    config.limits.max_friction = 2000.0;
    let e = config.validate().unwrap_err().to_string();
    assert!(
        e.contains("limits.max_friction = 2000") && e.contains("<= 1000"),
        "{e}"
    );
}
