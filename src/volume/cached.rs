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
//! is path traced per camera sample, as in the reference.
//!
//! Placement walks the query points of the window ([`super::camera_march`]: every
//! camera sample's march points) pixel by pixel in a coarse-to-fine order and
//! creates a record wherever no record that sees the point covers it, so the
//! reconstruction has no holes. Batches of pixels are checked in parallel against
//! the cache as it was at the batch's start, then their uncovered points are
//! re-checked and filled in order: the result does not depend on the thread count.
//! Each record's light field is captured in parallel over its rays. Methods:
//! - `ours`: occlusion-aware gradient and Hessian (`derivatives::aware`), extent =
//!   the seed's Hessian ellipsoid;
//! - `jarosz08`: occlusion-unaware gradient (`derivatives::unaware`), extent = the
//!   gradient ball.
//!
//! Both store the light field's plain Monte Carlo estimate as the value, so at equal
//! record positions they differ only in derivatives and extents.
//!
//! Light fields are memoised per query point ([`RecordMemo`]) with the seconds they
//! took, so an equal-count search pays for each point once and a placement's time
//! is still what a fresh placement would take (checks plus its records' capture).

use super::camera_march::{CameraRay, QueryKey};
use super::derivatives::{AwareSettings, aware, plain_estimate, unaware};
use super::probe::{Outgoing, ProbeSettings, capture_towards};
use super::proxy;
pub use super::reconstruct::{Reconstruction, march_reference, reconstruct};
use super::render::{RenderParams, camera};
use super::scene::Scene;
use crate::core::cache::{Cache, Record, placement_order};
use crate::core::color::luminance;
use crate::core::metric::{CacheMethod, MetricParams, with_radiance_floor};
use crate::core::rng::mix64;
use crate::core::space::D3;
use crate::core::taylor_rgb::TaylorRgb;
use crate::progress::{Cancelled, Progress};
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;
use std::time::Instant;

/// Pixels checked in parallel before their uncovered points are filled in order.
/// A constant, so that placement does not depend on the thread count.
const BATCH_PIXELS: usize = 64;

/// How a cache is built.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CacheSettings {
    pub method: CacheMethod,
    /// Error threshold ε (theory.md §6: length³ for ours, dimensionless for jarosz08).
    pub eps: f64,
    pub probe: ProbeSettings,
    pub aware: AwareSettings,
    /// Second-order interpolation (ours only; the baseline has no Hessian).
    pub second_order: bool,
    /// Fraction of the mean element radiance added before the metric's Hessian.
    pub hessian_floor: f64,
    /// Seed of the records' light fields.
    pub seed: u64,
}

impl CacheSettings {
    pub fn new(method: CacheMethod, eps: f64) -> Self {
        CacheSettings {
            method,
            eps,
            probe: ProbeSettings::default(),
            aware: AwareSettings::default(),
            second_order: false,
            hessian_floor: 0.01,
            seed: 1,
        }
    }

    /// A starting ε for a scene: ours' ε is a volume (scaled with the scene), the
    /// baseline's a fraction.
    pub fn default_eps(method: CacheMethod, scene: &Scene) -> f64 {
        match method {
            CacheMethod::Ours => 1e-4 * scene.scale.powi(3),
            CacheMethod::Jarosz08 => 0.1,
        }
    }

    pub fn metric(&self, scene: &Scene) -> MetricParams {
        MetricParams::scene_relative(scene.scale, self.eps)
    }
}

/// The image a cached render covers and how camera rays are marched.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CachedRenderParams {
    /// Size, window, camera samples per pixel, seed, path settings (no time budget).
    pub image: RenderParams,
    /// Distance Δ between march points along camera rays (scene units).
    pub march_step: f64,
    /// Reflected-light samples (NEE + a path each) per camera sample at the first
    /// surface: surfaces are path traced as in the reference, at a cost far below
    /// a record's, so they need not be the noise floor of a cached image.
    pub surface_paths: u32,
}

impl CachedRenderParams {
    pub fn from_scene(scene: &Scene) -> Self {
        CachedRenderParams {
            image: RenderParams::from_scene(scene),
            march_step: scene.scale / 128.0,
            surface_paths: 4,
        }
    }
}

