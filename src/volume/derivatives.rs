//! Derivative methods for L_s at a medium point in 3D (the counterpart of
//! `flatland::derivatives`), per part (direct: delta lights; single: light from
//! surfaces and the sky; multiple: light from the medium):
//! - [`aware`]: value, gradient and Hessian from the occlusion-free proxy elements
//!   ([`super::proxy`]);
//! - [`unaware`]: value and gradient as Jarosz et al. 2008 (directions and the
//!   along-ray parametrisation fixed, visibility and measure ignored);
//! - [`reference`]: central finite differences of the path-traced L_s (all parts
//!   together) with common random numbers;
//! - [`plain_estimate`]: the Monte Carlo estimate of the light field.

use super::lights::Lobe;
use super::probe::{DirectLight, LightField, Outgoing};
use super::proxy::{Element, ElementKind};
use super::scene::Scene;
use super::transport::{Settings, sample_lobe};
use crate::core::color::Rgb;
use crate::core::distance::distance;
use crate::core::element::{medium_form_factor_smoothed, near_distance};
use crate::core::phase::{phase_taylor_fixed_direction, phase_taylor_out};
use crate::core::rng::Sampler;
use crate::core::space::D3;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use crate::core::transmittance::{transmittance_taylor, transmittance_taylor_rgb};
use crate::core::triangle::triangle_form_factor;
use crate::core::unaware::{UnawareRay, hit_distance_gradient};
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// L_s with its derivatives, per part.
pub type PartDerivs = crate::core::taylor_rgb::PartDerivs<D3>;

/// The occlusion-aware method's settings are the 2D ones.
pub use crate::flatland::derivatives::AwareSettings;

/// The direct part (delta lights) with closed-form derivatives, visibility fixed.
/// Transmittance to a point light uses the effective extinction −ln T / r of the
/// stored value; a sun's uses the medium depth along it and its gradient.
pub fn direct_derivatives(lf: &LightField) -> TaylorRgb<D3> {
    let x = lf.x;
    let mut sum = TaylorRgb::default();
    for l in &lf.direct_lights {
        match *l {
            DirectLight::Point {
                position,
                intensity,
                transmittance,
            } => {
                let r = (position - x).length().max(1e-300);
                let phase = phase_taylor_out::<D3>(lf.g, x, position, lf.outgoing(), 0.0);
                let dist = distance::<D3>(x, position, 0.0);
                let inv_r2 = dist.compose(1.0 / (r * r), -2.0 / (r * r * r), 6.0 / (r * r * r * r));
                let t = [0, 1, 2].map(|c| {
                    let tr = transmittance[c];
                    if tr > 0.0 {
                        transmittance_taylor::<D3>(-tr.ln() / r, x, position, 0.0)
                    } else {
                        Taylor2::zero()
                    }
                });
                sum += TaylorRgb::tint(phase * inv_r2, intensity * lf.sigma_s).mul_channels(t);
            }
            DirectLight::Sun {
                to_sun,
                irradiance,
                depth,
                depth_grad,
                transmittance,
            } => {
                let f = phase_taylor_fixed_direction::<D3>(lf.g, x, to_sun, lf.outgoing());
                let t = [0, 1, 2].map(|c| {
                    let tr = transmittance[c];
                    let sig = if tr > 0.0 && depth > 0.0 { -tr.ln() / depth } else { 0.0 };
                    let outer = DMat3::from_cols(
                        depth_grad * depth_grad.x,
                        depth_grad * depth_grad.y,
                        depth_grad * depth_grad.z,
                    );
                    Taylor2::new(tr, depth_grad * (-sig * tr), outer * (sig * sig * tr))
                });
                sum += TaylorRgb::tint(f, irradiance * lf.sigma_s).mul_channels(t);
            }
        }
    }
    sum
}

