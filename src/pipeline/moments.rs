//! Records as harmonic moments over ω_o (issue 15; `core::harmonics`).
//!
//! In an anisotropic medium L_s(x, ω_o) depends on where it leaves towards, and a
//! 3D camera's ω_o at a medium point changes whenever the camera moves: a record
//! that stores L_s towards one camera is stale for the next. The light field at x
//! does not depend on ω_o (its samples' light is seen from x, whatever x then
//! scatters it towards); only the phase factor at x does, and the phase expands as
//! f(−ω·ω_o) = Σ_k g^{l(k)} B_k(−ω) B_k(ω_o). So a record can store, per basis
//! function k, the method's value, gradient and Hessian of M_k = ∫ B_k(−ω) L(ω) dω
//! — the same sums with B_k(−ω) in place of the phase factor — and serve any ω_o as
//! Σ_k g^{l(k)} B_k(ω_o) M_k, exact up to the phase's truncation (order g^{L+1}).
//!
//! Every phase factor of the derivative sums goes through the light field's
//! `angular_*` functions below, which switch between the phase and a basis
//! function; the moments are those sums per basis function: the medium samples —
//! most of the sums — in one pass for all of them (`super::moments_sum`), the few
//! surfaces, bridging pieces and delta lights once per basis function.
//!
//! Measured (tests/dims_moments.rs): Jarosz 2008's sums are linear in the phase
//! factor and the moments give its record to 5e-4. Ours softens the phase near x
//! (`derivatives::near_field_phase`: a shortened direction), where the basis
//! polynomials and the phase's closed form part: gradients differ by up to 14% (2D)
//! and 3% (3D) of their size, Hessians by 5% / 2% — the two are different
//! regularisations of the same near field, neither the exact one.

use super::derivatives::{AwareSettings, PartDerivs, with_values};
use super::dim::Dim;
use super::moments_sum::{arriving_travel, aware_moments, unaware_moments};
use super::probe::{Angular, LightField};
use super::proxy::Proxy;
use crate::core::color::Rgb;
use crate::core::harmonics::{basis, phase_weights};
use crate::core::phase::{hg_of_mu, phase_taylor_fixed_direction, phase_taylor_out};
use crate::core::space::Space;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;

impl<S: Dim> LightField<S> {
    /// The angular factor of light from the point `c` received at x (arriving from
    /// ω = (c − x)/|c − x|, softened at `soft`) with its derivatives in x: the
    /// phase f(−ω·ω_o), or the basis function B_k(−ω) of moment k.
    pub fn angular_towards(&self, x: S::Vec, c: S::Vec, soft: f64) -> Taylor2<S> {
        match self.angular {
            Angular::Phase => phase_taylor_out::<S>(self.g, x, c, self.outgoing(), soft),
            Angular::Moment(k) => basis(k, &arriving_travel::<S>(x, c, soft)[..S::DIM]),
            Angular::Cosine(n) => {
                // n·ω = −n·travel; clamped at the horizon (a kink only elements
                // straddling it see, where the cosine is small).
                let travel = arriving_travel::<S>(x, c, soft);
                let mut mu = Taylor2::<S>::zero();
                for (i, t) in travel.iter().enumerate().take(S::DIM) {
                    mu += *t * (-n[i]);
                }
                if mu.value > 0.0 { mu } else { Taylor2::zero() }
            }
        }
    }

    /// [`Self::angular_towards`] for light arriving along the fixed direction `w`
    /// (from w, travelling along −w): a basis function is then constant.
    pub fn angular_fixed(&self, x: S::Vec, w: S::Vec) -> Taylor2<S> {
        match self.angular {
            Angular::Phase => phase_taylor_fixed_direction::<S>(self.g, x, w, self.outgoing()),
            Angular::Moment(k) => Taylor2::constant(basis_at::<S>(k, -unit::<S>(w))),
            Angular::Cosine(n) => Taylor2::constant(S::dot(n, unit::<S>(w)).max(0.0)),
        }
    }

    /// The angular factor's value for light from `y` received at `x`.
    pub fn angular_at(&self, x: S::Vec, y: S::Vec) -> f64 {
        self.angular_from(x)(unit::<S>(y - x))
    }

    /// [`Self::angular_at`] for many directions u (unit, from x towards where the
    /// light comes from) at one x: the outgoing direction at x (towards a camera, a
    /// square root) is found once, and a caller that knows u spares its own.
    pub fn angular_from(&self, x: S::Vec) -> impl Fn(S::Vec) -> f64 + '_ {
        let w = match (self.angular, self.outgoing()) {
            (Angular::Phase, super::probe::Outgoing::Direction(w)) => unit::<S>(w),
            (Angular::Phase, super::probe::Outgoing::TowardsPoint(eye)) => unit::<S>(eye - x),
            _ => S::zero(),
        };
        move |u| match self.angular {
            Angular::Phase => hg_of_mu::<S>(self.g, -S::dot(u, w)).0,
            Angular::Moment(k) => basis_at::<S>(k, -u),
            Angular::Cosine(n) => S::dot(n, u).max(0.0),
        }
    }

    /// The angular factor does not depend on the direction (isotropic phase, or the
    /// constant basis function).
    pub fn angular_is_constant(&self) -> bool {
        match self.angular {
            Angular::Phase => self.g == 0.0,
            Angular::Moment(k) => k == 0,
            Angular::Cosine(_) => false,
        }
    }
}

