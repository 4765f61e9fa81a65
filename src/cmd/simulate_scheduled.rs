//! `tiltbox simulate --timeline FILE` and `--journal LOG`: runs driven by the daemon's own
//! [`Simulation`], so scheduled and recorded commands are validated and applied by the same
//! code as commands from the wire, and a recorded run comes out bit-identical.

use super::simulate::{finish, print_frame, row, Format, Plan, Row};
use anyhow::{anyhow, Context};
use std::borrow::Cow;
use std::cell::RefCell;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::process::ExitCode;
use tiltbox::cli::Failure;
use tiltbox::physics::WorkerPool;
use tiltbox::protocol::EventKind;
use tiltbox::scene::Scene;
use tiltbox::service::journal::{replay_with, Journal};
use tiltbox::service::timeline::Timeline;
use tiltbox::service::{Command, SceneSource, ServerConfig, Simulation};

/// Every dynamic body of `sim` (scene and spawned ones), in slot order.
fn sim_rows(sim: &Simulation) -> Vec<Row<'static>> {
    sim.world()
        .bodies()
        .filter(|b| !b.is_static())
        .map(|b| row(b, Cow::Owned(sim.body_name(b))))
        .collect()
}

/// Run `scene` for `plan`, applying the timeline at `path`.
pub fn timeline(
    scene: Scene,
    path: &Path,
    plan: &Plan,
    format: Format,
) -> Result<ExitCode, Failure> {
    // The daemon's defaults, at this dt; the body limit raised to what the scene and the
    // timeline's spawns could reach (a scripted run is not a public server).
    let mut config = ServerConfig {
        tick_hz: 1.0 / plan.dt,
        ..Default::default()
    };
    config.validate().map_err(|e| {
        Failure::Usage(format!(
            "--dt {} with --timeline: the daemon's {e} (tick_hz = 1 / dt)",
            plan.dt
        ))
    })?;
    let timeline =
        Timeline::load(path, plan.dt, plan.steps, &config.limits).map_err(Failure::usage)?;
    let spawned: usize = timeline
        .entries
        .iter()
        .map(|(_, _, c)| match &c.command {
            Ok(Command::Spawn(defs)) => defs.len(),
            _ => 0,
        })
        .sum();
    let most = scene.bodies.len() + spawned;
    config.limits.max_bodies = config
        .limits
        .max_bodies
        .max(u32::try_from(most).unwrap_or(u32::MAX));
    // The scene's workers (or `--workers`) share the steps, as without a timeline.
    let workers = scene.settings.workers;
    let pool = match workers {
        0 | 1 => None,
        n => Some(
            WorkerPool::new(n)
                .map_err(|e| Failure::Failed(anyhow!("cannot start {n} workers: {e}")))?,
        ),
    };
    let source = SceneSource::Given(Box::new(scene));
    let start = || {
        let mut sim =
            Simulation::new(&config, source.clone()).map_err(|e| Failure::Usage(e.to_string()))?;
        sim.share_workers(pool.clone());
        Ok::<_, Failure>(sim)
    };
    // A dry run first: a command the simulation refuses when it comes to apply it (an id
    // that is not there, the spawn rate limit) refuses the timeline before anything is
    // printed.
    if !timeline.entries.is_empty() {
        drive(&mut start()?, &timeline, path, plan, |_| Ok(())).map_err(|e| {
            match e.downcast::<Rejected>() {
                Ok(r) => Failure::Usage(r.0),
                Err(e) => Failure::Failed(e),
            }
        })?;
    }
    let mut sim = start()?;
    let stdout = io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let result = drive(&mut sim, &timeline, path, plan, |sim| {
        let frame = sim.frame();
        if frame == 0 || frame % plan.every == 0 || frame == plan.steps {
            print_frame(&mut out, format, frame, plan.dt, &sim_rows(sim))?;
        }
        Ok(())
    })
    .and_then(|()| out.flush().context("writing to stdout"));
    finish(result)
}

/// Step `sim` through `plan`, applying the timeline's commands before their frames;
/// `on_frame` sees frame 0 and every frame stepped.
fn drive(
    sim: &mut Simulation,
    timeline: &Timeline,
    path: &Path,
    plan: &Plan,
    mut on_frame: impl FnMut(&Simulation) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut entries = timeline.entries.iter().peekable();
    on_frame(sim)?;
    for frame in 1..=plan.steps {
        while let Some((_, i, incoming)) = entries.next_if(|(f, _, _)| *f == frame) {
            if let Some(ev) = sim.apply(incoming.clone()) {
                if let EventKind::Rejected { reason, .. } = ev.kind {
                    return Err(anyhow!(Rejected(format!(
                        "timeline {}: at[{i}].{} refused when applied before frame {frame}: \
                         {reason}",
                        path.display(),
                        incoming.key
                    ))));
                }
            }
        }
        let (_, recovered) = sim
            .step_guarded()
            .with_context(|| format!("step {frame}"))?;
        if recovered.is_some() {
            return Err(anyhow!("step {frame}: the engine failed"));
        }
        on_frame(sim)?;
    }
    Ok(())
}

/// A timeline command the simulation refused when it came to apply it (a bad value: exit 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct Rejected(String);

/// Replay the journal at `log` (against `scene` if given), printing as the run went. Exit 1
/// if a frame's hash differs from the recorded one.
pub fn journal(
    log: &Path,
    scene: Option<Scene>,
    every: u64,
    format: Format,
) -> Result<ExitCode, Failure> {
    let journal = Journal::read(log).map_err(Failure::usage)?;
    let dt = journal.config().map_err(Failure::usage)?.dt();
    let last = journal.last_frame();
    let stdout = io::stdout();
    let out = RefCell::new(BufWriter::new(stdout.lock()));
    let failed: RefCell<Option<anyhow::Error>> = RefCell::new(None);
    let print = |sim: &Simulation, always: bool| {
        if failed.borrow().is_some() {
            return;
        }
        let frame = sim.frame();
        if always || frame % every == 0 || Some(frame) == last {
            if let Err(e) = print_frame(&mut *out.borrow_mut(), format, frame, dt, &sim_rows(sim)) {
                *failed.borrow_mut() = Some(e);
            }
        }
    };
    let report = replay_with(
        &journal,
        scene.map(|s| SceneSource::Given(Box::new(s))),
        |sim| print(sim, true),
        |sim| print(sim, false),
    )
    .map_err(Failure::usage)?;
    let flushed = match failed.into_inner() {
        Some(e) => Err(e),
        None => out.borrow_mut().flush().context("writing to stdout"),
    };
    let code = finish(flushed)?;
    if let Some((frame, recorded, replayed)) = report.first_mismatch {
        eprintln!(
            "error: frame {frame} differs from the recording (hash {replayed:016x}, recorded \
             {recorded:016x}): {} of {} frames differ",
            report.mismatches, report.frames_checked
        );
        return Ok(ExitCode::from(1));
    }
    Ok(code)
}
