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
use crate::core::mis::power_heuristic;
use crate::core::rng::Sampler;
use crate::core::space::D3;
use crate::pipeline::dim::Dim;
use crate::pipeline::nee::{LightSample, gather, light_sample, point_lights};
use crate::pipeline::path::PointLights;
use crate::pipeline::world::{DirectLight, World, ignore};
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// A path vertex's lobe in 3D.
pub type Lobe = crate::pipeline::lobe::Lobe<D3>;

/// Light from delta lights (point lights, suns without a cone) at `p`, weighted by
/// `lobe`. `skip` is the triangle `p` lies on, if any.
pub fn delta_lights(
    scene: &Scene,
    p: DVec3,
    lobe: &Lobe,
    skip: Option<u32>,
    rays: &mut u64,
    each: &mut impl FnMut(DVec3, Rgb),
) -> Rgb {
    point_lights(scene, &scene.point_lights, p, lobe, skip, rays, each) + delta_suns(scene, p, lobe, skip, rays, each)
}

/// Light from suns without a cone arriving at `p` and weighted by `lobe`.
pub fn delta_suns(
    scene: &Scene,
    p: DVec3,
    lobe: &Lobe,
    skip: Option<u32>,
    rays: &mut u64,
    each: &mut impl FnMut(DVec3, Rgb),
) -> Rgb {
    let mut sum = Rgb::ZERO;
    for sun in scene.suns.iter().filter(|s| s.is_delta()) {
        let l = LightSample {
            w: sun.to_sun,
            dist: f64::INFINITY,
            radiance: sun.irradiance,
            pdf: 1.0,
        };
        sum += light_sample(scene, p, lobe, skip, &l, false, rays, each);
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
#[allow(clippy::too_many_arguments)] // the vertex state is spelled out
pub fn distant_nee(
    scene: &Scene,
    p: DVec3,
    lobe: &Lobe,
    skip: Option<u32>,
    mis: bool,
    s: &mut Sampler,
    rays: &mut u64,
    each: &mut impl FnMut(DVec3, Rgb),
) -> Rgb {
    let mut sum = Rgb::ZERO;
    let mut one = |w: DVec3, pdf: f64, radiance: Rgb, rays: &mut u64| {
        let l = LightSample {
            w,
            dist: f64::INFINITY,
            radiance,
            pdf,
        };
        sum += light_sample(scene, p, lobe, skip, &l, mis, rays, each);
    };
    if scene.sky != Rgb::ZERO {
        one(D3::sample_uniform(s), 1.0 / (4.0 * PI), scene.sky, rays);
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
    let Some(k) = scene.emitters.find(tri) else {
        return 0.0;
    };
    let t = &scene.geometry.prims[tri as usize];
    let d = y - p;
    let r2 = d.length_squared();
    let cos_l = t.normal.dot(d).abs() / r2.sqrt();
    if cos_l <= 0.0 {
        return 0.0;
    }
    scene.emitters.probability(k) / t.area * r2 / cos_l
}

/// One-sample NEE to emitting triangles at `p`, weighted by `lobe`; with `mis`, the
/// power-heuristic weight against lobe sampling (paths weight emission they hit
/// with [`emitter_pdf`]).
#[allow(clippy::too_many_arguments)] // the vertex state is spelled out
pub fn emitter_nee(
    scene: &Scene,
    p: DVec3,
    lobe: &Lobe,
    skip: Option<u32>,
    mis: bool,
    s: &mut Sampler,
    rays: &mut u64,
    each: &mut impl FnMut(DVec3, Rgb),
) -> Rgb {
    if scene.emitters.is_empty() {
        return Rgb::ZERO;
    }
    // One draw picks the triangle and places the point along one coordinate: a
    // stratified sample's first pair of draws then spreads over every emitter's
    // area (`Sampler::stratified`).
    let (k, i, u1) = scene.emitters.pick_remapped(s.next_f64());
    let u2 = s.next_f64();
    if Some(i) == skip {
        return Rgb::ZERO;
    }
    let t = &scene.geometry.prims[i as usize];
    let surf = scene.material(i);
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
    let pdf = scene.emitters.probability(k) / t.area * r2 / cos_l;
    // Short of the light's own triangle.
    let l = LightSample {
        w,
        dist: r * (1.0 - 1e-9),
        radiance: surf.emission,
        pdf,
    };
    light_sample(scene, p, lobe, skip, &l, mis, rays, each)
}

/// The direct part of L_s (theory.md §2) at a medium point: delta lights and suns
/// with a cone, one cone sample each. No MIS: a radiance cache's probe rays leave
/// sun cones to this part (see `probe`), so no other strategy samples them.
pub fn direct_part(scene: &Scene, p: DVec3, lobe: &Lobe, s: &mut Sampler, rays: &mut u64) -> Rgb {
    direct_part_with(scene, p, lobe, PointLights::Included, s, rays)
}

/// [`direct_part`], with or without the point lights' light.
pub fn direct_part_with(
    scene: &Scene,
    p: DVec3,
    lobe: &Lobe,
    points: PointLights,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    let mut sum = match points {
        PointLights::Included => delta_lights(scene, p, lobe, None, rays, &mut ignore),
        PointLights::Left => delta_suns(scene, p, lobe, None, rays, &mut ignore),
    };
    for sun in scene.suns.iter().filter(|s| !s.is_delta()) {
        let (u1, u2) = (s.next_f64(), s.next_f64());
        let w = sample_cone(sun.to_sun, sun.cos_max, u1, u2);
        // Uniform in the cone: pdf = 1 / solid angle.
        let l = LightSample {
            w,
            dist: f64::INFINITY,
            radiance: sun.radiance,
            pdf: 1.0 / sun.solid_angle(),
        };
        sum += light_sample(scene, p, lobe, None, &l, false, rays, &mut ignore);
    }
    sum
}

/// The delta lights visible from `x` (suns with a cone taken at its centre), and the
/// shadow rays this cost.
pub fn gather_direct(scene: &Scene, x: DVec3) -> (Vec<DirectLight<D3>>, u64) {
    let (mut out, mut rays) = (Vec::new(), 0);
    gather(scene, &scene.point_lights, x, &mut out, &mut rays);
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
        // The depth is piecewise linear in x: central differences are exact off the
        // box's edges.
        let h = 1e-6 * scene.scale;
        let depth_grad = DVec3::new(
            depth_at(x + DVec3::X * h) - depth_at(x - DVec3::X * h),
            depth_at(x + DVec3::Y * h) - depth_at(x - DVec3::Y * h),
            depth_at(x + DVec3::Z * h) - depth_at(x - DVec3::Z * h),
        ) / (2.0 * h);
        out.push(DirectLight::Directional {
            to_light: w,
            irradiance: sun.irradiance,
            depth: depth_at(x),
            depth_grad,
            transmittance: scene.transmittance(x, w, scene.world_exit(x, w)),
        });
    }
    (out, rays)
}
