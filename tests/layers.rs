//! The layers of ARCHITECTURE.md, checked against the code: each module of `src/`
//! may name (`crate::x`, or `volcache::x` from the binary) only the modules below it.
//! A new arrow back up, or between the two worlds, fails here.

use std::collections::BTreeSet;
use std::path::Path;

/// Every top-level module and what it may use.
const LAYERS: &[(&str, &[&str])] = &[
    ("core", &[]),
    ("progress", &[]),
    ("scene_check", &["core"]),
    ("pipeline", &["core", "progress"]),
    ("flatland", &["core", "progress", "scene_check", "pipeline"]),
    ("volume", &["core", "progress", "scene_check", "pipeline"]),
    ("output", &["core", "flatland", "volume"]),
    ("figure", &["core", "pipeline", "flatland", "volume", "output"]),
    (
        "app",
        &[
            "core",
            "progress",
            "scene_check",
            "pipeline",
            "flatland",
            "volume",
            "output",
            "figure",
        ],
    ),
    (
        "cli",
        &[
            "core",
            "progress",
            "scene_check",
            "pipeline",
            "flatland",
            "volume",
            "output",
            "figure",
            "app",
        ],
    ),
];

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level module a source file belongs to (`main.rs` is the CLI's).
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy()
        .to_string();
    match first.trim_end_matches(".rs") {
        "main" => "cli".into(),
        m => m.into(),
    }
}

/// Top-level modules named in code (comments stripped: prose may name anything).
fn named(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap();
        for prefix in ["crate::", "volcache::"] {
            let mut rest = code;
            while let Some(i) = rest.find(prefix) {
                rest = &rest[i + prefix.len()..];
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                out.insert(name);
            }
        }
    }
    out
}

#[test]
fn no_module_uses_a_layer_above_it_or_beside_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut wrong = Vec::new();
    for f in &files {
        let m = module_of(&src, f);
        if m == "lib" {
            continue;
        }
        let allowed = LAYERS
            .iter()
            .find(|(name, _)| *name == m)
            .unwrap_or_else(|| panic!("{}: module {m} has no layer in this test", f.display()))
            .1;
        for used in named(&std::fs::read_to_string(f).unwrap()) {
            if used != m && LAYERS.iter().any(|(n, _)| *n == used) && !allowed.contains(&used.as_str()) {
                wrong.push(format!("{} ({m}) uses {used}", f.strip_prefix(&src).unwrap().display()));
            }
        }
    }
    assert!(wrong.is_empty(), "imports against the layers:\n{}", wrong.join("\n"));
}
