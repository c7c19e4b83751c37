//! Homogeneous media in 3D, filling space or an axis-aligned box (index-matched).
//!
//! Scene parameters (`scene_desc::MediumDesc`): `sigma_a`, `sigma_s` (m⁻¹, RGB or
//! scalar), `g` (Henyey–Greenstein, in (−1, 1)), `region` ("everywhere" or a box).
//!
//! As in 2D (`flatland::medium`), one routine gives the piece of a ray inside the
//! region and both free-flight sampling and transmittance use it; chromatic media
//! draw one channel per flight and weight by the balance heuristic over channels.

use crate::core::color::Rgb;
use crate::core::phase::Hg3;
use crate::core::rng::Sampler;
use crate::core::transmittance::transmittance;
use glam::DVec3;

#[derive(Clone, Debug, PartialEq)]
pub enum Region {
    Everywhere,
    Box { min: DVec3, max: DVec3 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    pub sigma_a: Rgb,
    pub sigma_s: Rgb,
    pub sigma_t: Rgb,
    pub phase: Hg3,
    pub region: Region,
}

pub use crate::core::free_flight::Flight;

impl Medium {
    pub fn new(sigma_a: Rgb, sigma_s: Rgb, g: f64, region: Region) -> Self {
        let sigma_t = sigma_a + sigma_s;
        Medium {
            sigma_a,
            sigma_s,
            sigma_t,
            phase: Hg3::new(g),
            region,
        }
    }

    pub fn contains(&self, p: DVec3) -> bool {
        match self.region {
            Region::Everywhere => true,
            Region::Box { min, max } => p.cmpge(min).all() && p.cmple(max).all(),
        }
    }

    /// The piece [t0, t1] of o + t·d, 0 ≤ t ≤ t_max, inside the region (None if empty).
    #[inline]
    pub fn interval(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<(f64, f64)> {
        match self.region {
            Region::Everywhere => Some((0.0, t_max)),
            Region::Box { min, max } => {
                let (mut t0, mut t1) = (0.0f64, t_max);
                for k in 0..3 {
                    if d[k] == 0.0 {
                        // Parallel to this slab: inside it (closed) or never.
                        if o[k] < min[k] || o[k] > max[k] {
                            return None;
                        }
                        continue;
                    }
                    let (a, b) = ((min[k] - o[k]) / d[k], (max[k] - o[k]) / d[k]);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
                (t0 < t1).then_some((t0, t1))
            }
        }
    }

    pub fn length_inside(&self, o: DVec3, d: DVec3, t_max: f64) -> f64 {
        self.interval(o, d, t_max).map_or(0.0, |(a, b)| b - a)
    }

    pub fn transmittance(&self, o: DVec3, d: DVec3, t_max: f64) -> Rgb {
        transmittance(self.sigma_t, self.length_inside(o, d, t_max))
    }

    /// Sample the distance to the next real scattering event before `t_max`.
    pub fn sample_flight(&self, o: DVec3, d: DVec3, t_max: f64, s: &mut Sampler) -> Flight {
        crate::core::free_flight::sample_flight(self.sigma_t, self.sigma_s, self.interval(o, d, t_max), s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_interval() {
        let m = Medium::new(
            Rgb::ONE,
            Rgb::ONE,
            0.0,
            Region::Box {
                min: DVec3::ZERO,
                max: DVec3::splat(2.0),
            },
        );
        assert_eq!(m.interval(DVec3::new(-1.0, 1.0, 1.0), DVec3::X, 10.0), Some((1.0, 3.0)));
        assert_eq!(m.interval(DVec3::new(1.0, 1.0, 1.0), DVec3::X, 0.5), Some((0.0, 0.5)));
        assert_eq!(m.interval(DVec3::new(-1.0, 3.0, 1.0), DVec3::X, 10.0), None);
        // On a face, travelling along it: inside (closed box).
        assert_eq!(m.interval(DVec3::new(-1.0, 0.0, 1.0), DVec3::X, 10.0), Some((1.0, 3.0)));
    }

    /// Chromatic free flight: pass weights are unbiased for each channel.
    #[test]
    fn chromatic_free_flight_is_unbiased() {
        let sig_t = Rgb::new(0.5, 1.0, 3.0);
        let m = Medium::new(sig_t * 0.5, sig_t * 0.5, 0.0, Region::Everywhere);
        let mut s = Sampler::new(2, 0);
        let n = 400_000;
        let mut pass = Rgb::ZERO;
        for _ in 0..n {
            if let Flight::Pass { weight } = m.sample_flight(DVec3::ZERO, DVec3::X, 0.7, &mut s) {
                pass += weight;
            }
        }
        let (est, exact) = (pass / n as f64, transmittance(sig_t, 0.7));
        assert!((est - exact).abs().max_element() < 0.01, "{est} vs {exact}");
    }
}
