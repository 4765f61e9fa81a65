//! `tiltbox simulate`: step a scene headless and print the dynamic bodies' poses; with
//! `--timeline` or `--journal`, through the daemon's own simulation and command code
//! (`simulate_scheduled.rs`).

use anyhow::{bail, Context};
use clap::ValueEnum;
use serde::Serialize;
use std::borrow::Cow;
use std::io::{self, BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use tiltbox::cli::Failure;
use tiltbox::physics::{Body, BodyId, Real, SolverKind, World};
use tiltbox::scene::{Scene, SceneError};

/// The most steps one run may take (seconds / dt), so a typo cannot hang the terminal.
const MAX_STEPS: f64 = 1e5;

/// Arguments of `tiltbox simulate`.
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    /// Scene file (TOML; see docs/scenes.md), e.g. config/scenes/falling_bricks.toml. With
    /// --journal it replaces the scene recorded in the journal.
    #[arg(value_name = "SCENE", required_unless_present = "journal")]
    pub scene: Option<PathBuf>,
    /// Simulated time to run, in seconds (at most 100,000 steps of --dt).
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub seconds: f64,
    /// Fixed time step, in seconds.
    #[arg(long, default_value_t = 1.0 / 60.0, allow_negative_numbers = true)]
    pub dt: f64,
    /// Print every N-th step (frame 0 and the last frame are always printed).
    #[arg(long, default_value_t = 60, allow_negative_numbers = true)]
    pub every: i64,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    pub format: Format,
    /// Override the scene's solver.
    #[arg(long, value_enum)]
    pub solver: Option<SolverArg>,
    /// Threads that share each step (overrides the scene's `settings.workers`): the output is
    /// the same for any number, only the time it takes changes.
    #[arg(long, allow_negative_numbers = true, conflicts_with = "journal")]
    pub workers: Option<i64>,
    /// Commands at given simulated times (TOML `[[at]]` tables: gravity, tilt, spawn,
    /// remove, velocity; docs/scenes.md), validated and applied as the daemon applies commands.
    #[arg(long, value_name = "FILE", conflicts_with = "journal")]
    pub timeline: Option<PathBuf>,
    /// Replay a journal written by `tiltbox serve --record LOG`: its config, scene (unless
    /// SCENE is given) and commands at their recorded frames; prints as the run went.
    #[arg(long, value_name = "LOG", conflicts_with_all = ["seconds", "dt", "solver"])]
    pub journal: Option<PathBuf>,
}

/// How frames are printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// An aligned, human-readable table per printed frame.
    Table,
    /// One JSON object per printed frame: {"frame","time","bodies":[{"id","name","x","y","angle","vx","vy","omega","asleep"}]}.
    Jsonl,
}

/// The `--solver` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SolverArg {
    /// Sequential impulses with Baumgarte bias (the appendix, box2d-lite).
    Sequential,
    /// Box2D v3-style soft step with substeps.
    #[value(alias = "soft_step")]
    SoftStep,
}

impl From<SolverArg> for SolverKind {
    fn from(s: SolverArg) -> SolverKind {
        match s {
            SolverArg::Sequential => SolverKind::Sequential,
            SolverArg::SoftStep => SolverKind::SoftStep,
        }
    }
}

/// The checked run plan.
pub(super) struct Plan {
    pub(super) steps: u64,
    /// The step as asked for (s); the engine steps by it rounded to `Real`.
    pub(super) dt: f64,
    pub(super) every: u64,
}

