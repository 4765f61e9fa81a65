//! The tick thread: owns the [`Simulation`], steps it at a fixed dt against absolute deadlines,
//! applies queued commands at each tick boundary and hands every output to an [`Outputs`].
//! Zenoh is not here: [`run`] is the loop itself, which tests drive with their own outputs.

use super::checkpoint::Checkpointer;
use super::command::{DroppedCounts, Incoming};
use super::config::ServerConfig;
use super::journal::JournalWriter;
use super::scene_query::SceneQueries;
use super::sim::Simulation;
use super::world_query::WorldQueries;
use crate::protocol::{encode, CommandKey, Event, Stats};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Receiver;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Where the tick thread's encoded messages go. Implementations must not block.
pub trait Outputs: Send + 'static {
    /// A snapshot (`…/poses`) for `frame`.
    fn poses(&mut self, frame: u64, payload: Vec<u8>);
    /// An event (`…/events`).
    fn event(&mut self, payload: Vec<u8>);
    /// Stats (`…/stats`).
    fn stats(&mut self, payload: Vec<u8>);
    /// Every command taken from the channel, with the frame it is applied before (the frame
    /// of its event), whether it is then applied or rejected: the journal a replay needs.
    /// The default ignores it.
    fn command(&mut self, frame: u64, incoming: &Incoming) {
        let _ = (frame, incoming);
    }
    /// After every step, with the Simulation as it now is (journal hashes, checkpoints).
    fn stepped(&mut self, sim: &Simulation) {
        let _ = sim;
    }
    /// Once, when the loop stops, with the final Simulation (final checkpoint).
    fn finished(&mut self, sim: &Simulation) {
        let _ = sim;
    }
}

/// An [`Outputs`] plus the optional command journal and checkpoints, which see every command
/// and every step on the tick thread.
pub struct Recording<O> {
    /// Where messages go.
    pub inner: O,
    /// The command journal (`--record`).
    pub journal: Option<JournalWriter>,
    /// Periodic checkpoints (`--checkpoint`).
    pub checkpoints: Option<Checkpointer>,
}

impl<O: Outputs> Outputs for Recording<O> {
    fn poses(&mut self, frame: u64, payload: Vec<u8>) {
        self.inner.poses(frame, payload);
    }
    fn event(&mut self, payload: Vec<u8>) {
        self.inner.event(payload);
    }
    fn stats(&mut self, payload: Vec<u8>) {
        self.inner.stats(payload);
    }
    fn command(&mut self, frame: u64, incoming: &Incoming) {
        self.inner.command(frame, incoming);
        self.journal
            .iter_mut()
            .for_each(|j| j.command(frame, incoming));
    }
    fn stepped(&mut self, sim: &Simulation) {
        self.inner.stepped(sim);
        self.journal.iter_mut().for_each(|j| j.stepped(sim));
        self.checkpoints.iter_mut().for_each(|c| c.stepped(sim));
    }
    fn finished(&mut self, sim: &Simulation) {
        self.inner.finished(sim);
        self.journal.iter_mut().for_each(|j| j.finish(sim));
        self.checkpoints.iter_mut().for_each(|c| c.finish(sim));
    }
}

/// What the Zenoh side shares with the loop besides the command channel.
#[derive(Clone, Default)]
pub(crate) struct Shared {
    /// Commands a full channel refused, per key: reported as rejections.
    pub(crate) dropped: DroppedCounts,
    /// Command samples the subscribers received ([`super::command::Intake::received`]).
    pub(crate) received: Arc<std::sync::atomic::AtomicU64>,
    /// Late joiners waiting for the full state.
    pub(crate) scene_queries: Arc<SceneQueries>,
    /// `…/query` requests waiting for the next tick boundary.
    pub(crate) world_queries: Arc<WorldQueries>,
}

