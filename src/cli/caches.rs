//! `volcache caches`: reconstruct a scene's field from a radiance cache (ours or
//! Jarosz et al. 2008) or by path tracing, and measure it against a reference.

use super::common::{
    CACHES_BYTES_PER_PIXEL, ProgressUi, RecordNoiseArgs, check_count, check_plan, check_range, check_spp,
    ensure_memory, exr_bytes, load_scene, parse_res, png_bytes, scene_stem, write_outputs,
};
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use volcache::figure::{FieldStyle, field_figure};
use volcache::flatland::cached_field::{CacheMethod, CacheSettings, budget_settings};
use volcache::flatland::field::{Field, FieldParams};
use volcache::flatland::scene::Scene;
use volcache::limits;
use volcache::output::OutputPlan;
use volcache::pipeline::budget::{MAX_BUDGET, MIN_BUDGET, schedule};
use volcache::pipeline::path::Sampling;
use volcache::pipeline::placement::CountError;
use volcache::progress::Progress;
use volcache::study::field_runs::{self, FieldMethod, MethodRun, cache_run, pt_run};
use volcache::study::reference2d::{ReferenceInfo, reference_field, reference_files};
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
    /// One budget for the cache (`pipeline::budget`): B = 1 is ε 0.025 with 256
    /// directions per record; a budget k times larger costs about k times as much,
    /// spent as the measured error model says: on smaller ε alone up to B ≈ 4.7
    /// (ε 0.001), then on smaller ε and more directions alike (below B = 1, on
    /// fewer directions and larger ε). Sets --eps and --rays, and where the scene
    /// has emitting segments the straight light's samples per pixel (a quarter of
    /// the placement's rays per pixel at B = 1 and 128² pixels, that share falling
    /// as 1/√B and scaled by (pixels/128²)^(2/3); --direct-samples overrides), and --edge-reach max(1, 4√(ε/0.025)) unless
    /// given; for ours only (the model was measured for ours).
    #[arg(long, conflicts_with_all = ["eps", "caches", "rays"])]
    pub budget: Option<f64>,
    /// Directions per cache point.
    #[arg(long, default_value_t = 1024)]
    pub rays: usize,
    /// Ray-marched medium samples per direction.
    #[arg(long, default_value_t = 16)]
    pub steps: usize,
    /// Refinement of the march towards x: 0 spaces the samples evenly, k > 0 makes
    /// the first steps k/(e^k − 1) of the even step (see `pipeline::probe::March`).
    #[arg(long, default_value_t = <volcache::core::space::D2 as volcache::pipeline::dim::Dim>::PROBE_GRADING)]
    pub grading: f64,
    /// Separate caches for single and multiple scattering.
    #[arg(long)]
    pub per_part: bool,
    /// Second-order interpolation (ours).
    #[arg(long)]
    pub second_order: bool,
    /// Sample the light arriving straight from the lights (emitters, sky, delta
    /// lights) at every pixel with this many samples (NEE and a phase-sampled ray,
    /// MIS), and cache only the rest: the records leave it out. Default: only delta
    /// lights per pixel, the rest cached (the paper's split).
    #[arg(long)]
    pub direct_samples: Option<u32>,
    /// Sample the point lights' light scattered once in the fog on its way to
    /// every pixel, with this many phase-sampled directions per pixel (one
    /// equiangular distance per light along each), and cache only the rest: the
    /// records leave it out. Around a point light it peaks (log 1/r) where records
    /// extrapolate across. 0 caches it. Default: the budget's under --budget,
    /// else cached.
    #[arg(long)]
    pub point_scatter: Option<u32>,
    /// Path trace the pixels within one mean free path of a point light whole,
    /// with this many paths each, instead of reading them from records (records
    /// are still placed there, for the pixels just outside): around a point light
    /// the light scattered twice or more still peaks, and records there are
    /// noisy. Only in fog at least ten mean free paths across the scene (in
    /// thinner fog nothing is path traced: it does not pay there). 0 caches them.
    /// Default: the budget's under --budget, else cached.
    #[arg(long)]
    pub near_light_paths: Option<u32>,
    /// Limit every record's radii to this multiple of its distance to the nearest
    /// surface edge it sees (a segment's end, a triangle's silhouette edge), where
    /// the light turns with the angle and no Taylor expansion reaches across, or
    /// to the nearest point light it sees (the scattered light peaks around it).
    /// Default: the paper's metric alone.
    #[arg(long)]
    pub edge_reach: Option<f64>,
    /// Limit every record's radii to this multiple of its distance to the nearest
    /// point light that emits (`CacheSettings::lamp_reach`; no rays: the lights'
    /// positions): the light scattered around a point light peaks as it nears it,
    /// and a Taylor expansion of that peak converges only within that distance.
    /// Default: off in 2D (on in 3D, `render3d --lamp-reach`; README).
    #[arg(long)]
    pub lamp_reach: Option<f64>,
    /// Limit every record's radii by its multiple-scattering gradient's noise
    /// (`core::metric::gradient_noise_radius`): the radius at which that noise,
    /// integrated over the record's ball, adds the error ε allows the Hessian's
    /// term. Where a record's gradient is mostly noise (few directions, thick or
    /// forward-scattering fog) it then reaches less far. Ours only (Jarosz 2008
    /// measures no gradient noise). Off by default, also under --budget (README).
    #[arg(long)]
    pub gradient_noise_reach: bool,
    /// Russian roulette of the probes' phase-sampled paths by the phase's weight
    /// of each direction towards ω_o (`ProbeSettings::phase_roulette`: followed
    /// with probability min(1, C·f/f̄)); 0 turns it off. Unbiased; saves rays in
    /// anisotropic fog (see `volcache bench records`).
    #[arg(long, default_value_t = 0.0)]
    pub phase_roulette: f64,
    #[command(flatten)]
    pub record_noise: RecordNoiseArgs,
    /// Resolution WxH (default: half the scene's render resolution).
    #[arg(long, value_parser = parse_res)]
    pub res: Option<[u32; 2]>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// How the samples of a path-traced pixel (`--method pt`, the reference) draw
    /// their random numbers: stratified by default, as pbrt-v4's samplers are
    /// (`--direct-samples`' sets are always stratified).
    #[arg(long, value_enum, default_value = "stratified")]
    pub sampling: Sampling,
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

