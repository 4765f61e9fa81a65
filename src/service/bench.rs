//! `tiltbox serve --bench-net SECONDS [--bench-viewers N] [--bench-bodies B] [--bench-router
//! ENDPOINT]`: run the daemon with an in-process client on a second Zenoh session over TCP
//! loopback, and measure tick lateness, publish-to-receive latency of snapshots and snapshot
//! sizes; N more viewer sessions (the fan-out) count what each receives, connected to the
//! daemon directly or through a Zenoh router session listening on ENDPOINT (the same router
//! code `zenohd` runs, here in the benchmark's process). [`gas_scene`] is a scene of B bodies
//! that never rest, for the fan-out at scale.

use super::config::{ServerConfig, ZenohSettings};
use super::net::{Server, ServerOptions, ServiceError};
use crate::protocol::decode_frame;
use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use zenoh::Wait;

const SLOTS: usize = 4096;

/// What a benchmark run measured. Times in microseconds.
#[derive(Clone, Debug, Default)]
pub struct BenchReport {
    /// Seconds measured.
    pub seconds: f64,
    /// Frames stepped.
    pub frames: u64,
    /// Snapshots received by the client.
    pub received: u64,
    /// Steps dropped by the loop.
    pub steps_dropped: u64,
    /// Dynamic bodies in the last keyframe.
    pub bodies: usize,
    /// Tick lateness p50, p99, max (us).
    pub lateness_us: [u32; 3],
    /// `World::step` time p50, p99, max (us).
    pub step_us: [u32; 3],
    /// Publish (just before `put`) to receive (callback entry) p50, p99, max (us).
    pub latency_us: [u32; 3],
    /// Median keyframe size (bytes) and the poses it carried.
    pub keyframe: (usize, usize),
    /// Median delta size (bytes) and the median number of poses in a delta.
    pub delta: (usize, usize),
    /// Median delta size among deltas that carried at least one pose, and their median poses.
    pub moving_delta: (usize, usize),
    /// Viewer sessions besides the measuring client.
    pub viewers: usize,
    /// The router endpoint the viewers connected through; None: straight to the daemon.
    pub router: Option<String>,
    /// Snapshots a second received per viewer: the slowest and the median viewer.
    pub viewer_hz: [f64; 2],
    /// Bytes a second received per viewer (median), and by all viewers together.
    pub viewer_bytes_per_s: [f64; 2],
}

/// A scene of `bodies` discs (radius 0.1 m, 0.4 m apart) in a closed box, no gravity, no
/// friction, fully elastic, each with its own velocity (1 to 3 m/s): bodies that never come to
/// rest, so every delta carries them all.
pub fn gas_scene(bodies: u32) -> String {
    let side = (bodies as f64).sqrt().ceil().max(1.0) as u32;
    let half = side as f64 * 0.2 + 0.5;
    let mut s = format!(
        "name = \"gas of {bodies}\"\ngravity = [0.0, 0.0]\n\n[settings]\nenable_sleep = false\n"
    );
    let wall = |x: f64, y: f64, w: f64, h: f64| {
        format!(
            "\n[[body]]\nstatic = true\nshape = {{ type = \"rect\", width = {w}, height = {h} }}\n\
             position = [{x}, {y}]\n"
        )
    };
    s += &wall(0.0, -half - 0.25, 2.0 * half + 1.0, 0.5);
    s += &wall(0.0, half + 0.25, 2.0 * half + 1.0, 0.5);
    s += &wall(-half - 0.25, 0.0, 0.5, 2.0 * half);
    s += &wall(half + 0.25, 0.0, 0.5, 2.0 * half);
    for i in 0..bodies {
        let (col, row) = ((i % side) as f64, (i / side) as f64);
        let (x, y) = (-half + 0.7 + col * 0.4, -half + 0.7 + row * 0.4);
        let a = i as f64 * 2.399_963; // the golden angle: directions spread evenly
        let speed = 1.0 + (i % 3) as f64;
        s += &format!(
            "\n[[body]]\nshape = {{ type = \"circle\", radius = 0.1 }}\nposition = [{x:.3}, {y:.3}]\n\
             velocity = [{:.3}, {:.3}]\ndensity = 1.0\nfriction = 0.0\nrestitution = 1.0\n",
            speed * a.cos(),
            speed * a.sin()
        );
    }
    s
}

fn percentiles(mut v: Vec<u32>) -> [u32; 3] {
    if v.is_empty() {
        return [0; 3];
    }
    v.sort_unstable();
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    [at(0.5), at(0.99), *v.last().unwrap()]
}

/// The smallest and the median of `v` (0 for none).
fn spread(mut v: Vec<f64>) -> [f64; 2] {
    if v.is_empty() {
        return [0.0; 2];
    }
    v.sort_by(f64::total_cmp);
    [v[0], v[v.len() / 2]]
}

fn median_pair(mut v: Vec<(usize, usize)>) -> (usize, usize) {
    if v.is_empty() {
        return (0, 0);
    }
    v.sort_unstable();
    v[v.len() / 2]
}

