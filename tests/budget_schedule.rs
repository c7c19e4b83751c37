//! One budget for the 2D cache (`pipeline::budget`): four times the budget gives a
//! lower error over seeds, at about four times the cost in rays, on scenes of this
//! test's own (two bars beside a point light in fog; the same bars beside an
//! emitting segment, whose straight light the budget samples per pixel), none of
//! the shipped scenes.

mod common;

use volcache::core::metric::CacheMethod;
use volcache::flatland::cached_field::budget_settings;
use volcache::flatland::field::{Field, FieldParams, field_errors, render_field};
use volcache::flatland::scene::Scene;
use volcache::pipeline::budget::{flatland_near_light_paths, schedule};
use volcache::progress::Progress;
use volcache::study::field_runs::{cache_run, cache_settings};

const TWO_BARS: &str = r#"{
  "domain": {"min": [-1, -1], "max": [1, 1]},
  "segments": [
    {"name": "near", "a": [-0.5, 0.15], "b": [0.2, 0.3], "reflectance": 0.6},
    {"name": "far", "a": [0.1, -0.35], "b": [0.75, -0.55], "reflectance": 0.3}
  ],
  "lights": [{"type": "point", "position": [-0.2, 0.6], "intensity": 2.0}],
  "medium": {"sigma_a": 0.3, "sigma_s": 1.2, "g": 0.4, "region": "everywhere"},
  "render": {"resolution": [32, 32], "spp": 16, "seed": 1}
}"#;

/// The two bars lit by a tilted emitting segment above them instead of the point.
/// Per step of its budget, at least this many seeds of 4 must fall (a 32×32 field
/// has few records: a step moves them, and one seed may land higher).
const LAMP_AND_BARS: &str = r#"{
  "domain": {"min": [-1, -1], "max": [1, 1]},
  "segments": [
    {"name": "lamp", "a": [-0.45, 0.62], "b": [0.05, 0.72], "emission": 3.0, "two_sided": true},
    {"name": "near", "a": [-0.5, 0.15], "b": [0.2, 0.3], "reflectance": 0.6},
    {"name": "far", "a": [0.1, -0.35], "b": [0.75, -0.55], "reflectance": 0.3}
  ],
  "medium": {"sigma_a": 0.3, "sigma_s": 1.2, "g": 0.4, "region": "everywhere"},
  "render": {"resolution": [32, 32], "spp": 16, "seed": 1}
}"#;
const SEEDS_THAT_FALL: usize = 3;

/// One field of ours: its RMSE, the placement's rays and all its rays.
#[derive(Debug)]
struct Run {
    rmse: f64,
    placement_rays: u64,
    rays: u64,
}

/// Ours at budget `b` and seed `seed` (`budget_settings`: ε, directions and edge
/// reach), with the budget's straight-light samples or, with `cached`, none (the
/// records hold the straight light).
fn run(scene: &Scene, fp: &FieldParams, reference: &Field, b: f64, cached: bool, seed: u64) -> Run {
    let s = budget_settings(scene, b);
    let fp = FieldParams { seed, ..fp.clone() };
    let mut cs = cache_settings(CacheMethod::Ours, s.eps, &fp, s.rays, 16);
    cs.edge_reach = Some(s.edge_reach);
    cs.point_scatter = s.point_scatter;
    cs.near_light_paths = s.near_light_paths;
    if !cached {
        (cs.direct_samples, cs.direct_share) = s.direct.unzip();
    }
    let r = cache_run(scene, &fp, &cs, None, reference, &Progress::new()).unwrap();
    if let Some(n) = r.direct_samples {
        println!("  budget {b} seed {seed}: {n} straight-light samples per pixel");
    }
    Run {
        rmse: r.errors.unwrap().rmse,
        placement_rays: r.rays_placement,
        rays: r.rays_placement + r.rays_reconstruction,
    }
}

/// A scene, its field parameters, a 32,768-spp reference and that reference's
/// squared noise.
fn with_reference(json: &str) -> (Scene, FieldParams, Field, f64) {
    let scene = Scene::from_json(json, "<test scene>").unwrap_or_else(|e| panic!("{e}"));
    let (fp, reference, noise) = common::reference_2d(&scene, 32768);
    (scene, fp, reference, noise)
}

/// The mean of the squared errors `rmse`, the reference's noise subtracted.
fn mean_squared_error(rmse: impl Iterator<Item = f64>, noise: f64) -> f64 {
    let (sum, n) = rmse.fold((0.0, 0), |(s, n), e| (s + e * e - noise, n + 1));
    sum / n as f64
}

/// The rays of one path-traced sample per pixel of `fp`.
fn rays_per_spp(scene: &Scene, fp: &FieldParams) -> u64 {
    render_field(scene, &FieldParams { spp: 1, ..fp.clone() }, &Progress::new())
        .unwrap()
        .rays
}

