//! Reference estimator: unidirectional volumetric path tracing in 3D.
//!
//! Paths use free-flight sampling (chromatic balance heuristic), NEE at every vertex
//! (delta lights; sky, sun cones and emitters with MIS against phase/BRDF sampling),
//! Lambertian BRDF ρ/π with cosine sampling, and Russian roulette. Each sample draws
//! from its own stream derived from (seed, item, sample), so results do not depend
//! on threads.
//!
//! Quantities: the radiance L_i(x, ω) arriving at x from ω along one ray (camera
//! pixels), and the irradiance ∫ L_i max(0, n·ω) dω on a virtual sensor (power
//! leaving a boundary, for the published half-space and slab values).

use super::lights::{Lobe, all_nee, emitter_pdf, escaped_radiance, power_heuristic};
use super::medium::Flight;
use super::scene::Scene;
use crate::core::color::Rgb;
use crate::core::rng::Sampler;
use glam::DVec3;
use serde::Serialize;

/// Path-tracing settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Settings {
    /// Maximum number of path vertices (scattering or reflection) after the start.
    pub max_depth: u32,
    /// Russian roulette starts at this vertex.
    pub rr_depth: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            max_depth: 64,
            rr_depth: 3,
        }
    }
}

/// The radiance L_i(start, dir) arriving at `start` back along the ray start + t·dir. `skip` is the triangle
/// `start` lies on; `lobe_pdf` the pdf with which `dir` was sampled at a vertex that
/// also did NEE with MIS (None for camera rays and fixed directions).
#[allow(clippy::too_many_arguments)] // the path state is spelled out
pub fn radiance_path(
    scene: &Scene,
    start: DVec3,
    dir: DVec3,
    skip: Option<u32>,
    lobe_pdf: Option<f64>,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    radiance_path_split(scene, start, dir, skip, lobe_pdf, settings, s, rays).0
}

