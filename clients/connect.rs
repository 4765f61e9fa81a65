//! The flags every client takes to find its daemon and its world: `--world`, `--prefix`,
//! `--connect` and `--log`.

use super::session::DEFAULT_ENDPOINT;
use super::ClientError;
use crate::protocol::{Keys, DEFAULT_WORLD};

/// Which world to talk to, and where the daemon is.
#[derive(clap::Args, Clone, Debug)]
pub struct ConnectArgs {
    /// World name; keys are under tiltbox/<world> unless --prefix is given.
    #[arg(long, default_value = DEFAULT_WORLD)]
    pub world: String,
    /// Key prefix (default tiltbox/<world>).
    #[arg(long)]
    pub prefix: Option<String>,
    /// Zenoh endpoint of the daemon (repeatable).
    #[arg(long, value_name = "ENDPOINT", default_value = DEFAULT_ENDPOINT)]
    pub connect: Vec<String>,
    /// Log filter (tracing EnvFilter syntax; RUST_LOG wins) [default: info,zenoh=error; the
    /// viewer and the keyboard: error; --plain: warn].
    #[arg(long, value_name = "FILTER")]
    pub log: Option<String>,
}

impl ConnectArgs {
    /// The world's keys; a bad `--world` or `--prefix` is named with its value.
    pub fn keys(&self) -> Result<Keys, ClientError> {
        match &self.prefix {
            Some(p) => Keys::new(p)
                .map_err(|e| ClientError::Usage(format!("--prefix {p:?}: {}", e.reason))),
            None => {
                if self.world.is_empty() || self.world.contains(['/', '*', '$', '?', '#']) {
                    return Err(ClientError::Usage(format!(
                        "--world {:?}: must be a non-empty name without / * $ ? #",
                        self.world
                    )));
                }
                Keys::for_world(&self.world).map_err(|e| {
                    ClientError::Usage(format!("--world {:?}: {}", self.world, e.reason))
                })
            }
        }
    }

    /// The endpoints, checked (a bad one is named with `--connect`).
    pub fn endpoints(&self) -> Result<Vec<String>, ClientError> {
        super::session::client_config(&self.connect)?;
        Ok(self.connect.clone())
    }
}
