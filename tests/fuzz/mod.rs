//! A stable-toolchain fuzz harness (issue 14): inputs are mutations of a seeded
//! corpus (the shipped files and every input the issue reported), drawn from the
//! project's own deterministic streams, so a failing case is replayed from its
//! (seed, case) alone. Each case runs under `catch_unwind` and a wall-time bound;
//! the tally counts cases, panics, hangs and property failures.
//!
//! In CI (`cargo test`) the seed and case count are fixed; a long run sets
//! `VOLCACHE_FUZZ_CASES` (and optionally `VOLCACHE_FUZZ_SEED`), e.g.
//! `VOLCACHE_FUZZ_CASES=20000 cargo test --test fuzz_parsers -- --nocapture` (the test
//! profile is optimised).

#![allow(dead_code)] // each test crate uses a part

use std::panic::AssertUnwindSafe;
use std::path::Path;
use std::time::{Duration, Instant};
use volcache::core::rng::Sampler;

/// Numbers users (and the issue) pushed in: the ends of f64, of u32, of the
/// validated ranges, and what JSON cannot hold.
pub const EXTREMES: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "0.5",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "1e309",
    "5e-324",
    "-5e-324",
    "2.2250738585072014e-308",
    "1e-300",
    "1e300",
    "1e154",
    "1e155",
    "1e12",
    "1.0000001e12",
    "-1e12",
    "1e13",
    "1e-6",
    "9.99e-7",
    "1e-9",
    "1e-12",
    "1e-13",
    "1e-20",
    "1e-21",
    "1e20",
    "1.0001e20",
    "1e9",
    "1.01e9",
    "1e39",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775808",
    "100000",
    "100001",
    "16384",
    "16385",
    "1048576",
    "1048577",
    "0.999",
    "-0.999",
    "0.9991",
    "0.9999999999999999",
    "-0.9999999999999999",
    "45",
    "45.0001",
    "179",
    "180",
    "1e-3",
    "9e-4",
    "1e6",
    "1e7",
    "NaN",
    "nan",
    "Infinity",
    "-Infinity",
    "null",
    "true",
    "\"1\"",
    "[]",
    "{}",
    "[1, 2]",
    "[1e308, 1e308, 1e308]",
    "[0, 0, 0]",
];

