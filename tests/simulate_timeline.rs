//! `tiltbox simulate --timeline` and `--journal`, run as a user runs them (the real binary):
//! scheduled commands take effect at the documented frame (checked against free fall's
//! closed form), go through the daemon's validation (bad entries refused at load, exit 2,
//! nothing printed), and a journal recorded by a real daemon over Zenoh replays offline to
//! the daemon's own final checkpoint, bit for bit.
#![cfg(all(feature = "cli", feature = "net"))]
#![allow(clippy::unnecessary_cast)] // Real -> f32 casts matter with the `f64` feature.

mod common;

use common::cli::tiltbox;
use common::net::{daemon_config, open, serve, spawn_and_tilt_until_added, subscribe};
use common::rng::Rng;
use common::temp_dir;
use serde_json::Value;
use std::path::Path;
use std::process::Output;
use std::time::Duration;
use tiltbox::physics::World;
use tiltbox::protocol::*;
use tiltbox::service::checkpoint;

fn jsonl(o: &Output) -> Vec<Value> {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout.clone())
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// `simulate SCENE --seconds 1 --timeline TIMELINE`, every `every`-th frame as JSON lines.
fn one_second_with(scene: &str, timeline: &str, every: u32) -> Vec<Value> {
    let every = every.to_string();
    jsonl(&tiltbox(&[
        "simulate",
        scene,
        "--seconds",
        "1",
        "--every",
        &every,
        "--format",
        "jsonl",
        "--timeline",
        timeline,
    ]))
}

/// One falling disc, nothing to land on.
const DROP: &str = r#"
name = "drop"
gravity = [0, -10]
[[body]]
name = "ball"
shape = { type = "circle", radius = 0.5 }
position = [0, 100]
density = 1
"#;

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

fn body<'a>(frame: &'a Value, name: &str) -> Option<&'a Value> {
    frame["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["name"] == name)
}

