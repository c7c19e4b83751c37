//! Progressive image rendering with the reference path tracer.
//!
//! Samples are added in passes of 1, 1, 2, 4, … samples per pixel; sample k of
//! pixel (i, j) always draws from the stream (seed, j·W + i, k) of the *full* image,
//! so the image depends only on the number of samples — not on threads, on the
//! pass schedule or on the crop window (crops of one image tile it exactly). A time
//! budget shortens the first pass that would not fit to the samples that do
//! ([`fitting_pass`]) and stops there, so a budget only changes how many samples
//! were taken (reported).

use super::camera::Camera;
use super::scene::Scene;
use crate::core::color::{Rgb, luminance};
use crate::core::rng::Sampler;
use crate::pipeline::path::{Sampling, Settings, radiance_path_parts};
use crate::pipeline::world::World;
use crate::progress::{Cancelled, Progress};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct RenderParams {
    /// Full image size.
    pub width: usize,
    pub height: usize,
    /// Pixel window [x0, x1) × [y0, y1) of the full image to render (None: all).
    pub crop: Option<[usize; 4]>,
    /// Samples per pixel (the most, with a time budget).
    pub spp: u32,
    pub seed: u64,
    /// Seconds; stop before a pass that would exceed it.
    pub time_budget: Option<f64>,
    pub settings: Settings,
}

impl RenderParams {
    pub fn from_scene(scene: &Scene) -> Self {
        let r = &scene.desc.render;
        RenderParams {
            width: r.resolution[0] as usize,
            height: r.resolution[1] as usize,
            crop: None,
            spp: r.spp,
            seed: r.seed,
            time_budget: None,
            // Independent camera samples in 3D by default: with a stratified set
            // the surface cache's image measured worse against a reference that
            // shares its camera samples (tests/volume_surface_cache.rs: RMSE 0.023
            // against 0.010), not yet understood; `render3d --sampling
            // stratified` asks for it.
            settings: Settings {
                max_depth: r.max_depth,
                sampling: Sampling::Independent,
                ..Settings::default()
            },
        }
    }

    /// The path settings of the light at a camera ray's first vertex (a march
    /// point, the first surface, a record serving them): `settings` past 1, so that
    /// an image assembled there holds the orders a camera path holds, no more
    /// (at `max_depth` 1 a cached image held 0.40 more than path tracing's 0.114).
    pub fn first_vertex_settings(&self) -> Settings {
        self.settings.past(1)
    }

    /// The window rendered: [x0, y0, x1, y1].
    pub fn window(&self) -> [usize; 4] {
        self.crop.unwrap_or([0, 0, self.width, self.height])
    }
}

/// A rendered image (the crop window), linear RGB radiance, row 0 on top.
#[derive(Clone, Debug)]
pub struct Rendered {
    pub width: usize,
    pub height: usize,
    pub values: Vec<Rgb>,
    /// The part of `values` in-scattered by the medium along the camera rays
    /// (∫ T L_s dt); the rest is light from surfaces and the sky (T L_o).
    pub medium: Vec<Rgb>,
    /// Per pixel standard error of the luminance.
    pub std_error: Vec<f64>,
    /// Samples per pixel actually taken.
    pub spp: u32,
    pub rays: u64,
    pub seconds: f64,
}

