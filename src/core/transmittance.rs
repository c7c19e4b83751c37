//! Homogeneous transmittance T(d) = exp(-σ_t d) (theory.md §1), per RGB channel, and
//! its gradient and Hessian with respect to the receiving point (theory.md §5).
//!
//! For the derivatives, T(x) = exp(−σ_t r(x)) with r the (softened) distance from x
//! to a fixed point c (see [`crate::core::distance`]); σ_t is a scalar: the caller
//! evaluates RGB media per channel, or on luminance. Optically thick media (theory.md
//! §7): the factors σ_t T and σ_t² T are evaluated as exp(ln σ_t − σ_t r) and
//! exp(2 ln σ_t − σ_t r), so they underflow gracefully instead of giving 0 · ∞; they
//! are bounded by e⁻¹/r and 4e⁻²/r² for every σ_t.

use super::color::Rgb;
use super::distance::{Offset, distance_from};
use super::space::Space;
use super::taylor::Taylor2;

/// Transmittance over a length `d` of a homogeneous medium with extinction `sigma_t`.
#[inline]
pub fn transmittance(sigma_t: Rgb, d: f64) -> Rgb {
    let tau = sigma_t * d.max(0.0);
    // Grey media (the common case) need one exponential, the same bits as three.
    if tau.x == tau.y && tau.y == tau.z {
        return Rgb::splat((-tau.x).exp());
    }
    Rgb::new((-tau.x).exp(), (-tau.y).exp(), (-tau.z).exp())
}

/// T(x) = exp(−σ_t r(x)) between the receiving point `x` and a fixed point `c`, with
/// ∇T = σ_t T u and H T = σ_t² T u uᵀ − σ_t T (I − u uᵀ)/r (u = (c − x)/r).
/// `soft` is the softening length of [`crate::core::distance`] (0: exact distance);
/// it bounds the 1/r term of the Hessian when x nears c. Negative σ_t counts as 0.
pub fn transmittance_taylor<S: Space>(sigma_t: f64, x: S::Vec, c: S::Vec, soft: f64) -> Taylor2<S> {
    let sigma = sigma_t.max(0.0);
    if sigma == 0.0 {
        return Taylor2::constant(1.0);
    }
    let r = distance_from(&Offset::<S>::new(x, c, soft));
    let tau = sigma * r.value;
    let ln_sigma = sigma.ln();
    r.compose((-tau).exp(), -(ln_sigma - tau).exp(), (2.0 * ln_sigma - tau).exp())
}

