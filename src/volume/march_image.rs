//! The camera-march image shared by a cached render's reconstruction and its
//! path-traced twin ([`super::reconstruct`]): per camera sample, T L_o at the first
//! surface plus Σ_n T(t_n) Δ L_s(t_n) over its march points ([`super::camera_march`]).
//!
//! Camera samples are taken in passes. Without a time budget or an adaptive split
//! there is one pass of `image.spp` samples. With a time budget
//! (`image.time_budget`: what is left for the image once its records are placed),
//! the samples placement visited come first, then passes that double the count,
//! each started only if the last one's seconds per sample say it ends within the
//! budget: a cache's time saved on records is spent on camera samples, which
//! interpolation makes cheap. With an adaptive split ([`SplitMode::Adaptive`]) the
//! placed samples' statistics choose how the later ones march
//! ([`super::image_split`]); without a time budget, as many of those follow as cost
//! what the rest of `image.spp` would have. A pixel's samples are summed in order
//! whatever the passes, so the image does not depend on them.

use super::cached_params::CachedRenderParams;
use super::camera_march::CameraRay;
use super::image_split::{ImageSplit, MarchSpread, PixelSpread, choose, equal_cost_samples};
use super::lights::Lobe;
use super::mesh::Hit;
use super::render::{Rendered, camera};
use super::scene::Scene;
use crate::core::color::{Rgb, luminance};
use crate::core::rng::Sampler;
use crate::pipeline::path::DirectSpread;
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
    /// How the camera samples beyond the placed ones were taken, when chosen from
    /// the placed ones' statistics ([`SplitMode::Adaptive`]).
    pub split: Option<ImageSplit>,
    /// Every split the placed samples' statistics predicted (`image_split::candidates`).
    pub split_candidates: Vec<ImageSplit>,
}

/// How the camera samples beyond the placed ones march.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SplitMode {
    /// At `CachedRenderParams::march_step_of`, with the view's straight-light samples.
    Fixed,
    /// At the (K, straight-light samples) of least variance × cost measured on the
    /// placed samples ([`super::image_split`]), which march at Δ with `direct`
    /// samples. Without a time budget, as many of them as cost what the image's
    /// remaining camera samples would have cost at Δ.
    Adaptive { direct: Option<u32> },
}

/// L_s(p) towards the camera at one march point.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PointLs {
    pub value: Rgb,
    /// Whether a record covered p (the uncovered are path traced and counted).
    pub covered: bool,
    /// The straight light's spread when it was sampled at p, and its rays.
    pub direct: Option<DirectSpread>,
    pub direct_rays: u64,
}

/// Σ total, Σ medium part, Σ luminance, Σ luminance² of a pixel's samples.
type Pixel = (Rgb, Rgb, f64, f64);

