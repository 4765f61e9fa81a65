//! docs/scenes.md's `[settings]` table is the code's: it lists every field of the engine's
//! `Settings` and no other, and each default it states is the one `Settings::default()` has
//! (read from the value a scene file would write, so the names are the file's names). A user
//! of the binary cannot read `src/physics/settings.rs`; this keeps the table from drifting.
#![cfg(feature = "scene")]

mod common;

use common::read_repo_file;
use std::collections::BTreeMap;
use tiltbox::physics::Settings;

/// The rows of the first table after "## `[settings]`": key -> default cell.
fn documented() -> BTreeMap<String, String> {
    let doc = read_repo_file("docs/scenes.md");
    let at = doc.find("## `[settings]`").expect("a [settings] section");
    let section = &doc[at..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |i| i + 3)];
    let mut rows = BTreeMap::new();
    for line in section.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let key = cells[1].trim_matches('`').to_owned();
        assert!(
            rows.insert(key.clone(), cells[2].to_owned()).is_none(),
            "{key} is listed twice"
        );
    }
    rows
}

/// A default as written in the table: `"name"` in backticks, true/false, `0.25 pi rad`, or a
/// number followed by its unit.
fn parse_cell(cell: &str) -> toml::Value {
    let cell = cell.trim_matches('`');
    if let Some(s) = cell.strip_prefix('"').and_then(|s| s.strip_suffix('"')) {
        return toml::Value::String(s.to_owned());
    }
    if let Ok(b) = cell.parse::<bool>() {
        return toml::Value::Boolean(b);
    }
    let mut words = cell.split_whitespace();
    let number: f64 = words
        .next()
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("default {cell:?} is not a number with a unit"));
    match words.next() {
        Some("pi") => toml::Value::Float(number * std::f64::consts::PI),
        _ => toml::Value::Float(number),
    }
}

#[test]
fn the_settings_table_lists_every_field_with_its_real_default() {
    let code = toml::Table::try_from(Settings::default()).expect("Settings serializes");
    let docs = documented();
    let missing: Vec<&String> = code.keys().filter(|k| !docs.contains_key(*k)).collect();
    let extra: Vec<&String> = docs.keys().filter(|k| !code.contains_key(*k)).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "fields not in docs/scenes.md: {missing:?}; rows that are not fields: {extra:?}"
    );
    for (key, cell) in &docs {
        let written = parse_cell(cell);
        let real = &code[key];
        let same = match (&written, real) {
            (toml::Value::Float(w), toml::Value::Float(r)) => (w - r).abs() <= 1e-6 * r.abs(),
            (toml::Value::Float(w), toml::Value::Integer(r)) => *w == *r as f64,
            (w, r) => w == r,
        };
        assert!(
            same,
            "docs/scenes.md says {key} defaults to {cell}, the code has {real}"
        );
    }
}

#[test]
fn a_wrong_default_in_the_table_would_be_caught() {
    // The parser reads what the table writes, so a wrong row cannot slip through as
    // unparsed: 30 Hz is read as 30, which is not the code's contact_hertz.
    assert_eq!(parse_cell("30 Hz"), toml::Value::Float(30.0));
    assert_eq!(
        parse_cell("`\"soft_step\"`"),
        toml::Value::String("soft_step".into())
    );
    let code = toml::Table::try_from(Settings::default()).unwrap();
    assert_ne!(
        code["contact_hertz"].as_float(),
        Some(30.0),
        "contact_hertz"
    );
}
