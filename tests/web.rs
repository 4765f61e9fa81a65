//! tiltbox-web in a real browser: a daemon on Zenoh loopback, the gateway in process (HTTPS
//! with its self-signed certificate), and Debian's headless Chromium driven over the DevTools
//! protocol (CDP JSON over a plain WebSocket). Every assertion is on what the page did in the
//! browser or on what reached the daemon through it. Chromium missing is a failure, not a skip.
//!
//! Ports 17490-17494 (Zenoh). Browser tests run one at a time (a lock), so the figures they
//! print are not disturbed by each other.
#![cfg(feature = "web")]

mod common;

use common::net::{daemon_config, serve, subscribe, subscribe_snapshots};
use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tiltbox::client::session;
use tiltbox::client::web::wire::Allow;
use tiltbox::client::web::{Gateway, TlsMode, WebOptions};
use tiltbox::protocol::*;
use tiltbox::service::Server;
use tokio::sync::mpsc;
use tokio_tungstenite::tungstenite::Message as WsMessage;

static BROWSER_LOCK: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

// ------------------------------------------------------------------------------------------
// Chromium and a minimal CDP client.

struct Browser {
    child: Child,
    dir: PathBuf,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn chromium_path() -> PathBuf {
    for p in ["/usr/bin/chromium", "/usr/bin/chromium-browser"] {
        if Path::new(p).exists() {
            return p.into();
        }
    }
    panic!(
        "Chromium is not installed (/usr/bin/chromium): the web tests need a real browser; \
         `apt-get install -y chromium` (.ci/run does it)"
    );
}

/// Start headless Chromium with a fresh profile; returns it and its DevTools WebSocket URL.
async fn launch(tag: &str) -> (Browser, String) {
    let dir = std::env::temp_dir().join(format!("tiltbox-web-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let child = Command::new(chromium_path())
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-dev-shm-usage",
            "--hide-scrollbars",
            "--mute-audio",
            "--window-size=800,600",
            "--remote-debugging-port=0",
            "--remote-allow-origins=*",
        ])
        .arg(format!("--user-data-dir={}", dir.display()))
        .arg("about:blank")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chromium");
    let browser = Browser { child, dir };
    let file = browser.dir.join("DevToolsActivePort");
    let end = Instant::now() + Duration::from_secs(30);
    loop {
        if let Ok(s) = std::fs::read_to_string(&file) {
            let mut lines = s.lines();
            if let (Some(port), Some(path)) = (lines.next(), lines.next()) {
                return (browser, format!("ws://127.0.0.1:{port}{path}"));
            }
        }
        assert!(Instant::now() < end, "chromium wrote no DevToolsActivePort");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

struct Cdp {
    ws: Ws,
    next: u64,
    events: VecDeque<Value>,
    session: Option<String>,
}

impl Cdp {
    async fn connect(url: &str) -> Cdp {
        let (ws, _) = tokio_tungstenite::connect_async(url)
            .await
            .expect("DevTools WebSocket");
        Cdp {
            ws,
            next: 1,
            events: VecDeque::new(),
            session: None,
        }
    }

    /// A command to the page's session (or the browser before one is attached).
    async fn call(&mut self, method: &str, params: Value) -> Result<Value, Value> {
        let session = self.session.clone();
        self.call_on(session.as_deref(), method, params).await
    }

    async fn call_on(
        &mut self,
        session: Option<&str>,
        method: &str,
        params: Value,
    ) -> Result<Value, Value> {
        let id = self.next;
        self.next += 1;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if let Some(s) = session {
            msg["sessionId"] = json!(s);
        }
        self.ws
            .send(WsMessage::Text(msg.to_string().into()))
            .await
            .expect("CDP send");
        let end = Instant::now() + Duration::from_secs(30);
        loop {
            let left = end.saturating_duration_since(Instant::now());
            let m = tokio::time::timeout(left, self.ws.next())
                .await
                .unwrap_or_else(|_| panic!("CDP {method}: no answer in 30 s"))
                .expect("CDP closed")
                .expect("CDP read");
            let WsMessage::Text(t) = m else { continue };
            let v: Value = serde_json::from_str(t.as_str()).unwrap();
            if v["id"] == json!(id) {
                return match v.get("error") {
                    Some(e) => Err(e.clone()),
                    None => Ok(v["result"].clone()),
                };
            }
            if v.get("method").is_some() {
                self.events.push_back(v);
                if self.events.len() > 1000 {
                    self.events.pop_front();
                }
            }
        }
    }

    /// Open a tab, attach to it (flat session), and enable what the tests use.
    async fn open_page(url: &str) -> Cdp {
        let mut cdp = Cdp::connect(url).await;
        // the gateway's self-signed certificate is accepted for this test's browser only
        cdp.call(
            "Security.setIgnoreCertificateErrors",
            json!({"ignore": true}),
        )
        .await
        .expect("Security.setIgnoreCertificateErrors");
        let t = cdp
            .call("Target.createTarget", json!({"url": "about:blank"}))
            .await
            .unwrap();
        let a = cdp
            .call(
                "Target.attachToTarget",
                json!({"targetId": t["targetId"], "flatten": true}),
            )
            .await
            .unwrap();
        cdp.session = Some(a["sessionId"].as_str().unwrap().to_string());
        cdp.call("Page.enable", json!({})).await.unwrap();
        cdp.call("Runtime.enable", json!({})).await.unwrap();
        cdp
    }

    /// Evaluate JS in the page (promises awaited); the value, or a panic with the exception.
    async fn eval(&mut self, expr: &str) -> Value {
        let r = self
            .call(
                "Runtime.evaluate",
                json!({"expression": expr, "returnByValue": true, "awaitPromise": true}),
            )
            .await
            .unwrap_or_else(|e| panic!("evaluate {expr}: {e}"));
        if let Some(ex) = r.get("exceptionDetails") {
            panic!("evaluate {expr}: {ex}");
        }
        r["result"]["value"].clone()
    }

    /// Poll `expr` until it is true.
    async fn wait_for(&mut self, expr: &str, secs: u64) {
        let end = Instant::now() + Duration::from_secs(secs);
        while self.eval(expr).await != json!(true) {
            assert!(
                Instant::now() < end,
                "page: `{expr}` not true after {secs} s"
            );
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }

    async fn navigate(&mut self, url: &str) {
        let r = self
            .call("Page.navigate", json!({"url": url}))
            .await
            .unwrap();
        assert!(
            r.get("errorText").is_none(),
            "navigating to {url}: {}",
            r["errorText"]
        );
    }
}

// ------------------------------------------------------------------------------------------
// The daemon, the gateway, and a test session watching the daemon.

/// A fresh Chromium (`tag` names its profile) with one blank page open.
async fn browser_page(tag: &str) -> (Browser, Cdp) {
    let (browser, devtools) = launch(tag).await;
    (browser, Cdp::open_page(&devtools).await)
}

/// A fresh Chromium's page (`tag` names its profile) on the gateway's page, once it has
/// joined its world and drawn a frame.
async fn joined_page(tag: &str, gw: &Gateway) -> (Browser, Cdp) {
    let (browser, mut page) = browser_page(tag).await;
    page.navigate(gw.url()).await;
    page.wait_for(
        "!!(window.tiltbox && tiltbox.state.joined && tiltbox.state.frame > 0)",
        20,
    )
    .await;
    (browser, page)
}

/// Close the page, then stop the gateway, then the daemon.
async fn stop(page: Cdp, gw: Gateway, server: Server) {
    drop(page);
    gw.stop().await;
    server.shutdown().await.unwrap();
}

async fn daemon(port: u16) -> Server {
    serve(&daemon_config(port)).await
}

/// A daemon on `port` and the gateway towards it, tilts and spawns allowed.
async fn daemon_and_gateway(port: u16) -> (Server, Gateway) {
    let server = daemon(port).await;
    (server, gateway(port, "tilt,spawn").await)
}

async fn gateway(port: u16, allow: &str) -> Gateway {
    gateway_at_rate(port, allow, 60).await
}

/// [`gateway`] letting each page send `rate` commands a second.
async fn gateway_at_rate(port: u16, allow: &str, rate: u32) -> Gateway {
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    Gateway::start(
        s,
        WebOptions {
            listen: "127.0.0.1:0".parse().unwrap(),
            tls: TlsMode::SelfSigned,
            allow: Allow::parse(allow).unwrap(),
            rate,
            keys: Keys::for_world(DEFAULT_WORLD).unwrap(),
            fixed_prefix: false,
        },
    )
    .await
    .expect("gateway starts")
}

/// A gateway serving plain `ws://` (no TLS) toward the daemon on `port`, for WebSocket
/// clients in this process: the default world, `allow`, `rate` commands a second per page.
async fn plain_gateway(port: u16, allow: Allow, rate: u32) -> Gateway {
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    Gateway::start(
        s,
        WebOptions {
            listen: "127.0.0.1:0".parse().unwrap(),
            tls: TlsMode::Off,
            allow,
            rate,
            keys: Keys::for_world(DEFAULT_WORLD).unwrap(),
            fixed_prefix: false,
        },
    )
    .await
    .expect("gateway starts")
}

/// Decoded snapshots and events seen by the test's own Zenoh session.
struct Watch {
    snaps: mpsc::UnboundedReceiver<Snapshot>,
    events: mpsc::UnboundedReceiver<Event>,
    _subs: Vec<zenoh::pubsub::Subscriber<()>>,
}

async fn watch(s: &zenoh::Session, keys: &Keys) -> Watch {
    let (snaps, a) = subscribe_snapshots(s, keys.poses()).await;
    let (events, b) = subscribe::<Event>(s, keys.events()).await;
    Watch {
        snaps,
        events,
        _subs: vec![a, b],
    }
}

impl Watch {
    /// Wait for a snapshot whose gravity is within 0.05 of `g`.
    async fn gravity(&mut self, g: (f32, f32), secs: u64) -> Snapshot {
        let end = Instant::now() + Duration::from_secs(secs);
        loop {
            let left = end.saturating_duration_since(Instant::now());
            let s = tokio::time::timeout(left, self.snaps.recv())
                .await
                .unwrap_or_else(|_| panic!("daemon's gravity never became {g:?}"))
                .unwrap();
            if (s.gravity.x - g.0).abs() < 0.05 && (s.gravity.y - g.1).abs() < 0.05 {
                return s;
            }
        }
    }

    /// Wait until the world is still: `n` snapshots in a row in which no body moved more than
    /// [`STILL`] since its last pose (a body that falls asleep is no longer sent, which counts
    /// as still). Still, not asleep: the pixel checks need bodies where their poses say, and
    /// some tilt histories leave a stack of bricks rocking at a few cm/s without sleeping (of
    /// 100 simulated histories of this test's tilts and clicks, 3 to 9 took over 13 s to
    /// sleep and a few never did, with adaptive stiffness on or off), which moves a body's
    /// centre by about a millimetre a frame.
    async fn settled(&mut self, n: usize, secs: u64) -> Result<(), String> {
        let end = Instant::now() + Duration::from_secs(secs);
        let mut last: std::collections::HashMap<BodyRef, (f32, f32, f32)> =
            std::collections::HashMap::new();
        let mut quiet = 0;
        let mut fastest = (0.0f32, None);
        while quiet < n {
            let left = end.saturating_duration_since(Instant::now());
            let Ok(s) = tokio::time::timeout(left, self.snaps.recv()).await else {
                return Err(format!(
                    "not still after {secs} s: body {:?} moved {:.1} mm in one snapshot",
                    fastest.1,
                    fastest.0 * 1000.0
                ));
            };
            let s = s.unwrap();
            let mut still = true;
            fastest = (0.0, None);
            for p in &s.poses {
                // Angles are sent within [-pi, pi): a turn across the cut is not a jump.
                let moved = last.insert(p.id, (p.x, p.y, p.angle)).map(|(x, y, a)| {
                    let pi = std::f32::consts::PI;
                    let turn = (p.angle - a + pi).rem_euclid(2.0 * pi) - pi;
                    (p.x - x).hypot(p.y - y) + 0.5 * turn.abs()
                });
                if let Some(d) = moved {
                    if d > fastest.0 {
                        fastest = (d, Some(p.id));
                    }
                }
                if !matches!(moved, Some(d) if d <= STILL) {
                    still = false;
                }
            }
            quiet = if still { quiet + 1 } else { 0 };
        }
        Ok(())
    }
}

/// How far a body may move between two snapshots and count as still (m, with turns counted
/// at 0.5 m per radian, the size of the bricks): 2 mm, 0.12 m/s at 60 Hz. The pixels checked
/// are inside bodies at least 0.36 m across.
const STILL: f32 = 0.002;

async fn scene(s: &zenoh::Session, keys: &Keys) -> SceneState {
    tiltbox::client::view::query_scene(s, keys.scene())
        .await
        .expect("scene reply")
}

/// The page's documented fit (clients/web/page/app.js, `view`): the static bodies'
/// bounding box fitted into the canvas at 94 % of the tighter side, centred.
fn fit(scene: &SceneState, w: f64, h: f64) -> impl Fn(f32, f32) -> (f64, f64) {
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for b in scene.bodies.iter().filter(|b| b.is_static) {
        let ShapeSpec::Rect { width, height } = b.shape else {
            panic!("the test scene's walls are rectangles")
        };
        let (c, s) = ((b.angle as f64).cos(), (b.angle as f64).sin());
        for (dx, dy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let (px, py) = (dx * width as f64 / 2.0, dy * height as f64 / 2.0);
            let x = b.position.x as f64 + c * px - s * py;
            let y = b.position.y as f64 + s * px + c * py;
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
    }
    let scale = (w / (x1 - x0)).min(h / (y1 - y0)) * 0.94;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    move |x, y| {
        (
            w / 2.0 + scale * (x as f64 - cx),
            h / 2.0 - scale * (y as f64 - cy),
        )
    }
}

/// Each dynamic body of the daemon's current scene is drawn in its colour at its centre of
/// mass (the canvas read back in the page); returns the scene and how many were checked, or
/// the first body whose pixel is wrong.
async fn check_pixels(
    page: &mut Cdp,
    s: &zenoh::Session,
    keys: &Keys,
) -> Result<(SceneState, usize), String> {
    let sc = scene(s, keys).await;
    let size = page
        .eval("[document.getElementById('world').clientWidth, document.getElementById('world').clientHeight]")
        .await;
    let to_px = fit(&sc, size[0].as_f64().unwrap(), size[1].as_f64().unwrap());
    let mut checked = 0;
    for b in sc.bodies.iter().filter(|b| !b.is_static) {
        let (px, py) = to_px(b.position.x, b.position.y);
        let got = page.eval(&format!("tiltbox.pixel({px}, {py})")).await;
        if !close(&got, b.colour) {
            return Err(format!(
                "{} {} ({:?}) at ({}, {}) -> pixel ({px:.0}, {py:.0}) is {got}, expected {:?}",
                b.id, b.name, b.shape, b.position.x, b.position.y, b.colour
            ));
        }
        checked += 1;
    }
    Ok((sc, checked))
}

/// Once the world is still, every dynamic body is drawn in its colour at its pose. Some
/// tilt histories leave a stack rocking or a body rolling past the 15 s wait (CI at 7acc6e3
/// timed out on one; locally 8 runs of 8 settled in 10-13 s), so the wait and the check are
/// tried three times; the check itself stays exact, and a page that does not draw fails
/// every try.
async fn pixels_once_still(
    page: &mut Cdp,
    w: &mut Watch,
    s: &zenoh::Session,
    keys: &Keys,
) -> (SceneState, usize) {
    let mut failures = Vec::new();
    for _ in 0..3 {
        if let Err(e) = w.settled(30, 15).await {
            println!("{e}");
            failures.push(e);
        }
        tokio::time::sleep(Duration::from_millis(300)).await;
        match check_pixels(page, s, keys).await {
            Ok(done) => return done,
            Err(e) => failures.push(e),
        }
    }
    panic!("the page's pixels never matched the world: {failures:#?}")
}

fn close(a: &Value, c: Colour) -> bool {
    let v: Vec<i64> = a
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_i64().unwrap())
        .collect();
    (v[0] - c.r as i64).abs() <= 10
        && (v[1] - c.g as i64).abs() <= 10
        && (v[2] - c.b as i64).abs() <= 10
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

fn base64_decode(s: &str) -> Vec<u8> {
    let val = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => (c - b'A') as u32,
            b'a'..=b'z' => (c - b'a') as u32 + 26,
            b'0'..=b'9' => (c - b'0') as u32 + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let mut out = Vec::new();
    for chunk in s.as_bytes().chunks(4) {
        let n = chunk.iter().take_while(|&&c| c != b'=').count();
        let mut acc = 0u32;
        for (i, &c) in chunk[..n].iter().enumerate() {
            acc |= val(c) << (18 - 6 * i);
        }
        out.extend_from_slice(&acc.to_be_bytes()[1..n]);
    }
    out
}

// ------------------------------------------------------------------------------------------

/// The page over HTTPS draws the daemon's bodies in their colours where their poses are; an
/// emulated accelerometer turns the daemon's gravity; a click spawns a body at the click.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_draws_the_world_and_tilts_and_spawns_in_chromium() {
    let _lock = BROWSER_LOCK.lock().await;
    let port = 17490;
    let (server, gw) = daemon_and_gateway(port).await;
    let keys = server.keys().clone();
    assert!(gw.url().starts_with("https://127.0.0.1:"), "{}", gw.url());
    let fp = gw.fingerprint().unwrap().to_string();
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let mut w = watch(&s, &keys).await;

    let (_browser, mut page) = browser_page("draw").await;
    // the emulated motion sensors exist before the page asks for them
    let origin = gw.url().trim_end_matches('/').to_string();
    let granted = page
        .call_on(
            None,
            "Browser.grantPermissions",
            json!({"permissions": ["sensors"], "origin": origin}),
        )
        .await
        .is_ok();
    let mut overridden = true;
    for (t, y) in [
        ("accelerometer", 9.81),
        ("linear-acceleration", 0.0),
        ("gyroscope", 0.0),
    ] {
        overridden &= page
            .call(
                "Emulation.setSensorOverrideEnabled",
                json!({"enabled": true, "type": t}),
            )
            .await
            .is_ok();
        overridden &= page
            .call(
                "Emulation.setSensorOverrideReadings",
                json!({"type": t, "reading": {"xyz": {"x": 0.0, "y": y, "z": 0.0}}}),
            )
            .await
            .is_ok();
    }
    page.navigate(gw.url()).await;
    page.wait_for(
        "location.protocol === 'https:' && document.readyState === 'complete'",
        20,
    )
    .await;
    page.wait_for(
        "!!(window.tiltbox && tiltbox.state.joined && tiltbox.state.frame > 0)",
        20,
    )
    .await;

    // 1. pixels: once the bricks rest, each is drawn in its colour at its pose
    let (sc, checked) = pixels_once_still(&mut page, &mut w, &s, &keys).await;
    assert!(checked >= 6, "{checked} bricks checked");
    let size = page
        .eval("[document.getElementById('world').clientWidth, document.getElementById('world').clientHeight]")
        .await;
    let to_px = fit(&sc, size[0].as_f64().unwrap(), size[1].as_f64().unwrap());
    // a wall, and the empty middle of the box near the ceiling
    let floor = sc.bodies.iter().find(|b| b.name == "floor").unwrap();
    let (px, py) = to_px(floor.position.x, floor.position.y);
    assert!(close(
        &page.eval(&format!("tiltbox.pixel({px}, {py})")).await,
        floor.colour
    ));
    let (px, py) = to_px(0.0, 5.5);
    let bg = Colour {
        r: 0x16,
        g: 0x16,
        b: 0x1d,
    };
    assert!(close(
        &page.eval(&format!("tiltbox.pixel({px}, {py})")).await,
        bg
    ));

    // 2. device motion: the DevTools sensor override when it reaches the page's devicemotion
    // listener, else a synthetic devicemotion event (said which)
    let via_sensor = overridden && page.eval("tiltbox.motionSeen()").await == json!(true);
    println!(
        "sensors permission granted: {granted}; override accepted: {overridden}; device motion through: {}",
        if via_sensor {
            "CDP Emulation.setSensorOverrideReadings (accelerometer)"
        } else {
            "a synthetic devicemotion event (Runtime.evaluate): the sensor override did not reach the page"
        }
    );
    async fn reading(page: &mut Cdp, via_sensor: bool, x: f64, y: f64, z: f64) {
        if via_sensor {
            page.call(
                "Emulation.setSensorOverrideReadings",
                json!({"type": "accelerometer", "reading": {"xyz": {"x": x, "y": y, "z": z}}}),
            )
            .await
            .expect("accelerometer reading");
        } else {
            page.eval(&format!(
                "window.dispatchEvent(new DeviceMotionEvent('devicemotion', \
                 {{accelerationIncludingGravity: {{x: {x}, y: {y}, z: {z}}}, interval: 16}})), true"
            ))
            .await;
        }
    }
    let readings = [
        (9.81, 0.0, 0.0, (-9.81, 0.0)),
        (-9.81, 0.0, 0.0, (9.81, 0.0)),
        (0.0, 9.81, 0.0, (0.0, -9.81)),
        (6.0, 6.0, 4.0, (-6.0, -6.0)),
        (0.0, -9.81, 0.0, (0.0, 9.81)),
        (0.0, 9.81, 0.0, (0.0, -9.81)),
    ];
    for &(x, y, z, g) in &readings {
        let n0 = page.eval("tiltbox.metrics.tiltToVisible.length").await;
        reading(&mut page, via_sensor, x, y, z).await;
        w.gravity(g, 5).await;
        // the page draws the new gravity's first snapshot before the next reading
        page.wait_for(&format!("tiltbox.metrics.tiltToVisible.length > {n0}"), 5)
            .await;
        tokio::time::sleep(Duration::from_millis(150)).await;
    }

    // 3. figures: frame rate and bytes per second while the device turns around for 4 s
    let m0 = page
        .eval("[tiltbox.metrics.framesDrawn, tiltbox.metrics.bytesIn, tiltbox.metrics.framesIn, performance.now()]")
        .await;
    for i in 0..40 {
        let a = i as f64 * 0.35;
        reading(&mut page, via_sensor, 9.81 * a.sin(), 9.81 * a.cos(), 0.0).await;
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let m1 = page
        .eval("[tiltbox.metrics.framesDrawn, tiltbox.metrics.bytesIn, tiltbox.metrics.framesIn, performance.now()]")
        .await;
    let secs = (m1[3].as_f64().unwrap() - m0[3].as_f64().unwrap()) / 1000.0;
    let fps = (m1[0].as_f64().unwrap() - m0[0].as_f64().unwrap()) / secs;
    let bps = (m1[1].as_f64().unwrap() - m0[1].as_f64().unwrap()) / secs;
    let fin = (m1[2].as_f64().unwrap() - m0[2].as_f64().unwrap()) / secs;
    let lat: Vec<f64> =
        serde_json::from_value(page.eval("tiltbox.metrics.tiltToVisible").await).unwrap();
    let snap_lat: Vec<f64> =
        serde_json::from_value(page.eval("tiltbox.metrics.tiltToSnapshot").await).unwrap();
    println!(
        "figures: {fps:.1} frames drawn/s in headless Chromium; {fin:.1} WebSocket frames/s, \
         {bps:.0} bytes/s into the page (world moving, 6 bricks); tilt -> snapshot at the page \
         median {:.1} ms, tilt -> drawn median {:.1} ms (n = {}, min {:.0}, max {:.0})",
        median(&snap_lat),
        median(&lat),
        lat.len(),
        lat.iter().cloned().fold(f64::MAX, f64::min),
        lat.iter().cloned().fold(0.0, f64::max),
    );
    assert!(fps > 20.0, "{fps} frames drawn per second");
    assert!(fin > 40.0, "{fin} frames per second from the gateway");
    assert!(lat.len() >= 6 && median(&lat) < 500.0, "{lat:?}");
    reading(&mut page, via_sensor, 0.0, 9.81, 0.0).await;
    w.gravity((0.0, -9.81), 5).await;

    // 4. clicks spawn a crate, a ball, a capsule and a wedge where the pointer is
    // A press on a brick grabs it instead. The bricks flung about by the tilts above fly
    // through the spots for a while: CI at f2e979b pressed on a spot the page had just found
    // clear and got no spawn. So the world settles first (as in step 1, a stack left rocking
    // is reported and the clicks go on), each spot must be clear in the page, and a press
    // the page took as a grab (its spawn count unchanged) is let go and tried again, at
    // most three times.
    if let Err(e) = w.settled(30, 15).await {
        println!("before the clicks: {e}");
    }
    let spots = [(-2.5, 4.5), (-0.8, 4.5), (0.9, 4.5), (2.5, 4.5)];
    let mut spawned = Vec::new();
    for (x, y) in spots {
        let (px, py) = to_px(x, y);
        let mut tries = 0;
        loop {
            tries += 1;
            page.wait_for(&format!("tiltbox.bodyAt({x}, {y}) === null"), 10)
                .await;
            let before = page.eval("tiltbox.metrics.spawns").await;
            for t in ["mousePressed", "mouseReleased"] {
                page.call(
                    "Input.dispatchMouseEvent",
                    json!({"type": t, "x": px, "y": py, "button": "left", "clickCount": 1}),
                )
                .await
                .unwrap();
            }
            if page.eval("tiltbox.metrics.spawns").await != before {
                break;
            }
            assert!(
                tries < 3,
                "three presses at ({x}, {y}) all landed on a body"
            );
            println!("the press at ({x}, {y}) landed on a body that came by; pressing again");
            tokio::time::sleep(Duration::from_millis(500)).await;
        }
        let end = Instant::now() + Duration::from_secs(5);
        let added = loop {
            let left = end.saturating_duration_since(Instant::now());
            let e = tokio::time::timeout(left, w.events.recv())
                .await
                .expect("an Added event for the click")
                .unwrap();
            if let EventKind::Added { bodies } = e.kind {
                break bodies;
            }
        };
        assert_eq!(added.len(), 1);
        let b = added[0].clone();
        assert!(
            (b.position.x - x).abs() < 0.02 && (b.position.y - y).abs() < 0.02 && !b.is_static,
            "clicked at ({x}, {y}), spawned at {:?}",
            b.position
        );
        spawned.push(b);
    }
    let kinds: Vec<_> = spawned
        .iter()
        .map(|b| match b.shape {
            ShapeSpec::Rect { .. } => "rect",
            ShapeSpec::Circle { .. } => "circle",
            ShapeSpec::Capsule { .. } => "capsule",
            ShapeSpec::Polygon { .. } => "polygon",
            ShapeSpec::Segment { .. } => "segment",
            ShapeSpec::Compound { .. } => "compound",
        })
        .collect();
    assert_eq!(kinds, ["rect", "circle", "capsule", "polygon"]);
    let sc = scene(&s, &keys).await;
    for b in &spawned {
        assert!(
            sc.bodies.iter().any(|x| x.id == b.id),
            "the spawned body {} is in the daemon's scene",
            b.id
        );
        page.wait_for(&format!("tiltbox.state.bodies.has('{}')", b.id), 5)
            .await;
    }

    // 5. every kind drawn in its colour where it came to rest; the screenshot for the README
    let (_, checked) = pixels_once_still(&mut page, &mut w, &s, &keys).await;
    assert_eq!(checked, 10, "6 bricks and 4 spawned bodies");
    let shot = page
        .call("Page.captureScreenshot", json!({"format": "png"}))
        .await
        .unwrap();
    let png = base64_decode(shot["data"].as_str().unwrap());
    assert_eq!(&png[1..4], b"PNG");
    let out = if std::env::var_os("TILTBOX_UPDATE_SCREENSHOT").is_some() {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/img/web-client.png")
    } else {
        PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("web-client.png")
    };
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    std::fs::write(&out, &png).unwrap();
    println!(
        "screenshot: {} ({} bytes); certificate {fp}",
        out.display(),
        png.len()
    );

    let c = gw.counters();
    use std::sync::atomic::Ordering::Relaxed;
    assert!(c.commands.load(Relaxed) >= 10, "{c:?}");
    assert_eq!(c.refused.load(Relaxed), 0, "{c:?}");
    stop(page, gw, server).await;
}

/// Two fingers on two bricks in the page drag them at once (touches dispatched to headless
/// Chromium, the bricks' poses read from the daemon's own scene): once the fingers stop, each
/// brick's grabbed point comes within 5 cm of its finger (within 2 s; the time is printed);
/// let go, both fall.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_fingers_drag_two_bricks_in_chromium() {
    let _lock = BROWSER_LOCK.lock().await;
    let port = 17497;
    let server = daemon(port).await;
    let gw = gateway_at_rate(port, "tilt,spawn,drag", 120).await;
    let keys = server.keys().clone();
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let (_browser, mut page) = browser_page("drag").await;
    page.call(
        "Emulation.setTouchEmulationEnabled",
        json!({"enabled": true, "maxTouchPoints": 5}),
    )
    .await
    .unwrap();
    page.navigate(gw.url()).await;
    page.wait_for(
        "!!(window.tiltbox && tiltbox.state.joined && tiltbox.state.frame > 0)",
        20,
    )
    .await;
    // The bricks have landed by 2 s (they drop at most 4.6 m).
    tokio::time::sleep(Duration::from_secs(2)).await;
    let sc = scene(&s, &keys).await;
    let size = page
        .eval("[document.getElementById('world').clientWidth, document.getElementById('world').clientHeight]")
        .await;
    let to_px = fit(&sc, size[0].as_f64().unwrap(), size[1].as_f64().unwrap());
    let brick = |name: &str| sc.bodies.iter().find(|b| b.name == name).unwrap().clone();
    let (red, blue) = (brick("red brick"), brick("blue brick"));
    let targets = [(-2.0f32, 4.5f32), (2.0, 4.5)];
    let starts = [red.position, blue.position];
    let touch = |t: f32| -> Value {
        let points: Vec<Value> = (0..2)
            .map(|i| {
                let (x0, y0) = (starts[i].x, starts[i].y);
                let (x1, y1) = targets[i];
                let (px, py) = to_px(x0 + (x1 - x0) * t, y0 + (y1 - y0) * t);
                json!({"x": px, "y": py, "id": i})
            })
            .collect();
        Value::Array(points)
    };
    let send = |kind: &str, points: Value| json!({"type": kind, "touchPoints": points});
    page.call("Input.dispatchTouchEvent", send("touchStart", touch(0.0)))
        .await
        .unwrap();
    page.wait_for("tiltbox.hands() === 2", 5).await;
    for k in 1..=20 {
        page.call(
            "Input.dispatchTouchEvent",
            send("touchMove", touch(k as f32 / 20.0)),
        )
        .await
        .unwrap();
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    // The page sends the last position within a frame of the last move, and the bricks
    // reach it some 200 ms later on an idle machine. Under CI's load (tests running beside
    // the browser on two cores) one brick was once still 23 cm short 260 ms after the last
    // move, on its way: so the daemon's scene is read until both are there, for up to 2 s,
    // and the time taken is printed.
    let stopped = Instant::now();
    // The finger landed on the brick's centre to within a pixel; 5 cm is the bound.
    let pixel = 1.0 / (to_px(1.0, 0.0).0 - to_px(0.0, 0.0).0) as f32;
    let offs = loop {
        let sc = scene(&s, &keys).await;
        let offs: Vec<(String, Vector, f32)> = [&red, &blue]
            .iter()
            .zip(targets)
            .map(|(b, (x, y))| {
                let now = sc.bodies.iter().find(|n| n.id == b.id).unwrap().position;
                let off = ((now.x - x).powi(2) + (now.y - y).powi(2)).sqrt();
                (b.name.clone(), now, off)
            })
            .collect();
        if offs.iter().all(|o| o.2 < 0.05 + pixel) || stopped.elapsed() > Duration::from_secs(2) {
            break offs;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    };
    println!(
        "both bricks within 5 cm of their fingers {:.0} ms after the last move",
        stopped.elapsed().as_secs_f64() * 1000.0
    );
    for ((name, now, off), (x, y)) in offs.into_iter().zip(targets) {
        assert!(
            off < 0.05 + pixel,
            "{name} at {now:?}, finger at ({x}, {y}): {off} m, 2 s after the last move"
        );
    }
    page.call("Input.dispatchTouchEvent", send("touchEnd", json!([])))
        .await
        .unwrap();
    page.wait_for("tiltbox.hands() === 0", 5).await;
    tokio::time::sleep(Duration::from_millis(800)).await;
    let sc = scene(&s, &keys).await;
    for b in [&red, &blue] {
        let now = sc.bodies.iter().find(|n| n.id == b.id).unwrap().position;
        assert!(now.y < 3.5, "{} still held at {now:?}", b.name);
    }
    stop(page, gw, server).await;
}

/// The page's hand-written decoder, run in Chromium, gives every hex example of
/// docs/protocol.md exactly what the Rust decoder gives (and encodes the commands back to
/// the same bytes).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_decodes_every_documented_example() {
    let _lock = BROWSER_LOCK.lock().await;
    let port = 17491;
    let (server, gw) = daemon_and_gateway(port).await;
    let (_browser, mut page) = browser_page("decode").await;
    page.navigate(gw.url()).await;
    page.wait_for("!!window.tiltbox", 20).await;

    let doc = common::read_repo_file("docs/protocol.md");
    let examples = hex_examples(&doc);
    let mut count = 0;
    for (section, bytes) in &examples {
        let (ty, payload) = match section.as_str() {
            "frame" => {
                let tag = tiltbox::client::web::wire::Tag::from_byte(bytes[0])
                    .unwrap_or_else(|| panic!("bad tag in {bytes:02x?}"));
                (tag_type(tag), &bytes[1..])
            }
            s => (s, &bytes[..]),
        };
        let want = rust_json(ty, payload);
        let arr = format!("new Uint8Array({:?})", bytes);
        let got = if section == "frame" {
            page.eval(&format!(
                "JSON.stringify(tiltbox.decodeFrame({arr}).message)"
            ))
            .await
        } else {
            page.eval(&format!(
                "JSON.stringify(tiltbox.decodeMessage('{ty}', {arr}))"
            ))
            .await
        };
        let got: Value = serde_json::from_str(got.as_str().unwrap()).unwrap();
        assert!(
            same(&got, &want),
            "{section} example {bytes:02x?}:\n page {got}\n rust {want}"
        );
        if matches!(
            ty,
            "SetGravity" | "Tilt" | "Spawn" | "Remove" | "Reset" | "Drag" | "RemoveJoints"
        ) {
            let enc = page
                .eval(&format!("Array.from(tiltbox.encodeMessage('{ty}', {got}))"))
                .await;
            let enc: Vec<u8> = serde_json::from_value(enc).unwrap();
            assert_eq!(&enc[..], payload, "the page re-encodes {ty}");
        }
        count += 1;
    }
    println!("{count} documented examples decoded in the page");
    // the page's snapshot decoder rebuilds the documented keyframe and delta as Rust's does
    let snaps: Vec<&Vec<u8>> = examples
        .iter()
        .filter(|(section, _)| section == "Snapshot")
        .map(|(_, b)| b)
        .collect();
    assert_eq!(snaps.len(), 2, "a keyframe and a delta");
    let mut rust = SnapshotDecoder::new();
    page.eval("window.decoder = new tiltbox.SnapshotDecoder(), 0")
        .await;
    for bytes in snaps {
        let want = serde_json::to_value(rust.decode(bytes).unwrap().unwrap()).unwrap();
        let got = page
            .eval(&format!(
                "JSON.stringify(decoder.apply(tiltbox.decodeMessage('Snapshot', new Uint8Array({bytes:?}))))"
            ))
            .await;
        let got: Value = serde_json::from_str(got.as_str().unwrap()).unwrap();
        assert!(same(&got, &want), "page {got}\n rust {want}");
    }
    assert!(
        count >= 14,
        "only {count} hex examples found in docs/protocol.md"
    );
    // and garbage is an error in the page too, never a wrong value
    for bad in ["[]", "[2,0]", "[1]", "[1,1,2,3]"] {
        let r = page
            .eval(&format!(
                "(()=>{{try{{tiltbox.decodeMessage('Snapshot', new Uint8Array({bad}));return 'decoded'}}catch(e){{return e.message}}}})()"
            ))
            .await;
        assert_ne!(r, json!("decoded"), "{bad}");
    }
    stop(page, gw, server).await;
}

/// Garbage on the WebSocket (unknown tags, downstream tags, truncated or malformed payloads,
/// text, a command left out of --allow, a flood past the rate limit) is answered with error
/// frames; the same socket still carries a good tilt to the daemon, and the page goes on.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn garbage_frames_are_refused_and_the_gateway_keeps_serving() {
    let _lock = BROWSER_LOCK.lock().await;
    let port = 17492;
    let (server, gw) = daemon_and_gateway(port).await;
    let keys = server.keys().clone();
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let mut w = watch(&s, &keys).await;
    let (_browser, mut page) = browser_page("garbage").await;
    page.navigate(gw.url()).await;
    page.wait_for("!!(window.tiltbox && tiltbox.state.joined)", 20)
        .await;
    let errors = page
        .eval(
            r#"(async () => {
  const s = new WebSocket(location.origin.replace('https', 'wss') + '/ws');
  s.binaryType = 'arraybuffer';
  const errors = [];
  s.onmessage = e => { if (typeof e.data === 'string') { const m = JSON.parse(e.data); if (m.type === 'error') errors.push(m.reason); } };
  await new Promise(r => s.onopen = r);
  for (const f of [[0xee, 1, 2], [6, 1, 9], [6, 2, 0, 0], [1, 1, 0], [7, 1, 0xff, 0xff], [], [6], [9, 1], [8, 1, 1, 3, 0], [6, 1, 1, 0, 0]]) s.send(new Uint8Array(f));
  s.send('{"type":"spawn"}');
  s.send('not json');
  const end = performance.now() + 5000;
  while (errors.length < 12 && performance.now() < end) await new Promise(r => setTimeout(r, 20));
  // the same socket still works: a good tilt, upside down
  s.send(tiltbox.encodeFrame('Tilt', { Orientation: 'PortraitUpsideDown' }));
  // (until the page's own view shows it applied: a fixed wait lost the race on a loaded machine)
  const end1 = performance.now() + 5000;
  while (tiltbox.state.gravity.y < 9 && performance.now() < end1) await new Promise(r => setTimeout(r, 20));
  // a flood: 200 tilts at once, past the 60 per second limit
  for (let i = 0; i < 200; i++) s.send(tiltbox.encodeFrame('Tilt', { Accelerometer: { x: 0, y: 9.81, z: 0 } }));
  const end2 = performance.now() + 5000;
  while (!errors.some(e => e.startsWith('rate limit')) && performance.now() < end2) await new Promise(r => setTimeout(r, 20));
  s.close();
  return errors;
})()"#,
        )
        .await;
    let errors: Vec<String> = serde_json::from_value(errors).unwrap();
    let limited = errors
        .iter()
        .filter(|e| e.starts_with("rate limit"))
        .count();
    println!(
        "refusals: {:#?} and {limited} x rate limit",
        &errors[..errors.len() - limited]
    );
    let expect = [
        "unknown tag 0xee",
        "tilt: unknown variant in Tilt",
        "tilt: unsupported protocol version 2",
        "tag 0x01 (poses) is sent by the gateway",
        "spawn: truncated Spawn",
        "empty frame",
        "tilt: empty payload",
        "reset is not allowed by this gateway (--allow tilt,spawn)",
        "remove is not allowed by this gateway",
        "tilt: truncated Tilt",
        "text frames carry only",
        "text frames carry only",
    ];
    for (i, e) in expect.iter().enumerate() {
        assert!(
            errors.get(i).is_some_and(|g| g.contains(e)),
            "refusal {i}: expected {e:?}, got {:?}",
            errors.get(i)
        );
    }
    assert!(errors.iter().any(|e| e.starts_with("rate limit")));
    // the good tilt after the garbage reached the daemon
    w.gravity((0.0, 9.81), 5).await;
    // the flood's first 60-odd tilts (upright) did too, the rest were refused
    w.gravity((0.0, -9.81), 5).await;
    // and the page's own connection kept receiving all along
    let f0 = page.eval("tiltbox.state.frame").await.as_u64().unwrap();
    // A page that joined between keyframes applies deltas only from the next keyframe on (at
    // most a second at keyframe_every = 60; with 300 ms this failed whenever the keyframe was
    // further off): allow 5 s, and say how long it took.
    let mut f1 = f0;
    let waited = Instant::now();
    for _ in 0..50 {
        tokio::time::sleep(Duration::from_millis(100)).await;
        f1 = page.eval("tiltbox.state.frame").await.as_u64().unwrap();
        if f1 > f0 + 5 {
            break;
        }
    }
    println!("page frames {f0} -> {f1} after {:?}", waited.elapsed());
    let why = page
        .eval("JSON.stringify({skipped: tiltbox.snapshots.skipped, last: tiltbox.snapshots.last, key: tiltbox.snapshots.key && tiltbox.snapshots.key.frame, joined: tiltbox.state.joined, framesIn: tiltbox.metrics.framesIn, connected: tiltbox.metrics.connected})")
        .await;
    assert!(f1 > f0 + 5, "page frames {f0} -> {f1}: {why}");
    use std::sync::atomic::Ordering::Relaxed;
    let c = gw.counters();
    assert!(c.refused.load(Relaxed) >= 13, "{c:?}");
    // a new page still loads and joins
    page.navigate(gw.url()).await;
    page.wait_for(
        "!!(window.tiltbox && tiltbox.state.joined && tiltbox.state.frame > 0)",
        20,
    )
    .await;
    stop(page, gw, server).await;
}

fn tag_type(tag: tiltbox::client::web::wire::Tag) -> &'static str {
    use tiltbox::client::web::wire::Tag;
    match tag {
        Tag::Poses => "Snapshot",
        Tag::Events => "Event",
        Tag::Stats => "Stats",
        Tag::Scene => "SceneState",
        Tag::Gravity => "SetGravity",
        Tag::Tilt => "Tilt",
        Tag::Spawn => "Spawn",
        Tag::Remove => "Remove",
        Tag::Reset => "Reset",
        Tag::Velocity => "SetVelocity",
        Tag::Drag => "Drag",
        Tag::Build => "Build",
        Tag::RemoveJoints => "RemoveJoints",
        Tag::SceneWithJoints => "SceneWithJoints",
    }
}

fn rust_json(ty: &str, bytes: &[u8]) -> Value {
    fn j<M: Message>(b: &[u8]) -> Value {
        serde_json::to_value(decode::<M>(b).unwrap_or_else(|e| panic!("{}: {e}", M::NAME))).unwrap()
    }
    match ty {
        "Snapshot" => serde_json::to_value(decode_frame(bytes).unwrap()).unwrap(),
        "Event" => j::<Event>(bytes),
        "Stats" => j::<Stats>(bytes),
        "SceneState" => j::<SceneState>(bytes),
        "SetGravity" => j::<SetGravity>(bytes),
        "Tilt" => j::<Tilt>(bytes),
        "Spawn" => j::<Spawn>(bytes),
        "Remove" => j::<Remove>(bytes),
        "Reset" => j::<Reset>(bytes),
        "Drag" => j::<Drag>(bytes),
        "RemoveJoints" => j::<RemoveJoints>(bytes),
        "SceneWithJoints" => j::<SceneWithJoints>(bytes),
        _ => panic!("no message {ty}"),
    }
}

/// Numbers compare as the f32 they were on the wire (serde_json prints an f32 in its own
/// shortest form, JS reads it as the exact double).
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            x == y || (x as f32) == (y as f32)
        }
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        // A colour: three bytes on the wire, which the page decodes as {r, g, b} and Rust's
        // serde writes as "#rrggbb" in text formats.
        (Value::Object(rgb), Value::String(hex)) => {
            let byte = |k: &str| rgb.get(k).and_then(Value::as_u64).unwrap_or(256);
            format!("#{:02x}{:02x}{:02x}", byte("r"), byte("g"), byte("b"))
                == hex.to_ascii_lowercase()
        }
        _ => a == b,
    }
}

