//! Circular harmonics for anisotropic flatland media (theory.md §1).
//!
//! For HG media a cache stores the incident light field's circular-harmonic moments
//!   M_k = (∫ L_i(x, ω) cos kθ_ω dθ, ∫ L_i(x, ω) sin kθ_ω dθ),  k = 0..K,
//! where θ_ω is the angle of the direction ω light arrives *from*. From elements,
//! M_k = Σ_j (T · L_o · F)_j · (cos kθ_j, sin kθ_j) with ω_j = (c_j − x)/|c_j − x|;
//! [`circular_harmonics`] gives the basis functions with their gradients and
//! Hessians in x, so the moments carry derivatives ([`Taylor2`] per coefficient).
//! [`hg2_in_scatter`] turns moments into ∫ f(−ω·ω_o) L_i(ω) dω for any ω_o, using
//! the 2D HG Fourier series f = (1/2π) Σ_k g^|k| e^{ik(·)}: harmonic k is scaled by
//! g^k (times (−1)^k, since light arriving from ω travels along −ω). The caller
//! multiplies by σ_s. An isotropic medium needs only M_0 (K = 0).
//!
//! Softening (theory.md §7): with u = (c − x)/√(|c − x|² + ε²) the basis functions
//! are Re/Im of (u_x + i u_y)^k = (cos kθ, sin kθ)(|d|/r)^k: smooth everywhere and
//! zero at the element's centre for k ≥ 1 (an element around x has no preferred
//! direction), equal to cos kθ, sin kθ up to a relative k ε²/(2|d|²) far away.

use super::distance::{Offset, direction_along_from};
use super::space::D2;
use super::taylor::Taylor2;
use glam::DVec2;
use std::f64::consts::TAU;
use std::ops::{Add, Mul};

/// Fills `out[k] = [cos kθ, sin kθ]` (k = 0..out.len()) of the softened arrival
/// direction from `c` at `x`, as [`Taylor2`] fields of x, by the recurrence
/// (u_x + i u_y)^k = (u_x + i u_y)^{k−1} (u_x + i u_y) with the product rule.
pub fn circular_harmonics(x: DVec2, c: DVec2, soft: f64, out: &mut [[Taylor2<D2>; 2]]) {
    if out.is_empty() {
        return;
    }
    out[0] = [Taylor2::constant(1.0), Taylor2::zero()];
    if out.len() == 1 {
        return;
    }
    let o = Offset::<D2>::new(x, c, soft);
    let ux = direction_along_from(&o, DVec2::X);
    let uy = direction_along_from(&o, DVec2::Y);
    out[1] = [ux, uy];
    for k in 2..out.len() {
        let [re, im] = out[k - 1];
        out[k] = [re * ux - im * uy, re * uy + im * ux];
    }
}

