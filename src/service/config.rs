//! The daemon's configuration: `config/server.toml`, overridden by command-line flags, over
//! embedded defaults (loopback only, multicast scouting off).

use crate::protocol::{Keys, DEFAULT_WORLD};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Everything the daemon can be told. `ServerConfig::default()` is what runs when no file and
/// no flag is given; `config/server.toml` spells out the same values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ServerConfig {
    /// World name; the default key prefix is `tiltbox/<world>`. Default `bricks`.
    pub world: String,
    /// Key prefix; absent means `tiltbox/<world>`.
    pub prefix: Option<String>,
    /// More worlds served by the same daemon and Zenoh session, each on its own tick thread
    /// under `tiltbox/<name>` (same scene, tick rate and limits). Default none.
    pub worlds: Vec<String>,
    /// Steps per second (dt = 1 / tick_hz). Default 60.
    pub tick_hz: f64,
    /// Scene file; absent means the embedded Falling Bricks. `…/reset` re-reads it.
    pub scene: Option<PathBuf>,
    /// Every this many frames the snapshot is a keyframe with every dynamic body. Default 60.
    pub keyframe_every: u32,
    /// Snapshot positions are sent on a grid of `2^-snapshot_grid_bits` m (0..=24). Default
    /// 10: 1/1024 m.
    pub snapshot_grid_bits: u32,
    /// How many late steps the loop runs back to back before it drops time. Default 4.
    pub max_catch_up: u32,
    /// Capacity of the command channel between Zenoh callbacks and the tick thread; a
    /// command arriving when it is full is rejected. Default 256.
    pub command_queue: u32,
    /// Threads that share the steps of every world this daemon serves: one pool, the tick
    /// threads among them (1..=64). A world whose tick finds the pool in use by another
    /// world's step steps alone; the results are the same to the bit either way. Replaces a
    /// scene's `[settings] workers`. Default 1: each tick thread steps its world alone.
    pub workers: u32,
    /// Command journal: every command taken from the channel, stamped with its frame, plus a
    /// hash of the World after every step, for `tiltbox replay`. Absent: no journal.
    pub record: Option<PathBuf>,
    /// Checkpoint file: the full state, written atomically every `checkpoint_every` seconds
    /// and on shutdown; the previous one is kept as `<file>.prev`. Absent: no checkpoints.
    pub checkpoint: Option<PathBuf>,
    /// Seconds (of simulated time) between checkpoints. Default 10.
    pub checkpoint_every: f64,
    /// Start from the checkpoint (falling back to `<file>.prev` if it is damaged) instead of
    /// the scene. Needs `checkpoint`. Default false.
    pub resume: bool,
    /// Limits on what clients may ask for.
    pub limits: Limits,
    /// The Zenoh side.
    pub zenoh: ZenohSettings,
}

/// Limits on client input; anything beyond them is rejected on `…/events`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Limits {
    /// Most bodies in the world (static ones included). Default 1000.
    pub max_bodies: u32,
    /// Most `…/spawn` commands applied per second of simulated time. Default 20.
    pub max_spawns_per_second: u32,
    /// Most bodies in one `…/spawn`. Default 64.
    pub max_bodies_per_spawn: u32,
    /// Largest payload accepted on a command key (bytes). Default 65536.
    pub max_payload_bytes: u32,
    /// Largest gravity (or accelerometer reading) magnitude accepted (m/s^2). Default 100.
    pub max_gravity: f32,
    /// Spawned bodies must lie within +-max_coordinate on both axes (the position given, the
    /// centre of mass and every polygon vertex) and be no larger (rect sides, circle and
    /// capsule diameters, capsule length, a polygon's extent along x and y), in metres.
    /// Default 1000.
    pub max_coordinate: f32,
    /// Spawned bodies must be at least this big (m): rect sides, circle and capsule diameters,
    /// capsule length, a polygon's thickness (its smallest width). Default 0.01.
    pub min_size: f32,
    /// Spawned bodies' density must lie within [min_density, max_density] (kg/m^2): extreme
    /// mass ratios make any iterative solver blow up. Defaults 0.01 and 1000.
    pub min_density: f32,
    /// See `min_density`.
    pub max_density: f32,
    /// Largest spawn speed (m/s). Default 100.
    pub max_speed: f32,
    /// Largest spawn spin (rad/s). Default 100.
    pub max_angular_speed: f32,
    /// Largest friction coefficient. Default 10.
    pub max_friction: f32,
    /// Longest body name (bytes of UTF-8). Default 64.
    pub max_name_bytes: u32,
    /// Most `…/query` requests answered per second (wall clock, all clients together: Zenoh
    /// does not say who asked), with a second's burst; more are refused. Default 600.
    pub max_queries_per_second: u32,
}

