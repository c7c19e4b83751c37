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

use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

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
