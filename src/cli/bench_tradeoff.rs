//! `volcache bench tradeoff`: what users trade, time against error. Both cache
//! methods are swept over target record counts (ε found by bisection, then the
//! placement re-run from scratch so its time is honest) — or ours over budgets
//! (`--budgets`) and jarosz08 at ours' counts — and path tracing over samples per
//! pixel; error against one reference field (cached on disk). Writes the curves and
//! each method's time to 3%, 1% and 0.3% relative RMSE ([`volcache::study::targets`]).

use super::caches::{CacheArgs, check_cache_args, field_params, reference, run_method};
use super::common::{load_scene, scene_stem, wrote};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::figure::axis::Axis;
use volcache::figure::gradient_figure::{AWARE_PURPLE, REFERENCE_BLUE, UNAWARE_ORANGE};
use volcache::figure::plot::{LineStyle, Plot, Series, draw_plot_into};
use volcache::flatland::field::FieldParams;
use volcache::output::{write_json, write_png};
use volcache::pipeline::budget::schedule;
use volcache::pipeline::placement::CountError;
use volcache::progress::Progress;
use volcache::study::field_runs::{FieldMethod, MethodRun};
use volcache::study::reference2d::ReferenceInfo;
use volcache::study::targets::{TargetRow, table_text, target_rows};

#[derive(Args, Debug)]
pub struct TradeoffArgs {
    /// Scene JSON (default: the embedded occluder scene).
    pub scene: Option<PathBuf>,
    /// Target record counts for the cache methods.
    #[arg(long, value_delimiter = ',', default_values_t = [50usize, 100, 200, 400, 800])]
    pub counts: Vec<usize>,
    /// Sweep ours over these budgets (`--budget`, `pipeline::budget`) instead of
    /// record counts: each point is one placement at the budget's ε and rays, no
    /// search; jarosz08 is run at ours' record count with the same rays.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["counts", "eps", "caches", "rays"])]
    pub budgets: Option<Vec<f64>>,
    /// Samples per pixel for path tracing.
    #[arg(long, value_delimiter = ',', default_values_t = [1u32, 4, 16, 64, 256])]
    pub spps: Vec<u32>,
    #[command(flatten)]
    pub cache: CacheArgs,
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
}

#[derive(Serialize)]
struct Point {
    method: FieldMethod,
    target: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    budget: Option<f64>,
    /// Directions per record (cache methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    rays_per_record: Option<usize>,
    /// The records' edge reach (`--edge-reach`, or a budget's).
    #[serde(skip_serializing_if = "Option::is_none")]
    edge_reach: Option<f64>,
    /// Directions per pixel of the point lights' once-scattered light, where it
    /// is not cached (`--point-scatter`, or a budget's).
    #[serde(skip_serializing_if = "Option::is_none")]
    point_scatter: Option<u32>,
    spp: Option<u32>,
    #[serde(flatten)]
    run: MethodRun,
}

#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    params: &'a FieldParams,
    /// Directions per record of a count sweep (a budget sweep's points say theirs).
    #[serde(skip_serializing_if = "Option::is_none")]
    rays_per_cache: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    budgets: Option<&'a [f64]>,
    per_part: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    direct_samples: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    edge_reach: Option<f64>,
    reference: &'a ReferenceInfo,
    points: &'a [Point],
    /// Each method's time to 3%, 1% and 0.3% relative RMSE, and the ratios to ours.
    targets: &'a [TargetRow],
}

