//! `tiltbox simulate` run as a user runs it: the real binary, real scene files, real output.

#![cfg(feature = "cli")]

mod common;

use common::cli::tiltbox;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const BRICKS: &str = "config/scenes/falling_bricks.toml";

/// `tiltbox simulate` on Falling Bricks with `flags` (separated by spaces).
fn simulate_bricks(flags: &str) -> Output {
    let args: Vec<&str> = ["simulate", BRICKS]
        .into_iter()
        .chain(flags.split_whitespace())
        .collect();
    tiltbox(&args)
}

/// A scene file in the temp dir, removed on drop; unique per test and process.
struct TempScene(PathBuf);

impl TempScene {
    fn new(tag: &str, text: &str) -> TempScene {
        let path = std::env::temp_dir().join(format!(
            "tiltbox-simulate-{}-{tag}.toml",
            std::process::id()
        ));
        std::fs::write(&path, text).unwrap();
        TempScene(path)
    }
    fn path(&self) -> &str {
        self.0.to_str().unwrap()
    }
}

impl Drop for TempScene {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Exit 2 (a bad value), no panic, and stderr mentions every one of `needles`.
fn assert_refused(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "expected exit 2, stderr: {err}");
    assert!(!err.contains("panicked"), "panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}: {err}");
    }
}

#[test]
fn jsonl_prints_every_30th_frame_of_the_six_bricks() {
    let o = simulate_bricks("--format jsonl --seconds 1 --every 30");
    assert!(o.status.success(), "stderr: {}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let frames: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    // 1 s at 60 Hz is 60 steps: frames 0, 30 and 60.
    assert_eq!(frames.len(), 3, "{text}");
    let mut first_y = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        assert_eq!(f["frame"].as_u64(), Some(30 * k as u64));
        let t = f["time"].as_f64().unwrap();
        assert!(
            (t - 0.5 * k as f64).abs() < 1e-9,
            "time {t} at frame {}",
            30 * k
        );
        let bodies = f["bodies"].as_array().unwrap();
        // Only the dynamic bodies: the six bricks, not the four walls.
        assert_eq!(bodies.len(), 6, "{f}");
        for (i, b) in bodies.iter().enumerate() {
            // Walls are ids 0-3, bricks 4-9, in file order.
            assert_eq!(b["id"].as_str(), Some(format!("{}v0", 4 + i).as_str()));
            assert!(b["name"].as_str().unwrap().ends_with("brick"), "{b}");
            for key in ["x", "y", "angle", "vx", "vy", "omega"] {
                let v = b[key].as_f64();
                assert!(v.is_some_and(f64::is_finite), "{key} of {b}");
            }
            // Nothing sleeps at frame 0 (every body starts awake).
            assert!(b["asleep"].is_boolean(), "{b}");
            if k == 0 {
                assert_eq!(b["asleep"].as_bool(), Some(false), "{b}");
            }
            if k == 0 {
                first_y.push(b["y"].as_f64().unwrap());
            }
        }
    }
    let start = &frames[0]["bodies"][0];
    assert_eq!(start["name"], "red brick");
    assert!((start["x"].as_f64().unwrap() + 2.4).abs() < 1e-6);
    assert!((start["y"].as_f64().unwrap() - 1.2).abs() < 1e-6);
    assert!((start["angle"].as_f64().unwrap() - 0.3).abs() < 1e-6);
    assert_eq!(start["vy"].as_f64(), Some(0.0));
    // After half a second of gravity every brick has fallen (or landed) below where it started.
    for (b, y0) in frames[1]["bodies"].as_array().unwrap().iter().zip(&first_y) {
        let y = b["y"].as_f64().unwrap();
        assert!(y < y0 - 0.05, "{} did not fall: {y0} -> {y}", b["name"]);
        // ... and stays inside the 8 m x 6 m box.
        let x = b["x"].as_f64().unwrap();
        assert!(x > -4.0 && x < 4.0 && y > 0.0 && y < 6.0, "{b}");
    }
}