/// ∫ f(−ω·ω_o) L_i(ω) dω from the moments `moments[k] = [∫L cos kθ, ∫L sin kθ]`
/// (the sine part of k = 0 is ignored), for the 2D HG with asymmetry `g` (clamped to
/// [−1, 1]) and outgoing direction `w_o`:
///   (1/2π) [M_0 + 2 Σ_{k≥1} (−g)^k (M_k,cos cos kθ_o + M_k,sin sin kθ_o)].
/// Generic over the coefficient type: `f64`, or [`Taylor2`] for the derivatives.
pub fn hg2_in_scatter<T>(g: f64, moments: &[[T; 2]], w_o: DVec2) -> T
where
    T: Copy + Add<Output = T> + Mul<f64, Output = T>,
{
    let mut sum = moments[0][0] * (1.0 / TAU);
    if g == 0.0 {
        return sum;
    }
    let g = g.clamp(-1.0, 1.0);
    let dir = w_o.try_normalize().unwrap_or(DVec2::X);
    let mut rot = DVec2::X; // (cos kθ_o, sin kθ_o)
    let mut weight = 1.0 / TAU;
    for m in &moments[1..] {
        rot = rot.rotate(dir);
        weight *= -g;
        sum = sum + m[0] * (2.0 * weight * rot.x) + m[1] * (2.0 * weight * rot.y);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::phase::Hg2;
    use crate::core::rng::Sampler;
    use crate::core::space::Space;
    use crate::core::testing::*;
    use glam::DMat2;
    use num_dual::DualNum;

    const K: usize = 6;

    fn harmonic_ref(k: usize, sine: bool, c: DVec2, soft: f64, xs: &[HD]) -> HD {
        let (dx, dy) = (-xs[0] + c.x, -xs[1] + c.y);
        let r2 = dx * dx + dy * dy;
        let eps = soft.max(crate::core::distance::MIN_DISTANCE);
        let shrink = (r2 / (r2 + eps * eps)).sqrt().powi(k as i32);
        let angle = atan2_hd(dy, dx) * k as f64;
        (if sine { angle.sin() } else { angle.cos() }) * shrink
    }

    #[test]
    fn harmonics_match_ad() {
        let mut s = Sampler::new(61, 0);
        let mut worst = 0.0f64;
        let mut out = [[Taylor2::<D2>::zero(); 2]; K + 1];
        for i in 0..500 {
            let soft = [0.0, 1e-3, 0.3][i % 3];
            let x = random_vec::<D2>(&mut s, 1.0);
            let c = random_vec::<D2>(&mut s, 2.0);
            circular_harmonics(x, c, soft, &mut out);
            for (k, pair) in out.iter().enumerate() {
                for (j, got) in pair.iter().enumerate() {
                    let want = ad_taylor::<D2>(|xs| harmonic_ref(k, j == 1, c, soft, xs), x);
                    // Normalise by the first-order scale k/r so sin 0θ = 0 and nodes compare sanely.
                    let r = (c - x).length();
                    let scale = Taylor2::<D2>::new(
                        1.0,
                        DVec2::splat(k as f64 / r),
                        DMat2::IDENTITY * (k * k) as f64 / (r * r),
                    );
                    let e = (got.value - want.value).abs()
                        + D2::length(got.grad - want.grad) / D2::length(scale.grad).max(1.0)
                        + D2::frobenius(got.hess - want.hess) / D2::frobenius(scale.hess).max(1.0);
                    assert!(e < 1e-10, "k={k} sin={j}: {e:e}\n{got:?}\n{want:?}");
                    worst = worst.max(e);
                }
            }
        }
        eprintln!("circular_harmonics max scaled AD error: {worst:e}");
    }

    #[test]
    fn harmonics_at_the_centre_and_isotropic_order() {
        let mut out = [[Taylor2::<D2>::zero(); 2]; K + 1];
        let c = DVec2::new(0.3, -0.2);
        circular_harmonics(c, c, 0.0, &mut out);
        assert!(out.iter().flatten().all(|t| t.is_finite()));
        assert_eq!(out[0][0], Taylor2::constant(1.0));
        assert!(out[2..].iter().flatten().all(|t| t.value == 0.0));
        let mut one = [[Taylor2::<D2>::zero(); 2]; 1];
        circular_harmonics(DVec2::ZERO, c, 0.0, &mut one);
        assert_eq!(one[0][0], Taylor2::constant(1.0));
    }

    #[test]
    fn in_scatter_matches_quadrature() {
        let mut s = Sampler::new(62, 0);
        for g in [-0.9, -0.3, 0.0, 0.5, 0.95] {
            // L(θ) = Σ a_k cos kθ + b_k sin kθ with K harmonics: the moments are exact.
            let coef: Vec<[f64; 2]> = (0..=K).map(|_| [s.next_f64(), s.next_f64()]).collect();
            let l = |t: f64| {
                coef.iter()
                    .enumerate()
                    .map(|(k, [a, b])| a * (k as f64 * t).cos() + b * (k as f64 * t).sin())
                    .sum::<f64>()
            };
            let moments: Vec<[f64; 2]> = coef
                .iter()
                .enumerate()
                .map(|(k, [a, b])| {
                    if k == 0 {
                        [TAU * a, 0.0]
                    } else {
                        [std::f64::consts::PI * a, std::f64::consts::PI * b]
                    }
                })
                .collect();
            let p = Hg2::new(g);
            for _ in 0..5 {
                let w_o = DVec2::from_angle(TAU * s.next_f64());
                let n = 200_000;
                let h = TAU / n as f64;
                let quad: f64 = (0..n)
                    .map(|i| {
                        let t = (i as f64 + 0.5) * h;
                        p.eval(-DVec2::from_angle(t), w_o) * l(t) * h
                    })
                    .sum();
                let got = hg2_in_scatter(g, &moments, w_o);
                assert!(
                    (got - quad).abs() < 1e-9 * quad.abs().max(1.0),
                    "g={g}: {got} vs {quad}"
                );
                // The same with derivative-carrying coefficients.
                let tm: Vec<[Taylor2<D2>; 2]> = moments.iter().map(|m| m.map(Taylor2::constant)).collect();
                assert!((hg2_in_scatter(g, &tm, w_o).value - got).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn harmonics_rotate_with_the_scene() {
        // cos kθ and sin kθ mix under a rotation by φ: (C, S) → (C cos kφ − S sin kφ, ...);
        // check the derivatives of C_k transform as R g, R H Rᵀ for rotation-invariant
        // combinations: C_k² + S_k² (= (|d|/r)^{2k}).
        let mut s = Sampler::new(63, 0);
        let mut a = [[Taylor2::<D2>::zero(); 2]; K + 1];
        let mut b = [[Taylor2::<D2>::zero(); 2]; K + 1];
        for _ in 0..100 {
            let rot = DMat2::from_angle(TAU * s.next_f64());
            let shift = random_vec::<D2>(&mut s, 5.0);
            let (x, c) = (random_vec::<D2>(&mut s, 1.0), random_vec::<D2>(&mut s, 1.0));
            circular_harmonics(x, c, 0.2, &mut a);
            circular_harmonics(rot * x + shift, rot * c + shift, 0.2, &mut b);
            for k in 1..=K {
                let fa = a[k][0] * a[k][0] + a[k][1] * a[k][1];
                let fb = b[k][0] * b[k][0] + b[k][1] * b[k][1];
                let moved = Taylor2::<D2>::new(fa.value, rot * fa.grad, rot * fa.hess * rot.transpose());
                assert!(rel_err(&fb, &moved) < 1e-10);
            }
        }
    }
}
