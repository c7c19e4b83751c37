//! Derivative methods for L_s at a medium point (theory.md §4–5), per part (direct:
//! delta lights; single: light from surfaces and the sky; multiple: light from the
//! medium), in any dimension:
//! - [`aware`]: value, gradient and Hessian from the occlusion-free proxy elements
//!   (the paper's method, [`super::proxy`]);
//! - [`unaware`]: value and gradient as Jarosz et al. 2008 (directions and the
//!   along-ray parametrisation fixed, visibility and measure ignored);
//! - [`reference`]: central finite differences of the path-traced L_s with common
//!   random numbers (the same streams at every stencil point);
//! - [`plain_estimate`]: the light field's Monte Carlo estimate (theory.md §3).

use super::dim::Dim;
use super::path::{Estimate, Parts, Query, Settings, estimate};
use super::probe::{LightField, Outgoing};
use super::proxy::{Element, ElementKind, RadianceRule};
use super::slide;
use super::world::{DirectLight, World};
use crate::core::color::Rgb;
use crate::core::distance::distance;
use crate::core::element::{medium_form_factor_smoothed, near_distance};
use crate::core::phase::{phase_taylor_fixed_direction, phase_taylor_out};
use crate::core::space::Space;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use crate::core::transmittance::{transmittance_taylor, transmittance_taylor_rgb};
use crate::core::unaware::{UnawareRay, hit_distance_gradient};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// L_s with its derivatives, per part (theory.md §2).
pub type PartDerivs<S> = crate::core::taylor_rgb::PartDerivs<S>;

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
pub struct Derivatives<S: Dim> {
    pub method: Method,
    pub at: S::Vec,
    pub parts: PartDerivs<S>,
    /// False for first-order methods (the Hessian fields are zero).
    pub has_hessian: bool,
    pub rays: u64,
    pub seconds: f64,
}

/// Settings of the occlusion-aware method.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AwareSettings {
    pub rule: RadianceRule,
    /// Near-field clamp of medium elements' form-factor derivatives, in units of
    /// the march step Δt.
    pub medium_clamp: f64,
}

impl Default for AwareSettings {
    fn default() -> Self {
        AwareSettings {
            rule: RadianceRule::Farther,
            medium_clamp: 1.0,
        }
    }
}

/// The direct part (delta lights) with closed-form derivatives, visibility fixed.
/// Transmittance uses the effective extinction −ln T / depth of the stored value
/// (exact for a homogeneous medium along the whole way, and for partial regions
/// whose boundary does not move with x).
pub fn direct_derivatives<S: Dim>(lf: &LightField<S>) -> TaylorRgb<S> {
    let x = lf.x;
    let mut sum = TaylorRgb::default();
    let n = (S::DIM - 1) as f64;
    for l in &lf.direct_lights {
        match *l {
            DirectLight::Point {
                position,
                intensity,
                transmittance,
            } => {
                // I·T/r^{d−1}: 1/r (2D) or 1/r² (3D).
                let r = S::length(position - x).max(1e-300);
                let phase = phase_taylor_out::<S>(lf.g, x, position, lf.outgoing(), 0.0);
                let h = r.powi(-(S::DIM as i32 - 1));
                let falloff = distance::<S>(x, position, 0.0).compose(h, -n * h / r, n * (n + 1.0) * h / (r * r));
                let t = [0, 1, 2].map(|c| {
                    let tr = transmittance[c];
                    if tr > 0.0 {
                        transmittance_taylor::<S>(-tr.ln() / r, x, position, 0.0)
                    } else {
                        Taylor2::zero()
                    }
                });
                sum += TaylorRgb::tint(phase * falloff, intensity * lf.sigma_s).mul_channels(t);
            }
            DirectLight::Directional {
                to_light,
                irradiance,
                depth,
                depth_grad,
                transmittance,
            } => {
                let f = phase_taylor_fixed_direction::<S>(lf.g, x, to_light, lf.outgoing());
                let t = [0, 1, 2].map(|c| {
                    let tr = transmittance[c];
                    let sig = if tr > 0.0 && depth > 0.0 { -tr.ln() / depth } else { 0.0 };
                    Taylor2::new(
                        tr,
                        depth_grad * (-sig * tr),
                        S::outer(depth_grad, depth_grad) * (sig * sig * tr),
                    )
                });
                sum += TaylorRgb::tint(f, irradiance * lf.sigma_s).mul_channels(t);
            }
        }
    }
    sum
}

