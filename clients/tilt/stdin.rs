//! The stdin source: accelerometer readings as JSON text, one object per line or as
//! `termux-sensor -s accelerometer` prints them; a bad line is reported by its number and
//! skipped.

use crate::protocol::Tilt;
use std::io::BufRead;
use tokio::sync::mpsc::Sender;

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

/// Parse stdin line by line; bad lines are reported with their number and skipped.
pub fn read_stdin(tx: Sender<Tilt>) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::tilt::test_support::accel;

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
}