/// [`radiance_path`], also telling whether the path's first event was a scattering
/// in the medium: then everything it carries is in-scattered light along the first
/// segment (∫ T L_s dt), otherwise it is light from the first surface or the sky
/// (T L_o). Camera paths split an image into its medium and surface parts this way.
#[allow(clippy::too_many_arguments)] // the path state is spelled out
pub fn radiance_path_split(
    scene: &Scene,
    start: DVec3,
    dir: DVec3,
    skip: Option<u32>,
    lobe_pdf: Option<f64>,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> (Rgb, bool) {
    let (mut p, mut dir, mut skip, mut pdf_prev) = (start, dir, skip, lobe_pdf);
    let mut scattered_first = false;
    let mut beta = Rgb::ONE;
    let mut l = Rgb::ZERO;
    for depth in 1..=settings.max_depth {
        *rays += 1;
        let hit = scene.closest_hit(p, dir, f64::INFINITY, skip);
        // Unbounded media end at the world sphere: paths leaving it escape.
        let s_max = hit.map_or_else(|| scene.world_exit(p, dir), |h| h.t);
        let flight = match &scene.medium {
            Some(m) => m.sample_flight(p, dir, s_max, s),
            None => Flight::Pass { weight: Rgb::ONE },
        };
        let lobe = match flight {
            Flight::Scatter { t, weight } => {
                scattered_first |= depth == 1;
                beta *= weight;
                p += dir * t;
                skip = None;
                let m = scene.medium.as_ref().expect("scattering needs a medium");
                Lobe::Phase {
                    hg: m.phase,
                    travel: dir,
                }
            }
            Flight::Pass { weight } => {
                beta *= weight;
                let Some(h) = hit else {
                    l += beta * escaped_radiance(scene, dir, pdf_prev);
                    break;
                };
                let tri = &scene.triangles[h.tri as usize];
                let surf = scene.surface(h.tri);
                let facing = tri.normal.dot(dir) < 0.0;
                if !facing && !surf.two_sided {
                    break; // the inactive back of a one-sided surface absorbs
                }
                let normal = if facing { tri.normal } else { -tri.normal };
                let y = tri.point_at(h.u, h.v);
                if surf.emission != Rgb::ZERO {
                    let w = pdf_prev.map_or(1.0, |pb| power_heuristic(pb, emitter_pdf(scene, p, h.tri, y)));
                    l += beta * surf.emission * w;
                }
                if surf.reflectance == Rgb::ZERO {
                    break;
                }
                p = y;
                skip = Some(h.tri);
                Lobe::Lambert {
                    normal,
                    reflectance: surf.reflectance,
                }
            }
        };
        let last = depth == settings.max_depth;
        l += beta * all_nee(scene, p, &lobe, skip, !last, s, rays);
        if last {
            break;
        }
        let (w, weight, pdf) = lobe.sample(s);
        beta *= weight;
        dir = w;
        pdf_prev = Some(pdf);
        if depth >= settings.rr_depth && !crate::core::roulette::survives(&mut beta, s) {
            break;
        }
        if beta == Rgb::ZERO || !beta.is_finite() {
            break;
        }
    }
    (l, scattered_first)
}

/// One sample of ∫ value(ω) L_i(x, ω) dω for a lobe at `x` (on triangle `skip`, if
/// any): NEE plus one lobe-sampled path, MIS-combined.
pub fn sample_lobe(
    scene: &Scene,
    x: DVec3,
    lobe: &Lobe,
    skip: Option<u32>,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    let nee = all_nee(scene, x, lobe, skip, true, s, rays);
    let (w, weight, pdf) = lobe.sample(s);
    if weight == Rgb::ZERO {
        return nee;
    }
    nee + weight * radiance_path(scene, x, w, skip, Some(pdf), settings, s, rays)
}

/// The radiance leaving the surface point of `hit` back along `dir` (the ray that
/// found it): emission on an active side plus `paths` samples of the reflected
/// light (NEE and a BRDF-sampled path each). Returns the point, the unit normal on
/// the side facing the ray, and the radiance (zero on the inactive back of a
/// one-sided surface).
pub fn radiance_leaving_hit(
    scene: &Scene,
    hit: &super::mesh::Hit,
    dir: DVec3,
    paths: u32,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> (DVec3, DVec3, Rgb) {
    let tri = &scene.triangles[hit.tri as usize];
    let surf = scene.surface(hit.tri);
    let facing = tri.normal.dot(dir) < 0.0;
    let normal = if facing { tri.normal } else { -tri.normal };
    let point = tri.point_at(hit.u, hit.v);
    let mut l = Rgb::ZERO;
    if facing || surf.two_sided {
        l += surf.emission;
        if surf.reflectance != Rgb::ZERO {
            let lobe = Lobe::Lambert {
                normal,
                reflectance: surf.reflectance,
            };
            let paths = paths.max(1);
            let mut sum = Rgb::ZERO;
            for _ in 0..paths {
                sum += sample_lobe(scene, point, &lobe, Some(hit.tri), settings, s, rays);
            }
            l += sum / paths as f64;
        }
    }
    (point, normal, l)
}

/// One sample of the irradiance ∫ L_i(x, ω) max(0, n·ω) dω on a virtual sensor at
/// `x` with unit normal `n` (it faces the light it measures).
pub fn sample_irradiance(
    scene: &Scene,
    x: DVec3,
    n: DVec3,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    // Lambert with ρ = π has value max(0, n·ω): the cosine-weighted integral.
    let lobe = Lobe::Lambert {
        normal: n,
        reflectance: Rgb::splat(std::f64::consts::PI),
    };
    sample_lobe(scene, x, &lobe, None, settings, s, rays)
}

/// Mean and standard error per channel of `n` samples of `f(sampler)`, each with
/// its stream (seed, item, k).
pub fn estimate(n: u64, seed: u64, item: u64, mut f: impl FnMut(&mut Sampler) -> Rgb) -> (Rgb, Rgb) {
    let (mut sum, mut sum2) = (Rgb::ZERO, Rgb::ZERO);
    for k in 0..n {
        let v = f(&mut Sampler::new2(seed, item, k));
        sum += v;
        sum2 += v * v;
    }
    let nf = n.max(1) as f64;
    let mean = sum / nf;
    let var = (sum2 / nf - mean * mean).max(Rgb::ZERO) * (nf / (nf - 1.0).max(1.0));
    (mean, (var / nf).powf(0.5))
}
