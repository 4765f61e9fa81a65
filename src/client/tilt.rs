//! The sources of `tiltbox-tilt` and its publisher loop.
//!
//! Every source yields [`Tilt`] messages (the protocol's own type: this module only makes
//! them). Readings are in Android's `TYPE_ACCELEROMETER` convention (m/s^2, device frame, a
//! device at rest reads the reaction to gravity, pointing up): see `docs/protocol.md`.
//!
//! - [`sweep_reading`]: a device upright in portrait, turned about the screen's normal;
//! - [`StdinParser`]: JSON readings, one per line or as `termux-sensor` prints them;
//! - [`IioAccel`]: a Linux IIO accelerometer under `/sys/bus/iio/devices`;
//! - [`KeyboardTilt`]: a virtual device turned by arrow keys, or put in a discrete orientation;
//! - [`TiltPublisher`] and [`publish_loop`]: put each new reading on `…/tilt` at once, and
//!   the latest one again at a steady rate.

use super::ClientError;
use crate::protocol::{encode, Keys, Orientation, Tilt};
use std::path::{Path, PathBuf};
use std::time::Duration;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;
use zenoh::Session;

/// Standard gravity (m/s^2): the magnitude of the readings the sweep and keyboard make.
pub const STANDARD_GRAVITY: f32 = 9.81;

/// The reading of a device held upright (not tilted towards or away from the viewer) and
/// turned `degrees` counter-clockwise from portrait: `g (sin a, cos a, 0)`. 0 is portrait
/// (gravity down the screen), 90 landscape left (gravity to the left), 180 upside down.
pub fn sweep_reading(degrees: f64) -> Tilt {
    let (s, c) = degrees.to_radians().sin_cos();
    Tilt::Accelerometer {
        x: STANDARD_GRAVITY * s as f32,
        y: STANDARD_GRAVITY * c as f32,
        z: 0.0,
    }
}

/// A bad line of `--stdin` input.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct LineError {
    /// 1-based line number (the first line of a multi-line object).
    pub line: usize,
    /// What was wrong.
    pub message: String,
}

/// Reads accelerometer readings from text, line by line. Accepted:
///
/// - one JSON object per line with numeric `x`, `y`, `z` (m/s^2; other keys are ignored):
///   `{"x": 0.1, "y": 9.7, "z": 0.4}`;
/// - what `termux-sensor -s accelerometer` prints: an object per reading, pretty-printed over
///   several lines, keyed by the sensor's name, `{"<name>": {"values": [x, y, z]}}` (the
///   sensor whose name contains "accel" when there are several; `{}`, printed before the
///   first reading, is skipped);
/// - blank lines and lines starting with `#` are skipped.
///
/// Anything else is an error naming its line; parsing goes on with the next line.
#[derive(Debug, Default)]
pub struct StdinParser {
    line: usize,
    /// A multi-line object being collected, with its first line number.
    pending: Option<(usize, String)>,
}

/// Largest multi-line object collected before it is given up as garbage.
const MAX_OBJECT_LINES: usize = 256;

impl StdinParser {
    /// A parser at line 0.
    pub fn new() -> StdinParser {
        StdinParser::default()
    }

    /// Feed the next line (without its newline). `Ok(None)`: nothing to publish yet.
    pub fn line(&mut self, text: &str) -> Result<Option<Tilt>, LineError> {
        self.line += 1;
        let t = text.trim();
        if let Some((first, buf)) = &mut self.pending {
            let first = *first;
            buf.push_str(t);
            buf.push('\n');
            // termux-sensor closes each reading with a `}` alone at the start of a line
            if text.starts_with('}') {
                let Some((_, buf)) = self.pending.take() else {
                    return Ok(None);
                };
                return parse_reading(&buf).map_err(|message| LineError {
                    line: first,
                    message,
                });
            }
            if self.line - first >= MAX_OBJECT_LINES {
                self.pending = None;
                return Err(LineError {
                    line: first,
                    message: format!("no closing '}}' within {MAX_OBJECT_LINES} lines"),
                });
            }
            return Ok(None);
        }
        if t.is_empty() || t.starts_with('#') {
            return Ok(None);
        }
        if t == "{" {
            self.pending = Some((self.line, "{\n".to_owned()));
            return Ok(None);
        }
        parse_reading(t).map_err(|message| LineError {
            line: self.line,
            message,
        })
    }

