//! The viewer's terminal: a full-screen braille drawing ([`super::render`]) redrawn at most
//! 30 times a second (continuously, through the playout buffer, while bodies move), a status
//! line with rate and latency, keys to quit (and with `--control` to drive the world). The terminal is put
//! back on `q`, Esc, Ctrl-C, SIGTERM and on panic (ratatui's hook).

use super::control::{key_command, mouse_hand, Control, Key, Mouse, Put, KEY_HELP};
use super::playout::{Playout, Xya};
use super::render::{cell_to_world, render, Status};
use super::world::{Applied, Join, Received, WorldView};
use super::{query_scene_with_joints, Msg};
use crate::client::tilt::keyboard::KeyCommand;
use crate::client::ClientError;
use crate::protocol::snapshot::Decoded;
use crate::protocol::BodyRef;
use crate::protocol::{Keys, Snapshot, SnapshotDecoder};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender};
use std::sync::Arc;
use std::time::{Duration, Instant};
use zenoh::Session;

/// The longest between two redraws while something changes: about 30 frames a second.
const FRAME: Duration = Duration::from_millis(33);

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
struct TerminalGuard {
    /// Whether mouse capture was turned on (and must be turned off).
    mouse: bool,
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        if self.mouse {
            let _ = crossterm::execute!(std::io::stdout(), crossterm::event::DisableMouseCapture);
        }
        ratatui::restore();
    }
}

/// The drag a mouse event makes at world point `at` (None: off the canvas), if any (left
/// button only; letting go counts anywhere).
fn mouse_action(kind: crossterm::event::MouseEventKind, at: Option<(f32, f32)>) -> Option<Mouse> {
    use crossterm::event::{MouseButton::Left, MouseEventKind as K};
    match kind {
        K::Down(Left) => at.map(Mouse::Down),
        K::Drag(Left) => at.map(Mouse::Drag),
        K::Up(Left) => Some(Mouse::Up(at.unwrap_or_default())),
        _ => None,
    }
}

/// The dynamic bodies' poses of `view`.
fn dynamic(view: &WorldView) -> impl Iterator<Item = (BodyRef, Xya)> + '_ {
    view.bodies
        .iter()
        .filter(|(_, b)| !b.info.is_static)
        .map(|(id, b)| (*id, [b.x, b.y, b.angle]))
}

/// `view` with its dynamic bodies where the playout buffer draws them at `now` (s since the
/// loop's origin); `None` before the buffer's first sample.
fn drawn(view: &WorldView, playout: &Playout, now: f64) -> Option<WorldView> {
    let poses = playout.poses_at(now)?;
    let mut v = view.clone();
    for (id, [x, y, angle]) in poses {
        if let Some(b) = v.bodies.get_mut(&id) {
            (b.x, b.y, b.angle) = (x, y, angle);
        }
    }
    Some(v)
}

/// Put a command's payload from a task (Block for spawn and reset).
fn send(rt: &tokio::runtime::Handle, session: &Session, put: Put) {
    let session = session.clone();
    rt.spawn(async move {
        use zenoh::qos::CongestionControl;
        let cc = if put.block {
            CongestionControl::Block
        } else {
            CongestionControl::Drop
        };
        if let Err(e) = session
            .put(put.key, put.payload)
            .congestion_control(cc)
            .await
        {
            tracing::warn!("put refused: {e}");
        }
    });
}