/// The RMSE of path tracing with at least `rays` rays (seed `seed`), `per_spp`
/// rays a sample per pixel ([`rays_per_spp`]).
fn path_tracing_with(
    scene: &Scene,
    fp: &FieldParams,
    reference: &Field,
    (rays, per_spp): (u64, u64),
    seed: u64,
) -> f64 {
    let spp = (rays as f64 / per_spp as f64).ceil().max(1.0) as u32;
    let pt = render_field(
        scene,
        &FieldParams {
            spp,
            seed,
            ..fp.clone()
        },
        &Progress::new(),
    )
    .unwrap();
    assert!(pt.rays >= rays, "{} rays against {rays}", pt.rays);
    field_errors(&pt.field, reference).rmse
}

/// Budgets 1, 4 and 16 on seeds 1–4 of `json`: the mean squared error falls below
/// `bound` × the previous budget's, the RMSE of at least `seeds_that_fall` seeds
/// falls at each step and the placement's rays grow 2.5–6× per step (the model's
/// 4×). Returns the runs of each budget.
fn four_times_the_budget_lowers_the_error_of(
    (scene, fp, reference, noise): &(Scene, FieldParams, Field, f64),
    bound: f64,
    seeds_that_fall: usize,
) -> Vec<Vec<Run>> {
    let (scene, fp, reference, noise) = (scene, fp, reference, *noise);
    let budgets = [1.0, 4.0, 16.0];
    let seeds = 1..=4u64;
    let runs: Vec<Vec<Run>> = budgets
        .iter()
        .map(|&b| {
            seeds
                .clone()
                .map(|seed| run(scene, fp, reference, b, false, seed))
                .collect()
        })
        .collect();
    let mse: Vec<f64> = runs
        .iter()
        .map(|r| mean_squared_error(r.iter().map(|r| r.rmse), noise))
        .collect();
    for (b, r) in budgets.iter().zip(&runs) {
        println!("budget {b}: {r:?}");
    }
    println!("mean squared error (reference noise subtracted): {mse:?}");
    for k in 1..budgets.len() {
        let ratio = mse[k] / mse[k - 1];
        println!("budget {} / {}: mse ratio {ratio:.3}", budgets[k], budgets[k - 1]);
        assert!(
            ratio < bound,
            "budget {}: mean squared error {ratio:.3} of budget {}'s",
            budgets[k],
            budgets[k - 1]
        );
        let mut fell = 0;
        for (seed, (a, b)) in seeds.clone().zip(runs[k - 1].iter().zip(&runs[k])) {
            let rays = b.placement_rays as f64 / a.placement_rays as f64;
            println!("  seed {seed}: RMSE {:.4} -> {:.4}, rays x{rays:.2}", a.rmse, b.rmse);
            fell += usize::from(b.rmse < a.rmse);
            assert!(
                (2.5..6.0).contains(&rays),
                "seed {seed}: the rays grew {rays:.2}x for 4x the budget"
            );
        }
        assert!(
            fell >= seeds_that_fall,
            "budget {}: the RMSE of {fell} seeds of 4 fell from budget {}'s",
            budgets[k],
            budgets[k - 1]
        );
    }
    runs
}

/// Measured (32,768-spp reference, its noise subtracted): the mean squared error
/// falls to 0.20 and then 0.39 of the previous budget's (seeds 5–8: 0.23 and
/// 0.62; bound 0.9; before the budget sampled the point light's once-scattered
/// light per pixel 0.35 and 0.57, with the schedule balanced at budget 1 0.41
/// and 0.50, before the budget set the edge reach 0.59 and 0.78), every seed's
/// RMSE falls at both steps (seeds 1–8), and the placement's rays grow 3.3–4.0×
/// per step. A point light: the budget samples no straight light (it is per
/// pixel anyway), and its once-scattered light per pixel (`point_scatter`).
///
/// And the cache pays for itself: at budgets 1 and 4 its mean squared error is
/// 0.36 and 0.27 of path tracing's with at least as many rays (seeds 5–8: 0.32
/// and 0.28; bound 0.6), every seed's lower. Path tracing samples the point
/// light along its legs (`pipeline::point_leg`; the records' paths do too);
/// before the once-scattered light was per pixel, 0.35 and 0.48; before the
/// legs, 0.20 and 0.31 (the legs took more from path tracing's error than from
/// the cache's). (On the emitter's scene the two are about even at this 32×32
/// size, 0.55–0.90 at budgets 1 and 4, and path tracing is ahead at 16, 1.2:
/// not asserted.)
#[test]
fn four_times_the_budget_lowers_the_error() {
    let setup = with_reference(TWO_BARS);
    let (scene, fp, reference, noise) = &setup;
    assert_eq!(budget_settings(scene, 1.0).direct, None);
    let runs = four_times_the_budget_lowers_the_error_of(&setup, 0.9, 4);
    let per_spp = rays_per_spp(scene, fp);
    for (b, runs) in [1, 4].into_iter().zip(&runs) {
        let pt: Vec<f64> = (1..)
            .zip(runs)
            .map(|(seed, r)| path_tracing_with(scene, fp, reference, (r.rays, per_spp), seed + 100))
            .collect();
        let ratio =
            mean_squared_error(runs.iter().map(|r| r.rmse), *noise) / mean_squared_error(pt.iter().copied(), *noise);
        println!("budget {b}: mse ratio ours / path tracing at equal rays {ratio:.3} ({pt:?})");
        assert!(
            ratio < 0.6,
            "budget {b}: ours / path tracing mean squared error {ratio:.3}"
        );
        for (seed, (r, p)) in (1..).zip(runs.iter().zip(&pt)) {
            assert!(
                r.rmse < *p,
                "budget {b} seed {seed}: ours {} against path tracing {p}",
                r.rmse
            );
        }
    }
}

