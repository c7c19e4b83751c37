//! The 3D comparison runs (`figure compare3d`, `bench tradeoff3d`): a cache method at
//! a record count (ε searched with memoised light fields) or at ε, and path tracing
//! at a sample count or a time budget, each with its cost and its errors against a
//! converged reference, of the whole image and of its medium part.
//!
//! A cache run's time is its placement — the checks plus the capture time of the
//! records it uses, memoised or not — plus its reconstruction, so runs sharing a
//! memo across record counts are each charged what their own records cost.

use crate::core::metric::CacheMethod;
use crate::core::stats::{ImageErrors, luminance_errors};
use crate::pipeline::placement::CountError;
use crate::progress::Progress;
use crate::study::seeds::pt_seed;
use crate::volume::cached::{CacheSettings, CachedRenderParams, RecordInfo, RecordMemo, render_cached};
use crate::volume::image_split::ImageSplit;
use crate::volume::render::{RenderParams, Rendered, render};
use crate::volume::scene::Scene;
use serde::Serialize;

/// The image a comparison renders: the scene's, at `res` (default: half the scene's
/// resolution), with `spp` camera samples per pixel and `seed`.
pub fn comparison_image(scene: &Scene, res: Option<[usize; 2]>, spp: u32, seed: u64) -> RenderParams {
    let mut image = RenderParams::from_scene(scene);
    let [w, h] = res.unwrap_or([(image.width / 2).max(1), (image.height / 2).max(1)]);
    (image.width, image.height) = (w, h);
    (image.spp, image.seed) = (spp, seed);
    image
}

/// One method's image, cost and errors.
#[derive(Clone, Debug, Serialize)]
pub struct Run3d {
    pub method: String,
    pub records: usize,
    /// Records of the surface cache (zero without one).
    pub surface_records: usize,
    pub eps: Option<f64>,
    pub spp: u32,
    /// The camera samples of each pixel the placement visited (cache methods,
    /// when fewer than `spp`: `CachedRenderParams::place_spp`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub placed_spp: Option<u32>,
    /// The march step of the camera samples beyond the placed ones, when it is
    /// not the placement's (cache methods: `CachedRenderParams::image_march_step`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_march_step: Option<f64>,
    /// March points of the camera samples beyond the placed ones that no record
    /// covered, path traced instead (cache methods).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncovered: Option<u64>,
    /// How the camera samples beyond the placed ones marched, when chosen from
    /// the placed ones' statistics (`CachedRenderParams::adapt_image`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_split: Option<ImageSplit>,
    /// The budget that set ε, the directions and the camera samples (ours), or
    /// whose record count, directions and camera samples this run shares
    /// (jarosz08), in a budget sweep.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budget: Option<f64>,
    /// Directions per record (cache methods).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rays_per_record: Option<usize>,
    /// Samples of the straight light per march point, when the records leave it
    /// out (cache methods with `CacheSettings::direct_samples`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direct_samples: Option<u32>,
    /// The records' own noise relative to their values (cache methods;
    /// `pipeline::placement::ValueNoise`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub records_relative_noise: Option<f64>,
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
    /// A run that is all rendering (no placement), measured against `reference`.
    fn rendered(method: &str, image: Rendered, reference: &Rendered) -> Run3d {
        Run3d {
            method: method.into(),
            records: 0,
            surface_records: 0,
            eps: None,
            spp: image.spp,
            placed_spp: None,
            image_march_step: None,
            uncovered: None,
            image_split: None,
            budget: None,
            rays_per_record: None,
            direct_samples: None,
            records_relative_noise: None,
            seconds: image.seconds,
            placement_seconds: 0.0,
            reconstruction_seconds: image.seconds,
            rays: image.rays,
            errors: luminance_errors(&image.values, &reference.values),
            medium_errors: luminance_errors(&image.medium, &reference.medium),
            image,
            record_list: Vec::new(),
        }
    }
}

/// The name a cache method's runs carry.
pub fn method_name(method: CacheMethod) -> &'static str {
    match method {
        CacheMethod::Ours => "ours",
        CacheMethod::Jarosz08 => "jarosz08",
    }
}

/// `cs.method` at `target` records (or at `cs.eps`), timed as placement (with the
/// surface cache's, when `cp` asks for one) plus reconstruction.
pub fn cache_run(
    scene: &Scene,
    cs: &CacheSettings,
    cp: &CachedRenderParams,
    target: Option<usize>,
    memo: &mut RecordMemo,
    reference: &Rendered,
    progress: &Progress,
) -> Result<Run3d, CountError> {
    let r = render_cached(scene, cp, cs, target, memo, progress)?;
    let (placement, surfaces) = (r.placement, r.surfaces);
    let (uncovered, split) = (r.reconstruction.uncovered, r.reconstruction.split);
    let mut run = Run3d::rendered(method_name(cs.method), r.reconstruction.image, reference);
    run.records = placement.record_count();
    run.placed_spp = (cp.placed_spp() < run.spp).then_some(cp.placed_spp());
    run.uncovered = Some(uncovered);
    run.image_split = split;
    run.image_march_step = cp.image_march_step.filter(|_| run.placed_spp.is_some());
    run.eps = Some(placement.eps);
    run.rays_per_record = Some(cs.probe.rays);
    run.direct_samples = cs.direct_samples;
    run.records_relative_noise = placement.value_noise.relative();
    run.placement_seconds = placement.seconds;
    run.rays += placement.rays;
    if let Some(s) = &surfaces {
        run.surface_records = s.record_count();
        run.placement_seconds += s.seconds;
        run.rays += s.rays;
    }
    run.seconds = run.placement_seconds + run.reconstruction_seconds;
    run.record_list = placement.records().concat();
    Ok(run)
}

