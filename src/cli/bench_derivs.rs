//! `volcache bench derivatives`: the cost of one cache point — plain value, unaware
//! (Jarosz et al. 2008) and aware (ours) — for several light-field sizes N.
//!
//! Every method starts from the same light field ([`capture`]: N rays, their
//! recursive hit and medium estimates), which is where the rays and nearly all the
//! time go; the methods differ only in what they do with it afterwards:
//! - plain: [`derivatives::plain_estimate`] (the value alone);
//! - unaware: [`derivatives::unaware`] (value and gradient);
//! - aware: [`proxy::build`] then [`derivatives::aware`] (value, gradient, Hessian).
//!
//! Per point and N the capture runs once (parallel over rays, all threads) and each
//! evaluation (one thread) is repeated until it has run for at least `--min-eval-ms`,
//! its time being the mean per call. Reported per method and N: medians over the
//! points of the rays traced, the capture time, the evaluation time and their sum.
//! Timings are wall-clock on a possibly shared machine: read them as orders of
//! magnitude and ratios.

use super::common::{load_scene, scene_stem};
use clap::Args;
use glam::DVec2;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use volcache::output::write_json;
use volcache::pipeline::derivatives::{self, AwareSettings};
use volcache::pipeline::path::Settings;
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy;
use volcache::pipeline::world::World;
use volcache::progress::Progress;

#[derive(Args, Debug)]
pub struct DerivBench {
    /// Scene JSON (default: the embedded occluder scene).
    pub scene: Option<PathBuf>,
    #[arg(long, default_value = "results/bench_derivatives.json")]
    pub out: PathBuf,
    /// Light-field sizes N (directions per cache point), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1024usize, 4096, 16384])]
    pub sizes: Vec<usize>,
    /// How many of the fixed medium points to use (at most 8).
    #[arg(long, default_value_t = 5)]
    pub points: usize,
    /// Ray-marched medium samples per ray.
    #[arg(long, default_value_t = 24)]
    pub steps: usize,
    /// Repeat each evaluation for at least this long (milliseconds).
    #[arg(long, default_value_t = 50.0)]
    pub min_eval_ms: f64,
    #[arg(long)]
    pub seed: Option<u64>,
}

/// Fixed points as fractions of the domain: the centre, points in and beside the
/// occluder's shadow in `occluder.json`, near the walls and corners elsewhere.
const POINTS: [[f64; 2]; 8] = [
    [0.55, 0.5],
    [0.5, 0.72],
    [0.3, 0.45],
    [0.75, 0.62],
    [0.45, 0.9],
    [0.2, 0.2],
    [0.85, 0.35],
    [0.6, 0.15],
];

const METHODS: [&str; 3] = ["plain", "unaware", "aware"];

#[derive(Serialize, Clone)]
struct Sample {
    point: [f64; 2],
    rays_per_light_field: usize,
    rays_traced: u64,
    capture_seconds: f64,
    /// Per method (plain, unaware, aware): evaluation seconds per call.
    eval_seconds: [f64; 3],
    /// Of the aware evaluation: building the proxy.
    proxy_build_seconds: f64,
    elements: usize,
}

#[derive(Serialize)]
struct Row {
    rays_per_light_field: usize,
    method: &'static str,
    /// Medians over the points.
    rays_traced: f64,
    capture_seconds: f64,
    eval_seconds: f64,
    total_seconds: f64,
    /// Evaluation cost relative to the plain value's.
    eval_vs_plain: f64,
    /// Total cost relative to the plain value's.
    total_vs_plain: f64,
}

#[derive(Serialize)]
struct Report<'a> {
    volcache_version: &'a str,
    scene: &'a str,
    threads: usize,
    steps: usize,
    seed: u64,
    points: Vec<[f64; 2]>,
    note: &'a str,
    results: Vec<Row>,
    samples: Vec<Sample>,
}