/// An emitting segment: the budget samples its straight light per pixel (a share
/// of the placement's rays: 136–157, 276–288 and 489–509 samples at budgets 1, 4
/// and 16 on this 32×32 field, where records are dense), and at budget 1 that
/// gives a lower error than records holding it, on every seed. Measured (the
/// reference's noise subtracted): the mean squared error falls to 0.34 and then
/// 0.45 of the previous budget's (seeds 5–8: 0.27 and 0.44; bound 0.9; with the
/// schedule balanced at budget 1 0.64 and 0.51); all 16 seed-steps fell over
/// seeds 1–8 (without the budget's edge reach one step in 4 rose on two seeds: 3
/// of 4 asked); at budget 1 sampling the straight light took the mean squared
/// error to 0.10 of the cached straight light's (seeds 5–8: 0.12; bound 0.5),
/// every seed's RMSE from 0.046–0.061 to 0.015–0.023.
#[test]
fn four_times_the_budget_lowers_the_error_with_an_emitter() {
    let setup = with_reference(LAMP_AND_BARS);
    let (scene, fp, reference, noise) = &setup;
    assert!(budget_settings(scene, 1.0).direct.is_some());
    let sampled = four_times_the_budget_lowers_the_error_of(&setup, 0.9, SEEDS_THAT_FALL).swap_remove(0);
    let cached: Vec<_> = (1..=4).map(|seed| run(scene, fp, reference, 1.0, true, seed)).collect();
    println!("budget 1, straight light cached: {cached:?}");
    let ratio = mean_squared_error(sampled.iter().map(|r| r.rmse), *noise)
        / mean_squared_error(cached.iter().map(|r| r.rmse), *noise);
    println!("mse ratio sampled / cached {ratio:.3}");
    assert!(ratio < 0.5, "sampled / cached mean squared error {ratio:.3}");
    for (seed, (c, s)) in (1..).zip(cached.iter().zip(&sampled)) {
        assert!(
            s.rmse < c.rmse,
            "seed {seed}: sampled {} against cached {}",
            s.rmse,
            c.rmse
        );
    }
}

fn volcache() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_volcache"))
}

