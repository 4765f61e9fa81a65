//! Opening a Zenoh session towards a daemon and watching the daemon's liveliness token.
//!
//! Clients run as Zenoh peers that connect to the given endpoints and listen on nothing, with
//! multicast scouting off. In peer mode an endpoint that is not up yet is retried in the
//! background (every 250 ms, backing off to 1 s), so a client can start before its daemon and
//! say "waiting for server" meanwhile; the same holds when the daemon restarts.

use super::ClientError;
use crate::protocol::Keys;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use zenoh::pubsub::Subscriber;
use zenoh::sample::SampleKind;
use zenoh::Session;

/// The endpoint clients connect to when none is given.
pub const DEFAULT_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// The Zenoh configuration of a client: peer mode, `connect` endpoints, no listening, no
/// multicast scouting, quick reconnection.
pub fn client_config(connect: &[String]) -> Result<zenoh::Config, ClientError> {
    for e in connect {
        let ok = e
            .split_once('/')
            .is_some_and(|(proto, addr)| !proto.is_empty() && !addr.is_empty());
        if !ok || e.contains(['"', '\\']) {
            return Err(ClientError::Usage(format!(
                "--connect {e:?}: not a Zenoh endpoint such as \"tcp/127.0.0.1:7447\""
            )));
        }
    }
    let list: Vec<String> = connect.iter().map(|e| format!("\"{e}\"")).collect();
    let mut c = zenoh::Config::default();
    let set = |c: &mut zenoh::Config, key: &str, value: &str| {
        c.insert_json5(key, value)
            .map_err(|e| ClientError::Usage(format!("zenoh config {key} = {value}: {e}")))
    };
    set(&mut c, "mode", "\"peer\"")?;
    set(
        &mut c,
        "connect/endpoints",
        &format!("[{}]", list.join(",")),
    )?;
    set(&mut c, "listen/endpoints", "[]")?;
    set(&mut c, "scouting/multicast/enabled", "false")?;
    set(
        &mut c,
        "connect/retry",
        "{ period_init_ms: 250, period_max_ms: 1000, period_increase_factor: 2 }",
    )?;
    Ok(c)
}

/// Open a client session towards `connect`. Returns at once even if no daemon is up.
pub async fn open(connect: &[String]) -> Result<Session, ClientError> {
    let config = client_config(connect)?;
    zenoh::open(config)
        .await
        .map_err(ClientError::zenoh("cannot open a Zenoh session"))
}

/// Whether a daemon's liveliness token (`…/server`) is visible, kept up to date by a
/// liveliness subscriber. Dropping it undeclares the subscriber.
pub struct ServerWatch {
    alive: Arc<AtomicBool>,
    _subscriber: Subscriber<()>,
}

impl ServerWatch {
    /// True while a daemon serves this world.
    pub fn is_alive(&self) -> bool {
        self.alive.load(Ordering::Relaxed)
    }
}

/// Watch `…/server`; `on_change(alive)` runs on Zenoh's thread at every appearance or
/// disappearance of the token (also for one already there): it must not block.
pub async fn watch_server(
    session: &Session,
    keys: &Keys,
    on_change: impl Fn(bool) + Send + Sync + 'static,
) -> Result<ServerWatch, ClientError> {
    let alive = Arc::new(AtomicBool::new(false));
    let flag = alive.clone();
    let subscriber = session
        .liveliness()
        .declare_subscriber(keys.server())
        .history(true)
        .callback(move |sample| {
            let up = sample.kind() == SampleKind::Put;
            flag.store(up, Ordering::Relaxed);
            on_change(up);
        })
        .await
        .map_err(ClientError::zenoh("liveliness subscriber"))?;
    Ok(ServerWatch {
        alive,
        _subscriber: subscriber,
    })
}
