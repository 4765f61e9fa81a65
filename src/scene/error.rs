//! Why a scene file was refused, and how a refusal names where: the body or table, and the
//! line it starts on.

use crate::physics::PhysicsError;
use std::path::PathBuf;
use thiserror::Error;

/// Why a scene could not be loaded, validated or built. Every message says where (file, line,
/// body or table), which field, and what value was wrong.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read; the OS error is the [`std::error::Error::source`].
    #[error("cannot read scene file {}", path.display())]
    Io {
        /// The path as given.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The text is not TOML, or a table does not fit the schema (unknown field, wrong type,
    /// missing field). `message` is toml's, with its line and column.
    #[error("{}{message}", entry_prefix(.entry))]
    Parse {
        /// The body or generator table the error is in, e.g. `body "brick 3" (#5) at line 40`,
        /// when it is known.
        entry: Option<String>,
        /// toml's message.
        message: String,
    },
    /// A value is out of range or inconsistent, e.g.
    /// `body "brick 3" (#5): friction = -1: must be >= 0`.
    #[error("{body}: {field}{}: {message}", value_suffix(.value))]
    Invalid {
        /// Where: `body "NAME" (#INDEX)` (INDEX is the body's position in [`super::Scene::bodies`]),
        /// `body #INDEX` when unnamed, `stack "NAME" ([[stack]] #K)`, `[settings]` or `scene`.
        body: String,
        /// The field, as written in the scene file, e.g. `friction` or `shape.width`.
        field: String,
        /// The offending value as written, when there is one.
        value: Option<String>,
        /// What is expected, e.g. `must be >= 0`.
        message: String,
    },
}

fn entry_prefix(entry: &Option<String>) -> String {
    entry.as_ref().map(|e| format!("{e}: ")).unwrap_or_default()
}

fn value_suffix(value: &Option<String>) -> String {
    value
        .as_ref()
        .map(|v| format!(" = {v}"))
        .unwrap_or_default()
}

impl SceneError {
    /// The same error about the body's part `index`: its field named `parts[index].field`.
    pub(crate) fn in_part(self, index: usize) -> SceneError {
        match self {
            SceneError::Invalid {
                body,
                field,
                value,
                message,
            } => SceneError::Invalid {
                body,
                field: format!("parts[{index}].{field}"),
                value,
                message,
            },
            other => other,
        }
    }

    /// An [`SceneError::Invalid`] for `body`.
    pub(crate) fn invalid(
        body: impl Into<String>,
        field: impl Into<String>,
        value: Option<String>,
        message: impl Into<String>,
    ) -> SceneError {
        SceneError::Invalid {
            body: body.into(),
            field: field.into(),
            value,
            message: message.into(),
        }
    }

    /// Wrap the engine's refusal (which names field and value) with where it happened.
    pub(crate) fn physics(body: impl Into<String>, error: PhysicsError) -> SceneError {
        let (field, value, message) = match error {
            PhysicsError::NotFinite { field, value } => {
                (field, Some(value.to_string()), "must be a finite number")
            }
            PhysicsError::OutOfRange {
                field,
                value,
                expected,
            } => (field, Some(value.to_string()), expected),
            PhysicsError::AboveLimit {
                field,
                value,
                setting,
                limit,
            } => {
                let message = format!("must not exceed {setting} = {limit}");
                return SceneError::invalid(body, field, Some(value.to_string()), message);
            }
            PhysicsError::InvalidShape { field, reason } => {
                let (value, message) = split_value(&reason);
                return SceneError::invalid(body, field, value, message);
            }
            PhysicsError::CannotStartAsleep { reason } => {
                return SceneError::invalid(body, "awake", Some("false".into()), reason);
            }
            PhysicsError::InPart { index, source } => {
                return SceneError::physics(body, *source).in_part(index);
            }
            other => {
                return SceneError::invalid(body, "body", None, other.to_string());
            }
        };
        SceneError::invalid(body, field, value, message)
    }
}

/// Split the engine's shape reason into the value it quotes and what is wrong with it:
/// `= [1, 0.5] turns clockwise there` gives (`[1, 0.5]`, `turns clockwise there`) and
/// `= 0.8 must be more than ...` gives (`0.8`, `must be more than ...`), so the scene's message
/// reads `shape.vertices[2] = [1, 0.5]: turns clockwise there`. A reason that quotes no value
/// first (`must hold 3 to 8 points, got 2`) is kept whole.
fn split_value(reason: &str) -> (Option<String>, String) {
    let split = reason.strip_prefix("= ").and_then(|rest| {
        let end = if rest.starts_with('[') {
            rest.find(']')? + 1
        } else {
            rest.find(' ')?
        };
        let (value, message) = rest.split_at(end);
        let message = message.trim_start();
        (!message.is_empty()).then(|| (value.to_owned(), message.to_owned()))
    });
    match split {
        Some((value, message)) => (Some(value), message),
        None => (None, reason.to_owned()),
    }
}

/// How an error names a body: `body "NAME" (#INDEX)`, or `body #INDEX` when unnamed.
pub(crate) fn body_label(name: Option<&str>, index: usize) -> String {
    match name {
        Some(name) => format!("body {name:?} (#{index})"),
        None => format!("body #{index}"),
    }
}

/// 1-based line numbers of byte offsets in one text, asked in increasing order: each call
/// counts only the newlines since the previous one, so numbering every table of a file costs
/// one pass over it, not one pass per table (which made a 5,051-body file take 1.7 s).
pub(crate) struct LineCounter<'a> {
    text: &'a str,
    at: usize,
    line: usize,
}

impl<'a> LineCounter<'a> {
    pub(crate) fn new(text: &'a str) -> LineCounter<'a> {
        LineCounter {
            text,
            at: 0,
            line: 1,
        }
    }

    /// The line of byte offset `at`; `at` must not be less than the previous call's.
    pub(crate) fn line_of(&mut self, at: usize) -> usize {
        debug_assert!(at >= self.at, "offsets asked out of order");
        let at = at.clamp(self.at, self.text.len());
        self.line += self.text.as_bytes()[self.at..at]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        self.at = at;
        self.line
    }
}

/// toml's message for a table read on its own, with the key path (when there is one) in
/// front: `density: invalid type: string "heavy", expected f32`.
pub(crate) fn describe(e: &toml::de::Error) -> String {
    let text = e.to_string();
    let text = text.trim_end();
    match text.rsplit_once("\nin `") {
        Some((message, keys)) => format!("{}: {message}", keys.trim_end_matches('`')),
        None => text.to_owned(),
    }
}
