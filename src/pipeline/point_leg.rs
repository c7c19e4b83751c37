//! Point lights sampled along a path's legs, not only at its vertices.
//!
//! Why: a point light in fog lights a medium point at distance r with I·T/r^{d−1},
//! and free-flight vertices that land near it bring that peak into the estimate
//! with infinite variance (2D: ∫ (1/r)² r dr diverges logarithmically, 3D
//! linearly); a record or pixel that draws one carries a spike. Deep in fog free
//! flight also seldom reaches the stretch of a long leg that passes near a light.
//! Along each leg that passes within a mean free path of a light (at most a tenth
//! of the scene), or (3D) within three beyond its first mean free path, one
//! equiangular distance per light (`core::equiangular`, density ∝ 1/r^{d−1})
//! estimates the light scattered on that leg, and the free-flight vertex's own
//! estimate of that light is kept too: the two are combined by the power heuristic
//! (Kulla and Fajardo 2012), so neither strategy's weak region dominates. Legs far
//! from every light draw nothing extra (scenes without point lights draw the same
//! random numbers as before).

use super::dim::Dim;
use super::lobe::Lobe;
use super::medium::Medium;
use super::nee::point_lights;
use super::world::{VecOf, World, ignore};
use crate::core::color::Rgb;
use crate::core::equiangular::Equiangular;
use crate::core::free_flight::{Flight, sample_flight};
use crate::core::mis::power_heuristic;
use crate::core::rng::Sampler;
use crate::core::space::Space;
use crate::core::transmittance::transmittance;
use smallvec::SmallVec;

/// A leg that passes within this many mean free paths of a lamp, more than one mean
/// free path from its start, samples the lamp along it: free flight seldom gets
/// that far (e^{−σt}), and the lamp's light there, dimmed by less than e^−3, is what
/// a point many mean free paths from the lamp mostly receives (`tests/lamp_aim.rs`,
/// the far point: 7–28% low at up to 9 standard errors without). 3D only, so far:
/// in 2D a cached field of a lamp in fog (`tests/gradient_noise.rs`) came out
/// 10–20% higher in RMSE with it (against its own reference, seeds 1–3), which is
/// not yet understood; 2D keeps the legs within a mean free path.
const FAR_MEAN_FREE_PATHS: f64 = 3.0;

/// How near a leg must pass a light to sample it for the light's peak: a mean free
/// path, at most a tenth of the scene (also the reach of `super::lamp_aim`'s cones).
pub fn near_reach<W: World>(world: &W, medium: &Medium<W::S, W::Region>) -> f64 {
    let mean_sigma = crate::core::color::average(medium.sigma_t);
    (1.0 / mean_sigma).min(0.1 * world.scale())
}

/// The medium pieces of o + t·d, 0 ≤ t ≤ `s_max`, and their span (first start, last
/// end), if any.
#[allow(clippy::type_complexity)]
fn medium_pieces<S: Dim, R: super::medium::Region<S>>(
    medium: &Medium<S, R>,
    (origin, dir, s_max): (S::Vec, S::Vec, f64),
) -> (SmallVec<[(f64, f64); 4]>, Option<(f64, f64)>) {
    let pieces: SmallVec<[(f64, f64); 4]> = medium.region.pieces(origin, dir, s_max).into_iter().collect();
    let span = pieces.first().zip(pieces.last()).map(|(&(a, _), &(_, b))| (a, b));
    (pieces, span)
}

/// One leg o + t·d of a path up to its next surface (or the world's exit): its
/// medium pieces and the point lights it passes near.
pub struct Leg<S: Dim> {
    origin: S::Vec,
    dir: S::Vec,
    pieces: SmallVec<[(f64, f64); 4]>,
    /// (index into the world's point lights, the leg's distribution towards it).
    near: SmallVec<[(usize, Equiangular); 2]>,
    /// Whether free flight along the leg also gathers the lights (its vertex's NEE):
    /// then the equiangular samples are MIS-weighted against it.
    with_flight: bool,
    /// (a light, the share of its light on this leg that the leg estimates): the
    /// rest is estimated by aimed legs (`super::lamp_aim`).
    share: Option<(usize, f64)>,
}

/// The leg o + t·d, 0 ≤ t ≤ `s_max`, through `medium`; lights are sampled along it
/// only with `sample_lights` (`Settings::point_legs`).
pub fn leg<W: World>(
    world: &W,
    medium: &Medium<W::S, W::Region>,
    (origin, dir, s_max): (VecOf<W>, VecOf<W>, f64),
    sample_lights: bool,
) -> Leg<W::S> {
    let (pieces, span) = medium_pieces(medium, (origin, dir, s_max));
    let mut near = SmallVec::new();
    if let Some((a, b)) =
        span.filter(|&(a, b)| sample_lights && medium.sigma_s != Rgb::ZERO && (b - a).is_finite() && b > a)
    {
        let mean_sigma = crate::core::color::average(medium.sigma_t);
        let reach = near_reach(world, medium);
        let h_min = 1e-9 * world.scale();
        for (k, light) in world.point_lights().iter().enumerate() {
            let t0 = W::S::dot(light.position - origin, dir).clamp(a, b);
            let h = W::S::length(light.position - (origin + dir * t0));
            let beyond_flight = W::S::DIM == 3 && t0 * mean_sigma > 1.0 && h * mean_sigma < FAR_MEAN_FREE_PATHS;
            if h < reach || beyond_flight {
                near.push((
                    k,
                    Equiangular::towards::<W::S>((origin, dir), light.position, h_min, (a, b)),
                ));
            }
        }
    }
    Leg {
        origin,
        dir,
        pieces,
        near,
        with_flight: true,
        share: None,
    }
}

