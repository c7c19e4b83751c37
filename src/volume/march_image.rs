//! The camera-march image shared by a cached render's reconstruction and its
//! path-traced twin ([`super::reconstruct`]): per camera sample, T L_o at the first
//! surface plus Σ_n T(t_n) Δ L_s(t_n) over its march points ([`super::camera_march`]).
//!
//! Camera samples are taken in passes. Without a time budget or an adaptive split
//! there is one pass of `image.spp` samples. With a time budget
//! (`image.time_budget`: what is left for the image once its records are placed),
//! the samples placement visited come first, then passes that double the count
//! while the last one's seconds per sample say they end within the budget, the
//! last shortened to the samples that fit (`super::render::fitting_pass`): a
//! cache's time saved on records is spent on camera samples, which interpolation
//! makes cheap. With an adaptive split ([`SplitMode::Adaptive`]) the
//! placed samples' statistics choose how the later ones march
//! ([`super::image_split`]); without a time budget, as many of those follow as cost
//! what the rest of `image.spp` would have. A pixel's samples are summed in order
//! whatever the passes, so the image does not depend on them.

use super::cached_params::CachedRenderParams;
use super::camera_march::CameraRay;
use super::image_split::{
    ImageSplit, MarchSpread, PixelSpread, choose, equal_cost_samples, marched_samples, marches, shared_cost_ratio,
};
use super::lights::Lobe;
use super::mesh::Hit;
use super::render::{Rendered, camera, fitting_pass};
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
    /// remaining camera samples would have cost at Δ. With `share`, one camera
    /// sample in m of them marches, m chosen by `image_split::share_cost`.
    Adaptive { direct: Option<u32>, share: bool },
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

/// A pixel's sums: the light from the first surface over all its camera samples,
/// the medium part over the marched ones, and the luminances' moments for its
/// standard error.
#[derive(Clone, Copy, Debug, Default)]
struct Pixel {
    surface: Rgb,
    medium: Rgb,
    /// Σ, Σ² of the surface part's luminance (all samples).
    ys: (f64, f64),
    /// Σ, Σ² of the medium part's luminance, Σ of the surface part's and of their
    /// product (marched samples).
    ym: (f64, f64),
    ys_marched: f64,
    ysm: f64,
}

