//! `volcache bench tradeoff3d`: time against error in 3D. Both cache methods are
//! swept over target record counts (ε searched with memoised light fields; each
//! run's time is its placement — checks plus the capture time of the records it
//! uses — plus its reconstruction) and path tracing over samples per pixel; errors
//! of the image and of its medium part against one converged reference. Reports
//! rays/s, records/s and the speedup of ours over Jarosz 2008 at equal error.

use super::common::{ProgressUi, wrote};
use super::render3d_cache::Cache3dArgs;
use super::runs3d::{ReferenceInfo3d, Run3d, Setup3d, Setup3dArgs, pt_seed, run_cache, run_pt, setup3d};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::core::metric::CacheMethod;
use volcache::core::stats::time_to_error;
use volcache::figure::axis::Axis;
use volcache::figure::gradient_figure::{AWARE_PURPLE, REFERENCE_BLUE, UNAWARE_ORANGE};
use volcache::figure::plot::{LineStyle, Plot, Series, draw_plot_into};
use volcache::output::{write_json, write_png};
use volcache::volume::cached::RecordMemo;
use volcache::volume::render::RenderParams;

#[derive(Args, Debug)]
pub struct Tradeoff3dArgs {
    #[command(flatten)]
    pub setup: Setup3dArgs,
    /// Target record counts for the cache methods.
    #[arg(long, value_delimiter = ',', default_values_t = [50usize, 100, 200, 400, 800])]
    pub counts: Vec<usize>,
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
struct Speedup {
    /// Which error: "image" or "medium".
    of: &'static str,
    error: f64,
    seconds_ours: f64,
    seconds_jarosz08: f64,
    /// seconds_jarosz08 / seconds_ours.
    speedup: f64,
    /// True when ours' fastest run is already below `error`: then `seconds_ours` is
    /// that run's time and `speedup` a lower bound.
    lower_bound: bool,
}

#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    params: &'a RenderParams,
    rays_per_cache: usize,
    steps: usize,
    march_step: Option<f64>,
    surface_paths: u32,
    threads: usize,
    reference: &'a ReferenceInfo3d,
    runs: &'a [Run3d],
    speedups: &'a [Speedup],
}

fn curve(runs: &[Run3d], method: &str, x: impl Fn(&Run3d) -> f64, medium: bool) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = runs
        .iter()
        .filter(|r| r.method == method)
        .map(|r| (x(r), if medium { r.medium_errors.rmse } else { r.errors.rmse }))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

fn speedups(runs: &[Run3d]) -> Vec<Speedup> {
    [("image", false), ("medium", true)]
        .into_iter()
        .flat_map(|(of, medium)| {
            let ours = curve(runs, "ours", |r| r.seconds, medium);
            let jarosz = curve(runs, "jarosz08", |r| r.seconds, medium);
            speedups_of(of, &ours, &jarosz)
        })
        .collect()
}

/// At the errors Jarosz 2008 reached, the time each method needs, from (seconds,
/// error) runs sorted by time. Jarosz 2008's time is taken at its own Pareto-optimal
/// runs; ours' is interpolated on its Pareto front (`time_to_error`), and where ours'
/// fastest run already beats the error, that run's time bounds the speedup from below.
fn speedups_of(of: &'static str, ours: &[(f64, f64)], jarosz: &[(f64, f64)]) -> Vec<Speedup> {
    let mut out = Vec::new();
    for (i, &(tj, e)) in jarosz.iter().enumerate() {
        // A slower run with a larger error says nothing about the time that error needs.
        if jarosz[..i].iter().any(|p| p.1 <= e) {
            continue;
        }
        let (to, lower_bound) = match (time_to_error(ours, e), ours.first()) {
            (Some(to), _) => (to, false),
            (None, Some(&(t0, e0))) if e0 <= e => (t0, true),
            _ => continue,
        };
        out.push(Speedup {
            of,
            error: e,
            seconds_ours: to,
            seconds_jarosz08: tj,
            speedup: tj / to,
            lower_bound,
        });
    }
    out
}

pub fn run(a: Tradeoff3dArgs) -> anyhow::Result<ExitCode> {
    let Setup3d {
        scene,
        stem,
        image,
        reference,
        ref_info,
    } = setup3d(&a.setup, a.quiet)?;
    let mut runs = Vec::new();
    for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        let mut memo = RecordMemo::new();
        for &k in &a.counts {
            let ui = ProgressUi::new(&format!("{stem} {method:?} {k}"), !a.quiet);
            let r = run_cache(
                &scene,
                &image,
                method,
                &a.cache,
                Some(k),
                &mut memo,
                &reference,
                &ui.progress,
            );
            ui.finish();
            let r = r?;
            eprintln!(
                "{:>8} {k:>5}: {} records, {:.2} s ({:.2} placement), RMSE {:.4e}, medium {:.4e}",
                r.method, r.records, r.seconds, r.placement_seconds, r.errors.rmse, r.medium_errors.rmse
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
        let r = run_pt(&scene, &p, &reference, &ui.progress);
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
    let report = Report {
        scene: &scene.source,
        params: &image,
        rays_per_cache: a.cache.rays,
        steps: a.cache.steps,
        march_step: a.cache.march_step,
        surface_paths: a.cache.surface_paths,
        threads: rayon::current_num_threads(),
        reference: &ref_info,
        runs: &runs,
        speedups: &speedups,
    };
    let json = a.out.join(format!("tradeoff3d_{stem}.json"));
    wrote(&json, write_json(&json, &report))?;
    let png = a.out.join(format!("tradeoff3d_{stem}.png"));
    wrote(&png, write_png(&png, &tradeoff_plot(&stem, &runs)))?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speedups_at_jarosz_pareto_runs_with_lower_bounds() {
        // The staircase's medium errors (results/tradeoff3d_staircase.json), rounded.
        let ours = [(6.4, 0.0185), (7.8, 0.0176), (12.9, 0.0154), (20.7, 0.0109)];
        let jarosz = [
            (7.2, 0.0268),
            (8.9, 0.0180),
            (13.0, 0.0228),
            (21.4, 0.0174),
            (67.7, 0.0182),
        ];
        let s = speedups_of("medium", &ours, &jarosz);
        let errors: Vec<f64> = s.iter().map(|s| s.error).collect();
        assert_eq!(errors, [0.0268, 0.0180, 0.0174], "dominated runs skipped");
        // 0.0268: ours' fastest run is already below it, so only a lower bound.
        assert!(s[0].lower_bound && s[0].seconds_ours == 6.4);
        assert!((s[0].speedup - 7.2 / 6.4).abs() < 1e-12);
        // 0.0180: interpolated log-log between ours' first two runs.
        assert!(!s[1].lower_bound && s[1].seconds_ours > 6.4 && s[1].seconds_ours < 7.8);
        assert!(s[1].speedup > 1.1 && s[1].speedup < 1.4, "{}", s[1].speedup);
        assert!(s[2].speedup > 2.4 && s[2].speedup < 2.9, "{}", s[2].speedup);
        // Errors ours never reaches give nothing.
        assert!(speedups_of("medium", &[(10.0, 0.05)], &jarosz).is_empty());
    }
}