/// Check the flags, naming the flag and the value on refusal.
fn plan(args: &SimulateArgs) -> anyhow::Result<Plan> {
    if !(args.dt.is_finite() && args.dt > 0.0) {
        bail!("--dt {}: must be a finite number of seconds > 0", args.dt);
    }
    if (args.dt as Real) <= 0.0 {
        bail!("--dt {}: too small for the engine's precision", args.dt);
    }
    if !(args.seconds.is_finite() && args.seconds > 0.0) {
        bail!(
            "--seconds {}: must be a finite number of seconds > 0",
            args.seconds
        );
    }
    if args.every < 1 {
        bail!("--every {}: must be >= 1", args.every);
    }
    let most = i64::from(tiltbox::physics::settings::MAX_WORKERS);
    if let Some(n) = args.workers.filter(|n| !(1..=most).contains(n)) {
        bail!("--workers {n}: must be within 1..={most}");
    }
    let steps = (args.seconds / args.dt).round();
    if steps < 1.0 {
        bail!(
            "--seconds {} is shorter than one step of --dt {}",
            args.seconds,
            args.dt
        );
    }
    if steps > MAX_STEPS {
        bail!(
            "--seconds {} with --dt {} is {steps} steps: at most {MAX_STEPS} per run",
            args.seconds,
            args.dt
        );
    }
    Ok(Plan {
        steps: steps as u64,
        dt: args.dt,
        every: args.every as u64,
    })
}

/// Run `tiltbox simulate`.
pub fn run(args: SimulateArgs) -> Result<ExitCode, Failure> {
    // A bad flag or a scene that cannot be used is a bad value: exit 2, as everywhere.
    let usage = |e: anyhow::Error| Failure::Usage(format!("{e:#}"));
    let plan = plan(&args).map_err(usage)?;
    let scene = match &args.scene {
        Some(path) => Some(load_scene(path).map_err(usage)?),
        None => None,
    };
    if let Some(log) = &args.journal {
        #[cfg(feature = "net")]
        return super::simulate_scheduled::journal(log, scene, plan.every, args.format);
        #[cfg(not(feature = "net"))]
        return Err(Failure::Usage(format!(
            "--journal {}: this build has no `net` feature (the daemon's code)",
            log.display()
        )));
    }
    let (mut scene, scene_path) = (
        scene.expect("clap requires SCENE without --journal"),
        args.scene.clone().unwrap_or_default(),
    );
    if let Some(solver) = args.solver {
        scene.settings.solver = solver.into();
    }
    if let Some(workers) = args.workers {
        // (Within 1..=MAX_WORKERS: checked by `plan`.)
        scene.settings.workers = workers as u32;
    }
    if let Some(timeline) = &args.timeline {
        #[cfg(feature = "net")]
        return super::simulate_scheduled::timeline(scene, timeline, &plan, args.format);
        #[cfg(not(feature = "net"))]
        return Err(Failure::Usage(format!(
            "--timeline {}: this build has no `net` feature (the daemon's code)",
            timeline.display()
        )));
    }
    let (mut world, ids) = scene
        .build_world()
        .with_context(|| format!("scene {}", scene_path.display()))
        .map_err(usage)?;
    let tracked: Vec<(BodyId, &str)> = scene
        .dynamic_bodies()
        .map(|(i, b)| (ids[i], b.name.as_str()))
        .collect();

    let stdout = io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let result = simulate(&mut world, &tracked, &plan, args.format, &mut out)
        .and_then(|()| out.flush().context("writing to stdout"));
    finish(result)
}

/// The exit of a run that printed: success, also when the reader went away (`| head`).
pub(super) fn finish(result: anyhow::Result<()>) -> Result<ExitCode, Failure> {
    match result {
        Ok(()) => Ok(ExitCode::SUCCESS),
        // The reader went away (`| head`): that ends the run, it is not a failure.
        Err(e) if is_broken_pipe(&e) => Ok(ExitCode::SUCCESS),
        Err(e) => Err(e.into()),
    }
}

/// Load a scene file; the error names the file.
fn load_scene(path: &std::path::Path) -> anyhow::Result<Scene> {
    Scene::load(path).map_err(|e| match e {
        // already names the file
        SceneError::Io { .. } => anyhow::Error::new(e),
        e => anyhow::Error::new(e).context(format!("scene {}", path.display())),
    })
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|cause| {
        cause
            .downcast_ref::<io::Error>()
            .is_some_and(|io| io.kind() == io::ErrorKind::BrokenPipe)
    })
}