impl fmt::Display for BenchReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let per = |(bytes, n): (usize, usize)| {
            if n == 0 {
                "-".to_string()
            } else {
                format!("{:.1}", bytes as f64 / n as f64)
            }
        };
        let p = |v: [u32; 3]| format!("p50 {} us, p99 {} us, max {} us", v[0], v[1], v[2]);
        writeln!(
            f,
            "bench-net: {:.1} s, {} frames stepped, {} snapshots received, {} steps dropped, {} dynamic bodies",
            self.seconds, self.frames, self.received, self.steps_dropped, self.bodies
        )?;
        writeln!(f, "tick lateness:            {}", p(self.lateness_us))?;
        writeln!(f, "World::step time:         {}", p(self.step_us))?;
        writeln!(f, "publish -> receive:       {}", p(self.latency_us))?;
        writeln!(
            f,
            "keyframe:                 {} bytes, {} poses, {} bytes/body",
            self.keyframe.0,
            self.keyframe.1,
            per(self.keyframe)
        )?;
        writeln!(
            f,
            "delta (median):           {} bytes, {} poses",
            self.delta.0, self.delta.1
        )?;
        writeln!(
            f,
            "delta with motion (med.): {} bytes, {} poses, {} bytes/body",
            self.moving_delta.0,
            self.moving_delta.1,
            per(self.moving_delta)
        )?;
        write!(
            f,
            "fan-out:                  {} viewers ({}), {:.1} Hz slowest, {:.1} Hz median, {:.1} \
             kB/s each (median), {:.2} MB/s in all",
            self.viewers,
            match &self.router {
                Some(r) => format!("through a router at {r}"),
                None => "straight to the daemon".to_owned(),
            },
            self.viewer_hz[0],
            self.viewer_hz[1],
            self.viewer_bytes_per_s[0] / 1e3,
            self.viewer_bytes_per_s[1] / 1e6
        )
    }
}

struct Received {
    latency_us: u32,
    bytes: usize,
    poses: usize,
    keyframe: bool,
}