/// What one light field gives a record, kept to re-derive extents for another ε.
#[derive(Clone, Debug)]
pub struct RecordData {
    /// Single + multiple scattered L_s towards the camera, with derivatives.
    pub value: TaylorRgb<D3>,
    /// Luminance Hessian the metric uses (with the radiance floor; zero for jarosz08).
    pub metric_hessian: DMat3,
    pub rays: u64,
    /// Wall time of the capture and derivatives.
    pub seconds: f64,
}

/// Light fields per query point, shared by placements of the same scene, method,
/// probe settings and image.
pub type RecordMemo = HashMap<QueryKey, RecordData>;

pub type RadianceCache = Cache<D3, TaylorRgb<D3>>;

/// A placed cache and what placing it cost.
#[derive(Clone, Debug)]
pub struct Placement {
    pub cache: RadianceCache,
    pub eps: f64,
    /// Query points visited (every march point of every camera sample).
    pub query_points: u64,
    /// Rays of the records' light fields plus the visibility tests of the checks.
    pub rays: u64,
    /// Coverage checks plus the capture time of every record used.
    pub seconds: f64,
}

/// One record, for figures and JSON.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RecordInfo {
    pub position: DVec3,
    /// Unit axes of the extent and their radii.
    pub axes: [DVec3; 3],
    pub radii: [f64; 3],
    pub luminance: f64,
    pub rays: u64,
}

impl Placement {
    pub fn records(&self) -> Vec<RecordInfo> {
        self.cache
            .records()
            .iter()
            .map(|r| RecordInfo {
                position: r.position,
                axes: [r.extent.axes.x_axis, r.extent.axes.y_axis, r.extent.axes.z_axis],
                radii: r.extent.radii.to_array(),
                luminance: luminance(r.value.value()),
                rays: r.cost_rays,
            })
            .collect()
    }
}

/// A record at x may be used at y: it sees y (a record never extrapolates across a
/// surface, where radiance jumps).
pub(crate) fn sees(scene: &Scene, x: DVec3, y: DVec3, rays: &mut u64) -> bool {
    let d = y - x;
    let len = d.length();
    if len == 0.0 {
        return true;
    }
    *rays += 1;
    !scene.occluded(x, d / len, len, None)
}

