//! The camera-march image shared by a cached render's reconstruction and its
//! path-traced twin ([`super::reconstruct`]): per camera sample, T L_o at the first
//! surface plus Σ_n T(t_n) Δ L_s(t_n) over its march points ([`super::camera_march`]).
//!
//! Camera samples are taken in passes. Without a time budget there is one pass of
//! `image.spp` samples. With one (`image.time_budget`: what is left for the image
//! once its records are placed), the samples placement visited come first, then
//! passes that double the count, each started only if the last one's seconds per
//! sample say it ends within the budget: a cache's time saved on records is spent
//! on camera samples, which interpolation makes cheap. A pixel's samples are summed
//! in order whatever the passes, so the image does not depend on them.

use super::cached_params::CachedRenderParams;
use super::camera_march::CameraRay;
use super::lights::Lobe;
use super::mesh::Hit;
use super::render::{Rendered, camera};
use super::scene::Scene;
use crate::core::color::{Rgb, luminance};
use crate::core::rng::Sampler;
use crate::pipeline::world::World;
use crate::progress::{Cancelled, Progress};
use glam::DVec3;
use rayon::prelude::*;
use std::time::Instant;

/// A reconstructed image and its cost.
#[derive(Clone, Debug)]
pub struct Reconstruction {
    pub image: Rendered,
    /// March points no visible record covered, path traced instead (zero after a
    /// placement of the same window and samples; camera samples beyond the placed
    /// ones, or a tile rendered with another window's records, may have some).
    pub uncovered: u64,
}

/// Σ total, Σ medium part, Σ luminance, Σ luminance² of a pixel's samples.
type Pixel = (Rgb, Rgb, f64, f64);

/// The image with L_o at the first surface from `surface(hit, direction, stream,
/// rays)` and L_s(p) towards the camera from `l_s(p, phase lobe, σ_s, stream, rays)`
/// → (value, whether a record covered p; the uncovered are counted).
pub(super) fn march_image<G, F>(
    scene: &Scene,
    params: &CachedRenderParams,
    progress: &Progress,
    surface: G,
    l_s: F,
) -> Result<Reconstruction, Cancelled>
where
    G: FnMut(&Hit, DVec3, &mut Sampler, &mut u64) -> Rgb + Clone + Send + Sync,
    F: FnMut(DVec3, &Lobe, Rgb, &mut Sampler, &mut u64) -> (Rgb, bool) + Clone + Send + Sync,
{
    let start = Instant::now();
    let ip = &params.image;
    let cam = camera(scene, ip.width, ip.height);
    let [x0, y0, x1, y1] = ip.window();
    let (w, h) = (x1 - x0, y1 - y0);
    let mut acc: Vec<Pixel> = vec![(Rgb::ZERO, Rgb::ZERO, 0.0, 0.0); w * h];
    let (mut rays, mut uncovered, mut done, mut per_sample) = (0u64, 0u64, 0u32, 0.0f64);
    progress.start(h as u64);
    for (k0, k1) in sample_passes(params) {
        if let Some(budget) = ip.time_budget {
            let predicted = per_sample * (k1 - k0) as f64;
            if done > 0 && start.elapsed().as_secs_f64() + predicted > budget {
                break;
            }
            if done > 0 {
                progress.start(h as u64); // the number of passes is unknown: show each pass
            }
        }
        let pass_start = Instant::now();
        let rows: Vec<Result<(u64, u64), Cancelled>> = acc
            .par_chunks_mut(w)
            .enumerate()
            .map(|(row, pixels)| {
                let (mut l_s, mut surface) = (l_s.clone(), surface.clone());
                let (mut r, mut u) = (0u64, 0u64);
                let j = y0 + row;
                for (i, px) in (x0..x1).zip(pixels.iter_mut()) {
                    progress.check()?;
                    for k in k0..k1 {
                        let at = (j * ip.width + i, k);
                        let (total, medium, missed) =
                            camera_sample(scene, params, &cam, at, (&mut surface, &mut l_s), &mut r);
                        u += missed;
                        let y = luminance(total);
                        *px = (px.0 + total, px.1 + medium, px.2 + y, px.3 + y * y);
                    }
                }
                progress.advance(1);
                Ok((r, u))
            })
            .collect();
        for row in rows {
            let (r, u) = row?;
            rays += r;
            uncovered += u;
        }
        per_sample = pass_start.elapsed().as_secs_f64() / (k1 - k0) as f64;
        done = k1;
    }
    let mut image = finish(acc, (w, h), done.max(1));
    image.rays = rays;
    image.seconds = start.elapsed().as_secs_f64();
    Ok(Reconstruction { image, uncovered })
}

