//! The module graph keeps its shape (README, "Architecture"): no file imports a file
//! of a higher layer, and no files import each other in a circle. Read from the
//! source text: every `crate::`, `super::` and `volcache::` path outside test
//! modules, resolved to the longest module path that is a file. `mod.rs` and
//! `lib.rs` only declare and re-export, so they are not part of the graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Layers from the ground up; a file may import its own layer and those below.
/// `study` (the experiment protocols) runs `flatland` and `volume` and writes
/// through `output`; `figure` draws what it is handed; `app` and `cli` orchestrate.
const LAYERS: [&[&str]; 7] = [
    &["core", "progress", "limits"],
    &["pipeline", "scene_check"],
    &["flatland", "volume"],
    &["output", "study"],
    &["figure"],
    &["app"],
    &["cli", "main"],
];

fn layer(module: &str) -> usize {
    let top = module.split("::").next().unwrap_or_default();
    LAYERS
        .iter()
        .position(|l| l.contains(&top))
        .unwrap_or_else(|| panic!("`{top}` is in no layer: add it to LAYERS"))
}

/// Module path ("cli::figure") → source text without test modules and comments.
fn sources() -> BTreeMap<String, String> {
    fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&src, &mut files);
    let mut out = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap().with_extension("");
        let parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        let text = std::fs::read_to_string(&f).unwrap();
        // Test-only files: `#[path]` test modules and `#[cfg(test)] mod x;` helpers.
        let name = parts.last().unwrap();
        let test_only =
            name.ends_with("_tests") || ["core/testing", "figure/synthetic"].contains(&parts.join("/").as_str());
        if matches!(name.as_str(), "mod" | "lib") || test_only {
            continue;
        }
        let code = text.split("#[cfg(test)]").next().unwrap();
        let code: String = code
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        out.insert(parts.join("::"), code);
    }
    out
}

/// The files a file imports.
fn imports(module: &str, code: &str, files: &BTreeMap<String, String>) -> BTreeSet<String> {
    let mut parent: Vec<&str> = module.split("::").collect();
    parent.pop();
    let mut out = BTreeSet::new();
    for (prefix, base) in [("crate::", vec![]), ("volcache::", vec![]), ("super::", parent)] {
        for (i, _) in code.match_indices(prefix) {
            // A path continues an identifier only at its start (not `xcrate::`).
            if code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let rest = &code[i + prefix.len()..];
            let end = rest
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(rest.len());
            let mut path: Vec<&str> = base.clone();
            path.extend(rest[..end].split("::").filter(|s| !s.is_empty()));
            if let Some(k) = (1..=path.len())
                .rev()
                .find(|&k| files.contains_key(&path[..k].join("::")))
            {
                let target = path[..k].join("::");
                if target != module {
                    out.insert(target);
                }
            }
        }
    }
    out
}

#[test]
fn no_import_runs_back_up_a_layer() {
    let files = sources();
    assert!(
        files.len() > 100 && files.contains_key("study::stored"),
        "{} files",
        files.len()
    );
    let mut upward = Vec::new();
    for (m, code) in &files {
        for t in imports(m, code, &files) {
            if layer(&t) > layer(m) {
                upward.push(format!("{m} -> {t}"));
            }
        }
    }
    assert!(upward.is_empty(), "imports of a higher layer:\n{}", upward.join("\n"));
}

#[test]
fn no_files_import_each_other_in_a_circle() {
    let files = sources();
    let graph: BTreeMap<&String, BTreeSet<String>> = files.iter().map(|(m, c)| (m, imports(m, c, &files))).collect();
    // Depth-first search; a back edge to a file on the current path closes a circle.
    fn visit<'a>(
        m: &'a String,
        graph: &'a BTreeMap<&String, BTreeSet<String>>,
        state: &mut BTreeMap<&'a String, bool>,
        path: &mut Vec<&'a String>,
        circles: &mut Vec<String>,
    ) {
        state.insert(m, true);
        path.push(m);
        for t in &graph[m] {
            match state.get(t) {
                Some(true) => {
                    let start = path.iter().position(|p| *p == t).unwrap();
                    let names: Vec<&str> = path[start..].iter().map(|s| s.as_str()).collect();
                    circles.push(format!("{} -> {t}", names.join(" -> ")));
                }
                Some(false) => {}
                None => visit(t, graph, state, path, circles),
            }
        }
        path.pop();
        state.insert(m, false);
    }
    let (mut state, mut circles) = (BTreeMap::new(), Vec::new());
    for m in graph.keys() {
        if !state.contains_key(*m) {
            visit(m, &graph, &mut state, &mut Vec::new(), &mut circles);
        }
    }
    assert!(circles.is_empty(), "import circles:\n{}", circles.join("\n"));
}

/// The two worlds share one method (`pipeline`) and never each other: 2D code does
/// not name `volume`, 3D code does not name `flatland`.
#[test]
fn the_two_worlds_do_not_import_each_other() {
    let files = sources();
    let mut across = Vec::new();
    for (m, code) in &files {
        for t in imports(m, code, &files) {
            let (a, b) = (m.split("::").next().unwrap(), t.split("::").next().unwrap());
            if (a, b) == ("flatland", "volume") || (a, b) == ("volume", "flatland") {
                across.push(format!("{m} -> {t}"));
            }
        }
    }
    assert!(across.is_empty(), "imports between the worlds:\n{}", across.join("\n"));
}
