//! Scattering lobes at path vertices and next-event estimation (NEE) in 3D.
//!
//! Direction convention (theory.md §1): a direction ω at a vertex points *towards*
//! where light comes from; the light travels along −ω.
//!
//! - Point lights and suns of zero angular radius are delta lights: evaluated
//!   analytically with visibility and transmittance.
//! - Suns with a cone (uniform in the cone's solid angle), the constant sky (uniform
//!   over the sphere) and emitting triangles (picked ∝ luminance × area, uniform in
//!   area, converted to solid angle) are sampled and combined with lobe sampling by
//!   the power heuristic; each light is its own two-strategy MIS.

use super::scene::Scene;
use crate::core::color::Rgb;
use crate::core::phase::Hg3;
use crate::core::rng::Sampler;
use glam::DVec3;
use std::f64::consts::{FRAC_1_PI, PI, TAU};

/// What a vertex does with light arriving from ω: value(ω) multiplies L_i(ω) dω.
#[derive(Clone, Copy, Debug)]
pub enum Lobe {
    /// Scattering in a medium; `travel` is the direction the path arrived along.
    Phase { hg: Hg3, travel: DVec3 },
    /// Lambertian reflection on the side of unit `normal`: (ρ/π)·max(0, n·ω).
    Lambert { normal: DVec3, reflectance: Rgb },
}

impl Lobe {
    /// Value and sampling pdf (per steradian) of direction `w`.
    #[inline]
    pub fn eval(&self, w: DVec3) -> (Rgb, f64) {
        match *self {
            Lobe::Phase { hg, travel } => {
                let f = hg.eval(travel, w);
                (Rgb::splat(f), f)
            }
            Lobe::Lambert { normal, reflectance } => {
                let c = normal.dot(w).max(0.0) * FRAC_1_PI;
                (reflectance * c, c)
            }
        }
    }

    /// Sample a direction: (ω, value/pdf, pdf).
    #[inline]
    pub fn sample(&self, s: &mut Sampler) -> (DVec3, Rgb, f64) {
        let (u1, u2) = (s.next_f64(), s.next_f64());
        match *self {
            Lobe::Phase { hg, travel } => {
                let w = hg.sample(travel, u1, u2);
                (w, Rgb::ONE, hg.eval(travel, w))
            }
            Lobe::Lambert { normal, reflectance } => {
                // Cosine-weighted: a uniform disc point lifted to the hemisphere.
                let r = u1.sqrt();
                let phi = TAU * u2;
                let z = (1.0 - u1).max(0.0).sqrt();
                let (t, b) = normal.any_orthonormal_pair();
                let w = (t * (r * phi.cos()) + b * (r * phi.sin()) + normal * z).normalize();
                (w, reflectance, normal.dot(w).max(0.0) * FRAC_1_PI)
            }
        }
    }
}

pub use crate::core::mis::power_heuristic;

/// Transmittance along p + t·w for t in [0, dist] (one in vacuum).
#[inline]
pub fn transmittance(scene: &Scene, p: DVec3, w: DVec3, dist: f64) -> Rgb {
    scene.medium.as_ref().map_or(Rgb::ONE, |m| m.transmittance(p, w, dist))
}

/// Transmittance towards infinity along an unoccluded ray (the medium ends at the
/// world sphere, as for paths that escape).
#[inline]
fn transmittance_to_infinity(scene: &Scene, p: DVec3, w: DVec3) -> Rgb {
    match &scene.medium {
        None => Rgb::ONE,
        Some(m) => m.transmittance(p, w, scene.world_exit(p, w)),
    }
}

/// Light from delta lights (point lights, suns without a cone) at `p`, weighted by
/// `lobe`. `skip` is the triangle `p` lies on, if any.
pub fn delta_lights(scene: &Scene, p: DVec3, lobe: &Lobe, skip: Option<u32>, rays: &mut u64) -> Rgb {
    let mut sum = Rgb::ZERO;
    for l in &scene.point_lights {
        let d = l.position - p;
        let r2 = d.length_squared();
        if r2 == 0.0 {
            continue;
        }
        let r = r2.sqrt();
        let w = d / r;
        let (value, _) = lobe.eval(w);
        if value == Rgb::ZERO {
            continue;
        }
        *rays += 1;
        if !scene.occluded(p, w, r, skip) {
            sum += value * l.intensity * transmittance(scene, p, w, r) / r2;
        }
    }
    for sun in scene.suns.iter().filter(|s| s.is_delta()) {
        let w = sun.to_sun;
        let (value, _) = lobe.eval(w);
        if value == Rgb::ZERO {
            continue;
        }
        *rays += 1;
        if !scene.occluded(p, w, f64::INFINITY, skip) {
            sum += value * sun.irradiance * transmittance_to_infinity(scene, p, w);
        }
    }
    sum
}

/// A direction in the cone of half-angle acos(cos_max) around `axis`, uniform in
/// solid angle.
fn sample_cone(axis: DVec3, cos_max: f64, u1: f64, u2: f64) -> DVec3 {
    let cos_t = 1.0 - u1 * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = TAU * u2;
    let (t, b) = axis.any_orthonormal_pair();
    (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + axis * cos_t).normalize()
}