/// The light an element sends to x, T L F (no phase, no σ_s), with derivatives.
pub fn element_incident<S: Dim>(lf: &LightField<S>, e: &Element<S>, medium_clamp: f64) -> TaylorRgb<S> {
    let x = lf.x;
    let soft = near_distance(e.size());
    let clamp = medium_clamp * lf.step;
    let form = match e.kind {
        // Surfaces: the angle (solid angle), unclamped. Every vertex is a ray's end
        // or a silhouette, never nearer than the nearest surface, and the elements'
        // vertex terms cancel in pairs along a chain only if each vertex is treated
        // alike in both; a clamp scaled by each element's size broke that next to
        // surfaces (a long silhouette element clamped a near vertex its short
        // neighbour did not: gradient 26× off at 1e-5 from an emitter).
        ElementKind::Surface => S::form_factor_clamped(e.v, x, 0.0),
        // Shell pieces bridging an occluder's edge: the angle (solid angle), times
        // the thickness Δt carried in a medium piece's radiance.
        // Its near field is bounded at the march resolution: within medium_clamp·Δt
        // of x (where the form factor's derivatives grow like 1/distance to an edge)
        // it is treated as an ordinary shell piece.
        ElementKind::Medium if e.bridging && e.v.as_ref().iter().all(|&p| S::length(p - x) >= clamp) => {
            S::form_factor(e.v, x)
        }
        // An ordinary shell piece: a fixed measure A = Ω_dir r_anchor^{d−1} Δt with
        // form factor A/r^{d−1}, smoothed at the march resolution (the angle form
        // would make the gradient's noise grow like √N: its derivative is per vertex,
        // not per angle). Its radiance carries Δt.
        ElementKind::Medium => {
            let r = S::length(e.anchor - x);
            let measure = e.dir_measure * r.powi(S::DIM as i32 - 1) * lf.step;
            medium_form_factor_smoothed::<S>(e.anchor, measure, x, clamp) * (1.0 / lf.step)
        }
    };
    TaylorRgb::tint(form, e.radiance).mul_channels(transmittance_taylor_rgb::<S>(lf.sigma_t, x, e.anchor, soft))
}

/// One proxy element's contribution σ_s f T L F with its derivatives.
pub fn element_contribution<S: Dim>(lf: &LightField<S>, e: &Element<S>, medium_clamp: f64) -> TaylorRgb<S> {
    let soft = near_distance(e.size());
    let s = lf.sigma_s;
    let times_sigma_s = |t: [Taylor2<S>; 3]| [t[0] * s.x, t[1] * s.y, t[2] * s.z];
    if e.kind == ElementKind::Surface {
        // Where the phase integrates in closed form over the element (2D), it does:
        // a lobe narrower than the element (g → ±1) is then exact.
        if let Some(pw) = S::phase_weighted_form(lf.g, e.v, lf.x, lf.outgoing()) {
            let v = e.v.as_ref();
            let t = match e.far_plane {
                Some(plane) => slide::vertex_rule(lf, e, plane, soft, false),
                None if v.len() == 2 && lf.sigma_t.max_element() > 0.0 => slide::transmittance_mean(lf, v[0], v[1]),
                None => transmittance_taylor_rgb::<S>(lf.sigma_t, lf.x, e.anchor, soft),
            };
            return TaylorRgb::tint(pw, e.radiance).mul_channels(times_sigma_s(t));
        }
        if let Some(plane) = e.far_plane {
            // An occlusion boundary: f·T by the vertex rule with the near vertices
            // sliding on the far surface (see `slide`).
            let ft = slide::vertex_rule(lf, e, plane, soft, true);
            return TaylorRgb::tint(S::form_factor_clamped(e.v, lf.x, 0.0), e.radiance).mul_channels(times_sigma_s(ft));
        }
    }
    let phase = phase_taylor_out::<S>(lf.g, lf.x, e.anchor, lf.outgoing(), soft);
    element_incident(lf, e, medium_clamp).mul_channels(times_sigma_s([phase; 3]))
}

/// Elements summed per parallel task: the partial sums are added in a fixed order,
/// so the result is the same bit for bit whatever the thread count.
const SUM_CHUNK: usize = 2048;

