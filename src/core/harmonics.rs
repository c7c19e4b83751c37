//! Harmonic moments of the Henyey–Greenstein phase function (issue 15): real
//! circular harmonics in 2D, real spherical harmonics in 3D, each orthonormal over
//! the circle (sphere).
//!
//! Both phase functions expand in their dimension's harmonics with coefficients
//! gᴸ per band l (the addition theorem; 3D: f(μ) = Σ (2l+1)/4π gˡ P_l(μ); 2D, the
//! wrapped Cauchy: f(θ) = (1 + 2Σ gᵏ cos kθ)/2π), so for unit a, b
//!
//!   f(a · b) = Σ_k g^{l(k)} B_k(a) B_k(b).
//!
//! In-scattered light towards ω_o, L_s(ω_o) = ∫ f(−ω·ω_o) L(ω) dω, is then
//! Σ_k g^{l(k)} B_k(ω_o) M_k with moments M_k = ∫ B_k(−ω) L(ω) dω that do not depend
//! on ω_o: a record that stores M_k (with their derivatives in x) serves every
//! camera. Truncated at band L, the phase's error is of order g^{L+1}.
//!
//! The basis functions are polynomials in the direction's components, so they are
//! evaluated here on [`Taylor2`] components (value, gradient and Hessian in x of a
//! direction field) with the product rule, and on plain vectors.

use super::space::Space;
use super::taylor::Taylor2;
use std::f64::consts::PI;

/// The most bands a record may carry: (L+1)² = 1089 moments in 3D.
pub const MAX_BANDS: usize = 32;

/// The number of basis functions of bands 0..=`bands`: 2L + 1 (circle), (L + 1)²
/// (sphere).
pub fn basis_count<S: Space>(bands: usize) -> usize {
    if S::DIM == 2 {
        2 * bands + 1
    } else {
        (bands + 1) * (bands + 1)
    }
}

/// The band (degree) l of basis function k.
pub fn band_of<S: Space>(k: usize) -> usize {
    if S::DIM == 2 {
        k.div_ceil(2)
    } else {
        // l² ≤ k < (l + 1)².
        let mut l = (k as f64).sqrt() as usize;
        while l * l > k {
            l -= 1;
        }
        while (l + 1) * (l + 1) <= k {
            l += 1;
        }
        l
    }
}

/// Basis function k at a direction given by its components (each a [`Taylor2`]
/// field of x, or a constant). Order: 2D 1, cos θ, sin θ, cos 2θ, sin 2θ, …;
/// 3D by band, m = −l … l (sin-like m < 0, cos-like m > 0).
pub fn basis<S: Space>(k: usize, d: &[Taylor2<S>]) -> Taylor2<S> {
    if S::DIM == 2 {
        if k == 0 {
            return Taylor2::constant(1.0 / (2.0 * PI).sqrt());
        }
        let (c, s) = power_of(d[0], d[1], k.div_ceil(2));
        let part = if k % 2 == 1 { c } else { s };
        return part * (1.0 / PI.sqrt());
    }
    let l = band_of::<S>(k);
    let m = k as i64 - (l * l + l) as i64;
    let am = m.unsigned_abs() as usize;
    let q = legendre_part(d[2], l, am);
    let norm = normalisation(l, am);
    if m == 0 {
        return q * norm;
    }
    let (c, s) = power_of(d[0], d[1], am);
    q * (if m > 0 { c } else { s }) * (norm * std::f64::consts::SQRT_2)
}

/// Every basis function of bands 0..=`bands` at a direction given by its
/// components, in [`basis`]'s order, sharing the recurrences (one sweep over m,
/// then over l): a few products per function instead of [`basis`]'s O(l).
pub fn basis_all<S: Space>(bands: usize, d: &[Taylor2<S>]) -> Vec<Taylor2<S>> {
    let mut out = vec![Taylor2::zero(); basis_count::<S>(bands)];
    let (mut c, mut s) = (Taylor2::constant(1.0), Taylor2::<S>::zero());
    if S::DIM == 2 {
        out[0] = Taylor2::constant(1.0 / (2.0 * PI).sqrt());
        for m in 1..=bands {
            (c, s) = (d[0] * c - d[1] * s, d[0] * s + d[1] * c);
            out[2 * m - 1] = c * (1.0 / PI.sqrt());
            out[2 * m] = s * (1.0 / PI.sqrt());
        }
        return out;
    }
    let z = d[2];
    let mut pmm = 1.0;
    for m in 0..=bands {
        if m > 0 {
            (c, s) = (d[0] * c - d[1] * s, d[0] * s + d[1] * c);
            pmm *= (2 * m - 1) as f64;
        }
        // P_l^m for l = m, m + 1, …: the recurrence of [`legendre_part`].
        let (mut prev, mut cur) = (Taylor2::<S>::zero(), Taylor2::constant(pmm));
        for l in m..=bands {
            if l == m + 1 {
                (prev, cur) = (cur, z * ((2 * m + 1) as f64 * pmm));
            } else if l > m + 1 {
                let next = (z * cur * (2 * l - 1) as f64 - prev * (l + m - 1) as f64) * (1.0 / (l - m) as f64);
                (prev, cur) = (cur, next);
            }
            let norm = normalisation(l, m);
            let centre = l * l + l;
            if m == 0 {
                out[centre] = cur * norm;
            } else {
                let q = cur * (norm * std::f64::consts::SQRT_2);
                out[centre + m] = q * c;
                out[centre - m] = q * s;
            }
        }
    }
    out
}

