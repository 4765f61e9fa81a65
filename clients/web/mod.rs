//! `tiltbox-web`: a gateway between a daemon's Zenoh keys and web pages.
//!
//! It is a Zenoh client of a running daemon, like `tiltbox-tilt` and `tiltbox-view`, and
//! serves one embedded page (HTML, JS and CSS compiled into the binary, no build step) and a
//! WebSocket at `/ws?world=NAME`. On that socket each binary frame is a tag byte and a
//! documented protocol payload ([`wire`]): snapshots, events, stats and the scene reply go
//! down, tilts, spawns (and, if allowed, gravity, remove, reset) come up, each decoded and
//! checked before it is put on Zenoh. HTTPS by default ([`tls`]), since browsers give motion
//! sensors to secure contexts only.
//!
//! The daemon never speaks HTTP: everything here is a client of it.

mod conn;
pub mod tls;
pub mod wire;

use crate::protocol::Keys;
use axum::extract::{Query, State, WebSocketUpgrade};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use std::collections::BTreeSet;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::net::TcpListener;
use tokio::sync::{watch, Notify};
use wire::Allow;

/// The page, embedded.
pub const PAGE_HTML: &str = include_str!("page/index.html");
/// The page's main module: the connection, the drawing and the controls.
pub const PAGE_JS: &str = include_str!("page/app.js");
/// The page's protocol module: decoders, encoders, the snapshot decoder, frame tags.
pub const PAGE_WIRE_JS: &str = include_str!("page/wire.js");
/// The page's world module: the world as the page knows it (the late join).
pub const PAGE_WORLD_JS: &str = include_str!("page/world.js");
/// The page's style sheet.
pub const PAGE_CSS: &str = include_str!("page/style.css");

/// The largest frame a page may send (the daemon's own payload limit is 64 KiB).
pub const MAX_FRAME_BYTES: usize = 65_537;

