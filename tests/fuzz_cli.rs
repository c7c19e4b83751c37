//! Fuzzing the command line as a user would (issue 14): a mutated corpus scene and
//! a random command — field, probe (every method), caches (every method), render3d
//! (every method) — with options drawn from their valid values and their edges,
//! and output paths that sometimes name the scene or each other; one run in five
//! gets a SIGINT, SIGKILL or SIGTERM at a random moment (computing or writing).
//! Every run must end (no hang) with 0, 2 (a clear error) or 130, or by the kill we
//! sent, never a crash; what it writes must be finite (no NaN/inf EXR pixel, no
//! null number in a JSON summary); and it must be safe: the scene is unchanged,
//! nothing is written outside the outputs it was given, every summary's listed
//! outputs are the files beside it, and no temporary file is left behind (after a
//! kill, the next run of the same command removes the killed one's).
//!
//! CI runs a few cases; `VOLCACHE_FUZZ_CASES=N` makes a long run (see `fuzz/mod.rs`).

mod fuzz;

use std::collections::BTreeSet;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use volcache::core::rng::Sampler;

/// A run slower than this is a hang (the slowest measured: ~2 s, a 3D cache
/// placement at 3×2 pixels with deep paths).
const HANG: Duration = Duration::from_secs(60);

fn pick<'a>(s: &mut Sampler, from: &[&'a str]) -> &'a str {
    from[s.next_index(from.len())]
}