/// Cases per target: `VOLCACHE_FUZZ_CASES`, else `ci`.
pub fn cases(ci: usize) -> usize {
    std::env::var("VOLCACHE_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(ci)
}

pub fn seed() -> u64 {
    std::env::var("VOLCACHE_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(14)
}

/// The files of `dir` (relative to the crate) whose names end with `ext`, sorted.
pub fn corpus(dirs: &[&str], ext: &str) -> Vec<(String, Vec<u8>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut v = Vec::new();
    for d in dirs {
        let mut names: Vec<_> = std::fs::read_dir(root.join(d))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.to_string_lossy().ends_with(ext))
            .collect();
        names.sort();
        for p in names {
            v.push((p.display().to_string(), std::fs::read(&p).unwrap()));
        }
    }
    assert!(!v.is_empty(), "empty corpus in {dirs:?}");
    v
}

/// Spans of numbers in a text (JSON or OBJ): where a number token starts and ends.
fn number_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let c = text[i];
        let starts = c.is_ascii_digit() || (c == b'-' && text.get(i + 1).is_some_and(|d| d.is_ascii_digit()));
        let inside_word = i > 0 && (text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'_');
        if starts && !inside_word {
            let mut j = i + 1;
            while j < text.len() && (text[j].is_ascii_digit() || b".eE+-".contains(&text[j])) {
                j += 1;
            }
            spans.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    spans
}

/// One random edit of `input` (1–3 are chained per case).
pub fn mutate_once(input: &[u8], s: &mut Sampler) -> Vec<u8> {
    let mut v = input.to_vec();
    let n = v.len().max(1);
    match s.next_index(10) {
        // A number becomes an extreme (the most telling edit: weighted ×4).
        0..=3 => {
            let spans = number_spans(&v);
            if !spans.is_empty() {
                let (a, b) = spans[s.next_index(spans.len())];
                let with = EXTREMES[s.next_index(EXTREMES.len())].as_bytes();
                v.splice(a..b, with.iter().copied());
            }
        }
        // A number scaled by a power of ten, or drawn log-uniformly over 10^±25
        // (edits that often stay inside the ranges, so accepted inputs vary too).
        4 => {
            let spans = number_spans(&v);
            if !spans.is_empty() {
                let (a, b) = spans[s.next_index(spans.len())];
                let text = String::from_utf8_lossy(&v[a..b]).into_owned();
                if let Ok(x) = text.parse::<f64>() {
                    let y = if s.next_f64() < 0.5 {
                        x * 10f64.powi(s.next_index(41) as i32 - 20)
                    } else {
                        let sign = if s.next_f64() < 0.2 { -1.0 } else { 1.0 };
                        sign * 10f64.powf(50.0 * s.next_f64() - 25.0)
                    };
                    // Integers stay integers (sizes, counts, seeds).
                    let shown = if text.contains(['.', 'e', 'E']) {
                        format!("{y:e}")
                    } else {
                        format!("{}", y.abs().min(1e19) as u64)
                    };
                    v.splice(a..b, shown.bytes());
                }
            }
        }
        // JSON structure: drop, duplicate or swap a node (see `mutate_json`).
        5 | 6 => {
            if let Some(out) = mutate_json(&v, s) {
                v = out;
            }
        }
        // Bytes: delete a span, duplicate a span, insert a byte, truncate.
        7 => {
            let a = s.next_index(n);
            let b = (a + 1 + s.next_index(16)).min(v.len());
            if a < b {
                v.drain(a..b);
            }
        }
        8 => {
            let a = s.next_index(n);
            let b = (a + 1 + s.next_index(64)).min(v.len());
            if a < b {
                let chunk = v[a..b].to_vec();
                let at = s.next_index(v.len() + 1);
                v.splice(at..at, chunk);
            }
        }
        _ => {
            let at = s.next_index(v.len() + 1);
            let bytes = b"{}[],:\"0123456789.eE-+ \nnvf/#\\\x00\xff";
            let byte = bytes[s.next_index(bytes.len())];
            if s.next_f64() < 0.2 {
                v.truncate(at);
            } else {
                v.insert(at, byte);
            }
        }
    }
    v
}

/// A structural edit of JSON text (None if it does not parse).
fn mutate_json(text: &[u8], s: &mut Sampler) -> Option<Vec<u8>> {
    let mut root: serde_json::Value = serde_json::from_slice(text).ok()?;
    let mut paths = Vec::new();
    collect_paths(&root, &mut Vec::new(), &mut paths);
    if paths.is_empty() {
        return None;
    }
    let path = paths[s.next_index(paths.len())].clone();
    let donor = {
        let p = &paths[s.next_index(paths.len())];
        get(&root, p).cloned()
    };
    let (last, parent_path) = path.split_last()?;
    let parent = get_mut(&mut root, parent_path)?;
    match (parent, last, s.next_index(5)) {
        (serde_json::Value::Object(m), Key::Field(k), 0) => {
            m.remove(k);
        }
        (serde_json::Value::Object(m), Key::Field(_), 1) => {
            m.insert("unknown_field".into(), serde_json::json!(1));
        }
        (serde_json::Value::Array(a), Key::Index(i), 0) => {
            a.remove(*i);
        }
        (serde_json::Value::Array(a), Key::Index(i), 1) => {
            let x = a[*i].clone();
            for _ in 0..1 + s.next_index(3) {
                a.insert(*i, x.clone());
            }
        }
        (parent, key, _) => {
            let slot = match (parent, key) {
                (serde_json::Value::Object(m), Key::Field(k)) => m.get_mut(k)?,
                (serde_json::Value::Array(a), Key::Index(i)) => a.get_mut(*i)?,
                _ => return None,
            };
            *slot = match donor {
                Some(d) if s.next_f64() < 0.5 => d,
                _ => serde_json::from_str(EXTREMES[s.next_index(EXTREMES.len())]).unwrap_or(serde_json::Value::Null),
            };
        }
    }
    serde_json::to_vec(&root).ok()
}

#[derive(Clone, Debug)]
enum Key {
    Field(String),
    Index(usize),
}

fn collect_paths(v: &serde_json::Value, at: &mut Vec<Key>, out: &mut Vec<Vec<Key>>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                at.push(Key::Field(k.clone()));
                out.push(at.clone());
                collect_paths(x, at, out);
                at.pop();
            }
        }
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                at.push(Key::Index(i));
                out.push(at.clone());
                collect_paths(x, at, out);
                at.pop();
            }
        }
        _ => {}
    }
}