/// How the daemon joins Zenoh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ZenohSettings {
    /// `peer`, `client` or `router`. Default `peer`.
    pub mode: String,
    /// Endpoints to listen on. Default `["tcp/127.0.0.1:7447"]`: loopback only.
    pub listen: Vec<String>,
    /// Endpoints to connect to. Default none.
    pub connect: Vec<String>,
    /// UDP multicast scouting. Default off.
    pub multicast_scouting: bool,
    /// A full Zenoh json5 config (e.g. `config/zenoh/lan.json5`); when set it is used as it is
    /// and `mode`, `listen`, `connect` and `multicast_scouting` are ignored.
    pub config_file: Option<PathBuf>,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            world: DEFAULT_WORLD.to_owned(),
            prefix: None,
            worlds: Vec::new(),
            tick_hz: 60.0,
            scene: None,
            keyframe_every: 60,
            snapshot_grid_bits: crate::protocol::snapshot::DEFAULT_GRID_BITS as u32,
            max_catch_up: 4,
            command_queue: 256,
            workers: 1,
            record: None,
            checkpoint: None,
            checkpoint_every: 10.0,
            resume: false,
            limits: Limits::default(),
            zenoh: ZenohSettings::default(),
        }
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_bodies: 1000,
            max_spawns_per_second: 20,
            max_bodies_per_spawn: 64,
            max_payload_bytes: 65536,
            max_gravity: 100.0,
            max_coordinate: 1000.0,
            min_size: 0.01,
            min_density: 0.01,
            max_density: 1000.0,
            max_speed: 100.0,
            max_angular_speed: 100.0,
            max_friction: 10.0,
            max_name_bytes: 64,
            max_queries_per_second: 600,
        }
    }
}

impl ZenohSettings {
    /// The Zenoh configuration these settings describe (the file's when `config_file` is
    /// set); a value Zenoh refuses is named by its key.
    pub fn zenoh_config(&self) -> Result<zenoh::Config, ConfigError> {
        let z = self;
        if let Some(path) = &z.config_file {
            return zenoh::Config::from_file(path).map_err(|e| {
                invalid(
                    "zenoh.config_file",
                    path.display(),
                    format!("not a usable Zenoh config: {e}"),
                )
            });
        }
        let json_list = |v: &[String]| {
            let items: Vec<String> = v.iter().map(|s| format!("\"{s}\"")).collect();
            format!("[{}]", items.join(","))
        };
        let mut c = zenoh::Config::default();
        let set = |c: &mut zenoh::Config, zkey: &str, key: &'static str, value: String| {
            c.insert_json5(zkey, &value)
                .map_err(|e| invalid(key, &value, format!("refused by Zenoh: {e}")))
        };
        set(&mut c, "mode", "zenoh.mode", format!("\"{}\"", z.mode))?;
        set(
            &mut c,
            "listen/endpoints",
            "zenoh.listen",
            json_list(&z.listen),
        )?;
        set(
            &mut c,
            "connect/endpoints",
            "zenoh.connect",
            json_list(&z.connect),
        )?;
        set(
            &mut c,
            "scouting/multicast/enabled",
            "zenoh.multicast_scouting",
            z.multicast_scouting.to_string(),
        )?;
        Ok(c)
    }
}

impl Default for ZenohSettings {
    fn default() -> Self {
        ZenohSettings {
            mode: "peer".to_owned(),
            listen: vec!["tcp/127.0.0.1:7447".to_owned()],
            connect: Vec::new(),
            multicast_scouting: false,
            config_file: None,
        }
    }
}

/// A configuration the daemon refuses. Messages name the key and the value.
#[derive(Debug, Error)]
pub enum ConfigError {
    /// The config file could not be read.
    #[error("cannot read config file {}: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not TOML or has an unknown key or a wrong type (toml's message names both).
    #[error("config file {}: {message}", path.display())]
    Parse {
        /// The path.
        path: PathBuf,
        /// toml's message, with line and column.
        message: String,
    },
    /// A value is out of range.
    #[error("config key {key} = {value}: {expected}")]
    Invalid {
        /// The key, e.g. `limits.max_bodies`.
        key: &'static str,
        /// The value as given.
        value: String,
        /// What is accepted.
        expected: String,
    },
}

