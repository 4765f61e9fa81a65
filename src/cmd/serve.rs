//! `tiltbox serve` (and plain `tiltbox`): run the daemon until Ctrl-C / SIGTERM.
//!
//! Configuration: embedded defaults, then `--config FILE` (TOML, see `config/server.toml`),
//! then flags. A bad value is reported with its key and exit code 2.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;
use tiltbox::cli::{init_logging, runtime, wait_for_signal, Failure};
use tiltbox::service::{
    bench_net, gas_scene, shutdown_worlds, start_worlds, ConfigError, ServerConfig, ServerOptions,
    ServiceError,
};

/// Arguments of `tiltbox serve`. Every config value has a flag; a flag overrides the file.
#[derive(clap::Args, Default, Debug)]
pub struct ServeArgs {
    /// Config file (TOML, like config/server.toml). Without it the embedded defaults apply.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// World name [config: world; default bricks].
    #[arg(long)]
    pub world: Option<String>,
    /// Key prefix [config: prefix; default tiltbox/<world>].
    #[arg(long)]
    pub prefix: Option<String>,
    /// Another world to serve from this daemon (own tick thread, prefix tiltbox/NAME),
    /// repeatable; replaces the configured list [config: worlds].
    #[arg(long = "also-world", value_name = "NAME")]
    pub worlds: Vec<String>,
    /// Steps per second [config: tick_hz; default 60].
    #[arg(long, value_name = "HZ")]
    pub tick_hz: Option<f64>,
    /// Scene file [config: scene; default: the embedded Falling Bricks].
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Keyframe interval in frames [config: keyframe_every; default 60].
    #[arg(long, value_name = "FRAMES")]
    pub keyframe_every: Option<u32>,
    /// Snapshot positions on a grid of 2^-BITS m, 0..=24 [config: snapshot_grid_bits;
    /// default 10, 1/1024 m].
    #[arg(long, value_name = "BITS")]
    pub snapshot_grid_bits: Option<u32>,
    /// Late steps run back to back before time is dropped [config: max_catch_up; default 4].
    #[arg(long, value_name = "STEPS")]
    pub max_catch_up: Option<u32>,
    /// Command channel capacity [config: command_queue; default 256].
    #[arg(long, value_name = "N")]
    pub command_queue: Option<u32>,
    /// Threads sharing the steps of every world served, one pool, 1..=64 [config: workers;
    /// default 1].
    #[arg(long, value_name = "N")]
    pub workers: Option<u32>,
    /// [config: limits.max_bodies; default 1000]
    #[arg(long, value_name = "N")]
    pub max_bodies: Option<u32>,
    /// [config: limits.max_spawns_per_second; default 20]
    #[arg(long, value_name = "N")]
    pub max_spawns_per_second: Option<u32>,
    /// `…/query` requests answered per second, all clients together [config: limits.max_queries_per_second; default 600]
    #[arg(long, value_name = "N")]
    pub max_queries_per_second: Option<u32>,
    /// [config: limits.max_bodies_per_spawn; default 64]
    #[arg(long, value_name = "N")]
    pub max_bodies_per_spawn: Option<u32>,
    /// [config: limits.max_payload_bytes; default 65536]
    #[arg(long, value_name = "BYTES")]
    pub max_payload_bytes: Option<u32>,
    /// Largest gravity / accelerometer magnitude, m/s^2 [config: limits.max_gravity; default 100]
    #[arg(long, value_name = "M_S2")]
    pub max_gravity: Option<f32>,
    /// Spawn positions and sizes within +-this, metres [config: limits.max_coordinate; default 1000]
    #[arg(long, value_name = "M")]
    pub max_coordinate: Option<f32>,
    /// Smallest spawned size (box side, circle or capsule diameter, polygon width), m [config: limits.min_size; default 0.01]
    #[arg(long, value_name = "M")]
    pub min_size: Option<f32>,
    /// [config: limits.min_density; default 0.01 kg/m^2]
    #[arg(long, value_name = "KG_M2")]
    pub min_density: Option<f32>,
    /// [config: limits.max_density; default 1000 kg/m^2]
    #[arg(long, value_name = "KG_M2")]
    pub max_density: Option<f32>,
    /// Fastest spawn, m/s [config: limits.max_speed; default 100]
    #[arg(long, value_name = "M_S")]
    pub max_speed: Option<f32>,
    /// Fastest spawn spin, rad/s [config: limits.max_angular_speed; default 100]
    #[arg(long, value_name = "RAD_S")]
    pub max_angular_speed: Option<f32>,
    /// [config: limits.max_friction; default 10]
    #[arg(long, value_name = "MU")]
    pub max_friction: Option<f32>,
    /// Longest body name, bytes [config: limits.max_name_bytes; default 64]
    #[arg(long, value_name = "BYTES")]
    pub max_name_bytes: Option<u32>,
    /// Zenoh mode: peer, client or router [config: zenoh.mode; default peer].
    #[arg(long)]
    pub mode: Option<String>,
    /// Listen endpoint, repeatable; replaces the configured list [config: zenoh.listen;
    /// default tcp/127.0.0.1:7447].
    #[arg(long, value_name = "ENDPOINT")]
    pub listen: Vec<String>,
    /// Connect endpoint, repeatable; replaces the configured list [config: zenoh.connect].
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Vec<String>,
    /// UDP multicast scouting [config: zenoh.multicast_scouting; default false].
    #[arg(long, value_name = "BOOL")]
    pub multicast_scouting: Option<bool>,
    /// A full Zenoh json5 config, used as it is: --mode, --listen, --connect and
    /// --multicast-scouting are refused with it [config: zenoh.config_file].
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
    /// Write a command journal (commands stamped with their frame, a state hash per frame)
    /// for `tiltbox replay` [config: record].
    #[arg(long, value_name = "LOG")]
    pub record: Option<PathBuf>,
    /// Checkpoint file, written atomically every --checkpoint-every seconds and on shutdown;
    /// the previous one is kept as FILE.prev [config: checkpoint].
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints; needs --checkpoint [config: checkpoint_every; default 10].
    #[arg(long, value_name = "SECONDS")]
    pub checkpoint_every: Option<f64>,
    /// Start from the checkpoint (or FILE.prev if it is damaged) instead of the scene
    /// [config: resume; default false].
    #[arg(long)]
    pub resume: bool,
    /// Log filter (tracing EnvFilter syntax; RUST_LOG wins) [default info,zenoh=error: Zenoh's own warnings repeat what the daemon reports in its own words].
    #[arg(long, value_name = "FILTER")]
    pub log: Option<String>,
    /// Instead of serving: run the daemon with an in-process client for SECONDS and print
    /// tick lateness, publish-to-receive latency and snapshot sizes.
    #[arg(long, value_name = "SECONDS")]
    pub bench_net: Option<f64>,
    /// With --bench-net: viewer sessions subscribing to the poses besides the measuring one
    /// (the fan-out; each counts the snapshots and bytes it receives).
    #[arg(long, value_name = "N", default_value_t = 100, requires = "bench_net")]
    pub bench_viewers: usize,
    /// With --bench-net: serve a generated scene of B discs that never rest (a gas in a box,
    /// every body in every delta) instead of the configured one.
    #[arg(long, value_name = "B", requires = "bench_net",
          value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub bench_bodies: Option<u32>,
    /// With --bench-net: the viewers connect through a Zenoh router session listening on
    /// ENDPOINT (e.g. tcp/127.0.0.1:7448), which connects to the daemon, instead of directly.
    #[arg(long, value_name = "ENDPOINT", requires = "bench_net")]
    pub bench_router: Option<String>,
}

