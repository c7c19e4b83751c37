//! Scattering lobes at path vertices and next-event estimation (NEE) to lights.
//!
//! Direction convention (theory.md §1): a direction ω at a vertex points *towards*
//! where light comes from; the light travels along −ω.
//!
//! - Point and collimated lights are delta lights: evaluated analytically with
//!   visibility and transmittance.
//! - Emitting segments are sampled by subtended angle (uniform in angle, exact in
//!   2D) and combined with lobe sampling by the power heuristic (MIS).

use super::geometry::cross;
use super::scene::Scene;
use crate::core::color::Rgb;
use crate::core::phase::Hg2;
use crate::core::rng::Sampler;
use glam::DVec2;
use std::f64::consts::TAU;

/// What a vertex does with light arriving from a direction ω: value(ω) is the
/// factor multiplying L_i(ω) dθ (phase function, BRDF × cosine, or 1).
#[derive(Clone, Copy, Debug)]
pub enum Lobe {
    /// Scattering in a medium; `travel` is the direction the path arrived along
    /// (value f(travel, ω), HG is symmetric).
    Phase { hg: Hg2, travel: DVec2 },
    /// Lambertian reflection on the side with unit `normal`: (ρ/2)·max(0, n·ω).
    Lambert { normal: DVec2, reflectance: Rgb },
    /// Plain integration over the circle (fluence).
    Uniform,
}

impl Lobe {
    /// Value and sampling pdf (per radian) of direction `w`.
    #[inline]
    pub fn eval(&self, w: DVec2) -> (Rgb, f64) {
        match *self {
            Lobe::Phase { hg, travel } => {
                let f = hg.eval(travel, w);
                (Rgb::splat(f), f)
            }
            Lobe::Lambert { normal, reflectance } => {
                let c = normal.dot(w).max(0.0);
                (reflectance * (0.5 * c), 0.5 * c)
            }
            Lobe::Uniform => (Rgb::ONE, 1.0 / TAU),
        }
    }

    /// Sample a direction: (ω, value/pdf, pdf).
    #[inline]
    pub fn sample(&self, s: &mut Sampler) -> (DVec2, Rgb, f64) {
        match *self {
            Lobe::Phase { hg, travel } => {
                let w = hg.sample(travel, s.next_f64());
                (w, Rgb::ONE, hg.eval(travel, w))
            }
            Lobe::Lambert { normal, reflectance } => {
                // pdf cosθ/2 on the half circle: sinθ uniform in [−1, 1].
                let sin_t = 2.0 * s.next_f64() - 1.0;
                let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
                let w = normal * cos_t + normal.perp() * sin_t;
                (w, reflectance, 0.5 * cos_t)
            }
            Lobe::Uniform => (DVec2::from_angle(TAU * s.next_f64()), Rgb::splat(TAU), 1.0 / TAU),
        }
    }
}

pub use crate::core::mis::power_heuristic;

/// Transmittance along p + t·w for t in [0, dist] (one for vacuum).
#[inline]
fn transmittance(scene: &Scene, p: DVec2, w: DVec2, dist: f64) -> Rgb {
    scene.medium.as_ref().map_or(Rgb::ONE, |m| m.transmittance(p, w, dist))
}

/// Light from point and collimated lights arriving at `p` and weighted by `lobe`
/// (∫ value(ω) L_i,delta(ω) dω). `skip` is the segment `p` lies on, if any.
pub fn direct_lights(scene: &Scene, p: DVec2, lobe: &Lobe, skip: Option<u32>, rays: &mut u64) -> Rgb {
    let mut sum = Rgb::ZERO;
    // Keeps 1/r finite for points on top of a light (users probe there).
    let r_min = 1e-9 * scene.scale();
    for l in &scene.point_lights {
        let d = l.position - p;
        let r = d.length();
        if r == 0.0 {
            continue;
        }
        let w = d / r;
        let (value, _) = lobe.eval(w);
        if value == Rgb::ZERO {
            continue;
        }
        *rays += 1;
        if scene.geometry.occluded(p, w, r, skip) {
            continue;
        }
        sum += value * l.intensity * transmittance(scene, p, w, r) / r.max(r_min);
    }
    for l in &scene.collimated_lights {
        let w = -l.direction;
        let (value, _) = lobe.eval(w);
        if value == Rgb::ZERO {
            continue;
        }
        // The beam reaches p only through its aperture.
        let Some((t_ap, _)) =
            super::geometry::intersect_segment(p, w, l.aperture[0], l.aperture[1], 0.0, f64::INFINITY)
        else {
            continue;
        };
        *rays += 1;
        if scene.geometry.occluded(p, w, t_ap, skip) {
            continue;
        }
        sum += value * l.irradiance * transmittance(scene, p, w, t_ap);
    }
    sum
}

/// Angle subtended at `p` by segment `i`, and the direction to its end `a`.
#[inline]
fn subtended(scene: &Scene, p: DVec2, i: u32) -> (f64, DVec2, DVec2) {
    let s = &scene.geometry.segments[i as usize];
    let (a, b) = (s.a - p, s.b - p);
    (cross(a, b).abs().atan2(a.dot(b)), a, b)
}

/// Probability density (per radian) with which [`emitter_nee`] at `p` picks the
/// direction that hits emitting segment `seg`.
pub fn emitter_pdf(scene: &Scene, p: DVec2, seg: u32) -> f64 {
    let Ok(k) = scene.emitters.binary_search(&seg) else {
        return 0.0;
    };
    let (theta, _, _) = subtended(scene, p, seg);
    if theta > 0.0 {
        scene.emitter_probability(k) / theta
    } else {
        0.0
    }
}

/// One-sample NEE to emitting segments at `p`, weighted by `lobe`. With `mis`, the
/// result carries the power-heuristic weight against lobe sampling (the path then
/// weights emission it hits with [`emitter_pdf`]); without, the full contribution.
pub fn emitter_nee(
    scene: &Scene,
    p: DVec2,
    lobe: &Lobe,
    skip: Option<u32>,
    mis: bool,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    if scene.emitters.is_empty() {
        return Rgb::ZERO;
    }
    let u = s.next_f64();
    let k = scene
        .emitter_cdf
        .partition_point(|&c| c <= u)
        .min(scene.emitters.len() - 1);
    let i = scene.emitters[k];
    let v = s.next_f64();
    if Some(i) == skip {
        return Rgb::ZERO;
    }
    let seg = &scene.geometry.segments[i as usize];
    let (theta, a, b) = subtended(scene, p, i);
    if theta <= 1e-300 {
        return Rgb::ZERO;
    }
    let (_, active) = seg.facing(p);
    if !active {
        return Rgb::ZERO;
    }
    let sign = if cross(a, b) >= 0.0 { 1.0 } else { -1.0 };
    let w = DVec2::from_angle(sign * v * theta).rotate(a.normalize());
    let (value, lobe_pdf) = lobe.eval(w);
    if value == Rgb::ZERO {
        return Rgb::ZERO;
    }
    let e = seg.b - seg.a;
    let denom = cross(w, e);
    if denom == 0.0 {
        return Rgb::ZERO;
    }
    let dist = cross(seg.a - p, e) / denom;
    if !(dist > 0.0 && dist.is_finite()) {
        return Rgb::ZERO;
    }
    *rays += 1;
    if scene.geometry.occluded(p, w, dist, skip) {
        return Rgb::ZERO;
    }
    let light_pdf = scene.emitter_probability(k) / theta;
    let weight = if mis { power_heuristic(light_pdf, lobe_pdf) } else { 1.0 };
    value * seg.emission * transmittance(scene, p, w, dist) * (weight / light_pdf)
}
