//! Henyey–Greenstein phase functions (theory.md §1).
//!
//! Convention: `eval(d_in, d_out)` takes the direction of travel *before* and
//! *after* scattering (unit vectors), so forward scattering (g > 0) peaks when
//! `d_in == d_out`. The in-scattered radiance towards ω_o from light arriving from
//! ω uses `eval(-ω, ω_o)`.
//!
//! Numerics for g → ±1: 1 + g² − 2gμ is written as (1−g)² + 2g(1−μ) (g ≥ 0) or
//! (1+g)² − 2g(1+μ) (g < 0), with 1∓μ computed from |d_in ∓ d_out|²/2, which never
//! cancels catastrophically.
//!
//! Derivatives with respect to the receiving point x (theory.md §5): light reaches x
//! from an element centred at c, arriving from ω_j = (c − x)/|c − x| (travelling
//! along −ω_j), and leaves along ω_o, so the phase factor is f(μ) with
//! μ = −ω_j · ω_o; [`phase_taylor`] returns it with its gradient and Hessian in x,
//! using the 2D HG for `D2` and the 3D HG for `D3` ([`hg_of_mu`]).

use super::distance::{Offset, direction_along, direction_along_from, directions_dot};
use super::space::Space;
use super::taylor::Taylor2;
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

/// |g| is limited to this in the derivative functions: |g| = 1 is a Dirac delta with
/// no finite derivatives; below it every value stays finite (theory.md §7).
pub const G_MAX: f64 = 1.0 - 1e-12;

/// HG value and derivatives in μ from D = 1 + g² − 2gμ (> 0) for dimension `S`:
/// f = (1 − g²)/(|S^{d−1}| Dⁿ) with n = 1 (2D) or 3/2 (3D), f' = 2gn f/D,
/// f'' = 4g²n(n+1) f/D².
#[inline]
fn hg_of_den<S: Space>(g: f64, den: f64) -> (f64, f64, f64) {
    let den = den.max(f64::MIN_POSITIVE);
    let (n, pow) = if S::DIM == 2 {
        (1.0, den)
    } else {
        (1.5, den * den.sqrt())
    };
    let f = (1.0 - g) * (1.0 + g) / (S::SPHERE_MEASURE * pow);
    let df = 2.0 * g * n * f / den;
    let d2f = 4.0 * g * g * n * (n + 1.0) * f / (den * den);
    (f, df, d2f)
}

/// The Henyey–Greenstein phase function of dimension `S` (2D: wrapped Cauchy, 3D:
/// HG) as a function of μ, with df/dμ and d²f/dμ². 1 + g² − 2gμ is evaluated as
/// (1 − g)² + 2g(1 − μ) (g ≥ 0) or (1 + g)² − 2g(1 + μ) (g < 0): no cancellation
/// between 1 + g² and 2gμ. μ is clamped to [−1, 1] and |g| to [`G_MAX`].
pub fn hg_of_mu<S: Space>(g: f64, mu: f64) -> (f64, f64, f64) {
    if g == 0.0 {
        return (1.0 / S::SPHERE_MEASURE, 0.0, 0.0);
    }
    let g = g.clamp(-G_MAX, G_MAX);
    let mu = mu.clamp(-1.0, 1.0);
    let den = if g >= 0.0 {
        (1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - mu)
    } else {
        (1.0 + g) * (1.0 + g) - 2.0 * g * (1.0 + mu)
    };
    hg_of_den::<S>(g, den)
}

/// Where in-scattered light leaves towards: L_s(x, ω_o) with ω_o fixed, or ω_o
/// pointing from x to a fixed point (a pinhole camera), so that what the camera sees
/// of each medium point is a function of x alone, with derivatives that include the
/// turning of ω_o as x moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outgoing<V> {
    /// A fixed direction ω_o (need not be normalised; zero means the first axis).
    Direction(V),
    /// ω_o(x) = (e − x)/|e − x| towards the point e.
    TowardsPoint(V),
}

