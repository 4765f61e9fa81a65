//! A daemon on a loopback port and Zenoh peers towards it. Every test uses its own port, so
//! tests in one process never see each other (multicast scouting is off everywhere).

use super::bodies::random_brick;
use super::rng::Rng;
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::Receiver;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use tiltbox::protocol::{
    decode, encode, Event, EventKind, Keys, Message, SceneState, Snapshot, SnapshotDecoder, Spawn,
    Tilt,
};
use tiltbox::service::{
    run_loop, Incoming, Outputs, RunSummary, Server, ServerConfig, ServerOptions, Simulation,
    TickConfig,
};
use tokio::sync::mpsc::{unbounded_channel, UnboundedReceiver};
use zenoh::pubsub::Subscriber;
use zenoh::Session;

/// How long a test waits for anything to arrive.
pub const WAIT: Duration = Duration::from_secs(5);

/// The default config, listening on `tcp/127.0.0.1:port` only.
pub fn daemon_config(port: u16) -> ServerConfig {
    let mut c = ServerConfig::default();
    c.zenoh.listen = vec![endpoint(port)];
    c
}

/// `tcp/127.0.0.1:port`.
pub fn endpoint(port: u16) -> String {
    format!("tcp/127.0.0.1:{port}")
}

/// Start a daemon with `config`.
pub async fn serve(config: &ServerConfig) -> Server {
    Server::start(config, ServerOptions::default())
        .await
        .expect("daemon starts")
}

/// The Zenoh config of a test's own session: `mode` (`peer` or `client`) connecting to
/// `port`, listening on nothing, no scouting.
pub fn zenoh_config_as(mode: &str, port: u16) -> zenoh::Config {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", &format!("\"{mode}\"")).unwrap();
    c.insert_json5("connect/endpoints", &format!("[\"{}\"]", endpoint(port)))
        .unwrap();
    c.insert_json5("listen/endpoints", "[]").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    c
}

/// [`zenoh_config_as`] in peer mode.
pub fn zenoh_config(port: u16) -> zenoh::Config {
    zenoh_config_as("peer", port)
}

/// A peer session towards the daemon on `port`.
pub async fn open(port: u16) -> Session {
    zenoh::open(zenoh_config(port)).await.unwrap()
}

/// Every message of type `M` put on `key`, decoded, in a channel (undecodable ones dropped).
pub async fn subscribe<M: Message + Send + 'static>(
    session: &Session,
    key: String,
) -> (UnboundedReceiver<M>, Subscriber<()>) {
    let (tx, rx) = unbounded_channel();
    let sub = session
        .declare_subscriber(key)
        .callback(move |s| {
            if let Ok(m) = decode::<M>(&s.payload().to_bytes()) {
                let _ = tx.send(m);
            }
        })
        .await
        .unwrap();
    (rx, sub)
}

/// Every `…/poses` payload on `key` as a client decodes it ([`SnapshotDecoder`]): nothing
/// before the first keyframe, then keyframes and what changed since the previous snapshot.
pub async fn subscribe_snapshots(
    session: &Session,
    key: String,
) -> (UnboundedReceiver<Snapshot>, Subscriber<()>) {
    let (tx, rx) = unbounded_channel();
    let decoder = std::sync::Mutex::new(SnapshotDecoder::new());
    let sub = session
        .declare_subscriber(key)
        .callback(move |s| {
            let mut d = decoder.lock().unwrap();
            if let Ok(Some(m)) = d.decode(&s.payload().to_bytes()) {
                let _ = tx.send(m);
            }
        })
        .await
        .unwrap();
    (rx, sub)
}

/// Put a random brick on `…/spawn` and a random tilt on `…/tilt`, again and again, until
/// `added` `Added` events have come back on `events` (the daemon hears this session and has
/// applied spawns), or fail after `within`. Returns the commands put.
pub async fn spawn_and_tilt_until_added(
    session: &Session,
    keys: &Keys,
    events: &mut UnboundedReceiver<Event>,
    rng: &mut Rng,
    added: usize,
    within: Duration,
) -> usize {
    let deadline = Instant::now() + within;
    let (mut seen, mut puts) = (0, 0);
    while seen < added {
        assert!(Instant::now() < deadline, "no Added events");
        let spawn = Spawn {
            bodies: vec![random_brick(rng)],
        };
        let tilt = Tilt::Accelerometer {
            x: rng.f(-5.0, 5.0),
            y: -9.0,
            z: 0.0,
        };
        for (key, payload) in [
            (keys.spawn(), encode(&spawn).unwrap()),
            (keys.tilt(), encode(&tilt).unwrap()),
        ] {
            session.put(key, payload).await.unwrap();
            puts += 1;
        }
        if let Ok(Some(e)) = tokio::time::timeout(Duration::from_millis(150), events.recv()).await {
            if matches!(e.kind, EventKind::Added { .. }) {
                seen += 1;
            }
        }
    }
    puts
}

/// The next message from `rx` within [`WAIT`].
pub async fn next<M>(rx: &mut UnboundedReceiver<M>) -> M {
    tokio::time::timeout(WAIT, rx.recv())
        .await
        .expect("a message in time")
        .expect("the subscription is open")
}

/// The `…/scene` reply, asking again until one comes (within [`WAIT`]).
pub async fn query_scene(session: &Session, keys: &Keys) -> SceneState {
    let end = Instant::now() + WAIT;
    loop {
        assert!(Instant::now() < end, "no scene reply");
        let replies = session.get(keys.scene()).await.unwrap();
        if let Ok(Ok(reply)) = tokio::time::timeout(WAIT, replies.recv_async()).await {
            if let Ok(sample) = reply.into_result() {
                return decode::<SceneState>(&sample.payload().to_bytes()).unwrap();
            }
        }
    }
}

/// The daemon's tick loop, without Zenoh, on a thread of its own: commands from `rx`, every
/// output to `out`. Set the flag to stop it; joining returns the outputs and the summary.
pub fn spawn_loop<O: Outputs>(
    sim: Simulation,
    rx: Receiver<Incoming>,
    out: O,
    cfg: TickConfig,
) -> (Arc<AtomicBool>, JoinHandle<(O, RunSummary)>) {
    let stop = Arc::new(AtomicBool::new(false));
    let handle = {
        let stop = stop.clone();
        std::thread::spawn(move || run_loop(sim, rx, out, stop, cfg))
    };
    (stop, handle)
}
