//! Derivative methods for L_s at a medium point (theory.md §4–5), per part:
//! - `aware`: value, gradient and Hessian from the occlusion-free proxy elements
//!   (the paper's method, [`super::proxy`]);
//! - `unaware`: value and gradient as Jarosz et al. 2008 (directions and the
//!   along-ray parametrisation fixed, visibility and measure ignored);
//! - `reference`: central finite differences of the path-traced L_s with common
//!   random numbers (the same streams at every stencil point).

use super::scene::Scene;
use super::transport::{Estimate, Query, Settings, estimate};
use crate::core::color::Rgb;
use crate::core::space::D2;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use crate::core::unaware::{UnawareRay, hit_distance_gradient};
use glam::{DMat2, DVec2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// L_s with its derivatives, per part (theory.md §2).
pub type PartDerivs = crate::core::taylor_rgb::PartDerivs<D2>;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Occlusion-aware value, gradient and Hessian from proxy elements (ours).
    Aware,
    /// Occlusion-unaware value and gradient (Jarosz et al. 2008).
    Unaware,
    /// Central finite differences of path-traced L_s with common random numbers.
    Reference,
}

/// A method's answer at one point and what it cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Derivatives {
    pub method: Method,
    pub at: DVec2,
    pub parts: PartDerivs,
    /// False for first-order methods (the Hessian fields are zero).
    pub has_hessian: bool,
    pub rays: u64,
    pub seconds: f64,
}

/// Finite-difference reference settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReferenceSettings {
    /// Samples per stencil point.
    pub spp: u32,
    /// Step h as a fraction of the scene size (domain diagonal).
    pub relative_step: f64,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            spp: 20_000,
            relative_step: 4e-3,
        }
    }
}

/// Central differences of the estimated L_s at x: 9-point stencil (±h on each axis
/// for gradient and diagonal, the 4 diagonal points for the mixed term), every
/// point with the same random streams.
pub fn reference(
    scene: &Scene,
    x: DVec2,
    omega_o: DVec2,
    rs: &ReferenceSettings,
    settings: &Settings,
    seed: u64,
) -> Derivatives {
    let start = std::time::Instant::now();
    let h = rs.relative_step * scene.scale();
    let offsets = [
        (0, 0),
        (1, 0),
        (-1, 0),
        (0, 1),
        (0, -1),
        (1, 1),
        (1, -1),
        (-1, 1),
        (-1, -1),
    ];
    let q = Query::InScattered { omega_o };
    let est: Vec<Estimate> = offsets
        .par_iter()
        .map(|&(i, j)| {
            let p = x + DVec2::new(i as f64, j as f64) * h;
            estimate(scene, p, &q, settings, rs.spp, seed, 0)
        })
        .collect();
    let rays = est.iter().map(|e| e.rays).sum();
    let part = |get: &dyn Fn(&Estimate) -> Rgb| -> TaylorRgb<D2> {
        let v: Vec<Rgb> = est.iter().map(get).collect();
        let channel = |c: usize| {
            let f = |k: usize| v[k][c];
            let grad = DVec2::new(f(1) - f(2), f(3) - f(4)) / (2.0 * h);
            let hxx = (f(1) - 2.0 * f(0) + f(2)) / (h * h);
            let hyy = (f(3) - 2.0 * f(0) + f(4)) / (h * h);
            let hxy = (f(5) - f(6) - f(7) + f(8)) / (4.0 * h * h);
            Taylor2::new(f(0), grad, DMat2::from_cols_array(&[hxx, hxy, hxy, hyy]))
        };
        TaylorRgb {
            channels: [channel(0), channel(1), channel(2)],
        }
    };
    let parts = PartDerivs {
        direct: part(&|e| e.mean.direct),
        single: part(&|e| e.mean.single),
        multiple: part(&|e| e.mean.multiple),
    };
    Derivatives {
        method: Method::Reference,
        at: x,
        parts,
        has_hessian: true,
        rays,
        seconds: start.elapsed().as_secs_f64(),
    }
}

use super::direct::DirectLight;
use super::probe::LightField;
use super::proxy::{Element, ElementKind};
use crate::core::distance::distance;
use crate::core::element::{
    medium_form_factor_smoothed, near_distance, segment_form_factor, segment_form_factor_clamped,
};

/// Settings of the occlusion-aware method.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AwareSettings {
    pub rule: super::proxy::RadianceRule,
    /// Near-field clamp of medium elements' form-factor derivatives, in units of
    /// the march step Δt.
    pub medium_clamp: f64,
}

impl Default for AwareSettings {
    fn default() -> Self {
        AwareSettings {
            rule: super::proxy::RadianceRule::Farther,
            medium_clamp: 1.0,
        }
    }
}
use crate::core::phase::{Hg2, phase_taylor};
use crate::core::transmittance::{transmittance_taylor, transmittance_taylor_rgb};

