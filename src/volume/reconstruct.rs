//! Reconstruction of a cached 3D render, and its path-traced twin.
//!
//! Both walk the window's camera samples ([`super::camera_march`]): per sample,
//! T L_o at the first surface (path traced with `surface_paths` samples, or from
//! the surface cache in a cached render that has one) plus
//! Σ_n T(t_n) Δ L_s(t_n) over its march points, where L_s comes from the cache (with
//! the direct part sampled at the point) or is path traced. Sharing the camera rays,
//! march points and surface samples, the two differ only by the cache's error.

use super::cached_params::{CacheView, CachedRenderParams};
use super::lights::Lobe;
use super::lights::{delta_suns, direct_part_with};
pub use super::march_image::Reconstruction;
use super::march_image::{PointLs, SplitMode, march_image, march_point_lights};
use super::mesh::Hit;
use super::scene::Scene;
use super::surface_cache::surface_radiance;
use crate::core::color::Rgb;
use crate::core::rng::{Sampler, mix64};
use crate::core::space::D3;
use crate::pipeline::moments::{MomentQuery, weights_towards};
use crate::pipeline::path::{PointLights, direct_spread, radiance_leaving, sample_at};
use crate::pipeline::placement::{interpolate, interpolate_moments};
use crate::pipeline::sight::near_table;
use crate::pipeline::world::ignore;
use crate::progress::{Cancelled, Progress};
use glam::DVec3;

/// Render the window from the cache: per camera sample, T L_o at the first surface
/// (path traced) plus Σ_n T(t_n) Δ [σ_s·direct + cached L_s] over its march points.
/// Records with moments over ω_o give L_s towards each camera ray's own ω_o.
pub fn reconstruct(
    scene: &Scene,
    params: &CachedRenderParams,
    view: CacheView,
    second_order: bool,
    progress: &Progress,
) -> Result<Reconstruction, Cancelled> {
    // Each row's clone of the closure has its own scratch buffer, and the moments'
    // weights of the ray it is on (ω_o is the same along a camera ray).
    let mut scratch: Vec<(usize, f64)> = Vec::new();
    let mut weights: (DVec3, Vec<f64>) = (DVec3::ZERO, Vec::new());
    let g = scene.medium.as_ref().map_or(0.0, |m| m.g());
    let cache = view.cache;
    // The records' occluders, listed once: most visibility tests need no ray.
    let near = near_table(scene, cache);
    let settings = &params.image.first_vertex_settings();
    let mut surface_scratch: Vec<(usize, f64)> = Vec::new();
    let paths = params.surface_paths;
    let points = match march_point_lights(scene, params) {
        true => PointLights::Left,
        false => PointLights::Included,
    };
    let surface = move |hit: &Hit, dir: DVec3, s: &mut Sampler, rays: &mut u64| {
        let cached = view.surfaces.and_then(|sc| {
            surface_radiance(
                scene,
                sc,
                hit,
                dir,
                (paths, second_order),
                &mut surface_scratch,
                s,
                rays,
            )
        });
        cached.unwrap_or_else(|| radiance_leaving(scene, hit, dir, paths, settings, s, rays).1)
    };
    let mode = match params.adapt_image {
        true => SplitMode::Adaptive {
            direct: view.direct_samples,
            share: params.adapt_march_share,
        },
        false => SplitMode::Fixed,
    };
    march_image(
        scene,
        params,
        mode,
        progress,
        surface,
        move |p, lobe, sigma_s, n, s, rays| {
            let before = *rays;
            let (direct, spread) = match view.direct_samples {
                // The records leave the straight light out: sampled here in full.
                Some(own) => {
                    let (d, spread) = direct_spread(scene, p, (lobe, sigma_s), n.unwrap_or(own), points, s, rays);
                    (d, Some(spread))
                }
                None => (direct_part_with(scene, p, lobe, points, s, rays) * sigma_s, None),
            };
            let direct_rays = *rays - before;
            let cached = match (view.moments, lobe) {
                (Some(table), Lobe::Phase { travel, .. }) => {
                    if weights.0 != *travel || weights.1.is_empty() {
                        let bands = (table[0].moments.len() as f64).sqrt().round() as usize - 1;
                        weights = (*travel, weights_towards::<D3>(g, bands, -*travel));
                    }
                    let query = MomentQuery {
                        weights: &weights.1,
                        omega_o: -*travel,
                        g,
                    };
                    interpolate_moments(
                        scene,
                        (cache, &near),
                        table,
                        &query,
                        p,
                        second_order,
                        &mut scratch,
                        rays,
                    )
                }
                _ => interpolate(
                    scene,
                    (cache, &near, view.eye_cone.as_ref()),
                    p,
                    second_order,
                    &mut scratch,
                    rays,
                ),
            };
            match cached {
                Some(c) => PointLs {
                    value: direct + c,
                    covered: true,
                    direct: spread,
                    direct_rays,
                },
                // Not covered (a camera sample beyond the placed ones, or a tile read from
                // another window's records): path traced, all parts, and counted.
                None => PointLs {
                    value: traced_at(scene, p, lobe, points, settings, s, rays) * sigma_s,
                    ..PointLs::default()
                },
            }
        },
    )
}

/// The same image with L_s path traced at every march point (`paths` samples, all
/// parts) instead of cached: the same camera rays, march points and surface samples
/// as [`reconstruct`] with the same parameters, so the difference between the two
/// is the cache's error alone (common random numbers), up to this estimate's noise.
/// The paths at a point draw from a stream of (`path_seed`, the point), so two
/// references with different path seeds differ by their noise alone.
pub fn march_reference(
    scene: &Scene,
    params: &CachedRenderParams,
    paths: u32,
    path_seed: u64,
    progress: &Progress,
) -> Result<Reconstruction, Cancelled> {
    let paths = paths.max(1);
    let points = match march_point_lights(scene, params) {
        true => PointLights::Left,
        false => PointLights::Included,
    };
    let settings = &params.image.first_vertex_settings();
    let surface = |hit: &Hit, dir: DVec3, s: &mut Sampler, rays: &mut u64| {
        radiance_leaving(scene, hit, dir, params.surface_paths, settings, s, rays).1
    };
    march_image(
        scene,
        params,
        SplitMode::Fixed,
        progress,
        surface,
        |p, lobe, sigma_s, _, _, rays| {
            let point = mix64(p.x.to_bits() ^ mix64(p.y.to_bits() ^ mix64(p.z.to_bits())));
            let mut s = Sampler::new(path_seed, point);
            let mut sum = Rgb::ZERO;
            for _ in 0..paths {
                sum += traced_at(scene, p, lobe, points, settings, &mut s, rays);
            }
            PointLs {
                value: sum * sigma_s / paths as f64,
                covered: true,
                ..PointLs::default()
            }
        },
    )
}

/// One path-traced sample of ∫ f L_i dω at a march point (all parts; without the
/// point lights' light when the camera ray samples it, `super::march_lights`).
fn traced_at(
    scene: &Scene,
    p: DVec3,
    lobe: &Lobe,
    points: PointLights,
    settings: &crate::pipeline::path::Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    let parts = sample_at(scene, p, lobe, None, Rgb::ONE, settings, s, rays);
    match points {
        PointLights::Included => parts.total(),
        // The delta lights' share is deterministic: their directional part alone.
        PointLights::Left => parts.single + parts.multiple + delta_suns(scene, p, lobe, None, rays, &mut ignore),
    }
}
