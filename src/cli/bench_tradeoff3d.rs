//! `volcache bench tradeoff3d`: time against error in 3D. Both cache methods are
//! swept over target record counts (ε searched with memoised light fields; each
//! run's time is its placement — checks plus the capture time of the records it
//! uses — plus its reconstruction) — or ours over budgets (`--budgets`, each one
//! placement at its ε, directions and camera samples, placed over one camera
//! sample in eight) and jarosz08 at ours' counts with the same directions and
//! camera samples, placed alike — and path tracing over samples per pixel; errors
//! of the image and of its medium part against one converged reference. Reports
//! rays/s, records/s, the speedup of ours over Jarosz 2008 at equal error and each
//! method's time to 3%, 1% and 0.3% relative RMSE ([`volcache::study::targets`]).

use super::common::{ProgressUi, check_range, wrote};
use super::render3d_cache::Cache3dArgs;
use super::setup3d::{CachePoint, Setup3dArgs, run_cache, setup3d};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::core::metric::CacheMethod;
use volcache::figure::axis::Axis;
use volcache::figure::gradient_figure::{AWARE_PURPLE, REFERENCE_BLUE, UNAWARE_ORANGE};
use volcache::figure::plot::{LineStyle, Plot, Series, draw_plot_into};
use volcache::output::{write_json, write_png};
use volcache::pipeline::budget::{MAX_BUDGET, MIN_BUDGET};
use volcache::pipeline::placement::CountError;
use volcache::study::reference3d::ReferenceInfo3d;
use volcache::study::runs3d::{Run3d, curve, pt_run};
use volcache::study::seeds::pt_seed;
use volcache::study::speedup::{Speedup, speedups};
use volcache::study::targets::{TargetRow, rows_3d, table_text};
use volcache::volume::cached::{RecordMemo, budget_settings};
use volcache::volume::render::RenderParams;

#[derive(Args, Debug)]
pub struct Tradeoff3dArgs {
    #[command(flatten)]
    pub setup: Setup3dArgs,
    /// Target record counts for the cache methods.
    #[arg(long, value_delimiter = ',', default_values_t = [50usize, 100, 200, 400, 800])]
    pub counts: Vec<usize>,
    /// Sweep ours over these budgets (`render3d --budget`) instead of record
    /// counts: each point one placement at the budget's ε, directions and camera
    /// samples (placed over one in eight unless --place-spp), no search; jarosz08
    /// at ours' record count with the same directions and camera samples (the
    /// equal-count protocol).
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["counts", "eps", "caches", "rays", "spp"])]
    pub budgets: Option<Vec<f64>>,
    /// Samples per pixel for path tracing.
    #[arg(long, value_delimiter = ',', default_values_t = [4u32, 16, 64, 256])]
    pub spps: Vec<u32>,
    #[command(flatten)]
    pub cache: Cache3dArgs,
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    params: &'a RenderParams,
    /// Directions per record of a count sweep (a budget sweep's runs say theirs).
    #[serde(skip_serializing_if = "Option::is_none")]
    rays_per_cache: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    budgets: Option<&'a [f64]>,
    steps: usize,
    march_step: Option<f64>,
    surface_paths: u32,
    threads: usize,
    reference: &'a ReferenceInfo3d,
    runs: &'a [Run3d],
    speedups: &'a [Speedup],
    /// Each method's time to 3%, 1% and 0.3% relative RMSE, and the ratios to ours.
    targets: &'a [TargetRow],
}