/// A valid value most of the time (so that runs get far), else one beyond an edge.
fn opt<'a>(s: &mut Sampler, valid: &[&'a str], beyond: &[&'a str]) -> &'a str {
    if s.next_f64() < 0.9 {
        pick(s, valid)
    } else {
        pick(s, beyond)
    }
}

/// Options of one command, drawn from valid values and their edges (the options'
/// own ranges are `volcache::limits` and the `--help` of each command).
fn command(s: &mut Sampler, three_d: bool) -> (Vec<String>, Vec<&'static str>) {
    let mut a: Vec<String> = Vec::new();
    let mut add = |xs: &[&str]| a.extend(xs.iter().map(|x| x.to_string()));
    // Outputs: the usual names, sometimes the scene itself or one name twice.
    let out_file =
        |s: &mut Sampler, usual: &'static str| -> &'static str { opt(s, &[usual], &["scene.json", "o/dup"]) };
    let mut outputs = vec![];
    if three_d {
        let method = pick(s, &["pt", "ours", "jarosz08"]);
        add(&["render3d", "scene.json", "--quiet", "--method", method]);
        add(&["--res", opt(s, &["2x2", "3x2", "1x1"], &["0x2", "16384x16384"])]);
        add(&["--spp", opt(s, &["1", "2"], &["0", "1048577"])]);
        add(&["--out", "o"]);
        outputs.push("o");
        if s.next_f64() < 0.3 {
            add(&["--exposure", opt(s, &["0", "100", "-100"], &["101", "nan", "1e308"])]);
        }
        if method != "pt" {
            add(&["--rays", opt(s, &["4", "16"], &["3", "1048577"])]);
            add(&["--steps", opt(s, &["1", "2"], &["0", "4097"])]);
            if s.next_f64() < 0.5 {
                add(&[&format!(
                    "--eps={}",
                    opt(s, &["0", "1e30", "1e-12"], &["nan", "inf", "-1", "1e31"])
                )]);
            } else if s.next_f64() < 0.5 {
                add(&["--caches", opt(s, &["1", "2"], &["0"])]);
            }
            if s.next_f64() < 0.3 {
                add(&[&format!(
                    "--march-step={}",
                    opt(s, &["1e-3", "1e300"], &["0", "-1", "nan"])
                )]);
            }
            if s.next_f64() < 0.3 {
                let r = out_file(s, "o/r.json");
                add(&["--records-out", r]);
                outputs.push(r);
            }
            if s.next_f64() < 0.2 {
                add(&["--second-order"]);
            }
        }
    } else {
        match pick(s, &["field", "probe", "caches"]) {
            "field" => {
                add(&["field", "scene.json", "--quiet"]);
                add(&[
                    "--res",
                    opt(s, &["2x2", "3x2", "1x1"], &["0x2", "16384x16384", "4097x4097"]),
                ]);
                add(&["--spp", opt(s, &["1", "2"], &["0", "1048577"])]);
                if s.next_f64() < 0.3 {
                    add(&["--quantity", pick(s, &["ls", "fluence"])]);
                    add(&["--part", pick(s, &["all", "direct", "single", "multiple"])]);
                }
                if s.next_f64() < 0.3 {
                    add(&[&format!("--omega-o={}", opt(s, &["0", "1e6", "-45"], &["1e7", "nan"]))]);
                    add(&[&format!(
                        "--exposure={}",
                        opt(s, &["0", "100", "-100"], &["101", "inf"])
                    )]);
                }
                if s.next_f64() < 0.4 {
                    add(&["--false-color"]);
                }
                for (flag, usual) in [("--out", "o/f.png"), ("--exr", "o/f.exr"), ("--json", "o/f.json")] {
                    if flag == "--out" || s.next_f64() < 0.6 {
                        let p = out_file(s, usual);
                        add(&[flag, p]);
                        outputs.push(p);
                    }
                }
            }
            "probe" => {
                add(&["probe", "scene.json", "--json"]);
                let method = pick(s, &["pt", "aware", "unaware", "reference"]);
                add(&["--method", method]);
                if s.next_f64() < 0.2 {
                    // An irradiance meter instead of points (refused beside a derivative method).
                    let sensor = opt(
                        s,
                        &["-1,0,1,0", "0,0,1e-3,1e12", "1e12,0,-1e12,0"],
                        &["0,0,0,0", "1,2,3", "nan,0,1,0"],
                    );
                    add(&[&format!("--sensor={sensor}")]);
                } else {
                    let at = opt(s, &["0,0", "0.3,-0.2", "1e12,0", "0,1e-300"], &["1e13,0", "nan,0"]);
                    add(&[&format!("--at={at}")]);
                }
                add(&["--spp", opt(s, &["1", "4"], &["0"])]);
                add(&["--rays", opt(s, &["3", "16"], &["2", "1048577"])]);
                add(&["--steps", opt(s, &["1", "3"], &["0", "4097"])]);
                add(&[&format!(
                    "--fd-step={}",
                    opt(s, &["1e-9", "0.5", "1e-2"], &["1e-10", "1", "1e-300"])
                )]);
                add(&[&format!(
                    "--medium-clamp={}",
                    opt(s, &["1e-6", "1e6", "1"], &["0", "1e308"])
                )]);
            }
            _ => {
                add(&[
                    "caches",
                    "scene.json",
                    "--quiet",
                    "--method",
                    pick(s, &["ours", "jarosz08", "pt"]),
                ]);
                add(&["--res", opt(s, &["2x2", "3x2", "1x1"], &["16384x16384"])]);
                add(&["--rays", opt(s, &["4", "16"], &["0", "1048577"])]);
                add(&["--steps", opt(s, &["1", "2"], &["0"])]);
                add(&["--ref-spp", opt(s, &["1", "2"], &["0"])]);
                add(&["--spp", opt(s, &["1", "2"], &["0"])]);
                if s.next_f64() < 0.5 {
                    add(&[&format!(
                        "--eps={}",
                        opt(s, &["0", "1e30", "0.05"], &["nan", "inf", "-1"])
                    )]);
                } else if s.next_f64() < 0.5 {
                    add(&["--caches", opt(s, &["1", "3", "100"], &["0"])]);
                }
                if s.next_f64() < 0.2 {
                    add(&["--per-part", "--second-order"]);
                }
                if s.next_f64() < 0.2 {
                    add(&["--direct-samples", opt(s, &["1", "3"], &["0"])]);
                }
                if s.next_f64() < 0.2 {
                    add(&[&format!(
                        "--edge-reach={}",
                        opt(s, &["0.5", "0.01"], &["0", "nan", "-1", "1e9"])
                    )]);
                }
                let out = pick(s, &["o/c", "o/c", "o/c", "."]);
                add(&["--out", out, "--ref-cache", "o/ref"]);
                outputs.extend([out, "o/ref"]);
            }
        }
    }
    (a, outputs)
}

/// Run `args` in `dir` (sending `signal` after its delay), within [`HANG`].
fn run_once(dir: &Path, args: &[String], signal: Option<(i32, Duration)>) -> (std::process::Output, bool, Duration) {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_volcache"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut sent = false;
    let mut hung = false;
    while child.try_wait().unwrap().is_none() {
        if let Some((sig, after)) = signal
            && !sent
            && start.elapsed() >= after
        {
            // SAFETY: signalling our own child.
            unsafe { libc::kill(child.id() as i32, sig) };
            sent = true;
        }
        if start.elapsed() > HANG {
            child.kill().unwrap();
            hung = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    (child.wait_with_output().unwrap(), hung, start.elapsed())
}

/// Summaries whose listed outputs are not the files beside them (a mixed set).
fn mixed_sets(dir: &Path, files: &BTreeSet<(PathBuf, u64)>) -> Vec<String> {
    let mut bad = Vec::new();
    for (p, _) in files.iter().filter(|(p, _)| p.extension().is_some_and(|e| e == "json")) {
        let Ok(v) = serde_json::from_slice::<serde_json::Value>(&std::fs::read(dir.join(p)).unwrap_or_default()) else {
            continue;
        };
        let Some(listed) = v.get("outputs").and_then(|o| o.as_array()) else {
            continue;
        };
        let folder = dir.join(p).parent().unwrap().to_path_buf();
        for f in listed {
            let path = folder.join(f["path"].as_str().unwrap_or_default());
            let bytes = std::fs::read(&path).unwrap_or_default();
            let same =
                f["bytes"] == bytes.len() && f["fnv1a64"] == format!("{:016x}", volcache::core::rng::fnv1a(&bytes));
            if !same {
                bad.push(format!(
                    "{} lists {}, which is not the file beside it",
                    p.display(),
                    path.display()
                ));
            }
        }
    }
    bad
}

/// Every file under `dir` (relative paths) with its bytes' hash.
fn snapshot(dir: &Path) -> BTreeSet<(PathBuf, u64)> {
    let mut out = BTreeSet::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let h = volcache::core::rng::fnv1a(&std::fs::read(&p).unwrap_or_default());
                out.insert((p.strip_prefix(dir).unwrap().to_path_buf(), h));
            }
        }
    }
    out
}

