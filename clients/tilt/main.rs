//! `tiltbox-tilt`: a phone-tilt source for a tiltbox daemon. Publishes `…/tilt` at a steady
//! rate and on every change, from the keyboard (the default in a terminal), a sweep, JSON
//! readings on stdin (e.g. `termux-sensor -s accelerometer`) or a Linux IIO accelerometer.
//!
//! A thin program: flags and terminal I/O here, sources and publishing in
//! `tiltbox::client::tilt`.

#[cfg(feature = "tui")]
mod keyboard;

use clap::Parser;
use std::io::{BufRead, IsTerminal};
use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;
use tiltbox::client::args::{init_logging, ConnectArgs};
use tiltbox::client::session::{self, ServerWatch};
use tiltbox::client::tilt::{self, IioAccel, StdinParser, TiltPublisher, IIO_ROOT};
use tiltbox::client::ClientError;
use tiltbox::protocol::{Keys, Tilt};
use tokio::sync::mpsc;

/// Tilt a tiltbox world: arrow keys and p/u/l/r/f/d in a terminal, or --sweep, --stdin, --iio.
#[derive(Parser, Debug)]
#[command(name = "tiltbox-tilt", version, about)]
struct Cli {
    #[command(flatten)]
    connect: ConnectArgs,
    /// Turn a virtual device continuously, DEG_PER_S degrees per second (negative: clockwise).
    #[arg(long, value_name = "DEG_PER_S", allow_negative_numbers = true,
          conflicts_with_all = ["stdin", "iio"])]
    sweep: Option<f64>,
    /// Read accelerometer readings (m/s^2) from stdin: {"x":..,"y":..,"z":..} lines or
    /// termux-sensor output.
    #[arg(long, conflicts_with = "iio")]
    stdin: bool,
    /// Read a Linux IIO accelerometer: DEVICE is a directory or a name under
    /// /sys/bus/iio/devices (default: the first with in_accel_x_raw).
    #[arg(long, value_name = "DEVICE", num_args = 0..=1)]
    iio: Option<Option<String>>,
    /// Messages per second when nothing changes (also the sweep's and IIO's sampling rate).
    #[arg(
        long,
        value_name = "HZ",
        default_value_t = 30.0,
        allow_negative_numbers = true
    )]
    rate: f64,
    /// Keyboard: degrees per arrow key press.
    #[arg(long, value_name = "DEG", default_value_t = 15.0)]
    step: f32,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // In keyboard mode the terminal is raw and shows a status line: log errors only.
    let keyboard =
        cli.sweep.is_none() && !cli.stdin && cli.iio.is_none() && std::io::stdin().is_terminal();
    let default_filter = if keyboard {
        "error"
    } else {
        "info,zenoh=error"
    };
    init_logging(Some(cli.connect.log.as_deref().unwrap_or(default_filter)));
    match run(cli) {
        Ok(code) => code,
        Err(ClientError::Usage(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

enum Source {
    Sweep(f64),
    Stdin,
    Iio(IioAccel),
    #[cfg(feature = "tui")]
    Keyboard(f32),
}

fn source(cli: &Cli) -> Result<Source, ClientError> {
    if let Some(d) = cli.sweep {
        if !d.is_finite() || d.abs() > 36_000.0 {
            return Err(ClientError::Usage(format!(
                "--sweep {d}: must be a number of degrees per second within +-36000"
            )));
        }
        return Ok(Source::Sweep(d));
    }
    if cli.stdin {
        return Ok(Source::Stdin);
    }
    if let Some(dev) = &cli.iio {
        return IioAccel::open(dev.as_deref(), Path::new(IIO_ROOT))
            .map(Source::Iio)
            .map_err(|e| ClientError::Usage(format!("--iio: {e}")));
    }
    if !std::io::stdin().is_terminal() {
        tracing::info!("stdin is not a terminal: reading JSON readings from it (--stdin)");
        return Ok(Source::Stdin);
    }
    #[cfg(feature = "tui")]
    {
        if !(cli.step.is_finite() && cli.step > 0.0 && cli.step <= 90.0) {
            return Err(ClientError::Usage(format!(
                "--step {}: must be within (0, 90] degrees",
                cli.step
            )));
        }
        Ok(Source::Keyboard(cli.step))
    }
    #[cfg(not(feature = "tui"))]
    Err(ClientError::Usage(
        "the keyboard source needs the `tui` feature: use --sweep, --stdin or --iio".into(),
    ))
}

fn run(cli: Cli) -> Result<ExitCode, ClientError> {
    let keys = cli.connect.keys()?;
    let endpoints = cli.connect.endpoints()?;
    if !(cli.rate.is_finite() && cli.rate > 0.0 && cli.rate <= 1000.0) {
        return Err(ClientError::Usage(format!(
            "--rate {}: must be within (0, 1000] messages per second",
            cli.rate
        )));
    }
    let source = source(&cli)?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let result = rt.block_on(serve(source, keys, endpoints, cli.rate));
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
            tokio::spawn(tilt::sweep(deg, rate, tx));
            tracing::info!("sweeping at {deg} deg/s on {}", keys.tilt());
            run_until_signal(&mut publisher, rate, rx).await?
        }
        Source::Stdin => {
            std::thread::Builder::new()
                .name("tiltbox-tilt-stdin".into())
                .spawn(move || read_stdin(tx))?;
            run_until_signal(&mut publisher, rate, rx).await?
        }
        Source::Iio(dev) => {
            tracing::info!("reading {}", dev.dir().display());
            tokio::spawn(read_iio(dev, rate, tx));
            run_until_signal(&mut publisher, rate, rx).await?
        }
        #[cfg(feature = "tui")]
        Source::Keyboard(step) => {
            drop(tx);
            keyboard::run(&mut publisher, rate, step, &watch, &prefix).await?
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
        r = tilt::publish_loop(publisher, rate, rx) => r.map(|_| ExitCode::SUCCESS),
        _ = session::wait_for_signal() => Ok(ExitCode::SUCCESS),
    }
}

/// Parse stdin line by line; bad lines are reported with their number and skipped.
fn read_stdin(tx: mpsc::Sender<Tilt>) {
    let mut parser = StdinParser::new();
    let (mut readings, mut bad) = (0u64, 0u64);
    for (i, line) in std::io::stdin().lock().lines().enumerate() {
        let line = match line {
            Ok(l) => l,
            Err(e) => {
                tracing::error!("stdin line {}: {e}", i + 1);
                break;
            }
        };
        match parser.line(&line) {
            Ok(Some(t)) => {
                readings += 1;
                if tx.blocking_send(t).is_err() {
                    return;
                }
            }
            Ok(None) => {}
            Err(e) => {
                bad += 1;
                tracing::warn!("stdin {e} (skipped)");
            }
        }
    }
    if let Err(e) = parser.finish() {
        bad += 1;
        tracing::warn!("stdin {e} (skipped)");
    }
    tracing::info!("end of stdin: {readings} reading(s), {bad} bad line(s) skipped");
}

async fn read_iio(dev: IioAccel, rate: f64, tx: mpsc::Sender<Tilt>) {
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate));
    let mut last: Option<Tilt> = None;
    let mut last_error = String::new();
    loop {
        tick.tick().await;
        match dev.read() {
            Ok(t) if Some(t) != last => {
                last = Some(t);
                if tx.send(t).await.is_err() {
                    return;
                }
            }
            Ok(_) => {}
            Err(e) if e != last_error => {
                tracing::warn!("{e}");
                last_error = e;
            }
            Err(_) => {}
        }
    }
}