    /// At the end of input: an object left open is an error.
    pub fn finish(&mut self) -> Result<(), LineError> {
        match self.pending.take() {
            Some((line, _)) => Err(LineError {
                line,
                message: "input ended inside an object".into(),
            }),
            None => Ok(()),
        }
    }
}

/// One reading as JSON text: a plain `{"x","y","z"}` object or a termux-sensor object.
/// `Ok(None)` for termux's empty `{}`.
pub fn parse_reading(text: &str) -> Result<Option<Tilt>, String> {
    use serde_json::Value;
    let value: Value = serde_json::from_str(text).map_err(|e| {
        let short: String = text.chars().take(40).collect();
        format!("not JSON ({e}): {short:?}")
    })?;
    let Value::Object(map) = value else {
        return Err(format!(
            "expected an object {{\"x\":..,\"y\":..,\"z\":..}}, got {value}"
        ));
    };
    if map.is_empty() {
        return Ok(None);
    }
    let num = |v: Option<&Value>, what: &str| -> Result<f32, String> {
        let v = v.ok_or_else(|| format!("no {what}"))?;
        let n = v
            .as_f64()
            .ok_or_else(|| format!("{what} is not a number: {v}"))?;
        let f = n as f32;
        if f.is_finite() {
            Ok(f)
        } else {
            Err(format!("{what} = {n} is out of range"))
        }
    };
    if map.contains_key("x") || map.contains_key("y") || map.contains_key("z") {
        let (x, y, z) = (
            num(map.get("x"), "\"x\"")?,
            num(map.get("y"), "\"y\"")?,
            num(map.get("z"), "\"z\"")?,
        );
        return Ok(Some(Tilt::Accelerometer { x, y, z }));
    }
    // termux-sensor: {"<sensor name>": {"values": [x, y, z]}}
    let (name, sensor) = map
        .iter()
        .find(|(k, _)| k.to_ascii_lowercase().contains("accel"))
        .or_else(|| (map.len() == 1).then(|| map.iter().next()).flatten())
        .ok_or_else(|| {
            let keys: Vec<&String> = map.keys().collect();
            format!("no \"x\"/\"y\"/\"z\" and no accelerometer among {keys:?}")
        })?;
    let values = sensor
        .get("values")
        .and_then(Value::as_array)
        .ok_or_else(|| format!("sensor {name:?} has no \"values\" array"))?;
    if values.len() < 3 {
        return Err(format!(
            "sensor {name:?} has {} values, expected 3",
            values.len()
        ));
    }
    Ok(Some(Tilt::Accelerometer {
        x: num(values.first(), "values[0]")?,
        y: num(values.get(1), "values[1]")?,
        z: num(values.get(2), "values[2]")?,
    }))
}

/// Where Linux lists its IIO devices.
pub const IIO_ROOT: &str = "/sys/bus/iio/devices";

/// A Linux IIO accelerometer: `in_accel_{x,y,z}_raw`, plus `in_accel_offset` (if any), times
/// `in_accel_scale` (or per-axis `in_accel_{x,y,z}_scale`) gives m/s^2. The device's mount
/// matrix is not applied: readings are taken in the device's own frame.
#[derive(Clone, Debug)]
pub struct IioAccel {
    dir: PathBuf,
    scale: [f64; 3],
    offset: [f64; 3],
}

const AXES: [char; 3] = ['x', 'y', 'z'];