/// Every basis function of bands 0..=`bands` at the unit vector `d`.
pub fn basis_values<S: Space>(bands: usize, d: S::Vec) -> Vec<f64> {
    let comps: Vec<Taylor2<S>> = (0..S::DIM).map(|i| Taylor2::constant(d[i])).collect();
    (0..basis_count::<S>(bands)).map(|k| basis(k, &comps).value).collect()
}

/// The phase's weights of the moments for light leaving towards the unit `w_o`:
/// c_k = g^{l(k)} B_k(w_o), so that L_s(w_o) = Σ c_k M_k.
pub fn phase_weights<S: Space>(g: f64, bands: usize, w_o: S::Vec) -> Vec<f64> {
    basis_values::<S>(bands, w_o)
        .into_iter()
        .enumerate()
        .map(|(k, b)| g.powi(band_of::<S>(k) as i32) * b)
        .collect()
}

/// Re + i·Im of (a + i·b)^m, i.e. (cos mφ, sin mφ) scaled by sinᵐ (3D) or 1 (2D).
fn power_of<S: Space>(a: Taylor2<S>, b: Taylor2<S>, m: usize) -> (Taylor2<S>, Taylor2<S>) {
    let (mut c, mut s) = (Taylor2::constant(1.0), Taylor2::zero());
    for _ in 0..m {
        (c, s) = (a * c - b * s, a * s + b * c);
    }
    (c, s)
}

/// The associated Legendre function P_l^m(z) without its (1 − z²)^{m/2} factor
/// (which [`power_of`] carries), without the Condon–Shortley sign: the standard
/// three-term recurrence in l.
fn legendre_part<S: Space>(z: Taylor2<S>, l: usize, m: usize) -> Taylor2<S> {
    // P_m^m = (2m − 1)!!
    let pmm = (1..=m).fold(1.0, |acc, i| acc * (2 * i - 1) as f64);
    let mut prev = Taylor2::constant(pmm);
    if l == m {
        return prev;
    }
    let mut cur = z * ((2 * m + 1) as f64 * pmm);
    for n in (m + 2)..=l {
        let next = (z * cur * (2 * n - 1) as f64 - prev * (n + m - 1) as f64) * (1.0 / (n - m) as f64);
        (prev, cur) = (cur, next);
    }
    cur
}

