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