#[test]
fn table_format_is_aligned_and_names_the_bodies() {
    let o = tiltbox(&["simulate", BRICKS, "--seconds", "0.5", "--dt", "0.01"]);
    assert!(o.status.success(), "stderr: {}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    // 50 steps, every 60: frame 0 and the last frame.
    let headers: Vec<&str> = text.lines().filter(|l| l.starts_with("frame ")).collect();
    assert_eq!(headers, ["frame 0  t = 0.000 s", "frame 50  t = 0.500 s"]);
    let rows: Vec<&str> = text.lines().filter(|l| l.contains(" brick ")).collect();
    assert_eq!(rows.len(), 12, "{text}");
    assert!(rows[0].trim_start().starts_with("4v0"), "{}", rows[0]);
    assert!(
        rows[0].contains("-2.4000") && rows[0].contains("1.2000"),
        "{}",
        rows[0]
    );
    // Aligned: every row of a frame has the same length.
    assert!(rows.iter().all(|r| r.len() == rows[0].len()), "{text}");
}

#[test]
fn solver_flag_changes_the_run() {
    let run = |solver: &str| {
        let o = simulate_bricks(&format!(
            "--format jsonl --seconds 1 --every 60 --solver {solver}"
        ));
        assert!(o.status.success(), "stderr: {}", stderr(&o));
        String::from_utf8(o.stdout).unwrap()
    };
    let (seq, soft) = (run("sequential"), run("soft-step"));
    assert_eq!(seq.lines().count(), 2);
    // Same start, different solvers: the poses after 1 s differ.
    assert_eq!(seq.lines().next(), soft.lines().next());
    assert_ne!(seq.lines().nth(1), soft.lines().nth(1));
}

#[test]
fn closed_pipe_is_a_normal_end() {
    // Drop the reader after the first line; 10 s of the 211-body pyramid printing every step
    // is far more than a pipe buffer, so the writer meets the closed pipe.
    let mut child = Command::new(env!("CARGO_BIN_EXE_tiltbox"))
        .args([
            "simulate",
            "config/scenes/pyramid.toml",
            "--format",
            "jsonl",
            "--every",
            "1",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    {
        use std::io::BufRead;
        let stdout = child.stdout.take().unwrap();
        let mut line = String::new();
        std::io::BufReader::new(stdout)
            .read_line(&mut line)
            .unwrap();
        assert!(line.starts_with("{\"frame\":0,"), "{line}");
    } // reader closed here
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "status {:?}, stderr: {err}", o.status);
    assert!(!err.contains("panicked"), "{err}");
}

/// `--workers` shares each step among threads and changes nothing in the output: a pyramid
/// of 1,275 boxes (3,800 contacts, enough for its solve to be shared) with a few discs
/// dropped on it prints the same frames, to the last digit, on 1, 2 and 3 workers. A scene's
/// own `workers = 0` is refused with the field and the range.
#[test]
fn workers_share_the_step_and_change_nothing() {
    let mut text = String::from("[[pyramid]]\nbase = 50\nsize = 1.0\n\n");
    text += "[[body]]\nshape = { type = \"rect\", width = 80, height = 1 }\nposition = [0, -0.5]\nstatic = true\n";
    for i in 0..5 {
        text += &format!(
            "\n[[body]]\nshape = {{ type = \"circle\", radius = 0.5 }}\nposition = [{}, 60]\ndensity = 5\n",
            -10 + 5 * i
        );
    }
    let scene = TempScene::new("workers", &text);
    let run = |workers: &str| {
        let o = tiltbox(&[
            "simulate",
            scene.path(),
            "--seconds",
            "1",
            "--every",
            "20",
            "--format",
            "jsonl",
            "--workers",
            workers,
        ]);
        assert!(o.status.success(), "stderr: {}", stderr(&o));
        String::from_utf8(o.stdout).unwrap()
    };
    let one = run("1");
    assert_eq!(one.lines().count(), 4, "frames 0, 20, 40, 60");
    assert_eq!(run("2"), one);
    assert_eq!(run("3"), one);
    let refused = TempScene::new("workers0", "[settings]\nworkers = 0\n");
    assert_refused(
        &tiltbox(&["simulate", refused.path()]),
        &["workers = 0", "1..=64"],
    );
}

#[test]
fn bad_flags_name_the_flag_and_value() {
    // (flag, value given, how the refusal shows the value)
    for (flag, value, shown) in [
        ("--dt", "-1", "-1"),
        ("--dt", "0", "0"),
        ("--dt", "nan", "NaN"),
        ("--every", "0", "0"),
        ("--seconds", "-2", "-2"),
        ("--seconds", "inf", "inf"),
        ("--format", "xml", "xml"),
        ("--solver", "magic", "magic"),
        ("--workers", "0", "0"),
        ("--workers", "65", "65"),
        ("--workers", "-1", "-1"),
    ] {
        assert_refused(&tiltbox(&["simulate", BRICKS, flag, value]), &[flag, shown]);
    }
    // 1e9 s at 60 Hz would run for days: refused before any step.
    assert_refused(
        &tiltbox(&["simulate", BRICKS, "--seconds", "1e9"]),
        &["--seconds", "1000000000", "steps"],
    );
}

#[test]
fn missing_scene_file_is_reported() {
    let o = tiltbox(&["simulate", "config/scenes/no_such_scene.toml"]);
    assert_refused(&o, &["no_such_scene.toml", "cannot read"]);
    assert!(o.stdout.is_empty());
}

#[test]
fn malformed_scene_names_the_body_and_field() {
    let bad = TempScene::new(
        "friction",
        r#"
name = "bad"
[[body]]
name = "slippery"
shape = { type = "rect", width = 1, height = 1 }
position = [0, 1]
density = 1
friction = -1
"#,
    );
    let o = tiltbox(&["simulate", bad.path()]);
    assert_refused(
        &o,
        &[
            r#"body "slippery" (#0): friction = -1: must be >= 0"#,
            bad.path(),
        ],
    );
    assert!(o.stdout.is_empty());

    let typo = TempScene::new(
        "typo",
        "[[body]]\nname = \"b\"\nshape = { type = \"rect\", width = 1, height = 1 }\nposition = [0, 1]\nmass = 1\nfrction = 0.5\n",
    );
    assert_refused(
        &tiltbox(&["simulate", typo.path()]),
        &[r#"body "b" (#0) at line 1"#, "unknown field `frction`"],
    );

    let syntax = TempScene::new("syntax", "name = \"x\"\n[[body\n");
    assert_refused(&tiltbox(&["simulate", syntax.path()]), &["line 2"]);
}

#[test]
fn help_lists_the_flags() {
    let o = tiltbox(&["simulate", "--help"]);
    assert!(o.status.success());
    let text = String::from_utf8(o.stdout).unwrap();
    for flag in [
        "--seconds",
        "--dt",
        "--every",
        "--format",
        "--solver",
        "SCENE",
    ] {
        assert!(text.contains(flag), "{flag} missing from:\n{text}");
    }
    assert!(Path::new(env!("CARGO_MANIFEST_DIR")).join(BRICKS).exists());
}

#[test]
fn jsonl_time_is_frame_times_dt_without_float_noise_and_says_who_sleeps() {
    // 3 x 0.1 is 0.30000000000000004 in binary floating point; the output says 0.3.
    let o = simulate_bricks("--format jsonl --dt 0.1 --seconds 0.3 --every 3");
    assert!(o.status.success(), "stderr: {}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let last = text.lines().last().unwrap();
    assert!(last.starts_with(r#"{"frame":3,"time":0.3,"#), "{last}");
    // Bricks resting on the floor for 10 s (sleep on in scenes, 0.5 s to sleep) sleep.
    let o = simulate_bricks("--format jsonl --seconds 10 --every 600");
    assert!(o.status.success(), "stderr: {}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let last: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    let asleep = last["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|b| b["asleep"].as_bool() == Some(true))
        .count();
    assert!(asleep > 0, "no brick asleep after 10 s: {last}");
}
