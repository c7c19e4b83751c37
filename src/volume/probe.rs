//! A cache point's incoming light field in 3D (the 3D counterpart of
//! `flatland::probe`): N stratified directions over the sphere around a medium
//! point x ([`super::sphere`], jittered per (seed, item)), their triangulation, each
//! ray's surface hit with the radiance leaving it towards x, and ray-marched medium
//! samples with recursive estimates of L_s.
//!
//! The march: every ray is cast first; the march length is the farthest point any
//! ray still has medium in front of it (its hit, or where it leaves the medium box),
//! capped where the transmittance falls below `transmittance_cutoff` and at
//! `far_factor` × the scene size, and the step is that length over `steps` (so a
//! room is sampled at room scale, not at the scale of the fog's mean free path).
//! Medium sample i of ray k sits at depth (i + ξ_k)·Δt with the ray's own jitter ξ_k,
//! so the i-th samples of neighbouring rays form shells.
//!
//! Lights kept apart for the direct part (theory.md §2): point lights and suns, with
//! or without a cone. A sun's cone (0.27° for the real sun) is far narrower than the
//! solid angle per ray (4π/N), so a probe ray would find it with a probability of a
//! few percent and then carry a spike of 10⁴–10⁵ times the sky: it is evaluated as a
//! directional light at the cone's centre instead. Escaped rays end at the cut
//! length and carry the sky only, scaled by T_true / exp(−σ_t(x)·length), so that
//! the proxy's homogeneous transmittance model gives the true value through a medium
//! box (zero when that ratio is not representable).
//!
//! L_s is wanted towards a fixed direction ω_o, or towards a point (the camera of a
//! 3D render: [`Outgoing::TowardsPoint`]), in which case ω_o turns with x and the
//! derivatives include that turning.

use super::lights::Lobe;
use super::medium::Medium;
use super::scene::Scene;
use super::sphere::{fibonacci_directions, triangulate};
use super::transport::{Settings, radiance_leaving_hit, sample_lobe};
use crate::core::color::Rgb;
pub use crate::core::phase::Outgoing;
use crate::core::rng::Sampler;
use crate::progress::{Cancelled, Progress};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ProbeSettings {
    /// Number of stratified directions N.
    pub rays: usize,
    /// Recursive paths per hit point and per medium sample.
    pub paths: u32,
    /// Medium samples per ray over the march length.
    pub steps: usize,
    /// Stop marching where the transmittance from x falls below this.
    pub transmittance_cutoff: f64,
    /// Escaped rays end at this multiple of the scene size.
    pub far_factor: f64,
    /// Jitter of the directions in their strata, in [0, 1].
    pub jitter: f64,
    pub settings: Settings,
}

impl Default for ProbeSettings {
    fn default() -> Self {
        ProbeSettings {
            rays: 16384,
            paths: 1,
            steps: 24,
            transmittance_cutoff: 1e-3,
            far_factor: 4.0,
            jitter: 1.0,
            settings: Settings::default(),
        }
    }
}

/// Where a probe ray met a surface, and the radiance leaving it towards x.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SurfaceHit {
    pub point: DVec3,
    pub tri: u32,
    /// Unit normal on the side facing x.
    pub normal: DVec3,
    /// L_o(h → x): emission (active side) plus the reflected estimate.
    pub radiance: Rgb,
}

/// One ray of the light field.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProbeRay {
    pub dir: DVec3,
    /// Distance to the hit, or where the ray was cut (transmittance or far limit).
    pub length: f64,
    pub hit: Option<SurfaceHit>,
    /// Radiance carried by the end point of an escaped ray (see module docs).
    pub escaped: Rgb,
    /// Medium samples: L_s(m, −dir) (σ_s included) at depth (i + offset)·step.
    pub samples: Vec<Rgb>,
    /// Jitter of this ray's medium samples, in [0, 1).
    pub offset: f64,
}

impl ProbeRay {
    /// End point, its distance from x and the radiance it carries.
    pub fn end(&self, x: DVec3) -> (DVec3, f64, Rgb) {
        match &self.hit {
            Some(h) => (h.point, (h.point - x).length(), h.radiance),
            None => (x + self.dir * self.length, self.length, self.escaped),
        }
    }
}

/// A delta light seen from x (visibility and transmittance included).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum DirectLight {
    /// I·T/r² at x.
    Point {
        position: DVec3,
        intensity: Rgb,
        transmittance: Rgb,
    },
    /// A sun (its cone, if any, taken at its centre): E·T, with the medium depth
    /// along `to_sun` and its gradient in x (the exit face moves with x).
    Sun {
        to_sun: DVec3,
        irradiance: Rgb,
        depth: f64,
        depth_grad: DVec3,
        transmittance: Rgb,
    },
}