/// Ours: value, gradient and Hessian of L_s from the proxy elements.
pub fn aware<S: Dim>(lf: &LightField<S>, elements: &[Element<S>], settings: &AwareSettings) -> PartDerivs<S> {
    let partial: Vec<(TaylorRgb<S>, TaylorRgb<S>)> = elements
        .par_chunks(SUM_CHUNK)
        .map(|chunk| {
            let (mut s, mut m) = (TaylorRgb::<S>::default(), TaylorRgb::<S>::default());
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
/// the ray fixed; the hit point slides on the hit surface's tangent, so only the
/// transmittance (through the distance s to the surface) changes: ∇s = −n/(n·ω).
/// Medium samples sit at fixed fractions u of s, with thickness Δu·s. Escaped rays
/// have a fixed length. The measure and visibility are treated as constant. First
/// order only.
pub fn unaware<S: Dim>(lf: &LightField<S>) -> PartDerivs<S> {
    let measure = lf.ray_measure();
    let out = lf.outgoing();
    let (mut single, mut multiple) = ([Taylor2::<S>::zero(); 3], [Taylor2::<S>::zero(); 3]);
    let mut samples = Vec::new();
    for r in &lf.rays {
        samples.clear();
        samples.extend(r.samples.iter().enumerate().map(|(i, l)| (lf.sample_depth(r, i), *l)));
        let f = phase_taylor_fixed_direction::<S>(lf.g, lf.x, r.dir, out);
        UnawareRay::<S> {
            sigma_t: lf.sigma_t,
            weight: lf.sigma_s * (f.value * measure),
            weight_log_grad: if f.value > 0.0 { f.grad / f.value } else { S::zero() },
            grad_s: r.hit.map_or(S::zero(), |h| hit_distance_gradient::<S>(h.normal, r.dir)),
            length: r.length,
            end_radiance: r.hit.map_or(r.escaped, |h| h.radiance),
            samples: &samples,
            step: lf.step,
        }
        .accumulate(&mut single, &mut multiple);
    }
    let mut direct = direct_derivatives(lf);
    for ch in &mut direct.channels {
        ch.hess = S::zero_mat();
    }
    PartDerivs {
        direct,
        single: TaylorRgb { channels: single },
        multiple: TaylorRgb { channels: multiple },
    }
}

/// The plain Monte Carlo estimate of L_s from the light field, per part.
pub fn plain_estimate<S: Dim>(lf: &LightField<S>) -> Parts {
    let p = unaware(lf);
    Parts {
        direct: p.direct.value(),
        single: p.single.value(),
        multiple: p.multiple.value(),
    }
}

/// Finite-difference reference settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReferenceSettings {
    /// Samples per stencil point.
    pub spp: u32,
    /// Step h as a fraction of the scene size.
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

/// Central differences of the path-traced L_s at x, per part: ±h on each axis for
/// the gradient (and the diagonal of the Hessian), and with `hessian` the four
/// diagonal points of each pair of axes for the mixed terms; every point with the
/// same random streams. With ω_o turning towards a point, each stencil point
/// scatters towards it (the derivative of what a camera sees).
#[allow(clippy::too_many_arguments)] // the stencil's inputs are spelled out
pub fn reference<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    out: Outgoing<<W::S as Space>::Vec>,
    h: f64,
    spp: u32,
    settings: &Settings,
    seed: u64,
    hessian: bool,
) -> Derivatives<W::S> {
    type S<W> = <W as World>::S;
    let start = std::time::Instant::now();
    let d = S::<W>::DIM;
    let e = |i: usize| S::<W>::axis(i);
    let mut offsets = vec![S::<W>::zero()];
    for i in 0..d {
        offsets.extend([e(i), -e(i)]);
    }
    if hessian {
        for i in 0..d {
            for j in i + 1..d {
                offsets.extend([e(i) + e(j), e(i) - e(j), -e(i) + e(j), -e(i) - e(j)]);
            }
        }
    }
    let est: Vec<Estimate> = offsets
        .par_iter()
        .map(|&o| {
            let p = x + o * h;
            let omega_o = match out {
                Outgoing::Direction(w) => w,
                Outgoing::TowardsPoint(eye) => {
                    let v = eye - p;
                    let l = S::<W>::length(v);
                    if l > 0.0 { v / l } else { S::<W>::axis(0) }
                }
            };
            estimate(world, p, &Query::InScattered { omega_o }, settings, spp, seed, 0)
        })
        .collect();
    let part = |get: &dyn Fn(&Estimate) -> Rgb| -> TaylorRgb<S<W>> {
        let v: Vec<Rgb> = est.iter().map(get).collect();
        let channel = |c: usize| {
            let f = |k: usize| v[k][c];
            let (mut grad, mut hess) = (S::<W>::zero(), S::<W>::zero_mat());
            let mut k = 1 + 2 * d;
            for i in 0..d {
                let (p, m) = (f(1 + 2 * i), f(2 + 2 * i));
                grad += e(i) * ((p - m) / (2.0 * h));
                hess += S::<W>::outer(e(i), e(i)) * ((p - 2.0 * f(0) + m) / (h * h));
                for j in (i + 1..d).filter(|_| hessian) {
                    let hij = (f(k) - f(k + 1) - f(k + 2) + f(k + 3)) / (4.0 * h * h);
                    hess += (S::<W>::outer(e(i), e(j)) + S::<W>::outer(e(j), e(i))) * hij;
                    k += 4;
                }
            }
            if !hessian {
                hess = S::<W>::zero_mat();
            }
            Taylor2::new(f(0), grad, hess)
        };
        TaylorRgb {
            channels: [channel(0), channel(1), channel(2)],
        }
    };
    Derivatives {
        method: Method::Reference,
        at: x,
        parts: PartDerivs {
            direct: part(&|e| e.mean.direct),
            single: part(&|e| e.mean.single),
            multiple: part(&|e| e.mean.multiple),
        },
        has_hessian: hessian,
        rays: est.iter().map(|e| e.rays).sum(),
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// [`reference`] with the step and samples of `rs` (h relative to the scene size),
/// Hessian included.
pub fn reference_at<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    out: Outgoing<<W::S as Space>::Vec>,
    rs: &ReferenceSettings,
    settings: &Settings,
    seed: u64,
) -> Derivatives<W::S> {
    reference(
        world,
        x,
        out,
        rs.relative_step * world.scale(),
        rs.spp,
        settings,
        seed,
        true,
    )
}
