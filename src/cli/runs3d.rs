//! Runs of the 3D methods for comparisons (`figure compare3d`, `bench tradeoff3d`):
//! a converged path-traced reference kept on disk, a cache method at a record count
//! (or ε), path tracing at a sample count or a time budget, each with its cost and
//! its errors against the reference (whole image and medium part).

use super::common::{ProgressUi, parse_res};
use super::image3d::{as_field, errors, medium_path, read_image};
use super::render3d_cache::Cache3dArgs;
use clap::Args;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use volcache::core::metric::CacheMethod;
use volcache::core::rng::fnv1a;
use volcache::core::stats::ImageErrors;
use volcache::output::{encode_exr, write_atomic, write_json};
use volcache::progress::{Cancelled, Progress};
use volcache::volume::cached::{RecordInfo, RecordMemo, place, place_with_count, reconstruct};
use volcache::volume::render::{RenderParams, Rendered, render};
use volcache::volume::scene::Scene;

/// How converged the reference is.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceInfo3d {
    pub key: String,
    pub spp: u32,
    pub seconds: f64,
    /// RMS per-pixel standard error over the mean luminance.
    pub relative_std_error: f64,
    pub from_disk: bool,
}

/// A converged path-traced image of `params` (its spp), from `dir` when rendered
/// before, else rendered with a progress bar and stored (EXR, medium EXR, JSON).
pub fn reference3d(
    scene: &Scene,
    params: &RenderParams,
    dir: &Path,
    quiet: bool,
) -> anyhow::Result<(Rendered, ReferenceInfo3d)> {
    let text = format!(
        "{}|{}",
        serde_json::to_string(&scene.desc).unwrap_or_default(),
        serde_json::to_string(params).unwrap_or_default()
    );
    let key = format!("{:016x}", fnv1a(text.as_bytes()));
    let exr = dir.join(format!("{key}.exr"));
    let json = dir.join(format!("{key}.json"));
    let [x0, y0, x1, y1] = params.window();
    let (w, h) = (x1 - x0, y1 - y0);
    if let (Ok(values), Ok(medium), Ok(text)) = (
        read_image(&exr, w, h),
        read_image(&medium_path(&exr), w, h),
        std::fs::read_to_string(&json),
    ) && let Ok(mut info) = serde_json::from_str::<ReferenceInfo3d>(&text)
    {
        info.from_disk = true;
        let img = Rendered {
            width: w,
            height: h,
            values,
            medium,
            std_error: vec![0.0; w * h],
            spp: info.spp,
            rays: 0,
            seconds: info.seconds,
        };
        return Ok((img, info));
    }
    let ui = ProgressUi::new(&format!("reference {} spp", params.spp), !quiet);
    let img = render(scene, params, &ui.progress);
    ui.finish();
    let img = img.map_err(|_| anyhow::Error::from(Cancelled))?;
    let info = ReferenceInfo3d {
        key,
        spp: img.spp,
        seconds: img.seconds,
        relative_std_error: img.relative_std_error(),
        from_disk: false,
    };
    write_atomic(&exr, &encode_exr(&as_field(w, h, &img.values))?)?;
    write_atomic(&medium_path(&exr), &encode_exr(&as_field(w, h, &img.medium))?)?;
    write_json(&json, &info)?;
    Ok((img, info))
}

/// What a comparison runs on: the scene, its name, the image the caches render
/// (half the scene's resolution unless given) and the converged reference.
pub struct Setup3d {
    pub scene: Scene,
    pub stem: String,
    pub image: RenderParams,
    pub reference: Rendered,
    pub ref_info: ReferenceInfo3d,
}

/// What a comparison renders and against which reference.
#[derive(Args, Debug)]
pub struct Setup3dArgs {
    /// Scene JSON (see scenes3d/).
    pub scene: PathBuf,
    /// Resolution WxH (default: half the scene's).
    #[arg(long, value_parser = parse_res)]
    pub res: Option<[u32; 2]>,
    /// Camera samples per pixel of the caches.
    #[arg(long, default_value_t = 4)]
    pub spp: u32,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Samples per pixel of the path-traced reference.
    #[arg(long, default_value_t = 4096)]
    pub ref_spp: u32,
    /// Where references are kept between runs.
    #[arg(long, default_value = "out/reference_cache3d")]
    pub ref_cache: PathBuf,
}