impl DirectLight {
    /// The visible delta lights at x.
    pub fn gather(scene: &Scene, x: DVec3) -> (Vec<DirectLight>, u64) {
        let mut out = Vec::new();
        let mut rays = 0;
        for l in &scene.point_lights {
            let d = l.position - x;
            let r = d.length();
            if r == 0.0 {
                continue;
            }
            rays += 1;
            if !scene.occluded(x, d / r, r, None) {
                let tr = scene.medium.as_ref().map_or(Rgb::ONE, |m| m.transmittance(x, d / r, r));
                out.push(DirectLight::Point {
                    position: l.position,
                    intensity: l.intensity,
                    transmittance: tr,
                });
            }
        }
        for sun in &scene.suns {
            let w = sun.to_sun;
            rays += 1;
            if scene.occluded(x, w, f64::INFINITY, None) {
                continue;
            }
            let depth_at = |p: DVec3| {
                scene
                    .medium
                    .as_ref()
                    .map_or(0.0, |m| m.length_inside(p, w, scene.world_exit(p, w)))
            };
            let depth = depth_at(x);
            // The depth is piecewise linear in x: central differences are exact off
            // the box's edges.
            let h = 1e-6 * scene.scale;
            let depth_grad = DVec3::new(
                depth_at(x + DVec3::X * h) - depth_at(x - DVec3::X * h),
                depth_at(x + DVec3::Y * h) - depth_at(x - DVec3::Y * h),
                depth_at(x + DVec3::Z * h) - depth_at(x - DVec3::Z * h),
            ) / (2.0 * h);
            let tr = scene
                .medium
                .as_ref()
                .map_or(Rgb::ONE, |m| m.transmittance(x, w, scene.world_exit(x, w)));
            out.push(DirectLight::Sun {
                to_sun: w,
                irradiance: sun.irradiance,
                depth,
                depth_grad,
                transmittance: tr,
            });
        }
        (out, rays)
    }
}

/// The light field at one point.
#[derive(Clone, Debug, Serialize)]
pub struct LightField {
    pub x: DVec3,
    /// Direction L_s is wanted towards (at x, when it turns towards `eye`).
    pub omega_o: DVec3,
    /// The point ω_o turns towards as x moves (a camera), if any.
    pub eye: Option<DVec3>,
    pub rays: Vec<ProbeRay>,
    /// Outward-oriented triangles of the directions (indices into `rays`).
    pub triangles: Vec<[u32; 3]>,
    /// Spacing Δt of the ray-marched medium samples.
    pub step: f64,
    pub direct_lights: Vec<DirectLight>,
    /// σ_s, σ_t at x (zero without a medium).
    pub sigma_s: Rgb,
    pub sigma_t: Rgb,
    pub g: f64,
    /// Ray-casting queries spent.
    pub cost_rays: u64,
    pub seconds: f64,
}

impl LightField {
    /// Depth of medium sample i of `ray`.
    pub fn sample_depth(&self, ray: &ProbeRay, i: usize) -> f64 {
        (i as f64 + ray.offset) * self.step
    }

    /// Where L_s leaves towards, for the derivative core.
    pub fn outgoing(&self) -> Outgoing<DVec3> {
        self.eye
            .map_or(Outgoing::Direction(self.omega_o), Outgoing::TowardsPoint)
    }

    /// The solid angle per ray, 4π/N.
    pub fn ray_measure(&self) -> f64 {
        4.0 * PI / self.rays.len() as f64
    }
}

/// The longest march before the transmittance drops below the cutoff (or the far
/// limit).
fn march_limit(medium: Option<&Medium>, scale: f64, ps: &ProbeSettings) -> f64 {
    let far = ps.far_factor * scale;
    let sig = medium.map_or(0.0, |m| m.sigma_t.min_element());
    if sig > 0.0 {
        (-ps.transmittance_cutoff.ln() / sig).min(far)
    } else {
        far
    }
}

/// Capture the light field at `x` for L_s towards `omega_o`. Deterministic for
/// (seed, item) whatever the thread count.
pub fn capture(
    scene: &Scene,
    x: DVec3,
    omega_o: DVec3,
    ps: &ProbeSettings,
    seed: u64,
    item: u64,
    progress: &Progress,
) -> Result<LightField, Cancelled> {
    capture_towards(scene, x, Outgoing::Direction(omega_o), ps, seed, item, progress)
}

