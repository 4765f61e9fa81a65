//! Scene files for the tests: the shipped ones, and scene text built around a ground.

use std::path::PathBuf;
use tiltbox::physics::Vec2;
use tiltbox::scene::{Scene, SceneBody, SceneError};

/// A shipped scene file, `config/scenes/<name>`.
pub fn scene_path(name: &str) -> PathBuf {
    super::repo_path("config/scenes").join(name)
}

/// A shipped scene, loaded.
pub fn load(name: &str) -> Scene {
    Scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Equal within 1e-5 m.
pub fn close(a: Vec2, b: Vec2) -> bool {
    (a - b).length() < 1e-5
}

/// A scene named `test` with a static 10 m ground, its top at y = 0: body #0.
pub const GROUND: &str = r#"
name = "test"

[[body]]
name = "ground"
static = true
shape = { type = "rect", width = 10, height = 1 }
position = [0, -0.5]
"#;

/// [`GROUND`] followed by `extra`.
pub fn with_ground(extra: &str) -> String {
    format!("{GROUND}\n{extra}")
}

/// The error for a scene holding the ground (#0) and then `body`, and its message.
pub fn error_for(body: &str) -> (SceneError, String) {
    let e = Scene::from_toml_str(&with_ground(body)).unwrap_err();
    let s = e.to_string();
    (e, s)
}

/// A `[[body]]` named "brick 3", a 1 x 0.5 m box at (0, 1), with `fields` added.
pub fn brick(fields: &str) -> String {
    format!(
        "[[body]]\nname = \"{}\"\nshape = {{ type = \"rect\", width = 1, height = 0.5 }}\nposition = [0, 1]\n{fields}\n",
        "brick 3"
    )
}

/// A `[[body]]` named `name` with the inline table `shape` and `fields`.
pub fn shaped(name: &str, shape: &str, fields: &str) -> String {
    format!("[[body]]\nname = \"{name}\"\nshape = {shape}\n{fields}\n")
}

/// The one body after the ground, or the error's message.
pub fn parse_body(body: &str) -> Result<SceneBody, String> {
    Scene::from_toml_str(&with_ground(body))
        .map(|mut s| s.bodies.remove(1))
        .map_err(|e| e.to_string())
}

/// The message refusing a body named `name` of the inline table `shape`, at (0, 1) with
/// density 1: what is wrong is the shape.
pub fn refusal(name: &str, shape: &str) -> String {
    parse_body(&shaped(name, shape, "position = [0, 1]\ndensity = 1")).unwrap_err()
}

/// The first TOML example (a fenced `toml` block) after `heading` in docs/scenes.md.
pub fn docs_example(heading: &str) -> String {
    let doc = super::read_repo_file("docs/scenes.md");
    let at = doc
        .find(heading)
        .unwrap_or_else(|| panic!("{heading:?} in docs/scenes.md"));
    let start = at + doc[at..].find("```toml\n").expect("a toml example") + "```toml\n".len();
    let end = start + doc[start..].find("```").expect("the example's end");
    doc[start..end].to_owned()
}