impl IioAccel {
    /// Open `device` (a directory, or a name like `iio:device0` under [`IIO_ROOT`]), or the
    /// first accelerometer under `root` when `device` is `None`.
    pub fn open(device: Option<&str>, root: &Path) -> Result<IioAccel, String> {
        let dir = match device {
            Some(d) if d.contains('/') => PathBuf::from(d),
            Some(d) => root.join(d),
            None => {
                let entries = std::fs::read_dir(root)
                    .map_err(|e| format!("no IIO devices: cannot list {}: {e}", root.display()))?;
                let mut dirs: Vec<PathBuf> = entries
                    .filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.join("in_accel_x_raw").exists())
                    .collect();
                dirs.sort();
                dirs.into_iter().next().ok_or_else(|| {
                    format!(
                        "no IIO accelerometer: no device under {} has in_accel_x_raw",
                        root.display()
                    )
                })?
            }
        };
        if !dir.join("in_accel_x_raw").exists() {
            return Err(format!(
                "{} is not an IIO accelerometer (no in_accel_x_raw there)",
                dir.display()
            ));
        }
        let read_opt = |name: &str| -> Result<Option<f64>, String> {
            let p = dir.join(name);
            if !p.exists() {
                return Ok(None);
            }
            read_number(&p).map(Some)
        };
        let common_scale = read_opt("in_accel_scale")?;
        let common_offset = read_opt("in_accel_offset")?.unwrap_or(0.0);
        let mut scale = [0.0; 3];
        let mut offset = [0.0; 3];
        for (i, a) in AXES.iter().enumerate() {
            scale[i] = match read_opt(&format!("in_accel_{a}_scale"))?.or(common_scale) {
                Some(s) => s,
                None => {
                    return Err(format!(
                        "{}: no in_accel_scale nor in_accel_{a}_scale",
                        dir.display()
                    ))
                }
            };
            offset[i] = read_opt(&format!("in_accel_{a}_offset"))?.unwrap_or(common_offset);
        }
        Ok(IioAccel { dir, scale, offset })
    }

    /// The device's directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Read the three axes now.
    pub fn read(&self) -> Result<Tilt, String> {
        let mut v = [0f32; 3];
        for (i, a) in AXES.iter().enumerate() {
            let raw = read_number(&self.dir.join(format!("in_accel_{a}_raw")))?;
            v[i] = ((raw + self.offset[i]) * self.scale[i]) as f32;
        }
        Ok(Tilt::Accelerometer {
            x: v[0],
            y: v[1],
            z: v[2],
        })
    }
}

fn read_number(path: &Path) -> Result<f64, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{}: {:?} is not a number", path.display(), text.trim()))
}

/// A key of the keyboard source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TiltKey {
    /// Turn the device counter-clockwise (from portrait, gravity swings to the left).
    Left,
    /// Turn the device clockwise (from portrait, gravity swings to the right).
    Right,
    /// Lay the device back towards face up: less gravity in the screen's plane.
    Up,
    /// Raise the device back towards upright: more gravity in the screen's plane.
    Down,
    /// Put the device in a discrete orientation.
    Orientation(Orientation),
}

impl TiltKey {
    /// The orientation keys: `p` portrait, `u` upside down, `l` landscape left, `r`
    /// landscape right, `f` face up (flat), `d` face down; also `1`..`6` in that order.
    pub fn from_char(c: char) -> Option<TiltKey> {
        use Orientation::*;
        let o = match c.to_ascii_lowercase() {
            'p' | '1' => Portrait,
            'u' | '2' => PortraitUpsideDown,
            'l' | '3' => LandscapeLeft,
            'r' | '4' => LandscapeRight,
            'f' | '5' => FaceUp,
            'd' | '6' => FaceDown,
            _ => return None,
        };
        Some(TiltKey::Orientation(o))
    }
}

/// A virtual device: `roll` degrees counter-clockwise from portrait about the screen's
/// normal, and `lean` degrees laid back from upright (90 = flat face up, -90 = face down).
/// Its reading is `g (sin roll cos lean, cos roll cos lean, sin lean)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyboardTilt {
    /// Degrees counter-clockwise from portrait, in [0, 360).
    pub roll: f32,
    /// Degrees laid back from upright, within [-90, 90].
    pub lean: f32,
    /// Degrees per arrow key press.
    pub step: f32,
    /// The last discrete orientation chosen, until an arrow key moves away from it.
    pub orientation: Option<Orientation>,
}