/// Mean seconds per call of `f`, repeated for at least `min_s` (and at least once).
fn time_eval<T>(min_s: f64, mut f: impl FnMut() -> T) -> f64 {
    let start = Instant::now();
    let mut n = 0u32;
    loop {
        std::hint::black_box(f());
        n += 1;
        let t = start.elapsed().as_secs_f64();
        if t >= min_s {
            return t / n as f64;
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

pub fn run(b: DerivBench) -> anyhow::Result<ExitCode> {
    let scene = load_scene(b.scene.as_deref())?;
    anyhow::ensure!(!b.sizes.is_empty(), "--sizes needs at least one N");
    anyhow::ensure!(b.sizes.iter().all(|&n| n >= 3), "every N in --sizes must be at least 3");
    anyhow::ensure!(b.steps >= 1, "--steps must be at least 1");
    anyhow::ensure!(
        b.min_eval_ms >= 0.0 && b.min_eval_ms.is_finite(),
        "--min-eval-ms must be ≥ 0"
    );
    let r = &scene.desc.render;
    let seed = b.seed.unwrap_or(r.seed);
    let omega_o = DVec2::from_angle(r.omega_o_deg.to_radians());
    let size = scene.domain_max - scene.domain_min;
    let points: Vec<DVec2> = POINTS
        .iter()
        .map(|f| scene.domain_min + size * DVec2::from_array(*f))
        .filter(|&p| scene.medium_at(p).is_some())
        .take(b.points.max(1))
        .collect();
    anyhow::ensure!(
        !points.is_empty(),
        "none of the benchmark's fixed points lies in the scene's medium"
    );
    let aw = AwareSettings::default();
    let min_s = b.min_eval_ms / 1e3;
    let mut samples = Vec::new();
    for &n in &b.sizes {
        let ps = ProbeSettings {
            rays: n,
            steps: b.steps,
            settings: Settings {
                max_depth: r.max_depth,
                ..Settings::default()
            },
            ..ProbeSettings::default_for::<volcache::core::space::D2>()
        };
        for (k, &x) in points.iter().enumerate() {
            let t = Instant::now();
            let lf = capture(
                &scene,
                x,
                Outgoing::Direction(omega_o),
                &ps,
                seed,
                k as u64,
                &Progress::new(),
            )
            .map_err(|_| anyhow::Error::from(volcache::progress::Cancelled))?;
            let capture_seconds = t.elapsed().as_secs_f64();
            let plain = time_eval(min_s, || derivatives::plain_estimate(&lf));
            let unaware = time_eval(min_s, || derivatives::unaware(&lf));
            let build = time_eval(min_s, || proxy::build(&lf, aw.rule));
            let proxy = proxy::build(&lf, aw.rule);
            let aware_only = time_eval(min_s, || derivatives::aware(&lf, &proxy, &aw));
            samples.push(Sample {
                point: x.to_array(),
                rays_per_light_field: n,
                rays_traced: lf.cost_rays,
                capture_seconds,
                eval_seconds: [plain, unaware, build + aware_only],
                proxy_build_seconds: build,
                elements: proxy.count,
            });
        }
    }

    let mut rows = Vec::new();
    for &n in &b.sizes {
        let of_n: Vec<&Sample> = samples.iter().filter(|s| s.rays_per_light_field == n).collect();
        let med = |f: &dyn Fn(&Sample) -> f64| median(of_n.iter().map(|s| f(s)).collect());
        let plain_eval = med(&|s| s.eval_seconds[0]);
        let plain_total = med(&|s| s.capture_seconds + s.eval_seconds[0]);
        for (m, method) in METHODS.iter().enumerate() {
            let eval = med(&|s| s.eval_seconds[m]);
            let total = med(&|s| s.capture_seconds + s.eval_seconds[m]);
            rows.push(Row {
                rays_per_light_field: n,
                method,
                rays_traced: med(&|s| s.rays_traced as f64),
                capture_seconds: med(&|s| s.capture_seconds),
                eval_seconds: eval,
                total_seconds: total,
                eval_vs_plain: eval / plain_eval,
                total_vs_plain: total / plain_total,
            });
        }
    }

    let stem = scene_stem(b.scene.as_deref());
    println!(
        "cost of one cache point, {stem}, median over {} points, {} threads (capture parallel, evaluation on one thread)",
        points.len(),
        rayon::current_num_threads()
    );
    println!(
        "{:>7} {:>8} {:>12} {:>11} {:>11} {:>11} {:>9}",
        "N", "method", "rays", "capture s", "eval s", "total s", "eval/plain"
    );
    for row in &rows {
        println!(
            "{:>7} {:>8} {:>12.0} {:>11.4} {:>11.2e} {:>11.4} {:>9.1}",
            row.rays_per_light_field,
            row.method,
            row.rays_traced,
            row.capture_seconds,
            row.eval_seconds,
            row.total_seconds,
            row.eval_vs_plain
        );
    }
    let report = Report {
        volcache_version: env!("CARGO_PKG_VERSION"),
        scene: &scene.source,
        threads: rayon::current_num_threads(),
        steps: b.steps,
        seed,
        points: points.iter().map(|p| p.to_array()).collect(),
        note: "all methods share the light-field capture (rays_traced, capture_seconds; parallel over rays); \
               eval_seconds is the single-threaded work after it: plain = plain_estimate, unaware = unaware, \
               aware = proxy::build + aware. Medians over the points; wall-clock on a possibly shared machine.",
        results: rows,
        samples,
    };
    write_json(&b.out, &report)?;
    eprintln!("wrote {}", b.out.display());
    Ok(ExitCode::SUCCESS)
}