/// The phase factor f(−ω_j · ω_o) of light from an element centred at `c` received
/// at `x` and scattered towards the unit vector `w_o`, with gradient and Hessian in x.
///
/// `soft` is the softening length of [`crate::core::distance`]: ω_j is replaced by
/// u = (c − x)/√(|c − x|² + soft²), which keeps the derivatives bounded (≲ 1/soft,
/// 1/soft²) when x nears c; pass a small fraction of the element's size.
/// Isotropic media (g = 0) return the constant 1/|S^{d−1}| without any work.
pub fn phase_taylor<S: Space>(g: f64, x: S::Vec, c: S::Vec, w_o: S::Vec, soft: f64) -> Taylor2<S> {
    phase_taylor_out(g, x, c, Outgoing::Direction(w_o), soft)
}

/// [`phase_taylor`] for either kind of [`Outgoing`]. Towards a point e, μ = −u_c·u_e
/// is a product of two direction fields (product rule), and 1 ∓ μ comes from
/// |u_c ± u_e|² as for a fixed direction, so g → ±1 stays free of cancellation.
pub fn phase_taylor_out<S: Space>(g: f64, x: S::Vec, c: S::Vec, out: Outgoing<S::Vec>, soft: f64) -> Taylor2<S> {
    if g == 0.0 {
        return Taylor2::constant(1.0 / S::SPHERE_MEASURE);
    }
    let g = g.clamp(-G_MAX, G_MAX);
    let o = Offset::<S>::new(x, c, soft);
    let (w, oe) = outgoing_at(x, out);
    // μ = −u·w.
    let mu = match &oe {
        None => -direction_along_from(&o, w.u),
        Some(oe) => -directions_dot(&o, oe),
    };
    let (f, df, d2f) = hg_of_den::<S>(g, phase_den::<S>(g, &o, &w));
    mu.compose(f, df, d2f)
}

/// The value of [`phase_taylor_out`] alone (the same floating-point operations),
/// for rules that differentiate otherwise or not at all.
pub fn phase_value_out<S: Space>(g: f64, x: S::Vec, c: S::Vec, out: Outgoing<S::Vec>, soft: f64) -> f64 {
    if g == 0.0 {
        return 1.0 / S::SPHERE_MEASURE;
    }
    let g = g.clamp(-G_MAX, G_MAX);
    let (w, _) = outgoing_at(x, out);
    hg_of_den::<S>(g, phase_den::<S>(g, &Offset::new(x, c, soft), &w)).0
}

/// ω_o at x as a unit direction with its softening ratio (zero for a fixed
/// direction), and towards a point, the offset it comes from.
fn outgoing_at<S: Space>(x: S::Vec, out: Outgoing<S::Vec>) -> (Offset<S>, Option<Offset<S>>) {
    match out {
        Outgoing::Direction(w_o) => {
            let len = S::length(w_o);
            let u = if len > 0.0 { w_o / len } else { S::axis(0) };
            let w = Offset {
                r: 1.0,
                u,
                soft_ratio2: 0.0,
            };
            (w, None)
        }
        Outgoing::TowardsPoint(e) => {
            let oe = Offset::<S>::new(x, e, 0.0);
            (oe, Some(oe))
        }
    }
}

/// 1 + g² − 2gμ with μ = −u·w for the softened directions of `o` and `w`: 1 ∓ μ
/// from |u ± w|² and 1 − |u|² = ε²/r², so it never cancels.
fn phase_den<S: Space>(g: f64, o: &Offset<S>, w: &Offset<S>) -> f64 {
    let soft2 = o.soft_ratio2 + w.soft_ratio2;
    if g >= 0.0 {
        let one_minus_mu = 0.5 * (S::length_squared(o.u + w.u) + soft2);
        (1.0 - g) * (1.0 - g) + 2.0 * g * one_minus_mu
    } else {
        let one_plus_mu = 0.5 * (S::length_squared(o.u - w.u) + soft2);
        (1.0 + g) * (1.0 + g) - 2.0 * g * one_plus_mu
    }
}