impl CacheArgs {
    /// ε and directions per record: `--eps` (default 0.05) and `--rays`, or
    /// `--budget`'s.
    fn eps_and_rays(&self) -> (f64, usize) {
        match self.budget {
            Some(b) => schedule(b),
            None => (self.eps.unwrap_or(0.05), self.rays),
        }
    }

    /// Directions per record: `--rays`, or `--budget`'s.
    pub fn rays_per_record(&self) -> usize {
        self.eps_and_rays().1
    }

    /// `--edge-reach`, or `--budget`'s.
    pub fn edge_reach_for(&self, scene: &Scene) -> Option<f64> {
        (self.edge_reach).or_else(|| self.budget.map(|b| budget_settings(scene, b).edge_reach))
    }

    /// `--point-scatter` (0: none), or the budget's.
    pub fn point_scatter_for(&self, scene: &Scene) -> Option<u32> {
        match (self.point_scatter, self.budget) {
            (Some(n), _) => (n > 0).then_some(n),
            (None, Some(b)) => budget_settings(scene, b).point_scatter,
            (None, None) => None,
        }
    }

    /// `--near-light-paths` (0: none), or the budget's.
    pub fn near_light_paths_for(&self, scene: &Scene) -> Option<u32> {
        match (self.near_light_paths, self.budget) {
            (Some(n), _) => (n > 0).then_some(n),
            (None, Some(b)) => budget_settings(scene, b).near_light_paths,
            (None, None) => None,
        }
    }

    /// The straight light's samples per pixel and their share of the placement's
    /// rays: `--direct-samples` (no share), or under `--budget` the budget's where
    /// the scene has lights with an extent (delta lights' straight light is per
    /// pixel anyway: samples of it would repeat it).
    pub fn direct_for(&self, scene: &Scene) -> (Option<u32>, Option<f64>) {
        match (self.direct_samples, self.budget) {
            (Some(n), _) => (Some(n), None),
            (None, Some(b)) => budget_settings(scene, b).direct.unzip(),
            (None, None) => (None, None),
        }
    }
}

