//! tiltbox-tilt's sources against an in-process daemon: real Zenoh over TCP loopback, one port
//! per test (17480, 17481), multicast scouting off; waits are on conditions with deadlines.
#![cfg(all(feature = "net", feature = "cli"))]

mod common;

use common::net::{daemon_config, endpoint, serve, subscribe, subscribe_snapshots, WAIT};
use std::io::Write;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use tiltbox::client::session;
use tiltbox::client::tilt::publish::{self, TiltPublisher};
use tiltbox::client::tilt::sweep;
use tiltbox::client::view::query_scene;
use tiltbox::client::view::world::{Join, Received};
use tiltbox::protocol::*;
use tiltbox::service::Server;
use tokio::sync::mpsc;

fn mean_dynamic(join: &Join) -> (f32, f32) {
    let v = join.view().unwrap();
    let d: Vec<_> = v.bodies.values().filter(|b| !b.info.is_static).collect();
    let n = d.len() as f32;
    (
        d.iter().map(|b| b.x).sum::<f32>() / n,
        d.iter().map(|b| b.y).sum::<f32>() / n,
    )
}

/// A daemon on `port` and a session of the clients' own towards it, receiving its poses and
/// events into one channel, once the first snapshot has come.
struct Setup {
    server: Server,
    keys: Keys,
    session: zenoh::Session,
    received: mpsc::UnboundedReceiver<Received>,
    _subs: Vec<zenoh::pubsub::Subscriber<()>>,
}

impl Setup {
    async fn start(port: u16) -> Setup {
        let server = serve(&daemon_config(port)).await;
        let keys = server.keys().clone();
        let session = session::open(&[endpoint(port)]).await.unwrap();
        let (tx, received) = mpsc::unbounded_channel();
        let etx = tx.clone();
        let (mut snapshots, poses) = subscribe_snapshots(&session, keys.poses()).await;
        let (mut events, events_sub) = subscribe::<Event>(&session, keys.events()).await;
        tokio::spawn(async move {
            while let Some(s) = snapshots.recv().await {
                let _ = tx.send(Received::Snapshot(s));
            }
        });
        tokio::spawn(async move {
            while let Some(e) = events.recv().await {
                let _ = etx.send(Received::Event(e));
            }
        });
        let mut setup = Setup {
            server,
            keys,
            session,
            received,
            _subs: vec![poses, events_sub],
        };
        tokio::time::timeout(WAIT, setup.received.recv())
            .await
            .expect("a first snapshot");
        setup
    }

    /// Wait until a snapshot carries gravity `g`, within `within`.
    async fn gravity_becomes(&mut self, g: Vector, within: Duration) {
        let end = Instant::now() + within;
        loop {
            assert!(Instant::now() < end, "gravity never became {g:?}");
            let next = tokio::time::timeout(Duration::from_millis(500), self.received.recv());
            if let Ok(Some(Received::Snapshot(s))) = next.await {
                if s.gravity == g {
                    return;
                }
            }
        }
    }