impl Pixel {
    fn add(&mut self, surface: Rgb, medium: Option<Rgb>) {
        let y = luminance(surface);
        self.surface += surface;
        self.ys = (self.ys.0 + y, self.ys.1 + y * y);
        if let Some(m) = medium {
            let ym = luminance(m);
            self.medium += m;
            self.ym = (self.ym.0 + ym, self.ym.1 + ym * ym);
            self.ys_marched += y;
            self.ysm += y * ym;
        }
    }
}

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
    let mut acc: Vec<Pixel> = vec![Pixel::default(); w * h];
    let (mut rays, mut uncovered, mut done, mut per_sample) = (0u64, 0u64, 0u32, 0.0f64);
    let spp = ip.spp.max(1);
    let adaptive = matches!(mode, SplitMode::Adaptive { .. });
    let split_passes = adaptive || ip.time_budget.is_some();
    let first = if split_passes { params.placed_spp() } else { spp };
    let mut split = match mode {
        SplitMode::Adaptive { direct, .. } => ImageSplit::fine(direct),
        SplitMode::Fixed => ImageSplit {
            march_every: params.image_march_every.unwrap_or(1),
            ..ImageSplit::fine(None)
        },
    };
    let placed = params.placed_spp();
    let (mut chosen, mut candidates) = (None, Vec::new());
    let mut end = spp;
    let mut passes = vec![(0, first)];
    progress.start(h as u64);
    while let Some(pass) = passes.pop() {
        let (k0, k1) = match ip.time_budget {
            Some(budget) if done > 0 => match fitting_pass(pass, start.elapsed().as_secs_f64(), budget, per_sample) {
                Some(p) => p,
                None => break,
            },
            _ => pass,
        };
        if (k0, k1) != pass {
            passes.clear(); // a shortened pass is the last
        }
        if done > 0 {
            // Each pass shown on its own (with a time budget their number is unknown).
            progress.start(h as u64);
        }
        let pass_start = Instant::now();
        // The placed samples' statistics, when the rest's split is to be chosen.
        let measure = adaptive && k0 == 0;
        let mut spreads = vec![PixelSpread::default(); if measure { w * h } else { 0 }];
        let rows: Vec<Result<(u64, u64, u64), Cancelled>> = acc
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
                let (mut r, mut u, mut f) = (0u64, 0u64, 0u64);
                let j = y0 + row;
                for (x, (i, px)) in (x0..x1).zip(pixels.iter_mut()).enumerate() {
                    progress.check()?;
                    for k in k0..k1 {
                        let at = (j * ip.width + i, k);
                        let mut march = MarchSpread::default();
                        let spread = spreads.is_some().then_some(&mut march);
                        let (at_surface, medium, missed, fixed) = camera_sample(
                            scene,
                            params,
                            &cam,
                            at,
                            (&split, marches(k, placed, &split)),
                            (&mut surface, &mut l_s),
                            spread,
                            &mut r,
                        );
                        if let (Some(sp), Some(m)) = (spreads.as_deref_mut(), medium) {
                            sp[x].add((at_surface + m, m), fixed, &march);
                        }
                        u += missed;
                        f += fixed;
                        px.add(at_surface, medium);
                    }
                }
                progress.advance(1);
                Ok((r, u, f))
            })
            .collect();
        let (mut pass_rays, mut pass_fixed) = (0u64, 0u64);
        for row in rows {
            let (r, u, f) = row?;
            (pass_rays, pass_fixed) = (pass_rays + r, pass_fixed + f);
            uncovered += u;
        }
        rays += pass_rays;
        per_sample = pass_start.elapsed().as_secs_f64() / (k1 - k0) as f64;
        done = k1;
        if k0 == 0 && first < spp {
            match mode {
                SplitMode::Adaptive { direct, share } => {
                    (split, candidates) = choose(&spreads, direct, share);
                    chosen = Some(split);
                    per_sample *= split.cost_ratio;
                    if ip.time_budget.is_none() {
                        end = first + equal_cost_samples(spp - first, &split);
                    }
                }
                // A share given: the later samples cost less than the placed ones,
                // which all marched (else a time budget's first later pass would
                // be sized for the placed samples' cost and cut short).
                SplitMode::Fixed => per_sample *= shared_cost_ratio(pass_fixed, pass_rays, split.march_every),
            }
            passes = later_passes(first, end, ip.time_budget.is_some());
        }
    }
    let mut image = finish(acc, (w, h), (done.max(1), marched_samples(done, placed, &split).max(1)));
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

/// One camera sample (`k` of full-image pixel `pixel`): the light from its first
/// surface, its medium part (None when it does not march), its uncovered march
/// points and the rays it traced before marching; its march's statistics into
/// `spread` when given.
#[allow(clippy::too_many_arguments)]
fn camera_sample<G, F>(
    scene: &Scene,
    params: &CachedRenderParams,
    cam: &super::camera::Camera,
    (pixel, k): (usize, u32),
    (split, march): (&ImageSplit, bool),
    (surface, l_s): (&mut G, &mut F),
    mut spread: Option<&mut MarchSpread>,
    rays: &mut u64,
) -> (Rgb, Option<Rgb>, u64, u64)
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
    if !march {
        return (at_surface, None, 0, fixed);
    }
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
        if march_point_lights(scene, params) {
            // A stream of the camera sample's own, so that the cached render and its
            // path-traced twin draw the same distances (common random numbers).
            let mut own = Sampler::new2(params.image.seed ^ 0x9017_11E5, pixel as u64, k as u64);
            medium += super::march_lights::point_lights_along(scene, &ray, dt, &mut own, rays);
        }
    }
    (at_surface, Some(medium), uncovered, fixed)
}