fn get<'a>(v: &'a serde_json::Value, path: &[Key]) -> Option<&'a serde_json::Value> {
    path.iter().try_fold(v, |v, k| match k {
        Key::Field(f) => v.get(f),
        Key::Index(i) => v.get(*i),
    })
}

fn get_mut<'a>(v: &'a mut serde_json::Value, path: &[Key]) -> Option<&'a mut serde_json::Value> {
    path.iter().try_fold(v, |v, k| match k {
        Key::Field(f) => v.get_mut(f),
        Key::Index(i) => v.get_mut(*i),
    })
}

/// Case `k` of a run: a corpus entry, unchanged (the first pass) or with 1–3 edits.
pub fn case(corpus: &[(String, Vec<u8>)], seed: u64, k: usize) -> (String, Vec<u8>) {
    let (name, base) = &corpus[k % corpus.len()];
    if k < corpus.len() {
        return (name.clone(), base.clone());
    }
    let mut s = Sampler::new2(seed, 14, k as u64);
    let mut v = base.clone();
    // One edit most of the time (a single change is what a user makes), up to three.
    let edits = if s.next_f64() < 0.6 { 1 } else { 2 + s.next_index(2) };
    for _ in 0..edits {
        v = mutate_once(&v, &mut s);
    }
    (name.clone(), v)
}

/// What a run found.
#[derive(Debug, Default)]
pub struct Tally {
    pub cases: usize,
    pub accepted: usize,
    pub panics: usize,
    pub hangs: usize,
    /// Properties that failed (non-finite output, an error not naming the file…).
    pub failures: usize,
    pub slowest: Duration,
    pub examples: Vec<String>,
}

impl Tally {
    fn note(&mut self, what: String) {
        if self.examples.len() < 8 {
            self.examples.push(what);
        }
    }

    pub fn assert_clean(&self, target: &str) {
        eprintln!(
            "fuzz {target}: {} cases ({} accepted), {} panics, {} hangs, {} property failures; slowest case {:?}",
            self.cases, self.accepted, self.panics, self.hangs, self.failures, self.slowest
        );
        assert!(
            self.panics + self.hangs + self.failures == 0,
            "fuzz {target}: {}",
            self.examples.join("\n")
        );
    }
}

/// A case slower than this counts as a hang (the slowest measured was ~0.3 s: an
/// accepted scene with deep paths in a dense medium, rendered at 2×2).
pub const HANG: Duration = Duration::from_secs(20);

/// Run `check` on every case: Ok(true) accepted, Ok(false) refused cleanly,
/// Err(why) a property failure; panics and overtime are counted too. Failing
/// inputs are saved under `target/fuzz-failures/<target>/` for replay.
pub fn run(
    target: &str,
    corpus: &[(String, Vec<u8>)],
    n: usize,
    check: impl Fn(&[u8]) -> Result<bool, String>,
) -> Tally {
    let seed = seed();
    let mut t = Tally::default();
    for k in 0..n.max(corpus.len()) {
        let (name, input) = case(corpus, seed, k);
        let start = Instant::now();
        let r = std::panic::catch_unwind(AssertUnwindSafe(|| check(&input)));
        let dt = start.elapsed();
        t.cases += 1;
        t.slowest = t.slowest.max(dt);
        let bad = match r {
            Ok(Ok(accepted)) => {
                t.accepted += accepted as usize;
                None
            }
            Ok(Err(why)) => {
                t.failures += 1;
                Some(why)
            }
            Err(_) => {
                t.panics += 1;
                Some("panicked".to_string())
            }
        };
        if dt > HANG {
            t.hangs += 1;
        }
        if bad.is_some() || dt > HANG {
            let why = bad.unwrap_or_else(|| format!("took {dt:?}"));
            t.note(format!("case {k} (seed {seed}, from {name}): {why}"));
            let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
                .join("fuzz-failures")
                .join(target);
            let _ = std::fs::create_dir_all(&dir);
            let _ = std::fs::write(dir.join(format!("case{k}")), &input);
        }
    }
    t
}