/// The direct part (delta lights) with closed-form derivatives, visibility fixed.
/// Transmittance through partial medium regions uses the effective extinction
/// −ln T / r of the stored value.
pub fn direct_derivatives(lf: &LightField) -> TaylorRgb<D2> {
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
                let sig = transmittance
                    .to_array()
                    .map(|t| if t > 0.0 { -t.ln() / r } else { 0.0 });
                let phase = phase_taylor::<D2>(lf.g, x, position, lf.omega_o, 0.0);
                let dist = distance::<D2>(x, position, 0.0);
                let inv_r = dist.compose(1.0 / r, -1.0 / (r * r), 2.0 / (r * r * r));
                let geo = phase * inv_r;
                let t = [0, 1, 2].map(|c| {
                    if transmittance[c] > 0.0 {
                        transmittance_taylor::<D2>(sig[c], x, position, 0.0)
                    } else {
                        Taylor2::zero()
                    }
                });
                sum += TaylorRgb::tint(geo, intensity * lf.sigma_s).mul_channels(t);
            }
            DirectLight::Collimated {
                direction,
                irradiance,
                distance: d,
                aperture_normal,
                transmittance,
            } => {
                // t(x) = n·(x − a0)/(n·dir) is linear in x: ∇t = n/(n·dir).
                let nd = aperture_normal.dot(direction);
                let grad_t = if nd.abs() > 1e-12 {
                    aperture_normal / nd
                } else {
                    DVec2::ZERO
                };
                let f = Hg2::new(lf.g).eval(-lf.omega_o, -direction);
                let t = [0, 1, 2].map(|c| {
                    let tr = transmittance[c];
                    let sig = if tr > 0.0 && d > 0.0 { -tr.ln() / d } else { 0.0 };
                    let g = grad_t * (-sig * tr);
                    Taylor2::new(
                        tr,
                        g,
                        DMat2::from_cols(grad_t * grad_t.x, grad_t * grad_t.y) * (sig * sig * tr),
                    )
                });
                sum += TaylorRgb::tint(Taylor2::constant(f), irradiance * lf.sigma_s).mul_channels(t);
            }
        }
    }
    sum
}

/// One proxy element's contribution σ_s f T L F with its derivatives.
pub fn element_contribution(lf: &LightField, e: &Element, medium_clamp: f64) -> TaylorRgb<D2> {
    let soft = near_distance((e.b - e.a).length());
    let phase = phase_taylor::<D2>(lf.g, lf.x, e.anchor, lf.omega_o, soft);
    element_incident(lf, e, medium_clamp).mul_channels([
        phase * lf.sigma_s.x,
        phase * lf.sigma_s.y,
        phase * lf.sigma_s.z,
    ])
}

/// The light an element sends to x, T L F (no phase, no σ_s), with derivatives.
pub fn element_incident(lf: &LightField, e: &Element, medium_clamp: f64) -> TaylorRgb<D2> {
    let x = lf.x;
    let size = (e.b - e.a).length();
    let soft = near_distance(size);
    let form = match e.kind {
        ElementKind::Surface => segment_form_factor(e.a, e.b, x),
        // A shell piece bridging an occluder's edge: like a surface element, its
        // subtended angle (times the thickness Δt carried in its radiance) changes as
        // the edge moves. Its near field is bounded at the march resolution.
        ElementKind::Medium if e.bridging => segment_form_factor_clamped(e.a, e.b, x, soft.max(medium_clamp * lf.step)),
        // An ordinary shell piece: a fixed area A = width·Δt with form factor A/r
        // (theory.md §5). Its radiance carries Δt already, so the measure is the width.
        // (The subtended-angle form would make the gradient's noise grow like √N:
        // its derivative is per vertex, not per angle.)
        // The width is the angular extent at the anchor's depth (the two samples' depths
        // differ by the rays' jitter, which is not part of the piece's width).
        ElementKind::Medium => {
            let (pa, pb) = (e.a - x, e.b - x);
            let width = pa.perp_dot(pb).atan2(pa.dot(pb)).abs() * (e.anchor - x).length();
            medium_form_factor_smoothed::<D2>(e.anchor, width * lf.step, x, medium_clamp * lf.step) * (1.0 / lf.step)
        }
    };
    TaylorRgb::tint(form, e.radiance).mul_channels(transmittance_taylor_rgb::<D2>(lf.sigma_t, x, e.anchor, soft))
}

/// Circular-harmonic moments of the incident light, per cached part, each with its
/// derivatives (theory.md §1): M_k = Σ_j (T L F)_j (cos kθ_j, sin kθ_j), k = 0..=K.
/// An anisotropic medium caches these and evaluates L_s for any ω_o with
/// [`Moments::in_scattered`]; an isotropic one needs K = 0 only.
#[derive(Clone, Debug)]
pub struct Moments {
    pub single: Vec<[TaylorRgb<D2>; 2]>,
    pub multiple: Vec<[TaylorRgb<D2>; 2]>,
    pub g: f64,
    pub sigma_s: Rgb,
}

