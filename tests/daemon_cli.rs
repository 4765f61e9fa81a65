//! The `tiltbox serve` binary: bad config exits 2 naming key and value; a flag that would be
//! ignored is refused; a port in use exits 2 naming the endpoint and the key that chose it;
//! logs to a pipe are plain text; SIGTERM stops it cleanly within 2 s.
#![cfg(all(feature = "net", feature = "cli"))]
#![cfg(feature = "net")]

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_tiltbox");

fn run(args: &[&str]) -> (i32, String) {
    let out = Command::new(BIN).args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_config_names_key_and_value_and_exits_2() {
    let (code, err) = run(&["serve", "--max-bodies", "0"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("limits.max_bodies = 0"), "{err}");

    let (code, err) = run(&["serve", "--listen", "nowhere"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("zenoh.listen") && err.contains("nowhere"),
        "{err}"
    );

    let dir = std::env::temp_dir().join(format!("tiltbox-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("server.toml");
    std::fs::write(&file, "tick_hz = 0.0\n").unwrap();
    let (code, err) = run(&["serve", "--config", file.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("tick_hz = 0"), "{err}");
    std::fs::write(&file, "[limits]\nmax_bodys = 5\n").unwrap();
    let (code, err) = run(&["serve", "--config", file.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("max_bodys"), "{err}");
    let (code, err) = run(&[
        "serve",
        "--scene",
        dir.join("missing.toml").to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("missing.toml"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn flags_that_would_be_ignored_are_refused() {
    // Any value, the default included: the flag alone does nothing.
    for every in ["5", "10"] {
        let (code, err) = run(&["serve", "--checkpoint-every", every]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains(&format!("checkpoint_every = {every}")) && err.contains("--checkpoint"),
            "{err}"
        );
    }
    let (code, err) = run(&[
        "serve",
        "--zenoh-config",
        "config/zenoh/acl-daemon.json5",
        "--listen",
        "tcp/127.0.0.1:17472",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("zenoh.config_file = config/zenoh/acl-daemon.json5")
            && err.contains("--listen would be ignored"),
        "{err}"
    );
}

#[test]
fn a_port_in_use_exits_2_naming_the_endpoint_and_its_key() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let endpoint = format!("tcp/{}", taken.local_addr().unwrap());
    // With the default log filter: the clean error alone, not Zenoh's own warning about the
    // same port (which quotes source paths of the build machine).
    let (code, err) = run(&["serve", "--listen", &endpoint]);
    assert_eq!(code, 2, "{err}");
    assert!(
        !err.contains("WARN") && !err.contains(".cargo"),
        "only the clean error: {err}"
    );
    let line = err.lines().find(|l| l.starts_with("error:")).expect(&err);
    assert!(
        line.contains("zenoh.listen") && line.contains(&endpoint) && line.contains("--listen"),
        "{line}"
    );
    assert!(
        !line.contains(".cargo") && !line.contains(".rs:"),
        "no build-machine paths: {line}"
    );
}

#[cfg(unix)]
#[test]
fn sigterm_stops_the_daemon_within_2_s() {
    let mut child = Command::new(BIN)
        .args(["serve", "--listen", "tcp/127.0.0.1:17469", "--log", "info"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let t0 = Instant::now();
    loop {
        let line = lines.next().expect("daemon log").unwrap();
        // stderr is a pipe here, not a terminal: plain text, no colour codes.
        assert!(
            !line.contains('\x1b'),
            "ANSI escape in a piped log: {line:?}"
        );
        if line.contains("tick loop started") {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "daemon did not start"
        );
    }
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let t0 = Instant::now();
    // drain the log so the daemon never blocks on a full pipe
    std::thread::spawn(move || for _ in lines {});
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "{status}");
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(2),
            "still running after 2 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Every row of docs/reliability.md's "Start-up refusals" table: the start given exits 2 with
/// one `error:` line holding the text the table quotes.
#[test]
fn the_documented_start_up_refusals_are_the_binarys() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/reliability.md"))
        .unwrap();
    let at = doc.find("### Start-up refusals").expect("the section");
    let rows: Vec<(Vec<String>, String)> = doc[at..]
        .lines()
        .skip_while(|l| !l.starts_with("| `tiltbox serve"))
        .take_while(|l| l.starts_with("| `tiltbox serve"))
        .map(|l| {
            let cells: Vec<&str> = l.split(" | ").collect();
            let start = cells[0].trim_start_matches("| `").trim_end_matches('`');
            let args = start.split_whitespace().skip(1).map(String::from).collect();
            let quoted = cells[1]
                .split('`')
                .nth(1)
                .expect("a quoted message")
                .to_owned();
            (args, quoted)
        })
        .collect();
    assert!(rows.len() >= 6, "{} rows", rows.len());
    for (args, quoted) in rows {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = Command::new(BIN)
            .args(&args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        let line = err.lines().find(|l| l.starts_with("error:")).expect(&err);
        assert!(
            line.contains(&quoted),
            "{args:?}: {line:?} lacks {quoted:?}"
        );
    }
}
