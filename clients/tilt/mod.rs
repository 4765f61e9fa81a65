//! `tiltbox-tilt`, a phone-tilt source for a tiltbox daemon: it publishes `…/tilt` at a steady
//! rate and on every change, from one source at a time. Every source yields the protocol's own
//! [`Tilt`] messages; readings follow Android's `TYPE_ACCELEROMETER` convention (m/s^2, device
//! frame, a device at rest reads the reaction to gravity, pointing up): see
//! `docs/protocol.md`.
//!
//! - [`keyboard`]: a virtual device turned by arrow keys or put in a discrete orientation
//!   (the default in a terminal), with its terminal in `terminal` (feature `tui`);
//! - [`sweep`]: a device upright in portrait, turned about the screen's normal;
//! - [`stdin`]: JSON readings, one per line or as `termux-sensor` prints them;
//! - [`iio`]: a Linux IIO accelerometer under `/sys/bus/iio/devices`;
//! - [`publish`]: each new reading put on `…/tilt` at once, the latest again at a steady rate.
//!
//! The binary (`main.rs` here) parses [`TiltArgs`] and calls [`run`].

pub mod iio;
pub mod keyboard;
pub mod publish;
pub mod stdin;
pub mod sweep;
#[cfg(feature = "tui")]
mod terminal;

use super::connect::ConnectArgs;
use super::session::{self, ServerWatch};
use super::ClientError;
use crate::cli::wait_for_signal;
use crate::protocol::{Keys, Tilt};
use iio::IioAccel;
use publish::TiltPublisher;
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;

/// Standard gravity (m/s^2): the magnitude of the readings the sweep and keyboard make.
pub const STANDARD_GRAVITY: f32 = 9.81;

/// The flags of `tiltbox-tilt`.
#[derive(clap::Args, Debug)]
pub struct TiltArgs {
    /// Which world, on which daemon.
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Turn a virtual device continuously, DEG_PER_S degrees per second (negative: clockwise).
    #[arg(long, value_name = "DEG_PER_S", allow_negative_numbers = true,
          conflicts_with_all = ["stdin", "iio"])]
    pub sweep: Option<f64>,
    /// Read accelerometer readings (m/s^2) from stdin: {"x":..,"y":..,"z":..} lines or
    /// termux-sensor output.
    #[arg(long, conflicts_with = "iio")]
    pub stdin: bool,
    /// Read a Linux IIO accelerometer: DEVICE is a directory or a name under
    /// /sys/bus/iio/devices (default: the first with in_accel_x_raw).
    #[arg(long, value_name = "DEVICE", num_args = 0..=1)]
    pub iio: Option<Option<String>>,
    /// Messages per second when nothing changes (also the sweep's and IIO's sampling rate).
    #[arg(
        long,
        value_name = "HZ",
        default_value_t = 30.0,
        allow_negative_numbers = true
    )]
    pub rate: f64,
    /// Keyboard: degrees per arrow key press.
    #[arg(long, value_name = "DEG", default_value_t = 15.0)]
    pub step: f32,
}

impl TiltArgs {
    /// Whether the keyboard source will run: no other source asked for, and stdin is a
    /// terminal. Its terminal is raw and shows a status line, so it logs errors only.
    pub fn keyboard(&self) -> bool {
        self.sweep.is_none() && !self.stdin && self.iio.is_none() && std::io::stdin().is_terminal()
    }
}

/// The source in use, checked.
enum Source {
    Sweep(f64),
    Stdin,
    Iio(IioAccel),
    #[cfg(feature = "tui")]
    Keyboard(f32),
}

fn source(args: &TiltArgs) -> Result<Source, ClientError> {
    if let Some(d) = args.sweep {
        if !d.is_finite() || d.abs() > 36_000.0 {
            return Err(ClientError::Usage(format!(
                "--sweep {d}: must be a number of degrees per second within +-36000"
            )));
        }
        return Ok(Source::Sweep(d));
    }
    if args.stdin {
        return Ok(Source::Stdin);
    }
    if let Some(dev) = &args.iio {
        return IioAccel::open(dev.as_deref(), Path::new(iio::IIO_ROOT))
            .map(Source::Iio)
            .map_err(|e| ClientError::Usage(format!("--iio: {e}")));
    }
    if !std::io::stdin().is_terminal() {
        tracing::info!("stdin is not a terminal: reading JSON readings from it (--stdin)");
        return Ok(Source::Stdin);
    }
    #[cfg(feature = "tui")]
    {
        if !(args.step.is_finite() && args.step > 0.0 && args.step <= 90.0) {
            return Err(ClientError::Usage(format!(
                "--step {}: must be within (0, 90] degrees",
                args.step
            )));
        }
        Ok(Source::Keyboard(args.step))
    }
    #[cfg(not(feature = "tui"))]
    Err(ClientError::Usage(
        "the keyboard source needs the `tui` feature: use --sweep, --stdin or --iio".into(),
    ))
}

