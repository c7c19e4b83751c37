//! The occlusion-unaware first-order derivatives of Jarosz et al. 2008 along one
//! probe ray (theory.md §4), shared by the 2D and 3D light fields.
//!
//! The ray's direction and its samples' relative positions along it are fixed; a
//! ray ending on a surface has its end point slide on the surface's tangent plane,
//! so only the distance s to it changes, ∇s = −n/(n·ω), and with it the
//! transmittance. Medium samples sit at fixed fractions u of s with thickness
//! ∝ s (each Δt_i/s fixed).
//! The measure and visibility are treated as constant.

use super::color::Rgb;
use super::space::Space;
use super::taylor::Taylor2;

/// ∇s = −n/(n·ω) of the distance to a surface with normal `normal` hit along `dir`
/// (|n·ω| clamped at 1e-3 so grazing hits stay finite).
pub fn hit_distance_gradient<S: Space>(normal: S::Vec, dir: S::Vec) -> S::Vec {
    let nd = S::dot(normal, dir);
    -normal / nd.abs().max(1e-3).copysign(nd)
}

/// One probe ray's contribution, as per-channel value and gradient (zero Hessian).
pub struct UnawareRay<'a, S: Space> {
    pub sigma_t: Rgb,
    /// σ_s f(ω) dω of the ray.
    pub weight: Rgb,
    /// ∇ ln f: non-zero only when ω_o turns with x (towards a camera).
    pub weight_log_grad: S::Vec,
    /// ∇s (zero for rays whose length does not depend on x).
    pub grad_s: S::Vec,
    /// Distance s to where the ray ends.
    pub length: f64,
    /// Radiance arriving from the ray's end (surface or sky).
    pub end_radiance: Rgb,
    /// The medium samples: depth, L_s and thickness Δt.
    pub samples: &'a [(f64, Rgb, f64)],
}

impl<S: Space> UnawareRay<'_, S> {
    /// Add the surface term to `single` and the medium terms to `multiple`.
    pub fn accumulate(&self, single: &mut [Taylor2<S>; 3], multiple: &mut [Taylor2<S>; 3]) {
        let zero = S::zero_mat();
        if self.end_radiance != Rgb::ZERO {
            for (c, acc) in single.iter_mut().enumerate() {
                let v = self.weight[c] * (-self.sigma_t[c] * self.length).exp() * self.end_radiance[c];
                let grad = self.grad_s * (-self.sigma_t[c] * v) + self.weight_log_grad * v;
                *acc += Taylor2::new(v, grad, zero);
            }
        }
        let slides = S::dot(self.grad_s, self.grad_s) > 0.0;
        for &(t_i, l, dt) in self.samples {
            if l == Rgb::ZERO {
                continue;
            }
            for (c, acc) in multiple.iter_mut().enumerate() {
                let sig = self.sigma_t[c];
                let tr = (-sig * t_i).exp();
                let v = self.weight[c] * tr * l[c] * dt;
                // d/ds [T(u s) L Δu s] = T L Δu (1 − σ u s), with u s = t_i.
                let ds = if slides {
                    self.weight[c] * tr * l[c] * (dt / self.length) * (1.0 - sig * t_i)
                } else {
                    0.0
                };
                *acc += Taylor2::new(v, self.grad_s * ds + self.weight_log_grad * v, zero);
            }
        }
    }
}