/// How the loop runs.
#[derive(Clone, Debug)]
pub struct TickConfig {
    /// Fixed step.
    pub dt: Duration,
    /// Late steps run back to back before time is dropped.
    pub max_catch_up: u32,
    /// Command channel capacity (for messages).
    pub command_capacity: u32,
    /// Keep every tick's lateness and step time in the [`RunSummary`] (benchmarks).
    pub record: bool,
}

impl TickConfig {
    /// The loop a daemon with `config` runs; `record` keeps every tick's timings.
    pub fn of(config: &ServerConfig, record: bool) -> TickConfig {
        TickConfig {
            dt: Duration::from_secs_f64(config.dt()),
            max_catch_up: config.max_catch_up,
            command_capacity: config.command_queue,
            record,
        }
    }
}

/// What the loop did, returned when it stops.
#[derive(Clone, Debug, Default)]
pub struct RunSummary {
    /// Frames stepped.
    pub frames: u64,
    /// Steps dropped because the loop fell behind.
    pub steps_dropped: u64,
    /// Commands dropped: refused by a full command channel, or still queued when the loop
    /// stopped.
    pub commands_dropped: u64,
    /// At the stop: command samples the subscribers received (`commands_received`).
    pub commands_received: u64,
    /// At the stop: commands applied since the start (`commands_applied`).
    pub commands_applied: u64,
    /// At the stop: commands rejected with an event since the start (`commands_rejected`).
    pub commands_rejected: u64,
    /// Per tick: how long after its deadline it started (us); only with `record`.
    pub lateness_us: Vec<u32>,
    /// Per tick: `World::step` time (us); only with `record`.
    pub step_us: Vec<u32>,
}

struct Window {
    started: Instant,
    step_us: Vec<u32>,
    worst_lateness_us: u32,
}

fn micros(d: Duration) -> u32 {
    d.as_micros().min(u32::MAX as u128) as u32
}

/// Run until `stop` is set, taking commands from `rx`. Returns the outputs (so the caller can
/// undeclare them) and a summary.
pub fn run<O: Outputs>(
    sim: Simulation,
    rx: Receiver<Incoming>,
    out: O,
    stop: Arc<AtomicBool>,
    cfg: TickConfig,
) -> (O, RunSummary) {
    run_shared(sim, rx, Shared::default(), out, stop, cfg)
}