/// Run `tiltbox-tilt` until its source ends, the user quits, or Ctrl-C / SIGTERM.
pub fn run(args: TiltArgs) -> Result<ExitCode, ClientError> {
    let keys = args.connect.keys()?;
    let endpoints = args.connect.endpoints()?;
    if !(args.rate.is_finite() && args.rate > 0.0 && args.rate <= 1000.0) {
        return Err(ClientError::Usage(format!(
            "--rate {}: must be within (0, 1000] messages per second",
            args.rate
        )));
    }
    let source = source(&args)?;
    let rt = crate::cli::runtime()?;
    let result = rt.block_on(serve(source, keys, endpoints, args.rate));
    rt.shutdown_timeout(Duration::from_millis(100));
    result
}

async fn serve(
    source: Source,
    keys: Keys,
    endpoints: Vec<String>,
    rate: f64,
) -> Result<ExitCode, ClientError> {
    let session = session::open(&endpoints).await?;
    let prefix = keys.prefix().to_owned();
    let where_ = endpoints.join(", ");
    let watch = {
        let prefix = prefix.clone();
        session::watch_server(&session, &keys, move |up| {
            if up {
                tracing::info!("a daemon serves {prefix}");
            } else {
                tracing::warn!(
                    "the daemon of {prefix} is gone: tilts go nowhere until one is back"
                );
            }
        })
        .await?
    };
    let watch = Arc::new(watch);
    {
        let (watch, prefix, where_) = (watch.clone(), prefix.clone(), where_.clone());
        tokio::spawn(async move { warn_if_absent(&watch, &prefix, &where_).await });
    }
    let mut publisher = TiltPublisher::new(&session, &keys).await?;
    let (tx, rx) = mpsc::channel::<Tilt>(64);
    let code = match source {
        Source::Sweep(deg) => {
            tokio::spawn(sweep::sweep(deg, rate, tx));
            tracing::info!("sweeping at {deg} deg/s on {}", keys.tilt());
            run_until_signal(&mut publisher, rate, rx).await?
        }
        Source::Stdin => {
            std::thread::Builder::new()
                .name("tiltbox-tilt-stdin".into())
                .spawn(move || stdin::read_stdin(tx))?;
            run_until_signal(&mut publisher, rate, rx).await?
        }
        Source::Iio(dev) => {
            tracing::info!("reading {}", dev.dir().display());
            tokio::spawn(iio::read_iio(dev, rate, tx));
            run_until_signal(&mut publisher, rate, rx).await?
        }
        #[cfg(feature = "tui")]
        Source::Keyboard(step) => {
            drop(tx);
            terminal::run(&mut publisher, rate, step, &watch, &prefix).await?
        }
    };
    tracing::info!("{} tilt message(s) published", publisher.sent());
    drop(publisher);
    drop(watch);
    let _ = tokio::time::timeout(Duration::from_secs(1), session.close()).await;
    Ok(code)
}

async fn warn_if_absent(watch: &ServerWatch, prefix: &str, endpoints: &str) {
    tokio::time::sleep(Duration::from_millis(1500)).await;
    if !watch.is_alive() {
        tracing::warn!(
            "no daemon answers for {prefix} at {endpoints} (no liveliness token on {prefix}/server): \
             tilts are published but nothing applies them until a daemon starts"
        );
    }
}

async fn run_until_signal(
    publisher: &mut TiltPublisher,
    rate: f64,
    rx: mpsc::Receiver<Tilt>,
) -> Result<ExitCode, ClientError> {
    tokio::select! {
        r = publish::publish_loop(publisher, rate, rx) => r.map(|_| ExitCode::SUCCESS),
        _ = wait_for_signal() => Ok(ExitCode::SUCCESS),
    }
}

/// What the sources' tests share.
#[cfg(test)]
mod test_support {
    use super::STANDARD_GRAVITY;
    use crate::protocol::{Tilt, Vector};

    /// The reading a source made, or a panic naming what it made instead.
    pub(super) fn accel(t: Option<Tilt>) -> (f32, f32, f32) {
        match t {
            Some(Tilt::Accelerometer { x, y, z }) => (x, y, z),
            other => panic!("not a reading: {other:?}"),
        }
    }

    /// The gravity the daemon makes of `t` in a scene of standard gravity.
    pub(super) fn gravity(t: Tilt) -> Vector {
        t.gravity(STANDARD_GRAVITY)
    }

    /// `g` is (`x`, `y`) to within 1e-4 m/s^2.
    pub(super) fn near(g: Vector, x: f32, y: f32) -> bool {
        (g.x - x).abs() < 1e-4 && (g.y - y).abs() < 1e-4
    }
}