/// [`capture`] for L_s towards a fixed direction or towards a point (a camera).
pub fn capture_towards(
    scene: &Scene,
    x: DVec3,
    out: Outgoing<DVec3>,
    ps: &ProbeSettings,
    seed: u64,
    item: u64,
    progress: &Progress,
) -> Result<LightField, Cancelled> {
    let start = std::time::Instant::now();
    let (omega_o, eye) = match out {
        Outgoing::Direction(w) => (w, None),
        Outgoing::TowardsPoint(e) => ((e - x).try_normalize().unwrap_or(DVec3::Z), Some(e)),
    };
    let medium = scene.medium.as_ref();
    let at_x = scene.medium_at(x);
    let sigma_t_x = at_x.map_or(Rgb::ZERO, |m| m.sigma_t);
    let limit = march_limit(medium, scene.scale, ps);
    let n = ps.rays.max(4);
    let dir_seed = crate::core::rng::mix64(seed ^ crate::core::rng::mix64(item.wrapping_add(0x9e37)));
    let dirs = fibonacci_directions(n, ps.jitter, dir_seed);
    let triangles = triangulate(&dirs).expect("stratified directions triangulate");
    // Pass 1: every ray's hit and how far it still has medium in front of it.
    let hits: Vec<(Option<super::mesh::Hit>, f64)> = dirs
        .par_iter()
        .map(|&dir| {
            let hit = scene.closest_hit(x, dir, f64::INFINITY, None);
            let end = hit.map_or(limit, |h| h.t.min(limit));
            let medium_end = medium.and_then(|m| m.interval(x, dir, end)).map_or(0.0, |(_, b)| b);
            (hit, medium_end)
        })
        .collect();
    let march_len = hits.iter().map(|h| h.1).fold(0.0, f64::max).min(limit);
    let step = if march_len > 0.0 { march_len } else { limit } / ps.steps.max(1) as f64;
    let t_cut = step * ps.steps.max(1) as f64;
    let paths = ps.paths.max(1);
    let rays: Vec<Result<(ProbeRay, u64), Cancelled>> = dirs
        .par_iter()
        .zip(&hits)
        .enumerate()
        .map(|(k, (&dir, &(hit, _)))| {
            progress.check()?;
            let mut s = Sampler::new2(seed, item, k as u64);
            let offset = s.next_f64();
            let mut rays = 1u64;
            let hit_record = hit.map(|h| {
                let (point, normal, radiance) =
                    radiance_leaving_hit(scene, &h, dir, paths, &ps.settings, &mut s, &mut rays);
                SurfaceHit {
                    point,
                    tri: h.tri,
                    normal,
                    radiance,
                }
            });
            let length = hit.map_or(t_cut, |h| h.t);
            let escaped = if hit.is_none() && scene.sky != Rgb::ZERO {
                let t_true = medium.map_or(Rgb::ONE, |m| m.transmittance(x, dir, scene.world_exit(x, dir)));
                let t_model = (-sigma_t_x * length).exp();
                let ratio = Rgb::select(t_model.cmpgt(Rgb::splat(1e-200)), t_true / t_model, Rgb::ZERO);
                scene.sky * ratio
            } else {
                Rgb::ZERO
            };
            let mut samples = Vec::new();
            if let Some(m) = medium {
                let lobe = Lobe::Phase {
                    hg: m.phase,
                    travel: dir,
                };
                let mut i = 0;
                loop {
                    let t = (i as f64 + offset) * step;
                    if t >= length.min(t_cut) {
                        break;
                    }
                    let p = x + dir * t;
                    let mut sum = Rgb::ZERO;
                    if m.contains(p) {
                        for _ in 0..paths {
                            sum += sample_lobe(scene, p, &lobe, None, &ps.settings, &mut s, &mut rays);
                        }
                        sum = sum * m.sigma_s / paths as f64;
                    }
                    samples.push(sum);
                    i += 1;
                }
            }
            Ok((
                ProbeRay {
                    dir,
                    length,
                    hit: hit_record,
                    escaped,
                    samples,
                    offset,
                },
                rays,
            ))
        })
        .collect();
    let mut out = Vec::with_capacity(n);
    let mut cost = 0;
    for r in rays {
        let (ray, c) = r?;
        out.push(ray);
        cost += c;
    }
    let (direct_lights, c) = DirectLight::gather(scene, x);
    Ok(LightField {
        x,
        omega_o,
        eye,
        rays: out,
        triangles,
        step,
        direct_lights,
        sigma_s: at_x.map_or(Rgb::ZERO, |m| m.sigma_s),
        sigma_t: sigma_t_x,
        g: at_x.map_or(0.0, |m| m.phase.g),
        cost_rays: cost + c,
        seconds: start.elapsed().as_secs_f64(),
    })
}