/// [`run`], also reporting the commands a full channel dropped and answering scene queries.
pub(crate) fn run_shared<O: Outputs>(
    mut sim: Simulation,
    rx: Receiver<Incoming>,
    shared: Shared,
    mut out: O,
    stop: Arc<AtomicBool>,
    cfg: TickConfig,
) -> (O, RunSummary) {
    let dt = cfg.dt;
    let start = Instant::now();
    let deadline = |k: u64| start + dt.mul_f64(k as f64);
    let mut k: u64 = 1; // index of the next tick on the grid start + k dt
    let mut summary = RunSummary::default();
    let mut window = Window {
        started: start,
        step_us: Vec::with_capacity(128),
        worst_lateness_us: 0,
    };
    let mut last_payload = 1024;
    tracing::info!(dt_ms = dt.as_secs_f64() * 1e3, "tick loop started");
    while !stop.load(Ordering::Relaxed) {
        // 0. Late joiners: the state after the last step, built only when one is waiting.
        //    Asked between ticks too: the wait below is sliced into 50 ms.
        shared.scene_queries.answer(|| sim.scene_with_joints());
        shared.world_queries.answer(|q| sim.answer_query(q));
        let due = deadline(k);
        let now = Instant::now();
        if now < due {
            // Sleep in slices so a stop request is seen quickly.
            std::thread::sleep((due - now).min(Duration::from_millis(50)));
            continue;
        }
        let late = now - due;
        let behind = (late.as_secs_f64() / dt.as_secs_f64()) as u64;
        if behind > cfg.max_catch_up as u64 {
            let skip = behind - cfg.max_catch_up as u64;
            k += skip;
            summary.steps_dropped += skip;
            tracing::warn!(
                late_ms = late.as_secs_f64() * 1e3,
                dropped_steps = skip,
                "tick loop fell behind: dropping time"
            );
            continue;
        }
        k += 1;

        // 1. Commands, in arrival order, stamped with the frame about to be stepped.
        for key in CommandKey::ALL {
            let n = shared.dropped[key.index()].swap(0, Ordering::Relaxed);
            if n > 0 {
                summary.commands_dropped += n;
                let ev = sim.reject_dropped(key, n, cfg.command_capacity);
                publish_event(&mut out, &ev);
            }
        }
        while let Ok(incoming) = rx.try_recv() {
            out.command(sim.next_frame(), &incoming);
            if let Some(ev) = sim.apply(incoming) {
                publish_event(&mut out, &ev);
            }
        }

        // 2. Step.
        let step_time = match sim.step_guarded() {
            Ok((t, recovered)) => {
                if let Some(ev) = recovered {
                    publish_event(&mut out, &ev);
                }
                t
            }
            Err(e) => {
                tracing::error!(frame = sim.next_frame(), "step failed: {e}");
                continue;
            }
        };

        // 3. What touched, hit or entered what (only where the scene's shapes asked).
        for ev in sim.physics_events() {
            publish_event(&mut out, &ev);
        }

        // 4. Snapshot out, encoded once into a buffer of last frame's size and handed over.
        let frame = sim.frame();
        let mut payload = Vec::with_capacity(last_payload);
        sim.snapshot_into(&mut payload);
        last_payload = payload.len();
        out.poses(frame, payload);
        out.stepped(&sim);

        // 5. Bookkeeping and stats once a second.
        let (late_us, step_us) = (micros(late), micros(step_time));
        window.step_us.push(step_us);
        window.worst_lateness_us = window.worst_lateness_us.max(late_us);
        if cfg.record {
            summary.lateness_us.push(late_us);
            summary.step_us.push(step_us);
        }
        summary.frames = frame;
        let now = Instant::now();
        if now - window.started >= Duration::from_secs(1) {
            let n = window.step_us.len();
            let (_, &mut median, _) = window.step_us.select_nth_unstable(n / 2);
            let stats = Stats {
                frame,
                bodies: sim.world().body_count() as u32,
                awake: sim.awake_count() as u32,
                contacts: sim.world().contact_count() as u32,
                step_us_median: median,
                step_us_max: window.step_us.iter().copied().max().unwrap_or(0),
                lateness_us_max: window.worst_lateness_us,
                commands_applied: sim.applied(),
                commands_rejected: sim.rejected(),
                steps_dropped: summary.steps_dropped,
                commands_received: shared.received.load(Ordering::Relaxed),
                commands_dropped: summary.commands_dropped,
            };
            match encode(&stats) {
                Ok(p) => out.stats(p),
                Err(e) => tracing::error!("cannot encode stats: {e}"),
            }
            window.started = now;
            window.step_us.clear();
            window.worst_lateness_us = 0;
        }
    }
    // Every command ends counted: what is still queued (or was refused by the full channel
    // since the last tick) will never be applied.
    let unapplied = rx.try_iter().count() as u64
        + shared
            .dropped
            .iter()
            .map(|d| d.swap(0, Ordering::Relaxed))
            .sum::<u64>();
    if unapplied > 0 {
        tracing::warn!("{unapplied} command(s) still queued at shutdown were dropped");
    }
    summary.commands_dropped += unapplied;
    summary.commands_received = shared.received.load(Ordering::Relaxed);
    summary.commands_applied = sim.applied();
    summary.commands_rejected = sim.rejected();
    out.finished(&sim);
    tracing::info!(frames = summary.frames, "tick loop stopped");
    (out, summary)
}

fn publish_event<O: Outputs>(out: &mut O, ev: &Event) {
    match encode(ev) {
        Ok(p) => out.event(p),
        Err(e) => tracing::error!("cannot encode event: {e}"),
    }
}