/// Draw the world until q, Esc, Ctrl-C or a signal; with `control`, the keys drive it.
pub(super) fn show(
    rt: &tokio::runtime::Handle,
    session: &Session,
    keys: &Keys,
    (tx, rx): (&SyncSender<Msg>, &Receiver<Msg>),
    endpoint: &str,
    args: &super::ViewArgs,
) -> Result<(), ClientError> {
    let control = args.control;
    let mut playout = Playout::new(args.playout);
    let mut snap_next = false;
    let mut terminal = ratatui::try_init()?;
    let _guard = TerminalGuard { mouse: control };
    // The mouse drags bodies (left button), as a finger does on the web page. Its hand's
    // liveliness token lives as long as the viewer: a viewer that dies lets go at once.
    let _hand_token = if control {
        crossterm::execute!(std::io::stdout(), crossterm::event::EnableMouseCapture)?;
        let token = session.liveliness().declare_token(keys.hand(mouse_hand()));
        rt.block_on(async { token.await }).ok()
    } else {
        None
    };
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
    let mut decoder = SnapshotDecoder::new();
    let mut status = Status {
        world: keys.prefix().to_owned(),
        endpoint: endpoint.to_owned(),
        keys: if control { KEY_HELP } else { "q quits" },
        ..Status::default()
    };
    let mut driver = Control::default();
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
                Msg::Snapshot(frame, at, stamped) => {
                    let Decoded::Snapshot(s) = decoder.apply(&frame) else {
                        continue; // a delta without its keyframe: wait for the next one
                    };
                    meter.snapshot(&s, at, stamped, origin);
                    let (frame, time, keyframe) = (s.frame, s.time, s.keyframe);
                    match join.receive(Received::Snapshot(s)) {
                        Applied::Restarted => {
                            join.restart();
                            meter.reset();
                            playout.clear();
                        }
                        Applied::Applied => {
                            if let Some(v) = join.view() {
                                let arrival = at.duration_since(origin).as_secs_f64();
                                playout.push(frame, time, arrival, dynamic(v), keyframe);
                                if std::mem::take(&mut snap_next) {
                                    playout.snap_newest();
                                }
                            }
                        }
                        Applied::Stale => {}
                    }
                    dirty = true;
                }
                Msg::Event(e) => {
                    snap_next |= matches!(e.kind, crate::protocol::EventKind::Reset { .. });
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
                    join.scene_with_joints(state);
                    playout.clear();
                    dirty = true;
                }
                Msg::Scene(Err(e)) => {
                    asking = false;
                    tracing::debug!("scene query: {e}");
                    retry_at = Instant::now() + Duration::from_secs(1);
                }
                Msg::Input(crossterm::event::Event::Key(k)) => {
                    match Key::from_crossterm(k).and_then(key_command) {
                        Some(KeyCommand::Quit) => quit = true,
                        Some(command) if control => {
                            if let Some(put) = driver.put(command, keys, join.view()) {
                                send(rt, session, put);
                            }
                        }
                        _ => {}
                    }
                }
                Msg::Input(crossterm::event::Event::Mouse(m)) if control => {
                    let area = terminal.get_frame().area();
                    let at = join
                        .view()
                        .and_then(|v| cell_to_world(v, area, m.column, m.row));
                    let action = mouse_action(m.kind, at);
                    if let Some(put) = action.and_then(|a| driver.mouse(a, keys, join.view())) {
                        send(rt, session, put);
                    }
                }
                Msg::Input(_) => dirty = true, // resize and the like: redraw
                Msg::Quit => quit = true,
            }
        }
        if quit {
            break Ok(());
        }
        if let Some(put) = driver.keepalive(keys) {
            send(rt, session, put);
        }
        if status.alive && join.view().is_none() && !asking && Instant::now() >= retry_at {
            asking = true;
            let (session, key, tx) = (session.clone(), keys.scene(), tx.clone());
            rt.spawn(async move {
                let _ = tx.send(Msg::Scene(query_scene_with_joints(&session, key).await));
            });
        }
        if dirty && last_draw.elapsed() >= FRAME {
            status.rate_hz = meter.rate(Instant::now());
            status.latency = meter.latency;
            let now = origin.elapsed().as_secs_f64();
            let smooth = match join.view() {
                Some(v) if args.playout > 0.0 => drawn(v, &playout, now),
                _ => None,
            };
            let view = smooth.as_ref().or(join.view());
            if let Err(e) = terminal.draw(|f| render(view, &status, f.area(), f.buffer_mut())) {
                break Err(e.into());
            }
            last_draw = Instant::now();
            // with a playout buffer, motion goes on between snapshots
            dirty = args.playout > 0.0 && smooth.is_some();
        }
    };
    stop.store(true, Ordering::Relaxed);
    let _ = input.join();
    result
}