fn invalid(
    key: &'static str,
    value: impl fmt::Display,
    expected: impl Into<String>,
) -> ConfigError {
    ConfigError::Invalid {
        key,
        value: value.to_string(),
        expected: expected.into(),
    }
}

impl ServerConfig {
    /// Parse TOML text (`path` is only used in messages). Unknown keys are errors.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<ServerConfig, ConfigError> {
        toml::from_str(text).map_err(|e| ConfigError::Parse {
            path: path.to_owned(),
            message: e.to_string().trim_end().to_owned(),
        })
    }

    /// Read and parse a config file (not yet validated: flags may still override it).
    pub fn load(path: &Path) -> Result<ServerConfig, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.to_owned(),
            source,
        })?;
        ServerConfig::from_toml_str(&text, path)
    }

    /// The key prefix in force: `prefix`, or `tiltbox/<world>`.
    pub fn key_prefix(&self) -> String {
        self.prefix
            .clone()
            .unwrap_or_else(|| Keys::default_prefix(&self.world))
    }

    /// The keys in force (validated by [`ServerConfig::validate`]).
    pub fn keys(&self) -> Result<Keys, ConfigError> {
        let prefix = self.key_prefix();
        Keys::new(&prefix).map_err(|e| {
            let key = if self.prefix.is_some() {
                "prefix"
            } else {
                "world"
            };
            invalid(key, format!("{prefix:?}"), e.reason)
        })
    }

    /// dt in seconds.
    pub fn dt(&self) -> f64 {
        1.0 / self.tick_hz
    }

    /// Refuse values the daemon cannot run with, naming the key and the value.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.world.is_empty() || self.world.contains(['/', '*', '$', '?', '#']) {
            return Err(invalid(
                "world",
                format!("{:?}", self.world),
                "must be a non-empty name without / * $ ? #",
            ));
        }
        self.keys()?;
        for (i, w) in self.worlds.iter().enumerate() {
            let bad = w.is_empty()
                || w.contains(['/', '*', '$', '?', '#'])
                || *w == self.world
                || self.worlds[..i].contains(w)
                || Keys::for_world(w).is_err();
            if bad {
                return Err(invalid(
                    "worlds",
                    format!("{w:?}"),
                    "each must be a non-empty name without / * $ ? #, different from world and from each other",
                ));
            }
        }
        if !(self.tick_hz.is_finite() && (1.0..=1000.0).contains(&self.tick_hz)) {
            return Err(invalid("tick_hz", self.tick_hz, "must be within 1..=1000"));
        }
        let count = |key, v: u32, lo: u32, hi: u32| {
            if (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(invalid(key, v, format!("must be within {lo}..={hi}")))
            }
        };
        count("keyframe_every", self.keyframe_every, 1, 1_000_000)?;
        let max_grid = crate::protocol::snapshot::MAX_GRID_BITS;
        count(
            "snapshot_grid_bits",
            self.snapshot_grid_bits,
            0,
            max_grid as u32,
        )?;
        count("max_catch_up", self.max_catch_up, 0, 1000)?;
        count("command_queue", self.command_queue, 1, 1_000_000)?;
        count(
            "workers",
            self.workers,
            1,
            crate::physics::settings::MAX_WORKERS,
        )?;
        if !(self.checkpoint_every.is_finite()
            && (0.01..=86_400.0).contains(&self.checkpoint_every))
        {
            return Err(invalid(
                "checkpoint_every",
                self.checkpoint_every,
                "must be within 0.01..=86400 seconds",
            ));
        }
        if self.checkpoint.is_none()
            && self.checkpoint_every != ServerConfig::default().checkpoint_every
        {
            return Err(invalid(
                "checkpoint_every",
                self.checkpoint_every,
                "has no effect without a checkpoint file (config key checkpoint, flag --checkpoint)",
            ));
        }
        if self.resume && self.checkpoint.is_none() {
            return Err(invalid(
                "resume",
                true,
                "needs a checkpoint file (config key checkpoint, flag --checkpoint)",
            ));
        }
        let l = &self.limits;
        count("limits.max_bodies", l.max_bodies, 1, 1_000_000)?;
        count(
            "limits.max_spawns_per_second",
            l.max_spawns_per_second,
            1,
            1_000_000,
        )?;
        count(
            "limits.max_bodies_per_spawn",
            l.max_bodies_per_spawn,
            1,
            1_000_000,
        )?;
        count(
            "limits.max_payload_bytes",
            l.max_payload_bytes,
            16,
            64 << 20,
        )?;
        let positive = |key, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(key, v, "must be a finite number > 0"))
            }
        };
        positive("limits.max_gravity", l.max_gravity)?;
        positive("limits.max_coordinate", l.max_coordinate)?;
        positive("limits.min_size", l.min_size)?;
        positive("limits.min_density", l.min_density)?;
        positive("limits.max_density", l.max_density)?;
        positive("limits.max_speed", l.max_speed)?;
        positive("limits.max_angular_speed", l.max_angular_speed)?;
        positive("limits.max_friction", l.max_friction)?;
        if f64::from(l.max_friction) > f64::from(crate::physics::body::MAX_FRICTION) {
            return Err(invalid(
                "limits.max_friction",
                l.max_friction,
                format!(
                    "must be <= {} (the engine's largest friction coefficient)",
                    crate::physics::body::MAX_FRICTION
                ),
            ));
        }
        count("limits.max_name_bytes", l.max_name_bytes, 0, 1 << 20)?;
        count(
            "limits.max_queries_per_second",
            l.max_queries_per_second,
            1,
            1_000_000,
        )?;
        if l.min_size > l.max_coordinate || l.min_density > l.max_density {
            return Err(invalid(
                "limits.min_size / limits.min_density",
                format!("{} / {}", l.min_size, l.min_density),
                "must not exceed limits.max_coordinate / limits.max_density",
            ));
        }
        let z = &self.zenoh;
        if !["peer", "client", "router"].contains(&z.mode.as_str()) {
            return Err(invalid(
                "zenoh.mode",
                format!("{:?}", z.mode),
                "must be \"peer\", \"client\" or \"router\"",
            ));
        }
        for (key, list) in [("zenoh.listen", &z.listen), ("zenoh.connect", &z.connect)] {
            for e in list {
                let ok = e
                    .split_once('/')
                    .is_some_and(|(proto, addr)| !proto.is_empty() && !addr.is_empty());
                if !ok || e.contains('"') {
                    return Err(invalid(
                        key,
                        format!("{e:?}"),
                        "must be a Zenoh endpoint such as \"tcp/127.0.0.1:7447\"",
                    ));
                }
            }
        }
        if z.mode == "client" && z.connect.is_empty() && z.config_file.is_none() {
            return Err(invalid(
                "zenoh.connect",
                "[]",
                "client mode needs at least one endpoint to connect to",
            ));
        }
        Ok(())
    }

    /// The Zenoh configuration: `zenoh.config_file` as it is, or one built from mode, listen,
    /// connect and multicast scouting.
    pub fn zenoh_config(&self) -> Result<zenoh::Config, ConfigError> {
        self.zenoh.zenoh_config()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_loopback_only() {
        let c = ServerConfig::default();
        c.validate().unwrap();
        assert_eq!(c.key_prefix(), "tiltbox/bricks");
        assert_eq!(c.zenoh.listen, ["tcp/127.0.0.1:7447"]);
        assert!(!c.zenoh.multicast_scouting);
        c.zenoh_config().unwrap();
    }

    #[test]
    fn bad_values_name_key_and_value() {
        let mut c = ServerConfig::default();
        c.limits.max_bodies = 0;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("limits.max_bodies") && e.contains("= 0"), "{e}");
        let c = ServerConfig {
            tick_hz: f64::NAN,
            ..Default::default()
        };
        assert!(c
            .validate()
            .unwrap_err()
            .to_string()
            .contains("tick_hz = NaN"));
        let mut c = ServerConfig::default();
        c.zenoh.listen = vec!["nonsense".into()];
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("zenoh.listen") && e.contains("nonsense"), "{e}");
        let c = ServerConfig {
            prefix: Some("a/*".into()),
            ..Default::default()
        };
        assert!(c.validate().unwrap_err().to_string().contains("prefix"));
        let e = ServerConfig::from_toml_str("tick_hz = \"fast\"\n", Path::new("x.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("tick_hz"), "{e}");
        let e = ServerConfig::from_toml_str("[limits]\nmax_bodes = 3\n", Path::new("x.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("max_bodes"), "{e}");
        for workers in [0, 65] {
            let e = ServerConfig {
                workers,
                ..Default::default()
            }
            .validate()
            .unwrap_err()
            .to_string();
            assert!(
                e.contains(&format!("workers = {workers}")) && e.contains("1..=64"),
                "{e}"
            );
        }
    }
}