fn unit<S: Space>(v: S::Vec) -> S::Vec {
    let l = S::length(v);
    if l > 0.0 { v / l } else { S::axis(0) }
}

fn basis_at<S: Space>(k: usize, d: S::Vec) -> f64 {
    let mut c = [Taylor2::<S>::zero(); 3];
    for (i, ci) in c.iter_mut().enumerate().take(S::DIM) {
        *ci = Taylor2::constant(d[i]);
    }
    basis(k, &c[..S::DIM]).value
}

/// The method's value and derivatives of every moment of bands 0..=`bands`, per
/// part: ours' aware derivatives (from its `proxy`) or Jarosz 2008's (no proxy), each
/// with the plain estimate as its value, as a record's payload is made. The light
/// field is left as it was given.
pub fn moment_derivs<S: Dim>(
    lf: &mut LightField<S>,
    proxy: Option<&Proxy<S>>,
    settings: &AwareSettings,
    bands: usize,
) -> Vec<PartDerivs<S>> {
    // Jarosz 2008's sums, whose values are the plain estimates (a record's values).
    let plain = unaware_moments(lf, bands);
    match proxy {
        None => plain,
        Some(proxy) => aware_moments(lf, proxy, settings, bands)
            .into_iter()
            .zip(&plain)
            .map(|(parts, p)| with_values(parts, [p.direct.value(), p.single.value(), p.multiple.value()]))
            .collect(),
    }
}

/// The weights c_k of the moments for L_s leaving towards `w_o` in a medium of
/// phase parameter `g` (see the module's doc).
pub fn weights_towards<S: Dim>(g: f64, bands: usize, w_o: S::Vec) -> Vec<f64> {
    phase_weights::<S>(g, bands, unit::<S>(w_o))
}

/// Σ_k c_k M_k: the payload the moments give for one ω_o.
pub fn combine<S: Dim>(moments: &[TaylorRgb<S>], weights: &[f64]) -> TaylorRgb<S> {
    let mut sum = TaylorRgb::<S>::default();
    for (m, &c) in moments.iter().zip(weights) {
        for (s, ch) in sum.channels.iter_mut().zip(m.channels) {
            *s += ch * c;
        }
    }
    sum
}

/// Σ_k c_k M_k's value only.
pub fn combine_value<S: Dim>(moments: &[TaylorRgb<S>], weights: &[f64]) -> Rgb {
    let mut sum = Rgb::ZERO;
    for (m, &c) in moments.iter().zip(weights) {
        sum += m.value() * c;
    }
    sum
}

/// A record's moments over ω_o, with their sum for the ω_o it was made for.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordMoments<S: Dim> {
    /// M_k, all of bands 0..=L (empty: the record has none).
    pub moments: Vec<TaylorRgb<S>>,
    /// Σ c_k(ω_placed) M_k: the truncated series where the record's own payload
    /// is exact.
    pub as_placed: TaylorRgb<S>,
    /// The unit ω_o the record was made for, at its position.
    pub placed_omega: S::Vec,
}

/// Where the moments are read: their weights for the query's ω_o, that ω_o (unit)
/// and the medium's g.
#[derive(Clone, Copy, Debug)]
pub struct MomentQuery<'a, S: Dim> {
    pub weights: &'a [f64],
    pub omega_o: S::Vec,
    pub g: f64,
}

impl<S: Dim> RecordMoments<S> {
    pub fn is_empty(&self) -> bool {
        self.moments.is_empty()
    }

    /// The record's L_s towards the query's ω_o: the truncated series Σ c_k M_k plus
    /// the series' error where the record is exact (its payload `stored`, towards
    /// the ω_o it was made for), weighted by ρ = exp(−(θ/θ₀)²) of the angle θ
    /// between the two ω_o, θ₀ = 1 − |g| radians (the HG lobe's width): exact for
    /// the placing camera, the truncated series far from it.
    ///
    /// Why: the truncation's error lives in bands above L, at the lobe's angular
    /// scale, and decorrelates as ω_o turns. Measured on scenes3d/lamp_fog.json
    /// (g = 0.8, L = 4, 64×48, 1024 rays, medium RMSE at yaw 0° / 3° / 10° / 30°):
    /// the series alone 0.071 / 0.069 / 0.068 / 0.061; the full correction (ρ = 1)
    /// 0.052 / 0.057 / 0.076 / –; ρ = ½ 0.052 / 0.053 / 0.065 / 0.069; this ρ(θ)
    /// 0.050 / 0.052 / 0.062 / 0.061 (a fresh cache: 0.053 / 0.050 / 0.050 / 0.039).
    /// Far from the placing camera the truncation remains: more bands, at one
    /// derivative pass each.
    pub fn towards(&self, stored: &TaylorRgb<S>, q: &MomentQuery<S>) -> TaylorRgb<S> {
        let mut out = combine(&self.moments, q.weights);
        let cos = S::dot(self.placed_omega, q.omega_o).clamp(-1.0, 1.0);
        let theta0 = (1.0 - q.g.abs()).max(1e-3);
        let rho = (-(cos.acos() / theta0).powi(2)).exp();
        if rho > 1e-6 {
            for ((o, st), p) in out
                .channels
                .iter_mut()
                .zip(stored.channels)
                .zip(self.as_placed.channels)
            {
                *o += (st + p * -1.0) * rho;
            }
        }
        out
    }
}