/// The light an element sends to x, T L F (no phase, no σ_s), with derivatives.
pub fn element_incident(lf: &LightField, e: &Element, medium_clamp: f64) -> TaylorRgb<D3> {
    let x = lf.x;
    let soft = near_distance(e.size());
    let form = match e.kind {
        // Surfaces and shell pieces bridging an occluder's edge: the solid angle
        // (times the thickness Δt carried in a medium piece's radiance).
        ElementKind::Surface => triangle_form_factor(e.v, x),
        // Its near field is bounded at the march resolution: within medium_clamp·Δt
        // of x (where the solid angle's derivatives grow like 1/distance to an edge
        // and the core has no clamped triangle form factor) it is treated as an
        // ordinary shell piece.
        ElementKind::Medium if e.bridging && e.v.iter().all(|&p| (p - x).length() >= medium_clamp * lf.step) => {
            triangle_form_factor(e.v, x)
        }
        // An ordinary shell piece: a fixed volume V = Ω_dir r_anchor² Δt with form
        // factor V/r², smoothed at the march resolution. Its radiance carries Δt.
        ElementKind::Medium => {
            let r = (e.anchor - x).length();
            let volume = e.dir_solid_angle * r * r * lf.step;
            medium_form_factor_smoothed::<D3>(e.anchor, volume, x, medium_clamp * lf.step) * (1.0 / lf.step)
        }
    };
    TaylorRgb::tint(form, e.radiance).mul_channels(transmittance_taylor_rgb::<D3>(lf.sigma_t, x, e.anchor, soft))
}

/// One proxy element's contribution σ_s f T L F with its derivatives.
pub fn element_contribution(lf: &LightField, e: &Element, medium_clamp: f64) -> TaylorRgb<D3> {
    let soft = near_distance(e.size());
    let phase = phase_taylor_out::<D3>(lf.g, lf.x, e.anchor, lf.outgoing(), soft);
    element_incident(lf, e, medium_clamp).mul_channels([
        phase * lf.sigma_s.x,
        phase * lf.sigma_s.y,
        phase * lf.sigma_s.z,
    ])
}

/// Elements summed per parallel task: the partial sums are added in a fixed order,
/// so the result is the same bit for bit whatever the thread count.
const SUM_CHUNK: usize = 2048;

/// Ours: value, gradient and Hessian of L_s from the proxy elements.
pub fn aware(lf: &LightField, elements: &[Element], settings: &AwareSettings) -> PartDerivs {
    let partial: Vec<(TaylorRgb<D3>, TaylorRgb<D3>)> = elements
        .par_chunks(SUM_CHUNK)
        .map(|chunk| {
            let (mut s, mut m) = (TaylorRgb::<D3>::default(), TaylorRgb::<D3>::default());
            for e in chunk.iter().filter(|e| e.radiance != Rgb::ZERO) {
                let c = element_contribution(lf, e, settings.medium_clamp);
                match e.kind {
                    ElementKind::Surface => s += c,
                    ElementKind::Medium => m += c,
                }
            }
            (s, m)
        })
        .collect();
    let (mut single, mut multiple) = (TaylorRgb::default(), TaylorRgb::default());
    for (s, m) in partial {
        single += s;
        multiple += m;
    }
    PartDerivs {
        direct: direct_derivatives(lf),
        single,
        multiple,
    }
}