/// One camera sample (`k` of full-image pixel `pixel`): its total, its medium part
/// and its uncovered march points.
fn camera_sample<G, F>(
    scene: &Scene,
    params: &CachedRenderParams,
    cam: &super::camera::Camera,
    (pixel, k): (usize, u32),
    (surface, l_s): (&mut G, &mut F),
    rays: &mut u64,
) -> (Rgb, Rgb, u64)
where
    G: FnMut(&Hit, DVec3, &mut Sampler, &mut u64) -> Rgb,
    F: FnMut(DVec3, &Lobe, Rgb, &mut Sampler, &mut u64) -> (Rgb, bool),
{
    let (ray, mut s) = CameraRay::trace(
        scene,
        cam,
        pixel,
        k,
        (params.image.seed, params.image.settings.sampling),
    );
    *rays += 1;
    let end = ray.hit.map_or_else(|| scene.world_exit(ray.origin, ray.dir), |h| h.t);
    let t_end = scene
        .medium
        .as_ref()
        .map_or(Rgb::ONE, |m| m.transmittance(ray.origin, ray.dir, end));
    let at_surface = t_end
        * match &ray.hit {
            Some(hit) => surface(hit, ray.dir, &mut s, rays),
            None => scene.escaped(ray.dir, None),
        };
    let (mut medium, mut uncovered) = (Rgb::ZERO, 0u64);
    if let Some(m) = &scene.medium {
        let step = params.march_step_of(k);
        let dt = ray.step(step);
        let lobe = Lobe::Phase {
            phase: m.phase,
            travel: ray.dir,
        };
        for (_, t, weight) in ray.march(step) {
            let p = ray.at(t);
            let (v, covered) = l_s(p, &lobe, m.sigma_s, &mut s, rays);
            uncovered += !covered as u64;
            medium += m.transmittance(ray.origin, ray.dir, t) * weight * v * dt;
        }
    }
    (at_surface + medium, medium, uncovered)
}

/// Without a time budget, one pass of all `image.spp` samples; with one, the
/// samples placement visited, then passes doubling the count up to `image.spp`.
fn sample_passes(params: &CachedRenderParams) -> Vec<(u32, u32)> {
    let spp = params.image.spp.max(1);
    if params.image.time_budget.is_none() {
        return vec![(0, spp)];
    }
    let first = params.placed_spp();
    let mut v = vec![(0, first)];
    let mut k = first;
    while k < spp {
        let n = k.min(spp - k);
        v.push((k, k + n));
        k += n;
    }
    v
}

/// The image of `n` samples per pixel from their sums.
fn finish(acc: Vec<Pixel>, (w, h): (usize, usize), n: u32) -> Rendered {
    let n = n as f64;
    let mut image = Rendered {
        width: w,
        height: h,
        values: Vec::with_capacity(w * h),
        medium: Vec::with_capacity(w * h),
        std_error: Vec::with_capacity(w * h),
        spp: n as u32,
        rays: 0,
        seconds: 0.0,
    };
    for (total, medium, sy, sy2) in acc {
        image.values.push(total / n);
        image.medium.push(medium / n);
        let mean = sy / n;
        image
            .std_error
            .push(((sy2 / n - mean * mean).max(0.0) / (n - 1.0).max(1.0)).sqrt());
    }
    image
}
