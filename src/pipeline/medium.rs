//! Homogeneous media filling a region of the scene (index-matched boundary), in any
//! dimension. The region is the world's (a polygon in 2D, a box in 3D); everything
//! else is the same method.
//!
//! Scene parameters: `sigma_a`, `sigma_s` (m⁻¹, RGB), `g` (Henyey–Greenstein, in
//! (−1, 1)). One routine walks the medium along a ray (pbrt-v4's rule):
//! [`Region::pieces`] gives the parts of the ray inside the region, and free-flight
//! sampling and transmittance both use it.

use super::dim::Dim;
use crate::core::color::Rgb;
use crate::core::free_flight::{Flight, sample_flight};
use crate::core::rng::Sampler;
use crate::core::transmittance::transmittance;

/// Where a medium is.
pub trait Region<S: Dim>: Clone + std::fmt::Debug + PartialEq + Send + Sync {
    /// The pieces [t0, t1] of a ray inside the region, in increasing order.
    type Pieces: IntoIterator<Item = (f64, f64)>;
    fn contains(&self, p: S::Vec) -> bool;
    /// The parts of o + t·d, 0 ≤ t ≤ t_max, inside the region.
    fn pieces(&self, o: S::Vec, d: S::Vec, t_max: f64) -> Self::Pieces;
}

/// The probability that free-flight sampling (`core::free_flight`: one channel
/// drawn uniformly, its exponential distance) passes a stretch of transmittance
/// `tr`: the mean of the channels' transmittances (for a grey medium, T).
pub fn pass_probability(tr: Rgb) -> f64 {
    tr.element_sum() / 3.0
}

#[derive(Clone, Debug, PartialEq)]
pub struct Medium<S: Dim, R> {
    pub sigma_a: Rgb,
    pub sigma_s: Rgb,
    pub sigma_t: Rgb,
    pub phase: S::Phase,
    pub region: R,
}

impl<S: Dim, R: Region<S>> Medium<S, R> {
    pub fn new(sigma_a: Rgb, sigma_s: Rgb, g: f64, region: R) -> Self {
        Medium {
            sigma_a,
            sigma_s,
            sigma_t: sigma_a + sigma_s,
            phase: S::phase(g),
            region,
        }
    }

    pub fn g(&self) -> f64 {
        S::phase_g(&self.phase)
    }

    pub fn contains(&self, p: S::Vec) -> bool {
        self.region.contains(p)
    }

    /// Length of o + t·d, 0 ≤ t ≤ t_max, inside the medium.
    pub fn length_inside(&self, o: S::Vec, d: S::Vec, t_max: f64) -> f64 {
        self.region.pieces(o, d, t_max).into_iter().map(|(a, b)| b - a).sum()
    }

    /// Transmittance along o + t·d from t = 0 to t_max (per channel; a channel that
    /// does not attenuate keeps 1 even along an infinite ray).
    pub fn transmittance(&self, o: S::Vec, d: S::Vec, t_max: f64) -> Rgb {
        let len = self.length_inside(o, d, t_max);
        if len.is_infinite() {
            return Rgb::select(self.sigma_t.cmpgt(Rgb::ZERO), Rgb::ZERO, Rgb::ONE);
        }
        transmittance(self.sigma_t, len)
    }

