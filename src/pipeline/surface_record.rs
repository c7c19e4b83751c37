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
    /// jarosz08: zero), tangential.
    pub metric_hessian: S::Mat,
    pub rays: u64,
    /// Wall time of the capture and derivatives.
    pub seconds: f64,
}

impl<S: Dim> SurfaceRecordData<S> {
    /// The irradiance of every part, with its derivatives.
    pub fn irradiance(&self) -> TaylorRgb<S> {
        self.parts.total()
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
    let (parts, metric_hessian) = derive(&lf, cs);
    let n = receiver.normal;
    Ok(SurfaceRecordData {
        normal: n,
        parts: tangential(with_plain_values(parts, &lf), n),
        metric_hessian: project_mat::<W::S>(metric_hessian, n),
        rays: lf.cost_rays,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The method's derivatives of E and the metric's luminance Hessian.
fn derive<S: Dim>(lf: &LightField<S>, cs: &CacheSettings) -> (PartDerivs<S>, S::Mat) {
    match cs.method {
        CacheMethod::Ours => {
            let (parts, floored) = aware_with_floor(lf, &build(lf, cs.aware.rule), &cs.aware, cs.hessian_floor);
            (parts, floored.unwrap_or(parts).total().luminance().hess)
        }
        CacheMethod::Jarosz08 => (unaware(lf), S::zero_mat()),
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

/// (I − nnᵀ) M (I − nnᵀ).
fn project_mat<S: Space>(m: S::Mat, n: S::Vec) -> S::Mat {
    let p = S::identity() - S::outer(n, n);
    p * m * p
}
