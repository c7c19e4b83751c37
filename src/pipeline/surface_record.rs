//! A surface point's irradiance record, in any dimension: the surface counterpart
//! of a medium record, on the same core (occlusion-aware second-order irradiance
//! caching, Schwarzhaupt, Jensen and Jarosz 2012, of which the paper's medium
//! records are the volumetric extension).
//!
//! The light field over the half circle (hemisphere) a point of a diffuse surface
//! receives from ([`capture_surface`]) → its proxy → the method's value, gradient
//! and Hessian of the irradiance E = ∫ L(ω) max(0, n·ω) dω, with the cosine in place
//! of the phase and σ_s = 1 (`LightField::angular_*`). The value is the light
//! field's plain estimate, as a medium record's. The derivatives are those of E as
//! x moves with the normal held: on the surface, only their tangential part means
//! anything, and the record keeps that ((I − nnᵀ)∇E and (I − nnᵀ)H(I − nnᵀ)).
//!
//! By default a record holds the indirect irradiance only (light reflected by
//! surfaces or scattered by the medium before it arrives): the light arriving
//! straight from emitters and delta lights has sharp shadows, and is sampled per
//! pixel beside the cache ([`SurfaceReceiver::emitted`] includes it, for tests
//! against closed forms).

use super::derivatives::{aware_with_floor, unaware, with_plain_values};
use super::dim::Dim;
use super::probe::{LightField, SurfaceReceiver, capture_surface};
use super::proxy::build;
use super::record::CacheSettings;
use super::world::World;
use crate::core::metric::CacheMethod;
use crate::core::rng::mix64;
use crate::core::space::Space;
use crate::core::taylor_rgb::{PartDerivs, TaylorRgb};
use crate::progress::{Cancelled, Progress};
use std::time::Instant;

/// Salt of surface records' streams.
const SURFACE_STREAM: u64 = 0x5eed_5a7f_ace0_0001;

/// What one surface light field gives a record.
#[derive(Clone, Debug)]
pub struct SurfaceRecordData<S: Dim> {
    /// The receiving side's unit normal.
    pub normal: S::Vec,
    /// Irradiance (the plain estimate) with its tangential derivatives, per part:
    /// direct (delta lights, only with `emitted`), single (light from surfaces and
    /// the sky), multiple (light from the medium).
    pub parts: PartDerivs<S>,
    /// The luminance Hessian the metric uses (ours: with the radiance floor;
    /// jarosz08: zero): its tangential part, the normal axis closed
    /// ([`close_normal`]).
    pub metric_hessian: S::Mat,
    /// The luminance of the same floored irradiance (zero for jarosz08): what the
    /// metric measures a record that sees no light at all with
    /// ([`SurfaceRecordData::metric_luminance`]).
    pub floored_value: f64,
    pub rays: u64,
    /// Wall time of the capture and derivatives.
    pub seconds: f64,
}

impl<S: Dim> SurfaceRecordData<S> {
    /// The irradiance of every part, with its derivatives.
    pub fn irradiance(&self) -> TaylorRgb<S> {
        self.parts.total()
    }

    /// The luminance the metric measures this record with, `l` being its
    /// irradiance's: `l`, or its floored irradiance's where it sees no light at
    /// all, as a medium record's (`super::record::RecordData::metric_luminance`):
    /// with L = 0 each dark surface point took a record of its own (the floor
    /// around a sealed lamp: 460 records over 465 query points at 16×12).
    pub fn metric_luminance(&self, l: f64) -> f64 {
        if l == 0.0 && self.parts.sees_no_light() {
            self.floored_value
        } else {
            l
        }
    }
}