pub fn run(a: Tradeoff3dArgs) -> anyhow::Result<ExitCode> {
    let setup = setup3d(&a.setup, a.quiet)?;
    let (scene, stem, image) = (&setup.scene, &setup.stem, &setup.image);
    if let Some(budgets) = &a.budgets {
        anyhow::ensure!(!budgets.is_empty(), "--budgets needs at least one budget");
        for &b in budgets {
            check_range("--budgets", b, (MIN_BUDGET, MAX_BUDGET))?;
        }
    }
    let mut runs: Vec<Run3d> = Vec::new();
    for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        // One memo across the counts: each run is charged its own records' captures.
        let mut memo = RecordMemo::new();
        // The sweep's points, with their labels and budgets.
        let points: Vec<(String, CachePoint, Option<f64>)> = match &a.budgets {
            None => a
                .counts
                .iter()
                .map(|&k| {
                    let point = CachePoint {
                        cache: a.cache.clone(),
                        image: image.clone(),
                        target: Some(k),
                    };
                    (format!("{k:>5}"), point, None)
                })
                .collect(),
            Some(budgets) => budgets
                .iter()
                .filter_map(|&b| {
                    let s = budget_settings(scene, b);
                    // Ours at the budget's ε; Jarosz 2008 (whose ε means something
                    // else) at ours' count.
                    let (eps, target) = match method {
                        CacheMethod::Ours => (Some(s.eps), None),
                        CacheMethod::Jarosz08 => {
                            let ours = runs.iter().find(|r| r.method == "ours" && r.budget == Some(b))?;
                            (None, Some(ours.records))
                        }
                    };
                    let label = match target {
                        Some(k) => format!("budget {b} (at {k} records)"),
                        None => format!("budget {b}"),
                    };
                    // Both methods with the budget's straight-light samples, placed
                    // camera samples (a search probe walks only those) and split.
                    let mut cache = Cache3dArgs {
                        eps,
                        rays: s.rays,
                        ..a.cache.clone()
                    };
                    cache.budget_defaults(&s);
                    let point = CachePoint {
                        cache,
                        image: RenderParams {
                            spp: s.spp,
                            ..image.clone()
                        },
                        target,
                    };
                    Some((label, point, Some(b)))
                })
                .collect(),
        };
        for (label, point, budget) in points {
            // Each budget's records differ in directions: their own memo.
            if budget.is_some() {
                memo = RecordMemo::new();
            }
            let bar = format!("{stem} {method:?} {label}");
            let mut r = match run_cache(&setup, method, &point, &mut memo, &bar, a.quiet) {
                Ok(r) => r,
                // A count out of reach of this method is left out of its curve.
                Err(e) if matches!(e.downcast_ref(), Some(CountError::Unreachable { .. })) => {
                    eprintln!("{method:?} {label}: skipped: {e}");
                    continue;
                }
                Err(e) => return Err(e),
            };
            r.budget = budget;
            eprintln!(
                "{:>8} {label}: {} records, {} spp, {:.2} s ({:.2} placement), RMSE {:.4e}, medium {:.4e}",
                r.method, r.records, r.spp, r.seconds, r.placement_seconds, r.errors.rmse, r.medium_errors.rmse
            );
            runs.push(r);
        }
    }
    for &spp in &a.spps {
        let p = RenderParams {
            spp,
            seed: pt_seed(a.setup.seed),
            ..image.clone()
        };
        let ui = ProgressUi::new(&format!("{stem} pt {spp} spp"), !a.quiet);
        let r = pt_run(scene, &p, &setup.reference, &ui.progress);
        ui.finish();
        let r = r?;
        eprintln!(
            "{:>8} {spp:>5} spp: {:.2} s, RMSE {:.4e}, medium {:.4e}",
            r.method, r.seconds, r.errors.rmse, r.medium_errors.rmse
        );
        runs.push(r);
    }
    let speedups = speedups(&runs);
    for s in &speedups {
        eprintln!(
            "equal {} error {:.4e}: ours {:.2} s, jarosz08 {:.2} s: speedup {}{:.2}×",
            s.of,
            s.error,
            s.seconds_ours,
            s.seconds_jarosz08,
            if s.lower_bound { "≥ " } else { "" },
            s.speedup
        );
    }
    let targets = rows_3d(&runs, &setup.ref_info);
    eprint!("{}", table_text(&targets));
    let report = Report {
        scene: &scene.source,
        params: image,
        rays_per_cache: a.budgets.is_none().then_some(a.cache.rays),
        budgets: a.budgets.as_deref(),
        steps: a.cache.steps,
        march_step: a.cache.march_step,
        surface_paths: a.cache.surface_paths,
        threads: rayon::current_num_threads(),
        reference: &setup.ref_info,
        runs: &runs,
        speedups: &speedups,
        targets: &targets,
    };
    let json = a.out.join(format!("tradeoff3d_{stem}.json"));
    wrote(&json, write_json(&json, &report))?;
    let png = a.out.join(format!("tradeoff3d_{stem}.png"));
    wrote(&png, write_png(&png, &tradeoff_plot(stem, &runs)))?;
    Ok(ExitCode::SUCCESS)
}

fn tradeoff_plot(stem: &str, runs: &[Run3d]) -> tiny_skia::Pixmap {
    let mut pix = tiny_skia::Pixmap::new(1920, 480).expect("figure size");
    pix.fill(tiny_skia::Color::WHITE);
    let styled = |label: &str, color, pts| Series::new(label, color, pts).with_style(LineStyle::LineAndMarkers);
    let methods = [
        ("ours", "ours (aware, Hessian)", AWARE_PURPLE),
        ("jarosz08", "Jarosz 2008 (unaware)", UNAWARE_ORANGE),
        ("pt", "path tracing", REFERENCE_BLUE),
    ];
    let plot = |title: String, x: Axis, medium: bool, by_time: bool| {
        let mut p = Plot::new(x, Axis::log10(if medium { "RMSE, medium part" } else { "RMSE, image" }));
        p.title = Some(title);
        p.series = methods
            .iter()
            .filter(|m| by_time || m.0 != "pt")
            .map(|&(m, label, color)| {
                let x = |r: &Run3d| if by_time { r.seconds } else { r.records as f64 };
                styled(label, color, curve(runs, m, x, medium))
            })
            .collect();
        p.legend = true;
        p
    };
    let panels = [
        plot(
            format!("{stem}: image error vs time"),
            Axis::log10("time (s)"),
            false,
            true,
        ),
        plot(
            format!("{stem}: medium-part error vs time"),
            Axis::log10("time (s)"),
            true,
            true,
        ),
        plot(
            format!("{stem}: medium-part error vs records"),
            Axis::log10("records"),
            true,
            false,
        ),
    ];
    for (k, p) in panels.iter().enumerate() {
        draw_plot_into(&mut pix, (640.0 * k as f32, 0.0, 640.0, 480.0), p);
    }
    pix
}
