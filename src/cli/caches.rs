//! `volcache caches`: reconstruct a scene's field from a radiance cache (ours or
//! Jarosz et al. 2008) or by path tracing, and measure it against a reference.

use super::common::{
    CACHES_BYTES_PER_PIXEL, ProgressUi, check_count, check_plan, check_range, check_spp, ensure_memory, exr_bytes,
    load_scene, parse_res, png_bytes, scene_stem, write_outputs,
};
use super::reference::{ReferenceInfo, reference_field, reference_files};
use clap::{Args, ValueEnum};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use volcache::figure::{FieldStyle, field_figure};
use volcache::flatland::cached_field::{
    CacheMethod, CacheSettings, RecordInfo, RecordMemo, render_cached, render_with_count,
};
use volcache::flatland::field::{Field, FieldErrors, FieldParams, field_errors, render_field};
use volcache::flatland::scene::Scene;
use volcache::limits;
use volcache::output::OutputPlan;
use volcache::progress::Progress;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MethodArg {
    /// Second-order occlusion-aware cache (Hessian ellipses).
    Ours,
    /// First-order occlusion-unaware cache (gradient circles).
    Jarosz08,
    /// Per-pixel path tracing.
    Pt,
}

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
    pub method: MethodArg,
    /// Samples per pixel for `--method pt`.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    #[command(flatten)]
    pub cache: CacheArgs,
    /// Output directory.
    #[arg(long, default_value = "out/caches")]
    pub out: PathBuf,
}

