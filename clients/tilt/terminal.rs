//! The keyboard source's terminal: raw mode, the arrow and orientation keys read from it, and
//! a status line with the device's angles, the reading, the gravity it gives and whether a
//! daemon is up.

use super::keyboard::{key_command, Key, KeyCommand, KeyboardTilt, TiltKey};
use super::publish::{describe, TiltPublisher};
use crate::client::session::ServerWatch;
use crate::client::ClientError;
use crossterm::event::{self, Event};
use crossterm::{cursor, terminal, QueueableCommand};
use std::io::Write;
use std::process::ExitCode;
use std::time::Duration;
use tokio::sync::mpsc;

enum Input {
    Key(TiltKey),
    Quit,
}

/// Leaves raw mode when dropped; a panic hook does the same before the message.
struct RawMode;

impl RawMode {
    fn enable() -> std::io::Result<RawMode> {
        terminal::enable_raw_mode()?;
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let _ = terminal::disable_raw_mode();
            previous(info);
        }));
        Ok(RawMode)
    }
}

impl Drop for RawMode {
    fn drop(&mut self) {
        let _ = terminal::disable_raw_mode();
        println!();
    }
}

/// Read keys until q, Esc or Ctrl-C, publishing what each gives and the latest again at `rate`.
pub(super) async fn run(
    publisher: &mut TiltPublisher,
    rate: f64,
    step: f32,
    watch: &ServerWatch,
    prefix: &str,
) -> Result<ExitCode, ClientError> {
    println!(
        "tiltbox-tilt on {prefix}: arrows tilt by {step} deg; p portrait, u upside down, \
         l/r landscape left/right, f face up, d face down; q quits"
    );
    let _raw = RawMode::enable()?;
    let (tx, mut rx) = mpsc::channel::<Input>(16);
    std::thread::Builder::new()
        .name("tiltbox-tilt-keys".into())
        .spawn(move || read_keys(tx))?;
    let mut device = KeyboardTilt {
        step,
        ..KeyboardTilt::default()
    };
    publisher.send(device.tilt()).await?;
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate));
    loop {
        tokio::select! {
            input = rx.recv() => match input {
                Some(Input::Key(k)) => {
                    publisher.send(device.key(k)).await?;
                    tick.reset();
                }
                Some(Input::Quit) | None => break,
            },
            _ = tick.tick() => publisher.send(device.tilt()).await?,
        }
        status(&device, watch.is_alive(), publisher.sent());
    }
    Ok(ExitCode::SUCCESS)
}

fn status(device: &KeyboardTilt, alive: bool, sent: u64) {
    let server = if alive { "daemon up" } else { "NO DAEMON" };
    let line = format!(
        "roll {:>5.1} lean {:>5.1} | {} | {server} | sent {sent}",
        device.roll,
        device.lean,
        describe(&device.tilt())
    );
    let mut out = std::io::stdout();
    let _ = out.queue(cursor::MoveToColumn(0));
    let _ = out.queue(terminal::Clear(terminal::ClearType::CurrentLine));
    let _ = write!(out, "{line}");
    let _ = out.flush();
}

fn read_keys(tx: mpsc::Sender<Input>) {
    loop {
        let ev = match event::read() {
            Ok(e) => e,
            Err(_) => {
                let _ = tx.blocking_send(Input::Quit);
                return;
            }
        };
        let Event::Key(k) = ev else { continue };
        // tiltbox-tilt publishes tilts only: spawn and reset keys do nothing here
        let input = match Key::from_crossterm(k).and_then(key_command) {
            Some(KeyCommand::Quit) => Input::Quit,
            Some(KeyCommand::Tilt(k)) => Input::Key(k),
            _ => continue,
        };
        let quit = matches!(input, Input::Quit);
        if tx.blocking_send(input).is_err() || quit {
            return;
        }
    }
}
