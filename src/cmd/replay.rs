//! `tiltbox replay LOG`: rebuild a recorded run from its journal and check, frame by frame,
//! that every body ends up bit-identical (same build, same scene, same commands).

use std::path::PathBuf;
use std::process::ExitCode;
use tiltbox::cli::{init_logging, Failure};
use tiltbox::scene::Scene;
use tiltbox::service::journal::{replay, Journal};
use tiltbox::service::SceneSource;

/// Arguments of `tiltbox replay`.
#[derive(clap::Args, Debug)]
pub struct ReplayArgs {
    /// The journal written by `tiltbox serve --record LOG`.
    #[arg(value_name = "LOG")]
    pub log: PathBuf,
    /// Use this scene file instead of the one recorded in the log (needed when the run used
    /// an in-memory scene).
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Print every frame's state hash.
    #[arg(long)]
    pub hashes: bool,
}

/// Run `tiltbox replay`: exit 0 when every frame in the log matches (a torn tail, as a crash
/// leaves, ends the check where the log ends), 1 on a mismatch, 2 when the log is damaged
/// inside (the message names the record and its byte offset) or the log or scene cannot be
/// used.
pub fn run(args: ReplayArgs) -> Result<ExitCode, Failure> {
    init_logging(None, "warn");
    let journal = Journal::read(&args.log).map_err(Failure::usage)?;
    let scene = match &args.scene {
        Some(path) => {
            let scene = Scene::load(path)
                .map_err(|e| Failure::Usage(format!("scene {}: {e}", path.display())))?;
            Some(SceneSource::Given(Box::new(scene)))
        }
        None => None,
    };
    let hashes = args.hashes;
    let report = replay(&journal, scene, |sim| {
        if hashes {
            println!("{} {:016x}", sim.frame(), sim.world().state_hash());
        }
    })
    .map_err(Failure::usage)?;
    println!(
        "frames {}..={}: {} commands, {} frame hashes checked, {} mismatched; final hash {:016x}{}{}",
        report.start_frame,
        report.last_frame,
        report.commands,
        report.frames_checked,
        report.mismatches,
        report.final_hash,
        if report.clean_end {
            ""
        } else {
            "; the log has no clean end (the daemon was killed?)"
        },
        if report.truncated {
            "; its last record was cut short"
        } else {
            ""
        },
    );
    Ok(match report.first_mismatch {
        None => ExitCode::SUCCESS,
        Some((frame, recorded, replayed)) => {
            println!(
                "first mismatch at frame {frame}: recorded {recorded:016x}, replayed {replayed:016x}"
            );
            ExitCode::from(1)
        }
    })
}
