//! `tiltbox simulate --timeline` and `--journal`, run as a user runs them (the real binary):
//! scheduled commands take effect at the documented frame (checked against free fall's
//! closed form), go through the daemon's validation (bad entries refused at load, exit 2,
//! nothing printed), a `velocity` entry drives docs/scenes.md's lift (stop, turn back) and a
//! gate hinged at its segment's `position`, and a journal recorded by a real daemon over Zenoh
//! replays offline to the daemon's own final checkpoint, bit for bit.
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
use tiltbox::service::timeline::Timeline;
use tiltbox::service::{Command, Limits};

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

/// `tiltbox simulate SCENE --seconds 1 --timeline TIMELINE`, for timelines it must refuse.
fn refused_run(scene: &str, timeline: &str) -> Output {
    tiltbox(&["simulate", scene, "--seconds", "1", "--timeline", timeline])
}

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
        let o = refused_run(&scene, &timeline);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{entry}: {err}");
        assert!(o.stdout.is_empty(), "{entry}: printed before refusing");
        for n in *needles {
            assert!(err.contains(n), "{entry}: {n:?} not in {err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The fenced block number `n` (from 0) of language `lang` after `heading` in
/// docs/scenes.md, as written.
fn doc_block(heading: &str, lang: &str, n: usize) -> String {
    let doc = common::read_repo_file("docs/scenes.md");
    let fence = format!("```{lang}\n");
    let mut at = doc
        .find(heading)
        .unwrap_or_else(|| panic!("no {heading:?}"));
    for _ in 0..n {
        at += doc[at..].find(&fence).unwrap() + fence.len();
    }
    let start = at + doc[at..].find(&fence).unwrap() + fence.len();
    let end = start + doc[start..].find("```").unwrap();
    doc[start..end].to_string()
}

/// docs/scenes.md's lift example (scene, timeline) written to `dir`: their paths.
fn documented_lift(dir: &Path) -> (String, String) {
    let heading = "#### Example: a lift that stops and turns back";
    let scene = write(dir, "lift.toml", &doc_block(heading, "toml", 0));
    let timeline = write(dir, "lift-timeline.toml", &doc_block(heading, "toml", 1));
    (scene, timeline)
}

/// The timeline example of docs/scenes.md reads as written, its `velocity` entry as the
/// wire's `SetVelocity` would be.
#[test]
fn the_documented_timeline_example_reads() {
    let text = doc_block("### Scheduled commands: `--timeline FILE`", "toml", 0);
    let timeline = Timeline::parse(&text, 1.0 / 60.0, 600, &Limits::default()).unwrap();
    assert_eq!(timeline.entries.len(), 5);
    let (frame, i, last) = timeline.entries.last().unwrap();
    // 2.5 s at 60 Hz: frame boundary 150, applied before frame 151.
    assert_eq!((*frame, *i), (151, 4));
    assert_eq!(last.key, CommandKey::Velocity);
    assert_eq!(
        last.command,
        Ok(Command::SetVelocity {
            id: BodyRef {
                index: 3,
                generation: 0
            },
            velocity: Vector::new(0.0, 0.5),
            angular_velocity: 0.0,
        })
    );
}

/// docs/scenes.md's lift: the timeline stops it at 2 s and sends it down at 3 s. Its height
/// is the integral of the scripted velocity at every frame; the crate rides within the linear
/// slop of its top except in the two flights the closed form predicts (after the stop it flies
/// on at 0.5 m/s; after the turn it falls behind), each `v t - g t (t + h) / 2` above where it
/// rode (free fall as substeps of h = dt / 4 integrate it), landing after 2 v / g = 0.1 s.
#[test]
fn the_documented_lift_stops_and_turns_back_carrying_its_crate() {
    let dir = temp_dir("timeline-lift");
    let (scene, timeline) = documented_lift(&dir);
    let frames = jsonl(&tiltbox(&[
        "simulate",
        &scene,
        "--seconds",
        "5",
        "--every",
        "1",
        "--format",
        "jsonl",
        "--timeline",
        &timeline,
    ]));
    assert_eq!(frames.len(), 301);
    let (dt, g, v, slop) = (1.0 / 60.0, 9.81, 0.5, 0.005);
    let h = dt / 4.0;
    let num = |b: &Value, k: &str| b[k].as_f64().unwrap();
    // The crate's bottom less the lift's top (lift 0.2 m thick at its centre, crate 0.5 m).
    let gap = |k: usize| {
        let (lift, crate_) = (
            body(&frames[k], "lift").unwrap(),
            body(&frames[k], "crate").unwrap(),
        );
        num(crate_, "y") - 0.25 - (num(lift, "y") + 0.1)
    };
    let flight = |t: f64| v * t - g * t * (t + h) / 2.0;
    // The frame of each flight the crate is highest at.
    let mut highest = [(0.0, 0); 2];
    for (k, frame) in frames.iter().enumerate() {
        let lift = body(frame, "lift").unwrap();
        assert_eq!(lift["id"], "0v0");
        assert_eq!(body(frame, "crate").unwrap()["id"], "1v0");
        // Stop before frame 121 (t = 2 s is boundary 120), down before frame 181.
        let (up, down) = (k.min(120) as f64, k.saturating_sub(180) as f64);
        let y = 1.0 + v * up * dt - v * down * dt;
        assert!(
            (num(lift, "y") - y).abs() < 1e-5,
            "frame {k}: lift at {lift}, not {y}"
        );
        // The velocity it was given: exactly the scripted one.
        let vy = match k {
            0..=120 => v,
            121..=180 => 0.0,
            _ => -v,
        };
        assert_eq!(num(lift, "vy"), vy, "frame {k}");
        let crate_ = body(frame, "crate").unwrap();
        assert!(
            num(crate_, "x").abs() < 1e-4 && num(crate_, "angle").abs() < 1e-4,
            "{crate_}"
        );
        // In flight for 5 frames after each change (2 v / g = 0.102 s: lands in the 6th).
        let since = match k {
            121..=125 => Some((k - 120, 120)),
            181..=185 => Some((k - 180, 180)),
            _ => None,
        };
        match since {
            Some((n, before)) => {
                let up = gap(k) - gap(before);
                let want = flight(n as f64 * dt);
                assert!(
                    (up - want).abs() < 2e-4,
                    "frame {k}: {up} m up, closed form {want}"
                );
                assert!(up <= v * v / (2.0 * g), "frame {k}: {up} m, above v^2 / 2g");
                let top = &mut highest[usize::from(before == 180)];
                if up > top.0 {
                    *top = (up, n);
                }
            }
            None => assert!(
                gap(k).abs() <= slop,
                "frame {k}: crate {} m off the lift",
                gap(k)
            ),
        }
    }
    // The highest frame is the third of each flight (t = 0.05 s), where the closed form is
    // 1.17 cm, 1 mm short of v^2 / 2g, as the docs say.
    assert_eq!(highest.map(|(_, n)| n), [3, 3], "{highest:?}");
    assert!((flight(3.0 * dt) - 0.0117).abs() < 5e-5);
    assert!((v * v / (2.0 * g) - flight(3.0 * dt) - 0.001).abs() < 5e-5);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Each refusal docs/scenes.md lists for a `velocity` entry is what the binary says for that
/// entry at 0.5 s against the documented lift, with exit status 2 and nothing printed; also
/// when a good entry comes first (nothing is half-applied), a velocity left out, and an entry
/// with two commands.
#[test]
fn bad_velocity_entries_are_refused_with_the_documented_messages() {
    let dir = temp_dir("timeline-velocity-bad");
    let (scene, _) = documented_lift(&dir);
    let documented = doc_block("The refusals of a `velocity` entry", "text", 0);
    let entry = |id: &str, v: &str, w: &str| {
        format!("velocity = {{ id = \"{id}\", velocity = {v}, angular_velocity = {w} }}")
    };
    let cases: Vec<(String, &str)> = vec![
        (
            entry("lift", "[1, 0]", "0"),
            "at[0].velocity.id = \"lift\": not a body id",
        ),
        (
            entry("0v0", "[nan, 0]", "0"),
            "velocity.x must be a finite number, got NaN",
        ),
        (
            entry("0v0", "[0, 0]", "inf"),
            "angular_velocity must be a finite number, got inf",
        ),
        (entry("7v0", "[1, 0]", "0"), "id: no body with id 7v0"),
        (entry("1v0", "[1, 0]", "0"), "id: body 1v0 is not kinematic"),
        (
            entry("0v0", "[1000, 0]", "0"),
            "velocity (speed) = 1000 m/s is out of range",
        ),
        (
            entry("0v0", "[0, 0]", "500"),
            "angular_velocity = 500 rad/s is out of range",
        ),
    ];
    assert_eq!(cases.len(), documented.lines().count());
    let refuse = |name: &str, text: &str| {
        let timeline = write(&dir, name, text);
        let o = refused_run(&scene, &timeline);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(2), "{text}: {err}");
        assert!(o.stdout.is_empty(), "{text}: printed before refusing");
        err
    };
    for (i, (entry, needle)) in cases.iter().enumerate() {
        let line = documented
            .lines()
            .find(|l| l.contains(needle))
            .unwrap_or_else(|| panic!("docs/scenes.md lists no refusal with {needle:?}"));
        let err = refuse(
            &format!("bad{i}.toml"),
            &format!("[[at]]\ntime = 0.5\n{entry}\n"),
        );
        assert!(
            err.contains(line),
            "{entry}:\n{err}\ndoes not say as documented:\n{line}"
        );
        // A good entry before it changes nothing: the whole timeline is refused.
        let good = entry_at(
            0.25,
            "velocity = { id = \"0v0\", velocity = [0, 0], angular_velocity = 0 }",
        );
        let err = refuse(
            &format!("after{i}.toml"),
            &format!("{good}[[at]]\ntime = 0.5\n{entry}\n"),
        );
        assert!(err.contains(&line.replace("at[0]", "at[1]")), "{err}");
    }
    for (entry, needle) in [
        (
            "velocity = { id = \"0v0\", velocity = [0, 0] }",
            "missing field `angular_velocity`",
        ),
        (
            "velocity = { id = \"0v0\", angular_velocity = 1 }",
            "missing field `velocity`",
        ),
        (
            "velocity = { id = \"0v0\", velocity = [0, 0], angular_velocity = 0 }\ngravity = [0, 1]",
            "at[0]: give exactly one of gravity, tilt, spawn, remove, velocity",
        ),
    ] {
        let err = refuse("other.toml", &entry_at(0.5, entry));
        assert!(err.contains(needle), "{entry}: {needle:?} not in {err}");
    }
    // The cap named is the one the World runs with: here the scene's own.
    let lift = std::fs::read_to_string(&scene).unwrap();
    let capped = lift.replacen(
        "[[body]]",
        "[settings]\nmax_linear_speed = 50\n\n[[body]]",
        1,
    );
    let scene = write(&dir, "capped.toml", &capped);
    let timeline = write(
        &dir,
        "fast.toml",
        &entry_at(0.5, &entry("0v0", "[0, 60]", "0")),
    );
    let o = refused_run(&scene, &timeline);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("velocity (speed) = 60 m/s is out of range: must not exceed the World's settings.max_linear_speed = 50 m/s"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

fn entry_at(time: f64, command: &str) -> String {
    format!("[[at]]\ntime = {time}\n{command}\n\n")
}

/// A gate, a kinematic segment from `a = [0, 0]` to `b = [4, 0]` at `position = [0, 0]`, is
/// turned a quarter turn by the timeline (pi/2 rad/s for 1 s, then stopped) and then stops a
/// ball rolling at it 3 m up: it turned about its `position` (its end `a`), so it stands from
/// (0, 0) to (0, 4). Turned about the middle of a-b it would stand at x = 2 from y = -2 to 2,
/// and the ball would pass over it to x = 1.75.
#[test]
fn a_kinematic_segment_turns_about_its_position() {
    let dir = temp_dir("timeline-gate");
    let scene = write(
        &dir,
        "gate.toml",
        r#"
name = "gate"
gravity = [0, 0]
[[body]]
name = "gate"
kinematic = true
shape = { type = "segment", a = [0, 0], b = [4, 0] }
position = [0, 0]
[[body]]
name = "ball"
shape = { type = "circle", radius = 0.25 }
position = [-4.25, 3]
velocity = [2, 0]
density = 1
"#,
    );
    let timeline = write(
        &dir,
        "gate-timeline.toml",
        &[
            entry_at(
                0.0,
                "velocity = { id = \"0v0\", velocity = [0, 0], angular_velocity = 1.5707963 }",
            ),
            entry_at(
                1.0,
                "velocity = { id = \"0v0\", velocity = [0, 0], angular_velocity = 0 }",
            ),
        ]
        .concat(),
    );
    let frames = jsonl(&tiltbox(&[
        "simulate",
        &scene,
        "--seconds",
        "3",
        "--every",
        "30",
        "--format",
        "jsonl",
        "--timeline",
        &timeline,
    ]));
    let num = |frame: &Value, name: &str, k: &str| body(frame, name).unwrap()[k].as_f64().unwrap();
    for frame in &frames {
        // Its position never moves; its angle is pi/2 rad/s x t, to a quarter turn at 1 s.
        assert_eq!(
            (num(frame, "gate", "x"), num(frame, "gate", "y")),
            (0.0, 0.0)
        );
        let t = frame["time"].as_f64().unwrap();
        let angle = std::f64::consts::FRAC_PI_2 * t.min(1.0);
        assert!(
            (num(frame, "gate", "angle") - angle).abs() < 1e-5,
            "{frame}"
        );
    }
    let last = frames.last().unwrap();
    assert_eq!(last["frame"], 180);
    // Stopped by the gate's face at x = 0: centre one radius before it, within the slop.
    let x = num(last, "ball", "x");
    assert!((x + 0.25).abs() < 0.005, "ball at x = {x}");
    assert!((num(last, "ball", "y") - 3.0).abs() < 1e-4);
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