    /// Sample the distance to the next real scattering event before `t_max`.
    pub fn sample_flight(&self, o: S::Vec, d: S::Vec, t_max: f64, s: &mut Sampler) -> Flight {
        sample_flight(self.sigma_t, self.sigma_s, self.region.pieces(o, d, t_max), s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::space::{D2, D3, Space};
    use crate::pipeline::path::estimate_with;
    use crate::pipeline::testing::assert_estimate;

    /// A test region in any dimension: slabs a ≤ p·axis(0) ≤ b (disjoint, in
    /// increasing order), so a ray meets several pieces with gaps between them.
    #[derive(Clone, Debug, PartialEq)]
    struct Slabs(Vec<(f64, f64)>);

    impl<S: Dim> Region<S> for Slabs {
        type Pieces = Vec<(f64, f64)>;

        fn contains(&self, p: S::Vec) -> bool {
            self.0.iter().any(|&(a, b)| (a..=b).contains(&p[0]))
        }

        fn pieces(&self, o: S::Vec, d: S::Vec, t_max: f64) -> Vec<(f64, f64)> {
            let mut out: Vec<(f64, f64)> = self
                .0
                .iter()
                .filter_map(|&(a, b)| {
                    let (t0, t1) = ((a - o[0]) / d[0], (b - o[0]) / d[0]);
                    let (lo, hi) = (t0.min(t1).max(0.0), t0.max(t1).min(t_max));
                    (lo < hi).then_some((lo, hi))
                })
                .collect();
            out.sort_by(|x, y| x.0.total_cmp(&y.0));
            out
        }
    }

    /// A unit direction with a component along every axis.
    fn oblique<S: Dim>() -> S::Vec {
        let v = (0..S::DIM).fold(S::zero(), |v, i| v + S::axis(i) * (1.0 / (1 + i) as f64));
        v / S::length(v)
    }

    /// Free flight through two slabs, grey and chromatic: per channel, the pass
    /// weight averages to T(L), the scatter weight to σ_s∫T dt and the scatter weight
    /// times the distance to σ_s∫T t dt (so the events are where they should be), and
    /// no event falls in the gap between the slabs.
    fn free_flight_is_unbiased_per_channel<S: Dim>() {
        let region = Slabs(vec![(0.2, 0.5), (0.9, 1.6)]);
        let (o, d, t_max) = (S::zero(), oblique::<S>(), 2.0);
        let pieces: Vec<(f64, f64)> = Region::<S>::pieces(&region, o, d, t_max);
        assert_eq!(pieces.len(), 2);
        for sigma_t in [Rgb::splat(1.2), Rgb::new(0.5, 1.0, 3.0)] {
            let sigma_s = sigma_t * Rgb::new(0.6, 0.3, 0.9);
            let m = Medium::<S, Slabs>::new(sigma_t - sigma_s, sigma_s, 0.0, region.clone());
            // Closed forms per piece [a, b] entered after medium depth τ₀:
            // ∫ e^{−σ(τ₀+t−a)} dt and ∫ e^{−σ(τ₀+t−a)} t dt over [a, b].
            let (mut tau, mut scatter, mut moment) = (0.0, Rgb::ZERO, Rgb::ZERO);
            for &(a, b) in &pieces {
                let (t0, tl) = ((-sigma_t * tau).exp(), (-sigma_t * (tau + b - a)).exp());
                scatter += sigma_s * (t0 - tl) / sigma_t;
                let inv = Rgb::ONE / sigma_t;
                moment += sigma_s * (t0 * (inv * a + inv * inv) - tl * (inv * b + inv * inv));
                tau += b - a;
            }
            let pass = (-sigma_t * tau).exp();
            let exact = m.transmittance(o, d, t_max);
            assert!((exact - pass).abs().max_element() < 1e-14, "{exact} vs {pass}");
            let n = 400_000;
            let flight = |s: &mut Sampler| m.sample_flight(o, d, t_max, s);
            let what = |q: &str| format!("d = {}, σ_t = {sigma_t}: {q}", S::DIM);
            let pass_est = estimate_with(n, 3, 0, |s| match flight(s) {
                Flight::Pass { weight } => weight,
                Flight::Scatter { .. } => Rgb::ZERO,
            });
            let scatter_est = estimate_with(n, 3, 0, |s| match flight(s) {
                Flight::Scatter { t, weight } => {
                    assert!(m.contains(o + d * t), "scattered at t = {t}, outside the slabs");
                    weight
                }
                Flight::Pass { .. } => Rgb::ZERO,
            });
            let moment_est = estimate_with(n, 3, 0, |s| match flight(s) {
                Flight::Scatter { t, weight } => weight * t,
                Flight::Pass { .. } => Rgb::ZERO,
            });
            eprintln!(
                "{}: pass {} ± {} (T {pass}); scatter {} ± {} (want {scatter})",
                what("free flight"),
                pass_est.0,
                pass_est.1,
                scatter_est.0,
                scatter_est.1
            );
            assert_estimate(&what("pass weight"), pass_est, pass, 0.01);
            assert_estimate(&what("scatter weight"), scatter_est, scatter, 0.01);
            assert_estimate(&what("scatter weight × t"), moment_est, moment, 0.01);
        }
    }

    #[test]
    fn free_flight_is_unbiased_per_channel_2d() {
        free_flight_is_unbiased_per_channel::<D2>();
    }

    #[test]
    fn free_flight_is_unbiased_per_channel_3d() {
        free_flight_is_unbiased_per_channel::<D3>();
    }

    /// A channel that does not attenuate keeps transmittance one along an infinite
    /// ray; the others fall to zero.
    #[test]
    fn transmittance_along_an_infinite_ray() {
        let m = Medium::<D3, Slabs>::new(
            Rgb::new(0.0, 0.5, 0.0),
            Rgb::new(0.0, 0.0, 0.2),
            0.0,
            Slabs(vec![(-1.0, f64::INFINITY)]),
        );
        let t = m.transmittance(D3::zero(), oblique::<D3>(), f64::INFINITY);
        assert_eq!(t, Rgb::new(1.0, 0.0, 0.0));
    }
}
