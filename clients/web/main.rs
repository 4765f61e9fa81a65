//! `tiltbox-web`: serve a page that draws a tiltbox world and tilts it from a phone's motion
//! sensor, relaying the daemon's Zenoh keys over a WebSocket.
//!
//! A thin program: flags, a Zenoh session, then `tiltbox::client::web::Gateway`.

use clap::Parser;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use tiltbox::cli::{init_logging, wait_for_signal};
use tiltbox::client::connect::ConnectArgs;
use tiltbox::client::session;
use tiltbox::client::web::wire::Allow;
use tiltbox::client::web::{qr_text, Gateway, TlsMode, WebError, WebOptions};

/// Serve a web page that draws a tiltbox world and tilts it with a phone's motion sensor.
#[derive(Parser, Debug)]
#[command(name = "tiltbox-web", version, about)]
struct Cli {
    #[command(flatten)]
    connect: ConnectArgs,
    /// Address for the page (HTTPS). 0.0.0.0:8443 lets phones on the LAN in: anyone who
    /// reaches that port may watch every world and send what --allow allows.
    #[arg(long, default_value = "127.0.0.1:8443")]
    listen: SocketAddr,
    /// PEM certificate chain (default: a self-signed certificate made at start).
    #[arg(long, value_name = "FILE", requires = "tls_key")]
    tls_cert: Option<PathBuf>,
    /// PEM private key for --tls-cert.
    #[arg(long, value_name = "FILE", requires = "tls_cert")]
    tls_key: Option<PathBuf>,
    /// Serve plain HTTP (behind a TLS-terminating proxy; phones give motion sensors to HTTPS
    /// pages only).
    #[arg(long, conflicts_with_all = ["tls_cert", "tls_key"])]
    no_tls: bool,
    /// Commands pages may send: any of gravity, tilt, spawn, remove, reset, velocity, drag, or
    /// none.
    #[arg(long, default_value = "tilt,spawn,drag", value_parser = Allow::parse)]
    allow: Allow,
    /// Per-page limit on commands a second (a phone tilts at 30 Hz, a dragging finger moves at
    /// 30 Hz).
    #[arg(long, value_name = "N", default_value_t = 120)]
    rate: u32,
    /// Zenoh configuration file (JSON5) for the gateway's session, e.g. with the user and
    /// password of config/zenoh/acl-client.json5; --connect endpoints are added to it.
    #[arg(long, value_name = "FILE")]
    zenoh_config: Option<PathBuf>,
    /// Do not print the QR code.
    #[arg(long)]
    no_qr: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.connect.log.as_deref(), "info");
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e @ WebError::Usage(_)) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

fn usage(e: impl std::fmt::Display) -> WebError {
    WebError::Usage(e.to_string())
}

fn run(cli: Cli) -> Result<(), WebError> {
    let keys = cli.connect.keys().map_err(usage)?;
    let endpoints = cli.connect.endpoints().map_err(usage)?;
    let tls = match (&cli.tls_cert, &cli.tls_key, cli.no_tls) {
        (Some(cert), Some(key), _) => TlsMode::Files {
            cert: cert.clone(),
            key: key.clone(),
        },
        (_, _, true) => TlsMode::Off,
        _ => TlsMode::SelfSigned,
    };
    let opts = WebOptions {
        listen: cli.listen,
        tls,
        allow: cli.allow,
        rate: cli.rate,
        keys,
        fixed_prefix: cli.connect.prefix.is_some(),
    };
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    rt.block_on(async {
        let session = match &cli.zenoh_config {
            None => session::open(&endpoints).await.map_err(usage)?,
            Some(path) => {
                let mut c = zenoh::Config::from_file(path)
                    .map_err(|e| usage(format!("--zenoh-config {}: {e}", path.display())))?;
                let list: Vec<String> = endpoints.iter().map(|e| format!("\"{e}\"")).collect();
                c.insert_json5("connect/endpoints", &format!("[{}]", list.join(",")))
                    .map_err(|e| usage(format!("--connect: {e}")))?;
                zenoh::open(c)
                    .await
                    .map_err(|e| WebError::Zenoh(e.to_string()))?
            }
        };
        let gateway = Gateway::start(session.clone(), opts.clone()).await?;
        println!("tiltbox-web: open {}", gateway.url());
        if let Some(fp) = gateway.fingerprint() {
            println!("certificate SHA-256 {fp}");
            if matches!(opts.tls, TlsMode::SelfSigned) {
                println!(
                    "(self-signed: the browser warns once; check the fingerprint, then accept)"
                );
            }
        }
        println!(
            "world {} on {} · pages may send: {} · {} commands/s per page",
            opts.keys.prefix(),
            endpoints.join(", "),
            opts.allow,
            opts.rate
        );
        if opts.listen.ip().is_loopback() {
            println!(
                "listening on loopback only: --listen 0.0.0.0:8443 to reach a phone on the LAN"
            );
        }
        if !cli.no_qr {
            if let Some(q) = qr_text(gateway.url()) {
                println!("{q}");
            }
        }
        wait_for_signal().await;
        gateway.stop().await;
        let _ = tokio::time::timeout(std::time::Duration::from_secs(1), session.close()).await;
        Ok::<(), WebError>(())
    })?;
    rt.shutdown_timeout(std::time::Duration::from_millis(100));
    Ok(())
}
