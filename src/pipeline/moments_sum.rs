//! The moments of ours' aware sums in one pass over the medium samples (see
//! `super::moments`): a sample's kernel — transmittance, smoothed form factors at
//! the two scales, turning — does not depend on the angular factor, which enters
//! it linearly, so it is made once and multiplied by every basis function (all of
//! them from one shared recurrence, `core::harmonics::basis_all`). The same
//! arithmetic as `derivatives::medium_point` with the angular factor B_k(−ω) in
//! place of the phase; likewise a surface element's T L F. Occlusion boundaries'
//! surface elements (the slide rule), bridging pieces and delta lights, few, are
//! summed per basis function by the phase path's own functions.

use super::derivatives::{
    AwareSettings, HESSIAN_SCALE_REACH, RAY_CHUNK, SUM_CHUNK, direct_derivatives, element_contribution,
    element_incident, fill_ray_samples, turning,
};
use super::dim::Dim;
use super::probe::{Angular, LightField};
use super::proxy::{Element, ElementKind, Proxy};
use crate::core::color::Rgb;
use crate::core::distance::{Offset, direction_along_from, distance};
use crate::core::element::{medium_form_factor_smoothed, medium_softening, near_distance};
use crate::core::harmonics::{basis_all, basis_count};
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::{PartDerivs, TaylorRgb};
use crate::core::transmittance::transmittance_taylor_rgb;
use crate::core::unaware::{UnawareRay, hit_distance_gradient};
use rayon::prelude::*;

/// The components of −ω, the travel direction of light arriving at x from `c`
/// (ω softened at `soft`), as fields of x: what the basis functions are taken of.
pub(super) fn arriving_travel<S: Dim>(x: S::Vec, c: S::Vec, soft: f64) -> [Taylor2<S>; 3] {
    let o = Offset::<S>::new(x, c, soft);
    let mut d = [Taylor2::<S>::zero(); 3];
    for (i, di) in d.iter_mut().enumerate().take(S::DIM) {
        *di = -direction_along_from(&o, S::axis(i));
    }
    d
}

/// Every basis function B_k(−ω) of light from `c` received at `x`, ω softened at
/// `soft` (as `LightField::angular_towards`).
fn bases<S: Dim>(bands: usize, x: S::Vec, c: S::Vec, soft: f64) -> Vec<Taylor2<S>> {
    basis_all(bands, &arriving_travel::<S>(x, c, soft)[..S::DIM])
}

