//! docs/design.md's module diagrams are the code's own: every arrow is an import in the box it
//! leaves, every import from one box into another is an arrow, every source file sits in
//! exactly one box, and the arrows make no cycle (nothing lower imports anything higher).
//!
//! - The layers ("## Layers"): every file under `src/` and `clients/`; an import is a
//!   `crate::<module>` path in the library, or a `tiltbox::<module>` path in a binary.
//! - The engine ("## The engine's modules"): every file under `src/physics` but its root; an
//!   import is a `super::`, `self::` or `crate::physics::` path resolved to the module it names
//!   (inline modules such as `mod tests` counted), and nothing may import the root.
//!
//! Imports are read anywhere outside comments.

mod common;

use common::{read_repo_file, repo_path};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The diagram: each box with the paths it covers, and the arrows between boxes.
struct Diagram {
    boxes: BTreeMap<String, Vec<String>>,
    arrows: BTreeSet<(String, String)>,
}

/// The first `mermaid` flowchart after the heading `section` in docs/design.md:
/// `id["paths: words"]` declares a box (the paths before the colon, separated by commas),
/// `a --> b` an arrow.
fn diagram_after(section: &str) -> Diagram {
    let doc = read_repo_file("docs/design.md");
    let layers = doc.find(section).expect("the diagram's section");
    let start = layers + doc[layers..].find("```mermaid\n").expect("a mermaid block");
    let body = &doc[start + "```mermaid\n".len()..];
    let body = &body[..body.find("```").expect("the block's end")];
    let mut boxes = BTreeMap::new();
    let mut arrows = BTreeSet::new();
    for line in body.lines().map(str::trim) {
        if let Some((from, to)) = line.split_once("-->") {
            arrows.insert((from.trim().to_owned(), to.trim().to_owned()));
        } else if let Some((id, label)) = line.split_once("[\"") {
            let paths = label.split(':').next().unwrap_or_default();
            let paths = paths
                .split(',')
                .map(|p| p.trim().trim_end_matches('/').to_owned())
                .collect();
            boxes.insert(id.trim().to_owned(), paths);
        }
    }
    Diagram { boxes, arrows }
}

/// The layers' diagram.
fn diagram() -> Diagram {
    diagram_after("## Layers")
}

/// Every `.rs` file under `dir` (relative to the repository), recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(repo_path(dir.to_str().unwrap())).unwrap() {
        let path = entry.unwrap().path();
        let rel = path.strip_prefix(repo_path("")).unwrap().to_owned();
        if path.is_dir() {
            rust_files(&rel, out);
        } else if rel.extension().is_some_and(|e| e == "rs") {
            out.push(rel);
        }
    }
}

/// The modules a source text names: the identifier after every `crate::` or `tiltbox::`
/// outside comments.
fn named_modules(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in text.lines() {
        let code = match line.find("//") {
            Some(i) => &line[..i],
            None => line,
        };
        for prefix in ["crate::", "tiltbox::"] {
            for (i, _) in code.match_indices(prefix) {
                let preceded_by_ident = code[..i]
                    .chars()
                    .next_back()
                    .is_some_and(|c| c.is_alphanumeric() || c == '_');
                if preceded_by_ident {
                    continue;
                }
                let rest = &code[i + prefix.len()..];
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        }
    }
    out
}

/// The box that covers `file`: a box's path is the file itself or a directory above it.
fn box_of<'a>(diagram: &'a Diagram, file: &Path) -> Vec<&'a str> {
    diagram
        .boxes
        .iter()
        .filter(|(_, paths)| paths.iter().any(|p| file.starts_with(p)))
        .map(|(id, _)| id.as_str())
        .collect()
}

/// Whether the boxes still left after removing, again and again, every box that imports
/// nothing left are none: no cycle.
fn assert_acyclic(d: &Diagram) {
    let mut left: BTreeSet<&str> = d.boxes.keys().map(String::as_str).collect();
    while let Some(leaf) = left.iter().copied().find(|b| {
        !d.arrows
            .iter()
            .any(|(f, t)| f == b && left.contains(t.as_str()))
    }) {
        left.remove(leaf);
    }
    assert!(left.is_empty(), "the imports make a cycle among {left:?}");
}