/// The image with L_o at the first surface from `surface(hit, direction, stream,
/// rays)` and L_s(p) towards the camera from `l_s(p, phase lobe, σ_s, straight-light
/// samples (None: the view's), stream, rays)`.
pub(super) fn march_image<G, F>(
    scene: &Scene,
    params: &CachedRenderParams,
    mode: SplitMode,
    progress: &Progress,
    surface: G,
    l_s: F,
) -> Result<Reconstruction, Cancelled>
where
    G: FnMut(&Hit, DVec3, &mut Sampler, &mut u64) -> Rgb + Clone + Send + Sync,
    F: FnMut(DVec3, &Lobe, Rgb, Option<u32>, &mut Sampler, &mut u64) -> PointLs + Clone + Send + Sync,
{
    let start = Instant::now();
    let ip = &params.image;
    let cam = camera(scene, ip.width, ip.height);
    let [x0, y0, x1, y1] = ip.window();
    let (w, h) = (x1 - x0, y1 - y0);
    let mut acc: Vec<Pixel> = vec![(Rgb::ZERO, Rgb::ZERO, 0.0, 0.0); w * h];
    let (mut rays, mut uncovered, mut done, mut per_sample) = (0u64, 0u64, 0u32, 0.0f64);
    let spp = ip.spp.max(1);
    let adaptive = matches!(mode, SplitMode::Adaptive { .. });
    let split_passes = adaptive || ip.time_budget.is_some();
    let first = if split_passes { params.placed_spp() } else { spp };
    let mut split = match mode {
        SplitMode::Adaptive { direct } => ImageSplit::fine(direct),
        SplitMode::Fixed => ImageSplit::fine(None),
    };
    let (mut chosen, mut candidates) = (None, Vec::new());
    let mut end = spp;
    let mut passes = vec![(0, first)];
    progress.start(h as u64);
    while let Some((k0, k1)) = passes.pop() {
        if let Some(budget) = ip.time_budget {
            let predicted = per_sample * (k1 - k0) as f64;
            if done > 0 && start.elapsed().as_secs_f64() + predicted > budget {
                break;
            }
        }
        if done > 0 {
            // Each pass shown on its own (with a time budget their number is unknown).
            progress.start(h as u64);
        }
        let pass_start = Instant::now();
        // The placed samples' statistics, when the rest's split is to be chosen.
        let measure = adaptive && k0 == 0;
        let mut spreads = vec![PixelSpread::default(); if measure { w * h } else { 0 }];
        let rows: Vec<Result<(u64, u64), Cancelled>> = acc
            .par_chunks_mut(w)
            .zip(
                spreads
                    .par_chunks_mut(w.max(1))
                    .map(Some)
                    .chain(rayon::iter::repeat_n((), h).map(|_| None)),
            )
            .enumerate()
            .map(|(row, (pixels, mut spreads))| {
                let (mut l_s, mut surface) = (l_s.clone(), surface.clone());
                let (mut r, mut u) = (0u64, 0u64);
                let j = y0 + row;
                for (x, (i, px)) in (x0..x1).zip(pixels.iter_mut()).enumerate() {
                    progress.check()?;
                    for k in k0..k1 {
                        let at = (j * ip.width + i, k);
                        let mut march = MarchSpread::default();
                        let spread = spreads.is_some().then_some(&mut march);
                        let (total, medium, missed, fixed) = camera_sample(
                            scene,
                            params,
                            &cam,
                            at,
                            &split,
                            (&mut surface, &mut l_s),
                            spread,
                            &mut r,
                        );
                        if let Some(sp) = spreads.as_deref_mut() {
                            sp[x].add((total, medium), fixed, &march);
                        }
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
        if k0 == 0 && first < spp {
            if let SplitMode::Adaptive { direct } = mode {
                (split, candidates) = choose(&spreads, direct);
                chosen = Some(split);
                per_sample *= split.cost_ratio;
                if ip.time_budget.is_none() {
                    end = first + equal_cost_samples(spp - first, &split);
                }
            }
            passes = later_passes(first, end, ip.time_budget.is_some());
        }
    }
    let mut image = finish(acc, (w, h), done.max(1));
    image.rays = rays;
    image.seconds = start.elapsed().as_secs_f64();
    Ok(Reconstruction {
        image,
        uncovered,
        split: chosen,
        split_candidates: candidates,
    })
}

/// The passes after the first `first` samples up to `end`, last first (popped):
/// one, or with a time budget passes doubling the count.
fn later_passes(first: u32, end: u32, doubling: bool) -> Vec<(u32, u32)> {
    let mut v = Vec::new();
    let mut k = first;
    while k < end {
        let n = if doubling { k.max(1).min(end - k) } else { end - k };
        v.push((k, k + n));
        k += n;
    }
    v.reverse();
    v
}

/// One camera sample (`k` of full-image pixel `pixel`): its total, its medium part,
/// its uncovered march points and the rays it traced before marching; its march's
/// statistics into `spread` when given.
#[allow(clippy::too_many_arguments)]
fn camera_sample<G, F>(
    scene: &Scene,
    params: &CachedRenderParams,
    cam: &super::camera::Camera,
    (pixel, k): (usize, u32),
    split: &ImageSplit,
    (surface, l_s): (&mut G, &mut F),
    mut spread: Option<&mut MarchSpread>,
    rays: &mut u64,
) -> (Rgb, Rgb, u64, u64)
where
    G: FnMut(&Hit, DVec3, &mut Sampler, &mut u64) -> Rgb,
    F: FnMut(DVec3, &Lobe, Rgb, Option<u32>, &mut Sampler, &mut u64) -> PointLs,
{
    let rays_before = *rays;
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
    let fixed = *rays - rays_before;
    let (mut medium, mut uncovered) = (Rgb::ZERO, 0u64);
    if let Some(m) = &scene.medium {
        let step = match split.march_factor {
            1 => params.march_step_of(k),
            factor => params.march_step * factor as f64,
        };
        let dt = ray.step(step);
        let lobe = Lobe::Phase {
            phase: m.phase,
            travel: ray.dir,
        };
        for (n, t, weight) in ray.march(step) {
            let p = ray.at(t);
            let before = *rays;
            let v = l_s(p, &lobe, m.sigma_s, split.direct_samples, &mut s, rays);
            uncovered += !v.covered as u64;
            let scale = m.transmittance(ray.origin, ray.dir, t) * weight * dt;
            let c = scale * v.value;
            medium += c;
            if let Some(sp) = spread.as_deref_mut() {
                sp.add(n, c, (luminance(scale), v.direct), (*rays - before, v.direct_rays));
            }
        }
    }
    (at_surface + medium, medium, uncovered, fixed)
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