impl ServeArgs {
    /// The config: the file (or the embedded defaults), then every flag given.
    pub fn config(&self) -> Result<ServerConfig, ConfigError> {
        let mut c = match &self.config {
            Some(path) => ServerConfig::load(path)?,
            None => ServerConfig::default(),
        };
        fn set<T: Clone>(slot: &mut T, v: &Option<T>) {
            if let Some(v) = v {
                *slot = v.clone();
            }
        }
        set(&mut c.world, &self.world);
        if self.prefix.is_some() {
            c.prefix = self.prefix.clone();
        }
        if !self.worlds.is_empty() {
            c.worlds = self.worlds.clone();
        }
        set(&mut c.tick_hz, &self.tick_hz);
        if self.scene.is_some() {
            c.scene = self.scene.clone();
        }
        set(&mut c.keyframe_every, &self.keyframe_every);
        set(&mut c.snapshot_grid_bits, &self.snapshot_grid_bits);
        set(&mut c.max_catch_up, &self.max_catch_up);
        set(&mut c.command_queue, &self.command_queue);
        set(&mut c.workers, &self.workers);
        if self.record.is_some() {
            c.record = self.record.clone();
        }
        if self.checkpoint.is_some() {
            c.checkpoint = self.checkpoint.clone();
        }
        set(&mut c.checkpoint_every, &self.checkpoint_every);
        if self.resume {
            c.resume = true;
        }
        let l = &mut c.limits;
        set(&mut l.max_bodies, &self.max_bodies);
        set(&mut l.max_spawns_per_second, &self.max_spawns_per_second);
        set(&mut l.max_bodies_per_spawn, &self.max_bodies_per_spawn);
        set(&mut l.max_payload_bytes, &self.max_payload_bytes);
        set(&mut l.max_gravity, &self.max_gravity);
        set(&mut l.max_coordinate, &self.max_coordinate);
        set(&mut l.min_size, &self.min_size);
        set(&mut l.min_density, &self.min_density);
        set(&mut l.max_density, &self.max_density);
        set(&mut l.max_speed, &self.max_speed);
        set(&mut l.max_angular_speed, &self.max_angular_speed);
        set(&mut l.max_friction, &self.max_friction);
        set(&mut l.max_name_bytes, &self.max_name_bytes);
        set(&mut l.max_queries_per_second, &self.max_queries_per_second);
        let z = &mut c.zenoh;
        set(&mut z.mode, &self.mode);
        if !self.listen.is_empty() {
            z.listen = self.listen.clone();
        }
        if !self.connect.is_empty() {
            z.connect = self.connect.clone();
        }
        set(&mut z.multicast_scouting, &self.multicast_scouting);
        if self.zenoh_config.is_some() {
            z.config_file = self.zenoh_config.clone();
        }
        // A Zenoh config file is used as it is: a flag that would set what it sets is refused
        // rather than silently dropped.
        if let Some(file) = &z.config_file {
            let given: Vec<&str> = [
                ("--listen", !self.listen.is_empty()),
                ("--connect", !self.connect.is_empty()),
                ("--mode", self.mode.is_some()),
                ("--multicast-scouting", self.multicast_scouting.is_some()),
            ]
            .into_iter()
            .filter_map(|(flag, given)| given.then_some(flag))
            .collect();
            if !given.is_empty() {
                return Err(ConfigError::Invalid {
                    key: "zenoh.config_file",
                    value: file.display().to_string(),
                    expected: format!(
                        "is used as it is, so {} would be ignored: set it in that file, or drop \
                         the file",
                        given.join(", ")
                    ),
                });
            }
        }
        // The config cannot tell a checkpoint_every left at its default from one given; the
        // flag can, so `--checkpoint-every 10` alone is refused as `--checkpoint-every 5` is.
        if let (Some(every), None) = (self.checkpoint_every, &c.checkpoint) {
            return Err(ConfigError::Invalid {
                key: "checkpoint_every",
                value: every.to_string(),
                expected: "has no effect without a checkpoint file (config key checkpoint, flag \
                           --checkpoint)"
                    .into(),
            });
        }
        c.validate()?;
        Ok(c)
    }
}