/// √((2l + 1)/4π · (l − m)!/(l + m)!).
fn normalisation(l: usize, m: usize) -> f64 {
    let ratio = ((l - m + 1)..=(l + m)).fold(1.0, |acc, j| acc / j as f64);
    ((2 * l + 1) as f64 / (4.0 * PI) * ratio).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::distance::direction_along;
    use crate::core::phase::{hg_of_mu, phase_taylor};
    use crate::core::space::{D2, D3};
    use glam::{DVec2, DVec3};

    fn fibonacci(n: usize) -> Vec<DVec3> {
        let golden = PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - (2 * i + 1) as f64 / n as f64;
                let r = (1.0 - z * z).sqrt();
                let phi = golden * i as f64;
                DVec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect()
    }

    /// The basis is orthonormal: quadrature over 20k sphere points (circle: 4096
    /// equally spaced angles, exact for trigonometric polynomials of low degree).
    #[test]
    fn the_basis_is_orthonormal() {
        let bands = 6;
        let pts = fibonacci(20_000);
        let vals: Vec<Vec<f64>> = pts.iter().map(|&d| basis_values::<D3>(bands, d)).collect();
        let n = basis_count::<D3>(bands);
        for i in 0..n {
            for j in 0..n {
                let s: f64 = vals.iter().map(|v| v[i] * v[j]).sum::<f64>() * 4.0 * PI / pts.len() as f64;
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((s - want).abs() < 2e-3, "3D <B{i}, B{j}> = {s}");
            }
        }
        let m = 4096;
        let vals: Vec<Vec<f64>> = (0..m)
            .map(|i| basis_values::<D2>(bands, DVec2::from_angle(2.0 * PI * i as f64 / m as f64)))
            .collect();
        for i in 0..basis_count::<D2>(bands) {
            for j in 0..basis_count::<D2>(bands) {
                let s: f64 = vals.iter().map(|v| v[i] * v[j]).sum::<f64>() * 2.0 * PI / m as f64;
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((s - want).abs() < 1e-12, "2D <B{i}, B{j}> = {s}");
            }
        }
    }

    /// The shared sweep gives every basis function as [`basis`] does.
    #[test]
    fn the_sweep_gives_each_basis_function() {
        let (x, c) = (DVec3::new(0.1, -0.3, 0.2), DVec3::new(-0.7, 0.5, 0.9));
        let d: Vec<Taylor2<D3>> = (0..3).map(|i| -direction_along::<D3>(x, c, 0.1, D3::axis(i))).collect();
        let all = basis_all(7, &d);
        for (k, got) in all.iter().enumerate() {
            let want = basis(k, &d);
            assert!((got.value - want.value).abs() < 1e-12, "3D k = {k}");
            assert!((got.grad - want.grad).length() < 1e-11, "3D k = {k}");
            assert!(
                (got.hess - want.hess).abs().to_cols_array().iter().all(|e| *e < 1e-10),
                "3D k = {k}"
            );
        }
        let (x, c) = (DVec2::new(0.1, -0.3), DVec2::new(-0.7, 0.5));
        let d: Vec<Taylor2<D2>> = (0..2).map(|i| -direction_along::<D2>(x, c, 0.1, D2::axis(i))).collect();
        for (k, got) in basis_all(7, &d).iter().enumerate() {
            let want = basis(k, &d);
            assert!(
                (got.value - want.value).abs() < 1e-12 && (got.grad - want.grad).length() < 1e-11,
                "2D k = {k}"
            );
        }
    }

    /// Σ g^l B_k(a) B_k(b) is the phase function f(a·b), to g^{L+1}.
    #[test]
    fn the_weighted_moments_are_the_phase_function() {
        let a3 = DVec3::new(0.3, -0.5, 0.81).normalize();
        let a2 = DVec2::new(0.6, -0.8);
        for g in [-0.6, 0.0, 0.3, 0.7] {
            for (i, b3) in fibonacci(40).into_iter().enumerate() {
                let bands = 30;
                let w = phase_weights::<D3>(g, bands, b3);
                let sum: f64 = w.iter().zip(basis_values::<D3>(bands, a3)).map(|(c, b)| c * b).sum();
                let want = hg_of_mu::<D3>(g, a3.dot(b3)).0;
                // The tail beyond band 30 is Σ (2l + 1)/4π gˡ ≈ 3e-4 at g = 0.7.
                assert!((sum - want).abs() < 1e-3, "3D g {g} #{i}: {sum} vs {want}");
                let b2 = DVec2::from_angle(0.37 * i as f64);
                let w = phase_weights::<D2>(g, bands, b2);
                let sum: f64 = w.iter().zip(basis_values::<D2>(bands, a2)).map(|(c, b)| c * b).sum();
                let want = hg_of_mu::<D2>(g, a2.dot(b2)).0;
                assert!((sum - want).abs() < 1e-4, "2D g {g} #{i}: {sum} vs {want}");
            }
        }
    }

    /// On a direction field's components, the weighted sum has the phase's
    /// derivatives in x too (phase_taylor, same softening).
    #[test]
    fn the_moments_carry_the_phase_derivatives() {
        // Unsoftened: a softened u is shorter than a unit vector, where the basis
        // polynomials and the phase's closed form part by O((soft/r)²).
        let (g, bands, soft) = (0.4, 28, 0.0);
        let (x, c, w) = (
            DVec3::new(0.1, 0.2, -0.1),
            DVec3::new(0.9, -0.4, 0.6),
            DVec3::new(0.2, 0.9, 0.1).normalize(),
        );
        let d: Vec<Taylor2<D3>> = (0..3)
            .map(|i| -direction_along::<D3>(x, c, soft, D3::axis(i)))
            .collect();
        let weights = phase_weights::<D3>(g, bands, w);
        let mut sum = Taylor2::<D3>::zero();
        for (k, cw) in weights.iter().enumerate() {
            sum += basis(k, &d) * *cw;
        }
        let want = phase_taylor::<D3>(g, x, c, w, soft);
        assert!((sum.value - want.value).abs() < 1e-6, "{} vs {}", sum.value, want.value);
        assert!((sum.grad - want.grad).length() < 1e-5 * want.grad.length().max(1.0));
        for j in 0..3 {
            assert!((sum.hess.col(j) - want.hess.col(j)).length() < 1e-4 * want.hess.col(0).length().max(1.0));
        }
    }
}