/// Per-channel [`transmittance_taylor`] for an RGB extinction (one evaluation for
/// grey media).
pub fn transmittance_taylor_rgb<S: Space>(sigma_t: Rgb, x: S::Vec, c: S::Vec, soft: f64) -> [Taylor2<S>; 3] {
    if sigma_t.x == sigma_t.y && sigma_t.y == sigma_t.z {
        [transmittance_taylor::<S>(sigma_t.x, x, c, soft); 3]
    } else {
        [0, 1, 2].map(|ch| transmittance_taylor::<S>(sigma_t[ch], x, c, soft))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Sampler;
    use crate::core::space::{D2, D3};
    use crate::core::testing::*;
    use glam::{DMat2, DVec2, DVec3};

    fn ad_errors<S: Space>(seed: u64) -> f64 {
        let mut s = Sampler::new(seed, 0);
        let mut worst = 0.0f64;
        for i in 0..600 {
            let sigma = [1e-6, 0.3, 2.0, 1e3][i % 4];
            let soft = [0.0, 1e-3, 0.2][(i / 4) % 3];
            let x = random_vec::<S>(&mut s, 1.0);
            // Keep σ_t r moderate for σ_t = 1e3 so that T does not underflow to 0.
            let reach = if sigma > 100.0 { 0.02 } else { 2.0 };
            let c = x + random_vec::<S>(&mut s, reach);
            let got = transmittance_taylor::<S>(sigma, x, c, soft);
            let want = ad_taylor::<S>(|xs| transmittance_ref::<S>(sigma, xs, c, soft), x);
            let e = rel_err(&got, &want);
            assert!(e < 1e-9, "σ={sigma} soft={soft}: {e:e}\n{got:?}\n{want:?}");
            worst = worst.max(e);
        }
        worst
    }

    #[test]
    fn transmittance_derivatives_match_ad() {
        let e2 = ad_errors::<D2>(31);
        let e3 = ad_errors::<D3>(32);
        eprintln!("transmittance_taylor max rel AD error: 2D {e2:e}, 3D {e3:e}");
        assert!(e2 < 1e-10 && e3 < 1e-10);
    }

    #[test]
    fn matches_rgb_transmittance_and_vacuum_is_constant() {
        let (x, c) = (DVec3::new(0.1, 0.2, 0.3), DVec3::new(1.0, -1.0, 2.0));
        let t = transmittance_taylor::<D3>(0.7, x, c, 0.0);
        let rgb = transmittance(Rgb::splat(0.7), (c - x).length());
        assert!((t.value - rgb.x).abs() < 1e-15);
        assert_eq!(transmittance_taylor::<D3>(0.0, x, c, 0.0), Taylor2::constant(1.0));
        assert_eq!(transmittance_taylor::<D3>(-1.0, x, c, 0.0), Taylor2::constant(1.0));
    }

    #[test]
    fn finite_for_extreme_extinction_and_distance() {
        let mut s = Sampler::new(33, 0);
        for i in 0..5000 {
            let sigma = 10f64.powf(-12.0 + 24.0 * s.next_f64()) * if i % 50 == 0 { 1e280 } else { 1.0 };
            let x = random_vec::<D2>(&mut s, 1.0);
            let reach = 10f64.powf(-15.0 + 16.0 * s.next_f64());
            let c = x + random_vec::<D2>(&mut s, reach);
            let c = if i % 10 == 0 { x } else { c };
            for soft in [0.0, 1e-9, 1e-2] {
                let t = transmittance_taylor::<D2>(sigma, x, c, soft);
                assert!(t.is_finite(), "σ={sigma} d={:?}: {t:?}", c - x);
                assert!((0.0..=1.0).contains(&t.value));
            }
        }
        // An optically thick medium: the Hessian stays bounded by 4e⁻²/r² + e⁻¹/r².
        let r = 1e-3;
        for sigma in [1e3, 1e5, 1e8, 1e300] {
            let t = transmittance_taylor::<D2>(sigma, DVec2::ZERO, DVec2::new(r, 0.0), 0.0);
            assert!(D2::frobenius(t.hess) <= 2.0 / (r * r), "σ={sigma}: {:?}", t.hess);
        }
        assert_eq!(
            transmittance_taylor::<D2>(1e300, DVec2::ZERO, DVec2::X, 0.0).hess,
            DMat2::ZERO
        );
    }

    #[test]
    fn finite_differences_converge_at_second_order() {
        let mut s = Sampler::new(34, 0);
        let mut checked = 0;
        for i in 0..30 {
            let sigma = [0.1, 1.0, 5.0][i % 3];
            let x = random_vec::<D2>(&mut s, 1.0);
            let c = DVec2::new(2.5, 0.0) + random_vec::<D2>(&mut s, 1.0);
            checked += assert_fd_order2::<D2>(|y| transmittance_taylor::<D2>(sigma, y, c, 0.0), x, 0.04) as usize;
            let x = random_vec::<D3>(&mut s, 1.0);
            let c = DVec3::new(2.5, 0.0, 0.0) + random_vec::<D3>(&mut s, 1.0);
            checked += assert_fd_order2::<D3>(|y| transmittance_taylor::<D3>(sigma, y, c, 0.01), x, 0.04) as usize;
        }
        assert!(checked > 50, "only {checked} measurable cases");
    }
}