    async fn stop(self) {
        let _ = self.session.close().await;
        self.server.shutdown().await.unwrap();
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_sweep_turns_gravity_around_and_the_bricks_follow() {
    let mut setup = Setup::start(17480).await;
    let (s, keys) = (setup.session.clone(), setup.keys.clone());
    // after the first snapshot, join late through the scene query
    let mut join = Join::new();
    join.scene(query_scene(&s, keys.scene()).await.unwrap());

    // let the bricks settle on the floor under the scene's gravity (down)
    let settle = Instant::now() + Duration::from_millis(1500);
    while Instant::now() < settle {
        if let Ok(Some(r)) =
            tokio::time::timeout(Duration::from_millis(100), setup.received.recv()).await
        {
            join.receive(r);
        }
    }
    let (x0, y0) = mean_dynamic(&join);

    // sweep at 180 deg/s: down, left (t = 0.5 s), up (t = 1 s), right (t = 1.5 s)
    let mut publisher = TiltPublisher::new(&s, &keys).await.unwrap();
    let (tx, readings) = mpsc::channel(64);
    let sweeping = tokio::spawn(sweep::sweep(180.0, 30.0, tx));
    let publish = tokio::spawn(async move {
        publish::publish_loop(&mut publisher, 30.0, readings)
            .await
            .unwrap();
        publisher.sent()
    });

    // follow the snapshots: gravity's rotation (summed step by step) and the bricks' mean
    use std::f32::consts::PI;
    let mut turned = 0f32; // radians, clockwise on screen, since the sweep began
    let mut last_angle: Option<f32> = None;
    let mut max_y = y0;
    let mut left_phase_min_x = x0;
    let end = Instant::now() + Duration::from_secs(5);
    while Instant::now() < end && !(turned > 1.2 * PI && max_y > y0 + 1.5) {
        let Ok(Some(r)) =
            tokio::time::timeout(Duration::from_millis(500), setup.received.recv()).await
        else {
            continue;
        };
        join.receive(r);
        let g = join.view().unwrap().gravity;
        assert!(
            (g.x.hypot(g.y) - 9.81).abs() < 1e-3,
            "the sweep keeps |g| = 9.81: {g:?}"
        );
        let angle = g.y.atan2(g.x);
        if let Some(prev) = last_angle {
            // clockwise step, wrapped into (-pi, pi]
            let step = (prev - angle + PI).rem_euclid(2.0 * PI) - PI;
            assert!(step > -0.05, "gravity turned back by {step} rad");
            turned += step;
        }
        last_angle = Some(angle);
        let (x, y) = mean_dynamic(&join);
        max_y = max_y.max(y);
        if turned < PI {
            left_phase_min_x = left_phase_min_x.min(x);
        }
    }
    sweeping.abort();
    let _ = sweeping.await;
    let sent = publish.await.unwrap();
    assert!(
        turned > 1.2 * PI,
        "gravity turned {:.0} deg",
        turned.to_degrees()
    );
    assert!(sent >= 20, "{sent} tilts sent");
    // while gravity swung through the left the bricks slid left, and once it pointed up
    // they fell towards the ceiling
    assert!(
        left_phase_min_x < x0 - 0.5,
        "mean x {x0} -> {left_phase_min_x} while gravity pointed left"
    );
    assert!(max_y > y0 + 1.5, "mean y {y0} -> {max_y}");
    setup.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stdin_readings_reach_the_daemon_and_bad_lines_are_reported_by_number() {
    let port = 17481;
    let mut setup = Setup::start(port).await;

    let mut child = Command::new(env!("CARGO_BIN_EXE_tiltbox-tilt"))
        .args(["--stdin", "--log", "info", "--connect"])
        .arg(endpoint(port))
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    // line 1 is garbage, lines 2-10 a termux-sensor reading: phone turned clockwise
    // (landscape right), so gravity points to the screen's right
    stdin
        .write_all(
            b"not json\n{\n  \"BMI160 Accelerometer\": {\n    \"values\": [\n      -9.81,\n      0,\n      0\n    ]\n  }\n}\n",
        )
        .unwrap();
    stdin.flush().unwrap();
    setup
        .gravity_becomes(Vector::new(9.81, 0.0), Duration::from_secs(8))
        .await;
    // then a plain line, with a wrong one before it (line 11)
    stdin
        .write_all(b"{\"x\": 1, \"y\": 2}\n{\"x\": 0, \"y\": -9.81, \"z\": 0}\n")
        .unwrap();
    stdin.flush().unwrap();
    setup
        .gravity_becomes(Vector::new(0.0, 9.81), Duration::from_secs(5))
        .await;
    drop(stdin); // end of input: the source exits
    let out = tokio::task::spawn_blocking(move || child.wait_with_output())
        .await
        .unwrap()
        .unwrap();
    assert!(out.status.success(), "{:?}", out.status);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("line 1: not JSON"), "{err}");
    assert!(err.contains("line 11: no \"z\""), "{err}");
    assert!(err.contains("2 reading(s), 2 bad line(s) skipped"), "{err}");
    assert!(
        !err.contains('\x1b'),
        "no colour codes when stderr is a pipe"
    );
    setup.stop().await;
}
