//! Helpers shared by the integration tests: each test file that needs them declares
//! `mod common;` and uses what it needs (the rest is dead code in that file's binary).
//!
//! - [`rng`]: a small deterministic generator, so random inputs are the same every run;
//! - `net` (feature `net`): a daemon on a loopback port, Zenoh peers towards it, typed
//!   subscriptions and the `…/scene` query; `bodies`: bodies to spawn;
//! - `scene` (feature `scene`): scene files and scene text built for the tests;
//! - `cli` (feature `cli`): the `tiltbox` binary run as a user runs it.
#![allow(dead_code)]

#[cfg(feature = "net")]
pub mod bodies;
#[cfg(feature = "cli")]
pub mod cli;
#[cfg(feature = "net")]
pub mod net;
pub mod rng;
#[cfg(feature = "scene")]
pub mod scene;

use std::path::{Path, PathBuf};

/// A path inside the repository, from its root (`docs/scenes.md`).
pub fn repo_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A text file of the repository, read whole.
pub fn read_repo_file(rel: &str) -> String {
    std::fs::read_to_string(repo_path(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// A fresh, empty directory under the system's temporary directory, unique to this process.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tiltbox-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Bytes as docs/protocol.md shows them: lower-case hex separated by spaces, 16 bytes a line.
pub fn hex(bytes: &[u8]) -> String {
    bytes
        .chunks(16)
        .map(|row| {
            row.iter()
                .map(|b| format!("{b:02x}"))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n")
}
