//! Distance and direction from the receiving point x to a fixed point c, as
//! [`Taylor2`] fields of x: the building blocks of the phase, transmittance and
//! medium-element derivatives (theory.md §5).
//!
//! Convention (theory.md §1): d = c − x, and ω = d/|d| is the direction light
//! arrives *from* when it comes from c (it travels along −ω).
//!
//! Softening (theory.md §7, x close to an element): with a softening length ε ≥ 0
//! the distance is r = √(|d|² + ε²) and the "direction" u = d / r (|u| < 1 when
//! ε > 0). Everything stays smooth and bounded near c (derivatives of order 1/ε,
//! 1/ε²), the Hessians stay exact second derivatives of the softened functions, and
//! for |d| ≫ ε the relative change is ε²/(2|d|²). ε = 0 gives the exact formulas;
//! it is raised to [`MIN_DISTANCE`] so that 1/r³ can never overflow. Callers pass a
//! small fraction of the element's size ([`near_distance`]; the segment and
//! triangle form factors clamp their vertex and edge distances to it).

use super::space::Space;
use super::taylor::Taylor2;

/// Absolute floor of every softening or clamping length: 1/r³ stays below 1e240.
pub const MIN_DISTANCE: f64 = 1e-80;

/// Fraction of an element's size below which vertex/edge distances are clamped.
pub const NEAR_FRACTION: f64 = 1e-2;

/// The clamping distance for an element of the given size (and the softening length
/// to pass to the phase and transmittance factors of a surface element).
pub fn near_distance(size: f64) -> f64 {
    (NEAR_FRACTION * size.abs()).max(MIN_DISTANCE)
}

/// d = c − x, softened distance r and u = d / r. The one place these are computed.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Offset<S: Space> {
    /// Softened distance √(|d|² + ε²) (≥ MIN_DISTANCE).
    pub r: f64,
    /// d / r.
    pub u: S::Vec,
    /// ε² / r² = 1 − |u|², computed without cancellation.
    pub soft_ratio2: f64,
}

impl<S: Space> Offset<S> {
    pub fn new(x: S::Vec, c: S::Vec, soft: f64) -> Self {
        let eps = soft.abs().max(MIN_DISTANCE);
        let d = c - x;
        let r = (S::length_squared(d) + eps * eps).sqrt();
        let q = eps / r;
        Offset {
            r,
            u: d / r,
            soft_ratio2: q * q,
        }
    }
}

/// The softened distance r(x) = √(|c − x|² + ε²): ∇r = −u, H r = (I − u uᵀ)/r.
pub fn distance<S: Space>(x: S::Vec, c: S::Vec, soft: f64) -> Taylor2<S> {
    distance_from(&Offset::new(x, c, soft))
}

pub(crate) fn distance_from<S: Space>(o: &Offset<S>) -> Taylor2<S> {
    Taylor2::new(o.r, -o.u, (S::identity() - S::outer(o.u, o.u)) * (1.0 / o.r))
}

/// The component u·w of the softened direction u = (c − x)/r along a fixed vector w:
/// ∇ = −(w − (u·w)u)/r, H = [−(w uᵀ + u wᵀ) − (u·w)(I − 3u uᵀ)]/r².
pub fn direction_along<S: Space>(x: S::Vec, c: S::Vec, soft: f64, w: S::Vec) -> Taylor2<S> {
    direction_along_from(&Offset::new(x, c, soft), w)
}

pub(crate) fn direction_along_from<S: Space>(o: &Offset<S>, w: S::Vec) -> Taylor2<S> {
    let u = o.u;
    let m = S::dot(u, w);
    let p = w - u * m;
    let wu = S::outer(w, u);
    let hess = -(wu + S::transpose(wu)) - (S::identity() - S::outer(u, u) * 3.0) * m;
    Taylor2::new(m, -p * (1.0 / o.r), hess * (1.0 / (o.r * o.r)))
}