/// Step and print.
fn simulate(
    world: &mut World,
    tracked: &[(BodyId, &str)],
    plan: &Plan,
    format: Format,
    out: &mut impl Write,
) -> anyhow::Result<()> {
    for frame in 0..=plan.steps {
        if frame > 0 {
            world
                .step(plan.dt as Real)
                .with_context(|| format!("step {frame}"))?;
        }
        if frame % plan.every == 0 || frame == plan.steps {
            print_frame(out, format, frame, plan.dt, &rows(world, tracked))?;
        }
    }
    Ok(())
}

/// Print one frame's rows in `format`.
pub(super) fn print_frame(
    out: &mut impl Write,
    format: Format,
    frame: u64,
    dt: f64,
    rows: &[Row<'_>],
) -> anyhow::Result<()> {
    // frame x dt as asked for, rather than the engine's sum of rounded steps, to the
    // nanosecond (3 x 0.1 prints 0.3, not 0.30000000000000004)
    let time = (frame as f64 * dt * 1e9).round() / 1e9;
    match format {
        Format::Jsonl => {
            let line = FrameJson {
                frame,
                time,
                bodies: rows,
            };
            serde_json::to_writer(&mut *out, &line)
                .map_err(io::Error::from)
                .and_then(|()| writeln!(out))
                .context("writing to stdout")?;
        }
        Format::Table => {
            let name_width = rows
                .iter()
                .map(|r| r.name.chars().count())
                .max()
                .unwrap_or(0)
                .max(4);
            write_table(out, frame, time, rows, name_width).context("writing to stdout")?
        }
    }
    Ok(())
}

/// One printed frame in `jsonl`.
#[derive(Serialize)]
struct FrameJson<'a, 'r> {
    frame: u64,
    /// Simulated time, s.
    time: f64,
    bodies: &'r [Row<'a>],
}

/// One dynamic body's state: position (m), angle (rad), velocity (m/s), angular velocity (rad/s).
#[derive(Serialize)]
pub(super) struct Row<'a> {
    id: String,
    name: Cow<'a, str>,
    x: Real,
    y: Real,
    angle: Real,
    vx: Real,
    vy: Real,
    omega: Real,
    /// The body sleeps (with its island): the engine skips it until something wakes it.
    asleep: bool,
}

fn rows<'a>(world: &World, tracked: &[(BodyId, &'a str)]) -> Vec<Row<'a>> {
    tracked
        .iter()
        .filter_map(|&(id, name)| Some(row(world.body(id)?, Cow::Borrowed(name))))
        .collect()
}

/// One body's row.
pub(super) fn row<'a>(b: &Body, name: Cow<'a, str>) -> Row<'a> {
    let (p, v) = (b.position(), b.linear_velocity());
    Row {
        id: b.id().to_string(),
        name,
        x: p.x,
        y: p.y,
        angle: b.angle(),
        vx: v.x,
        vy: v.y,
        omega: b.angular_velocity(),
        asleep: !b.is_awake(),
    }
}

fn write_table(
    out: &mut impl Write,
    frame: u64,
    time: f64,
    rows: &[Row<'_>],
    name_width: usize,
) -> io::Result<()> {
    writeln!(out, "frame {frame}  t = {time:.3} s")?;
    writeln!(
        out,
        "  {:<6} {:<name_width$} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "id", "name", "x [m]", "y [m]", "angle", "vx [m/s]", "vy [m/s]", "w [rad/s]"
    )?;
    for r in rows {
        writeln!(
            out,
            "  {:<6} {:<name_width$} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
            r.id, r.name, r.x, r.y, r.angle, r.vx, r.vy, r.omega
        )?;
    }
    writeln!(out)
}
