//! `volcache bench moments3d`: does a cache survive camera motion? A cache is placed
//! for the scene's camera (with its records' moments over ω_o, and without), the
//! camera orbits by each `--yaws` angle, and the new view is rendered by a fresh
//! cache (`recompute`), by the first records with their moments extended where
//! needed (`moments`), and by the first records read as stored (`stale`), each
//! against a converged reference of that view (study::moments3d).

use super::common::{ProgressUi, wrote};
use super::render3d_cache::Cache3dArgs;
use super::setup3d::{Setup3dArgs, setup3d};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::core::harmonics::{MAX_BANDS, basis_count};
use volcache::core::metric::CacheMethod;
use volcache::core::space::D3;
use volcache::output::write_json;
use volcache::study::moments3d::{FirstView, MotionRun, first_views, moved_view, orbited};
use volcache::study::reference3d::{reference_image, reference_params};
use volcache::volume::render::RenderParams;

#[derive(Args, Debug)]
pub struct Moments3dArgs {
    #[command(flatten)]
    pub setup: Setup3dArgs,
    /// Camera orbits (degrees about the look-at point's up axis) to render after
    /// the first view.
    #[arg(long, value_delimiter = ',', default_values_t = [10.0, 30.0, 90.0])]
    pub yaws: Vec<f64>,
    /// Highest band of the moments over ω_o ((L + 1)² per record).
    #[arg(long, default_value_t = 4)]
    pub bands: usize,
    #[arg(long, value_enum, default_value_t = CacheMethod::Ours)]
    pub method: CacheMethod,
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
    g: f64,
    params: &'a RenderParams,
    bands: usize,
    moments_per_record: usize,
    rays_per_cache: usize,
    steps: usize,
    threads: usize,
    first_view: [&'a FirstView; 2],
    runs: &'a [MotionRun],
}

pub fn run(a: Moments3dArgs) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(a.bands <= MAX_BANDS, "--bands must be at most {MAX_BANDS}");
    anyhow::ensure!(
        a.yaws.iter().all(|y| y.is_finite()),
        "--yaws must be finite angles in degrees"
    );
    anyhow::ensure!(
        a.cache.caches.is_none(),
        "--caches: bench moments3d places at ε (--eps)"
    );
    let setup = setup3d(&a.setup, a.quiet)?;
    let (scene, stem, image) = (&setup.scene, &setup.stem, &setup.image);
    let (mut cs, cp) = a.cache.settings(scene, image, a.method)?;
    cs.moment_bands = Some(a.bands);
    let ui = ProgressUi::new(&format!("{stem} first view"), !a.quiet);
    let first = first_views(scene, &cs, &cp, &ui.progress);
    ui.finish();
    let first = first?;
    for f in [&first.with_moments.1, &first.without.1] {
        eprintln!(
            "first view, moments {}: {} records, {:.2} s placement",
            f.moments, f.records, f.seconds
        );
    }
    let mut runs = Vec::new();
    for &yaw in &a.yaws {
        let moved = orbited(scene, yaw);
        let ref_params = reference_params(image, a.setup.ref_spp);
        let (reference, _) = reference_image(&moved, &ref_params, &a.setup.ref_cache, |label| {
            ProgressUi::new(label, !a.quiet)
        })?;
        let ui = ProgressUi::new(&format!("{stem} yaw {yaw}°"), !a.quiet);
        let r = moved_view(&moved, yaw, &cs, &cp, &first, &reference, &ui.progress);
        ui.finish();
        for run in r? {
            eprintln!(
                "yaw {yaw:>6.1}° {:>9}: {} records ({} new), {:.2} s ({:.2} placement), RMSE {:.4e}, medium {:.4e}",
                run.mode,
                run.records,
                run.new_records,
                run.seconds,
                run.placement_seconds,
                run.errors.rmse,
                run.medium_errors.rmse
            );
            runs.push(run);
        }
    }
    let report = Report {
        scene: &scene.source,
        g: scene.medium.as_ref().map_or(0.0, |m| m.g()),
        params: image,
        bands: a.bands,
        moments_per_record: basis_count::<D3>(a.bands),
        rays_per_cache: a.cache.rays,
        steps: a.cache.steps,
        threads: rayon::current_num_threads(),
        first_view: [&first.with_moments.1, &first.without.1],
        runs: &runs,
    };
    let json = a.out.join(format!("moments3d_{stem}.json"));
    wrote(&json, write_json(&json, &report))?;
    Ok(ExitCode::SUCCESS)
}