/// What can go wrong in the gateway.
#[derive(Debug, thiserror::Error)]
pub enum WebError {
    /// A bad option value, naming the flag.
    #[error("{0}")]
    Usage(String),
    /// Certificate generation or loading.
    #[error("tls: {0}")]
    Tls(String),
    /// Zenoh refused something.
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// Binding the listening socket, and the like.
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

/// Where the certificate comes from.
#[derive(Clone, Debug)]
pub enum TlsMode {
    /// A self-signed certificate made at start (for localhost, 127.0.0.1, the listening
    /// address and the machine's LAN address).
    SelfSigned,
    /// PEM files.
    Files {
        /// Certificate chain, leaf first.
        cert: PathBuf,
        /// Private key.
        key: PathBuf,
    },
    /// Plain HTTP, for a TLS-terminating reverse proxy in front (motion sensors then need
    /// the proxy's HTTPS, or `localhost`).
    Off,
}

/// How the gateway runs.
#[derive(Clone, Debug)]
pub struct WebOptions {
    /// Address to listen on (default 127.0.0.1:8443).
    pub listen: SocketAddr,
    /// TLS.
    pub tls: TlsMode,
    /// Commands pages may send.
    pub allow: Allow,
    /// Per-connection limit on commands a second (tilts included).
    pub rate: u32,
    /// The world a page gets when it names none.
    pub keys: Keys,
    /// True when `--prefix` was given: pages cannot pick another world.
    pub fixed_prefix: bool,
}

/// Counters over the gateway's life, for logs and measurements.
#[derive(Debug, Default)]
pub struct Counters {
    /// Pages connected now.
    pub pages: AtomicU64,
    /// Pages ever connected.
    pub pages_total: AtomicU64,
    /// Binary frames sent to pages.
    pub frames_out: AtomicU64,
    /// Bytes of binary frames sent to pages.
    pub bytes_out: AtomicU64,
    /// Snapshot frames dropped because a page's queue was full.
    pub dropped: AtomicU64,
    /// Commands put on Zenoh.
    pub commands: AtomicU64,
    /// Frames from pages refused.
    pub refused: AtomicU64,
}

impl Counters {
    fn add(c: &AtomicU64, n: u64) {
        c.fetch_add(n, Ordering::Relaxed);
    }
    /// Read one counter.
    pub fn get(c: &AtomicU64) -> u64 {
        c.load(Ordering::Relaxed)
    }
}

/// Shared by every connection.
struct Ctx {
    session: zenoh::Session,
    opts: WebOptions,
    worlds: watch::Receiver<Vec<String>>,
    counters: Arc<Counters>,
}

/// A running gateway. Dropping it does not stop it: call [`Gateway::stop`].
pub struct Gateway {
    addr: SocketAddr,
    url: String,
    fingerprint: Option<String>,
    cert_pem: Option<String>,
    counters: Arc<Counters>,
    stop: Arc<Notify>,
    task: tokio::task::JoinHandle<()>,
}

impl Gateway {
    /// Bind, make or load the certificate, watch the live worlds and start serving.
    pub async fn start(session: zenoh::Session, opts: WebOptions) -> Result<Gateway, WebError> {
        let listener = TcpListener::bind(opts.listen)
            .await
            .map_err(|e| WebError::Usage(format!("--listen {}: {e}", opts.listen)))?;
        let addr = listener.local_addr()?;
        let host = url_host(addr);
        let (acceptor, fingerprint, cert_pem) = match &opts.tls {
            TlsMode::Off => (None, None, None),
            mode => {
                let id = match mode {
                    TlsMode::Files { cert, key } => tls::Identity::from_files(cert, key)?,
                    _ => {
                        let mut names = vec!["localhost".to_string(), "127.0.0.1".to_string()];
                        for ip in [Some(addr.ip()), lan_ip()].into_iter().flatten() {
                            if !ip.is_unspecified() && !names.contains(&ip.to_string()) {
                                names.push(ip.to_string());
                            }
                        }
                        tls::Identity::self_signed(&names)?
                    }
                };
                let fp = id.fingerprint();
                let pem = id.pem.clone();
                let cfg = id.server_config()?;
                (Some(tokio_rustls::TlsAcceptor::from(cfg)), Some(fp), pem)
            }
        };
        let scheme = if acceptor.is_some() { "https" } else { "http" };
        let url = format!("{scheme}://{host}/");

        // The live worlds, from the daemons' liveliness tokens.
        let (wtx, wrx) = watch::channel(Vec::new());
        let live = Arc::new(Mutex::new(BTreeSet::new()));
        let liveliness = session
            .liveliness()
            .declare_subscriber("tiltbox/*/server")
            .history(true)
            .callback(move |sample| {
                let key = sample.key_expr().as_str();
                let Some(world) = key
                    .strip_prefix("tiltbox/")
                    .and_then(|k| k.strip_suffix("/server"))
                else {
                    return;
                };
                let mut set = live.lock().unwrap_or_else(|p| p.into_inner());
                if sample.kind() == zenoh::sample::SampleKind::Put {
                    set.insert(world.to_string());
                } else {
                    set.remove(world);
                }
                let _ = wtx.send(set.iter().cloned().collect());
            })
            .await
            .map_err(|e| WebError::Zenoh(format!("liveliness subscriber: {e}")))?;

        let counters = Arc::new(Counters::default());
        let ctx = Arc::new(Ctx {
            session,
            opts,
            worlds: wrx,
            counters: counters.clone(),
        });
        let app = Router::new()
            .route(
                "/",
                get(|| async { page(PAGE_HTML, "text/html; charset=utf-8") }),
            )
            .route(
                "/app.js",
                get(|| async { page(PAGE_JS, "text/javascript; charset=utf-8") }),
            )
            .route(
                "/wire.js",
                get(|| async { page(PAGE_WIRE_JS, "text/javascript; charset=utf-8") }),
            )
            .route(
                "/world.js",
                get(|| async { page(PAGE_WORLD_JS, "text/javascript; charset=utf-8") }),
            )
            .route(
                "/style.css",
                get(|| async { page(PAGE_CSS, "text/css; charset=utf-8") }),
            )
            .route("/ws", get(ws_handler))
            .with_state(ctx);
        let stop = Arc::new(Notify::new());
        let stopped = stop.clone();
        let task = tokio::spawn(async move {
            let _liveliness = liveliness;
            loop {
                let (tcp, peer) = tokio::select! {
                    _ = stopped.notified() => break,
                    r = listener.accept() => match r {
                        Ok(x) => x,
                        Err(e) => {
                            tracing::warn!("accept: {e}");
                            tokio::time::sleep(Duration::from_millis(50)).await;
                            continue;
                        }
                    },
                };
                let _ = tcp.set_nodelay(true);
                let app = app.clone();
                let acceptor = acceptor.clone();
                tokio::spawn(async move {
                    match acceptor {
                        Some(a) => {
                            match tokio::time::timeout(Duration::from_secs(10), a.accept(tcp)).await
                            {
                                Ok(Ok(tls)) => serve_http(tls, app).await,
                                Ok(Err(e)) => tracing::debug!("{peer}: TLS handshake: {e}"),
                                Err(_) => tracing::debug!("{peer}: TLS handshake timed out"),
                            }
                        }
                        None => serve_http(tcp, app).await,
                    }
                });
            }
        });
        Ok(Gateway {
            addr,
            url,
            fingerprint,
            cert_pem,
            counters,
            stop,
            task,
        })
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's URL (with the LAN address when listening on all interfaces).
    pub fn url(&self) -> &str {
        &self.url
    }

    /// SHA-256 fingerprint of the certificate (None with TLS off).
    pub fn fingerprint(&self) -> Option<&str> {
        self.fingerprint.as_deref()
    }

    /// The generated certificate in PEM (None when loaded from files or with TLS off).
    pub fn certificate_pem(&self) -> Option<&str> {
        self.cert_pem.as_deref()
    }

    /// The counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// Stop accepting; connections already open end with their page.
    pub async fn stop(self) {
        self.stop.notify_one();
        let _ = self.task.await;
    }
}

fn page(body: &'static str, content_type: &'static str) -> Response {
    (
        [
            (header::CONTENT_TYPE, content_type),
            (header::CACHE_CONTROL, "no-store"),
        ],
        body,
    )
        .into_response()
}

#[derive(serde::Deserialize)]
struct WsQuery {
    world: Option<String>,
}

async fn ws_handler(
    ws: WebSocketUpgrade,
    Query(q): Query<WsQuery>,
    State(ctx): State<Arc<Ctx>>,
) -> Response {
    let keys = match q.world.as_deref() {
        Some(w) if !ctx.opts.fixed_prefix && !w.is_empty() => {
            if w.contains(['/', '*', '$', '?', '#']) {
                return (axum::http::StatusCode::BAD_REQUEST, "bad world name").into_response();
            }
            match Keys::for_world(w) {
                Ok(k) => k,
                Err(_) => {
                    return (axum::http::StatusCode::BAD_REQUEST, "bad world name").into_response()
                }
            }
        }
        _ => ctx.opts.keys.clone(),
    };
    ws.max_message_size(MAX_FRAME_BYTES)
        .max_frame_size(MAX_FRAME_BYTES)
        .on_upgrade(move |socket| conn::run(socket, ctx, keys))
}

async fn serve_http<I>(io: I, app: Router)
where
    I: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin + Send + 'static,
{
    let svc = hyper_util::service::TowerToHyperService::new(app);
    let conn = hyper::server::conn::http1::Builder::new()
        .serve_connection(hyper_util::rt::TokioIo::new(io), svc)
        .with_upgrades();
    if let Err(e) = conn.await {
        tracing::debug!("http connection: {e}");
    }
}

/// The host part of the URL: the LAN address when listening on all interfaces.
fn url_host(addr: SocketAddr) -> String {
    let ip = if addr.ip().is_unspecified() {
        lan_ip().unwrap_or(IpAddr::V4(Ipv4Addr::LOCALHOST))
    } else {
        addr.ip()
    };
    SocketAddr::new(ip, addr.port()).to_string()
}

/// The address this machine would use towards the LAN (no packet is sent: connecting a UDP
/// socket only picks a route).
pub fn lan_ip() -> Option<IpAddr> {
    let s = std::net::UdpSocket::bind("0.0.0.0:0").ok()?;
    s.connect("192.0.2.1:9").ok()?;
    let ip = s.local_addr().ok()?.ip();
    (!ip.is_unspecified() && !ip.is_loopback()).then_some(ip)
}

/// A QR code of `text` for a terminal: two modules per character cell (half blocks), light
/// on dark, with its quiet zone.
pub fn qr_text(text: &str) -> Option<String> {
    use qrcode::render::unicode::Dense1x2;
    let code = qrcode::QrCode::new(text.as_bytes()).ok()?;
    Some(
        code.render::<Dense1x2>()
            .dark_color(Dense1x2::Light)
            .light_color(Dense1x2::Dark)
            .quiet_zone(true)
            .build(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_qr_code_is_square_text() {
        let q = qr_text("https://192.168.1.20:8443/").unwrap();
        let lines: Vec<_> = q.lines().collect();
        let w = lines[0].chars().count();
        assert!(w >= 25, "{w}");
        assert!(lines.iter().all(|l| l.chars().count() == w));
        assert_eq!(lines.len(), w.div_ceil(2));
    }

    #[test]
    fn the_page_is_embedded_and_names_its_parts() {
        assert!(PAGE_HTML.contains("app.js") && PAGE_HTML.contains("style.css"));
        assert!(PAGE_JS.contains("from './wire.js'") && PAGE_JS.contains("from './world.js'"));
        assert!(PAGE_WIRE_JS.contains("function decodeFrame"));
        assert!(PAGE_WORLD_JS.contains("function applyScene"));
    }
}
