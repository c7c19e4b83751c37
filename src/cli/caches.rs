//! `volcache caches`: reconstruct a scene's field from a radiance cache (ours or
//! Jarosz et al. 2008) or by path tracing, and measure it against a reference.

use super::common::{ProgressUi, load_scene, parse_res, scene_stem, wrote};
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use volcache::figure::{FieldStyle, field_figure};
use volcache::flatland::cached_field::{CacheMethod, CacheSettings};
use volcache::flatland::field::{Field, FieldParams};
use volcache::flatland::scene::Scene;
use volcache::output::{write_exr, write_json, write_png};
use volcache::pipeline::placement::CountError;
use volcache::progress::Progress;
use volcache::study::field_runs::{self, FieldMethod, MethodRun, cache_run, pt_run};
use volcache::study::reference2d::{ReferenceInfo, reference_field};
use volcache::study::seeds::reference_seed;

/// Cache parameters shared by `caches`, `figure compare` and `bench tradeoff`.
#[derive(Args, Debug, Clone)]
pub struct CacheArgs {
    /// Error threshold ε.
    #[arg(long)]
    pub eps: Option<f64>,
    /// Equal-count mode: search ε so that the method places this many records (±1%).
    #[arg(long, conflicts_with = "eps")]
    pub caches: Option<usize>,
    /// Directions per cache point.
    #[arg(long, default_value_t = 1024)]
    pub rays: usize,
    /// Ray-marched medium samples per direction.
    #[arg(long, default_value_t = 16)]
    pub steps: usize,
    /// Separate caches for single and multiple scattering.
    #[arg(long)]
    pub per_part: bool,
    /// Second-order interpolation (ours).
    #[arg(long)]
    pub second_order: bool,
    /// Resolution WxH (default: half the scene's render resolution).
    #[arg(long, value_parser = parse_res)]
    pub res: Option<[u32; 2]>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Samples per pixel of the reference field.
    #[arg(long, default_value_t = 4096)]
    pub ref_spp: u32,
    /// Where reference fields are cached.
    #[arg(long, default_value = "out/reference_cache")]
    pub ref_cache: PathBuf,
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Args, Debug)]
pub struct CachesArgs {
    /// Scene JSON (default: the embedded occluder scene).
    pub scene: Option<PathBuf>,
    #[arg(long, value_enum, default_value = "ours")]
    pub method: FieldMethod,
    /// Samples per pixel for `--method pt`.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    #[command(flatten)]
    pub cache: CacheArgs,
    /// Output directory.
    #[arg(long, default_value = "out/caches")]
    pub out: PathBuf,
}

pub fn field_params(scene: &Scene, a: &CacheArgs) -> FieldParams {
    let mut fp = FieldParams::from_scene(scene);
    match a.res {
        Some([w, h]) => (fp.width, fp.height) = (w as usize, h as usize),
        None => (fp.width, fp.height) = ((fp.width / 2).max(1), (fp.height / 2).max(1)),
    }
    fp.seed = a.seed;
    fp
}

/// The options' cache settings (`fp.seed` is `--seed`, see [`field_params`]).
pub fn cache_settings(method: CacheMethod, a: &CacheArgs, fp: &FieldParams) -> CacheSettings {
    let mut cs = field_runs::cache_settings(method, a.eps.unwrap_or(0.05), fp, a.rays, a.steps);
    cs.per_part = a.per_part;
    cs.second_order = a.second_order;
    cs
}

/// `method` with the options' cache settings and record count (`--caches`: the
/// equal-count protocol), measured against `reference`.
pub fn run_method(
    scene: &Scene,
    fp: &FieldParams,
    method: FieldMethod,
    spp: u32,
    a: &CacheArgs,
    reference: &Field,
    progress: &Progress,
) -> Result<MethodRun, CountError> {
    match method.cache_method() {
        Some(m) => cache_run(scene, fp, &cache_settings(m, a, fp), a.caches, reference, progress),
        None => Ok(pt_run(scene, fp, spp, reference, progress)?),
    }
}

#[derive(Serialize)]
struct Summary<'a> {
    scene: &'a str,
    params: &'a FieldParams,
    rays_per_cache: usize,
    per_part: bool,
    second_order: bool,
    run: &'a MethodRun,
    reference: &'a ReferenceInfo,
}

/// The reference field of the options (`--ref-spp`, the reference's own seed),
/// from the store in `--ref-cache` or rendered (with a progress bar) into it.
pub fn reference(scene: &Scene, fp: &FieldParams, a: &CacheArgs) -> anyhow::Result<(Field, ReferenceInfo)> {
    let ref_fp = FieldParams {
        spp: a.ref_spp,
        seed: reference_seed(a.seed),
        ..fp.clone()
    };
    reference_field(scene, &ref_fp, &a.ref_cache, |label| ProgressUi::new(label, !a.quiet))
}

pub fn run(a: CachesArgs) -> anyhow::Result<ExitCode> {
    let scene = load_scene(a.scene.as_deref())?;
    let stem = scene_stem(a.scene.as_deref());
    let fp = field_params(&scene, &a.cache);
    let (reference, ref_info) = reference(&scene, &fp, &a.cache)?;
    let ui = ProgressUi::new(&format!("{stem} {:?}", a.method), !a.cache.quiet);
    let run = run_method(&scene, &fp, a.method, a.spp, &a.cache, &reference, &ui.progress);
    ui.finish();
    let run = match run {
        Ok(run) => run,
        Err(CountError::Cancelled(_)) => {
            eprintln!("cancelled: no output written");
            return Ok(ExitCode::from(130));
        }
        Err(e) => anyhow::bail!("--caches: {e}"),
    };
    write_outputs(&a.out, &scene, &run, &reference)?;
    let e = run.errors.unwrap_or_default();
    eprintln!(
        "{:?}: {} records, {:.2} s (placement {:.2} s), {} rays; RMSE {:.4e}, relMSE {:.4e} (reference {} spp, rel. std error {:.2}%)",
        run.method,
        run.records,
        run.seconds_total,
        run.seconds_placement,
        run.rays_placement + run.rays_reconstruction,
        e.rmse,
        e.relmse,
        ref_info.spp,
        100.0 * ref_info.mean_relative_std_error
    );
    let summary = Summary {
        scene: &scene.source,
        params: &fp,
        rays_per_cache: a.cache.rays,
        per_part: a.cache.per_part,
        second_order: a.cache.second_order,
        run: &run,
        reference: &ref_info,
    };
    let json = a.out.join("summary.json");
    wrote(&json, write_json(&json, &summary))?;
    Ok(ExitCode::SUCCESS)
}

fn write_outputs(dir: &Path, scene: &Scene, run: &MethodRun, reference: &Field) -> anyhow::Result<()> {
    let style = FieldStyle::Tonemapped {
        exposure: scene.desc.render.exposure,
    };
    let title = format!("{:?}: {} records", run.method, run.records);
    let png = dir.join("field.png");
    wrote(
        &png,
        write_png(&png, &field_figure(&run.field, Some(scene), &style, Some(&title))),
    )?;
    let exr = dir.join("field.exr");
    wrote(&exr, write_exr(&exr, &run.field))?;
    super::caches_figures::write_cache_figures(dir, scene, run, reference)
}