/// Keys that hold an optional value (null when absent); any other null in a
/// summary is a number that was NaN or inf.
const OPTIONAL: &[&str] = &[
    "time_budget",
    "rays3d_closest_hit_per_second",
    "exr",
    "png",
    "crop",
    "records_in",
    "records_out",
    "errors",
    "target_records",
    "cache",
];

fn null_numbers(v: &serde_json::Value, key: &str, method_pt: bool, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Null if !(OPTIONAL.contains(&key) || (key == "eps" && method_pt)) => {
            out.push(key.to_string())
        }
        serde_json::Value::Object(m) => m.iter().for_each(|(k, x)| null_numbers(x, k, method_pt, out)),
        serde_json::Value::Array(a) => a.iter().for_each(|x| null_numbers(x, key, method_pt, out)),
        _ => {}
    }
}

/// What is wrong with the outputs in `dir` (written by a successful run).
fn unfinite_outputs(dir: &Path, stdout: &[u8], files: &BTreeSet<(PathBuf, u64)>) -> Vec<String> {
    let mut bad = Vec::new();
    for (p, _) in files {
        let path = dir.join(p);
        let name = p.display().to_string();
        if name.ends_with(".json") && name != "scene.json" {
            match serde_json::from_slice::<serde_json::Value>(&std::fs::read(&path).unwrap()) {
                Ok(v) => {
                    let pt = v["run"]["method"] == "pt";
                    let mut nulls = Vec::new();
                    null_numbers(&v, "", pt, &mut nulls);
                    if !nulls.is_empty() {
                        bad.push(format!("{name}: null {nulls:?}"));
                    }
                }
                Err(e) => bad.push(format!("{name}: not JSON: {e}")),
            }
        }
        if name.ends_with(".exr") {
            match volcache::output::read_exr(&path) {
                Ok((_, _, px)) if px.iter().flatten().all(|c| c.is_finite()) => {}
                Ok(_) => bad.push(format!("{name}: non-finite pixels")),
                Err(e) => bad.push(format!("{name}: {e}")),
            }
        }
        if name.contains(".tmp") {
            bad.push(format!("{name}: a temporary file was left"));
        }
    }
    if !stdout.is_empty() {
        match serde_json::from_slice::<serde_json::Value>(stdout) {
            Ok(v) => {
                let mut nulls = Vec::new();
                null_numbers(&v, "", false, &mut nulls);
                if !nulls.is_empty() {
                    bad.push(format!("stdout: null {nulls:?}"));
                }
            }
            Err(e) => bad.push(format!("stdout: not JSON: {e}")),
        }
    }
    bad
}