/// Every hex example in docs/protocol.md, with the message its section documents
/// (`frame` for the WebSocket gateway's tagged frames). A block whose lines carry a comment
/// after the bytes holds one message per line.
fn hex_examples(doc: &str) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut section = String::new();
    let mut in_block = false;
    let mut block: Vec<&str> = Vec::new();
    for line in doc.lines() {
        if let Some(h) = line.strip_prefix("### ") {
            section = h.trim().to_string();
        }
        if line.starts_with("## ") {
            section = if line.contains("WebSocket") {
                "frame".into()
            } else {
                String::new()
            };
        }
        if line.trim_start().starts_with("```") {
            if in_block {
                let msg_ty = match section.as_str() {
                    "frame" | "Frames" => Some("frame"),
                    "Snapshot" | "Event" | "SetGravity" | "Tilt" | "Spawn" | "Remove" | "Reset"
                    | "Drag" | "RemoveJoints" => Some(section.as_str()),
                    _ => None,
                };
                let is_hex = |t: &str| t.len() == 2 && t.chars().all(|c| c.is_ascii_hexdigit());
                let rows: Vec<(Vec<u8>, bool)> = block
                    .iter()
                    .map(|l| {
                        let toks: Vec<&str> = l.split_whitespace().collect();
                        let n = toks.iter().take_while(|t| is_hex(t)).count();
                        let bytes = toks[..n]
                            .iter()
                            .map(|t| u8::from_str_radix(t, 16).unwrap())
                            .collect();
                        (bytes, n < toks.len())
                    })
                    .collect();
                let hex_block = !rows.is_empty() && rows.iter().all(|(b, _)| !b.is_empty());
                if let (Some(ty), true) = (msg_ty, hex_block) {
                    let ty = if section == "Frames" { "frame" } else { ty };
                    if rows.iter().any(|(_, commented)| *commented) {
                        for (b, _) in rows {
                            out.push((ty.to_string(), b));
                        }
                    } else {
                        out.push((ty.to_string(), rows.into_iter().flat_map(|r| r.0).collect()));
                    }
                }
                block.clear();
            }
            in_block = !in_block;
            continue;
        }
        if in_block {
            block.push(line);
        }
    }
    out
}

