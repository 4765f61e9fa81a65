//! The loop of `tiltbox-view` (and of `tiltbox demo`): subscribe, join late, draw or print.
//!
//! Zenoh callbacks only decode and `try_send` into one bounded channel; the loop on the
//! caller's thread applies what arrives to a [`Join`], asks `…/scene` (on a tokio task) when a
//! daemon is alive and the view is missing or stale, and redraws at most 30 times a second.
//! The terminal is put back on `q`, Esc, Ctrl-C, SIGTERM and on panic (ratatui's hook).
//!
//! **Latency.** Snapshots carry no wall-clock time. When a sample has a Zenoh timestamp (the
//! daemon's session timestamps data) the latency is receive time minus that timestamp.
//! Otherwise it is estimated from the simulated clock: `arrival - time` minus its smallest
//! value over the last seconds, i.e. how much later than the quickest recent snapshot this one
//! came (the daemon publishes on absolute tick deadlines).

use super::plain::PlainPrinter;
use super::render::{render, Status};
use super::session::{wait_for_signal, watch_server};
use super::world::{Applied, Join, Received};
use super::ClientError;
use crate::protocol::{decode, Event, Keys, SceneState, Snapshot};
use std::collections::VecDeque;
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError, SyncSender};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime};
use zenoh::Session;

/// How the viewer runs.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// Where the daemon is expected, for messages.
    pub endpoint: String,
    /// `--plain`: print a line per snapshot instead of drawing.
    pub plain: bool,
    /// `--every N` (plain mode).
    pub every: u64,
    /// `--count N`: stop after N plain lines.
    pub count: Option<u64>,
}

enum Msg {
    Snapshot(Snapshot, Instant, Option<Duration>),
    Event(Event),
    Alive(bool),
    Scene(Result<SceneState, String>),
    Input(crossterm::event::Event),
    Quit,
}

const CHANNEL: usize = 4096;
const FRAME: Duration = Duration::from_millis(33);

/// Run the viewer until the user quits (or `--count` lines are printed). `out` receives the
/// plain lines; the terminal view draws on stdout through crossterm.
pub fn run(
    rt: &tokio::runtime::Handle,
    session: &Session,
    keys: &Keys,
    opts: &ViewOptions,
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
                match decode::<Snapshot>(&sample.payload().to_bytes()) {
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
    let result = if opts.plain {
        plain_loop(&rx, opts, out)
    } else {
        tui_loop(rt, session, keys, &tx, &rx, opts)
    };
    drop(subs);
    result
}

fn plain_loop(
    rx: &Receiver<Msg>,
    opts: &ViewOptions,
    out: &mut dyn Write,
) -> Result<(), ClientError> {
    let mut printer = PlainPrinter::new(opts.every);
    let mut printed = 0u64;
    let mut alive = false;
    let started = Instant::now();
    let mut warned = false;
    loop {
        let msg = match rx.recv_timeout(Duration::from_millis(500)) {
            Ok(m) => m,
            Err(RecvTimeoutError::Timeout) => {
                if !alive && !warned && started.elapsed() > Duration::from_secs(1) {
                    eprintln!("waiting for server at {} ...", opts.endpoint);
                    warned = true;
                }
                continue;
            }
            Err(RecvTimeoutError::Disconnected) => return Ok(()),
        };
        match msg {
            Msg::Snapshot(s, _, _) => {
                if let Some(line) = printer.snapshot(&s) {
                    if writeln!(out, "{line}").and_then(|_| out.flush()).is_err() {
                        return Ok(()); // the pipe closed
                    }
                    printed += 1;
                    if opts.count.is_some_and(|n| printed >= n) {
                        return Ok(());
                    }
                }
            }
            Msg::Alive(up) => {
                if up != alive && (warned || !up) {
                    eprintln!(
                        "{}",
                        if up {
                            "server is up"
                        } else {
                            "server is gone; waiting"
                        }
                    );
                }
                alive = up;
            }
            Msg::Quit => return Ok(()),
            _ => {}
        }
    }
}

/// Received rate and latency bookkeeping.
#[derive(Default)]
struct Meter {
    arrivals: VecDeque<Instant>,
    /// (window start, smallest offset in it) for the current and the previous window.
    windows: [(Option<Instant>, f64); 2],
    latency: Option<Duration>,
}

impl Meter {
    fn snapshot(&mut self, s: &Snapshot, at: Instant, stamped: Option<Duration>, origin: Instant) {
        self.arrivals.push_back(at);
        while self
            .arrivals
            .front()
            .is_some_and(|t| at.duration_since(*t) > Duration::from_secs(1))
        {
            self.arrivals.pop_front();
        }
        if let Some(d) = stamped {
            self.latency = Some(d);
            return;
        }
        let offset = at.duration_since(origin).as_secs_f64() - s.time;
        let window = Duration::from_secs(5);
        match self.windows[0].0 {
            Some(start) if at.duration_since(start) < window => {
                self.windows[0].1 = self.windows[0].1.min(offset)
            }
            _ => {
                self.windows[1] = self.windows[0];
                self.windows[0] = (Some(at), offset);
            }
        }
        let mut min = self.windows[0].1;
        if self.windows[1].0.is_some() {
            min = min.min(self.windows[1].1);
        }
        self.latency = Some(Duration::from_secs_f64((offset - min).max(0.0)));
    }

    fn rate(&self, now: Instant) -> f64 {
        self.arrivals
            .iter()
            .filter(|t| now.duration_since(**t) <= Duration::from_secs(1))
            .count() as f64
    }

    fn reset(&mut self) {
        *self = Meter::default();
    }
}

/// Puts the terminal back when dropped (normal exit and errors; panics go through ratatui's
/// hook).
struct TerminalGuard;

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        ratatui::restore();
    }
}