/// The phase factor f(−ω · ω_o) of light arriving along a *fixed* direction ω
/// (from ω, travelling along −ω), as a field of x: constant for a fixed ω_o, and
/// turning with ω_o(x) towards a point (the occlusion-unaware derivatives of Jarosz
/// et al. 2008 keep each ray's direction fixed).
pub fn phase_taylor_fixed_direction<S: Space>(g: f64, x: S::Vec, w: S::Vec, out: Outgoing<S::Vec>) -> Taylor2<S> {
    if g == 0.0 {
        return Taylor2::constant(1.0 / S::SPHERE_MEASURE);
    }
    let g = g.clamp(-G_MAX, G_MAX);
    let unit = |v: S::Vec| {
        let len = S::length(v);
        if len > 0.0 { v / len } else { S::axis(0) }
    };
    let w = unit(w);
    match out {
        Outgoing::Direction(w_o) => {
            let den = hg_denominator(g, -w, unit(w_o), S::length_squared);
            Taylor2::constant(hg_of_den::<S>(g, den).0)
        }
        Outgoing::TowardsPoint(e) => {
            let mu = direction_along::<S>(x, e, 0.0, -w);
            let den = hg_denominator(g, -w, Offset::<S>::new(x, e, 0.0).u, S::length_squared);
            let (f, df, d2f) = hg_of_den::<S>(g, den);
            mu.compose(f, df, d2f)
        }
    }
}

/// 1 + g² − 2gμ for unit vectors a, b (μ = a·b), computed without cancellation.
#[inline]
fn hg_denominator<V: Copy + std::ops::Sub<Output = V> + std::ops::Add<Output = V>>(
    g: f64,
    a: V,
    b: V,
    len2: impl Fn(V) -> f64,
) -> f64 {
    if g >= 0.0 {
        let one_minus_mu = 0.5 * len2(a - b);
        (1.0 - g) * (1.0 - g) + 2.0 * g * one_minus_mu
    } else {
        let one_plus_mu = 0.5 * len2(a + b);
        (1.0 + g) * (1.0 + g) - 2.0 * g * one_plus_mu
    }
}

/// The 2D (flatland) Henyey–Greenstein phase function: the wrapped Cauchy distribution,
/// f(θ) = (1/2π)(1 − g²)/(1 + g² − 2g cos θ), normalised over the circle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hg2 {
    pub g: f64,
}

impl Hg2 {
    pub fn new(g: f64) -> Self {
        Hg2 { g }
    }

    pub fn is_isotropic(&self) -> bool {
        self.g == 0.0
    }

    /// Phase value per radian for travel direction `d_in` scattered into `d_out`.
    #[inline]
    pub fn eval(&self, d_in: DVec2, d_out: DVec2) -> f64 {
        let g = self.g;
        if g == 0.0 {
            return 1.0 / TAU;
        }
        let den = hg_denominator(g, d_in, d_out, |v: DVec2| v.length_squared());
        (1.0 - g * g) / (TAU * den.max(f64::MIN_POSITIVE))
    }

    /// Same as [`Hg2::eval`] from the angle θ between the two directions.
    pub fn eval_angle(&self, theta: f64) -> f64 {
        self.eval(DVec2::X, DVec2::from_angle(theta))
    }

    /// Exact sampling: θ = 2 atan(((1 − g)/(1 + g)) tan(π(ξ − ½))), measured from `d_in`.
    /// Returns the new direction of travel; its pdf (per radian) is `eval(d_in, d_out)`.
    #[inline]
    pub fn sample(&self, d_in: DVec2, xi: f64) -> DVec2 {
        let g = self.g;
        let theta = if g == 0.0 {
            TAU * (xi - 0.5)
        } else {
            2.0 * (((1.0 - g) / (1.0 + g)) * (PI * (xi - 0.5)).tan()).atan()
        };
        DVec2::from_angle(theta).rotate(d_in)
    }
}