/// Path tracing at `image.spp` samples, or within `image.time_budget` seconds.
pub fn pt_run(
    scene: &Scene,
    image: &RenderParams,
    reference: &Rendered,
    progress: &Progress,
) -> Result<Run3d, CountError> {
    let img = render(scene, image, progress)?;
    Ok(Run3d::rendered("pt", img, reference))
}

/// The paper's 3D comparison (`figure compare3d` and the app's 3D compare view):
/// ours, then Jarosz 2008, at `target` records (or at their ε), each with a memo
/// of its own, then path tracing in the time ours took on its own streams
/// ([`pt_seed`] of the image's seed), all against `reference`. `settings` gives a
/// method's cache settings and image; `progress` a handle per run, by label.
pub fn compare3d<P: AsRef<Progress>>(
    scene: &Scene,
    settings: impl Fn(CacheMethod) -> (CacheSettings, CachedRenderParams),
    target: Option<usize>,
    reference: &Rendered,
    progress: impl Fn(&str) -> P,
) -> Result<Vec<Run3d>, CountError> {
    let mut runs = Vec::new();
    for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        let (cs, cp) = settings(method);
        let handle = progress(method_name(method));
        let memo = &mut RecordMemo::new();
        runs.push(cache_run(scene, &cs, &cp, target, memo, reference, handle.as_ref())?);
    }
    let image = settings(CacheMethod::Ours).1.image;
    let pt_params = RenderParams {
        spp: 1 << 24,
        seed: pt_seed(image.seed),
        time_budget: Some(runs[0].seconds),
        ..image
    };
    let handle = progress("pt (equal time)");
    runs.push(pt_run(scene, &pt_params, reference, handle.as_ref())?);
    Ok(runs)
}

/// The (x, RMSE) points of `method`'s runs, sorted by x: of the image, or of its
/// medium part.
pub fn curve(runs: &[Run3d], method: &str, x: impl Fn(&Run3d) -> f64, medium: bool) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = runs
        .iter()
        .filter(|r| r.method == method)
        .map(|r| (x(r), if medium { r.medium_errors.rmse } else { r.errors.rmse }))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// On a tiny fog box: a cache run is charged its placement and reconstruction,
    /// and compared with a reference of the same window.
    #[test]
    fn runs_carry_their_costs_and_errors() {
        let scene = Scene::load(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes3d/fog_box.json"))).unwrap();
        let image = comparison_image(&scene, Some([8, 6]), 1, 1);
        assert_eq!((image.width, image.height, image.spp), (8, 6, 1));
        let half = comparison_image(&scene, None, 1, 1);
        let full = RenderParams::from_scene(&scene);
        assert_eq!((half.width, half.height), (full.width / 2, full.height / 2));
        let p = Progress::new();
        let reference = render(
            &scene,
            &RenderParams {
                spp: 4,
                ..image.clone()
            },
            &p,
        )
        .unwrap();
        let mut cs =
            CacheSettings::new::<crate::core::space::D3>(CacheMethod::Ours, 1.0, image.first_vertex_settings());
        // A plumbing test: two even steps (a graded march needs more than two).
        (cs.probe.rays, cs.probe.steps, cs.probe.grading) = (64, 2, 0.0);
        let cp = CachedRenderParams {
            image: image.clone(),
            ..CachedRenderParams::from_scene(&scene)
        };
        let run = cache_run(&scene, &cs, &cp, Some(12), &mut RecordMemo::new(), &reference, &p).unwrap();
        assert_eq!(run.method, "ours");
        assert_eq!(run.records, run.record_list.len());
        assert!(run.records > 0 && run.eps.is_some());
        assert_eq!(run.seconds, run.placement_seconds + run.reconstruction_seconds);
        assert!(run.errors.rmse.is_finite() && run.medium_errors.pixels == 48);
        let pt = pt_run(&scene, &image, &reference, &p).unwrap();
        assert_eq!((pt.method.as_str(), pt.records, pt.spp), ("pt", 0, 1));
        let runs = [pt.clone(), run.clone()];
        assert_eq!(
            curve(&runs, "pt", |r| r.seconds, true),
            [(pt.seconds, pt.medium_errors.rmse)]
        );
    }
}