/// What one method produced and what it cost.
#[derive(Clone, Debug, Serialize)]
pub struct MethodRun {
    pub method: MethodArg,
    pub eps: Option<f64>,
    pub records: usize,
    #[serde(skip)]
    pub record_list: Vec<Vec<RecordInfo>>,
    #[serde(skip)]
    pub field: Field,
    pub rays_placement: u64,
    pub rays_reconstruction: u64,
    pub seconds_placement: f64,
    pub seconds_reconstruction: f64,
    pub seconds_total: f64,
    pub errors: Option<FieldErrors>,
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

pub fn cache_settings(method: CacheMethod, a: &CacheArgs) -> CacheSettings {
    let mut cs = CacheSettings::new(method, a.eps.unwrap_or(0.05));
    cs.probe.rays = a.rays.max(3);
    cs.probe.steps = a.steps.max(1);
    cs.per_part = a.per_part;
    cs.second_order = a.second_order;
    cs.seed = a.seed;
    cs
}

/// Run one method (a fresh memo: times are honest).
pub fn run_method(
    scene: &Scene,
    fp: &FieldParams,
    method: MethodArg,
    spp: u32,
    a: &CacheArgs,
    progress: &Progress,
) -> anyhow::Result<MethodRun> {
    let cancelled = |_| anyhow::Error::from(volcache::progress::Cancelled);
    Ok(match method {
        MethodArg::Pt => {
            let p = FieldParams { spp, ..fp.clone() };
            let r = render_field(scene, &p, progress).map_err(cancelled)?;
            MethodRun {
                method,
                eps: None,
                records: 0,
                record_list: vec![],
                field: r.field,
                rays_placement: 0,
                rays_reconstruction: r.rays,
                seconds_placement: 0.0,
                seconds_reconstruction: r.seconds,
                seconds_total: r.seconds,
                errors: None,
            }
        }
        MethodArg::Ours | MethodArg::Jarosz08 => {
            let m = if method == MethodArg::Ours {
                CacheMethod::Ours
            } else {
                CacheMethod::Jarosz08
            };
            let cs = cache_settings(m, a);
            let mut memo = RecordMemo::new();
            let eps = match a.caches {
                Some(k) => {
                    render_with_count(scene, fp, &cs, k.max(1), &mut memo, progress)
                        .map_err(cancelled)?
                        .1
                }
                None => cs.eps,
            };
            // Time a fresh placement at the chosen ε (the search's memo would hide its cost).
            let start = std::time::Instant::now();
            let f = render_cached(
                scene,
                fp,
                &CacheSettings { eps, ..cs },
                &mut RecordMemo::new(),
                progress,
            )
            .map_err(cancelled)?;
            let seconds_total = start.elapsed().as_secs_f64();
            MethodRun {
                method,
                eps: Some(eps),
                records: f.record_count(),
                record_list: f.records.clone(),
                rays_placement: f.placement_rays,
                rays_reconstruction: f.reconstruction_rays,
                seconds_placement: f.placement_seconds,
                seconds_reconstruction: f.reconstruction_seconds,
                // With --caches, the cost of the placement at the found ε (the search's
                // earlier placements are not counted).
                seconds_total,
                field: f.field,
                errors: None,
            }
        }
    })
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

/// Check the options `caches`, `figure compare` and `bench tradeoff` share.
pub fn check_cache_args(a: &CacheArgs, fp: &FieldParams) -> anyhow::Result<()> {
    if let Some(eps) = a.eps {
        check_range("--eps", eps, limits::EPS)?;
    }
    if let Some(k) = a.caches {
        check_count("--caches", k as u64, (fp.width * fp.height) as u64)?;
    }
    check_count("--rays", a.rays as u64, 1 << 20)?;
    check_count("--steps", a.steps as u64, 4096)?;
    check_spp("--ref-spp", a.ref_spp, limits::MAX_SPP)?;
    ensure_memory(fp.width * fp.height, CACHES_BYTES_PER_PIXEL, "the field")
}

pub fn run(a: CachesArgs) -> anyhow::Result<ExitCode> {
    let scene = load_scene(a.scene.as_deref())?;
    let stem = scene_stem(a.scene.as_deref());
    let fp = field_params(&scene, &a.cache);
    check_cache_args(&a.cache, &fp)?;
    check_spp("--spp", a.spp, limits::MAX_SPP)?;
    let ref_fp = FieldParams {
        spp: a.cache.ref_spp,
        seed: a.cache.seed ^ 0x5EED,
        ..fp.clone()
    };
    let mut plan = OutputPlan::new();
    if let Some(s) = &a.scene {
        plan.input("the scene", s);
    }
    for name in OUTPUTS {
        plan.output(format!("--out {}", a.out.display()), &a.out.join(name));
    }
    let (ref_exr, ref_json) = reference_files(&scene, &ref_fp, &a.cache.ref_cache);
    plan.output("--ref-cache", &ref_exr).output("--ref-cache", &ref_json);
    check_plan(&plan)?;

    let (reference, ref_info) = reference_field(&scene, &ref_fp, &a.cache.ref_cache, a.cache.quiet)?;
    let ui = ProgressUi::new(&format!("{stem} {:?}", a.method), !a.cache.quiet);
    let progress = ui.progress.clone();
    let run = run_method(&scene, &fp, a.method, a.spp, &a.cache, &progress);
    ui.finish();
    let mut run = run?;
    run.errors = Some(field_errors(&run.field, &reference));
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
    let files = output_files(&a.out, &scene, &run, &reference)?;
    let json = a.out.join("summary.json");
    write_outputs(files, Some((&json, serde_json::to_value(&summary)?)), &progress)
}

/// Every file `caches` may write into its folder (the summary last).
const OUTPUTS: [&str; 5] = ["field.png", "field.exr", "error.png", "records.png", "summary.json"];

fn output_files(
    dir: &Path,
    scene: &Scene,
    run: &MethodRun,
    reference: &Field,
) -> anyhow::Result<Vec<(PathBuf, Vec<u8>)>> {
    let style = FieldStyle::Tonemapped {
        exposure: scene.desc.render.exposure,
    };
    let title = format!("{:?}: {} records", run.method, run.records);
    let png = dir.join("field.png");
    let exr = dir.join("field.exr");
    let mut files = vec![
        (
            png.clone(),
            png_bytes(&png, &field_figure(&run.field, Some(scene), &style, Some(&title)))?,
        ),
        (exr.clone(), exr_bytes(&exr, &run.field)?),
    ];
    files.extend(super::caches_figures::cache_figures(dir, scene, run, reference)?);
    Ok(files)
}