/// How many pages one gateway keeps at the daemon's 60 Hz on this machine: N WebSocket
/// clients (plain `ws://`, `--no-tls`, in this process, on the same 2 cores as the gateway and
/// the daemon) each count the snapshots they receive over 5 s while gravity turns, so every
/// snapshot carries poses. In CI: 25 pages, and every one of them must receive snapshots (the
/// fan-out works; rates are printed, not asserted: time is for benchmarks). As a measurement,
/// N doubles up to `TILTBOX_WEB_PAGES_MAX` until the slowest page gets less than 95 % of what
/// the daemon published. Not a browser test: the figure is the gateway's.
/// `TILTBOX_WEB_PAGES_MAX=3200 cargo test --release --test web pages_at_60_hz -- --nocapture`
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pages_at_60_hz() {
    let max_pages: usize = std::env::var("TILTBOX_WEB_PAGES_MAX")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(25);
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
    use std::sync::Arc;
    let port = 17494;
    let server = daemon(port).await;
    let keys = server.keys().clone();
    let gw = plain_gateway(port, Allow::NONE, 60).await;
    let url = format!("ws://{}/ws", gw.local_addr());
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let published = Arc::new(AtomicU64::new(0));
    let p2 = published.clone();
    let _sub = s
        .declare_subscriber(keys.poses())
        .callback(move |_| {
            p2.fetch_add(1, Relaxed);
        })
        .await
        .unwrap();
    // gravity turns at 90 degrees a second: the bricks never rest
    let gs2 = s.clone();
    let gkey = keys.gravity();
    let spin = tokio::spawn(async move {
        let t0 = Instant::now();
        loop {
            let a = t0.elapsed().as_secs_f32() * std::f32::consts::FRAC_PI_2;
            let g = SetGravity {
                x: 9.81 * a.sin(),
                y: -9.81 * a.cos(),
            };
            let _ = gs2.put(gkey.clone(), encode(&g).unwrap()).await;
            tokio::time::sleep(Duration::from_millis(33)).await;
        }
    });
    let mut best = 0;
    let mut n = 25;
    let mut clients: Vec<(Arc<AtomicU64>, Arc<AtomicU64>, tokio::task::JoinHandle<()>)> =
        Vec::new();
    loop {
        while clients.len() < n {
            let (ws, _) = tokio_tungstenite::connect_async(url.as_str())
                .await
                .expect("connect");
            let (count, bytes) = (Arc::new(AtomicU64::new(0)), Arc::new(AtomicU64::new(0)));
            let (c2, b2) = (count.clone(), bytes.clone());
            let task = tokio::spawn(async move {
                let (_tx, mut rx) = ws.split();
                while let Some(Ok(m)) = rx.next().await {
                    if let WsMessage::Binary(b) = m {
                        b2.fetch_add(b.len() as u64, Relaxed);
                        if b.first() == Some(&1) {
                            c2.fetch_add(1, Relaxed);
                        }
                    }
                }
            });
            clients.push((count, bytes, task));
        }
        tokio::time::sleep(Duration::from_secs(2)).await;
        let c0: Vec<u64> = clients.iter().map(|c| c.0.load(Relaxed)).collect();
        let b0: u64 = clients.iter().map(|c| c.1.load(Relaxed)).sum();
        let p0 = published.load(Relaxed);
        let t0 = Instant::now();
        tokio::time::sleep(Duration::from_secs(5)).await;
        let secs = t0.elapsed().as_secs_f64();
        let pub_rate = (published.load(Relaxed) - p0) as f64 / secs;
        let rates: Vec<f64> = clients
            .iter()
            .zip(&c0)
            .map(|(c, c0)| (c.0.load(Relaxed) - c0) as f64 / secs)
            .collect();
        let bytes: u64 = clients.iter().map(|c| c.1.load(Relaxed)).sum::<u64>() - b0;
        let min = rates.iter().cloned().fold(f64::MAX, f64::min);
        let mean = rates.iter().sum::<f64>() / rates.len() as f64;
        println!(
            "{n} pages: daemon {pub_rate:.1} snapshots/s; per page min {min:.1}, mean {mean:.1}; {:.0} bytes/s per page",
            bytes as f64 / secs / n as f64
        );
        assert!(
            min > 0.0 && pub_rate > 0.0,
            "with {n} pages one page got no snapshot (daemon {pub_rate:.1}/s)"
        );
        if min < 0.95 * pub_rate || n >= max_pages {
            break;
        }
        best = n;
        n *= 2;
    }
    println!("one gateway kept {best} pages at the daemon's rate");
    spin.abort();
    for c in clients {
        c.2.abort();
    }
    gw.stop().await;
    server.shutdown().await.unwrap();
}