/// Ours' aware sums for every basis function of bands 0..=`bands` (values are the
/// sums', not the plain estimate's). `lf.angular` is used and left as given.
pub fn aware_moments<S: Dim>(
    lf: &mut LightField<S>,
    proxy: &Proxy<S>,
    settings: &AwareSettings,
    bands: usize,
) -> Vec<PartDerivs<S>> {
    let kept = lf.angular;
    let clamp = settings.medium_clamp;
    let chunks = proxy.chunks(SUM_CHUNK);
    // Surfaces that are no occlusion boundary: T L F at the anchor times the
    // angular factor there (`element_contribution`'s plain case), F and T once.
    let plain_surface = |e: &Element<S>| e.kind == ElementKind::Surface && e.far_plane.is_none();
    let mut out: Vec<PartDerivs<S>> = (0..basis_count::<S>(bands))
        .map(|k| {
            lf.angular = Angular::Moment(k);
            let lf = &*lf;
            let sums: Vec<(TaylorRgb<S>, TaylorRgb<S>)> = chunks
                .par_iter()
                .map(|chunk| {
                    let (mut single, mut multiple) = (TaylorRgb::default(), TaylorRgb::default());
                    let per_moment = |e: &&Element<S>| !plain_surface(e) && e.radiance != Rgb::ZERO;
                    for e in chunk.iter().filter(per_moment) {
                        let c = element_contribution(lf, e, settings);
                        match e.kind {
                            ElementKind::Surface => single += c,
                            ElementKind::Medium => multiple += c,
                        }
                    }
                    (single, multiple)
                })
                .collect();
            let mut p = PartDerivs {
                direct: direct_derivatives(lf),
                ..PartDerivs::default()
            };
            for (s, m) in sums {
                p.single += s;
                p.multiple += m;
            }
            p
        })
        .collect();
    lf.angular = kept;
    let lf = &*lf;
    let k_count = out.len();
    let sigma_s = [lf.sigma_s.x, lf.sigma_s.y, lf.sigma_s.z].map(Taylor2::constant);
    let surface_sums: Vec<Vec<TaylorRgb<S>>> = chunks
        .par_iter()
        .map(|chunk| {
            let mut sums = vec![TaylorRgb::<S>::default(); k_count];
            for e in chunk.iter().filter(|e| plain_surface(e) && e.radiance != Rgb::ZERO) {
                let incident = element_incident(lf, e).mul_channels(sigma_s);
                for (sum, b) in sums
                    .iter_mut()
                    .zip(bases::<S>(bands, lf.x, e.anchor, near_distance(e.size())))
                {
                    *sum += incident.mul_channels([b; 3]);
                }
            }
            sums
        })
        .collect();
    for chunk in surface_sums {
        for (p, c) in out.iter_mut().zip(chunk) {
            p.single += c;
        }
    }
    let shares = &proxy.shares;
    let sample_sums: Vec<Vec<TaylorRgb<S>>> = lf
        .rays
        .par_chunks(RAY_CHUNK)
        .enumerate()
        .map(|(c, rays)| {
            let mut sums = vec![TaylorRgb::<S>::default(); k_count];
            for (j, r) in (c * RAY_CHUNK..).zip(rays) {
                for i in 0..r.samples.len() {
                    let Some((measure, size)) = shares.of(j, i) else {
                        continue;
                    };
                    let m = lf.medium_sample(j, i).expect("a shared sample is present");
                    if m.light == Rgb::ZERO {
                        continue;
                    }
                    let soft = near_distance(size);
                    sample_moments(lf, m.at, measure, (m.light, m.slope), soft, clamp, bands, &mut sums);
                }
            }
            sums
        })
        .collect();
    for chunk in sample_sums {
        for (p, c) in out.iter_mut().zip(chunk) {
            p.multiple += c.mul_channels(sigma_s);
        }
    }
    out
}

/// One medium point's f·T·L·F (no σ_s) for every basis function, added to `sums`:
/// `derivatives::medium_point` with B_k(−ω) for the phase.
#[allow(clippy::too_many_arguments)] // medium_point's inputs and the band
fn sample_moments<S: Dim>(
    lf: &LightField<S>,
    p: S::Vec,
    dir_measure: f64,
    (radiance, slope): (Rgb, [S::Vec; 3]),
    soft: f64,
    medium_clamp: f64,
    bands: usize,
    sums: &mut [TaylorRgb<S>],
) {
    let x = lf.x;
    let r = S::length(p - x);
    let t = transmittance_taylor_rgb::<S>(lf.sigma_t, x, p, soft);
    let exact = bases::<S>(bands, x, p, soft);
    let local = lf.march.thickness_at(r);
    let (fine, even) = super::derivatives::smoothing_scales(&lf.march);
    // A kernel's form factor (over Δt) and its near-field angular factors per k.
    let kernel = |scale: f64| -> (Taylor2<S>, Vec<Taylor2<S>>) {
        let smoothing = medium_clamp * scale;
        let n = S::DIM as i32 - 1;
        let measure = dir_measure * r.powi(n) * local;
        let eps = smoothing.max(medium_softening::<S>(measure));
        let form = Taylor2 {
            value: measure / (r * r + eps * eps).powf(0.5 * n as f64),
            ..medium_form_factor_smoothed::<S>(p, measure, x, smoothing)
        } * (1.0 / local);
        // derivatives::near_field_phase, per basis function (B_0 is constant).
        let a = 2.0 * eps;
        let angular = if r >= 2.0 * a {
            exact.clone()
        } else {
            let smooth = bases::<S>(bands, x, p, a.max(soft));
            let blend = (r > a).then(|| {
                let s = (r - a) / a;
                let w = s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
                let dw = 30.0 * s * s * (1.0 - s) * (1.0 - s) / a;
                let d2w = 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s) / (a * a);
                distance::<S>(x, p, 0.0).compose(w, dw, d2w)
            });
            exact
                .iter()
                .zip(smooth)
                .enumerate()
                .map(|(k, (&e, m))| match blend {
                    _ if k == 0 => e,
                    None => m,
                    Some(w) => m + w * (e - m),
                })
                .collect()
        };
        (form, angular)
    };
    let (fine_form, fine_angular) = kernel(fine);
    let coarse = (even > fine && r < HESSIAN_SCALE_REACH * medium_clamp * even).then(|| kernel(even));
    for k in 0..sums.len() {
        let fine_kernel = fine_form * fine_angular[k];
        let mut c = TaylorRgb::tint(fine_kernel, radiance).mul_channels(t);
        for ((ch, tc), g) in c.channels.iter_mut().zip(&t).zip(slope) {
            ch.grad += turning::<S>(x, p, g, fine_kernel.value * tc.value);
        }
        if let Some((form, angular)) = &coarse {
            let h = TaylorRgb::tint(*form * angular[k], radiance).mul_channels(t);
            for (ch, hc) in c.channels.iter_mut().zip(h.channels) {
                ch.hess = hc.hess;
            }
        }
        let value = dir_measure * exact[k].value;
        for (ch, (tc, rad)) in c
            .channels
            .iter_mut()
            .zip(t.iter().zip([radiance.x, radiance.y, radiance.z]))
        {
            ch.value = value * tc.value * rad;
        }
        sums[k] += c;
    }
}

