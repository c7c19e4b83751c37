//! Test helpers for the pipeline, generic over the dimension: a chi-square test of
//! a direction sampler against its pdf on the circle or the sphere (pbrt-v4's habit:
//! every sampler gets one) and a per-channel check of a Monte Carlo estimate.

use super::dim::Dim;
use crate::core::color::Rgb;
use std::f64::consts::{PI, TAU};

/// Azimuthal sectors about the axis on the sphere (on the circle: the two sides).
const SECTORS_3D: usize = 6;
/// Quadrature intervals per bin and per axis (even, for Simpson's rule).
const QUAD: usize = 48;

/// Directions binned by the polar angle θ to `axis(0)` in `rings` bands, narrower
/// towards both poles (θ_k = π(1 − cos(πk/K))/2: a lobe with |g| → 1 puts its mass
/// within ~(1 − |g|) of a pole), times the side of the axis (2D) or an azimuthal
/// sector about it (3D).
struct Bins<S> {
    edges: Vec<f64>,
    _dim: std::marker::PhantomData<S>,
}

impl<S: Dim> Bins<S> {
    fn new(rings: usize) -> Self {
        let edges = (0..=rings)
            .map(|k| 0.5 * PI * (1.0 - (PI * k as f64 / rings as f64).cos()))
            .collect();
        Bins {
            edges,
            _dim: std::marker::PhantomData,
        }
    }

    fn sectors() -> usize {
        if S::DIM == 2 { 2 } else { SECTORS_3D }
    }

    fn len(&self) -> usize {
        (self.edges.len() - 1) * Self::sectors()
    }

    /// The unit direction at polar angle θ and azimuth φ about `axis(0)` (in 2D, φ is
    /// 0 or π: the two sides).
    fn direction(theta: f64, phi: f64) -> S::Vec {
        let mut w = S::axis(0) * theta.cos() + S::axis(1) * (phi.cos() * theta.sin());
        if S::DIM == 3 {
            w += S::axis(2) * (phi.sin() * theta.sin());
        }
        w
    }

    fn index(&self, w: S::Vec) -> usize {
        let theta = w[0].clamp(-1.0, 1.0).acos();
        let rings = self.edges.len() - 1;
        let ring = self.edges[1..].partition_point(|&e| e <= theta).min(rings - 1);
        let sector = if S::DIM == 2 {
            (w[1] < 0.0) as usize
        } else {
            let phi = w[2].atan2(w[1]) + PI;
            ((phi / TAU * SECTORS_3D as f64) as usize).min(SECTORS_3D - 1)
        };
        ring * Self::sectors() + sector
    }

    /// ∫ pdf over bin `k`: dθ on the circle, sinθ dθ dφ on the sphere (Simpson's
    /// rule in θ, exact to ~10⁻¹⁰ for HG with |g| = 0.99; midpoints in φ).
    fn probability(&self, k: usize, pdf: &impl Fn(S::Vec) -> f64) -> f64 {
        let (ring, sector) = (k / Self::sectors(), k % Self::sectors());
        let (t0, t1) = (self.edges[ring], self.edges[ring + 1]);
        let dt = (t1 - t0) / QUAD as f64;
        let simpson = |i: usize| match i {
            0 | QUAD => 1.0,
            i if i % 2 == 1 => 4.0,
            _ => 2.0,
        };
        let mut sum = 0.0;
        for i in 0..=QUAD {
            let theta = t0 + i as f64 * dt;
            let w = simpson(i) * dt / 3.0;
            sum += w * if S::DIM == 2 {
                pdf(Self::direction(theta, PI * sector as f64))
            } else {
                let dphi = TAU / (SECTORS_3D * QUAD) as f64;
                (0..QUAD)
                    .map(|j| {
                        let phi = -PI + (sector * QUAD + j) as f64 * dphi + 0.5 * dphi;
                        pdf(Self::direction(theta, phi)) * theta.sin() * dphi
                    })
                    .sum::<f64>()
            };
        }
        sum
    }
}

/// Pearson's χ² of sampled unit directions against `pdf` (per unit angle or solid
/// angle) on bins about `axis(0)`, pooled in order until each expects at least 20
/// samples. Returns (χ², degrees of freedom, the pdf's integral over all bins).
pub fn chi_square<S: Dim>(dirs: &[S::Vec], pdf: impl Fn(S::Vec) -> f64, rings: usize) -> (f64, usize, f64) {
    let bins = Bins::<S>::new(rings);
    let mut counts = vec![0.0; bins.len()];
    for &w in dirs {
        counts[bins.index(w)] += 1.0;
    }
    let n = dirs.len() as f64;
    // (observed, expected) per pooled group; what is left at the end joins the last.
    let (mut groups, mut obs, mut exp, mut total) = (Vec::<(f64, f64)>::new(), 0.0, 0.0, 0.0);
    for (k, &c) in counts.iter().enumerate() {
        let p = bins.probability(k, &pdf);
        total += p;
        obs += c;
        exp += p * n;
        if exp >= 20.0 {
            groups.push((obs, exp));
            (obs, exp) = (0.0, 0.0);
        }
    }
    match groups.last_mut() {
        Some(last) => (last.0, last.1) = (last.0 + obs, last.1 + exp),
        None => groups.push((obs, exp)),
    }
    let chi2 = groups.iter().map(|&(o, e)| (o - e) * (o - e) / e.max(1e-300)).sum();
    (chi2, groups.len().saturating_sub(1), total)
}

/// Upper quantile of χ² with `dof` degrees of freedom at the standard normal
/// quantile `z` (Wilson–Hilferty; z = 3.72 is the 10⁻⁴ tail).
pub fn chi_square_quantile(dof: usize, z: f64) -> f64 {
    let k = dof.max(1) as f64;
    let c = 2.0 / (9.0 * k);
    k * (1.0 - c + z * c.sqrt()).powi(3)
}

/// Asserts that a Monte Carlo estimate (mean, standard error per channel) matches
/// `want`: within 4 standard errors, with the standard error below `rel_se` of the
/// value (so that the check has teeth).
pub fn assert_estimate(what: &str, (mean, se): (Rgb, Rgb), want: Rgb, rel_se: f64) {
    for c in 0..3 {
        assert!(
            se[c] <= rel_se * want[c].abs(),
            "{what}: channel {c}: standard error {} above {rel_se} of {}",
            se[c],
            want[c]
        );
        assert!(
            (mean[c] - want[c]).abs() <= 4.0 * se[c],
            "{what}: channel {c}: {} vs {} ({:.1} standard errors)",
            mean[c],
            want[c],
            (mean[c] - want[c]).abs() / se[c]
        );
    }
}
