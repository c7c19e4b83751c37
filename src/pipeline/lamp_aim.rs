//! Legs aimed near point lamps: at a medium vertex near a lamp, one extra leg drawn
//! in a cone around the lamp gathers the lamp's light scattered along it, combined
//! (power heuristic over directions) with what the path's own next leg gathers.
//!
//! Why: a path leg that passes at distance h from a point lamp in fog brings light
//! ∝ I/h in 3D, even with the lamp sampled along the leg (`super::point_leg`),
//! while phase sampling draws such legs with a probability ∝ h²: the second moment
//! ∫ (1/h)² h dh diverges logarithmically. Deep in fog this heavy tail is what a
//! record or pixel catches as a spike (README, "Where the 3D cache fails"). A cone
//! around the lamp with the angle θ to it uniform (a density ∝ 1/θ ∝ 1/h) bounds
//! that moment.
//!
//! Why an extra leg and not a mixture for the path's direction: the mixture's
//! weight f/p is 1/(1 − share) wherever the cone is not, and a path deep in fog
//! scatters dozens of times near the lamp; its throughput's second moment grows as
//! (1/(1 − share))^k (measured: max/mean 10⁵ instead of 10⁴ for one sample of a
//! point's light at g = −0.9, albedo 0.94). The path here keeps the phase's
//! directions and weights; only the lamp's once-scattered light on its next leg is
//! shared between the two legs, each estimating it whole for its own directions.
//!
//! 2D has no such tail (the leg brings ∝ log(1/h), square-integrable): nothing is
//! aimed there.

use super::dim::Dim;
use super::medium::Medium;
use super::point_leg;
use super::world::{VecOf, World};
use crate::core::color::{Rgb, luminance};
use crate::core::mis::power_heuristic;
use crate::core::rng::Sampler;
use crate::core::space::Space;
use std::f64::consts::FRAC_PI_2;

/// Lamps farther than this many mean free paths are not aimed at: their light,
/// and any spike it brings, is dimmed by at least e^−3 against the diffuse light
/// that has travelled as far.
const NEAR_MEAN_FREE_PATHS: f64 = 3.0;

/// The cone towards one lamp from a medium vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aim<V> {
    /// The lamp (index into the world's point lights).
    pub light: usize,
    /// Unit direction towards it.
    pub axis: V,
    /// The cone's half-angle: the legs it draws pass within `point_leg`'s reach of
    /// the lamp (the half-space towards it when the vertex is that close).
    pub theta_max: f64,
}

/// The lamp whose unshadowed straight light at medium point `x` is strongest,
/// if one is within [`NEAR_MEAN_FREE_PATHS`] (3D only).
pub fn aim<W: World>(world: &W, medium: &Medium<W::S, W::Region>, x: VecOf<W>) -> Option<Aim<VecOf<W>>> {
    if W::S::DIM != 3 || medium.sigma_s == Rgb::ZERO || world.point_lights().is_empty() {
        return None;
    }
    let mean_sigma = crate::core::color::average(medium.sigma_t);
    let reach = point_leg::near_reach(world, medium);
    let d_min = 1e-9 * world.scale();
    let mut best: Option<(f64, Aim<VecOf<W>>, f64)> = None;
    for (light, lamp) in world.point_lights().iter().enumerate() {
        let to = lamp.position - x;
        let d = W::S::length(to);
        let strength = luminance(lamp.intensity);
        if !(d > d_min && d * mean_sigma < NEAR_MEAN_FREE_PATHS && strength > 0.0) {
            continue;
        }
        let rank = strength * (-mean_sigma * d).exp() / (d * d);
        if best.as_ref().is_none_or(|(r, _, _)| rank > *r) {
            let axis = to * (1.0 / d);
            let theta_max = if d <= reach { FRAC_PI_2 } else { (reach / d).asin() };
            best = Some((rank, Aim { light, axis, theta_max }, d));
        }
    }
    best.map(|(_, a, _)| a)
}