/// Run `tiltbox serve`.
pub fn run(args: ServeArgs) -> Result<ExitCode, Failure> {
    init_logging(args.log.as_deref(), "info,zenoh=error");
    let config = args
        .config()
        .map_err(|e| Failure::Usage(format!("bad config: {e}")))?;
    let runtime = runtime().map_err(anyhow::Error::from)?;
    let result = runtime.block_on(async {
        if let Some(seconds) = args.bench_net {
            let mut config = config.clone();
            if let Some(b) = args.bench_bodies {
                let path =
                    std::env::temp_dir().join(format!("tiltbox-gas-{}.toml", std::process::id()));
                std::fs::write(&path, gas_scene(b)).map_err(anyhow::Error::from)?;
                config.scene = Some(path);
                config.limits.max_bodies = config.limits.max_bodies.max(b + 4);
            }
            let report = bench_net(
                &config,
                seconds,
                args.bench_viewers,
                args.bench_router.as_deref(),
            )
            .await
            .map_err(failure)?;
            println!("{report}");
            return Ok(ExitCode::SUCCESS);
        }
        let servers = start_worlds(&config, ServerOptions::default())
            .await
            .map_err(failure)?;
        wait_for_signal().await;
        tracing::info!("stopping");
        match tokio::time::timeout(Duration::from_millis(1900), shutdown_worlds(servers)).await {
            Ok(Ok(_)) => {}
            Ok(Err(e)) => tracing::warn!("shutdown: {e}"),
            Err(_) => tracing::warn!("shutdown took more than 2 s; exiting anyway"),
        }
        Ok(ExitCode::SUCCESS)
    });
    runtime.shutdown_timeout(Duration::from_millis(100));
    result
}

/// Config and scene problems are usage errors (exit 2), anything else a failure (exit 1).
fn failure(e: ServiceError) -> Failure {
    match e {
        ServiceError::Config(_) | ServiceError::Start(_) => Failure::usage(e),
        e => Failure::Failed(e.into()),
    }
}