/// A leg o + t·d, 0 ≤ t ≤ `s_max`, that gathers only light `k`'s light scattered
/// along it, by one equiangular sample, wherever the lamp lies (no free flight:
/// `super::lamp_aim`'s aimed legs). Surfaces are not looked for up front: the
/// sample's own point is tested for being seen from o (one any-hit ray, where a
/// closest hit would cost more and serve no other sample).
pub fn leg_towards<W: World>(
    world: &W,
    medium: &Medium<W::S, W::Region>,
    (origin, dir, s_max): (VecOf<W>, VecOf<W>, f64),
    k: usize,
) -> Leg<W::S> {
    let (pieces, span) = medium_pieces(medium, (origin, dir, s_max));
    let mut near = SmallVec::new();
    if let Some((a, b)) = span.filter(|&(a, b)| (b - a).is_finite() && b > a) {
        let position = world.point_lights()[k].position;
        let h_min = 1e-9 * world.scale();
        near.push((k, Equiangular::towards::<W::S>((origin, dir), position, h_min, (a, b))));
    }
    Leg {
        origin,
        dir,
        pieces,
        near,
        with_flight: false,
        share: None,
    }
}

impl<S: Dim> Leg<S> {
    /// Free flight along the leg (`core::free_flight` on its pieces).
    pub fn flight<R>(&self, medium: &Medium<S, R>, s: &mut Sampler) -> Flight {
        sample_flight(medium.sigma_t, medium.sigma_s, self.pieces.iter().copied(), s)
    }

    /// Does the leg sample any light?
    pub fn samples_lights(&self) -> bool {
        !self.near.is_empty()
    }

    /// Does the leg gather any light apart from its vertex's plain NEE (samples
    /// along it, or a share left to aimed legs)?
    pub fn gathers_apart(&self) -> bool {
        !self.near.is_empty() || self.share.is_some()
    }

    /// The leg estimates only `share` of light `k`'s light scattered along it
    /// (both its equiangular samples and its free-flight vertex's NEE).
    pub fn with_share(mut self, share: Option<(usize, f64)>) -> Self {
        self.share = share;
        self
    }

    /// The factor on light `k`'s light gathered along the leg.
    fn share_of(&self, k: usize) -> f64 {
        match self.share {
            Some((j, w)) if j == k => w,
            _ => 1.0,
        }
    }

    /// The medium length of the leg before distance `t`.
    fn depth(&self, t: f64) -> f64 {
        self.pieces.iter().map(|&(a, b)| (b.min(t) - a).max(0.0)).sum()
    }

    /// Is distance `t` inside one of the leg's medium pieces?
    fn inside(&self, t: f64) -> bool {
        self.pieces.iter().any(|&(a, b)| a <= t && t <= b)
    }

    /// The density with which free flight scatters at `t` (a medium point): one
    /// channel drawn uniformly, then its exponential depth.
    fn flight_pdf(&self, sigma_t: Rgb, t: f64) -> f64 {
        (sigma_t * transmittance(sigma_t, self.depth(t))).element_sum() / 3.0
    }

    /// One equiangular sample per near light of the light scattered towards the
    /// leg's origin along it — σ_s T(0, t) f · (light at t) / pdf — each weighted by
    /// the power heuristic against free flight (to multiply by the throughput at the
    /// leg's start).
    pub fn scattered<W: World<S = S>>(
        &self,
        world: &W,
        medium: &Medium<S, W::Region>,
        s: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        let lobe = Lobe::Phase {
            phase: medium.phase,
            travel: self.dir,
        };
        let mut sum = Rgb::ZERO;
        for &(k, eq) in &self.near {
            let t = eq.sample(s.next_f64());
            if !self.inside(t) {
                continue;
            }
            let pdf = eq.pdf(t);
            let weight = if self.with_flight {
                power_heuristic(pdf, self.flight_pdf(medium.sigma_t, t))
            } else {
                1.0
            } * self.share_of(k);
            // An aimed leg runs to the world's exit: a surface before t ends it.
            if !self.with_flight {
                *rays += 1;
                if world.occluded(self.origin, self.dir, t, None) {
                    continue;
                }
            }
            let x = self.origin + self.dir * t;
            let light = std::slice::from_ref(&world.point_lights()[k]);
            let lit = point_lights(world, light, x, &lobe, None, rays, &mut ignore);
            sum += medium.sigma_s * transmittance(medium.sigma_t, self.depth(t)) * lit * (weight / pdf);
        }
        sum
    }

    /// The point lights' light at the free-flight vertex `x` at distance `t` of the
    /// leg, weighted by `lobe`, each near light's share weighted by the power
    /// heuristic against its equiangular samples.
    pub fn vertex_point_lights<W: World<S = S>>(
        &self,
        world: &W,
        medium: &Medium<S, W::Region>,
        (x, t): (S::Vec, f64),
        lobe: &Lobe<S>,
        rays: &mut u64,
    ) -> Rgb {
        let flight_pdf = self.flight_pdf(medium.sigma_t, t);
        let mut sum = Rgb::ZERO;
        for (k, light) in world.point_lights().iter().enumerate() {
            let lit = point_lights(world, std::slice::from_ref(light), x, lobe, None, rays, &mut ignore);
            let weight = match self.near.iter().find(|(j, _)| *j == k) {
                Some((_, eq)) => power_heuristic(flight_pdf, eq.pdf(t)),
                None => 1.0,
            };
            sum += lit * (weight * self.share_of(k));
        }
        sum
    }
}