impl Default for KeyboardTilt {
    fn default() -> Self {
        KeyboardTilt {
            roll: 0.0,
            lean: 0.0,
            step: 15.0,
            orientation: Some(Orientation::Portrait),
        }
    }
}

impl KeyboardTilt {
    /// Apply a key; returns the message to publish.
    pub fn key(&mut self, key: TiltKey) -> Tilt {
        match key {
            TiltKey::Left => self.roll += self.step,
            TiltKey::Right => self.roll -= self.step,
            TiltKey::Up => self.lean = (self.lean + self.step).min(90.0),
            TiltKey::Down => self.lean = (self.lean - self.step).max(-90.0),
            TiltKey::Orientation(o) => {
                use Orientation::*;
                (self.roll, self.lean) = match o {
                    Portrait => (0.0, 0.0),
                    PortraitUpsideDown => (180.0, 0.0),
                    LandscapeLeft => (90.0, 0.0),
                    LandscapeRight => (270.0, 0.0),
                    FaceUp => (self.roll, 90.0),
                    FaceDown => (self.roll, -90.0),
                };
                self.orientation = Some(o);
                return Tilt::Orientation(o);
            }
        }
        self.roll = self.roll.rem_euclid(360.0);
        self.orientation = None;
        self.tilt()
    }

    /// The current message: the discrete orientation if one was chosen last, else the reading.
    pub fn tilt(&self) -> Tilt {
        match self.orientation {
            Some(o) => Tilt::Orientation(o),
            None => self.reading(),
        }
    }

    /// The accelerometer reading of the virtual device.
    pub fn reading(&self) -> Tilt {
        let (sr, cr) = self.roll.to_radians().sin_cos();
        let (sl, cl) = self.lean.to_radians().sin_cos();
        let g = STANDARD_GRAVITY;
        let clean = |v: f32| if v.abs() < 1e-5 { 0.0 } else { v };
        Tilt::Accelerometer {
            x: clean(g * sr * cl),
            y: clean(g * cr * cl),
            z: clean(g * sl),
        }
    }
}

/// A short text for a tilt message, e.g. `accel (0.00, 9.81, 0.00) -> gravity (-0.00, -9.81)`.
pub fn describe(t: &Tilt) -> String {
    let g = t.gravity(STANDARD_GRAVITY);
    match t {
        Tilt::Orientation(o) => format!("{o:?} -> gravity ({:.2}, {:.2})", g.x, g.y),
        Tilt::Accelerometer { x, y, z } => format!(
            "accel ({x:.2}, {y:.2}, {z:.2}) -> gravity ({:.2}, {:.2})",
            g.x, g.y
        ),
    }
}

/// Puts [`Tilt`] messages on `…/tilt` (congestion Drop, express: a newer reading supersedes).
pub struct TiltPublisher {
    publisher: Publisher<'static>,
    last: Option<Tilt>,
    sent: u64,
}

impl TiltPublisher {
    /// Declare the publisher on `keys.tilt()`.
    pub async fn new(session: &Session, keys: &Keys) -> Result<TiltPublisher, ClientError> {
        let publisher = session
            .declare_publisher(keys.tilt())
            .congestion_control(CongestionControl::Drop)
            .express(true)
            .await
            .map_err(ClientError::zenoh("tilt publisher"))?;
        Ok(TiltPublisher {
            publisher,
            last: None,
            sent: 0,
        })
    }

    /// Publish `tilt` now and remember it as the latest.
    pub async fn send(&mut self, tilt: Tilt) -> Result<(), ClientError> {
        let payload = encode(&tilt).map_err(|e| ClientError::Zenoh(e.to_string()))?;
        self.publisher
            .put(payload)
            .await
            .map_err(ClientError::zenoh("cannot publish a tilt"))?;
        self.last = Some(tilt);
        self.sent += 1;
        Ok(())
    }

    /// The latest message published.
    pub fn last(&self) -> Option<Tilt> {
        self.last
    }