/// The arrows the diagram lacks and the arrows nothing imports, as a failure message.
fn assert_arrows_match(d: &Diagram, imports: &BTreeSet<(String, String)>) {
    let missing: Vec<_> = imports.difference(&d.arrows).collect();
    let stale: Vec<_> = d.arrows.difference(imports).collect();
    assert!(
        missing.is_empty() && stale.is_empty(),
        "docs/design.md's diagram and the imports disagree.\n\
         imports the diagram lacks: {missing:?}\narrows nothing imports: {stale:?}"
    );
}

#[test]
fn the_module_diagram_is_the_code() {
    let d = diagram();
    assert!(d.boxes.len() >= 8, "boxes read: {:?}", d.boxes);
    for (id, paths) in &d.boxes {
        for p in paths {
            assert!(
                repo_path(p).exists(),
                "box {id} names {p}, which does not exist"
            );
        }
    }
    for (from, to) in &d.arrows {
        assert!(
            d.boxes.contains_key(from) && d.boxes.contains_key(to),
            "arrow {from} --> {to} between boxes the diagram does not declare"
        );
    }

    let mut files = Vec::new();
    rust_files(Path::new("src"), &mut files);
    rust_files(Path::new("clients"), &mut files);
    let mut imports = BTreeSet::new();
    for file in &files {
        if file == Path::new("src/lib.rs") {
            continue; // the crate root declares the modules; it imports none
        }
        let owners = box_of(&d, file);
        assert_eq!(owners.len(), 1, "{} is in boxes {owners:?}", file.display());
        let from = owners[0];
        let text = std::fs::read_to_string(repo_path(file.to_str().unwrap())).unwrap();
        for module in named_modules(&text) {
            assert!(
                d.boxes.contains_key(&module),
                "{} names crate module `{module}`, which the diagram has no box for",
                file.display()
            );
            if module != from {
                imports.insert((from.to_owned(), module));
            }
        }
    }
    assert_arrows_match(&d, &imports);
    assert_acyclic(&d);
}

/// The module a file under `src/` is: `src/physics/solver/mod.rs` is `physics::solver`.
fn module_of(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix("src").expect("a file under src/");
    let mut path: Vec<String> = rel
        .with_extension("")
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    if path.last().is_some_and(|last| last == "mod") {
        path.pop();
    }
    path
}

/// The file of module `path`, if it is one: `src/<path>.rs` or `src/<path>/mod.rs`.
fn module_file(path: &[String]) -> Option<PathBuf> {
    let base = PathBuf::from("src").join(path.join("/"));
    [base.with_extension("rs"), base.join("mod.rs")]
        .into_iter()
        .find(|f| repo_path(f.to_str().unwrap()).is_file())
}

/// Every path in `code` (a line without its comment) that starts `crate::physics`, `self::`
/// or `super`, resolved from module `here` to the longest module it names.
fn engine_imports(code: &str, here: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let chars: Vec<char> = code.chars().collect();
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut i = 0;
    while i < chars.len() {
        if !ident(chars[i]) || (i > 0 && (ident(chars[i - 1]) || chars[i - 1] == ':')) {
            i += 1;
            continue;
        }
        // A run of identifiers joined by `::`.
        let start = i;
        let mut run = Vec::new();
        loop {
            let word_start = i;
            while i < chars.len() && ident(chars[i]) {
                i += 1;
            }
            run.push(chars[word_start..i].iter().collect::<String>());
            let joined = chars.get(i..i + 2) == Some(&[':', ':'][..]);
            if joined && chars.get(i + 2).is_some_and(|&c| ident(c)) {
                i += 2;
            } else {
                break;
            }
        }
        let after_pub =
            code[..code.char_indices().nth(start).map_or(0, |(b, _)| b)].ends_with("pub(");
        let base: Vec<String> = match run[0].as_str() {
            "crate" if run.get(1).is_some_and(|w| w == "physics") => {
                run.drain(..2);
                vec!["physics".to_owned()]
            }
            "self" if run.len() > 1 => {
                run.remove(0);
                here.to_vec()
            }
            "super" if !after_pub => {
                let mut base = here.to_vec();
                while run.first().is_some_and(|w| w == "super") {
                    run.remove(0);
                    base.pop();
                }
                base
            }
            _ => continue,
        };
        let mut path: Vec<String> = base.into_iter().chain(run).collect();
        while path.len() > 1 && module_file(&path).is_none() {
            path.pop();
        }
        out.push(path);
    }
    out
}