/// Are the point lights sampled along each camera ray (`super::march_lights`)
/// rather than at the march points (which then leave them out)?
pub(super) fn march_point_lights(scene: &Scene, params: &CachedRenderParams) -> bool {
    params.image.settings.point_legs && scene.medium.is_some() && !scene.point_lights.is_empty()
}

/// The image of `n` samples per pixel, `n_marched` of them marched, from their
/// sums: the surface part's mean over all, the medium part's over the marched
/// ones. The standard error is that of this sum: Var(S)/n + Var(M)/n_marched +
/// 2 Cov(S, M)/n (the marched samples are among all of them), each moment
/// estimated over the samples that have it.
fn finish(acc: Vec<Pixel>, (w, h): (usize, usize), (n, n_marched): (u32, u32)) -> Rendered {
    let (nf, nm) = (n as f64, n_marched as f64);
    let mut image = Rendered {
        width: w,
        height: h,
        values: Vec::with_capacity(w * h),
        medium: Vec::with_capacity(w * h),
        std_error: Vec::with_capacity(w * h),
        spp: n,
        rays: 0,
        seconds: 0.0,
    };
    // The samples' (biased) second central moment, divided by count − 1: the
    // squared standard error of their mean, as the path tracer's.
    let spread = |(s, s2): (f64, f64), k: f64| (s2 / k - (s / k).powi(2)).max(0.0) / (k - 1.0).max(1.0);
    for p in acc {
        let medium = p.medium / nm;
        image.values.push(p.surface / nf + medium);
        image.medium.push(medium);
        let cov = (p.ysm / nm - p.ys_marched / nm * p.ym.0 / nm) / (nm - 1.0).max(1.0) * nm / nf;
        let se2 = spread(p.ys, nf) + spread(p.ym, nm) + 2.0 * cov;
        image.std_error.push(se2.max(0.0).sqrt());
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With one sample in m marched, the pixel is the surface's mean over all
    /// samples plus the medium's over the marched ones, and its standard error
    /// that of this sum: checked against the moments computed directly.
    #[test]
    fn a_pixel_averages_each_part_over_its_own_samples() {
        let surface = [0.3, 0.9, 0.1, 0.5, 0.7, 0.2, 0.4, 0.8];
        let medium = [(0, 0.2), (3, 0.5), (6, 0.1)];
        let mut p = Pixel::default();
        for (k, s) in surface.iter().enumerate() {
            let m = medium.iter().find(|(j, _)| *j == k).map(|(_, v)| Rgb::splat(*v));
            p.add(Rgb::splat(*s), m);
        }
        let img = finish(vec![p], (1, 1), (8, 3));
        let ms: f64 = surface.iter().sum::<f64>() / 8.0;
        let mm: f64 = medium.iter().map(|(_, v)| v).sum::<f64>() / 3.0;
        assert!((luminance(img.values[0]) - (ms + mm)).abs() < 1e-12);
        assert!((luminance(img.medium[0]) - mm).abs() < 1e-12);
        // Unbiased variances and covariance over the samples that have them.
        let vs = surface.iter().map(|s| (s - ms).powi(2)).sum::<f64>() / 7.0;
        let vm = medium.iter().map(|(_, v)| (v - mm).powi(2)).sum::<f64>() / 2.0;
        let sm: Vec<f64> = medium.iter().map(|(j, _)| surface[*j]).collect();
        let msm = sm.iter().sum::<f64>() / 3.0;
        let c = medium
            .iter()
            .zip(&sm)
            .map(|((_, v), s)| (v - mm) * (s - msm))
            .sum::<f64>()
            / 2.0;
        let se = (vs / 8.0 + vm / 3.0 + 2.0 * c / 8.0).sqrt();
        assert!((img.std_error[0] - se).abs() < 1e-12, "{} vs {se}", img.std_error[0]);
    }
}
