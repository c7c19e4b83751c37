//! Scattering lobes at path vertices and next-event estimation (NEE) to lights.
//!
//! Direction convention (theory.md §1): a direction ω at a vertex points *towards*
//! where light comes from; the light travels along −ω.
//!
//! - Point and collimated lights are delta lights: evaluated analytically with
//!   visibility and transmittance.
//! - Emitting segments are sampled by subtended angle (uniform in angle, exact in
//!   2D) and combined with lobe sampling by the power heuristic (MIS).

use super::geometry::{cross, intersect_segment};
use super::scene::Scene;
use crate::core::color::Rgb;
use crate::core::rng::Sampler;
use crate::core::space::D2;
use crate::pipeline::nee::{LightSample, gather, light_sample, point_lights};
use crate::pipeline::world::{DirectLight, World};
use glam::DVec2;

/// A path vertex's lobe in flatland.
pub type Lobe = crate::pipeline::lobe::Lobe<D2>;

/// Light from point and collimated lights arriving at `p` and weighted by `lobe`
/// (∫ value(ω) L_i,delta(ω) dω). `skip` is the segment `p` lies on, if any.
pub fn direct_lights(
    scene: &Scene,
    p: DVec2,
    lobe: &Lobe,
    skip: Option<u32>,
    rays: &mut u64,
    each: &mut impl FnMut(DVec2, Rgb),
) -> Rgb {
    point_lights(scene, &scene.point_lights, p, lobe, skip, rays, each)
        + collimated_lights(scene, p, lobe, skip, rays, each)
}

/// Light from collimated lights arriving at `p` and weighted by `lobe`.
pub fn collimated_lights(
    scene: &Scene,
    p: DVec2,
    lobe: &Lobe,
    skip: Option<u32>,
    rays: &mut u64,
    each: &mut impl FnMut(DVec2, Rgb),
) -> Rgb {
    let mut sum = Rgb::ZERO;
    for l in &scene.collimated_lights {
        let w = -l.direction;
        // The beam reaches p only through its aperture.
        if let Some((dist, _)) = intersect_segment(p, w, l.aperture[0], l.aperture[1], 0.0, f64::INFINITY) {
            let l = LightSample {
                w,
                dist,
                radiance: l.irradiance,
                pdf: 1.0,
            };
            sum += light_sample(scene, p, lobe, skip, &l, false, rays, each);
        }
    }
    sum
}

/// Angle subtended at `p` by segment `i`, and the direction to its end `a`.
#[inline]
fn subtended(scene: &Scene, p: DVec2, i: u32) -> (f64, DVec2, DVec2) {
    let s = &scene.geometry.prims[i as usize];
    let (a, b) = (s.a - p, s.b - p);
    (cross(a, b).abs().atan2(a.dot(b)), a, b)
}

/// Probability density (per radian) with which [`emitter_nee`] at `p` picks the
/// direction that hits emitting segment `seg`.
pub fn emitter_pdf(scene: &Scene, p: DVec2, seg: u32) -> f64 {
    let Some(k) = scene.emitters.find(seg) else {
        return 0.0;
    };
    let (theta, _, _) = subtended(scene, p, seg);
    if theta > 0.0 {
        scene.emitters.probability(k) / theta
    } else {
        0.0
    }
}

/// One-sample NEE to emitting segments at `p`, weighted by `lobe`. With `mis`, the
/// result carries the power-heuristic weight against lobe sampling (the path then
/// weights emission it hits with [`emitter_pdf`]); without, the full contribution.
#[allow(clippy::too_many_arguments)] // the vertex state is spelled out
pub fn emitter_nee(
    scene: &Scene,
    p: DVec2,
    lobe: &Lobe,
    skip: Option<u32>,
    mis: bool,
    s: &mut Sampler,
    rays: &mut u64,
    each: &mut impl FnMut(DVec2, Rgb),
) -> Rgb {
    if scene.emitters.is_empty() {
        return Rgb::ZERO;
    }
    let (k, i) = scene.emitters.pick(s.next_f64());
    let v = s.next_f64();
    if Some(i) == skip {
        return Rgb::ZERO;
    }
    let seg = &scene.geometry.prims[i as usize];
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
    let e = seg.b - seg.a;
    let dist = cross(seg.a - p, e) / cross(w, e);
    if !(dist > 0.0 && dist.is_finite()) {
        return Rgb::ZERO;
    }
    let pdf = scene.emitters.probability(k) / theta;
    let l = LightSample {
        w,
        dist,
        radiance: seg.emission,
        pdf,
    };
    light_sample(scene, p, lobe, skip, &l, mis, rays, each)
}

/// The delta lights visible from `x` (theory.md §2), and the shadow rays this cost.
pub fn gather_direct(scene: &Scene, x: DVec2) -> (Vec<DirectLight<D2>>, u64) {
    let (mut out, mut rays) = (Vec::new(), 0);
    gather(scene, &scene.point_lights, x, &mut out, &mut rays);
    for l in &scene.collimated_lights {
        let w = -l.direction;
        let Some((t, _)) = intersect_segment(x, w, l.aperture[0], l.aperture[1], 0.0, f64::INFINITY) else {
            continue;
        };
        rays += 1;
        if !scene.occluded(x, w, t, None) {
            // The distance t(x) = n·(x − a0)/(n·dir) to the aperture is linear in x.
            let n = (l.aperture[1] - l.aperture[0]).perp().normalize();
            let nd = n.dot(l.direction);
            out.push(DirectLight::Directional {
                to_light: w,
                irradiance: l.irradiance,
                depth: t,
                depth_grad: if nd.abs() > 1e-12 { n / nd } else { DVec2::ZERO },
                transmittance: scene.transmittance(x, w, t),
            });
        }
    }
    (out, rays)
}
