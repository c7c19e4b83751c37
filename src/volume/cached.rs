//! Radiance caching in 3D (theory.md §6–8): records placed where camera rays march
//! through the medium, and the image reconstructed from them.
//!
//! What is cached: the single + multiple scattered L_s of theory.md §2 towards the
//! camera. With a pinhole camera, ω_o at a medium point x is the direction from x
//! to the camera, so the cached quantity is a function of x alone and its
//! derivatives include the turning of ω_o (`Outgoing::TowardsPoint`); an isotropic
//! medium pays nothing for it. The direct part (point lights, suns with or without a
//! cone) is sampled at every march point, never cached: it is singular at shadow
//! edges and costs one shadow ray. Light from surfaces seen by the camera (T L_o)
//! is path traced per camera sample, as in the reference, or read from a surface
//! cache (`CachedRenderParams::surface_eps`, [`super::surface_cache`]).
//!
//! The query points of the pipeline's placement (`pipeline::placement`, which
//! also decides the records' methods and values) are the window's camera samples'
//! march points ([`super::camera_march`]), pixel by pixel in a coarse-to-fine order.

pub use super::cached_params::{
    CacheView, CachedRenderParams, Placement, RadianceCache, RecordInfo, RecordMemo, SurfaceCache, SurfaceMemo,
};
use super::camera::Camera;
use super::camera_march::{CameraRay, window_order};
pub use super::reconstruct::{Reconstruction, march_reference, reconstruct};
use super::render::camera;
use super::scene::Scene;
use crate::core::metric::CacheMethod;
use crate::core::rng::mix64;
use crate::core::space::D3;
use crate::pipeline::eye_cone::EyeCone;
pub use crate::pipeline::placement::CountError;
use crate::pipeline::placement::{
    QueryPoint, QuerySource, place as place_points, place_onto as place_points_onto, place_with_count as place_count,
};
use crate::pipeline::probe::Outgoing;
use crate::pipeline::record::Cached;
use crate::progress::{Cancelled, Progress};
use glam::DVec3;

pub use crate::pipeline::record::CacheSettings;

/// A starting ε for a scene: ours' ε is a volume (scaled with the scene), the
/// baseline's a fraction.
pub fn default_eps(method: CacheMethod, scene: &Scene) -> f64 {
    match method {
        CacheMethod::Ours => 1e-4 * scene.scale.powi(3),
        CacheMethod::Jarosz08 => 0.1,
    }
}

/// What a budget sets for ours on a scene (`budget_settings`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BudgetSettings {
    pub eps: f64,
    /// Directions per record.
    pub rays: usize,
    /// Camera samples per pixel.
    pub spp: u32,
    /// The camera samples the placement visits of each pixel
    /// (`pipeline::budget::volume_placed_spp`).
    pub place_spp: u32,
    /// Samples of the straight light per march point
    /// (`pipeline::budget::VOLUME_DIRECT_SAMPLES`).
    pub direct_samples: u32,
}

/// What budget `b` (`pipeline::budget::VOLUME`) sets for ours on `scene`.
pub fn budget_settings(scene: &Scene, b: f64) -> BudgetSettings {
    use crate::pipeline::budget::{VOLUME, VOLUME_DIRECT_SAMPLES, VOLUME_EPS_AT_ONE, volume_placed_spp};
    let s = VOLUME.schedule(b);
    let spp = s.spp.unwrap_or(1);
    BudgetSettings {
        eps: default_eps(CacheMethod::Ours, scene) * VOLUME_EPS_AT_ONE * s.eps_scale,
        rays: s.rays,
        spp,
        place_spp: volume_placed_spp(spp),
        direct_samples: VOLUME_DIRECT_SAMPLES,
    }
}

/// Every march point of every camera sample of the window's pixels, pixel by
/// pixel in a coarse-to-fine order; L_s leaves each towards the camera.
struct CameraSamples<'a> {
    scene: &'a Scene,
    cam: Camera,
    params: &'a CachedRenderParams,
    /// Full-image pixel indices in placement order.
    order: Vec<usize>,
    /// The image's width and height, 16 bits each, as the top of the memo's keys.
    size_key: u128,
}

impl<'a> CameraSamples<'a> {
    fn new(scene: &'a Scene, params: &'a CachedRenderParams) -> Self {
        let (order, size_key) = window_order(&params.image);
        CameraSamples {
            scene,
            cam: camera(scene, params.image.width, params.image.height),
            params,
            order,
            size_key,
        }
    }
}

impl QuerySource<D3> for CameraSamples<'_> {
    fn units(&self) -> usize {
        self.order.len()
    }

    fn points(&self, k: usize, out: &mut Vec<QueryPoint<D3>>) {
        let pixel = self.order[k];
        let ip = &self.params.image;
        for sample in 0..self.params.placed_spp() {
            let (ray, _) = CameraRay::trace(self.scene, &self.cam, pixel, sample, (ip.seed, ip.settings.sampling));
            for (i, t, _) in ray.march(self.params.march_step) {
                let (p, k, i) = (pixel as u64, sample as u64, i as u64);
                out.push(QueryPoint {
                    // The image's size is part of the key: a memo shared by placements
                    // of two sizes (the app's half-size preview, then its full size)
                    // must not hand one size's light field to the other's pixel.
                    key: (self.size_key << 96) | ((p as u128) << 64) | ((k as u128) << 32) | i as u128,
                    id: mix64((p << 32) | k) ^ i,
                    y: ray.at(t),
                });
            }
        }
    }

    fn outgoing(&self, _: DVec3) -> Outgoing<DVec3> {
        Outgoing::TowardsPoint(self.cam.position)
    }
}