/// The 3D Henyey–Greenstein phase function, f(μ) = (1/4π)(1 − g²)/(1 + g² − 2gμ)^{3/2}.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hg3 {
    pub g: f64,
}

impl Hg3 {
    pub fn new(g: f64) -> Self {
        Hg3 { g }
    }

    /// Phase value per steradian.
    #[inline]
    pub fn eval(&self, d_in: DVec3, d_out: DVec3) -> f64 {
        let g = self.g;
        if g == 0.0 {
            return 1.0 / (4.0 * PI);
        }
        let den = hg_denominator(g, d_in, d_out, |v: DVec3| v.length_squared());
        (1.0 - g * g) / (4.0 * PI * den.max(f64::MIN_POSITIVE) * den.max(f64::MIN_POSITIVE).sqrt())
    }

    /// Exact sampling of the scattered direction of travel; pdf = `eval`.
    pub fn sample(&self, d_in: DVec3, xi1: f64, xi2: f64) -> DVec3 {
        let g = self.g;
        let mu = if g.abs() < 1e-4 {
            1.0 - 2.0 * xi1
        } else {
            let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi1);
            ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
        };
        let sin_t = (1.0 - mu * mu).max(0.0).sqrt();
        let phi = TAU * xi2;
        let (t, b) = d_in.any_orthonormal_pair();
        (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + d_in * mu).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Sampler;

    const GS: [f64; 7] = [-0.95, -0.5, 0.0, 0.5, 0.95, 0.99, -0.99];

    use crate::core::space::{D2, D3};
    use crate::core::testing::*;
    use num_dual::DualNum;

    fn phase_ad_errors<S: Space>(seed: u64) -> f64 {
        let mut s = Sampler::new(seed, 0);
        let mut worst = 0.0f64;
        for i in 0..600 {
            let g = [-0.99, -0.5, 0.0, 0.3, 0.99][i % 5];
            let soft = [0.0, 1e-3, 0.2][(i / 5) % 3];
            let x = random_vec::<S>(&mut s, 1.0);
            let c = random_vec::<S>(&mut s, 3.0);
            let mut w = random_unit::<S>(&mut s);
            if i % 7 == 0 {
                // Close to the forward peak, where 1 + g² − 2gμ is smallest.
                let d = c - x;
                w = -(d / S::length(d)) + random_vec::<S>(&mut s, 1e-3);
                w = w / S::length(w);
            }
            let got = phase_taylor::<S>(g, x, c, w, soft);
            let want = ad_taylor::<S>(|xs| phase_ref::<S>(g, xs, c, w, soft), x);
            let e = rel_err(&got, &want);
            assert!(e < 1e-9, "g={g} soft={soft}: rel err {e:e}\n{got:?}\n{want:?}");
            worst = worst.max(e);
        }
        worst
    }

    /// ω_o towards a point (the camera): both directions turn with x.
    fn phase_to_point_ad_errors<S: Space>(seed: u64) -> f64 {
        let mut s = Sampler::new(seed, 0);
        let mut worst = 0.0f64;
        for i in 0..600 {
            let g = [-0.99, -0.5, 0.3, 0.9, 0.99][i % 5];
            let soft = [0.0, 1e-3, 0.2][(i / 5) % 3];
            let x = random_vec::<S>(&mut s, 1.0);
            let c = random_vec::<S>(&mut s, 3.0);
            let mut e = x + random_unit::<S>(&mut s) * (0.5 + 3.0 * s.next_f64());
            if i % 7 == 0 {
                // The camera right behind the element: μ ≈ 1, the forward peak.
                e = x - (c - x) * (0.5 + s.next_f64()) + random_vec::<S>(&mut s, 1e-3);
            }
            let got = phase_taylor_out::<S>(g, x, c, Outgoing::TowardsPoint(e), soft);
            let want = ad_taylor::<S>(|xs| phase_ref_point::<S>(g, xs, c, e, soft), x);
            let err = rel_err(&got, &want);
            assert!(err < 1e-9, "g={g} soft={soft}: rel err {err:e}\n{got:?}\n{want:?}");
            worst = worst.max(err);
        }
        worst
    }

