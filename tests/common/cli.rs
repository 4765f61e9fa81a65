//! The `tiltbox` binary run as a user runs it.

use std::process::{Command, Output, Stdio};

/// `tiltbox ARGS...` from the repository root, stdin closed; its exit status and output.
pub fn tiltbox(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tiltbox"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null())
        .output()
        .expect("run tiltbox")
}
