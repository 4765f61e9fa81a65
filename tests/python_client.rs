//! The Python client (`clients/python`), tested by its own tests with a real Python: a venv
//! made under `target/`, the package installed into it as the README says (which brings
//! eclipse-zenoh from PyPI), its wire tests against docs/protocol.md, and its daemon tests
//! against a real daemon over a real Zenoh socket. Without python3 this fails saying what to
//! install; it never skips.
#![cfg(feature = "net")]

mod common;

use common::net::{daemon_config, endpoint, serve};
use std::path::{Path, PathBuf};
use std::process::Command;

const PORT: u16 = 17570;

/// Run `cmd`, panicking with its output unless it succeeds.
fn run(cmd: &mut Command, what: &str) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot run {cmd:?}: {e}"));
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{text}",
        out.status
    );
    text
}

/// The venv's python, the package installed into it.
fn venv(repo: &Path) -> PathBuf {
    let found = Command::new("python3").arg("--version").output();
    assert!(
        found.is_ok_and(|o| o.status.success()),
        "the Python client's tests need python3 (3.9 or newer) with its venv and pip modules: \
         install them (Debian: apt install python3 python3-venv python3-pip)"
    );
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| repo.join("target"), PathBuf::from);
    let dir = target.join("python-venv");
    let python = dir.join("bin").join("python");
    if !python.exists() {
        run(
            Command::new("python3").args(["-m", "venv"]).arg(&dir),
            "making the venv (python3 -m venv)",
        );
    }
    run(
        Command::new(&python)
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
            ])
            .arg(repo.join("clients/python")),
        "pip install clients/python",
    );
    python
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_python_client_passes_its_tests_against_a_real_daemon() {
    let repo = common::repo_path(".");
    let python = venv(&repo);
    let server = serve(&daemon_config(PORT)).await;
    let out = tokio::task::spawn_blocking(move || {
        run(
            Command::new(&python)
                .args(["-m", "unittest", "discover", "-v", "-s", "tests"])
                .current_dir(repo.join("clients/python"))
                .env("TILTBOX_REPO", &repo)
                .env("TILTBOX_ENDPOINT", endpoint(PORT)),
            "the Python client's tests",
        )
    })
    .await
    .unwrap();
    println!("{out}");
    // Every test ran and passed (none skipped: the daemon's endpoint was given).
    let ran: usize = out
        .split("Ran ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .expect("unittest's summary");
    let passed = out.lines().filter(|l| l.ends_with("... ok")).count();
    assert!(
        ran >= 6 && passed == ran && !out.contains("skipped"),
        "{out}"
    );
    server.shutdown().await.unwrap();
}
