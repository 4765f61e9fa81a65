//! The daemon end to end: a real Zenoh session per daemon and per client, TCP loopback, one
//! port per test, multicast scouting off. Waits are on conditions with deadlines.
#![cfg(feature = "net")]

mod common;

use common::net::{
    daemon_config as config, query_scene, serve, subscribe, subscribe_snapshots, zenoh_config_as,
    WAIT,
};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};
use tiltbox::protocol::*;
use tiltbox::service::{Server, ServerConfig, ServerOptions};
use tokio::sync::mpsc::UnboundedReceiver;
use zenoh::pubsub::Subscriber;
use zenoh::Session;

struct Client {
    session: Session,
    keys: Keys,
    snapshots: UnboundedReceiver<Snapshot>,
    events: UnboundedReceiver<Event>,
    stats: UnboundedReceiver<Stats>,
    _subs: Vec<Subscriber<()>>,
}

impl Client {
    /// Connect, subscribe to poses, events and stats, and wait for the first snapshot.
    async fn connect(port: u16, keys: &Keys) -> Client {
        Client::connect_as("peer", port, keys).await
    }

    /// A daemon with `config` listening on `port`, and a client connected to it.
    async fn with_daemon(config: &ServerConfig, port: u16) -> (Server, Client) {
        let server = serve(config).await;
        let client = Client::connect(port, server.keys()).await;
        (server, client)
    }

    /// Connect in Zenoh mode `mode` (`peer` or `client`).
    async fn connect_as(mode: &str, port: u16, keys: &Keys) -> Client {
        let session = zenoh::open(zenoh_config_as(mode, port)).await.unwrap();
        let (snapshots, poses) = subscribe_snapshots(&session, keys.poses()).await;
        let (events, events_sub) = subscribe(&session, keys.events()).await;
        let (stats, stats_sub) = subscribe(&session, keys.stats()).await;
        let mut client = Client {
            session,
            keys: keys.clone(),
            snapshots,
            events,
            stats,
            _subs: vec![poses, events_sub, stats_sub],
        };
        client.snapshot_where(|_| true).await;
        client
    }

    async fn put_raw(&self, key: String, payload: Vec<u8>) {
        self.session.put(key, payload).await.unwrap();
    }

    async fn put<M: Message>(&self, key: String, msg: &M) {
        self.put_raw(key, encode(msg).unwrap()).await;
    }

    async fn snapshot_where(&mut self, pred: impl FnMut(&Snapshot) -> bool) -> Snapshot {
        first_where(&mut self.snapshots, pred, "snapshot").await
    }

    async fn event_where(&mut self, pred: impl FnMut(&Event) -> bool) -> Event {
        first_where(&mut self.events, pred, "event").await
    }

    async fn rejected(&mut self, key: &str, reason_has: &str) -> Event {
        let key = key.to_owned();
        self.event_where(|e| match &e.kind {
            EventKind::Rejected { key: k, reason } => *k == key && reason.contains(reason_has),
            _ => false,
        })
        .await
    }

    async fn scene(&self) -> SceneState {
        query_scene(&self.session, &self.keys).await
    }

    /// Wait until `frames` more frames have been stepped.
    async fn frames_pass(&mut self, frames: u64) -> Snapshot {
        // skip what is buffered: count from the newest snapshot
        let mut first = self.snapshot_where(|_| true).await.frame;
        while let Ok(s) = self.snapshots.try_recv() {
            first = s.frame;
        }
        self.snapshot_where(|s| s.frame >= first + frames).await
    }
}

/// The first message from `rx` that satisfies `pred`, within [`WAIT`].
async fn first_where<M>(
    rx: &mut UnboundedReceiver<M>,
    mut pred: impl FnMut(&M) -> bool,
    what: &str,
) -> M {
    let end = Instant::now() + WAIT;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        match tokio::time::timeout(left, rx.recv()).await {
            Ok(Some(m)) if pred(&m) => return m,
            Ok(Some(_)) => {}
            _ => panic!("no matching {what} within {WAIT:?}"),
        }
    }
}

fn mean_dynamic(state: &SceneState) -> (f32, f32) {
    let d: Vec<_> = state.bodies.iter().filter(|b| !b.is_static).collect();
    let n = d.len() as f32;
    (
        d.iter().map(|b| b.position.x).sum::<f32>() / n,
        d.iter().map(|b| b.position.y).sum::<f32>() / n,
    )
}

