//! What a 3D comparison (`figure compare3d`, `bench tradeoff3d`) runs on: the scene,
//! the image the caches render (half the scene's resolution unless given) and the
//! converged reference from the store ([`volcache::study::reference3d`]).

use super::common::{ProgressUi, parse_res};
use super::render3d_cache::Cache3dArgs;
use clap::Args;
use std::path::PathBuf;
use volcache::core::metric::CacheMethod;
use volcache::study::reference3d::{ReferenceInfo3d, reference_image, reference_params};
use volcache::study::runs3d::{Run3d, cache_run, comparison_image};
use volcache::volume::cached::RecordMemo;
use volcache::volume::render::{RenderParams, Rendered};
use volcache::volume::scene::Scene;

/// The scene, its name, the image and the reference.
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
    let scene = Scene::load(&a.scene)?;
    let stem = a
        .scene
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    anyhow::ensure!(a.spp > 0 && a.ref_spp > 0, "--spp and --ref-spp must be at least 1");
    let res = a.res.map(|[w, h]| [w as usize, h as usize]);
    let image = comparison_image(&scene, res, a.spp, a.seed);
    let ref_params = reference_params(&image, a.ref_spp);
    let (reference, ref_info) = reference_image(&scene, &ref_params, &a.ref_cache, |label| {
        ProgressUi::new(label, !quiet)
    })?;
    Ok(Setup3d {
        scene,
        stem,
        image,
        reference,
        ref_info,
    })
}

/// One cache run of a comparison: the cache options, the image it renders (the
/// setup's, or one with a budget's camera samples) and the record count it
/// searches for (None: the options' ε).
pub struct CachePoint {
    pub cache: Cache3dArgs,
    pub image: RenderParams,
    pub target: Option<usize>,
}

/// `method` at `point`, with a progress bar.
pub fn run_cache(
    s: &Setup3d,
    method: CacheMethod,
    point: &CachePoint,
    memo: &mut RecordMemo,
    label: &str,
    quiet: bool,
) -> anyhow::Result<Run3d> {
    let (cs, cp) = point.cache.settings(&s.scene, &point.image, method)?;
    let ui = ProgressUi::new(label, !quiet);
    let r = cache_run(&s.scene, &cs, &cp, point.target, memo, &s.reference, &ui.progress);
    ui.finish();
    Ok(r?)
}
