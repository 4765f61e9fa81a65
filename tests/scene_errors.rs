//! Bad scene files are refused with messages that name the body (or table), the field and
//! the value, and where they can, the line.

#![cfg(feature = "scene")]

mod common;

use common::scene::*;

/// The refusal of "brick 3" (#1) with `fields` added, checked to start with `start`.
fn brick_refusal(fields: &str, start: &str) -> String {
    let (_, s) = error_for(&brick(fields));
    assert!(s.starts_with(start), "{s}");
    s
}
use std::path::Path;
use tiltbox::scene::{Scene, SceneError};

#[test]
fn negative_friction_names_body_field_and_value() {
    let (e, s) = error_for(&brick("density = 1\nfriction = -1"));
    assert_eq!(s, r#"body "brick 3" (#1): friction = -1: must be >= 0"#);
    match e {
        SceneError::Invalid {
            body, field, value, ..
        } => {
            assert_eq!(body, r#"body "brick 3" (#1)"#);
            assert_eq!(field, "friction");
            assert_eq!(value.as_deref(), Some("-1"));
        }
        other => panic!("expected Invalid, got {other:?}"),
    }
}

#[test]
fn restitution_above_one_is_refused() {
    let (_, s) = error_for(&brick("density = 1\nrestitution = 2"));
    assert_eq!(
        s,
        r#"body "brick 3" (#1): restitution = 2: must be within [0, 1]"#
    );
}

#[test]
fn nan_is_refused_wherever_it_appears() {
    brick_refusal("density = nan", r#"body "brick 3" (#1): density = NaN"#);
    let (_, s) = error_for(&brick("density = 1\nangle = nan"));
    assert_eq!(
        s,
        r#"body "brick 3" (#1): angle = NaN: must be a finite number"#
    );
    let (_, s) = error_for(
        "[[body]]\nshape = { type = \"rect\", width = 1, height = 1 }\nposition = [nan, 0]\nmass = 1",
    );
    // unnamed: the index names it
    assert_eq!(s, "body #1: position.x = NaN: must be a finite number");
    let e = Scene::from_toml_str("gravity = [0, nan]").unwrap_err();
    assert_eq!(
        e.to_string(),
        "scene: gravity.y = NaN: must be a finite number"
    );
}

#[test]
fn zero_width_is_refused() {
    let (_, s) = error_for(
        "[[body]]\nname = \"flat\"\nshape = { type = \"rect\", width = 0, height = 1 }\nposition = [0, 1]\ndensity = 1",
    );
    assert_eq!(s, r#"body "flat" (#1): shape.width = 0: must be > 0"#);
}

#[test]
fn density_and_mass_together_are_refused() {
    let s = brick_refusal(
        "density = 1\nmass = 2",
        r#"body "brick 3" (#1): density = 1: give exactly one of density"#,
    );
    assert!(s.contains("mass = 2"), "{s}");
    brick_refusal("", r#"body "brick 3" (#1): density: missing"#);
}

#[test]
fn static_bodies_take_no_density_mass_or_velocity() {
    brick_refusal(
        "static = true\ndensity = 1",
        r#"body "brick 3" (#1): density = 1: a static body has neither"#,
    );
    brick_refusal(
        "static = true\nmass = 5",
        r#"body "brick 3" (#1): mass = 5"#,
    );
    brick_refusal(
        "static = true\nvelocity = [1, 0]",
        r#"body "brick 3" (#1): velocity = [1, 0]: a static body does not move"#,
    );
}

#[test]
fn only_a_dynamic_body_at_rest_starts_asleep() {
    brick_refusal(
        "static = true\nawake = false",
        r#"body "brick 3" (#1): awake = false: only a dynamic body sleeps"#,
    );
    brick_refusal(
        "density = 1\nvelocity = [2, 0]\nawake = false",
        r#"body "brick 3" (#1): awake = false: a body created asleep must be at rest, and this one moves: velocity (2, 0) m/s"#,
    );
    let (_, s) = error_for(
        "[[body]]\nname = \"hill\"\nshape = { type = \"chain\", points = [[0, 0], [1, 0]] }\n\
         position = [0, 0]\nawake = false\n",
    );
    assert!(
        s.contains("awake = false: a chain is static terrain"),
        "{s}"
    );
}

#[test]
fn malformed_colour_names_the_value() {
    brick_refusal(
        "density = 1\ncolour = \"#12345\"",
        r##"body "brick 3" (#1): colour = "#12345": expected "#rrggbb""##,
    );
    let (_, s) = error_for(&brick("density = 1\ncolour = \"red\""));
    assert!(s.contains(r#"colour = "red""#), "{s}");
}

#[test]
fn unknown_field_names_the_body_its_line_and_the_field() {
    let (e, s) = error_for(&brick("density = 1\nfrction = 0.5"));
    assert!(
        matches!(e, SceneError::Parse { entry: Some(_), .. }),
        "{e:?}"
    );
    // The [[body]] header of "brick 3" is on line 10 of the document (GROUND takes 9).
    assert!(
        s.starts_with(r#"body "brick 3" (#1) at line 10: unknown field `frction`"#),
        "{s}"
    );
    // A wrong type is reported the same way.
    brick_refusal(
        "density = \"heavy\"",
        r#"body "brick 3" (#1) at line 10: density: invalid type"#,
    );
    // ... and a field inside the shape.
    let (_, s) = error_for(
        "[[body]]\nname = \"cube\"\nshape = { type = \"rect\", width = 1, height = 1, depth = 1 }\nposition = [0, 1]\ndensity = 1",
    );
    assert!(s.starts_with(r#"body "cube" (#1) at line 10: "#), "{s}");
    assert!(s.contains("depth"), "{s}");
}

#[test]
fn unknown_top_level_keys_and_bad_toml_report_line_and_column() {
    let e = Scene::from_toml_str("name = \"x\"\ngravty = [0, -1]\n").unwrap_err();
    let s = e.to_string();
    assert!(matches!(e, SceneError::Parse { entry: None, .. }));
    assert!(
        s.contains("line 2, column 1") && s.contains("gravty"),
        "{s}"
    );
    let e = Scene::from_toml_str("name = \"x\"\n[[body]\n").unwrap_err();
    let s = e.to_string();
    assert!(s.contains("line 2"), "{s}");
}

#[test]
fn settings_are_validated_by_the_engine() {
    let e = Scene::from_toml_str("[settings]\nsubsteps = 0\n").unwrap_err();
    assert_eq!(
        e.to_string(),
        "[settings]: substeps = 0: must be within 1..=64"
    );
    let e = Scene::from_toml_str("[settings]\nsubstep = 4\n").unwrap_err();
    let s = e.to_string();
    assert!(s.contains("substep") && s.contains("line 2"), "{s}");
    for workers in [0, 65] {
        let e = Scene::from_toml_str(&format!("[settings]\nworkers = {workers}\n")).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!("[settings]: workers = {workers}: must be within 1..=64")
        );
    }
    let e = Scene::from_toml_str("[settings]\nworkers = -1\n").unwrap_err();
    assert!(e.to_string().contains("workers"), "{e}");
}

#[test]
fn generator_errors_name_the_generator_and_field() {
    let e = Scene::from_toml_str("[[stack]]\ncount = 0\nsize = 1\n").unwrap_err();
    assert_eq!(e.to_string(), "[[stack]] #0: count = 0: must be >= 1");
    let e = Scene::from_toml_str(
        "[[stack]]\ncount = 1\nsize = 1\n[[pyramid]]\nname = \"p\"\nbase = 2\nsize = -1\n",
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        r#"pyramid "p" ([[pyramid]] #0): size = -1: must be > 0"#
    );
    let e = Scene::from_toml_str("[[stack]]\ncount = 2\nsize = 1\ngap = -0.5\n").unwrap_err();
    assert_eq!(e.to_string(), "[[stack]] #0: gap = -0.5: must be >= 0");
    let e = Scene::from_toml_str("[[pyramid]]\nbase = 2\nsize = 1\nheight = 3\n").unwrap_err();
    let s = e.to_string();
    assert!(
        s.starts_with("[[pyramid]] #0 at line 1: unknown field `height`"),
        "{s}"
    );
    // A typo that would need millions of boxes is refused before any is made.
    let e = Scene::from_toml_str("[[pyramid]]\nbase = 10000\nsize = 1\n").unwrap_err();
    assert!(
        e.to_string().starts_with("scene: bodies = 50005000:"),
        "{e}"
    );
}

#[test]
fn missing_file_names_the_path_and_the_os_error() {
    let path = Path::new("/nonexistent/scene.toml");
    let e = Scene::load(path).unwrap_err();
    match &e {
        SceneError::Io { path: p, source } => {
            assert_eq!(p, path);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected Io, got {other:?}"),
    }
    assert!(e.to_string().contains("/nonexistent/scene.toml"));
}

#[test]
fn the_line_of_a_late_table_is_counted_across_every_table_before_it() {
    // 300 bodies of 6 lines each (header, name, shape, position, density, blank), a [[stack]]
    // of 4 lines in the middle, and a typo in body #250: its header is on line
    // 1 + 150 * 6 + 4 + 100 * 6 = 1505 (the stack expands to 3 bodies, hence #253).
    let mut text = String::new();
    for i in 0..300 {
        if i == 150 {
            text.push_str("[[stack]]\ncount = 3\nsize = 1\nx = -20\n");
        }
        let typo = if i == 250 { "frction = 1\n" } else { "" };
        text.push_str(&format!(
            "[[body]]\nname = \"b{i}\"\nshape = {{ type = \"circle\", radius = 0.5 }}\nposition = [{i}, 0]\ndensity = 1\n{typo}"
        ));
        if typo.is_empty() {
            text.push('\n');
        }
    }
    let e = Scene::from_toml_str(&text).unwrap_err().to_string();
    assert!(
        e.starts_with(r#"body "b250" (#253) at line 1505: unknown field `frction`"#),
        "{e}"
    );
}