/// The cone of `half_angle_deg` at the camera of `params`' image within which
/// records placed for it serve points ([`CameraSamples`]' placement makes the
/// same), None where it does not apply (`pipeline::eye_cone`).
pub fn eye_cone(scene: &Scene, params: &CachedRenderParams, half_angle_deg: Option<f64>) -> Option<EyeCone<D3>> {
    let cam = camera(scene, params.image.width, params.image.height);
    let g = scene.medium.as_ref().map_or(0.0, |m| m.g());
    EyeCone::towards(Outgoing::TowardsPoint(cam.position), half_angle_deg, g)
}

/// Place records over every query point of the window.
pub fn place(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<Placement, Cancelled> {
    place_points(
        scene,
        &CameraSamples::new(scene, params),
        cs,
        &[Cached::Scattered],
        memo,
        progress,
    )
}

/// Place records over every query point of the window, starting from `earlier`
/// (records placed for another camera of the same scene): with moments over ω_o
/// (`CacheSettings::moment_bands`) they serve this camera too, and only the points
/// they leave uncovered get new records. The placement's cost is this walk's.
pub fn place_onto(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    earlier: Placement,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<Placement, Cancelled> {
    let source = CameraSamples::new(scene, params);
    place_points_onto(scene, &source, cs, &[Cached::Scattered], Some(earlier), memo, progress)
}

/// Equal-count mode: search ε until placement makes `target` records (±1%),
/// reusing memoised light fields.
pub fn place_with_count(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    target: usize,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<Placement, CountError> {
    let source = CameraSamples::new(scene, params);
    place_count(scene, &source, cs, &[Cached::Scattered], target, memo, progress)
}

/// A cached render: its placement, the image and the costs.
#[derive(Clone, Debug)]
pub struct CachedRender {
    pub placement: Placement,
    /// The surface cache, when the reflected light is read from one
    /// (`CachedRenderParams::surface_eps`).
    pub surfaces: Option<SurfaceCache>,
    pub reconstruction: Reconstruction,
}

impl CachedRender {
    /// Placements plus reconstruction.
    pub fn seconds(&self) -> f64 {
        self.placement.seconds + self.surfaces.as_ref().map_or(0.0, |s| s.seconds) + self.reconstruction.image.seconds
    }

    pub fn rays(&self) -> u64 {
        self.placement.rays + self.surfaces.as_ref().map_or(0, |s| s.rays) + self.reconstruction.image.rays
    }
}

/// Place (at `cs.eps`, or at the ε giving `target` records) and reconstruct.
pub fn render_cached(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    target: Option<usize>,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<CachedRender, CountError> {
    let placement = match target {
        Some(n) => place_with_count(scene, params, cs, n, memo, progress)?,
        None => place(scene, params, cs, memo, progress)?,
    };
    Ok(reconstructed(scene, params, cs, placement, progress)?)
}

/// [`place_onto`] `earlier` (another camera's records, with moments over ω_o) and
/// reconstruct.
pub fn render_cached_onto(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    earlier: Placement,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<CachedRender, Cancelled> {
    let placement = place_onto(scene, params, cs, earlier, memo, progress)?;
    reconstructed(scene, params, cs, placement, progress)
}

/// The surface cache of the window, when `params.surface_eps` asks for one (its
/// records as `surface_cache::surface_settings` makes them from `cs`).
pub fn place_surfaces(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    progress: &Progress,
) -> Result<Option<SurfaceCache>, Cancelled> {
    let Some(eps) = params.surface_eps else {
        return Ok(None);
    };
    let settings = super::surface_cache::surface_settings(cs, eps);
    super::surface_cache::place(scene, params, &settings, &mut SurfaceMemo::new(), progress).map(Some)
}

/// The image's parameters once `spent` seconds went to records: what is left of a
/// time budget (the placed camera samples are rendered whatever it is).
pub fn image_after(params: &CachedRenderParams, spent: f64) -> CachedRenderParams {
    let mut p = params.clone();
    p.image.time_budget = params.image.time_budget.map(|b| (b - spent).max(0.0));
    p
}

fn reconstructed(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    placement: Placement,
    progress: &Progress,
) -> Result<CachedRender, Cancelled> {
    let second_order = cs.second_order && cs.method == CacheMethod::Ours;
    let surfaces = place_surfaces(scene, params, cs, progress)?;
    let view = CacheView::of(&placement).with_surfaces(surfaces.as_ref());
    let spent = placement.seconds + surfaces.as_ref().map_or(0.0, |s| s.seconds);
    let reconstruction = reconstruct(scene, &image_after(params, spent), view, second_order, progress)?;
    Ok(CachedRender {
        placement,
        surfaces,
        reconstruction,
    })
}
