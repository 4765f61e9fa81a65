//! `tiltbox-view`, the viewer (also the front end of `tiltbox demo`): subscribe to one world,
//! join late, and draw it in the terminal or print it as text.
//!
//! - [`world`]: the viewer's copy of the world, rebuilt from `…/scene`, snapshots and events;
//! - `render` (feature `tui`): the drawing, a pure function from that copy to cells;
//! - `terminal` (feature `tui`): the terminal loop, redrawing at most 30 times a second;
//! - [`plain`]: the `--plain` line per snapshot, its parser, and the loop that prints them;
//! - `control` (feature `tui`): `--control`, the keys that tilt, spawn and reset.
//!
//! Zenoh callbacks only decode and `try_send` into one bounded channel; the loop on the
//! caller's thread applies what arrives, and asks `…/scene` (on a tokio task) when a daemon
//! is alive and the view is missing or stale. The binary (`main.rs` here) parses
//! [`ViewArgs`] with the connection flags and calls `run`.
//!
//! **Latency.** Snapshots carry no wall-clock time. When a sample has a Zenoh timestamp (the
//! daemon's session timestamps data) the latency is receive time minus that timestamp.
//! Otherwise it is estimated from the simulated clock: `arrival - time` minus its smallest
//! value over the last seconds, i.e. how much later than the quickest recent snapshot this one
//! came (the daemon publishes on absolute tick deadlines).

#[cfg(feature = "tui")]
pub mod control;
pub mod plain;
pub mod playout;
#[cfg(feature = "tui")]
pub mod render;
#[cfg(feature = "tui")]
mod terminal;
pub mod world;

use crate::protocol::{decode, Message, SceneState, SceneWithJoints};
use std::time::Duration;
use zenoh::Session;
#[cfg(feature = "tui")]
use {
    super::session::watch_server,
    super::ClientError,
    crate::cli::wait_for_signal,
    crate::protocol::{decode_frame, Event, Keys, SnapshotFrame},
    std::io::Write,
    std::sync::mpsc::sync_channel,
    std::time::{Instant, SystemTime},
};

/// How the viewer shows the world: the flags `tiltbox-view` and `tiltbox demo` share.
#[derive(clap::Args, Clone, Debug)]
pub struct ViewArgs {
    /// Print one line per snapshot instead of drawing: "frame time id:x,y,angle ..." (no
    /// control codes).
    #[arg(long)]
    pub plain: bool,
    /// With --plain: one line every N snapshots, listing what moved since the previous line.
    #[arg(long, value_name = "N", default_value_t = 1, requires = "plain",
          value_parser = clap::value_parser!(u64).range(1..))]
    pub every: u64,
    /// With --plain: stop after N lines.
    #[arg(long, value_name = "N", requires = "plain")]
    pub count: Option<u64>,
    /// Drive the world from the keyboard, as tiltbox-tilt does: arrows and p/u/l/r/f/d tilt,
    /// space drops a brick, R resets (the daemon's ACL decides whether this session may).
    /// Always on in `tiltbox demo`.
    #[arg(long, conflicts_with = "plain")]
    pub control: bool,
    /// Draw this many snapshot intervals behind the newest snapshot, interpolating between
    /// snapshots (at most one interval of extrapolation when one is late); 0 draws each
    /// snapshot as it arrives.
    #[arg(long, value_name = "INTERVALS", default_value_t = 2.0,
          value_parser = playout_intervals)]
    pub playout: f64,
}

/// `--playout`: a finite number of intervals within 0..=30.
fn playout_intervals(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .parse()
        .map_err(|e| format!("{s:?} is not a number: {e}"))?;
    if v.is_finite() && (0.0..=30.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not within 0..=30 snapshot intervals"))
    }
}

impl ViewArgs {
    /// The log filter when none is given: errors only while drawing (the terminal is the
    /// screen), warnings in plain mode.
    pub fn default_log(&self) -> &'static str {
        if self.plain {
            "warn,zenoh=error"
        } else {
            "error"
        }
    }
}