/// The field of the options on `scene`: of L_s, what the cache holds, whatever
/// quantity the scene renders (`field_runs::cached_quantity`; said on stderr).
pub fn field_params(scene: &Scene, a: &CacheArgs) -> FieldParams {
    let mut fp = field_runs::cached_quantity(FieldParams::from_scene(scene));
    if fp.quantity != scene.desc.render.quantity && !a.quiet {
        eprintln!(
            "note: {} renders {}; a cache holds in-scattered radiance, so its field and the reference are of L_s",
            scene.source,
            super::field::quantity_label(scene.desc.render.quantity)
        );
    }
    match a.res {
        Some([w, h]) => (fp.width, fp.height) = (w as usize, h as usize),
        None => (fp.width, fp.height) = ((fp.width / 2).max(1), (fp.height / 2).max(1)),
    }
    fp.seed = a.seed;
    fp.settings.sampling = a.sampling;
    fp
}

/// The options' cache settings on `scene` (`fp.seed` is `--seed`, see [`field_params`]).
pub fn cache_settings(scene: &Scene, method: CacheMethod, a: &CacheArgs, fp: &FieldParams) -> CacheSettings {
    let (eps, rays) = a.eps_and_rays();
    let mut cs = field_runs::cache_settings(method, eps, fp, rays, a.steps);
    cs.probe.grading = a.grading;
    cs.per_part = a.per_part;
    cs.second_order = a.second_order;
    (cs.direct_samples, cs.direct_share) = a.direct_for(scene);
    cs.edge_reach = a.edge_reach_for(scene);
    cs.lamp_reach = a.lamp_reach;
    cs.gradient_noise_reach = a.gradient_noise_reach;
    cs.probe.phase_roulette = a.phase_roulette;
    cs.record_noise = a.record_noise.target();
    cs.point_scatter = a.point_scatter_for(scene);
    cs.near_light_paths = a.near_light_paths_for(scene);
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
        Some(m) => cache_run(
            scene,
            fp,
            &cache_settings(scene, m, a, fp),
            a.caches,
            reference,
            progress,
        ),
        None => Ok(pt_run(scene, fp, spp, reference, progress)?),
    }
}

#[derive(Serialize)]
struct Summary<'a> {
    scene: &'a str,
    params: &'a FieldParams,
    rays_per_cache: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    budget: Option<f64>,
    per_part: bool,
    second_order: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    direct_samples: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    point_scatter: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    edge_reach: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lamp_reach: Option<f64>,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    gradient_noise_reach: bool,
    run: &'a MethodRun,
    reference: &'a ReferenceInfo,
}

/// The reference field of the options (`--ref-spp`, the reference's own seed),
/// from the store in `--ref-cache` or rendered (with a progress bar) into it.
pub fn reference(scene: &Scene, fp: &FieldParams, a: &CacheArgs) -> anyhow::Result<(Field, ReferenceInfo)> {
    reference_field(scene, &reference_params(fp, a), &a.ref_cache, |label| {
        ProgressUi::new(label, !a.quiet)
    })
}

/// The reference's field parameters: `--ref-spp` samples, its own seed.
fn reference_params(fp: &FieldParams, a: &CacheArgs) -> FieldParams {
    FieldParams {
        spp: a.ref_spp,
        seed: reference_seed(a.seed),
        ..fp.clone()
    }
}

/// The store's files for the reference of the options (outputs of any run that
/// may render it).
pub fn reference_outputs(scene: &Scene, fp: &FieldParams, a: &CacheArgs) -> Vec<PathBuf> {
    reference_files(scene, &reference_params(fp, a), &a.ref_cache)
}