/// NEE to the sky and to suns with a cone, one sample each. With `mis`, weighted by
/// the power heuristic against lobe sampling (see [`escaped_radiance`]).
pub fn distant_nee(
    scene: &Scene,
    p: DVec3,
    lobe: &Lobe,
    skip: Option<u32>,
    mis: bool,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    let mut sum = Rgb::ZERO;
    let mut one = |w: DVec3, pdf_light: f64, radiance: Rgb, rays: &mut u64| {
        let (value, pdf_lobe) = lobe.eval(w);
        if value == Rgb::ZERO {
            return;
        }
        *rays += 1;
        if scene.occluded(p, w, f64::INFINITY, skip) {
            return;
        }
        let weight = if mis { power_heuristic(pdf_light, pdf_lobe) } else { 1.0 };
        sum += value * radiance * transmittance_to_infinity(scene, p, w) * (weight / pdf_light);
    };
    if scene.sky != Rgb::ZERO {
        let (u1, u2) = (s.next_f64(), s.next_f64());
        let z = 1.0 - 2.0 * u1;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let w = DVec3::new(r * (TAU * u2).cos(), r * (TAU * u2).sin(), z);
        one(w, 1.0 / (4.0 * PI), scene.sky, rays);
    }
    for sun in scene.suns.iter().filter(|s| !s.is_delta()) {
        let (u1, u2) = (s.next_f64(), s.next_f64());
        let w = sample_cone(sun.to_sun, sun.cos_max, u1, u2);
        one(w, 1.0 / sun.solid_angle(), sun.radiance, rays);
    }
    sum
}

/// Radiance of the sky and sun cones seen along an escaping ray `w`, MIS-weighted
/// against their NEE when the direction was lobe-sampled with pdf `lobe_pdf`.
pub fn escaped_radiance(scene: &Scene, w: DVec3, lobe_pdf: Option<f64>) -> Rgb {
    let weight = |pdf_light: f64| lobe_pdf.map_or(1.0, |pb| power_heuristic(pb, pdf_light));
    let mut l = Rgb::ZERO;
    if scene.sky != Rgb::ZERO {
        l += scene.sky * weight(1.0 / (4.0 * PI));
    }
    for sun in scene.suns.iter().filter(|s| !s.is_delta()) {
        if w.dot(sun.to_sun) >= sun.cos_max {
            l += sun.radiance * weight(1.0 / sun.solid_angle());
        }
    }
    l
}

/// Solid-angle pdf with which [`emitter_nee`] at `p` samples point `y` of emitting
/// triangle `tri`.
pub fn emitter_pdf(scene: &Scene, p: DVec3, tri: u32, y: DVec3) -> f64 {
    let Ok(k) = scene.emitters.binary_search(&tri) else {
        return 0.0;
    };
    let t = &scene.triangles[tri as usize];
    let d = y - p;
    let r2 = d.length_squared();
    let cos_l = t.normal.dot(d).abs() / r2.sqrt();
    if cos_l <= 0.0 {
        return 0.0;
    }
    scene.emitter_probability(k) / t.area * r2 / cos_l
}

/// One-sample NEE to emitting triangles at `p`, weighted by `lobe`; with `mis`, the
/// power-heuristic weight against lobe sampling (paths weight emission they hit
/// with [`emitter_pdf`]).
pub fn emitter_nee(
    scene: &Scene,
    p: DVec3,
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
    let (u1, u2) = (s.next_f64(), s.next_f64());
    if Some(i) == skip {
        return Rgb::ZERO;
    }
    let t = &scene.triangles[i as usize];
    let surf = scene.surface(i);
    let y = t.sample_point(u1, u2);
    let d = y - p;
    let r2 = d.length_squared();
    let r = r2.sqrt();
    if r == 0.0 {
        return Rgb::ZERO;
    }
    let w = d / r;
    // Cosine at the light; a one-sided emitter shines on its front side only.
    let cos_l = -t.normal.dot(w);
    let cos_l = if surf.two_sided { cos_l.abs() } else { cos_l };
    if cos_l <= 0.0 {
        return Rgb::ZERO;
    }
    let (value, pdf_lobe) = lobe.eval(w);
    if value == Rgb::ZERO {
        return Rgb::ZERO;
    }
    *rays += 1;
    if scene.occluded(p, w, r * (1.0 - 1e-9), skip) {
        return Rgb::ZERO;
    }
    let pdf_light = scene.emitter_probability(k) / t.area * r2 / cos_l;
    let weight = if mis { power_heuristic(pdf_light, pdf_lobe) } else { 1.0 };
    value * surf.emission * transmittance(scene, p, w, r) * (weight / pdf_light)
}

/// The direct part of L_s (theory.md §2) at a medium point: delta lights and suns
/// with a cone, one cone sample each. No MIS: a radiance cache's probe rays leave
/// sun cones to this part (see `probe`), so no other strategy samples them.
pub fn direct_part(scene: &Scene, p: DVec3, lobe: &Lobe, s: &mut Sampler, rays: &mut u64) -> Rgb {
    let mut sum = delta_lights(scene, p, lobe, None, rays);
    for sun in scene.suns.iter().filter(|s| !s.is_delta()) {
        let (u1, u2) = (s.next_f64(), s.next_f64());
        let w = sample_cone(sun.to_sun, sun.cos_max, u1, u2);
        let (value, _) = lobe.eval(w);
        if value == Rgb::ZERO {
            continue;
        }
        *rays += 1;
        if !scene.occluded(p, w, f64::INFINITY, None) {
            // Uniform in the cone: radiance / pdf = radiance × solid angle = E.
            sum += value * sun.radiance * sun.solid_angle() * transmittance_to_infinity(scene, p, w);
        }
    }
    sum
}

/// All NEE at a vertex: delta lights, distant lights with a solid angle, emitters.
pub fn all_nee(
    scene: &Scene,
    p: DVec3,
    lobe: &Lobe,
    skip: Option<u32>,
    mis: bool,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    delta_lights(scene, p, lobe, skip, rays)
        + distant_nee(scene, p, lobe, skip, mis, s, rays)
        + emitter_nee(scene, p, lobe, skip, mis, s, rays)
}
