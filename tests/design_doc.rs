//! docs/design.md's module diagram is the code's own: every arrow is an import in the box it
//! leaves, every import from one box into another is an arrow, every source file under `src/`
//! and `clients/` sits in exactly one box, and the arrows make no cycle (nothing lower imports
//! anything higher). An import is a `crate::<module>` path in the library, or a
//! `tiltbox::<module>` path in a binary, anywhere outside comments.

mod common;

use common::{read_repo_file, repo_path};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The diagram: each box with the paths it covers, and the arrows between boxes.
struct Diagram {
    boxes: BTreeMap<String, Vec<String>>,
    arrows: BTreeSet<(String, String)>,
}

/// The first `mermaid` flowchart after "## Layers" in docs/design.md: `id["paths: words"]`
/// declares a box (the paths before the colon, separated by commas), `a --> b` an arrow.
fn diagram() -> Diagram {
    let doc = read_repo_file("docs/design.md");
    let layers = doc.find("## Layers").expect("a Layers section");
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
    let missing: Vec<_> = imports.difference(&d.arrows).collect();
    let stale: Vec<_> = d.arrows.difference(&imports).collect();
    assert!(
        missing.is_empty() && stale.is_empty(),
        "docs/design.md's diagram and the imports disagree.\n\
         imports the diagram lacks: {missing:?}\narrows nothing imports: {stale:?}"
    );

    // No cycle: repeatedly remove boxes that import nothing left.
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

#[test]
fn the_reader_finds_imports_and_skips_comments() {
    let text = "use crate::physics::World;\n\
                // use crate::service::Server;\n\
                let x = tiltbox::scene::Scene::load(p); // crate::protocol\n\
                use super::crate_like; my_crate::measure::x();\n";
    let found: Vec<String> = named_modules(text).into_iter().collect();
    assert_eq!(found, ["physics", "scene"]);
}