#[test]
fn fuzz_the_command_line() {
    let corpus2 = fuzz::corpus(&["flatland_scenes", "tests/corpus/2d"], ".json");
    let corpus3 = fuzz::corpus(&["scenes3d", "tests/corpus/3d"], ".json");
    let seed = fuzz::seed();
    let n = fuzz::cases(40);
    let (mut crashes, mut hangs, mut unfinite, mut unsafe_outputs, mut ok, mut refused, mut slowest) =
        (0, 0, 0, 0, 0, 0, Duration::ZERO);
    let mut examples = Vec::new();
    let (mut signalled, mut kills) = (0, 0);
    let obj = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes3d/icosphere.obj")).unwrap();
    for k in 0..n {
        let mut s = Sampler::new2(seed, 1400, k as u64);
        let three_d = s.next_f64() < 0.4;
        // Mostly valid scenes (shipped ones, one edit at most), so runs get far.
        let corpus = if three_d { &corpus3 } else { &corpus2 };
        let (name, text) = if s.next_f64() < 0.7 {
            corpus[s.next_index(corpus.len())].clone()
        } else {
            fuzz::case(corpus, seed, corpus.len() + s.next_index(1 << 20))
        };
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scene.json"), &text).unwrap();
        std::fs::write(dir.path().join("icosphere.obj"), &obj).unwrap();
        let (args, outputs) = command(&mut s, three_d);
        let before = snapshot(dir.path());
        // Sometimes a signal mid-run (or mid-write): Ctrl-C, a kill, a terminate.
        let signal = match s.next_index(20) {
            0 | 1 => Some(libc::SIGINT),
            2 => Some(libc::SIGKILL),
            3 => Some(libc::SIGTERM),
            _ => None,
        }
        .map(|sig| (sig, Duration::from_millis(s.next_index(400) as u64)));
        let (mut out, hung, took) = run_once(dir.path(), &args, signal);
        slowest = slowest.max(took);
        let mut what = format!("case {k} (seed {seed}, {name}): volcache {}", args.join(" "));
        let killed = out.status.signal().is_some() && signal.is_some_and(|(sig, _)| sig != libc::SIGINT);
        signalled += signal.is_some() as usize;
        kills += killed as usize;
        if killed {
            // A killed run may leave its temporary files: the next run into the same
            // folders must remove them (and must itself be sound).
            what = format!("{what} (killed, then run again)");
            let (again, hung_again, took) = run_once(dir.path(), &args, None);
            slowest = slowest.max(took);
            if hung_again {
                hangs += 1;
            }
            out = again;
        }
        let after = snapshot(dir.path());
        let mut problems = Vec::new();
        if hung {
            hangs += 1;
            problems.push("hung".to_string());
        }
        let mixed = mixed_sets(dir.path(), &after);
        if !mixed.is_empty() {
            unsafe_outputs += 1;
            problems.extend(mixed);
        }
        match out.status.code() {
            Some(0) => {
                ok += 1;
                let bad = unfinite_outputs(dir.path(), &out.stdout, &after);
                if !bad.is_empty() {
                    unfinite += 1;
                    problems.extend(bad);
                }
            }
            Some(2) | Some(130) => {
                refused += 1;
                if std::env::var_os("VOLCACHE_FUZZ_VERBOSE").is_some() {
                    let err = String::from_utf8_lossy(&out.stderr);
                    eprintln!("refused: {}", err.lines().next().unwrap_or_default());
                }
            }
            _ if hung => {}
            // The signal we sent ended it (SIGINT has a handler: it exits 130).
            None if signal.is_some() && !killed => {}
            code => {
                crashes += 1;
                problems.push(format!("exit {code:?}: {}", String::from_utf8_lossy(&out.stderr)));
            }
        }
        // Safety: the scene and mesh untouched; new or changed files only under
        // the outputs the command was given.
        let changed: Vec<&PathBuf> = after.difference(&before).map(|(p, _)| p).collect();
        // (`caches --out .` writes its fixed file names beside the scene.)
        let caches_here = ["field.png", "field.exr", "error.png", "records.png", "summary.json"];
        let allowed = |p: &Path| {
            outputs
                .iter()
                .any(|&o| p.starts_with(o) || (o == "." && caches_here.iter().any(|f| p == Path::new(f))))
        };
        let stray: Vec<String> = changed
            .iter()
            .filter(|p| !allowed(p) || p.as_os_str() == "scene.json" || p.as_os_str() == "icosphere.obj")
            .map(|p| p.display().to_string())
            .collect();
        if !stray.is_empty() {
            unsafe_outputs += 1;
            problems.push(format!("wrote outside its outputs or over its inputs: {stray:?}"));
        }
        if !problems.is_empty() && examples.len() < 8 {
            examples.push(format!("{what}: {}", problems.join("; ")));
        }
    }
    eprintln!(
        "fuzz command line: {n} runs ({ok} succeeded, {refused} refused or interrupted; {signalled} signalled, \
         {kills} killed and run again), {crashes} crashes, {hangs} hangs, {unfinite} with non-finite outputs, \
         {unsafe_outputs} with unsafe outputs; slowest {slowest:?}"
    );
    assert!(
        crashes + hangs + unfinite + unsafe_outputs == 0,
        "{}",
        examples.join("\n")
    );
}
