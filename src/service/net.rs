//! The Zenoh side of the daemon: one session, the command subscribers (callbacks that only
//! decode, validate and `try_send`), the publishers, the `…/scene` queryable and the liveliness
//! token. The tick thread is started here and stopped by [`Server::shutdown`].

use super::checkpoint::{self, Checkpointer};
use super::command::{Incoming, Intake};
use super::config::Limits;
use super::config::{ConfigError, ServerConfig};
use super::journal::JournalWriter;
use super::sim::{SceneSource, StartError};
use super::tick::{self, Outputs, Recording, RunSummary, Shared, TickConfig};
use super::wire::check_query;
use super::world_query::{WorldQueries, MAX_PENDING};
use crate::physics::WorkerPool;
use crate::protocol::RateLimit;
use crate::protocol::{decode, encode, CommandKey, Keys, QueryAnswer, WorldQuery};
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::sync_channel;
use std::sync::Arc;
use std::time::Duration;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::query::{Query, Queryable};
use zenoh::{Session, Wait};

/// Why the daemon could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The scene could not be loaded.
    #[error(transparent)]
    Start(#[from] StartError),
    /// Zenoh refused (e.g. the listen port is taken).
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// The command journal could not be created.
    #[error("journal: {0}")]
    Record(String),
    /// The tick thread could not be started or panicked.
    #[error("tick thread: {0}")]
    Thread(String),
}

fn zerr(what: &str) -> impl FnOnce(zenoh::Error) -> ServiceError + '_ {
    move |e| ServiceError::Zenoh(format!("{what}: {}", without_source_paths(&e.to_string())))
}