pub fn run(a: TradeoffArgs) -> anyhow::Result<ExitCode> {
    let scene = load_scene(a.scene.as_deref())?;
    let stem = scene_stem(a.scene.as_deref());
    let fp = field_params(&scene, &a.cache);
    check_cache_args(&a.cache, &fp)?;
    let (reference, ref_info) = reference(&scene, &fp, &a.cache)?;
    let progress = Progress::new();
    let mut points = Vec::new();
    // The sweep's options, one set per point: a budget, or a record count (ε for k
    // records, then a fresh placement at that ε, timed).
    let sweep: Vec<CacheArgs> = match &a.budgets {
        Some(budgets) => budgets
            .iter()
            .map(|&b| CacheArgs {
                budget: Some(b),
                ..a.cache.clone()
            })
            .collect(),
        None => a
            .counts
            .iter()
            .map(|&k| CacheArgs {
                caches: Some(k),
                ..a.cache.clone()
            })
            .collect(),
    };
    for args in &sweep {
        check_cache_args(args, &fp)?;
    }
    for method in [FieldMethod::Ours, FieldMethod::Jarosz08] {
        for args in &sweep {
            let budget = args.budget;
            // Under a budget, jarosz08 (whose ε means something else) at ours' count.
            let target = match (method, budget) {
                (FieldMethod::Jarosz08, Some(b)) => {
                    let Some(ours) = points.iter().find(|p: &&Point| p.budget == Some(b)) else {
                        continue;
                    };
                    std::borrow::Cow::Owned(CacheArgs {
                        budget: None,
                        caches: Some(ours.run.records),
                        rays: schedule(b).1,
                        direct_samples: ours.run.direct_samples,
                        // The same split as ours: the two caches hold the same light.
                        point_scatter: Some(args.point_scatter_for(&scene).unwrap_or(0)),
                        near_light_paths: Some(args.near_light_paths_for(&scene).unwrap_or(0)),
                        ..a.cache.clone()
                    })
                }
                _ => std::borrow::Cow::Borrowed(args),
            };
            let k = target.caches;
            let label = match (budget, k) {
                (Some(b), Some(k)) => format!("budget {b} (at {k} records)"),
                (Some(b), None) => format!("budget {b}"),
                (None, k) => format!("{:>5}", k.unwrap_or(0)),
            };
            let run = match run_method(&scene, &fp, method, 0, &target, &reference, &progress) {
                Ok(run) => run,
                // A count out of reach of this method is left out of its curve.
                Err(e @ CountError::Unreachable { .. }) => {
                    eprintln!("{method:?} {label}: skipped: {e}");
                    continue;
                }
                Err(e) => return Err(e.into()),
            };
            eprintln!(
                "{method:?} {label}: {} records, {:.2} s, RMSE {:.4e}",
                run.records,
                run.seconds_total,
                run.errors.unwrap_or_default().rmse
            );
            points.push(Point {
                method,
                target: k,
                budget,
                rays_per_record: Some(target.rays_per_record()),
                edge_reach: target.edge_reach_for(&scene),
                point_scatter: target.point_scatter_for(&scene),
                spp: None,
                run,
            });
        }
    }
    for &spp in &a.spps {
        let run = run_method(&scene, &fp, FieldMethod::Pt, spp, &a.cache, &reference, &progress)?;
        eprintln!(
            "Pt {spp:>5} spp: {:.2} s, RMSE {:.4e}",
            run.seconds_total,
            run.errors.unwrap_or_default().rmse
        );
        points.push(Point {
            method: FieldMethod::Pt,
            target: None,
            budget: None,
            rays_per_record: None,
            edge_reach: None,
            point_scatter: None,
            spp: Some(spp),
            run,
        });
    }
    let targets = field_targets(&points, &ref_info);
    eprint!("{}", table_text(&targets));
    let report = Report {
        scene: &scene.source,
        params: &fp,
        rays_per_cache: a.budgets.is_none().then_some(a.cache.rays),
        budgets: a.budgets.as_deref(),
        per_part: a.cache.per_part,
        direct_samples: a.cache.direct_samples,
        edge_reach: a.cache.edge_reach,
        reference: &ref_info,
        points: &points,
        targets: &targets,
    };
    let json = a.out.join(format!("tradeoff_{stem}.json"));
    wrote(&json, write_json(&json, &report))?;
    let png = a.out.join(format!("tradeoff_{stem}.png"));
    wrote(&png, write_png(&png, &tradeoff_plot(&stem, &points)))?;
    Ok(ExitCode::SUCCESS)
}

/// The time-to-error table of the field (the reference's noise: its RMS standard error).
fn field_targets(points: &[Point], ref_info: &ReferenceInfo) -> Vec<TargetRow> {
    let Some(mean) = points.iter().find_map(|p| p.run.errors.map(|e| e.mean_reference)) else {
        return Vec::new();
    };
    let curves: Vec<(&str, Vec<(f64, f64)>)> = [
        ("ours", FieldMethod::Ours),
        ("jarosz08", FieldMethod::Jarosz08),
        ("pt", FieldMethod::Pt),
    ]
    .into_iter()
    .map(|(name, m)| (name, series(points, m, |p| p.run.seconds_total)))
    .filter(|c| !c.1.is_empty())
    .collect();
    target_rows("field", &curves, mean, ref_info.rms_std_error)
}

fn series(points: &[Point], method: FieldMethod, x: impl Fn(&Point) -> f64) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.method == method)
        .map(|p| (x(p), p.run.errors.map_or(f64::NAN, |e| e.rmse)))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

fn tradeoff_plot(stem: &str, points: &[Point]) -> tiny_skia::Pixmap {
    let mut pix = tiny_skia::Pixmap::new(1280, 480).expect("figure size");
    pix.fill(tiny_skia::Color::WHITE);
    let styled = |label: &str, color, pts| Series::new(label, color, pts).with_style(LineStyle::LineAndMarkers);
    let mut by_time = Plot::new(Axis::log10("time (s)"), Axis::log10("RMSE (luminance)"));
    by_time.title = Some(format!("{stem}: error vs time"));
    by_time.series = vec![
        styled(
            "ours (aware, Hessian)",
            AWARE_PURPLE,
            series(points, FieldMethod::Ours, |p| p.run.seconds_total),
        ),
        styled(
            "Jarosz 2008 (unaware)",
            UNAWARE_ORANGE,
            series(points, FieldMethod::Jarosz08, |p| p.run.seconds_total),
        ),
        styled(
            "path tracing",
            REFERENCE_BLUE,
            series(points, FieldMethod::Pt, |p| p.run.seconds_total),
        ),
    ];
    by_time.legend = true;
    let mut by_count = Plot::new(Axis::log10("records"), Axis::log10("RMSE (luminance)"));
    by_count.title = Some(format!("{stem}: error vs cache count"));
    by_count.series = vec![
        styled(
            "ours (aware, Hessian)",
            AWARE_PURPLE,
            series(points, FieldMethod::Ours, |p| p.run.records as f64),
        ),
        styled(
            "Jarosz 2008 (unaware)",
            UNAWARE_ORANGE,
            series(points, FieldMethod::Jarosz08, |p| p.run.records as f64),
        ),
    ];
    by_count.legend = true;
    draw_plot_into(&mut pix, (0.0, 0.0, 640.0, 480.0), &by_time);
    draw_plot_into(&mut pix, (640.0, 0.0, 640.0, 480.0), &by_count);
    pix
}