/// Jarosz et al. 2008: each ray's direction and its samples' relative position along
/// the ray fixed; the hit point slides on the hit surface's plane, so only the
/// transmittance (through the distance s to the surface) changes: ∇s = −n/(n·ω).
/// Medium samples sit at fixed fractions u of s, with thickness Δu·s. Escaped rays
/// have a fixed length. The measure and visibility are treated as constant. First
/// order only.
pub fn unaware(lf: &LightField) -> PartDerivs {
    let domega = lf.ray_measure();
    let out = lf.outgoing();
    let (mut single, mut multiple) = ([Taylor2::<D3>::zero(); 3], [Taylor2::<D3>::zero(); 3]);
    let mut samples = Vec::new();
    for r in &lf.rays {
        samples.clear();
        samples.extend(r.samples.iter().enumerate().map(|(i, l)| (lf.sample_depth(r, i), *l)));
        let f = phase_taylor_fixed_direction::<D3>(lf.g, lf.x, r.dir, out);
        UnawareRay::<D3> {
            sigma_t: lf.sigma_t,
            weight: lf.sigma_s * (f.value * domega),
            weight_log_grad: if f.value > 0.0 { f.grad / f.value } else { DVec3::ZERO },
            grad_s: r
                .hit
                .map_or(DVec3::ZERO, |h| hit_distance_gradient::<D3>(h.normal, r.dir)),
            length: r.length,
            end_radiance: r.hit.map_or(r.escaped, |h| h.radiance),
            samples: &samples,
            step: lf.step,
        }
        .accumulate(&mut single, &mut multiple);
    }
    let mut direct = direct_derivatives(lf);
    for ch in &mut direct.channels {
        ch.hess = DMat3::ZERO;
    }
    PartDerivs {
        direct,
        single: TaylorRgb { channels: single },
        multiple: TaylorRgb { channels: multiple },
    }
}

/// The plain Monte Carlo estimate of L_s from the light field, per part
/// (direct, single, multiple).
pub fn plain_estimate(lf: &LightField) -> [Rgb; 3] {
    let p = unaware(lf);
    [p.direct.value(), p.single.value(), p.multiple.value()]
}

/// Path-traced L_s(x, ω_o) (all parts), `spp` samples with streams (seed, 0, k).
pub fn path_traced(scene: &Scene, x: DVec3, omega_o: DVec3, spp: u64, settings: &Settings, seed: u64) -> (Rgb, u64) {
    let Some(m) = scene.medium_at(x) else {
        return (Rgb::ZERO, 0);
    };
    let lobe = Lobe::Phase {
        hg: m.phase,
        travel: -omega_o,
    };
    let mut rays = 0;
    let mut sum = Rgb::ZERO;
    for k in 0..spp {
        let mut s = Sampler::new2(seed, 0, k);
        sum += sample_lobe(scene, x, &lobe, None, settings, &mut s, &mut rays);
    }
    (sum * m.sigma_s / spp.max(1) as f64, rays)
}

/// Central differences of the path-traced L_s at x with common random numbers:
/// value and gradient (7 points), Hessian left zero. Step `h` in scene units.
pub fn reference_gradient(
    scene: &Scene,
    x: DVec3,
    omega_o: DVec3,
    h: f64,
    spp: u64,
    settings: &Settings,
    seed: u64,
) -> TaylorRgb<D3> {
    reference_gradient_towards(scene, x, Outgoing::Direction(omega_o), h, spp, settings, seed)
}

/// [`reference_gradient`] of L_s towards a fixed direction or towards a point (then
/// each stencil point scatters towards it: the derivative of what a camera sees).
pub fn reference_gradient_towards(
    scene: &Scene,
    x: DVec3,
    out: Outgoing<DVec3>,
    h: f64,
    spp: u64,
    settings: &Settings,
    seed: u64,
) -> TaylorRgb<D3> {
    let offsets = [
        DVec3::ZERO,
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Y,
        DVec3::Z,
        -DVec3::Z,
    ];
    let v: Vec<Rgb> = offsets
        .par_iter()
        .map(|&o| {
            let p = x + o * h;
            let omega_o = match out {
                Outgoing::Direction(w) => w,
                Outgoing::TowardsPoint(e) => (e - p).normalize_or(DVec3::Z),
            };
            path_traced(scene, p, omega_o, spp, settings, seed).0
        })
        .collect();
    let ch = |c: usize| {
        let g = DVec3::new(v[1][c] - v[2][c], v[3][c] - v[4][c], v[5][c] - v[6][c]) / (2.0 * h);
        Taylor2::new(v[0][c], g, DMat3::ZERO)
    };
    TaylorRgb {
        channels: [ch(0), ch(1), ch(2)],
    }
}
