//! `tiltbox-tilt`: tilt a tiltbox world from the keyboard, a sweep, JSON readings on stdin
//! (e.g. `termux-sensor -s accelerometer`) or a Linux IIO accelerometer.
//!
//! The binary's entry point only: its flags and everything it does are in this directory's
//! library modules, `tiltbox::client::tilt` (`mod.rs` and its sources).

use clap::Parser;
use std::process::ExitCode;
use tiltbox::cli::{exit_code, init_logging};
use tiltbox::client::tilt::{self, TiltArgs};

/// Tilt a tiltbox world: arrow keys and p/u/l/r/f/d in a terminal, or --sweep, --stdin, --iio.
#[derive(Parser, Debug)]
#[command(name = "tiltbox-tilt", version, about)]
struct Cli {
    #[command(flatten)]
    args: TiltArgs,
}

fn main() -> ExitCode {
    let Cli { args } = Cli::parse();
    let default_log = if args.keyboard() {
        "error"
    } else {
        "info,zenoh=error"
    };
    init_logging(args.connect.log.as_deref(), default_log);
    exit_code(tilt::run(args).map_err(Into::into))
}