#[test]
fn a_gravity_flip_takes_effect_at_the_documented_frame() {
    let dir = temp_dir("timeline-flip");
    let scene = write(&dir, "drop.toml", DROP);
    // t = 0.5 s at dt = 1/60 is frame boundary 30 (0.5 / dt = 30.000000000000004, within
    // 1e-9 of 30): applied before frame 31 is stepped.
    let timeline = write(&dir, "flip.toml", "[[at]]\ntime = 0.5\ngravity = [0, 10]\n");
    let frames = one_second_with(&scene, &timeline, 1);
    let vy = |k: usize| body(&frames[k], "ball").unwrap()["vy"].as_f64().unwrap();
    // Semi-implicit Euler: v_k = sum of g_i dt. 30 steps at -10, then +10: at frame 30,
    // v = -10 x 30/60 = -5 m/s; at 60, 0; the first step after the flip adds +10/60.
    // Tolerance: f32 sums of 60 terms of 1/6, a few ulp of 5 (1e-5).
    let dt = 1.0 / 60.0;
    assert!((vy(30) + 5.0).abs() < 1e-5, "v(30) = {}", vy(30));
    assert!(
        (vy(31) - (-5.0 + 10.0 * dt)).abs() < 1e-5,
        "v(31) = {}",
        vy(31)
    );
    assert!(vy(60).abs() < 1e-5, "v(60) = {}", vy(60));
    // One frame late would leave -2 dt x 10 = -0.33 m/s at frame 60.
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn spawn_and_remove_are_scheduled_and_their_bodies_listed() {
    let dir = temp_dir("timeline-spawn");
    let scene = write(&dir, "drop.toml", DROP);
    // The ball is 0v0 (the scene's only body); the spawned brick takes slot 1.
    let timeline = write(
        &dir,
        "spawn.toml",
        r#"
[[at]]
time = 0.25
spawn = [{ name = "late", shape = { Rect = { width = 0.4, height = 0.2 } }, position = [3, 50], velocity = [1, 0] }]

[[at]]
time = 0.5
remove = ["0v0"]
"#,
    );
    let frames = one_second_with(&scene, &timeline, 15);
    let at = |frame: u64| frames.iter().find(|f| f["frame"] == frame).unwrap();
    assert!(body(at(15), "late").is_none(), "spawned before its time");
    let late = body(at(30), "late").expect("spawned at 0.25 s");
    assert_eq!(late["id"], "1v0");
    // Spawned before frame 16, so 15 steps by frame 30: x = 3 + 1 m/s x 15/60 s.
    assert!((late["x"].as_f64().unwrap() - 3.25).abs() < 1e-5, "{late}");
    assert!(body(at(30), "ball").is_some());
    assert!(body(at(45), "ball").is_none(), "removed at 0.5 s");
    assert!(body(at(60), "late").is_some());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_timeline_entries_are_refused_before_anything_runs() {
    let dir = temp_dir("timeline-bad");
    let scene = write(&dir, "drop.toml", DROP);
    let cases: [(&str, &[&str]); 6] = [
        (
            "time = 0.5\ngravity = [0, 300]",
            &["at[0].gravity", "|gravity| = 300", "limits.max_gravity"],
        ),
        (
            "time = 0.5\nspawn = [{ shape = { Circle = { radius = 0.2 } }, position = [0, 1], restitution = 2 }]",
            &["at[0].spawn", "restitution = 2", "[0, 1]"],
        ),
        ("time = 7\ngravity = [0, 1]", &["at[0].time = 7", "1 s"]),
        ("time = -1\ngravity = [0, 1]", &["at[0].time = -1", ">= 0"]),
        ("time = 0.5\ngravty = [0, 1]", &["unknown field `gravty`"]),
        // Known only when applied: found by the dry run, before anything is printed.
        ("time = 0.5\nremove = [\"9v0\"]", &["at[0]", "no body with id 9v0"]),
    ];
    for (i, (entry, needles)) in cases.iter().enumerate() {
        let timeline = write(&dir, &format!("bad{i}.toml"), &format!("[[at]]\n{entry}\n"));
        let o = tiltbox(&[
            "simulate",
            &scene,
            "--seconds",
            "1",
            "--timeline",
            &timeline,
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{entry}: {err}");
        assert!(o.stdout.is_empty(), "{entry}: printed before refusing");
        for n in *needles {
            assert!(err.contains(n), "{entry}: {n:?} not in {err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A daemon run over Zenoh, recorded and checkpointed at its stop, reproduced offline by
/// `simulate --journal`: every body's final pose and velocity equals the checkpoint's, bit
/// for bit, and the sleep flags agree.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recorded_daemon_run_is_reproduced_bit_for_bit_by_simulate_journal() {
    let port = 17545;
    let dir = temp_dir("simulate-journal");
    let (log, ckpt) = (dir.join("run.journal"), dir.join("run.ckpt"));
    let mut config = daemon_config(port);
    config.record = Some(log.clone());
    config.checkpoint = Some(ckpt.clone());
    let server = serve(&config).await;
    let keys = server.keys().clone();
    let session = open(port).await;
    let (mut events, _sub) = subscribe::<Event>(&session, keys.events()).await;
    let within = Duration::from_secs(10);
    spawn_and_tilt_until_added(&session, &keys, &mut events, &mut Rng(11), 4, within).await;
    // Let it settle a little with the last tilt, so some bodies may sleep.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let summary = server.shutdown().await.unwrap();
    session.close().await.unwrap();

    let state = checkpoint::decode(&std::fs::read(&ckpt).unwrap()).unwrap();
    assert_eq!(state.frame, summary.frames);
    let world = World::import_state(&state.world).unwrap();

    let o = tiltbox(&[
        "simulate",
        "--journal",
        &log.display().to_string(),
        "--every",
        "1000000",
        "--format",
        "jsonl",
    ]);
    let frames = jsonl(&o);
    let last = frames.last().unwrap();
    assert_eq!(last["frame"].as_u64().unwrap(), summary.frames);
    let rows = last["bodies"].as_array().unwrap();
    let dynamic: Vec<_> = world.bodies().filter(|b| !b.is_static()).collect();
    assert_eq!(rows.len(), dynamic.len());
    assert!(dynamic.len() >= 6 + 4, "scene bricks and spawned ones");
    let bits = |v: &Value| (v.as_f64().unwrap() as f32).to_bits();
    for b in dynamic {
        let row = rows
            .iter()
            .find(|r| r["id"] == b.id().to_string())
            .unwrap_or_else(|| panic!("body {} not printed", b.id()));
        let (p, v) = (b.position(), b.linear_velocity());
        for (field, want) in [
            ("x", p.x),
            ("y", p.y),
            ("angle", b.angle()),
            ("vx", v.x),
            ("vy", v.y),
            ("omega", b.angular_velocity()),
        ] {
            assert_eq!(
                bits(&row[field]),
                (want as f32).to_bits(),
                "body {} {field}: printed {}, the daemon's checkpoint {want}",
                b.id(),
                row[field]
            );
        }
        assert_eq!(row["asleep"], !b.is_awake(), "body {} sleep flag", b.id());
    }
    let _ = std::fs::remove_dir_all(&dir);
}