    /// How many messages were published.
    pub fn sent(&self) -> u64 {
        self.sent
    }
}

/// Publish every message from `readings` as it comes, and the latest one again whenever
/// `1 / rate_hz` seconds pass without a new one. Returns when `readings` closes.
pub async fn publish_loop(
    publisher: &mut TiltPublisher,
    rate_hz: f64,
    mut readings: tokio::sync::mpsc::Receiver<Tilt>,
) -> Result<(), ClientError> {
    let period = Duration::from_secs_f64(1.0 / rate_hz);
    let mut tick = tokio::time::interval(period);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tokio::select! {
            r = readings.recv() => match r {
                Some(t) => {
                    publisher.send(t).await?;
                    tick.reset();
                }
                None => return Ok(()),
            },
            _ = tick.tick() => {
                if let Some(t) = publisher.last() {
                    publisher.send(t).await?;
                }
            }
        }
    }
}

/// The sweep source: every `1 / rate_hz` s, the reading of a device turned `deg_per_s * t`
/// degrees from portrait. Ends when the receiver is dropped.
pub async fn sweep(deg_per_s: f64, rate_hz: f64, tx: tokio::sync::mpsc::Sender<Tilt>) {
    let start = tokio::time::Instant::now();
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate_hz));
    loop {
        tick.tick().await;
        let deg = (deg_per_s * start.elapsed().as_secs_f64()).rem_euclid(360.0);
        if tx.send(sweep_reading(deg)).await.is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn accel(t: Option<Tilt>) -> (f32, f32, f32) {
        match t {
            Some(Tilt::Accelerometer { x, y, z }) => (x, y, z),
            other => panic!("not a reading: {other:?}"),
        }
    }

    #[test]
    fn plain_lines_parse() {
        let mut p = StdinParser::new();
        assert_eq!(
            accel(p.line(r#"{"x": 0.5, "y": 9.7, "z": -1e-1}"#).unwrap()),
            (0.5, 9.7, -0.1)
        );
        // extra keys (a timestamp) are fine, integers are numbers
        assert_eq!(
            accel(p.line(r#"{"t": 123, "x": 0, "y": -9, "z": 1}"#).unwrap()),
            (0.0, -9.0, 1.0)
        );
        assert_eq!(p.line("").unwrap(), None);
        assert_eq!(p.line("# a comment").unwrap(), None);
    }

    #[test]
    fn termux_sensor_output_parses() {
        // as `termux-sensor -s accelerometer -d 100` prints it: `{}` first, then objects
        // pretty-printed with an indentation of 2.
        let text = r#"{}
{
  "lsm6dso LSM6DSO Accelerometer Non-wakeup": {
    "values": [
      -0.0597,
      9.7766,
      0.3807
    ]
  }
}
{
  "BMI160 Accelerometer": {
    "values": [
      9.81,
      0,
      0
    ]
  }
}
"#;
        let mut p = StdinParser::new();
        let got: Vec<_> = text
            .lines()
            .filter_map(|l| p.line(l).unwrap())
            .map(|t| accel(Some(t)))
            .collect();
        assert_eq!(got, vec![(-0.0597, 9.7766, 0.3807), (9.81, 0.0, 0.0)]);
        p.finish().unwrap();
        // single-line termux objects, several sensors: the accelerometer is picked
        let one =
            r#"{"gyro": {"values": [1, 2, 3]}, "K6DS3TR Acceleration": {"values": [1, 2, 3.5]}}"#;
        assert_eq!(accel(p.line(one).unwrap()), (1.0, 2.0, 3.5));
    }

    #[test]
    fn garbage_is_rejected_with_its_line_number_and_skipped() {
        let text = "{\"x\":1,\"y\":2,\"z\":3}\nhello\n{\"x\":1,\"y\":2}\n[1,2,3]\n{\"x\":\"a\",\"y\":2,\"z\":3}\n{\"x\":1e99,\"y\":0,\"z\":0}\n{\n  \"a\": {\"values\": [1]}\n}\n{\"x\":4,\"y\":5,\"z\":6}\n{\n  \"s\": {\n";
        let mut p = StdinParser::new();
        let mut ok = Vec::new();
        let mut errors = Vec::new();
        for l in text.lines() {
            match p.line(l) {
                Ok(Some(t)) => ok.push(accel(Some(t))),
                Ok(None) => {}
                Err(e) => errors.push(e),
            }
        }
        errors.extend(p.finish().err());
        assert_eq!(ok, vec![(1.0, 2.0, 3.0), (4.0, 5.0, 6.0)]);
        let lines: Vec<usize> = errors.iter().map(|e| e.line).collect();
        assert_eq!(lines, vec![2, 3, 4, 5, 6, 7, 11], "{errors:?}");
        let text: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
        assert!(text[0].starts_with("line 2: not JSON"), "{}", text[0]);
        assert!(text[1].contains("no \"z\""), "{}", text[1]);
        assert!(text[2].contains("expected an object"), "{}", text[2]);
        assert!(text[3].contains("not a number"), "{}", text[3]);
        assert!(text[4].contains("out of range"), "{}", text[4]);
        assert!(text[5].contains("1 values, expected 3"), "{}", text[5]);
        assert!(text[6].contains("ended inside an object"), "{}", text[6]);
    }

    #[test]
    fn sweep_and_keyboard_readings_point_gravity_where_expected() {
        let g = |t: Tilt| t.gravity(STANDARD_GRAVITY);
        let close = |a: crate::protocol::Vector, x: f32, y: f32| {
            (a.x - x).abs() < 1e-4 && (a.y - y).abs() < 1e-4
        };
        assert!(close(g(sweep_reading(0.0)), 0.0, -9.81));
        assert!(close(g(sweep_reading(90.0)), -9.81, 0.0));
        assert!(close(g(sweep_reading(180.0)), 0.0, 9.81));
        let mut k = KeyboardTilt::default();
        assert_eq!(k.tilt(), Tilt::Orientation(Orientation::Portrait));
        for _ in 0..6 {
            k.key(TiltKey::Left);
        }
        assert!(close(g(k.tilt()), -9.81, 0.0), "{:?}", k.tilt());
        k.key(TiltKey::Orientation(Orientation::FaceUp));
        assert_eq!(k.tilt(), Tilt::Orientation(Orientation::FaceUp));
        k.key(TiltKey::Down); // from flat, raise by one step: a little gravity to the left
        let v = g(k.tilt());
        assert!(v.x < -2.0 && v.x > -3.0 && v.y.abs() < 1e-4, "{v:?}");
        assert_eq!(
            TiltKey::from_char('u'),
            Some(TiltKey::Orientation(Orientation::PortraitUpsideDown))
        );
    }

    #[test]
    fn iio_devices_are_read_and_absence_is_explained() {
        let root = std::env::temp_dir().join(format!("tiltbox-iio-{}", std::process::id()));
        let dev = root.join("iio:device3");
        std::fs::create_dir_all(&dev).unwrap();
        let e = IioAccel::open(None, &root).unwrap_err();
        assert!(e.contains("no IIO accelerometer"), "{e}");
        let e = IioAccel::open(None, &root.join("nothing")).unwrap_err();
        assert!(e.contains("no IIO devices"), "{e}");
        for (f, v) in [
            ("in_accel_x_raw", "0\n"),
            ("in_accel_y_raw", "-1000\n"),
            ("in_accel_z_raw", "20"),
            ("in_accel_scale", "0.00981\n"),
        ] {
            std::fs::write(dev.join(f), v).unwrap();
        }
        let a = IioAccel::open(None, &root).unwrap();
        let (x, y, z) = accel(Some(a.read().unwrap()));
        assert!(x == 0.0 && (y + 9.81).abs() < 1e-5 && (z - 0.1962).abs() < 1e-5);
        std::fs::write(dev.join("in_accel_y_raw"), "oops").unwrap();
        assert!(a.read().unwrap_err().contains("\"oops\" is not a number"));
        let _ = std::fs::remove_dir_all(root);
    }
}