impl Rendered {
    /// Mean luminance standard error relative to the mean luminance.
    pub fn relative_std_error(&self) -> f64 {
        let n = self.values.len().max(1) as f64;
        let mean = self.values.iter().map(|v| luminance(*v)).sum::<f64>() / n;
        let se = (self.std_error.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        if mean > 0.0 { se / mean } else { 0.0 }
    }
}

/// The scene's camera for an image of `width` × `height`.
pub fn camera(scene: &Scene, width: usize, height: usize) -> Camera {
    let c = &scene.desc.camera;
    let v = DVec3::from_array;
    Camera::new(v(c.position), v(c.look_at), v(c.up), c.fov_deg, width, height)
}

/// The pass sizes: 1, 1, 2, 4, … up to `spp` in total.
fn passes(spp: u32) -> Vec<(u32, u32)> {
    let mut v = Vec::new();
    let mut k = 0;
    while k < spp {
        let n = k.max(1).min(spp - k);
        v.push((k, k + n));
        k += n;
    }
    v
}

/// Share of a time budget's remaining seconds a last, shortened pass is sized to
/// fill (its seconds per sample are predicted from the pass before it).
const LAST_PASS_FILL: f64 = 0.9;

/// The pass `(k0, k1)` if `per_sample` seconds a sample say it ends within
/// `budget` seconds of which `elapsed` are spent; else the samples that fit
/// (shortened: the last pass), or None when none does. Doubling passes alone
/// would leave up to half a budget unspent.
pub(super) fn fitting_pass((k0, k1): (u32, u32), elapsed: f64, budget: f64, per_sample: f64) -> Option<(u32, u32)> {
    if elapsed + per_sample * (k1 - k0) as f64 <= budget {
        return Some((k0, k1));
    }
    let fit = LAST_PASS_FILL * (budget - elapsed) / per_sample;
    (fit >= 1.0).then(|| (k0, k0 + (fit as u32).min(k1 - k0)))
}

/// Render the window of the image. Cancellation is checked per pixel; progress
/// counts rows of passes (with a time budget: rows of the current pass).
pub fn render(scene: &Scene, params: &RenderParams, progress: &Progress) -> Result<Rendered, Cancelled> {
    let start = Instant::now();
    let cam = camera(scene, params.width, params.height);
    let [x0, y0, x1, y1] = params.window();
    let (w, h) = (x1 - x0, y1 - y0);
    let schedule = passes(params.spp);
    progress.start((h * schedule.len()) as u64);
    // Per pixel: Σ radiance, Σ luminance, Σ luminance², Σ medium part.
    let mut acc = vec![(Rgb::ZERO, 0.0, 0.0, Rgb::ZERO); w * h];
    // Seconds per sample of the last pass predict the next one.
    let (mut rays, mut done, mut per_sample) = (0u64, 0u32, 0.0f64);
    for &pass in &schedule {
        let (k0, k1) = match params.time_budget {
            Some(budget) if done > 0 => match fitting_pass(pass, start.elapsed().as_secs_f64(), budget, per_sample) {
                Some(p) => p,
                None => break,
            },
            _ => pass,
        };
        if params.time_budget.is_some() {
            progress.start(h as u64); // the number of passes is unknown: show each pass
        }
        let pass_start = Instant::now();
        let pass_rays: Vec<u64> = acc
            .par_chunks_mut(w)
            .enumerate()
            .map(|(row, px)| -> Result<u64, Cancelled> {
                let j = y0 + row;
                let mut r = 0;
                for (di, a) in px.iter_mut().enumerate() {
                    progress.check()?;
                    let i = x0 + di;
                    let item = (j * params.width + i) as u64;
                    for k in k0..k1 {
                        let mut s = params.settings.sample_stream(params.seed, item, k as u64);
                        let p = DVec2::new(i as f64 + s.next_f64(), j as f64 + s.next_f64());
                        let path = radiance_path_parts(
                            scene,
                            cam.position,
                            cam.direction(p),
                            None,
                            None,
                            &params.settings,
                            &mut s,
                            &mut r,
                        );
                        let (l, m) = (path.radiance, path.from_medium());
                        let y = luminance(l);
                        *a = (a.0 + l, a.1 + y, a.2 + y * y, a.3 + m);
                    }
                }
                progress.advance(1);
                Ok(r)
            })
            .collect::<Result<_, _>>()?;
        rays += pass_rays.iter().sum::<u64>();
        per_sample = pass_start.elapsed().as_secs_f64() / (k1 - k0) as f64;
        done = k1;
        if (k0, k1) != pass {
            break; // a shortened pass is the last
        }
    }
    let n = done.max(1) as f64;
    let values = acc.iter().map(|a| a.0 / n).collect();
    let medium = acc.iter().map(|a| a.3 / n).collect();
    let std_error = acc
        .iter()
        .map(|a| {
            let m = a.1 / n;
            ((a.2 / n - m * m).max(0.0) / (n - 1.0).max(1.0)).sqrt()
        })
        .collect();
    Ok(Rendered {
        width: w,
        height: h,
        values,
        medium,
        std_error,
        spp: done,
        rays,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Rays per second of closest-hit queries on random rays through the scene's
/// bounds (origins uniform in the bounds, directions uniform), on the current
/// rayon pool: the ray-casting throughput alone.
pub fn ray_cast_rate(scene: &Scene, rays: u64, seed: u64) -> f64 {
    let start = Instant::now();
    let (lo, hi) = (scene.bounds.min, scene.bounds.max);
    let hits: u64 = (0..rays)
        .into_par_iter()
        .map(|k| {
            let mut s = Sampler::new(seed, k);
            let o = lo + (hi - lo) * DVec3::new(s.next_f64(), s.next_f64(), s.next_f64());
            let z = 1.0 - 2.0 * s.next_f64();
            let phi = std::f64::consts::TAU * s.next_f64();
            let r = (1.0 - z * z).sqrt();
            let d = DVec3::new(r * phi.cos(), r * phi.sin(), z);
            scene.closest_hit(o, d, f64::INFINITY, None).is_some() as u64
        })
        .sum();
    std::hint::black_box(hits);
    rays as f64 / start.elapsed().as_secs_f64().max(1e-9)
}

#[cfg(test)]
mod tests {
    use super::{fitting_pass, passes};

    /// A pass that fits is kept; one that does not is shortened to the samples
    /// that fill 90% of what is left; none fits when not one sample does.
    #[test]
    fn the_last_pass_fills_the_budget() {
        assert_eq!(fitting_pass((64, 128), 50.0, 90.0, 0.5), Some((64, 128)));
        assert_eq!(fitting_pass((64, 128), 60.0, 90.0, 1.0), Some((64, 91)));
        assert_eq!(fitting_pass((64, 128), 89.5, 90.0, 1.0), None);
        assert_eq!(fitting_pass((64, 128), 95.0, 90.0, 1.0), None);
    }

    #[test]
    fn pass_schedule_covers_all_samples() {
        for spp in [1, 2, 3, 7, 64, 100] {
            let p = passes(spp);
            assert_eq!(p[0].0, 0);
            assert_eq!(p.last().unwrap().1, spp);
            assert!(p.windows(2).all(|w| w[0].1 == w[1].0));
        }
    }
}