/// The irradiance record of the surface point `x` (stream `id`). The probe, the
/// method, the proxy's rule, the metric's radiance floor and the seed are the
/// cache's (`cs`); moments over ω_o do not apply (E has no ω_o).
pub fn compute_surface_record<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    receiver: SurfaceReceiver<<W::S as Space>::Vec>,
    cs: &CacheSettings,
    id: u64,
    progress: &Progress,
) -> Result<SurfaceRecordData<W::S>, Cancelled> {
    let start = Instant::now();
    let probe = super::probe::ProbeSettings {
        slopes: cs.probe.slopes && cs.method == CacheMethod::Ours,
        ..cs.probe
    };
    // A stream of its own: a surface record at a medium record's id draws others.
    let seed = mix64(cs.seed ^ mix64(id ^ SURFACE_STREAM));
    let lf = capture_surface(world, x, receiver, &probe, seed, 0, progress)?;
    let (parts, metric_hessian, floored_value) = derive(&lf, cs);
    let n = receiver.normal;
    Ok(SurfaceRecordData {
        normal: n,
        parts: tangential(with_plain_values(parts, &lf), n),
        metric_hessian: close_normal::<W::S>(project_mat::<W::S>(metric_hessian, n), n),
        floored_value,
        rays: lf.cost_rays,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The method's derivatives of E, the metric's luminance Hessian and the floored
/// irradiance's luminance.
fn derive<S: Dim>(lf: &LightField<S>, cs: &CacheSettings) -> (PartDerivs<S>, S::Mat, f64) {
    match cs.method {
        CacheMethod::Ours => {
            let (parts, floored) = aware_with_floor(lf, &build(lf, cs.aware.rule), &cs.aware, cs.hessian_floor);
            let floored = floored.unwrap_or(parts).total().luminance();
            (parts, floored.hess, floored.value)
        }
        CacheMethod::Jarosz08 => (unaware(lf), S::zero_mat(), 0.0),
    }
}

/// The derivatives' tangential parts on the plane with unit normal `n`.
pub fn tangential<S: Space>(mut parts: PartDerivs<S>, n: S::Vec) -> PartDerivs<S> {
    for part in [&mut parts.direct, &mut parts.single, &mut parts.multiple] {
        for ch in &mut part.channels {
            ch.grad = ch.grad - n * S::dot(n, ch.grad);
            ch.hess = project_mat::<S>(ch.hess, n);
        }
    }
    parts
}

/// A tangential Hessian `h` with its normal axis (eigenvalue 0) given the largest
/// tangential curvature. The metric's radii follow |λ|^−1/(d+2) and are held
/// within `max_anisotropy` of the longest: left at 0, the normal axis took the
/// longest radius allowed (r_max) and raised the tangential ones to r_max / 4
/// whatever ε, so that surface records spread over ≈ 0.06 of the scene's size
/// across steps and edges (the staircase's surface error did not fall below
/// ε ≈ 0.05). Closed, the extent is the tangential ellipse's, as thick along
/// the normal as its shortest axis (points off the plane — a parallel surface
/// beyond — are served only that close).
pub fn close_normal<S: Space>(h: S::Mat, n: S::Vec) -> S::Mat {
    let (lambda, _) = S::sym_eigen(h);
    let largest = (0..S::DIM)
        .map(|k| S::dot(lambda, S::axis(k)).abs())
        .fold(0.0, f64::max);
    h + S::outer(n, n) * largest
}

/// (I − nnᵀ) M (I − nnᵀ).
fn project_mat<S: Space>(m: S::Mat, n: S::Vec) -> S::Mat {
    let p = S::identity() - S::outer(n, n);
    p * m * p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::metric::{MetricParams, second_order_extent};
    use crate::core::space::D3;
    use glam::{DMat3, DVec3};

    /// A surface record's extent follows ε in the tangent plane (radii ∝ ε^1/5
    /// in 3D) instead of being held at r_max / 4 by the normal axis, and is as
    /// thick along the normal as its shortest tangential axis.
    #[test]
    fn the_tangential_extent_follows_eps() {
        let n = DVec3::new(0.0, 0.6, 0.8);
        let (t1, t2) = (DVec3::X, n.cross(DVec3::X));
        // Curvatures 4 and −1 along the tangents, projected as a record's are.
        let h = project_mat::<D3>(
            DMat3::from_cols(t1, t2, n)
                * DMat3::from_diagonal(DVec3::new(4.0, -1.0, 0.0))
                * DMat3::from_cols(t1, t2, n).transpose(),
            n,
        );
        let closed = close_normal::<D3>(h, n);
        assert!(((closed * n).dot(n) - 4.0).abs() < 1e-12);
        let radii = |eps: f64, m: DMat3| {
            let e = second_order_extent::<D3>(1.0, m, DVec3::ZERO, &MetricParams::scene_relative(10.0, eps));
            // Radius along a direction: the axis that points there.
            let along = |d: DVec3| {
                (0..3)
                    .map(|k| (e.axes.col(k).dot(d).abs(), e.radii[k]))
                    .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
                    .1
            };
            (along(t1), along(t2), along(n))
        };
        let (a, b, c) = radii(1e-4, closed);
        let (a2, b2, _) = radii(1e-4 / 32.0, closed);
        assert!(
            (a / a2 - 2.0).abs() < 1e-9 && (b / b2 - 2.0).abs() < 1e-9,
            "{a} {a2} {b} {b2}"
        );
        assert!(a < 0.25 * 10.0 / 4.0 && (c - a).abs() < 1e-12, "{a} {b} {c}");
        // Open, the normal axis held the tangential radii at r_max / 4.
        let (a, _, c) = radii(1e-4, h);
        assert!(
            (a - 0.25 * 10.0 / 4.0).abs() < 1e-12 && (c - 2.5).abs() < 1e-12,
            "{a} {c}"
        );
    }
}