fn tui_loop(
    rt: &tokio::runtime::Handle,
    session: &Session,
    keys: &Keys,
    tx: &SyncSender<Msg>,
    rx: &Receiver<Msg>,
    opts: &ViewOptions,
) -> Result<(), ClientError> {
    let mut terminal = ratatui::try_init()?;
    let _guard = TerminalGuard;
    let stop = Arc::new(AtomicBool::new(false));
    let input = {
        let (tx, stop) = (tx.clone(), stop.clone());
        std::thread::Builder::new()
            .name("tiltbox-view-input".into())
            .spawn(move || {
                use crossterm::event;
                while !stop.load(Ordering::Relaxed) {
                    match event::poll(Duration::from_millis(100)) {
                        Ok(true) => match event::read() {
                            Ok(e) => {
                                if tx.send(Msg::Input(e)).is_err() {
                                    return;
                                }
                            }
                            Err(_) => return,
                        },
                        Ok(false) => {}
                        Err(_) => return,
                    }
                }
            })?
    };
    let mut join = Join::new();
    let mut status = Status {
        world: keys.prefix().to_owned(),
        endpoint: opts.endpoint.clone(),
        ..Status::default()
    };
    let mut meter = Meter::default();
    let origin = Instant::now();
    let mut asking = false;
    let mut retry_at = Instant::now();
    let mut dirty = true;
    let mut last_draw = Instant::now() - FRAME;
    let result = loop {
        let timeout = if dirty {
            FRAME.saturating_sub(last_draw.elapsed())
        } else {
            Duration::from_millis(250)
        };
        let first = match rx.recv_timeout(timeout) {
            Ok(m) => Some(m),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => break Ok(()),
        };
        let mut quit = false;
        for msg in first
            .into_iter()
            .chain(std::iter::from_fn(|| rx.try_recv().ok()))
        {
            match msg {
                Msg::Snapshot(s, at, stamped) => {
                    meter.snapshot(&s, at, stamped, origin);
                    if join.receive(Received::Snapshot(s)) == Applied::Restarted {
                        join.restart();
                        meter.reset();
                    }
                    dirty = true;
                }
                Msg::Event(e) => {
                    join.receive(Received::Event(e));
                    dirty = true;
                }
                Msg::Alive(up) => {
                    if !up {
                        join.restart();
                        meter.reset();
                    }
                    status.alive = up;
                    dirty = true;
                }
                Msg::Scene(Ok(state)) => {
                    asking = false;
                    join.scene(state);
                    dirty = true;
                }
                Msg::Scene(Err(e)) => {
                    asking = false;
                    tracing::debug!("scene query: {e}");
                    retry_at = Instant::now() + Duration::from_secs(1);
                }
                Msg::Input(crossterm::event::Event::Key(k)) => {
                    use crossterm::event::{KeyCode, KeyEventKind, KeyModifiers};
                    if k.kind != KeyEventKind::Release {
                        let ctrl_c = k.code == KeyCode::Char('c')
                            && k.modifiers.contains(KeyModifiers::CONTROL);
                        if ctrl_c || matches!(k.code, KeyCode::Char('q') | KeyCode::Esc) {
                            quit = true;
                        }
                    }
                }
                Msg::Input(_) => dirty = true, // resize and the like: redraw
                Msg::Quit => quit = true,
            }
        }
        if quit {
            break Ok(());
        }
        if status.alive && join.view().is_none() && !asking && Instant::now() >= retry_at {
            asking = true;
            let (session, key, tx) = (session.clone(), keys.scene(), tx.clone());
            rt.spawn(async move {
                let _ = tx.send(Msg::Scene(query_scene(&session, key).await));
            });
        }
        if dirty && last_draw.elapsed() >= FRAME {
            status.rate_hz = meter.rate(Instant::now());
            status.latency = meter.latency;
            let view = join.view();
            if let Err(e) = terminal.draw(|f| render(view, &status, f.area(), f.buffer_mut())) {
                break Err(e.into());
            }
            last_draw = Instant::now();
            dirty = false;
        }
    };
    stop.store(true, Ordering::Relaxed);
    let _ = input.join();
    result
}

/// Ask `…/scene` once; the first good reply wins.
pub async fn query_scene(session: &Session, key: String) -> Result<SceneState, String> {
    let replies = session
        .get(key)
        .timeout(Duration::from_secs(2))
        .await
        .map_err(|e| e.to_string())?;
    while let Ok(reply) = replies.recv_async().await {
        match reply.into_result() {
            Ok(sample) => {
                return decode::<SceneState>(&sample.payload().to_bytes())
                    .map_err(|e| e.to_string())
            }
            Err(e) => tracing::debug!("scene reply error: {e:?}"),
        }
    }
    Err("no reply to the scene query".into())
}