/// Jarosz et al. 2008's sums (`derivatives::unaware`) for every basis function of
/// bands 0..=`bands`: a ray's direction is fixed, so its angular factor B_k(−ω) is
/// a constant and the ray's sums are made once with a unit factor, then scaled.
/// The values are the plain estimates of the moments. `lf.angular` is used and left
/// as given.
pub fn unaware_moments<S: Dim>(lf: &mut LightField<S>, bands: usize) -> Vec<PartDerivs<S>> {
    let k_count = basis_count::<S>(bands);
    let measure = lf.ray_measure();
    let (mut single, mut multiple) = (
        vec![[Taylor2::<S>::zero(); 3]; k_count],
        vec![[Taylor2::<S>::zero(); 3]; k_count],
    );
    let mut samples = Vec::new();
    for r in &lf.rays {
        fill_ray_samples(lf, r, &mut samples);
        let (mut s1, mut m1) = ([Taylor2::<S>::zero(); 3], [Taylor2::<S>::zero(); 3]);
        UnawareRay::<S> {
            sigma_t: lf.sigma_t,
            weight: lf.sigma_s * measure,
            weight_log_grad: S::zero(),
            grad_s: r.hit.map_or(S::zero(), |h| hit_distance_gradient::<S>(h.normal, r.dir)),
            length: r.length,
            end_radiance: r.hit.map_or(r.escaped, |h| h.radiance),
            samples: &samples,
        }
        .accumulate(&mut s1, &mut m1);
        let len = S::length(r.dir);
        let mut d = [Taylor2::<S>::zero(); 3];
        for (i, di) in d.iter_mut().enumerate().take(S::DIM) {
            *di = Taylor2::constant(-r.dir[i] / len);
        }
        for (k, b) in basis_all(bands, &d[..S::DIM]).into_iter().enumerate() {
            for c in 0..3 {
                single[k][c] += s1[c] * b.value;
                multiple[k][c] += m1[c] * b.value;
            }
        }
    }
    let kept = lf.angular;
    let out = (0..k_count)
        .map(|k| {
            lf.angular = Angular::Moment(k);
            let mut direct = direct_derivatives(lf);
            for ch in &mut direct.channels {
                ch.hess = S::zero_mat();
            }
            PartDerivs {
                direct,
                single: TaylorRgb { channels: single[k] },
                multiple: TaylorRgb { channels: multiple[k] },
            }
        })
        .collect();
    lf.angular = kept;
    out
}