    #[test]
    fn phase_of_a_fixed_direction_towards_a_point_matches_ad() {
        let mut s = Sampler::new(25, 0);
        for i in 0..200 {
            let g = [-0.9, -0.3, 0.0, 0.5, 0.95][i % 5];
            let x = random_vec::<D3>(&mut s, 1.0);
            let w = random_unit::<D3>(&mut s);
            let e = x + random_unit::<D3>(&mut s) * (0.5 + 3.0 * s.next_f64());
            let got = phase_taylor_fixed_direction::<D3>(g, x, w, Outgoing::TowardsPoint(e));
            // A source point far along w: its direction from x is w whatever x does.
            let want = ad_taylor::<D3>(|xs| phase_ref_point::<D3>(g, xs, x + w * 1e12, e, 0.0), x);
            let err = rel_err(&got, &want);
            assert!(err < 1e-6, "g={g}: rel err {err:e}\n{got:?}\n{want:?}");
            let fixed = phase_taylor_fixed_direction::<D3>(g, x, w, Outgoing::Direction(e - x));
            assert!((fixed.value - got.value).abs() <= 1e-12 * got.value.abs().max(1e-300));
            assert_eq!(fixed.grad, glam::DVec3::ZERO);
        }
    }

    #[test]
    fn phase_towards_a_point_matches_ad() {
        let e2 = phase_to_point_ad_errors::<D2>(23);
        let e3 = phase_to_point_ad_errors::<D3>(24);
        eprintln!("phase_taylor_out(TowardsPoint) max rel AD error: 2D {e2:e}, 3D {e3:e}");
        assert!(e2 < 1e-10 && e3 < 1e-10, "2D {e2:e}, 3D {e3:e}");
        // With the point far away along w, it is the fixed-direction phase.
        let (x, c, w) = (
            glam::DVec3::new(0.1, 0.2, 0.3),
            glam::DVec3::new(1.0, -0.5, 2.0),
            glam::DVec3::Y,
        );
        let far = phase_taylor_out::<D3>(0.7, x, c, Outgoing::TowardsPoint(x + w * 1e9), 0.0);
        let fixed = phase_taylor::<D3>(0.7, x, c, w, 0.0);
        assert!(rel_err(&far, &fixed) < 1e-6);
    }

    #[test]
    fn phase_derivatives_match_ad() {
        let e2 = phase_ad_errors::<D2>(21);
        let e3 = phase_ad_errors::<D3>(22);
        eprintln!("phase_taylor max rel AD error: 2D {e2:e}, 3D {e3:e}");
        assert!(e2 < 1e-10 && e3 < 1e-10, "2D {e2:e}, 3D {e3:e}");
    }