/// The binary: on start it prints the HTTPS URL, the certificate's fingerprint and a QR code,
/// and serves the page; a bad flag is named and exits with 2.
#[test]
fn the_binary_prints_its_url_fingerprint_and_qr_code() {
    use std::io::{BufRead, BufReader};
    let exe = env!("CARGO_BIN_EXE_tiltbox-web");
    let bad = Command::new(exe)
        .args(["--allow", "tilt,fly"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("\"fly\""));

    let mut child = Command::new(exe)
        .args([
            "--listen",
            "127.0.0.1:0",
            "--connect",
            "tcp/127.0.0.1:17493",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut lines = Vec::new();
    let mut line = String::new();
    while lines.len() < 20 && out.read_line(&mut line).unwrap_or(0) > 0 {
        lines.push(std::mem::take(&mut line));
    }
    let _ = child.kill();
    let _ = child.wait();
    let text = lines.concat();
    assert!(
        text.starts_with("tiltbox-web: open https://127.0.0.1:"),
        "{text}"
    );
    let fp = text
        .lines()
        .find_map(|l| l.strip_prefix("certificate SHA-256 "))
        .expect("a fingerprint line");
    assert_eq!(fp.len(), 95, "{fp}");
    assert!(text.contains("loopback only"), "{text}");
    assert!(
        text.contains('▀') || text.contains('▄'),
        "a QR code: {text}"
    );
}

/// A body of several shapes and a joint built over `…/build` are drawn by the page: the
/// second shape of a static L in the L's colour where the build put it, and the pendulum's
/// hinge as a light dot on the pin; a `…/remove_joints` takes the hinge off the page.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_draws_compounds_and_joints_built_over_the_wire() {
    let _lock = BROWSER_LOCK.lock().await;
    let port = 17498;
    let (server, gw) = daemon_and_gateway(port).await;
    let keys = server.keys().clone();
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let (_browser, mut page) = joined_page("joints", &gw).await;
    let v = Vector::new;
    let part = |w: f32, h: f32, at: Vector| {
        PartSpec::at(
            ShapeSpec::Rect {
                width: w,
                height: h,
            },
            at,
        )
    };
    let fixed = |at: Vector, colour: &str, parts| BuildBody {
        colour: colour.parse().unwrap(),
        ..BuildBody::new(Motion::Static, at, parts)
    };
    let build = Build {
        bodies: vec![
            // an L: a 1 x 0.25 bar, and a 0.5 x 1 post above its right end
            fixed(
                v(-2.0, 3.0),
                "#20c020",
                vec![part(1.0, 0.25, v(0.0, 0.0)), part(0.5, 1.0, v(0.25, 0.625))],
            ),
            fixed(v(1.5, 5.0), "#5b5b66", vec![part(0.25, 0.25, v(0.0, 0.0))]),
            BuildBody {
                motion: Motion::Dynamic,
                ..fixed(
                    v(2.5, 5.0),
                    "#d64541",
                    vec![PartSpec::at(ShapeSpec::Circle { radius: 0.2 }, v(0.0, 0.0))],
                )
            },
        ],
        joints: vec![JointSpec::hinge(
            JointEnd::New(1),
            JointEnd::New(2),
            v(0.0, 0.0),
            v(-1.0, 0.0),
        )],
    };
    let mut w = watch(&s, &keys).await;
    s.put(keys.build(), encode(&build).unwrap()).await.unwrap();
    let joint = loop {
        let e = tokio::time::timeout(Duration::from_secs(5), w.events.recv())
            .await
            .expect("a Built event")
            .unwrap();
        if let EventKind::Built { joints, .. } = e.kind {
            break joints[0].id;
        }
    };
    page.wait_for("tiltbox.joints() === 1", 10).await;
    // The event is applied between frames: wait for two frames drawn after it.
    let f0 = page.eval("tiltbox.metrics.framesDrawn").await;
    page.wait_for(&format!("tiltbox.metrics.framesDrawn > {f0} + 1"), 5)
        .await;
    // The post of the L: centre (-2 + 0.25, 3 + 0.625), drawn in the L's green.
    let green = page
        .eval(
            "(() => { const v = tiltbox.view(); \
             return tiltbox.pixel(v.ox + v.scale * -1.75, v.oy - v.scale * 3.625); })()",
        )
        .await;
    assert_eq!(green, json!([0x20, 0xc0, 0x20]), "the L's second shape");
    // The hinge's dot, read back from the frame that drew it.
    let dot = page
        .eval("(() => { const p = tiltbox.jointPixels()[0]; return tiltbox.pixel(p[0], p[1]); })()")
        .await;
    let rgb: Vec<u64> = serde_json::from_value(dot).unwrap();
    assert!(
        rgb.iter().all(|&c| c >= 200),
        "the hinge is drawn as a light dot on the grey pin: {rgb:?}"
    );
    s.put(
        keys.remove_joints(),
        encode(&RemoveJoints { ids: vec![joint] }).unwrap(),
    )
    .await
    .unwrap();
    page.wait_for("tiltbox.joints() === 0", 10).await;
    stop(page, gw, server).await;
}

/// A page that holds a brick and goes away (its WebSocket closes) lets the brick go at once:
/// the gateway keeps a `…/hand/<hand>` liveliness token for each hand a page grabs with, and
/// drops it with the connection, so the daemon does not wait out its 3 s time-out.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_page_that_leaves_lets_go_of_what_it_held() {
    let port = 17499;
    let server = daemon(port).await;
    let keys = server.keys().clone();
    let gw = plain_gateway(port, Allow::parse("drag").unwrap(), 120).await;
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_secs(2)).await; // the bricks land
    let red = |sc: SceneState| {
        sc.bodies
            .into_iter()
            .find(|b| b.name == "red brick")
            .unwrap()
    };
    let brick = red(scene(&s, &keys).await);
    let url = format!("ws://{}/ws", gw.local_addr());
    let (mut ws, _) = tokio_tungstenite::connect_async(url.as_str())
        .await
        .expect("connect");
    let frame = |d: Drag| {
        let mut f = vec![0x0b];
        f.extend(encode(&d).unwrap());
        WsMessage::Binary(f.into())
    };
    let hand = 9;
    ws.send(frame(Drag::Grab {
        hand,
        id: brick.id,
        point: brick.position,
    }))
    .await
    .unwrap();
    for _ in 0..10 {
        let target = Vector::new(0.0, 4.5);
        ws.send(frame(Drag::Move { hand, target })).await.unwrap();
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let held = red(scene(&s, &keys).await).position;
    assert!(held.y > 4.0, "the page holds the brick up: {held:?}");
    ws.close(None).await.unwrap();
    let left = Instant::now();
    loop {
        let y = red(scene(&s, &keys).await).position.y;
        if y < 3.5 {
            break;
        }
        assert!(
            left.elapsed() < Duration::from_millis(1500),
            "still held {:?} after the page left (y = {y})",
            left.elapsed()
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    gw.stop().await;
    server.shutdown().await.unwrap();
}

/// Finger to screen through the page: a mouse grabs the red brick and moves 1 m up; the page
/// times each first move until the first frame that draws the brick 5 mm from where it was
/// (`metrics.dragToVisible`), eight times. The figure is printed for the README beside tilt
/// to visible; asserted only to exist and to be under half a second (the page works), since
/// time is for benchmarks.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn finger_to_screen_through_the_page_is_measured() {
    let _lock = BROWSER_LOCK.lock().await;
    let port = 17495;
    let server = daemon(port).await;
    let gw = gateway_at_rate(port, "drag", 120).await;
    let keys = server.keys().clone();
    let s = session::open(&[format!("tcp/127.0.0.1:{port}")])
        .await
        .unwrap();
    let (_browser, mut page) = joined_page("finger", &gw).await;
    tokio::time::sleep(Duration::from_secs(2)).await; // the bricks land
    let size = page
        .eval("[document.getElementById('world').clientWidth, document.getElementById('world').clientHeight]")
        .await;
    let (w, h) = (size[0].as_f64().unwrap(), size[1].as_f64().unwrap());
    for round in 0..8 {
        let sc = scene(&s, &keys).await;
        let to_px = fit(&sc, w, h);
        let red = sc.bodies.iter().find(|b| b.name == "red brick").unwrap();
        let (x, y) = to_px(red.position.x, red.position.y);
        let (_, y_up) = to_px(red.position.x, red.position.y + 1.0);
        let mouse = |kind: &str, y: f64| json!({"type": kind, "x": x, "y": y, "button": "left", "buttons": 1, "clickCount": 1});
        let n0 = page.eval("tiltbox.metrics.dragToVisible.length").await;
        page.call("Input.dispatchMouseEvent", mouse("mousePressed", y))
            .await
            .unwrap();
        page.wait_for("tiltbox.hands() === 1", 5).await;
        tokio::time::sleep(Duration::from_millis(50)).await;
        page.call("Input.dispatchMouseEvent", mouse("mouseMoved", y_up))
            .await
            .unwrap();
        page.wait_for(&format!("tiltbox.metrics.dragToVisible.length > {n0}"), 5)
            .await;
        page.call("Input.dispatchMouseEvent", mouse("mouseReleased", y_up))
            .await
            .unwrap();
        page.wait_for("tiltbox.hands() === 0", 5).await;
        tokio::time::sleep(Duration::from_millis(1200 + 10 * round)).await; // it lands again
    }
    let lat: Vec<f64> =
        serde_json::from_value(page.eval("tiltbox.metrics.dragToVisible").await).unwrap();
    println!(
        "figures: finger -> drawn (first move of a drag until the body is drawn 5 mm away) \
         median {:.1} ms (n = {}, min {:.0}, max {:.0})",
        median(&lat),
        lat.len(),
        lat.iter().cloned().fold(f64::MAX, f64::min),
        lat.iter().cloned().fold(0.0, f64::max),
    );
    assert!(lat.len() >= 6 && median(&lat) < 500.0, "{lat:?}");
    stop(page, gw, server).await;
}