#[test]
fn the_engine_module_diagram_is_the_code() {
    let d = diagram_after("## The engine's modules");
    assert!(d.boxes.len() >= 15, "boxes read: {:?}", d.boxes);
    let mut files = Vec::new();
    rust_files(Path::new("src/physics"), &mut files);
    let mut imports = BTreeSet::new();
    for file in &files {
        if file == Path::new("src/physics/mod.rs") {
            continue; // the engine's root declares and re-exports; it is imported by nothing
        }
        let owners = box_of(&d, file);
        assert_eq!(owners.len(), 1, "{} is in boxes {owners:?}", file.display());
        let from = owners[0];
        let text = std::fs::read_to_string(repo_path(file.to_str().unwrap())).unwrap();
        // Inline modules (`mod tests { ... }`), by the indentation of their braces.
        let mut inline: Vec<(usize, String)> = Vec::new();
        for line in text.lines() {
            let code = line.find("//").map_or(line, |i| &line[..i]);
            let indent = code.len() - code.trim_start().len();
            let words: Vec<&str> = code.split_whitespace().collect();
            let opens = words.last() == Some(&"{") && words.iter().rev().nth(2) == Some(&"mod");
            if opens && words.len() <= 4 {
                inline.push((indent, words[words.len() - 2].to_owned()));
                continue;
            }
            if inline
                .last()
                .is_some_and(|(i, _)| code.trim_end() == format!("{}}}", " ".repeat(*i)))
            {
                inline.pop();
                continue;
            }
            let mut here = module_of(file);
            here.extend(inline.iter().map(|(_, name)| name.clone()));
            for path in engine_imports(code, &here) {
                assert!(
                    path != ["physics"],
                    "{} imports the engine's root: {}",
                    file.display(),
                    line.trim()
                );
                let target = module_file(&path).expect("a module");
                let owner = box_of(&d, &target);
                assert_eq!(owner.len(), 1, "{} is in boxes {owner:?}", target.display());
                if owner[0] != from {
                    imports.insert((from.to_owned(), owner[0].to_owned()));
                }
            }
        }
    }
    assert_arrows_match(&d, &imports);
    assert_acyclic(&d);
}

#[test]
fn the_engine_reader_resolves_relative_paths() {
    let here: Vec<String> = ["physics", "solver", "bundles"].map(String::from).to_vec();
    let found = engine_imports(
        "use super::contact_solver::{Bundle, Pass}; use super::{Selected, SolverBody}; \
         pub(super) fn f(&self) {} use crate::physics::math::Real; self.x",
        &here,
    );
    let want: Vec<Vec<String>> = [
        &["physics", "solver", "contact_solver"][..],
        &["physics", "solver"],
        &["physics", "math"],
    ]
    .iter()
    .map(|p| p.iter().map(|s| s.to_string()).collect())
    .collect();
    assert_eq!(found, want);
}

#[test]
fn the_reader_finds_imports_and_skips_comments() {
    let text = "use crate::physics::World;\n\
                // use crate::service::Server;\n\
                let x = tiltbox::scene::Scene::load(p); // crate::protocol\n\
                use super::crate_like; my_crate::measure::x();\n";
    let found: Vec<String> = named_modules(text).into_iter().collect();
    assert_eq!(found, ["physics", "scene"]);
}