/// Check the options `caches`, `figure compare` and `bench tradeoff` share.
pub fn check_cache_args(a: &CacheArgs, fp: &FieldParams) -> anyhow::Result<()> {
    if let Some(eps) = a.eps {
        check_range("--eps", eps, limits::EPS)?;
    }
    if let Some(b) = a.budget {
        check_range("--budget", b, (MIN_BUDGET, MAX_BUDGET))?;
    }
    if let Some(k) = a.caches {
        check_count("--caches", k as u64, (fp.width * fp.height) as u64)?;
    }
    check_count("--rays", a.rays as u64, 1 << 20)?;
    check_count("--steps", a.steps as u64, 4096)?;
    check_range("--grading", a.grading, limits::GRADING)?;
    check_spp("--ref-spp", a.ref_spp, limits::MAX_SPP)?;
    if let Some(n) = a.direct_samples {
        check_spp("--direct-samples", n, limits::MAX_SPP)?;
    }
    if let Some(n) = a.point_scatter.filter(|&n| n > 0) {
        check_spp("--point-scatter", n, limits::MAX_SPP)?;
    }
    if let Some(n) = a.near_light_paths.filter(|&n| n > 0) {
        check_spp("--near-light-paths", n, limits::MAX_SPP)?;
    }
    if let Some(k) = a.edge_reach {
        check_range("--edge-reach", k, limits::EDGE_REACH)?;
    }
    if let Some(k) = a.lamp_reach {
        check_range("--lamp-reach", k, limits::EDGE_REACH)?;
    }
    check_range("--phase-roulette", a.phase_roulette, (0.0, 100.0))?;
    a.record_noise.check()?;
    ensure_memory(fp.width * fp.height, CACHES_BYTES_PER_PIXEL, "the field")
}

pub fn run(a: CachesArgs) -> anyhow::Result<ExitCode> {
    let scene = load_scene(a.scene.as_deref())?;
    let stem = scene_stem(a.scene.as_deref());
    let fp = field_params(&scene, &a.cache);
    check_cache_args(&a.cache, &fp)?;
    check_spp("--spp", a.spp, limits::MAX_SPP)?;
    anyhow::ensure!(
        a.cache.budget.is_none() || a.method == FieldMethod::Ours,
        "--budget schedules ours (its error model was measured for ours): with --method {}, give --eps or --caches",
        format!("{:?}", a.method).to_lowercase()
    );
    let mut plan = OutputPlan::new();
    if let Some(s) = &a.scene {
        plan.input("the scene", s);
    }
    for name in OUTPUTS {
        plan.output(format!("--out {}", a.out.display()), &a.out.join(name));
    }
    for file in reference_outputs(&scene, &fp, &a.cache) {
        plan.output("--ref-cache", &file);
    }
    check_plan(&plan)?;

    let (reference, ref_info) = reference(&scene, &fp, &a.cache)?;
    let ui = ProgressUi::new(&format!("{stem} {:?}", a.method), !a.cache.quiet);
    let progress = ui.progress.clone();
    let run = run_method(&scene, &fp, a.method, a.spp, &a.cache, &reference, &progress);
    ui.finish();
    let run = match run {
        Ok(run) => run,
        Err(CountError::Cancelled(c)) => return Err(c.into()),
        Err(e) => anyhow::bail!("--caches: {e}"),
    };
    let e = run.errors.unwrap_or_default();
    eprintln!(
        "{:?}: {} records, {:.2} s (placement {:.2} s), {} rays; RMSE {:.4e} (bias {:+.3e}, mean {:.4e}), relMSE {:.4e} (reference {} spp, rel. std error {:.2}%)",
        run.method,
        run.records,
        run.seconds_total,
        run.seconds_placement,
        run.rays_placement + run.rays_reconstruction,
        e.rmse,
        e.bias,
        e.mean_reference,
        e.relmse,
        ref_info.spp,
        100.0 * ref_info.mean_relative_std_error
    );
    let summary = Summary {
        scene: &scene.source,
        params: &fp,
        rays_per_cache: a.cache.rays_per_record(),
        budget: a.cache.budget,
        per_part: a.cache.per_part,
        direct_samples: run.direct_samples,
        point_scatter: run.point_scatter,
        edge_reach: a.cache.edge_reach_for(&scene),
        lamp_reach: a.cache.lamp_reach,
        gradient_noise_reach: a.cache.gradient_noise_reach,
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