/// A 0.6 x 0.3 m brick named `name` at (`x`, `y`), coloured #010203.
fn brick(name: &str, x: f32, y: f32) -> SpawnBody {
    SpawnBody {
        name: Some(name.into()),
        colour: Colour { r: 1, g: 2, b: 3 },
        ..SpawnBody::at(
            ShapeSpec::Rect {
                width: 0.6,
                height: 0.3,
            },
            Vector::new(x, y),
        )
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn snapshots_arrive_at_60_hz_with_increasing_frames_and_keyframes() {
    let cfg = config(17461);
    let server = serve(&cfg).await;
    let keys = server.keys().clone();
    let mut c = Client::connect(17461, &keys).await;

    // the liveliness token is visible
    let tokens = c.session.liveliness().get(keys.server()).await.unwrap();
    let token = tokio::time::timeout(WAIT, tokens.recv_async())
        .await
        .unwrap()
        .unwrap();
    assert_eq!(token.result().unwrap().key_expr().as_str(), keys.server());

    let scene = c.scene().await;
    let dynamic = scene.bodies.iter().filter(|b| !b.is_static).count();
    let first = c.snapshot_where(|_| true).await;
    let t0 = Instant::now();
    let mut last = first.frame;
    let mut count = 0;
    let mut keyframes = 0;
    while t0.elapsed() < Duration::from_millis(1000) {
        let s = c.snapshot_where(|_| true).await;
        assert!(s.frame > last, "frames increase: {} after {last}", s.frame);
        assert!(s.time > 0.0 && (s.time - s.frame as f64 / 60.0).abs() < 1e-9);
        if s.frame % 60 == 0 {
            assert!(s.keyframe);
            assert_eq!(
                s.poses.len(),
                dynamic,
                "a keyframe carries every dynamic body"
            );
            keyframes += 1;
        } else {
            assert!(!s.keyframe);
        }
        // static bodies never appear
        for p in &s.poses {
            let b = scene.bodies.iter().find(|b| b.id == p.id).unwrap();
            assert!(!b.is_static);
        }
        last = s.frame;
        count += 1;
    }
    let rate = count as f64 / t0.elapsed().as_secs_f64();
    assert!((45.0..=75.0).contains(&rate), "{rate:.1} snapshots/s");
    assert!(keyframes >= 1);

    let stats = tokio::time::timeout(WAIT, c.stats.recv())
        .await
        .unwrap()
        .unwrap();
    assert!(stats.frame > 0 && stats.bodies as usize == scene.bodies.len());
    assert!(stats.awake as usize <= dynamic);

    // clean shutdown within 2 s, token gone
    let t0 = Instant::now();
    server.shutdown().await.unwrap();
    assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
    let end = Instant::now() + WAIT;
    loop {
        let tokens = c.session.liveliness().get(keys.server()).await.unwrap();
        if tokio::time::timeout(WAIT, tokens.recv_async())
            .await
            .unwrap()
            .is_err()
        {
            break;
        }
        assert!(Instant::now() < end, "token still alive");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sideways_gravity_moves_bricks_sideways() {
    let (server, mut c) = Client::with_daemon(&config(17462), 17462).await;
    let before = c.scene().await;
    c.put(c.keys.gravity(), &SetGravity { x: 15.0, y: 0.0 })
        .await;
    let s = c
        .snapshot_where(|s| s.gravity == Vector::new(15.0, 0.0))
        .await;
    c.snapshot_where(|x| x.frame >= s.frame + 60).await;
    let after = c.scene().await;
    let (x0, _) = mean_dynamic(&before);
    let (x1, _) = mean_dynamic(&after);
    assert!(x1 > x0 + 0.5, "mean x {x0} -> {x1}");
    let moved = before
        .bodies
        .iter()
        .filter(|b| !b.is_static)
        .filter(|b| {
            let a = after.bodies.iter().find(|a| a.id == b.id).unwrap();
            a.position.x > b.position.x + 0.5
        })
        .count();
    assert!(moved >= 1);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tilting_upside_down_makes_bricks_fall_towards_the_top() {
    let (server, mut c) = Client::with_daemon(&config(17463), 17463).await;
    let before = c.scene().await;
    let g = before.gravity.y.abs();
    c.put(
        c.keys.tilt(),
        &Tilt::Orientation(Orientation::PortraitUpsideDown),
    )
    .await;
    let s = c.snapshot_where(|s| s.gravity == Vector::new(0.0, g)).await;
    c.snapshot_where(|x| x.frame >= s.frame + 60).await;
    let after = c.scene().await;
    let (_, y0) = mean_dynamic(&before);
    let (_, y1) = mean_dynamic(&after);
    assert!(y1 > y0 + 1.0, "mean y {y0} -> {y1}");
    // a phone lying flat: no gravity in the plane
    c.put(
        c.keys.tilt(),
        &Tilt::Accelerometer {
            x: 0.0,
            y: 0.0,
            z: 9.81,
        },
    )
    .await;
    c.snapshot_where(|s| s.gravity == Vector::new(0.0, 0.0))
        .await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn spawn_shows_up_in_events_scene_and_snapshots_then_remove_and_reset() {
    let (server, mut c) = Client::with_daemon(&config(17464), 17464).await;
    let initial = c.scene().await;
    c.put(
        c.keys.spawn(),
        &Spawn {
            bodies: vec![brick("probe-a", -1.0, 4.5), brick("probe-b", 1.0, 4.5)],
        },
    )
    .await;
    let ev = c
        .event_where(|e| matches!(e.kind, EventKind::Added { .. }))
        .await;
    let EventKind::Added { bodies } = ev.kind else {
        unreachable!()
    };
    assert_eq!(bodies.len(), 2);
    assert_eq!(bodies[0].name, "probe-a");
    assert_eq!(bodies[1].colour, Colour { r: 1, g: 2, b: 3 });
    assert!(!bodies[0].is_static && (bodies[0].mass - 0.18).abs() < 1e-5);
    let ids: Vec<BodyRef> = bodies.iter().map(|b| b.id).collect();
    // the frame stamp is the first snapshot that holds them
    let s = c.snapshot_where(|s| s.frame >= ev.frame).await;
    assert_eq!(s.frame, ev.frame, "no snapshot lost in between");
    for id in &ids {
        assert!(s.poses.iter().any(|p| p.id == *id), "{id} in snapshot");
    }
    let scene = c.scene().await;
    assert_eq!(scene.bodies.len(), initial.bodies.len() + 2);
    let a = scene.bodies.iter().find(|b| b.id == ids[0]).unwrap();
    assert_eq!(a.name, "probe-a");
    assert_eq!(
        a.shape,
        ShapeSpec::Rect {
            width: 0.6,
            height: 0.3
        }
    );

    c.put(c.keys.remove(), &Remove { ids: vec![ids[0]] }).await;
    let ev = c
        .event_where(|e| matches!(e.kind, EventKind::Removed { .. }))
        .await;
    assert_eq!(ev.kind, EventKind::Removed { ids: vec![ids[0]] });
    c.snapshot_where(|s| s.frame >= ev.frame).await;
    let scene = c.scene().await;
    assert!(scene.frame >= ev.frame);
    assert!(scene.bodies.iter().all(|b| b.id != ids[0]));
    assert!(scene.bodies.iter().any(|b| b.id == ids[1]));

    c.put(c.keys.reset(), &Reset).await;
    let ev = c
        .event_where(|e| matches!(e.kind, EventKind::Reset { .. }))
        .await;
    let EventKind::Reset { bodies, .. } = &ev.kind else {
        unreachable!()
    };
    assert_eq!(bodies.len(), initial.bodies.len());
    let s = c.snapshot_where(|s| s.frame >= ev.frame).await;
    assert!(s.keyframe, "the snapshot after a reset is a keyframe");
    let scene = c.scene().await;
    assert!(scene.bodies.iter().all(|b| !b.name.starts_with("probe")));
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_is_rejected_on_events_while_frames_keep_increasing() {
    let mut cfg = config(17465);
    cfg.limits.max_bodies_per_spawn = 4;
    cfg.limits.max_spawns_per_second = 2;
    cfg.limits.max_bodies = 20; // Falling Bricks has 10
    let (server, mut c) = Client::with_daemon(&cfg, 17465).await;
    let k = c.keys.clone();
    let start = c.snapshot_where(|_| true).await.frame;

    // malformed: not postcard at all
    c.put_raw(k.spawn(), vec![1, 0xff, 0xff, 0xff]).await;
    c.rejected(&k.spawn(), "truncated Spawn").await;
    // empty payload, wrong version, trailing bytes
    c.put_raw(k.gravity(), vec![]).await;
    c.rejected(&k.gravity(), "empty payload").await;
    c.put_raw(k.reset(), vec![7]).await;
    c.rejected(&k.reset(), "unsupported protocol version 7")
        .await;
    c.put_raw(k.reset(), vec![1, 0]).await;
    c.rejected(&k.reset(), "unexpected byte").await;
    // unknown variants
    c.put_raw(k.tilt(), vec![1, 9]).await;
    c.rejected(&k.tilt(), "unknown variant").await;
    c.put_raw(k.tilt(), vec![1, 0, 42]).await;
    c.rejected(&k.tilt(), "unknown variant").await;
    // NaN and infinities, named with their value
    c.put(
        k.gravity(),
        &SetGravity {
            x: f32::NAN,
            y: -9.81,
        },
    )
    .await;
    c.rejected(&k.gravity(), "gravity.x must be a finite number, got NaN")
        .await;
    let mut b = brick("bad", 0.0, 3.0);
    b.angular_velocity = f32::INFINITY;
    c.put(
        k.spawn(),
        &Spawn {
            bodies: vec![brick("ok", 0.0, 2.0), b],
        },
    )
    .await;
    c.rejected(
        &k.spawn(),
        "bodies[1]: angular_velocity must be a finite number, got inf",
    )
    .await;
    let mut b = brick("bad", 0.0, 3.0);
    b.restitution = 2.0;
    c.put(k.spawn(), &Spawn { bodies: vec![b] }).await;
    c.rejected(&k.spawn(), "restitution = 2").await;
    // over the limits
    c.put(
        k.spawn(),
        &Spawn {
            bodies: vec![brick("x", 0.0, 3.0); 5],
        },
    )
    .await;
    c.rejected(&k.spawn(), "max_bodies_per_spawn = 4").await;
    c.put(
        k.remove(),
        &Remove {
            ids: vec![BodyRef {
                index: 999,
                generation: 0,
            }],
        },
    )
    .await;
    c.rejected(&k.remove(), "no body with id 999v0").await;
    // nothing was half-applied
    let scene = c.scene().await;
    assert_eq!(scene.bodies.len(), 10);
    assert!(scene.bodies.iter().all(|b| b.name != "ok"));

    // rate: two spawns in a second are applied, the third is refused
    for _ in 0..2 {
        c.put(
            k.spawn(),
            &Spawn {
                bodies: vec![brick("fill", 0.0, 3.0); 4],
            },
        )
        .await;
        c.event_where(|e| matches!(e.kind, EventKind::Added { .. }))
            .await;
    }
    c.put(
        k.spawn(),
        &Spawn {
            bodies: vec![brick("over", 0.0, 3.0)],
        },
    )
    .await;
    c.rejected(&k.spawn(), "max_spawns_per_second = 2").await;
    assert_eq!(c.scene().await.bodies.len(), 18);
    // wait out the rate window, then the body limit speaks: 18 + 3 > 20
    c.frames_pass(61).await;
    c.put(
        k.spawn(),
        &Spawn {
            bodies: vec![brick("over", 0.0, 3.0); 3],
        },
    )
    .await;
    c.rejected(&k.spawn(), "more than limits.max_bodies = 20")
        .await;
    assert_eq!(c.scene().await.bodies.len(), 18);

    // the world kept stepping throughout
    let end = c.frames_pass(2).await.frame;
    assert!(end > start + 2);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_full_command_queue_rejects_instead_of_blocking() {
    let mut cfg = config(17466);
    cfg.command_queue = 1;
    let (server, mut c) = Client::with_daemon(&cfg, 17466).await;
    let k = c.keys.clone();
    for i in 0..200 {
        c.put(
            k.gravity(),
            &SetGravity {
                x: i as f32 * 0.01,
                y: -9.81,
            },
        )
        .await;
    }
    c.rejected(&k.gravity(), "command queue full (capacity 1)")
        .await;
    c.frames_pass(2).await;
    server.shutdown().await.unwrap();
}

/// The largest difference between a client's poses and the daemon's scene query, over the
/// dynamic bodies: (position m, angle rad, the angle compared modulo a turn).
fn pose_error(poses: &BTreeMap<BodyRef, (f32, f32, f32)>, truth: &SceneState) -> (f64, f64) {
    let (mut dp, mut da) = (0.0f64, 0.0f64);
    for t in truth.bodies.iter().filter(|b| !b.is_static) {
        let (x, y, angle) = poses
            .get(&t.id)
            .unwrap_or_else(|| panic!("{} ({}) missing", t.id, t.name));
        dp = dp
            .max((*x as f64 - t.position.x as f64).abs())
            .max((*y as f64 - t.position.y as f64).abs());
        let tau = std::f64::consts::TAU;
        let d = (*angle as f64 - t.angle as f64).rem_euclid(tau);
        da = da.max(d.min(tau - d));
    }
    (dp, da)
}

/// A client follows a settling mixed pile through quantized snapshots: once it holds a
/// keyframe, its poses equal the daemon's scene query within half a grid step (1/2048 m,
/// pi/65536 rad) at every frame compared. A second decoder fed the same payloads with every
/// third one dropped on purpose is exact too: deltas are against the keyframe, never against
/// a delta it may have lost.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_matches_the_scene_within_half_a_grid_step_even_with_lost_samples() {
    let server = serve(&config(17467)).await;
    let mut a = Client::connect(17467, server.keys()).await;
    let mut spawned: Vec<_> = (0..4)
        .map(|i| brick(&format!("late-{i}"), -2.0 + i as f32, 5.0))
        .collect();
    spawned.push(shaped(
        "ball",
        ShapeSpec::Circle { radius: 0.3 },
        0.5,
        7.0,
        0.0,
    ));
    let capsule = ShapeSpec::Capsule {
        length: 1.0,
        radius: 0.2,
    };
    spawned.push(shaped("capsule", capsule, -0.5, 8.0, 2.5));
    a.put(a.keys.spawn(), &Spawn { bodies: spawned }).await;
    a.event_where(|e| matches!(e.kind, EventKind::Added { .. }))
        .await;

    // Raw payloads, decoded by the test itself: all of them, and all but every third.
    let session = zenoh::open(zenoh_config_as("client", 17467)).await.unwrap();
    let (tx, mut raw) = tokio::sync::mpsc::unbounded_channel::<Vec<u8>>();
    let _sub = session
        .declare_subscriber(a.keys.poses())
        .callback(move |x| {
            let _ = tx.send(x.payload().to_bytes().to_vec());
        })
        .await
        .unwrap();
    let step = 1.0 / 1024.0;
    let (mut all, mut lossy) = (SnapshotDecoder::new(), SnapshotDecoder::new());
    let (mut seen, mut seen_lossy) = (BTreeMap::new(), BTreeMap::new());
    let mut last = 0u64;
    let (mut compared, mut compared_lossy, mut dropped) = (0, 0, 0);
    let apply = |map: &mut BTreeMap<BodyRef, (f32, f32, f32)>, s: &Snapshot| {
        if s.keyframe {
            map.clear();
        }
        for p in &s.poses {
            map.insert(p.id, (p.x, p.y, p.angle));
        }
    };
    while compared < 6 || compared_lossy < 3 {
        let truth = a.scene().await;
        // decode until the truth's frame
        while last < truth.frame {
            let bytes = tokio::time::timeout(WAIT, raw.recv())
                .await
                .unwrap()
                .unwrap();
            let frame = decode_frame(&bytes).unwrap();
            last = frame.frame;
            if let Some(s) = all.decode(&bytes).unwrap() {
                apply(&mut seen, &s);
            }
            if frame.frame % 3 == 1 {
                dropped += 1;
            } else if let Some(s) = lossy.decode(&bytes).unwrap() {
                apply(&mut seen_lossy, &s);
            }
        }
        if last != truth.frame || seen.is_empty() {
            continue; // the reply raced a step, or no keyframe yet: ask again
        }
        let (dp, da) = pose_error(&seen, &truth);
        assert!(dp <= step / 2.0, "frame {last}: position off by {dp}");
        assert!(
            da <= Grid::angle_step() / 2.0 + 1e-6,
            "frame {last}: angle off by {da}"
        );
        compared += 1;
        if last % 3 != 1 && !seen_lossy.is_empty() {
            assert_eq!(seen_lossy, seen, "frame {last}: the lossy view differs");
            compared_lossy += 1;
        }
    }
    assert!(dropped > 10, "{dropped} samples dropped");
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_scene_file_is_served_and_reloaded_on_reset() {
    let dir = std::env::temp_dir().join(format!("tiltbox-daemon-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("one.toml");
    let one = |name: &str| {
        format!(
            "name = \"{name}\"\n[[body]]\nname = \"b\"\nshape = {{ type = \"rect\", width = 1, height = 1 }}\nposition = [0, 0]\ndensity = 1\n"
        )
    };
    std::fs::write(&path, one("first")).unwrap();
    let mut cfg = config(17468);
    cfg.scene = Some(path.clone());
    let (server, mut c) = Client::with_daemon(&cfg, 17468).await;
    assert_eq!(c.scene().await.scene, "first");
    std::fs::write(&path, one("second")).unwrap();
    c.put(c.keys.reset(), &Reset).await;
    let ev = c
        .event_where(|e| matches!(e.kind, EventKind::Reset { .. }))
        .await;
    assert!(matches!(ev.kind, EventKind::Reset { ref scene, .. } if scene == "second"));
    // a broken file: the reset is rejected and the world keeps running
    std::fs::write(&path, "name = 3").unwrap();
    c.put(c.keys.reset(), &Reset).await;
    c.rejected(&c.keys.reset(), "cannot reload the scene").await;
    c.frames_pass(2).await;
    assert_eq!(c.scene().await.scene, "second");
    server.shutdown().await.unwrap();
    let _ = std::fs::remove_dir_all(dir);
}

/// A flat static floor 40 m wide whose top is at y = `GROUND_TOP`, no gravity until the
/// test sets it: spawned bodies stay exactly where they were put until then.
const GROUND_TOP: f32 = 0.0;

async fn serve_floor(port: u16) -> Server {
    use tiltbox::physics::{vec2, BodyDef, Shape};
    use tiltbox::scene::{Scene, SceneBody};
    // 1 m thick, its top at y = GROUND_TOP = 0
    let floor = BodyDef::fixed(Shape::rect(40.0, 1.0), vec2(0.0, -0.5));
    let scene = Scene {
        name: "floor".into(),
        gravity: vec2(0.0, 0.0),
        settings: Default::default(),
        bodies: vec![SceneBody::new("floor", floor)],
        joints: Vec::new(),
    };
    let options = ServerOptions {
        source: Some(tiltbox::service::SceneSource::Given(Box::new(scene))),
        ..Default::default()
    };
    Server::start(&config(port), options)
        .await
        .expect("daemon starts")
}

fn shaped(name: &str, shape: ShapeSpec, x: f32, y: f32, angle: f32) -> SpawnBody {
    SpawnBody {
        shape,
        angle,
        restitution: 0.0,
        ..brick(name, x, y)
    }
}

/// Area centroid of a simple polygon (shoelace formula), in f64:
/// A = 1/2 sum cross(p_i, p_i+1), C = 1/(6A) sum (p_i + p_i+1) cross(p_i, p_i+1).
fn shoelace_centroid(v: &[(f64, f64)]) -> (f64, f64) {
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 0..v.len() {
        let (p, q) = (v[i], v[(i + 1) % v.len()]);
        let cross = p.0 * q.1 - q.0 * p.1;
        a += 0.5 * cross;
        cx += (p.0 + q.0) * cross;
        cy += (p.1 + q.1) * cross;
    }
    (cx / (6.0 * a), cy / (6.0 * a))
}

fn rotate(angle: f64, v: (f64, f64)) -> (f64, f64) {
    let (s, c) = angle.sin_cos();
    (c * v.0 - s * v.1, s * v.0 + c * v.1)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn circle_capsule_and_off_centre_polygon_spawn_where_asked_and_the_circle_settles() {
    let server = serve_floor(17600).await;
    let mut c = Client::connect(17600, server.keys()).await;
    let initial = c.scene().await;
    assert_eq!(initial.bodies.len(), 1);

    const R: f32 = 0.25;
    let (cap_len, cap_r) = (1.2f32, 0.2f32);
    // A trapezoid drawn off its centroid, relative to the spawn position (5, 1), turned 0.4.
    let quad = [(1.0, 0.0), (3.0, 0.0), (3.0, 1.0), (1.0, 2.0)];
    let (px, py, pangle) = (5.0f32, 1.0f32, 0.4f32);
    let spawn = Spawn {
        bodies: vec![
            shaped("ball", ShapeSpec::Circle { radius: R }, 0.0, 1.5, 0.0),
            shaped(
                "pill",
                ShapeSpec::Capsule {
                    length: cap_len,
                    radius: cap_r,
                },
                -6.0,
                1.0,
                0.3,
            ),
            shaped(
                "wedge",
                ShapeSpec::Polygon {
                    vertices: quad
                        .iter()
                        .map(|&(x, y)| Vector::new(x as f32, y as f32))
                        .collect(),
                },
                px,
                py,
                pangle,
            ),
        ],
    };
    c.put(c.keys.spawn(), &spawn).await;
    let ev = c.event_where(|_| true).await;
    let EventKind::Added { bodies: added } = ev.kind else {
        panic!("expected Added, got {ev:?}")
    };
    assert_eq!(added.len(), 3);
    c.snapshot_where(|s| s.frame >= ev.frame).await;
    let scene = c.scene().await;
    assert_eq!(scene.bodies.len(), 4);
    let by_name = |name: &str| {
        scene
            .bodies
            .iter()
            .find(|b| b.name == name)
            .unwrap_or_else(|| panic!("{name} in {scene:?}"))
            .clone()
    };
    let (ball, pill, wedge) = (by_name("ball"), by_name("pill"), by_name("wedge"));
    for (b, a) in [&ball, &pill, &wedge].into_iter().zip(&added) {
        assert_eq!(b.id, a.id);
        assert_eq!(
            b.shape, a.shape,
            "the scene and the event agree on the shape"
        );
    }

    // no gravity yet, no velocity: everything is exactly where it was put
    assert_eq!(ball.shape, ShapeSpec::Circle { radius: R });
    assert_eq!(ball.position, Vector::new(0.0, 1.5));
    // mass = density pi r^2
    assert!((ball.mass - std::f32::consts::PI * R * R).abs() < 1e-6);
    let ShapeSpec::Capsule { length, radius } = pill.shape else {
        panic!("{:?}", pill.shape)
    };
    assert!(
        (length - cap_len).abs() < 1e-6 && radius == cap_r,
        "{:?}",
        pill.shape
    );
    assert_eq!((pill.position, pill.angle), (Vector::new(-6.0, 1.0), 0.3));
    // capsule area: a 2 (L/2 - r) x 2 r rectangle plus a disc of radius r
    let cap_area =
        2.0 * (cap_len / 2.0 - cap_r) * 2.0 * cap_r + std::f32::consts::PI * cap_r * cap_r;
    assert!(
        (pill.mass - cap_area).abs() < 1e-5,
        "{} vs {cap_area}",
        pill.mass
    );

    // the polygon: its centre of mass is the spawn position plus its centroid, turned
    let centroid = shoelace_centroid(&quad);
    let turned = rotate(pangle as f64, centroid);
    let want = (px as f64 + turned.0, py as f64 + turned.1);
    let got = (wedge.position.x as f64, wedge.position.y as f64);
    assert!(
        (got.0 - want.0).abs() < 1e-5 && (got.1 - want.1).abs() < 1e-5,
        "wedge at {got:?}, closed form {want:?} (centroid {centroid:?})"
    );
    assert_eq!(wedge.angle, pangle);
    let ShapeSpec::Polygon { vertices } = &wedge.shape else {
        panic!("{:?}", wedge.shape)
    };
    assert_eq!(vertices.len(), 4);
    for (v, q) in vertices.iter().zip(quad) {
        // reported relative to the centroid, same order
        let (dx, dy) = (q.0 - centroid.0, q.1 - centroid.1);
        assert!(
            (v.x as f64 - dx).abs() < 1e-5 && (v.y as f64 - dy).abs() < 1e-5,
            "{v:?} vs ({dx}, {dy})"
        );
    }
    // trapezoid area: (2 + 1) / 2 x 2 = 3 m^2, density 1
    assert!((wedge.mass - 3.0).abs() < 1e-5, "{}", wedge.mass);

    // now gravity: the ball falls onto the floor and rests on it, its centre one radius up
    c.put(c.keys.gravity(), &SetGravity { x: 0.0, y: -9.81 })
        .await;
    let g = c
        .snapshot_where(|s| s.gravity == Vector::new(0.0, -9.81))
        .await
        .frame;
    // free fall from 1.5 - 0.25 = 1.25 m above the floor takes sqrt(2 h / g) = 0.5 s
    // = 30 frames; from 2 s after the gravity change every pose of the ball sent (deltas,
    // and at least one keyframe, which carries resting bodies too) must be within 1 cm.
    let settled_from = g + 120;
    let (mut checked, mut keyframes) = (0, 0);
    let (mut last_ball, mut last_pill) = (None, None);
    while keyframes < 2 || checked < 2 {
        let s = c.snapshot_where(|_| true).await;
        if s.frame < settled_from {
            continue;
        }
        keyframes += s.keyframe as u32;
        for p in &s.poses {
            if p.id == ball.id {
                let err = (p.y - (GROUND_TOP + R)).abs();
                assert!(
                    err < 0.01,
                    "frame {}: ball at y = {} (closed form {}), off by {err}",
                    s.frame,
                    p.y,
                    GROUND_TOP + R
                );
                assert!(p.x.abs() < 0.01, "the ball rolled to x = {}", p.x);
                checked += 1;
                last_ball = Some(*p);
            }
            if p.id == pill.id {
                last_pill = Some(*p);
            }
        }
    }
    // the capsule lies on its side: centre one radius above the floor, axis level
    let pill_pose = last_pill.expect("the capsule is in the keyframes");
    eprintln!("resting: ball {last_ball:?}, capsule {pill_pose:?}");
    assert!(
        (pill_pose.y - (GROUND_TOP + cap_r)).abs() < 0.01 && pill_pose.angle.sin().abs() < 0.02,
        "capsule at {pill_pose:?}"
    );
    let end = c.scene().await;
    assert_eq!(end.bodies.len(), 4);
    assert!(end
        .bodies
        .iter()
        .all(|b| b.position.x.is_finite() && b.position.y.is_finite()));
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn refused_shape_spawns_name_the_field_and_add_nothing() {
    let server = serve_floor(17601).await;
    let mut c = Client::connect(17601, server.keys()).await;
    let k = c.keys.clone();
    let before = c.scene().await.bodies.len();

    let poly = |points: &[(f32, f32)]| ShapeSpec::Polygon {
        vertices: points.iter().map(|&(x, y)| Vector::new(x, y)).collect(),
    };
    let nonagon: Vec<(f32, f32)> = (0..9)
        .map(|i| {
            let a = i as f32 * std::f32::consts::TAU / 9.0;
            (a.cos(), a.sin())
        })
        .collect();
    let huge: Vec<(f32, f32)> = (0..10_000)
        .map(|i| {
            let a = i as f32 * std::f32::consts::TAU / 10_000.0;
            (a.cos(), a.sin())
        })
        .collect();
    let ok_ball = shaped("ok", ShapeSpec::Circle { radius: 0.3 }, 0.0, 2.0, 0.0);
    let body = |shape| shaped("bad", shape, 0.0, 2.0, 0.0);
    let cases: Vec<(Vec<SpawnBody>, &str)> = vec![
        (
            vec![body(poly(&[(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)]))],
            "bodies[0]: shape.vertices[1] = [0, 1] turns clockwise there",
        ),
        (
            vec![body(poly(&nonagon))],
            "bodies[0]: shape.vertices must hold 3 to 8 points, got 9",
        ),
        (
            vec![body(ShapeSpec::Circle { radius: f32::NAN })],
            "bodies[0]: shape.radius must be a finite number, got NaN",
        ),
        (
            vec![body(ShapeSpec::Capsule {
                length: 0.8,
                radius: 0.5,
            })],
            "bodies[0]: shape.length = 0.8 must be more than twice shape.radius = 0.5",
        ),
        (
            vec![body(ShapeSpec::Circle { radius: 0.004 })],
            "bodies[0]: shape.radius = 0.004 is too small: the diameter 0.008 must be >= 0.01",
        ),
        (
            vec![body(poly(&[(5000.0, 0.0), (5001.0, 0.0), (5000.0, 1.0)]))],
            "bodies[0]: shape.vertices[0].x = 5000 is out of range",
        ),
        // a NaN angle on an off-centre polygon is named as the angle, not as the centre of
        // mass it would have made
        (
            vec![shaped(
                "bad",
                poly(&[(1.0, 0.0), (2.0, 0.0), (1.0, 1.0)]),
                0.0,
                2.0,
                f32::NAN,
            )],
            "bodies[0]: angle must be a finite number, got NaN",
        ),
        // all or nothing: the good ball before the bad polygon is not added either
        (
            vec![
                ok_ball.clone(),
                body(poly(&[(0.0, 0.0), (f32::NAN, 0.0), (0.0, 1.0)])),
            ],
            "bodies[1]: shape.vertices[1] must be finite, got [NaN, 0]",
        ),
        // 10,000 vertices: version 1 + count 1 + Some("bad") 5 + variant 1 + varint(10000) 2
        // + 80,000 + the other fields 39 = 80,049 bytes, refused by size before decoding
        (
            vec![body(poly(&huge))],
            "payload of 80049 bytes is larger than limits.max_payload_bytes = 65536",
        ),
    ];
    let mut last = 0;
    for (bodies, want) in cases {
        c.put(k.spawn(), &Spawn { bodies }).await;
        // commands are applied in arrival order: the next event is this one's refusal
        let ev = c.event_where(|_| true).await;
        match &ev.kind {
            EventKind::Rejected { key, reason } => {
                assert_eq!(*key, k.spawn());
                assert!(reason.contains(want), "{reason:?} should say {want:?}");
            }
            other => panic!("expected a refusal saying {want:?}, got {other:?}"),
        }
        last = ev.frame;
    }
    c.snapshot_where(|s| s.frame >= last).await;
    let scene = c.scene().await;
    assert!(scene.frame >= last);
    assert_eq!(scene.bodies.len(), before, "nothing was added: {scene:?}");
    assert!(scene
        .bodies
        .iter()
        .all(|b| b.name != "ok" && b.name != "bad"));

    // the same path accepts a good one
    c.put(
        k.spawn(),
        &Spawn {
            bodies: vec![ok_ball],
        },
    )
    .await;
    let ev = c.event_where(|_| true).await;
    assert!(
        matches!(&ev.kind, EventKind::Added { bodies } if bodies.len() == 1 && bodies[0].shape == ShapeSpec::Circle { radius: 0.3 }),
        "{ev:?}"
    );
    c.snapshot_where(|s| s.frame >= ev.frame).await;
    assert_eq!(c.scene().await.bodies.len(), before + 1);
    server.shutdown().await.unwrap();
}