    #[test]
    fn hg_of_mu_matches_eval_and_its_mu_derivatives() {
        for g in [-0.99, -0.3, 0.0, 0.6, 0.99] {
            for k in 0..=40 {
                let t = PI * k as f64 / 40.0;
                let mu = t.cos();
                let (f2, df2, d2f2) = hg_of_mu::<D2>(g, mu);
                let (f3, df3, d2f3) = hg_of_mu::<D3>(g, mu);
                let e2 = Hg2::new(g).eval_angle(t);
                let e3 = Hg3::new(g).eval(DVec3::Z, DVec3::new(t.sin(), 0.0, mu));
                assert!((f2 - e2).abs() <= 1e-12 * e2 && (f3 - e3).abs() <= 1e-12 * e3);
                // d/dμ by a hyper-dual number in μ.
                let m = HD::new(mu, 1.0, 1.0, 0.0);
                let den = -m * (2.0 * g) + (1.0 + g * g);
                let r2 = den.recip() * ((1.0 - g * g) / TAU);
                let r3 = den.powf(-1.5) * ((1.0 - g * g) / (4.0 * PI));
                for (a, b) in [(df2, r2.eps1), (d2f2, r2.eps1eps2), (df3, r3.eps1), (d2f3, r3.eps1eps2)] {
                    assert!(
                        (a - b).abs() <= 1e-10 * b.abs().max(1e-300),
                        "g={g} mu={mu}: {a} vs {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn isotropic_phase_is_constant() {
        let t = phase_taylor::<D2>(0.0, DVec2::ZERO, DVec2::X, DVec2::Y, 0.0);
        assert_eq!(t, Taylor2::constant(1.0 / TAU));
        let t = phase_taylor::<D3>(0.0, DVec3::ZERO, DVec3::X, DVec3::Y, 0.0);
        assert_eq!(t, Taylor2::constant(1.0 / (4.0 * PI)));
    }

    #[test]
    fn phase_finite_at_extremes() {
        let mut s = Sampler::new(23, 0);
        for i in 0..4000 {
            let g = [-0.999999, 0.999999, 1.0, -1.0, 0.5][i % 5];
            let soft = [0.0, 1e-12, 1e-3][i % 3];
            let x = random_vec::<D3>(&mut s, 1.0);
            let c = if i % 4 == 0 {
                x + random_vec::<D3>(&mut s, 1e-9)
            } else {
                random_vec::<D3>(&mut s, 1.0)
            };
            // Exactly on the forward and backward peaks, and at random.
            let d = (c - x).normalize_or(DVec3::X);
            let w = [-d, d, random_unit::<D3>(&mut s)][i % 3];
            let t3 = phase_taylor::<D3>(g, x, c, w, soft);
            assert!(t3.is_finite() && t3.value > 0.0, "g={g}: {t3:?}");
            let (x2, c2, w2) = (x.truncate(), c.truncate(), w.truncate());
            let t2 = phase_taylor::<D2>(g, x2, c2, w2, soft);
            assert!(t2.is_finite() && t2.value >= 0.0, "g={g}: {t2:?}");
        }
    }

    #[test]
    fn phase_finite_differences_converge_at_second_order() {
        let mut s = Sampler::new(24, 0);
        let mut checked = 0;
        for i in 0..40 {
            let g = [-0.7, 0.5, 0.9][i % 3];
            let x = random_vec::<D2>(&mut s, 1.0);
            let c = random_vec::<D2>(&mut s, 1.0) + DVec2::new(3.0, 0.0);
            let w = random_unit::<D2>(&mut s);
            checked += assert_fd_order2::<D2>(|y| phase_taylor::<D2>(g, y, c, w, 0.0), x, 0.05) as usize;
            let x = random_vec::<D3>(&mut s, 1.0);
            let c = random_vec::<D3>(&mut s, 1.0) + DVec3::new(3.0, 0.0, 0.0);
            let w = random_unit::<D3>(&mut s);
            checked += assert_fd_order2::<D3>(|y| phase_taylor::<D3>(g, y, c, w, 0.1), x, 0.05) as usize;
        }
        assert!(checked > 60, "only {checked} measurable cases");
    }

    #[test]
    fn phase_derivatives_rotate_with_the_scene() {
        let mut s = Sampler::new(25, 0);
        for _ in 0..100 {
            let rot = glam::DMat3::from_axis_angle(random_unit::<D3>(&mut s), TAU * s.next_f64());
            let shift = random_vec::<D3>(&mut s, 5.0);
            let (x, c, w) = (
                random_vec::<D3>(&mut s, 1.0),
                random_vec::<D3>(&mut s, 2.0),
                random_unit::<D3>(&mut s),
            );
            let a = phase_taylor::<D3>(0.8, x, c, w, 0.0);
            let b = phase_taylor::<D3>(0.8, rot * x + shift, rot * c + shift, rot * w, 0.0);
            let moved = Taylor2::<D3>::new(a.value, rot * a.grad, rot * a.hess * rot.transpose());
            assert!(rel_err(&b, &moved) < 1e-12);
        }
    }

    /// Midpoint quadrature over the circle, fine enough for g = 0.99 (peak width ~0.01).
    fn circle_integral(f: impl Fn(f64) -> f64) -> f64 {
        let n = 400_000;
        let h = TAU / n as f64;
        (0..n).map(|i| f(-PI + (i as f64 + 0.5) * h) * h).sum()
    }

    #[test]
    fn hg2_normalised_with_mean_cosine_g() {
        for g in GS {
            let p = Hg2::new(g);
            let norm = circle_integral(|t| p.eval_angle(t));
            let mean_cos = circle_integral(|t| p.eval_angle(t) * t.cos());
            assert!((norm - 1.0).abs() < 1e-9, "g={g}: ∫f = {norm}");
            assert!((mean_cos - g).abs() < 1e-9, "g={g}: mean cosine {mean_cos}");
        }
    }

    #[test]
    fn hg2_extremes_are_finite_and_positive() {
        for g in [-0.999999, 0.999999, 1e-12, -1e-12] {
            let p = Hg2::new(g);
            for t in [0.0, 1e-12, 1e-6, 0.5, PI - 1e-9, PI] {
                let v = p.eval_angle(t);
                assert!(v.is_finite() && v > 0.0, "g={g} t={t}: {v}");
            }
        }
    }

    /// Chi-square test of the sampler against the pdf on 64 angular bins.
    #[test]
    fn hg2_sampling_matches_pdf() {
        for g in GS {
            let p = Hg2::new(g);
            let bins = 64;
            let n = 200_000;
            let mut counts = vec![0.0f64; bins];
            let d_in = DVec2::from_angle(0.3);
            let mut s = Sampler::new(11, (g * 1000.0) as i64 as u64);
            for _ in 0..n {
                let d = p.sample(d_in, s.next_f64());
                let t = d_in.angle_to(d); // (-π, π]
                let b = (((t + PI) / TAU) * bins as f64) as usize;
                counts[b.min(bins - 1)] += 1.0;
            }
            let mut chi2 = 0.0;
            let mut dof = 0;
            let mut pooled_obs = 0.0;
            let mut pooled_exp = 0.0;
            for (b, &obs) in counts.iter().enumerate() {
                let lo = -PI + TAU * b as f64 / bins as f64;
                let m = 2000;
                let h = TAU / bins as f64 / m as f64;
                let prob: f64 = (0..m).map(|k| p.eval_angle(lo + (k as f64 + 0.5) * h) * h).sum();
                let expct = prob * n as f64;
                // Pool sparse bins so the chi-square approximation holds.
                pooled_obs += obs;
                pooled_exp += expct;
                if pooled_exp >= 20.0 {
                    chi2 += (pooled_obs - pooled_exp).powi(2) / pooled_exp;
                    dof += 1;
                    pooled_obs = 0.0;
                    pooled_exp = 0.0;
                }
            }
            // 99.9% quantile of chi-square with ≤ 63 dof is below 105.
            assert!(chi2 < 105.0, "g={g}: chi2 = {chi2} over {dof} bins");
        }
    }

    #[test]
    fn hg3_normalised_and_sampled() {
        for g in [-0.9, 0.0, 0.7] {
            let p = Hg3::new(g);
            let n = 200_000;
            let h = 2.0 / n as f64;
            let norm: f64 = (0..n)
                .map(|i| {
                    let mu = -1.0 + (i as f64 + 0.5) * h;
                    let d = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                    TAU * p.eval(DVec3::Z, d) * h
                })
                .sum();
            assert!((norm - 1.0).abs() < 1e-6, "g={g}: {norm}");
            let mut s = Sampler::new(5, 1);
            let m = 100_000;
            let mean: f64 = (0..m)
                .map(|_| p.sample(DVec3::Z, s.next_f64(), s.next_f64()).z)
                .sum::<f64>()
                / m as f64;
            assert!((mean - g).abs() < 0.01, "g={g}: mean cosine {mean}");
        }
    }
}