impl Moments {
    /// Single and multiple scattering towards `omega_o` (σ_s f ∗ moments).
    pub fn in_scattered(&self, omega_o: DVec2) -> (TaylorRgb<D2>, TaylorRgb<D2>) {
        let eval = |m: &[[TaylorRgb<D2>; 2]]| {
            let ch = |c: usize| {
                let per: Vec<[Taylor2<D2>; 2]> = m.iter().map(|k| [k[0].channels[c], k[1].channels[c]]).collect();
                crate::core::harmonics::hg2_in_scatter(self.g, &per, omega_o) * self.sigma_s[c]
            };
            TaylorRgb {
                channels: [ch(0), ch(1), ch(2)],
            }
        };
        (eval(&self.single), eval(&self.multiple))
    }
}

/// The moments of order 0..=`order` (forced to 0 for isotropic media: they pay nothing).
pub fn aware_moments(lf: &LightField, elements: &[Element], settings: &AwareSettings, order: usize) -> Moments {
    let order = if lf.g == 0.0 { 0 } else { order };
    let zero = [TaylorRgb::default(); 2];
    let (mut single, mut multiple) = (vec![zero; order + 1], vec![zero; order + 1]);
    let mut basis = vec![[Taylor2::<D2>::zero(); 2]; order + 1];
    for e in elements {
        let incident = element_incident(lf, e, settings.medium_clamp);
        let soft = near_distance((e.b - e.a).length());
        crate::core::harmonics::circular_harmonics(lf.x, e.anchor, soft, &mut basis);
        let target = match e.kind {
            ElementKind::Surface => &mut single,
            ElementKind::Medium => &mut multiple,
        };
        for (m, b) in target.iter_mut().zip(&basis) {
            m[0] += incident.mul_channels([b[0]; 3]);
            m[1] += incident.mul_channels([b[1]; 3]);
        }
    }
    Moments {
        single,
        multiple,
        g: lf.g,
        sigma_s: lf.sigma_s,
    }
}

/// Ours: value, gradient and Hessian of L_s from the proxy elements.
pub fn aware(lf: &LightField, elements: &[Element], settings: &AwareSettings) -> PartDerivs {
    let mut parts = PartDerivs {
        direct: direct_derivatives(lf),
        ..Default::default()
    };
    for e in elements {
        let c = element_contribution(lf, e, settings.medium_clamp);
        match e.kind {
            ElementKind::Surface => parts.single += c,
            ElementKind::Medium => parts.multiple += c,
        }
    }
    parts
}

/// Jarosz et al. 2008: each ray's direction and its samples' relative position along
/// the ray fixed; the hit point slides on the hit surface's line, so only the
/// transmittance (through the distance s to the surface) changes:
/// ∇s = −n/(n·ω). Medium samples sit at fixed fractions u of s, with thickness
/// Δu·s. The measure and visibility are treated as constant. First order only.
pub fn unaware(lf: &LightField) -> PartDerivs {
    let hg = Hg2::new(lf.g);
    let dtheta = lf.ray_measure();
    let (mut single, mut multiple) = ([Taylor2::<D2>::zero(); 3], [Taylor2::<D2>::zero(); 3]);
    let mut samples = Vec::new();
    for r in &lf.rays {
        samples.clear();
        samples.extend(r.samples.iter().enumerate().map(|(i, l)| (lf.sample_depth(r, i), *l)));
        UnawareRay::<D2> {
            sigma_t: lf.sigma_t,
            weight: lf.sigma_s * (hg.eval(-lf.omega_o, r.dir) * dtheta),
            weight_log_grad: DVec2::ZERO,
            // Rays cut in the medium have a length that does not depend on x.
            grad_s: r
                .hit
                .map_or(DVec2::ZERO, |h| hit_distance_gradient::<D2>(h.normal, r.dir)),
            length: r.length,
            end_radiance: r.hit.map_or(Rgb::ZERO, |h| h.radiance),
            samples: &samples,
            step: lf.step,
        }
        .accumulate(&mut single, &mut multiple);
    }
    let mut direct = direct_derivatives(lf);
    for ch in &mut direct.channels {
        ch.hess = DMat2::ZERO;
    }
    PartDerivs {
        direct,
        single: TaylorRgb { channels: single },
        multiple: TaylorRgb { channels: multiple },
    }
}

/// The plain Monte Carlo estimate of L_s from the light field (theory.md §3).
pub fn plain_estimate(lf: &LightField) -> super::transport::Parts {
    let p = unaware(lf);
    super::transport::Parts {
        direct: p.direct.value(),
        single: p.single.value(),
        multiple: p.multiple.value(),
    }
}