impl<V: Copy> Aim<V> {
    /// The share of the lamp's light on a phase-sampled leg along `w` that the
    /// path's own leg keeps (the power heuristic against the cone).
    pub fn path_share<S: Dim<Vec = V>>(&self, phase: &S::Phase, travel: V, w: V) -> f64 {
        let cone = S::cone_pdf(self.axis, self.theta_max, w);
        if cone == 0.0 {
            return 1.0;
        }
        power_heuristic(S::phase_eval(phase, travel, w), cone)
    }

    /// One aimed leg from `x` (the path arrived along `travel`): its direction and
    /// the lamp's light scattered along it towards `x`, times f/pdf and the leg's
    /// share, to be multiplied by the throughput at `x`.
    pub fn aimed_leg<W: World<S: Dim<Vec = V>>>(
        &self,
        world: &W,
        medium: &Medium<W::S, W::Region>,
        (x, travel): (V, V),
        s: &mut Sampler,
        rays: &mut u64,
    ) -> (V, Rgb) {
        let w = W::S::sample_cone(self.axis, self.theta_max, s);
        let cone = W::S::cone_pdf(self.axis, self.theta_max, w);
        let f = W::S::phase_eval(&medium.phase, travel, w);
        if f == 0.0 || cone == 0.0 {
            return (w, Rgb::ZERO);
        }
        let leg = point_leg::leg_towards(world, medium, (x, w, world.world_exit(x, w)), self.light);
        let share = power_heuristic(cone, f);
        (w, leg.scattered(world, medium, s, rays) * (f / cone * share))
    }
}

#[cfg(test)]
mod tests {
    use crate::core::color::Rgb;
    use crate::core::space::{D2, D3};
    use crate::pipeline::dim::Dim;
    use crate::pipeline::path::estimate_with;
    use std::f64::consts::{PI, TAU};

    /// `Dim::sample_cone` and `Dim::cone_pdf` agree: over cone samples, 1/pdf
    /// estimates the cone's measure (2θ, 2π(1 − cos θ)) and (ω·axis)/pdf its
    /// ∫cosθ dω (2 sin θ, π sin²θ), for cones from narrow to the half-space about
    /// random axes; samples stay in the cone and outside it the pdf is zero.
    fn cone_sampling_matches_its_pdf<S: Dim>() {
        for (k, theta_max) in [1e-3, 0.1, 0.7, PI / 2.0].into_iter().enumerate() {
            let (measure, cosine) = if S::DIM == 2 {
                (2.0 * theta_max, 2.0 * theta_max.sin())
            } else {
                (TAU * (1.0 - theta_max.cos()), PI * theta_max.sin().powi(2))
            };
            let (mean, se) = estimate_with(100_000, 5, k as u64, |s| {
                let axis = S::sample_uniform(s);
                let w = S::sample_cone(axis, theta_max, s);
                let pdf = S::cone_pdf(axis, theta_max, w);
                assert!((S::length(w) - 1.0).abs() < 1e-12);
                assert!(pdf > 0.0, "a sample outside its cone");
                assert_eq!(S::cone_pdf(axis, theta_max, -axis), 0.0);
                Rgb::new(1.0 / pdf, S::dot(w, axis) / pdf, 0.0)
            });
            eprintln!(
                "d = {}, θ_max = {theta_max}: measure {:.6} ± {:.6} (want {measure:.6}), cosine {:.6} ± {:.6} (want {cosine:.6})",
                S::DIM,
                mean.x,
                se.x,
                mean.y,
                se.y
            );
            for (got, err, want) in [(mean.x, se.x, measure), (mean.y, se.y, cosine)] {
                assert!((got - want).abs() <= 4.0 * err + 1e-9 * want, "{got} ± {err} vs {want}");
                assert!(err <= 0.01 * want, "standard error {err} of {want}");
            }
        }
    }

    #[test]
    fn cone_sampling_matches_its_pdf_on_the_circle() {
        cone_sampling_matches_its_pdf::<D2>();
    }

    #[test]
    fn cone_sampling_matches_its_pdf_on_the_sphere() {
        cone_sampling_matches_its_pdf::<D3>();
    }
}
