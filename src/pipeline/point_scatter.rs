//! The point lights' light scattered exactly once in the medium on its way to a
//! point x, sampled per point served instead of cached.
//!
//! Why: around a point light in fog, the light scattered twice before it reaches
//! the eye (once on the way to x, once at x) peaks as log(1/r) in 2D and 1/r in
//! 3D at distance r from the light. A record's Taylor expansion carries that peak
//! across the light, and records that crowd around it to follow it cost more than
//! path tracing's pixels (issue 16: `shaded_lamp.json`). Per point it is cheap
//! and well sampled: a few directions drawn from the phase at x, along each one
//! equiangular distance per light (density ∝ 1/r^{d−1}: `core::equiangular`) —
//! what is left to vary is the phase, visibility and transmittance. The records'
//! probes then leave the point lights' straight light out of their medium samples
//! (`path::PointLights::Left`), so that they hold the rest (light scattered three
//! times or more, or reflected on the way), which has no such peak.

use super::lobe::Lobe;
use super::medium::{Medium, Region as _};
use super::nee::point_lights;
use super::path::Sampling;
use super::world::{VecOf, World, ignore};
use crate::core::color::Rgb;
use crate::core::equiangular::Equiangular;
use crate::core::rng::Sampler;
use crate::core::space::Space;
use crate::core::transmittance::transmittance;
use smallvec::SmallVec;

/// ∫ σ_s T(o, o + t·d) f · (the point lights' straight light at o + t·d) dt over
/// the medium pieces of o + t·d, 0 ≤ t ≤ `s_max` (f scattering back towards o).
/// Per light, `n` stratified equiangular distances over the pieces' span (at
/// least one); zero without point lights or scattering.
pub fn point_lights_along<W: World>(
    world: &W,
    medium: &Medium<W::S, W::Region>,
    (origin, dir, s_max): (VecOf<W>, VecOf<W>, f64),
    n: u32,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    let lights = world.point_lights();
    if lights.is_empty() || medium.sigma_s == Rgb::ZERO {
        return Rgb::ZERO;
    }
    let pieces: SmallVec<[(f64, f64); 4]> = medium.region.pieces(origin, dir, s_max).into_iter().collect();
    let (Some(&(a, _)), Some(&(_, b))) = (pieces.first(), pieces.last()) else {
        return Rgb::ZERO;
    };
    if !(b > a && (b - a).is_finite()) {
        return Rgb::ZERO;
    }
    let depth = |t: f64| -> f64 { pieces.iter().map(|&(p, q)| (q.min(t) - p).max(0.0)).sum() };
    let inside = |t: f64| pieces.iter().any(|&(p, q)| p <= t && t <= q);
    let lobe = Lobe::Phase {
        phase: medium.phase,
        travel: dir,
    };
    let h_min = 1e-9 * world.scale();
    let n = n.max(1);
    let mut sum = Rgb::ZERO;
    for light in lights {
        let eq = Equiangular::towards::<W::S>((origin, dir), light.position, h_min, (a, b));
        let u0 = s.next_f64();
        for j in 0..n {
            let t = eq.sample((j as f64 + u0) / n as f64).clamp(a, b);
            if !inside(t) {
                continue;
            }
            let x = origin + dir * t;
            let lit = point_lights(world, std::slice::from_ref(light), x, &lobe, None, rays, &mut ignore);
            sum += medium.sigma_s * transmittance(medium.sigma_t, depth(t)) * lit / (eq.pdf(t) * n as f64);
        }
    }
    sum
}

/// The point lights' light scattered once in the medium and arriving at `x` from
/// the directions of `lobe` (at a medium point: its phase towards the eye), up to
/// the first surface: `n` lobe-sampled directions (one stratified set drawn from
/// stream (`seed`, `item`)), one equiangular distance per light along each. Not
/// multiplied by x's own σ_s. Zero without a medium or point lights.
pub fn once_scattered_point_lights<W: World>(
    world: &W,
    x: VecOf<W>,
    lobe: &Lobe<W::S>,
    n: u32,
    (seed, item): (u64, u64),
    rays: &mut u64,
) -> Rgb {
    let Some(medium) = world.medium() else {
        return Rgb::ZERO;
    };
    if world.point_lights().is_empty() || n == 0 {
        return Rgb::ZERO;
    }
    let mut sum = Rgb::ZERO;
    for k in 0..n {
        let mut s = Sampling::Stratified.stream(seed ^ POINT_SCATTER_STREAM, item, k as u64);
        let (w, weight, _) = lobe.sample(&mut s);
        if weight == Rgb::ZERO {
            continue;
        }
        *rays += 1;
        let s_max = world
            .closest_hit(x, w, f64::INFINITY, None)
            .map_or_else(|| world.world_exit(x, w), |h| h.t);
        sum += weight * point_lights_along(world, medium, (x, w, s_max), 1, &mut s, rays);
    }
    sum / n as f64
}

/// Salt of [`once_scattered_point_lights`]' streams: apart from the pixel's other
/// samples.
const POINT_SCATTER_STREAM: u64 = 0x0A5C_A77E_2D00_0001;

/// Radius around each point light within which a point served is path traced
/// whole ([`super::record::CacheSettings::near_light_paths`]): one mean free path
/// of the fog (its thinnest channel) where that is at most a tenth of the
/// scene's scale (fog at least ten mean free paths across), else zero, as
/// without scattering fog.
///
/// Why one mean free path: the light scattered twice or more still peaks as
/// log(1/r) (2D) around a point light, until the fog has attenuated the light's
/// own 1/r (2D) fall-off, about one mean free path out. Records there hold a
/// peak made of few, bright paths: their values are noisy (over record seeds the
/// error is almost all variance), and extents stretched along the peak's ridge
/// carry that noise across many pixels. Measured on `shaded_lamp.json` (128²,
/// budget 1, seed 1, 1,024 paths): 0.5 / 1 / 2 mean free paths gave RMSE 0.41 /
/// 0.25 / 0.25 (0.44 without). In thinner fog the light scattered twice is weak
/// against the once-scattered light sampled per pixel, and the records hold it
/// well: on `tests/budget_schedule.rs`' lamp beside two bars (4.2 mean free
/// paths across, 32², budget 1, seeds 1–4) 1,024 paths within 0.28 took the
/// mean squared error down 21% for 62% more rays (256: −7% for +15%), a loss
/// against path tracing's 1/rays.
pub fn near_light_radius<W: World>(world: &W) -> f64 {
    let Some(m) = world.medium().filter(|m| m.sigma_s != Rgb::ZERO) else {
        return 0.0;
    };
    let thinnest = m.sigma_t.x.min(m.sigma_t.y).min(m.sigma_t.z);
    let mean_free_path = 1.0 / thinnest;
    if mean_free_path <= 0.1 * world.scale() {
        mean_free_path
    } else {
        0.0
    }
}

/// Is `x` within `radius` of a point light?
pub fn near_a_point_light<W: World>(world: &W, x: VecOf<W>, radius: f64) -> bool {
    world.point_lights().iter().any(|l| {
        let d = l.position - x;
        <W::S as Space>::dot(d, d) < radius * radius
    })
}