/// Load the scene, size the image and get the reference (`ref_spp`, its own seed).
pub fn setup3d(a: &Setup3dArgs, quiet: bool) -> anyhow::Result<Setup3d> {
    let (scene_path, spp, seed, ref_spp) = (&a.scene, a.spp, a.seed, a.ref_spp);
    let scene = Scene::load(scene_path)?;
    let stem = scene_path
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let mut image = RenderParams::from_scene(&scene);
    match a.res {
        Some([w, h]) => (image.width, image.height) = (w as usize, h as usize),
        None => (image.width, image.height) = ((image.width / 2).max(1), (image.height / 2).max(1)),
    }
    anyhow::ensure!(spp > 0 && ref_spp > 0, "--spp and --ref-spp must be at least 1");
    (image.spp, image.seed) = (spp, seed);
    let ref_params = RenderParams {
        spp: ref_spp,
        seed: seed ^ 0x5EED,
        ..image.clone()
    };
    let (reference, ref_info) = reference3d(&scene, &ref_params, &a.ref_cache, quiet)?;
    Ok(Setup3d {
        scene,
        stem,
        image,
        reference,
        ref_info,
    })
}

/// Path tracing's own seed in comparisons (not the caches' camera rays).
pub fn pt_seed(seed: u64) -> u64 {
    seed ^ 0xB7
}

/// One method's image, cost and errors.
#[derive(Clone, Debug, Serialize)]
pub struct Run3d {
    pub method: String,
    pub records: usize,
    pub eps: Option<f64>,
    pub spp: u32,
    pub seconds: f64,
    pub placement_seconds: f64,
    pub reconstruction_seconds: f64,
    pub rays: u64,
    pub errors: ImageErrors,
    pub medium_errors: ImageErrors,
    #[serde(skip)]
    pub image: Rendered,
    #[serde(skip)]
    pub record_list: Vec<RecordInfo>,
}

impl Run3d {
    fn new(method: &str, image: Rendered, reference: &Rendered) -> Run3d {
        Run3d {
            method: method.into(),
            records: 0,
            eps: None,
            spp: image.spp,
            seconds: image.seconds,
            placement_seconds: 0.0,
            reconstruction_seconds: image.seconds,
            rays: image.rays,
            errors: errors(&image.values, &reference.values),
            medium_errors: errors(&image.medium, &reference.medium),
            image,
            record_list: Vec::new(),
        }
    }
}

/// A cache method at `target` records (or at the arguments' ε), timed as placement
/// (checks plus its records' captures, memoised or not) plus reconstruction.
#[allow(clippy::too_many_arguments)] // the run is spelled out
pub fn run_cache(
    scene: &Scene,
    image: &RenderParams,
    method: CacheMethod,
    a: &Cache3dArgs,
    target: Option<usize>,
    memo: &mut RecordMemo,
    reference: &Rendered,
    progress: &Progress,
) -> anyhow::Result<Run3d> {
    let (cs, cp) = a.settings(scene, image, method)?;
    let placement = match target {
        Some(n) => place_with_count(scene, &cp, &cs, n, memo, progress)?,
        None => place(scene, &cp, &cs, memo, progress)?,
    };
    let second_order = cs.second_order && method == CacheMethod::Ours;
    let r = reconstruct(scene, &cp, &placement.caches[0], second_order, progress)?;
    let name = match method {
        CacheMethod::Ours => "ours",
        CacheMethod::Jarosz08 => "jarosz08",
    };
    let mut run = Run3d::new(name, r.image, reference);
    run.records = placement.record_count();
    run.eps = Some(placement.eps);
    run.placement_seconds = placement.seconds;
    run.seconds = placement.seconds + run.reconstruction_seconds;
    run.rays += placement.rays;
    run.record_list = placement.records().concat();
    Ok(run)
}

/// Path tracing at `image.spp` samples, or within `image.time_budget` seconds.
pub fn run_pt(scene: &Scene, image: &RenderParams, reference: &Rendered, progress: &Progress) -> anyhow::Result<Run3d> {
    let img = render(scene, image, progress)?;
    Ok(Run3d::new("pt", img, reference))
}
