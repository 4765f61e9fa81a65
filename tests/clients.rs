//! tiltbox-tilt's sources against an in-process daemon: real Zenoh over TCP loopback, one port
//! per test (17480, 17481), multicast scouting off; waits are on conditions with deadlines.
#![cfg(all(feature = "net", feature = "cli"))]

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use tiltbox::client::session;
use tiltbox::client::tilt::publish::{self, TiltPublisher};
use tiltbox::client::tilt::sweep;
use tiltbox::client::view::query_scene;
use tiltbox::client::view::world::{Join, Received};
use tiltbox::protocol::*;
use tiltbox::service::{Server, ServerConfig, ServerOptions};
use tokio::sync::mpsc;

async fn daemon(port: u16) -> Server {
    let mut cfg = ServerConfig::default();
    cfg.zenoh.listen = vec![format!("tcp/127.0.0.1:{port}")];
    Server::start(&cfg, ServerOptions::default())
        .await
        .expect("daemon starts")
}

fn mean_dynamic(join: &Join) -> (f32, f32) {
    let v = join.view().unwrap();
    let d: Vec<_> = v.bodies.values().filter(|b| !b.info.is_static).collect();
    let n = d.len() as f32;
    (
        d.iter().map(|b| b.x).sum::<f32>() / n,
        d.iter().map(|b| b.y).sum::<f32>() / n,
    )
}

/// Subscribe to poses and events into one channel.
async fn subscribe(
    s: &zenoh::Session,
    keys: &Keys,
) -> (
    mpsc::UnboundedReceiver<Received>,
    Vec<zenoh::pubsub::Subscriber<()>>,
) {
    let (tx, rx) = mpsc::unbounded_channel();
    let etx = tx.clone();
    let poses = s
        .declare_subscriber(keys.poses())
        .callback(move |x| {
            if let Ok(snap) = decode::<Snapshot>(&x.payload().to_bytes()) {
                let _ = tx.send(Received::Snapshot(snap));
            }
        })
        .await
        .unwrap();
    let events = s
        .declare_subscriber(keys.events())
        .callback(move |x| {
            if let Ok(e) = decode::<Event>(&x.payload().to_bytes()) {
                let _ = etx.send(Received::Event(e));
            }
        })
        .await
        .unwrap();
    (rx, vec![poses, events])
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_sweep_turns_gravity_around_and_the_bricks_follow() {
    let port = 17480;
    let server = daemon(port).await;
    let keys = server.keys().clone();
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let (mut rx, _subs) = subscribe(&s, &keys).await;
    // wait for the first snapshot, then join late through the scene query
    tokio::time::timeout(Duration::from_secs(5), rx.recv())
        .await
        .expect("a first snapshot");
    let mut join = Join::new();
    join.scene(query_scene(&s, keys.scene()).await.unwrap());

    // let the bricks settle on the floor under the scene's gravity (down)
    let settle = Instant::now() + Duration::from_millis(1500);
    while Instant::now() < settle {
        if let Ok(Some(r)) = tokio::time::timeout(Duration::from_millis(100), rx.recv()).await {
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
        let Ok(Some(r)) = tokio::time::timeout(Duration::from_millis(500), rx.recv()).await else {
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
    let _ = s.close().await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stdin_readings_reach_the_daemon_and_bad_lines_are_reported_by_number() {
    let port = 17481;
    let server = daemon(port).await;
    let keys = server.keys().clone();
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let (mut rx, _subs) = subscribe(&s, &keys).await;
    tokio::time::timeout(Duration::from_secs(5), rx.recv())
        .await
        .expect("a first snapshot");

    let mut child = Command::new(env!("CARGO_BIN_EXE_tiltbox-tilt"))
        .args(["--stdin", "--log", "info", "--connect"])
        .arg(format!("tcp/127.0.0.1:{port}"))
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
    let end = Instant::now() + Duration::from_secs(8);
    loop {
        assert!(Instant::now() < end, "gravity never turned right");
        if let Ok(Some(Received::Snapshot(snap))) =
            tokio::time::timeout(Duration::from_millis(500), rx.recv()).await
        {
            if snap.gravity == Vector::new(9.81, 0.0) {
                break;
            }
        }
    }
    // then a plain line, with a wrong one before it (line 11)
    stdin
        .write_all(b"{\"x\": 1, \"y\": 2}\n{\"x\": 0, \"y\": -9.81, \"z\": 0}\n")
        .unwrap();
    stdin.flush().unwrap();
    let end = Instant::now() + Duration::from_secs(5);
    loop {
        assert!(Instant::now() < end, "gravity never turned up");
        if let Ok(Some(Received::Snapshot(snap))) =
            tokio::time::timeout(Duration::from_millis(500), rx.recv()).await
        {
            if snap.gravity == Vector::new(0.0, 9.81) {
                break;
            }
        }
    }
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
    let _ = s.close().await;
    server.shutdown().await.unwrap();
}