/// Run the daemon configured by `config` for `seconds` with a client connected to its first
/// listen endpoint and `viewers` more viewer sessions, and report. With `router`, the viewers
/// connect to a router session listening there, which connects to the daemon.
pub async fn bench_net(
    config: &ServerConfig,
    seconds: f64,
    viewers: usize,
    router: Option<&str>,
) -> Result<BenchReport, ServiceError> {
    let epoch = Instant::now();
    let published: Arc<Vec<AtomicU64>> = Arc::new((0..SLOTS).map(|_| AtomicU64::new(0)).collect());
    let hook = {
        let published = published.clone();
        Arc::new(move |frame: u64| {
            published[frame as usize % SLOTS]
                .store(epoch.elapsed().as_nanos() as u64, Ordering::Relaxed);
        })
    };
    let options = ServerOptions {
        record: true,
        on_publish: Some(hook),
        ..Default::default()
    };
    let server = Server::start(config, options).await?;

    let endpoint = config
        .zenoh
        .listen
        .first()
        .cloned()
        .unwrap_or_else(|| "tcp/127.0.0.1:7447".into());
    // A peer that connects to the daemon and listens on nothing, as the clients are.
    let client_endpoint = endpoint.clone();
    let client = ZenohSettings {
        mode: "peer".into(),
        listen: Vec::new(),
        connect: vec![endpoint],
        ..ZenohSettings::default()
    }
    .zenoh_config()?;
    let session = zenoh::open(client.clone())
        .await
        .map_err(|e| ServiceError::Zenoh(format!("client session: {e}")))?;
    // Optionally a router between the daemon and the viewers, as a deployment with zenohd has.
    let router_session = match router {
        Some(at) => {
            let settings = ZenohSettings {
                mode: "router".into(),
                listen: vec![at.to_owned()],
                connect: vec![client_endpoint.clone()],
                ..ZenohSettings::default()
            }
            .zenoh_config()?;
            Some(
                zenoh::open(settings)
                    .await
                    .map_err(|e| ServiceError::Zenoh(format!("router session on {at}: {e}")))?,
            )
        }
        None => None,
    };
    // Through a router the viewers are Zenoh clients: a client talks to its router only, so
    // nothing reaches it straight from the daemon.
    let viewer = match router {
        Some(at) => ZenohSettings {
            mode: "client".into(),
            listen: Vec::new(),
            connect: vec![at.to_owned()],
            ..ZenohSettings::default()
        }
        .zenoh_config()?,
        None => client.clone(),
    };
    // The fan-out: each viewer its own session, counting snapshots and bytes.
    let mut fan = Vec::with_capacity(viewers);
    for _ in 0..viewers {
        let s = zenoh::open(viewer.clone())
            .await
            .map_err(|e| ServiceError::Zenoh(format!("viewer session: {e}")))?;
        let counts: Arc<[AtomicU64; 2]> = Arc::default();
        let c = counts.clone();
        let sub = s
            .declare_subscriber(server.keys().poses())
            .callback(move |sample| {
                c[0].fetch_add(1, Ordering::Relaxed);
                c[1].fetch_add(sample.payload().len() as u64, Ordering::Relaxed);
            })
            .await
            .map_err(|e| ServiceError::Zenoh(format!("viewer subscriber: {e}")))?;
        fan.push((s, sub, counts));
    }
    // count from here: the sessions opened one after the other, some long before
    for (_, _, counts) in &fan {
        counts[0].store(0, Ordering::Relaxed);
        counts[1].store(0, Ordering::Relaxed);
    }
    let fan_start = Instant::now();
    let samples: Arc<Mutex<Vec<Received>>> = Arc::default();
    let sub = {
        let samples = samples.clone();
        let published = published.clone();
        session
            .declare_subscriber(server.keys().poses())
            .callback(move |sample| {
                let now = epoch.elapsed().as_nanos() as u64;
                let bytes = sample.payload().to_bytes();
                if let Ok(s) = decode_frame(&bytes) {
                    let sent = published[s.frame as usize % SLOTS].load(Ordering::Relaxed);
                    let latency_us = (now.saturating_sub(sent) / 1000).min(u32::MAX as u64) as u32;
                    if let Ok(mut v) = samples.lock() {
                        v.push(Received {
                            latency_us,
                            bytes: bytes.len(),
                            poses: s.poses.len(),
                            keyframe: s.is_keyframe(),
                        });
                    }
                }
            })
            .await
            .map_err(|e| ServiceError::Zenoh(format!("client subscriber: {e}")))?
    };
    tokio::time::sleep(Duration::from_secs_f64(seconds)).await;
    let fan_secs = fan_start.elapsed().as_secs_f64();
    let mut per_viewer: Vec<(f64, f64)> = Vec::with_capacity(viewers);
    for (s, sub, counts) in fan {
        let (n, bytes) = (
            counts[0].load(Ordering::Relaxed),
            counts[1].load(Ordering::Relaxed),
        );
        per_viewer.push((n as f64 / fan_secs, bytes as f64 / fan_secs));
        let _ = sub.undeclare().await;
        let _ = s.close().await;
    }
    let _ = sub.undeclare().wait();
    let _ = session.close().await;
    if let Some(r) = router_session {
        let _ = r.close().await;
    }
    let summary = server.shutdown().await?;
    let samples = std::mem::take(&mut *samples.lock().unwrap_or_else(|e| e.into_inner()));

    let keyframes: Vec<_> = samples
        .iter()
        .filter(|s| s.keyframe)
        .map(|s| (s.bytes, s.poses))
        .collect();
    let bodies = samples
        .iter()
        .rev()
        .find(|s| s.keyframe)
        .map_or(0, |s| s.poses);
    let deltas: Vec<_> = samples.iter().filter(|s| !s.keyframe).collect();
    let delta_bytes = median_pair(deltas.iter().map(|s| (s.bytes, 0)).collect()).0;
    let delta_poses = median_pair(deltas.iter().map(|s| (s.poses, 0)).collect()).0;
    let moving: Vec<_> = deltas
        .iter()
        .filter(|s| s.poses > 0)
        .map(|s| (s.bytes, s.poses))
        .collect();
    Ok(BenchReport {
        seconds,
        frames: summary.frames,
        received: samples.len() as u64,
        steps_dropped: summary.steps_dropped,
        bodies,
        lateness_us: percentiles(summary.lateness_us),
        step_us: percentiles(summary.step_us),
        latency_us: percentiles(samples.iter().map(|s| s.latency_us).collect()),
        keyframe: median_pair(keyframes),
        delta: (delta_bytes, delta_poses),
        moving_delta: median_pair(moving),
        viewers,
        router: router.map(str::to_owned),
        viewer_hz: spread(per_viewer.iter().map(|v| v.0).collect()),
        viewer_bytes_per_s: [
            spread(per_viewer.iter().map(|v| v.1).collect())[1],
            per_viewer.iter().map(|v| v.1).sum(),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gas_scene_loads_with_its_bodies_inside_the_box() {
        for n in [1, 7, 1000] {
            let scene = crate::scene::Scene::from_toml_str(&gas_scene(n)).unwrap();
            let (world, _) = scene.build_world().unwrap();
            let dynamic: Vec<_> = world.bodies().filter(|b| !b.is_static()).collect();
            assert_eq!(dynamic.len(), n as usize);
            let half = (n as f64).sqrt().ceil() * 0.2 + 0.5;
            for b in dynamic {
                let p = b.position();
                let inside = |v: f64| v.abs() < half - 0.1;
                assert!(
                    inside(p.x as f64) && inside(p.y as f64),
                    "{p:?} outside {half}"
                );
                assert!(b.linear_velocity().length() >= 0.99);
            }
        }
    }
}