/// Zenoh's message without the ` at /path/to/file.rs:LINE.` locations it appends (paths of
/// the machine that built the binary, meaningless to its user).
fn without_source_paths(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(i) = rest.find(" at /") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 4..];
        let end = after.find(".rs:").map(|j| {
            let digits = after[j + 4..]
                .bytes()
                .take_while(u8::is_ascii_digit)
                .count();
            let dot = usize::from(after[j + 4 + digits..].starts_with('.'));
            j + 4 + digits + dot
        });
        match end {
            Some(end) => rest = &after[end..],
            None => {
                out.push_str(" at ");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out.trim_end().to_owned()
}

/// Why the session could not be opened: a listen endpoint that cannot be bound is a bad
/// value (exit 2) named with the config key or flag that chose it; anything else is Zenoh's.
fn open_error(config: &ServerConfig, e: zenoh::Error) -> ServiceError {
    let reason = without_source_paths(&e.to_string());
    if !reason.contains("listener") {
        return ServiceError::Zenoh(format!("cannot open session: {reason}"));
    }
    let z = &config.zenoh;
    ServiceError::Config(match &z.config_file {
        Some(path) => ConfigError::Invalid {
            key: "zenoh.config_file",
            value: path.display().to_string(),
            expected: format!("its listen endpoint cannot be used: {reason}"),
        },
        None => ConfigError::Invalid {
            key: "zenoh.listen",
            value: format!("{:?}", z.listen),
            expected: format!(
                "cannot listen there (flag --listen or config key zenoh.listen chose it; \
                 another process may hold the port): {reason}"
            ),
        },
    })
}

/// A hook called with the frame number just before each snapshot is put (benchmarks).
pub type PublishHook = Arc<dyn Fn(u64) + Send + Sync>;

/// Extra knobs for embedding the daemon (tests, benchmarks).
#[derive(Clone, Default)]
pub struct ServerOptions {
    /// Where the scene comes from; `None` means the config's `scene` (or the embedded one).
    pub source: Option<SceneSource>,
    /// Keep every tick's lateness and step time for the [`RunSummary`].
    pub record: bool,
    /// Called just before each snapshot is put.
    pub on_publish: Option<PublishHook>,
    /// The workers this world's steps share with other worlds; `None`: a pool of the
    /// config's `workers` is started for it (none for 1). [`start_worlds`] starts one for
    /// all its worlds.
    pub workers: Option<WorkerPool>,
}

struct ZenohOutputs {
    poses: Publisher<'static>,
    tx: tokio::sync::mpsc::Sender<Vec<u8>>,
    stats_tx: tokio::sync::mpsc::Sender<Vec<u8>>,
    on_publish: Option<PublishHook>,
}

impl ZenohOutputs {
    fn queue(tx: &tokio::sync::mpsc::Sender<Vec<u8>>, what: &str, payload: Vec<u8>) {
        if tx.try_send(payload).is_err() {
            tracing::warn!("{what} dropped: its publisher task is behind or gone");
        }
    }
}

impl Outputs for ZenohOutputs {
    fn poses(&mut self, frame: u64, payload: Vec<u8>) {
        if let Some(hook) = &self.on_publish {
            hook(frame);
        }
        // CongestionControl::Drop: never blocks the loop.
        if let Err(e) = self.poses.put(payload).wait() {
            tracing::warn!(frame, "snapshot not published: {e}");
        }
    }
    fn event(&mut self, payload: Vec<u8>) {
        Self::queue(&self.tx, "event", payload);
    }
    fn stats(&mut self, payload: Vec<u8>) {
        Self::queue(&self.stats_tx, "stats", payload);
    }
}

/// A running daemon. Stop it with [`Server::shutdown`].
pub struct Server {
    session: Session,
    owns_session: bool,
    keys: Keys,
    subscribers: Vec<Subscriber<()>>,
    queryable: Queryable<()>,
    /// `…/query`, and the task that answers it through the tick thread.
    world_queryable: Queryable<()>,
    world_query_task: tokio::task::JoinHandle<()>,
    token: LivelinessToken,
    stop: Arc<AtomicBool>,
    tick: std::thread::JoinHandle<(Recording<ZenohOutputs>, RunSummary)>,
    publisher_task: tokio::task::JoinHandle<()>,
    query_task: tokio::task::JoinHandle<()>,
}

impl Server {
    /// Validate `config`, load the scene, open the Zenoh session, declare everything and start
    /// the tick thread. Must be called inside a multi-thread tokio runtime.
    pub async fn start(
        config: &ServerConfig,
        options: ServerOptions,
    ) -> Result<Server, ServiceError> {
        Server::start_inner(None, config, options).await
    }

    /// Like [`Server::start`], but on an open session shared with other worlds (see
    /// [`start_worlds`]); the session's own settings apply and `config.zenoh` is ignored.
    /// [`Server::shutdown`] then leaves the session open.
    pub async fn start_on(
        session: &Session,
        config: &ServerConfig,
        options: ServerOptions,
    ) -> Result<Server, ServiceError> {
        Server::start_inner(Some(session.clone()), config, options).await
    }

    async fn start_inner(
        shared_session: Option<Session>,
        config: &ServerConfig,
        options: ServerOptions,
    ) -> Result<Server, ServiceError> {
        config.validate()?;
        let keys = config.keys()?;
        let source = options
            .source
            .clone()
            .unwrap_or_else(|| SceneSource::from_config(config));
        let (mut sim, resumed) = checkpoint::start(config, source.clone())?;
        sim.share_workers(match options.workers.clone() {
            Some(pool) => Some(pool),
            None => worker_pool(config)?,
        });
        let journal = match &config.record {
            Some(path) => Some(
                JournalWriter::create(path, config, &source, &sim, resumed)
                    .map_err(|e| ServiceError::Record(e.to_string()))?,
            ),
            None => None,
        };
        let checkpoints = match &config.checkpoint {
            Some(path) => {
                let every = (config.checkpoint_every * config.tick_hz).round().max(1.0) as u64;
                Some(
                    Checkpointer::new(path.clone(), every, sim.frame())
                        .map_err(|e| ServiceError::Thread(e.to_string()))?,
                )
            }
            None => None,
        };
        let owns_session = shared_session.is_none();
        let session = match shared_session {
            Some(s) => s,
            None => zenoh::open(config.zenoh_config()?)
                .await
                .map_err(|e| open_error(config, e))?,
        };

        let poses = session
            .declare_publisher(keys.poses())
            .congestion_control(CongestionControl::Drop)
            .express(true)
            .await
            .map_err(zerr("poses publisher"))?;
        let events = session
            .declare_publisher(keys.events())
            .congestion_control(CongestionControl::Drop)
            .await
            .map_err(zerr("events publisher"))?;
        let stats = session
            .declare_publisher(keys.stats())
            .await
            .map_err(zerr("stats publisher"))?;

        // Events and stats are put from tasks, so a congested link never blocks the loop; each
        // its own, so a burst of events queued behind a slow link does not hold the stats
        // back. (Events were put with `Block`, which waited up to 5 s for a stalled
        // subscriber's link and froze the whole session: see docs/reliability.md.)
        let (out_tx, mut out_rx) = tokio::sync::mpsc::channel::<Vec<u8>>(1024);
        let (stats_tx, mut stats_rx) = tokio::sync::mpsc::channel::<Vec<u8>>(4);
        let events_task = tokio::spawn(async move {
            while let Some(payload) = out_rx.recv().await {
                if let Err(e) = events.put(payload).await {
                    tracing::warn!("cannot publish on {}: {e}", events.key_expr());
                }
            }
            let _ = events.undeclare().await;
        });
        let stats_task = tokio::spawn(async move {
            while let Some(payload) = stats_rx.recv().await {
                if let Err(e) = stats.put(payload).await {
                    tracing::warn!("cannot publish on {}: {e}", stats.key_expr());
                }
            }
            let _ = stats.undeclare().await;
        });
        let publisher_task = tokio::spawn(async move {
            let _ = tokio::join!(events_task, stats_task);
        });

        // The channels between Zenoh callbacks and the tick thread.
        let capacity = config.command_queue;
        let (tx, rx) = sync_channel::<Incoming>(capacity as usize);
        let mut shared = Shared::default();
        let stop = Arc::new(AtomicBool::new(false));
        // The queryable: the callback only hands the query to a task, which asks the tick
        // thread for the state (built only then) and replies to every query that came in
        // meanwhile with it.
        let (qtx, mut qrx) = tokio::sync::mpsc::channel::<Query>(64);
        let scene_key = keys.scene();
        let query_task = {
            let scene_queries = shared.scene_queries.clone();
            let scene_key = scene_key.clone();
            tokio::spawn(async move {
                while let Some(first) = qrx.recv().await {
                    let mut queries = vec![first];
                    while let Ok(q) = qrx.try_recv() {
                        queries.push(q);
                    }
                    let Ok(state) = scene_queries.ask().await else {
                        continue; // the tick loop stopped
                    };
                    // `…/scene?joints` gets the joints too; a plain `…/scene` the state alone.
                    let (Ok(plain), Ok(with_joints)) = (encode(&state.scene), encode(&*state))
                    else {
                        tracing::error!("cannot encode the scene");
                        continue;
                    };
                    for query in queries {
                        let joints = query.parameters().contains_key("joints");
                        let payload = if joints { &with_joints } else { &plain };
                        if let Err(e) = query.reply(&scene_key, payload.clone()).await {
                            tracing::warn!("cannot reply to a scene query: {e}");
                        }
                    }
                }
            })
        };
        let queryable = session
            .declare_queryable(&scene_key)
            .callback(move |query: Query| {
                if qtx.try_send(query).is_err() {
                    tracing::warn!("scene query dropped: too many pending");
                }
            })
            .await
            .map_err(zerr("scene queryable"))?;

        let (world_queryable, world_query_task) = declare_world_queries(
            &session,
            keys.query(),
            shared.world_queries.clone(),
            config.limits.clone(),
        )
        .await?;

        // The command subscribers.
        let intake = Intake::new(tx, config.limits.clone(), shared.dropped.clone());
        shared.received = intake.received();
        let mut subscribers = Vec::new();
        for key in CommandKey::ALL {
            let intake = intake.clone();
            let sub = session
                .declare_subscriber(keys.command(key))
                .callback(move |sample| intake.handle(key, &sample.payload().to_bytes()))
                .await
                .map_err(zerr("command subscriber"))?;
            subscribers.push(sub);
        }
        // Hands whose client went away: their `…/hand/<hand>` liveliness token is deleted.
        let hand_intake = intake.clone();
        let hand_keys = keys.clone();
        let hands = session
            .liveliness()
            .declare_subscriber(keys.hands())
            .callback(move |sample| {
                if sample.kind() == zenoh::sample::SampleKind::Delete {
                    if let Some(hand) = hand_keys.hand_of(sample.key_expr().as_str()) {
                        hand_intake.hand_gone(hand);
                    }
                }
            })
            .await
            .map_err(zerr("hand liveliness subscriber"))?;
        subscribers.push(hands);
        drop(intake);

        let token = session
            .liveliness()
            .declare_token(keys.server())
            .await
            .map_err(zerr("liveliness token"))?;
        // Last, the tick thread: nothing after this can fail.
        let outputs = Recording {
            inner: ZenohOutputs {
                poses,
                tx: out_tx,
                stats_tx,
                on_publish: options.on_publish.clone(),
            },
            journal,
            checkpoints,
        };
        let tick_cfg = TickConfig::of(config, options.record);
        let tick = {
            let stop = stop.clone();
            std::thread::Builder::new()
                .name("tiltbox-tick".into())
                .spawn(move || tick::run_shared(sim, rx, shared, outputs, stop, tick_cfg))
                .map_err(|e| ServiceError::Thread(e.to_string()))?
        };

        tracing::info!(prefix = keys.prefix(), zid = %session.zid(), "serving");
        Ok(Server {
            session,
            owns_session,
            keys,
            subscribers,
            queryable,
            world_queryable,
            world_query_task,
            token,
            stop,
            tick,
            publisher_task,
            query_task,
        })
    }

    /// The keys this daemon serves.
    pub fn keys(&self) -> &Keys {
        &self.keys
    }

    /// The Zenoh session (e.g. to open a client on it in benchmarks).
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// Stop: undeclare the subscribers and the queryable, stop the tick thread after its
    /// current tick, flush events, undeclare the publishers and the token, close the session.
    pub async fn shutdown(self) -> Result<RunSummary, ServiceError> {
        for s in self.subscribers {
            let _ = s.undeclare().await;
        }
        let _ = self.queryable.undeclare().await;
        self.query_task.abort();
        let _ = self.world_queryable.undeclare().await;
        self.world_query_task.abort();
        let (session, stop, tick) = (self.session, self.stop, self.tick);
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        let joined = tokio::task::spawn_blocking(move || tick.join())
            .await
            .map_err(|e| ServiceError::Thread(e.to_string()))?;
        let (outputs, summary) =
            joined.map_err(|_| ServiceError::Thread("the tick thread panicked".into()))?;
        let ZenohOutputs {
            poses,
            tx,
            stats_tx,
            ..
        } = outputs.inner;
        drop((tx, stats_tx));
        let _ = poses.undeclare().await;
        if tokio::time::timeout(Duration::from_millis(500), self.publisher_task)
            .await
            .is_err()
        {
            tracing::warn!("events still queued at shutdown were dropped");
        }
        let _ = self.token.undeclare().await;
        if self.owns_session {
            match tokio::time::timeout(Duration::from_millis(1000), session.close()).await {
                Ok(Ok(())) => {}
                Ok(Err(e)) => tracing::warn!("closing the session: {e}"),
                Err(_) => tracing::warn!("closing the session took more than 1 s"),
            }
        }
        tracing::info!(frames = summary.frames, "stopped");
        Ok(summary)
    }
}

/// Declare `…/query`: the callback hands each query to a task, which decodes and checks it,
/// waits for the tick thread's answer (the World after the last step) and replies. A query
/// that cannot be decoded or checked, or finds the queue full, is answered `Refused` at once.
async fn declare_world_queries(
    session: &Session,
    key: String,
    queries: Arc<WorldQueries>,
    limits: Limits,
) -> Result<(Queryable<()>, tokio::task::JoinHandle<()>), ServiceError> {
    let (tx, mut rx) = tokio::sync::mpsc::channel::<Query>(MAX_PENDING);
    let reply_key = key.clone();
    let task = tokio::spawn(async move {
        let mut rate = RateLimit::new(limits.max_queries_per_second);
        // Every query that came in meanwhile is asked at once, so they share one tick.
        while let Some(first) = rx.recv().await {
            let mut batch = vec![first];
            while let Ok(q) = rx.try_recv() {
                batch.push(q);
            }
            let asked: Vec<_> = batch
                .into_iter()
                .map(|query| {
                    if !rate.take(std::time::Instant::now()) {
                        let reason = format!(
                            "rate limit: limits.max_queries_per_second = {} queries already \
                             answered in the last second",
                            rate.rate()
                        );
                        return (query, Err(reason));
                    }
                    let bytes = query
                        .payload()
                        .map(|p| p.to_bytes().to_vec())
                        .unwrap_or_default();
                    let waiting = decode::<WorldQuery>(&bytes)
                        .map_err(|e| e.to_string())
                        .and_then(|q| check_query(&q, &limits).map(|()| q))
                        .and_then(|q| queries.ask(q));
                    (query, waiting)
                })
                .collect();
            for (query, waiting) in asked {
                let answer = match waiting {
                    Ok(rx) => match rx.await {
                        Ok(a) => a,
                        Err(_) => return, // the tick loop stopped
                    },
                    Err(reason) => QueryAnswer::Refused { reason },
                };
                let Ok(payload) = encode(&answer) else {
                    continue;
                };
                if let Err(e) = query.reply(&reply_key, payload).await {
                    tracing::warn!("cannot reply to a world query: {e}");
                }
            }
        }
    });
    let queryable = session
        .declare_queryable(&key)
        .callback(move |query: Query| {
            if tx.try_send(query).is_err() {
                tracing::warn!("world query dropped: {MAX_PENDING} pending");
            }
        })
        .await
        .map_err(zerr("query queryable"))?;
    Ok((queryable, task))
}

/// The pool of `config.workers` threads (the tick thread among them) that a daemon's worlds
/// share; none for one.
fn worker_pool(config: &ServerConfig) -> Result<Option<WorkerPool>, ServiceError> {
    if config.workers <= 1 {
        return Ok(None);
    }
    WorkerPool::new(config.workers)
        .map(Some)
        .map_err(|e| ServiceError::Thread(format!("{} workers: {e}", config.workers)))
}

/// The config of each world a daemon serves: `config.world` first, then every name in
/// `config.worlds`, each with its own key prefix `tiltbox/<name>` (the first keeps
/// `config.prefix` if set) and, when recording or checkpointing, its own files
/// (`<file>.<name>` for the extra worlds). Scene, tick rate and limits are shared.
pub fn world_configs(config: &ServerConfig) -> Vec<ServerConfig> {
    let mut out = Vec::with_capacity(1 + config.worlds.len());
    let mut first = config.clone();
    first.worlds.clear();
    out.push(first);
    for name in &config.worlds {
        let suffixed = |p: &Option<std::path::PathBuf>| {
            p.as_ref().map(|p| {
                let mut s = p.as_os_str().to_owned();
                s.push(format!(".{name}"));
                std::path::PathBuf::from(s)
            })
        };
        let mut c = config.clone();
        c.worlds.clear();
        c.world = name.clone();
        c.prefix = None;
        c.record = suffixed(&config.record);
        c.checkpoint = suffixed(&config.checkpoint);
        out.push(c);
    }
    out
}

/// Serve every world of `config` (see [`world_configs`]) from one Zenoh session, each on its
/// own tick thread. Stop them with [`shutdown_worlds`]. With no extra worlds this is
/// [`Server::start`].
pub async fn start_worlds(
    config: &ServerConfig,
    options: ServerOptions,
) -> Result<Vec<Server>, ServiceError> {
    config.validate()?;
    if config.worlds.is_empty() {
        return Ok(vec![Server::start(config, options).await?]);
    }
    let mut options = options;
    if options.workers.is_none() {
        options.workers = worker_pool(config)?;
    }
    let session = zenoh::open(config.zenoh_config()?)
        .await
        .map_err(|e| open_error(config, e))?;
    let mut servers: Vec<Server> = Vec::new();
    for c in world_configs(config) {
        match Server::start_on(&session, &c, options.clone()).await {
            Ok(s) => servers.push(s),
            Err(e) => {
                let _ = shutdown_worlds(servers).await;
                let _ = session.close().await;
                return Err(e);
            }
        }
    }
    // The first world closes the shared session when it stops (it is stopped last).
    servers[0].owns_session = true;
    Ok(servers)
}

/// Stop the worlds started by [`start_worlds`] (the session's owner last).
pub async fn shutdown_worlds(servers: Vec<Server>) -> Result<Vec<RunSummary>, ServiceError> {
    let mut summaries = Vec::with_capacity(servers.len());
    let mut result = Ok(());
    for s in servers.into_iter().rev() {
        match s.shutdown().await {
            Ok(summary) => summaries.push(summary),
            Err(e) => result = Err(e),
        }
    }
    summaries.reverse();
    result.map(|()| summaries)
}