/// The light field at query point `y` and what the method derives from it.
pub fn compute_record(
    scene: &Scene,
    y: DVec3,
    eye: DVec3,
    cs: &CacheSettings,
    key: QueryKey,
    progress: &Progress,
) -> Result<RecordData, Cancelled> {
    let start = Instant::now();
    let id = mix64(((key.0 as u64) << 32) | key.1 as u64) ^ key.2 as u64;
    let seed = mix64(cs.seed ^ mix64(id));
    let lf = capture_towards(scene, y, Outgoing::TowardsPoint(eye), &cs.probe, seed, 0, progress)?;
    let (value, metric_hessian) = match cs.method {
        CacheMethod::Ours => {
            let elements = proxy::build(&lf, cs.aware.rule);
            let parts = aware(&lf, &elements, &cs.aware);
            let floored = aware(&lf, &with_radiance_floor(&elements, cs.hessian_floor), &cs.aware);
            // The value is the light field's plain Monte Carlo estimate (unbiased, as
            // the baseline's); the proxy gives the derivatives. The proxy's own value
            // is 4–8% low where emitters' outlines cross the direction triangles (the
            // farther-vertex rule darkens them), which would bias every pixel.
            let [_, single, multiple] = plain_estimate(&lf);
            let mut value = parts.single + parts.multiple;
            let mean = single + multiple;
            for (c, ch) in value.channels.iter_mut().enumerate() {
                ch.value = mean[c];
            }
            (value, (floored.single + floored.multiple).luminance().hess)
        }
        CacheMethod::Jarosz08 => {
            let parts = unaware(&lf);
            (parts.single + parts.multiple, DMat3::ZERO)
        }
    };
    Ok(RecordData {
        value,
        metric_hessian,
        rays: lf.cost_rays,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The window's full-image pixel indices in placement order.
fn window_order(p: &RenderParams) -> Vec<usize> {
    let [x0, y0, x1, y1] = p.window();
    let (w, h) = (x1 - x0, y1 - y0);
    placement_order(w, h)
        .into_iter()
        .map(|k| (y0 + k / w) * p.width + x0 + k % w)
        .collect()
}

/// Place records over every query point of the window (see the module docs).
pub fn place(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<Placement, Cancelled> {
    let start = Instant::now();
    let ip = &params.image;
    let cam = camera(scene, ip.width, ip.height);
    let metric = cs.metric(scene);
    let order = window_order(ip);
    progress.start(order.len() as u64);
    let mut cache = RadianceCache::new();
    let (mut query_points, mut rays, mut records_seconds, mut capture_wall) = (0u64, 0u64, 0.0, 0.0);
    for batch in order.chunks(BATCH_PIXELS) {
        progress.check()?;
        // Per pixel: its uncovered points in order, its query points, the checks' rays.
        type Pending = (Vec<(QueryKey, DVec3)>, u64, u64);
        let pending: Vec<Pending> = batch
            .par_iter()
            .map(|&pixel| {
                let (mut out, mut n, mut r) = (Vec::new(), 0u64, 0u64);
                for k in 0..ip.spp {
                    let (ray, _) = CameraRay::trace(scene, &cam, pixel, k, ip.seed);
                    for (i, t) in ray.march(params.march_step) {
                        let y = ray.at(t);
                        n += 1;
                        if !cache.is_covered_where(y, |x| sees(scene, x, y, &mut r)) {
                            out.push(((pixel as u32, k, i as u32), y));
                        }
                    }
                }
                (out, n, r)
            })
            .collect();
        for (points, n, r) in pending {
            query_points += n;
            rays += r;
            for (key, y) in points {
                if cache.is_covered_where(y, |x| sees(scene, x, y, &mut rays)) {
                    continue;
                }
                let d = match memo.entry(key) {
                    std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                    std::collections::hash_map::Entry::Vacant(e) => {
                        let t = Instant::now();
                        let d = compute_record(scene, y, cam.position, cs, key, progress)?;
                        capture_wall += t.elapsed().as_secs_f64();
                        e.insert(d)
                    }
                };
                rays += d.rays;
                records_seconds += d.seconds;
                let record = Record {
                    position: y,
                    value: d.value,
                    extent: cs.method.extent(&d.value.luminance(), d.metric_hessian, &metric),
                    cost_rays: d.rays,
                };
                // A non-finite light field is refused by the cache: the point stays
                // uncovered (reported by the reconstruction) rather than failing.
                let _ = cache.insert(record);
            }
        }
        progress.advance(batch.len() as u64);
    }
    Ok(Placement {
        cache,
        eps: cs.eps,
        query_points,
        rays,
        seconds: start.elapsed().as_secs_f64() - capture_wall + records_seconds,
    })
}

/// Equal-count mode: search ε (`core::equal_count`) until placement makes `target`
/// records (±1%), reusing memoised light fields.
pub fn place_with_count(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    target: usize,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<Placement, Cancelled> {
    let tol = (target as f64 * 0.01).max(1.0);
    let (placement, _) = crate::core::equal_count::search_eps(target, tol, cs.eps, |eps| {
        let c = CacheSettings { eps, ..cs.clone() };
        place(scene, params, &c, memo, progress).map(|p| (p.cache.len(), p))
    })?;
    Ok(placement)
}

/// A cached render: its placement, the image and the costs.
#[derive(Clone, Debug)]
pub struct CachedRender {
    pub placement: Placement,
    pub reconstruction: Reconstruction,
}

impl CachedRender {
    /// Placement plus reconstruction.
    pub fn seconds(&self) -> f64 {
        self.placement.seconds + self.reconstruction.image.seconds
    }

    pub fn rays(&self) -> u64 {
        self.placement.rays + self.reconstruction.image.rays
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
) -> Result<CachedRender, Cancelled> {
    let placement = match target {
        Some(n) => place_with_count(scene, params, cs, n, memo, progress)?,
        None => place(scene, params, cs, memo, progress)?,
    };
    let second_order = cs.second_order && cs.method == CacheMethod::Ours;
    let reconstruction = reconstruct(scene, params, &placement.cache, second_order, progress)?;
    Ok(CachedRender {
        placement,
        reconstruction,
    })
}