/// What the loops receive: from Zenoh's callbacks, the scene query, the keyboard and signals.
#[cfg(feature = "tui")]
enum Msg {
    /// A `…/poses` payload, decoded without state: the loop's [`crate::protocol::SnapshotDecoder`]
    /// applies it, so a payload dropped on a full channel is a lost sample, nothing worse.
    Snapshot(SnapshotFrame, Instant, Option<Duration>),
    Event(Event),
    Alive(bool),
    Scene(Result<SceneWithJoints, String>),
    Input(crossterm::event::Event),
    Quit,
}

#[cfg(feature = "tui")]
const CHANNEL: usize = 4096;

#[cfg(feature = "tui")]
/// Run the viewer until the user quits (or `--count` lines are printed). `endpoint` says
/// where the daemon is expected, for messages; `out` receives the plain lines; the terminal
/// view draws on stdout through crossterm.
pub fn run(
    rt: &tokio::runtime::Handle,
    session: &Session,
    keys: &Keys,
    args: &ViewArgs,
    endpoint: &str,
    out: &mut dyn Write,
) -> Result<(), ClientError> {
    let (tx, rx) = sync_channel::<Msg>(CHANNEL);
    // Subscribe first, then watch liveliness: the scene is asked once a daemon is seen.
    let subs = rt.block_on(async {
        let stx = tx.clone();
        let poses = session
            .declare_subscriber(keys.poses())
            .callback(move |sample| {
                let now = Instant::now();
                let latency = sample.timestamp().and_then(|ts| {
                    SystemTime::now()
                        .duration_since(ts.get_time().to_system_time())
                        .ok()
                });
                match decode_frame(&sample.payload().to_bytes()) {
                    Ok(s) => {
                        let _ = stx.try_send(Msg::Snapshot(s, now, latency));
                    }
                    Err(e) => tracing::debug!("bad snapshot: {e}"),
                }
            })
            .await
            .map_err(ClientError::zenoh("poses subscriber"))?;
        let etx = tx.clone();
        let events = session
            .declare_subscriber(keys.events())
            .callback(
                move |sample| match decode::<Event>(&sample.payload().to_bytes()) {
                    Ok(e) => {
                        let _ = etx.try_send(Msg::Event(e));
                    }
                    Err(e) => tracing::debug!("bad event: {e}"),
                },
            )
            .await
            .map_err(ClientError::zenoh("events subscriber"))?;
        let atx = tx.clone();
        let watch = watch_server(session, keys, move |up| {
            let _ = atx.try_send(Msg::Alive(up));
        })
        .await?;
        Ok::<_, ClientError>((poses, events, watch))
    })?;
    {
        let qtx = tx.clone();
        rt.spawn(async move {
            wait_for_signal().await;
            let _ = qtx.send(Msg::Quit);
        });
    }
    let result = if args.plain {
        plain::run(&rx, args, endpoint, out)
    } else {
        terminal::show(rt, session, keys, (&tx, &rx), endpoint, args)
    };
    drop(subs);
    result
}

/// Ask `…/scene` once; the first good reply wins.
pub async fn query_scene(session: &Session, key: String) -> Result<SceneState, String> {
    query_one(session, key).await
}

/// Ask `…/scene?joints` once (the state and every joint); the first good reply wins.
pub async fn query_scene_with_joints(
    session: &Session,
    key: String,
) -> Result<SceneWithJoints, String> {
    query_one(session, format!("{key}?joints")).await
}

/// Ask `selector` once and decode the first good reply as `M`.
async fn query_one<M: Message>(session: &Session, selector: String) -> Result<M, String> {
    let replies = session
        .get(selector)
        .timeout(Duration::from_secs(2))
        .await
        .map_err(|e| e.to_string())?;
    while let Ok(reply) = replies.recv_async().await {
        match reply.into_result() {
            Ok(sample) => {
                return decode::<M>(&sample.payload().to_bytes()).map_err(|e| e.to_string())
            }
            Err(e) => tracing::debug!("scene reply error: {e:?}"),
        }
    }
    Err("no reply to the scene query".into())
}
