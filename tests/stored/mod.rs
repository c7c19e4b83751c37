//! Converged references computed once and kept in `tests/references/`, so that a
//! test compares against a reference whose noise is far below its bounds without
//! paying minutes of path tracing on every run.
//!
//! A stored reference is trusted only while it answers the same question: each file
//! holds a `key` — the text of everything that determines the reference (scene,
//! points, sample counts, seeds, steps) — and a key that differs from the test's
//! makes the test compute the reference live (slow but right) and say how to
//! refresh the file. Whether the code still computes the same thing in expectation
//! is the test's own business: it recomputes a few points live on fresh seeds and
//! checks them against the stored values within their noise ([`agrees`]).
//!
//! `VOLCACHE_REFRESH_REFERENCES=1 cargo test --test NAME` recomputes and rewrites
//! the test's files (written beside and renamed over, never left partial).

#![allow(dead_code)] // each test file uses part of the store

use serde::{Serialize, de::DeserializeOwned};
use std::path::PathBuf;

const REFRESH: &str = "VOLCACHE_REFRESH_REFERENCES";

#[derive(serde::Serialize, serde::Deserialize)]
struct File<T> {
    key: String,
    value: T,
}

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/references")
        .join(format!("{name}.json"))
}

/// The reference stored as `tests/references/<name>.json` if its key is `key`;
/// otherwise (missing, stale, or a refresh asked for) `compute`'s, written back
/// only on a refresh.
pub fn load_or_compute<T: Serialize + DeserializeOwned>(name: &str, key: &str, compute: impl FnOnce() -> T) -> T {
    let file = path(name);
    let refresh = std::env::var_os(REFRESH).is_some();
    if !refresh {
        let stored = std::fs::read_to_string(&file)
            .ok()
            .and_then(|text| serde_json::from_str::<File<T>>(&text).ok());
        match stored {
            Some(f) if f.key == key => return f.value,
            Some(_) => eprintln!(
                "{}: stale (its key differs from the test's); computing the reference live. \
                 Refresh it with {REFRESH}=1 cargo test --test <this test>",
                file.display()
            ),
            None => eprintln!(
                "{}: missing or unreadable; computing the reference live. \
                 Store it with {REFRESH}=1 cargo test --test <this test>",
                file.display()
            ),
        }
    }
    let value = compute();
    if refresh {
        let text = serde_json::to_string_pretty(&File {
            key: key.to_string(),
            value: &value,
        })
        .expect("a reference serializes");
        let tmp = file.with_extension("json.partial");
        std::fs::create_dir_all(file.parent().unwrap()).unwrap();
        std::fs::write(&tmp, text).unwrap_or_else(|e| panic!("{}: {e}", tmp.display()));
        std::fs::rename(&tmp, &file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        eprintln!("{}: refreshed", file.display());
    }
    value
}

/// Whether a live mean of `live_n` seeds agrees with a stored mean of `stored_n`
/// seeds whose standard error (the length of its deviation) is `stored_se`: the
/// live mean's noise is the stored seeds' spread over √live_n. Returns the verdict
/// and the difference's length in standard deviations of that length. The bound is
/// four of them: a false alarm has a chance below 1e-4 (6e-5 for noise along one
/// axis, 1e-7 for noise spread evenly over two).
pub fn agrees(live: &[f64], live_n: usize, stored: &[f64], stored_se: f64, stored_n: usize) -> (bool, f64) {
    let diff: f64 = live
        .iter()
        .zip(stored)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt();
    let per_seed_var = stored_se * stored_se * stored_n as f64;
    let sd = (per_seed_var / live_n as f64 + stored_se * stored_se).sqrt();
    (diff <= 4.0 * sd, diff / sd)
}