/// The product u_a·u_b of two softened direction fields from x (to two fixed
/// points), in closed form: ∇ = ∇(u_a·w)|_{w=u_b} + ∇(u_b·w)|_{w=u_a}, and the
/// Hessian the two fixed-w Hessians plus the cross terms J_a J_b + J_b J_a, with
/// J = ∂u/∂x = −(I − u uᵀ)/r. Why: the same field summed from its components
/// (2·d direction fields and d products) cost 3× as much, and a camera's ω_o
/// makes it every phase factor of a record's derivatives.
pub(crate) fn directions_dot<S: Space>(a: &Offset<S>, b: &Offset<S>) -> Taylor2<S> {
    let along_a = direction_along_from(a, b.u);
    let along_b = direction_along_from(b, a.u);
    let pa = S::identity() - S::outer(a.u, a.u);
    let pb = S::identity() - S::outer(b.u, b.u);
    let cross = (pa * pb + pb * pa) * (1.0 / (a.r * b.r));
    Taylor2::new(
        along_a.value,
        along_a.grad + along_b.grad,
        along_a.hess + along_b.hess + cross,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Sampler;
    use crate::core::space::{D2, D3};
    use crate::core::testing::*;
    use num_dual::DualNum;

    fn check<S: Space>(seed: u64) -> f64 {
        let mut s = Sampler::new(seed, 0);
        let mut worst = 0.0f64;
        for i in 0..300 {
            let x = random_vec::<S>(&mut s, 2.0);
            let c = random_vec::<S>(&mut s, 2.0);
            let w = random_unit::<S>(&mut s);
            let soft = [0.0, 1e-3, 0.3][i % 3];
            let ad_r = ad_taylor::<S>(
                |xs| {
                    let mut r2 = HD::from(soft * soft);
                    for k in 0..S::DIM {
                        let dk = -xs[k] + c[k];
                        r2 += dk * dk;
                    }
                    r2.sqrt()
                },
                x,
            );
            worst = worst.max(rel_err(&distance::<S>(x, c, soft), &ad_r));
            let ad_u = ad_taylor::<S>(
                |xs| {
                    let mut r2 = HD::from(soft * soft);
                    let mut dw = HD::from(0.0);
                    for k in 0..S::DIM {
                        let dk = -xs[k] + c[k];
                        r2 += dk * dk;
                        dw += dk * w[k];
                    }
                    dw / r2.sqrt()
                },
                x,
            );
            worst = worst.max(rel_err(&direction_along::<S>(x, c, soft, w), &ad_u));
            let e = random_vec::<S>(&mut s, 2.0);
            let soft_e = [0.3, 0.0, 1e-3][i % 3];
            let ad_dot = ad_taylor::<S>(
                |xs| {
                    let (mut rc2, mut re2) = (HD::from(soft * soft), HD::from(soft_e * soft_e));
                    let mut dd = HD::from(0.0);
                    for k in 0..S::DIM {
                        let (dc, de) = (-xs[k] + c[k], -xs[k] + e[k]);
                        rc2 += dc * dc;
                        re2 += de * de;
                        dd += dc * de;
                    }
                    dd / (rc2.sqrt() * re2.sqrt())
                },
                x,
            );
            let got = directions_dot(&Offset::<S>::new(x, c, soft), &Offset::<S>::new(x, e, soft_e));
            worst = worst.max(rel_err(&got, &ad_dot));
        }
        worst
    }

    #[test]
    fn distance_and_direction_match_ad() {
        let e2 = check::<D2>(1);
        let e3 = check::<D3>(2);
        eprintln!("distance/direction max rel AD error: 2D {e2:e}, 3D {e3:e}");
        assert!(e2 < 1e-12 && e3 < 1e-12);
    }

    #[test]
    fn at_the_centre_it_is_finite() {
        let c = glam::DVec3::new(1.0, 2.0, 3.0);
        for soft in [0.0, 1e-9, 1.0] {
            let r = distance::<D3>(c, c, soft);
            let u = direction_along::<D3>(c, c, soft, glam::DVec3::X);
            assert!(r.is_finite() && u.is_finite(), "{r:?} {u:?}");
            assert_eq!(u.value, 0.0);
        }
    }
}