/// `caches --budget`: the summary says the budget and the rays it chose; a budget
/// out of range, given with --eps, or for a method it was not measured for is a
/// clear error (exit 2) and writes nothing; so is a budget where it would mean
/// something else.
#[test]
fn caches_takes_a_budget() {
    let d = tempfile::tempdir().unwrap();
    let scene = d.path().join("two_bars.json");
    std::fs::write(&scene, TWO_BARS).unwrap();
    let lamp = d.path().join("lamp_and_bars.json");
    std::fs::write(&lamp, LAMP_AND_BARS).unwrap();
    let on = |scene: &std::path::Path, out: &str| {
        let mut c = volcache();
        c.arg("caches").arg(scene);
        c.args(["--res", "12x12", "--steps", "2", "--ref-spp", "4", "--quiet"]);
        c.arg("--out").arg(d.path().join(out));
        c.arg("--ref-cache").arg(d.path().join("ref"));
        c
    };
    let base = |out: &str| on(&scene, out);
    let out = base("ok").args(["--budget", "0.25"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.path().join("ok/summary.json")).unwrap()).unwrap();
    let (eps, rays) = schedule(0.25);
    assert_eq!(summary["budget"], 0.25);
    assert_eq!(summary["rays_per_cache"], rays);
    assert_eq!(summary["run"]["eps"], eps);
    // A point light: no straight-light samples (its straight light is per pixel).
    assert!(summary["direct_samples"].is_null(), "{summary}");
    // A point light in fog: its once-scattered light per pixel, the budget's
    // directions (`--point-scatter 0` caches it).
    assert_eq!(
        summary["point_scatter"],
        u64::from(
            budget_settings(&Scene::from_json(TWO_BARS, "t").unwrap(), 0.25)
                .point_scatter
                .unwrap()
        )
    );
    assert_eq!(summary["run"]["point_scatter"], summary["point_scatter"]);
    // Fog of 4.2 mean free paths across: no pixels are path traced near the lamp.
    assert!(summary["run"]["near_light"].is_null(), "{summary}");
    let out = base("cached")
        .args(["--budget", "0.25", "--point-scatter", "0", "--near-light-paths", "0"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.path().join("cached/summary.json")).unwrap()).unwrap();
    assert!(summary["point_scatter"].is_null(), "{summary}");
    assert!(summary["run"]["near_light"].is_null(), "{summary}");
    // In fog of 15 mean free paths across, the pixels within one of the lamp are
    // path traced, with the budget's paths or `--near-light-paths`' (0: none).
    let thick = d.path().join("thick.json");
    std::fs::write(&thick, TWO_BARS.replace(r#""sigma_s": 1.2"#, r#""sigma_s": 5.0"#)).unwrap();
    let near_light = |extra: &[&str], out: &str| {
        let out_dir = d.path().join(out);
        let run = on(&thick, out).args(extra).output().unwrap();
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out_dir.join("summary.json")).unwrap()).unwrap();
        s["run"]["near_light"].clone()
    };
    let budget = near_light(&["--budget", "0.25"], "thick_budget");
    assert_eq!(budget["paths"], u64::from(flatland_near_light_paths(0.25)), "{budget}");
    assert!(
        (budget["radius"].as_f64().unwrap() - 1.0 / 5.3).abs() < 1e-12,
        "{budget}"
    );
    assert!(budget["pixels"].as_u64().unwrap() > 0, "{budget}");
    assert_eq!(
        near_light(&["--eps", "0.05", "--near-light-paths", "100"], "thick_100")["paths"],
        100
    );
    assert!(near_light(&["--budget", "0.25", "--near-light-paths", "0"], "thick_none").is_null());
    // An emitting segment: the budget's samples, unless --direct-samples says.
    for (extra, samples) in [(vec![], None), (vec!["--direct-samples", "3"], Some(3))] {
        let out = on(&lamp, "lamp")
            .args(["--budget", "0.25"])
            .args(&extra)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.path().join("lamp/summary.json")).unwrap()).unwrap();
        // The budget's samples are a share of the placement's rays: at least 4.
        let n = summary["direct_samples"].as_u64().unwrap();
        assert_eq!(summary["run"]["direct_samples"], n, "{extra:?}");
        match samples {
            Some(s) => assert_eq!(n, s, "{extra:?}"),
            None => assert!(n >= 4, "{extra:?}: {n}"),
        }
    }
    // The budget's samples follow the placement's rays: the field is the same
    // whatever the thread count.
    let field_with = |threads: &str| {
        let out_dir = d.path().join(format!("threads{threads}"));
        let out = volcache()
            .args(["--threads", threads, "caches"])
            .arg(&lamp)
            .args([
                "--budget",
                "1",
                "--res",
                "12x12",
                "--steps",
                "2",
                "--ref-spp",
                "4",
                "--quiet",
            ])
            .arg("--out")
            .arg(&out_dir)
            .arg("--ref-cache")
            .arg(d.path().join("ref"))
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        volcache::output::read_exr(&out_dir.join("field.exr")).unwrap().2
    };
    assert_eq!(field_with("1"), field_with("2"));
    for (args, says) in [
        (vec!["--budget", "1e5"], "--budget must lie between"),
        (vec!["--budget", "nan"], "--budget must lie between"),
        (vec!["--budget", "2", "--eps", "0.1"], "cannot be used with"),
        (vec!["--budget", "2", "--method", "jarosz08"], "with --method jarosz08"),
    ] {
        let out = base("bad").args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    assert!(!d.path().join("bad").exists());
    // Where a budget would mean something else, it is refused too: figure compare
    // runs both caches at one count, and a budget sweep sets its own ε and rays.
    for (args, says) in [
        (
            vec!["figure", "compare", "--budget", "1"],
            "--budget schedules ours alone",
        ),
        (
            vec!["bench", "tradeoff", "--budgets", "1,4", "--rays", "64"],
            "cannot be used with",
        ),
    ] {
        let out = volcache()
            .args(&args)
            .arg(&scene)
            .arg("--out")
            .arg(d.path().join("bad"))
            .arg("--ref-cache")
            .arg(d.path().join("ref"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    assert!(!d.path().join("bad").exists());
}
