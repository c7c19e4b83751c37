//! Reference estimators: unidirectional volumetric path tracing, in any dimension.
//!
//! Quantities (theory.md §1–2) at a point x:
//! - in-scattered radiance L_s(x, ω_o) = σ_s ∫ f(−ω·ω_o) L_i(x, ω) dω, split into
//!   **direct** (delta lights at x), **single** (light arriving at x from surfaces
//!   and the sky: emitters seen directly and light reflected by surfaces) and
//!   **multiple** (light arriving at x from the medium itself);
//! - fluence φ(x) = ∫ L_i(x, ω) dω, split the same way;
//! - irradiance at a point of a virtual sensor with normal n, ∫ L_i max(0, n·ω) dω
//!   (reflected power; its mean over a sensor is [`super::sensor`]);
//! - the radiance L_i(x, ω) along one ray (camera pixels).
//!
//! Paths use free-flight sampling, NEE at every vertex (MIS with lobe sampling for
//! lights with an extent) and Russian roulette. Each sample draws from its own
//! stream derived from (seed, item, sample), so results do not depend on threads.

use super::dim::Dim;
use super::lamp_aim;
use super::lobe::{Lobe, phase_log_slope};
use super::medium::pass_probability;
use super::point_leg;
use super::world::{Hit, SurfacePoint, VecOf, World, ignore};
use crate::core::color::{Rgb, luminance};
use crate::core::free_flight::Flight;
use crate::core::mis::power_heuristic;
use crate::core::rng::Sampler;
use crate::core::space::Space;
use crate::progress::{Cancelled, Progress};
use serde::{Deserialize, Serialize};

/// Path-tracing settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Maximum number of path vertices after the start.
    pub max_depth: u32,
    /// Russian roulette starts at this vertex.
    pub rr_depth: u32,
    /// How a pixel's (or point's) samples draw their random numbers.
    #[serde(default)]
    pub sampling: Sampling,
    /// Sample point lights along every leg that passes near them, not only at the
    /// vertices (`super::point_leg`); off only to measure what it gains.
    #[serde(default = "yes")]
    pub point_legs: bool,
    /// At medium vertices near a point lamp, one extra leg aimed near it (3D,
    /// `super::lamp_aim`); off only to measure what it gains.
    #[serde(default = "yes")]
    pub aimed_legs: bool,
}

fn yes() -> bool {
    true
}

impl Settings {
    /// The settings of the light arriving at the `n`-th vertex after a path's start
    /// (1: its first scattering or surface point): the paths traced from there may
    /// add only `max_depth` − `n` vertices, so that an estimate assembled at that
    /// vertex (a camera ray's march point, a light field's medium sample or hit)
    /// traces no deeper than one path from the start. `max_depth` 0: the light
    /// straight at the vertex only ([`sample_at_each`]). Saturates: ask [`Self::reaches`]
    /// whether the vertex counts at all.
    pub fn past(self, n: u32) -> Settings {
        Settings {
            max_depth: self.max_depth.saturating_sub(n),
            ..self
        }
    }

    /// Whether a path from the start may hold an `n`-th vertex (n ≤ `max_depth`).
    pub fn reaches(&self, n: u32) -> bool {
        n <= self.max_depth
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            max_depth: 1024,
            rr_depth: 3,
            sampling: Sampling::default(),
            point_legs: true,
            aimed_legs: true,
        }
    }
}

/// How the samples of one estimate (a pixel, a point) draw their random numbers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// The samples are one stratified set: their first draws (the light sample,
    /// the lobe, the pixel position in 3D) are a padded Owen-scrambled Sobol'
    /// point set (pbrt-v4's default kind). Unbiased; its reported standard error
    /// is the independent samples' formula, an overestimate (the samples spread).
    #[default]
    Stratified,
    /// Every sample its own independent stream.
    Independent,
}

impl Settings {
    /// The random stream of sample `k` of item `item` (a pixel or point) seeded
    /// with `seed`.
    pub fn sample_stream(&self, seed: u64, item: u64, k: u64) -> Sampler {
        self.sampling.stream(seed, item, k)
    }
}

impl Sampling {
    /// The random stream of sample `k` of item `item` (a pixel or point) seeded
    /// with `seed`.
    pub fn stream(self, seed: u64, item: u64, k: u64) -> Sampler {
        match self {
            Sampling::Independent => Sampler::new2(seed, item, k),
            Sampling::Stratified => Sampler::stratified(
                crate::core::rng::mix64(seed ^ crate::core::rng::mix64(item ^ 0x57A7_1F1E)),
                k as u32,
            ),
        }
    }
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// In-scattered radiance L_s(x, ω_o) (the cached quantity).
    #[default]
    Ls,
    /// Fluence φ(x) = ∫ L_i dθ.
    Fluence,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    #[default]
    All,
    Direct,
    Single,
    Multiple,
}

/// A value split into the parts of theory.md §2.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Parts {
    pub direct: Rgb,
    pub single: Rgb,
    pub multiple: Rgb,
}

impl Parts {
    pub fn total(&self) -> Rgb {
        self.direct + self.single + self.multiple
    }

    pub fn scaled(self, k: Rgb) -> Parts {
        Parts {
            direct: self.direct * k,
            single: self.single * k,
            multiple: self.multiple * k,
        }
    }

    pub fn get(&self, part: Part) -> Rgb {
        match part {
            Part::All => self.total(),
            Part::Direct => self.direct,
            Part::Single => self.single,
            Part::Multiple => self.multiple,
        }
    }

    pub fn as_array(&self) -> [Rgb; 3] {
        [self.direct, self.single, self.multiple]
    }
}

/// What a path met first: this decides which part its light belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FirstEvent {
    Scatter,
    Surface,
    Escape,
}

/// Radiance arriving at `start` back along the ray start + t·dir, and what the path
/// met first. `skip` is the primitive `start` lies on; `lobe_pdf` the pdf with which
/// `dir` was sampled at a vertex that also did NEE with MIS (None for camera rays
/// and fixed directions).
#[allow(clippy::too_many_arguments)] // the path state is spelled out
pub fn radiance_path<W: World>(
    world: &W,
    start: VecOf<W>,
    dir: VecOf<W>,
    skip: Option<u32>,
    lobe_pdf: Option<f64>,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> (Rgb, FirstEvent) {
    let r = radiance_path_parts(world, start, dir, skip, lobe_pdf, settings, s, rays);
    (r.radiance, r.first)
}

/// What one path brought back (see [`radiance_path_parts`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathRadiance {
    pub radiance: Rgb,
    /// What the path met first.
    pub first: FirstEvent,
    /// The part of `radiance` that point lights sampled along the first leg
    /// brought: light scattered by the medium before the first event, even when
    /// that event is a surface or the path's escape.
    pub first_leg_scattered: Rgb,
}

impl PathRadiance {
    /// The light that the medium scattered towards the start (theory.md §2's
    /// multiple part when the start scatters itself).
    pub fn from_medium(&self) -> Rgb {
        if self.first == FirstEvent::Scatter {
            self.radiance
        } else {
            self.first_leg_scattered
        }
    }
}

/// [`radiance_path`], with the light scattered on the first leg apart.
#[allow(clippy::too_many_arguments)] // the path state is spelled out
pub fn radiance_path_parts<W: World>(
    world: &W,
    start: VecOf<W>,
    dir: VecOf<W>,
    skip: Option<u32>,
    lobe_pdf: Option<f64>,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> PathRadiance {
    radiance_path_shared(world, (start, dir, skip, lobe_pdf), None, settings, s, rays)
}

/// [`radiance_path_parts`] whose first leg estimates only `share` = (light, w) of
/// that point light's light scattered along it: an aimed leg from `start`
/// estimates the rest (`super::lamp_aim`).
fn radiance_path_shared<W: World>(
    world: &W,
    (start, dir, skip, lobe_pdf): (VecOf<W>, VecOf<W>, Option<u32>, Option<f64>),
    mut share: Option<(usize, f64)>,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> PathRadiance {
    let (mut p, mut dir, mut skip, mut pdf_prev) = (start, dir, skip, lobe_pdf);
    let mut beta = Rgb::ONE;
    let mut l = Rgb::ZERO;
    let mut first_leg_scattered = Rgb::ZERO;
    let mut first = None;
    let medium = world.medium();
    for depth in 1..=settings.max_depth {
        *rays += 1;
        let hit = world.closest_hit(p, dir, f64::INFINITY, skip);
        // An unbounded medium ends at the world sphere: paths leaving it escape, so a
        // thin non-absorbing fog cannot keep a path scattering far away forever.
        let s_max = hit.map_or_else(|| world.world_exit(p, dir), |h| h.t);
        // The lamp's light on this leg is shared with the aimed leg drawn at its
        // start, if one was.
        let leg = medium.map(|m| point_leg::leg(world, m, (p, dir, s_max), settings.point_legs).with_share(share));
        let mut aim = None;
        let flight = match (medium, &leg) {
            (Some(m), Some(leg)) => {
                if leg.samples_lights() {
                    let scattered = beta * leg.scattered(world, m, s, rays);
                    l += scattered;
                    if depth == 1 {
                        first_leg_scattered = scattered;
                    }
                }
                leg.flight(m, s)
            }
            _ => Flight::Pass { weight: Rgb::ONE },
        };
        let (lobe, leg_vertex) = match (flight, hit) {
            (Flight::Scatter { t, weight }, _) => {
                first.get_or_insert(FirstEvent::Scatter);
                beta *= weight;
                p += dir * t;
                skip = None;
                let m = medium.expect("scattering needs a medium");
                let lobe = Lobe::Phase {
                    phase: m.phase,
                    travel: dir,
                };
                if settings.aimed_legs {
                    aim = lamp_aim::aim(world, m, p);
                }
                (lobe, leg.filter(|l| l.gathers_apart()).map(|l| (l, t)))
            }
            (Flight::Pass { weight }, None) => {
                first.get_or_insert(FirstEvent::Escape);
                let pass = |pb: f64| pb * pass_probability(world.transmittance(p, dir, s_max));
                l += beta * weight * world.escaped(dir, pdf_prev.map(pass));
                break;
            }
            (Flight::Pass { weight }, Some(h)) => {
                first.get_or_insert(FirstEvent::Surface);
                beta *= weight;
                let sp = world.surface(&h, dir);
                if !sp.active {
                    break;
                }
                if sp.emission != Rgb::ZERO {
                    // The lobe strategy's density includes passing the medium (see nee).
                    let w = pdf_prev.map_or(1.0, |pb| {
                        let pass = pass_probability(world.transmittance(p, dir, h.t));
                        power_heuristic(pb * pass, world.emitter_pdf(p, h.prim, sp.point))
                    });
                    l += beta * sp.emission * w;
                }
                if sp.reflectance == Rgb::ZERO {
                    break;
                }
                p = sp.point;
                skip = Some(h.prim);
                let lobe = Lobe::Lambert {
                    normal: sp.normal,
                    reflectance: sp.reflectance,
                };
                (lobe, None)
            }
        };
        let last = depth == settings.max_depth;
        l += beta
            * match (leg_vertex, medium) {
                // The point lights' share at a vertex of a leg that also sampled them
                // is MIS-weighted against those samples.
                (Some((leg, t)), Some(m)) => {
                    leg.vertex_point_lights(world, m, (p, t), &lobe, rays)
                        + world.directional_lights_each(p, &lobe, skip, rays, &mut ignore)
                        + world.sampled_nee(p, &lobe, skip, !last, s, rays)
                }
                _ => world.nee(p, &lobe, skip, !last, s, rays),
            };
        if last {
            break;
        }
        let (w, weight, pdf) = lobe.sample(s);
        share = None;
        if let (Some(a), Some(m)) = (aim, medium) {
            l += beta * a.aimed_leg(world, m, (p, dir), s, rays).1;
            share = Some((a.light, a.path_share::<W::S>(&m.phase, dir, w)));
        }
        beta *= weight;
        dir = w;
        pdf_prev = Some(pdf);
        if depth >= settings.rr_depth && !crate::core::roulette::survives(&mut beta, s) {
            break;
        }
        if beta == Rgb::ZERO || !beta.is_finite() {
            break;
        }
    }
    PathRadiance {
        radiance: l,
        first: first.unwrap_or(FirstEvent::Escape),
        first_leg_scattered,
    }
}

/// One sample of ∫ value(ω) L_i(x, ω) dω at `x` for a lobe, times `prefactor`, in
/// parts: delta lights, NEE to lights with an extent and one lobe-sampled path
/// (MIS-combined). `skip` is the primitive `x` lies on, if any.
#[allow(clippy::too_many_arguments)] // the vertex state is spelled out
pub fn sample_at<W: World>(
    world: &W,
    x: VecOf<W>,
    lobe: &Lobe<W::S>,
    skip: Option<u32>,
    prefactor: Rgb,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> Parts {
    let (parts, _) = sample_at_each(
        world,
        x,
        lobe,
        skip,
        (1.0, PointLights::Included),
        settings,
        s,
        rays,
        &mut ignore,
    );
    parts.scaled(prefactor)
}

/// [`sample_at`] without the prefactor, showing its parts: `each` sees every light
/// sample's direction and share, and the lobe-sampled path comes back as its
/// direction and what it brought (weight · L), if the lobe drew one and the path
/// survived its roulette (probability `keep_path`, one draw only when it is below
/// one; what it brought is then divided by it). With `PointLights::Left` the point
/// lights' straight light at `x` is left out (the caller takes it elsewhere:
/// `super::point_scatter`); what the path brings is whole.
#[allow(clippy::too_many_arguments)] // the vertex state is spelled out
pub fn sample_at_each<W: World>(
    world: &W,
    x: VecOf<W>,
    lobe: &Lobe<W::S>,
    skip: Option<u32>,
    (keep_path, points): (f64, PointLights),
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
    each: &mut impl FnMut(VecOf<W>, Rgb),
) -> (Parts, Option<(VecOf<W>, Rgb)>) {
    let delta = match points {
        PointLights::Included => world.delta_lights_each(x, lobe, skip, rays, each),
        PointLights::Left => world.directional_lights_each(x, lobe, skip, rays, each),
    };
    // With no vertex left after `x`, no path follows: the lights' samples take
    // their whole share (no MIS against a lobe-sampled ray), as at a path's last
    // vertex, and no aimed leg scatters again.
    let path_follows = settings.max_depth > 0;
    let mut parts = Parts {
        direct: delta,
        single: world.sampled_nee_each(x, lobe, skip, path_follows, s, rays, each),
        multiple: Rgb::ZERO,
    };
    if !path_follows {
        return (parts, None);
    }
    let (w, mut weight, pdf) = lobe.sample(s);
    if weight == Rgb::ZERO {
        return (parts, None);
    }
    // A medium point near a lamp also aims a leg at it (`super::lamp_aim`); it is
    // light from the medium, seen by `each` like a light sample.
    let mut share = None;
    if let (Lobe::Phase { travel, phase }, Some(m), true) = (*lobe, world.medium(), settings.aimed_legs)
        && let Some(a) = lamp_aim::aim(world, m, x)
    {
        let (aimed_w, aimed) = a.aimed_leg(world, m, (x, travel), s, rays);
        if aimed != Rgb::ZERO {
            each(aimed_w, aimed);
            parts.multiple += aimed;
        }
        share = Some((a.light, a.path_share::<W::S>(&phase, travel, w)));
    }
    if keep_path < 1.0 {
        if s.next_f64() >= keep_path {
            return (parts, None);
        }
        weight /= keep_path;
    }
    let path = radiance_path_shared(world, (x, w, skip, Some(pdf)), share, settings, s, rays);
    let brought = weight * path.radiance;
    let from_medium = weight * path.from_medium();
    parts.multiple += from_medium;
    parts.single += brought - from_medium;
    (parts, Some((w, brought)))
}

/// The light a medium point `x` scatters back along −`travel` (one sample of
/// ∫ f(travel, ω) L_i(x, ω) dω, all parts, no σ_s) and its gradient with respect to
/// `travel` per channel, from the same sample: each light sample and the
/// lobe-sampled path weighted by its score ∇_travel ln f. The value is bit for bit
/// [`sample_at`]'s, and the gradient costs no ray.
///
/// Why: a probe's medium sample m is seen from x along ω = (m − x)/r, so what m sends
/// to x turns with x; holding it fixed leaves out ∫ K ∂_ωL·∇_x ω dm, which is
/// log-divergent near x (∇_x ω ∝ 1/r) wherever f ≠ const and the light at m is
/// anisotropic. `keep`: the lobe-sampled path's roulette and whether the point
/// lights' straight light counts ([`sample_at_each`]).
#[allow(clippy::too_many_arguments)] // the vertex state is spelled out
pub fn scattered_with_slope<W: World>(
    world: &W,
    x: VecOf<W>,
    phase: <W::S as Dim>::Phase,
    travel: VecOf<W>,
    (keep_path, points): (f64, PointLights),
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> ScatteredSample<VecOf<W>> {
    let lobe = Lobe::Phase { phase, travel };
    let mut slope = [W::S::zero(); 3];
    let mut tap = |w: VecOf<W>, l: Rgb| {
        let along = phase_log_slope::<W::S>(&phase, travel, w);
        for (c, v) in slope.iter_mut().zip([l.x, l.y, l.z]) {
            *c += along * v;
        }
    };
    let (parts, path) = sample_at_each(world, x, &lobe, None, (keep_path, points), settings, s, rays, &mut tap);
    let (score, path) = path.map_or((W::S::zero(), Rgb::ZERO), |(w, brought)| {
        (phase_log_slope::<W::S>(&phase, travel, w), brought)
    });
    ScatteredSample {
        value: parts.total(),
        slope,
        score,
        path,
        keep: keep_path.clamp(f64::MIN_POSITIVE, 1.0),
    }
}

/// One sample of [`scattered_with_slope`]: the value, and the direction gradient
/// `slope + score ⊗ (path − b)` for any baseline b that does not depend on this
/// sample's draws (E[score] = ∫∇f dω = 0 under phase sampling, so b changes only the
/// variance: the caller passes the mean of other samples' `path`).
#[derive(Clone, Copy, Debug)]
pub struct ScatteredSample<V> {
    pub value: Rgb,
    /// The NEE part of the gradient, per channel.
    pub slope: [V; 3],
    /// ∇ ln f at the lobe-sampled direction.
    pub score: V,
    /// What the lobe-sampled path brought (divided by its roulette's probability).
    pub path: Rgb,
    /// The probability with which the path was followed (one without roulette).
    pub keep: f64,
}

impl<V: Copy + std::ops::Mul<f64, Output = V> + std::ops::Add<Output = V>> ScatteredSample<V> {
    /// The gradient per channel with baseline `b` (an estimate of the path's
    /// mean): a followed path's score term is score·(path − b/q), the 1/q weight
    /// applied to the difference from the baseline and not to the path alone, so
    /// that the roulette does not undo the baseline (unbiased either way: the score's
    /// mean is zero).
    pub fn gradient(&self, b: Rgb) -> [V; 3] {
        let d = self.path - b / self.keep;
        let mut g = self.slope;
        for (c, v) in g.iter_mut().zip([d.x, d.y, d.z]) {
            *c = *c + self.score * v;
        }
        g
    }
}

/// The radiance leaving the surface point of `hit` back along `dir` (the ray that
/// found it): emission on an active side plus `paths` samples of the reflected
/// light (NEE and a BRDF-sampled path each); zero on the inactive back of a
/// one-sided surface.
#[allow(clippy::too_many_arguments)] // the vertex state is spelled out
pub fn radiance_leaving<W: World>(
    world: &W,
    hit: &Hit,
    dir: VecOf<W>,
    paths: u32,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> (SurfacePoint<W::S>, Rgb) {
    let sp = world.surface(hit, dir);
    if !sp.active {
        return (sp, Rgb::ZERO);
    }
    let mut l = sp.emission;
    if sp.reflectance != Rgb::ZERO {
        let lobe = Lobe::Lambert {
            normal: sp.normal,
            reflectance: sp.reflectance,
        };
        let paths = paths.max(1);
        let mut sum = Rgb::ZERO;
        for _ in 0..paths {
            sum += sample_at(world, sp.point, &lobe, Some(hit.prim), Rgb::ONE, settings, s, rays).total();
        }
        l += sum / paths as f64;
    }
    (sp, l)
}

/// One sample of the light arriving at `x` unscattered — from delta lights, from
/// lights with an extent by NEE, and along one lobe-sampled ray to the emitter or
/// sky it meets, MIS-combined as in [`sample_at`] and weighted by the ray's
/// transmittance (no free flight: nothing scattered is counted) — weighted by
/// `lobe`. The direct lighting a surface cache leaves to every pixel
/// (`super::surface_cache`); the rest of [`sample_at`]'s value is what its records
/// hold.
pub fn direct_at<W: World>(
    world: &W,
    x: VecOf<W>,
    lobe: &Lobe<W::S>,
    skip: Option<u32>,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    direct_at_with(world, x, lobe, skip, PointLights::Included, s, rays)
}

/// Whether a point's straight light includes the point lights' (a camera ray's
/// march leaves them to `volume::march_lights`, which samples them along the ray;
/// a 2D field's probes to `super::point_scatter`, which samples them per pixel).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PointLights {
    Included,
    Left,
}

/// [`direct_at`], with or without the point lights' light.
pub fn direct_at_with<W: World>(
    world: &W,
    x: VecOf<W>,
    lobe: &Lobe<W::S>,
    skip: Option<u32>,
    points: PointLights,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    let mut l = match points {
        PointLights::Included => world.nee(x, lobe, skip, true, s, rays),
        PointLights::Left => {
            world.directional_lights_each(x, lobe, skip, rays, &mut ignore)
                + world.sampled_nee(x, lobe, skip, true, s, rays)
        }
    };
    let (w, weight, pdf) = lobe.sample(s);
    if weight == Rgb::ZERO {
        return l;
    }
    *rays += 1;
    // The lobe strategy's MIS density includes passing the medium, as the path
    // tracer's (so the two weights still sum to one with NEE's).
    match world.closest_hit(x, w, f64::INFINITY, skip) {
        None => {
            let tr = world.transmittance(x, w, world.world_exit(x, w));
            l += weight * tr * world.escaped(w, Some(pdf * pass_probability(tr)));
        }
        Some(h) => {
            let sp = world.surface(&h, w);
            if sp.active && sp.emission != Rgb::ZERO {
                let tr = world.transmittance(x, w, h.t);
                let mis = power_heuristic(pdf * pass_probability(tr), world.emitter_pdf(x, h.prim, sp.point));
                l += weight * tr * sp.emission * mis;
            }
        }
    }
    l
}

/// `scale` × the mean of `n` (at least one) [`direct_at`] samples: the straight
/// light a point adds (`scale` = σ_s) when its records leave it out
/// (`CacheSettings::direct_samples`).
pub fn direct_mean<W: World>(
    world: &W,
    x: VecOf<W>,
    (lobe, scale): (&Lobe<W::S>, Rgb),
    n: u32,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    direct_spread(world, x, (lobe, scale), n, PointLights::Included, s, rays).0
}

/// What fewer samples of the straight light would have cost a point in variance:
/// for the blocks of a [`direct_spread`] set (n/4 and n/2 samples when n divides),
/// the added variance of one block's mean (luminance) instead of the set's mean.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DirectSpread {
    /// (block size, added variance) for n/4 and n/2; None where n does not divide.
    pub added: [Option<(u32, f64)>; 2],
}

/// [`direct_mean`] (`points`: with or without the point lights), and the added
/// variance of its set's aligned blocks of n/4 and n/2 samples. A block drawn at random is an estimator of that many samples
/// whose mean over blocks is the set's (the set is a scrambled Sobol' sequence,
/// whose aligned blocks are stratified alike): by the law of total variance it
/// adds the blocks' spread around the set's mean, measured here for free.
pub fn direct_spread<W: World>(
    world: &W,
    x: VecOf<W>,
    (lobe, scale): (&Lobe<W::S>, Rgb),
    n: u32,
    points: PointLights,
    s: &mut Sampler,
    rays: &mut u64,
) -> (Rgb, DirectSpread) {
    let n = n.max(1);
    // The n samples are one stratified set (their light and lobe draws spread
    // over the emitters' extent and the lobe): the visible part of an emitter is
    // a function with a few jumps, whose stratified estimate converges ~1/n.
    let set = s.next_u64();
    // Quarters (n divisible by 4) or halves (by 2) of the set, as block sums.
    let (quarters, halves) = (n.is_multiple_of(4), n.is_multiple_of(2));
    let mut blocks = [0.0f64; 4];
    let mut sum = Rgb::ZERO;
    for k in 0..n {
        let v = direct_at_with(world, x, lobe, None, points, &mut Sampler::stratified(set, k), rays);
        sum += v;
        if halves {
            let b = if quarters { 4 * k / n } else { 2 * (2 * k / n) };
            blocks[b as usize] += luminance(v * scale);
        }
    }
    let mean = sum * scale / n as f64;
    let mut spread = DirectSpread::default();
    if halves {
        let m = luminance(mean);
        let added = |sums: &[f64], size: u32| {
            sums.iter().map(|b| (b / size as f64 - m).powi(2)).sum::<f64>() / sums.len() as f64
        };
        if quarters {
            spread.added[0] = Some((n / 4, added(&blocks, n / 4)));
        }
        let half_sums = [blocks[0] + blocks[1], blocks[2] + blocks[3]];
        spread.added[1] = Some((n / 2, added(&half_sums, n / 2)));
    }
    (mean, spread)
}

/// What to estimate at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Query<S: Dim> {
    /// L_s(x, ω_o), zero outside the medium.
    InScattered {
        omega_o: S::Vec,
    },
    Fluence,
    /// ∫ L_i(x, ω) max(0, n·ω) dω on a virtual sensor with unit normal n.
    Irradiance {
        normal: S::Vec,
    },
}

impl<S: Dim> Query<S> {
    pub fn from_quantity(q: Quantity, omega_o: S::Vec) -> Self {
        match q {
            Quantity::Ls => Query::InScattered { omega_o },
            Quantity::Fluence => Query::Fluence,
        }
    }

    /// Is the query defined at `x`? (L_s needs a medium.)
    pub fn defined_at<W: World<S = S>>(&self, world: &W, x: S::Vec) -> bool {
        match self {
            Query::InScattered { .. } => world.medium_at(x).is_some(),
            _ => true,
        }
    }
}

/// One sample of the query at `x`.
pub fn sample_query<W: World>(
    world: &W,
    x: VecOf<W>,
    q: &Query<W::S>,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> Parts {
    match *q {
        Query::InScattered { omega_o } => match world.medium_at(x) {
            Some(m) => {
                let lobe = Lobe::Phase {
                    phase: m.phase,
                    travel: -omega_o,
                };
                sample_at(world, x, &lobe, None, m.sigma_s, settings, s, rays)
            }
            None => Parts::default(),
        },
        Query::Fluence => sample_at(world, x, &Lobe::Uniform, None, Rgb::ONE, settings, s, rays),
        Query::Irradiance { normal } => {
            // A Lambertian lobe of reflectance 1/(BRDF per unit ρ at cos = 1) has
            // value max(0, n·ω): the cosine-weighted integral.
            let lobe = Lobe::Lambert {
                normal,
                reflectance: Rgb::splat(1.0 / <W::S as Dim>::lambert(1.0)),
            };
            sample_at(world, x, &lobe, None, Rgb::ONE, settings, s, rays)
        }
    }
}

/// Mean and standard error of an estimate, per part and channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Estimate {
    pub mean: Parts,
    /// Per part; `std_error.total()` would only bound the total's.
    pub std_error: Parts,
    /// Of the total (the parts of one sample are correlated).
    pub total_std_error: Rgb,
    pub samples: u64,
    pub rays: u64,
}

/// Running sums for [`Estimate`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Accumulator {
    sum: [Rgb; 3],
    sum2: [Rgb; 3],
    total2: Rgb,
    n: u64,
    rays: u64,
}

impl Accumulator {
    pub fn push(&mut self, p: &Parts) {
        for (k, v) in p.as_array().into_iter().enumerate() {
            self.sum[k] += v;
            self.sum2[k] += v * v;
        }
        let t = p.total();
        self.total2 += t * t;
        self.n += 1;
    }

    pub fn add_rays(&mut self, r: u64) {
        self.rays += r;
    }

    /// Add another accumulator's samples (merge in a fixed order for results that
    /// do not depend on the thread count).
    pub fn merge(&mut self, o: &Accumulator) {
        for k in 0..3 {
            self.sum[k] += o.sum[k];
            self.sum2[k] += o.sum2[k];
        }
        self.total2 += o.total2;
        self.n += o.n;
        self.rays += o.rays;
    }

    pub fn estimate(&self) -> Estimate {
        let n = self.n.max(1) as f64;
        let mean = self.sum.map(|s| s / n);
        let se_of = |mean: Rgb, sum2: Rgb| {
            let var = (sum2 / n - mean * mean).max(Rgb::ZERO) * (n / (n - 1.0).max(1.0));
            (var / n).powf(0.5)
        };
        let se: [Rgb; 3] = std::array::from_fn(|k| se_of(mean[k], self.sum2[k]));
        let total_std_error = se_of(mean[0] + mean[1] + mean[2], self.total2);
        let parts = |v: [Rgb; 3]| Parts {
            direct: v[0],
            single: v[1],
            multiple: v[2],
        };
        Estimate {
            mean: parts(mean),
            std_error: parts(se),
            total_std_error,
            samples: self.n,
            rays: self.rays,
        }
    }
}

/// Estimate the query at `x` with `spp` samples; `item` selects the random streams
/// (e.g. the pixel index), so equal (seed, item) give identical results.
#[allow(clippy::too_many_arguments)] // the estimate's inputs are spelled out
pub fn estimate<W: World>(
    world: &W,
    x: VecOf<W>,
    q: &Query<W::S>,
    settings: &Settings,
    spp: u32,
    seed: u64,
    item: u64,
) -> Estimate {
    let never = Progress::new();
    match estimate_cancellable(world, x, q, settings, spp, (seed, item), &never) {
        Ok(e) => e,
        Err(Cancelled) => unreachable!("nobody holds the progress to cancel it"),
    }
}

/// [`estimate`], checking `progress` for cancellation every 1,024 samples: one
/// point may take a million paths (a pixel beside a lamp).
pub fn estimate_cancellable<W: World>(
    world: &W,
    x: VecOf<W>,
    q: &Query<W::S>,
    settings: &Settings,
    spp: u32,
    (seed, item): (u64, u64),
    progress: &Progress,
) -> Result<Estimate, Cancelled> {
    let mut acc = Accumulator::default();
    if !q.defined_at(world, x) {
        return Ok(acc.estimate());
    }
    let mut rays = 0;
    for k in 0..spp {
        if k % 1024 == 0 {
            progress.check()?;
        }
        let mut s = settings.sample_stream(seed, item, k as u64);
        acc.push(&sample_query(world, x, q, settings, &mut s, &mut rays));
    }
    acc.add_rays(rays);
    let mut e = acc.estimate();
    e.samples = spp as u64;
    Ok(e)
}

/// Mean and standard error per channel of `n` samples of `f(sampler)`, each with
/// its stream (seed, item, k).
pub fn estimate_with(n: u64, seed: u64, item: u64, mut f: impl FnMut(&mut Sampler) -> Rgb) -> (Rgb, Rgb) {
    let mut acc = Accumulator::default();
    for k in 0..n {
        acc.push(&Parts {
            direct: f(&mut Sampler::new2(seed, item, k)),
            ..Default::default()
        });
    }
    let e = acc.estimate();
    (e.mean.direct, e.std_error.direct)
}

/// Estimate the radiance L_i(x, ω) arriving at `x` from the unit direction `w`:
/// (mean, standard error).
pub fn estimate_radiance<W: World>(
    world: &W,
    x: VecOf<W>,
    w: VecOf<W>,
    settings: &Settings,
    spp: u32,
    seed: u64,
) -> (Rgb, Rgb) {
    let mut rays = 0;
    estimate_with(spp as u64, seed, 0, |s| {
        radiance_path(world, x, w, None, None, settings, s, &mut rays).0
    })
}

#[cfg(test)]
mod tests {
    use super::Settings;

    /// A vertex n after the start leaves max_depth − n vertices to its paths, none
    /// below zero, and counts only while n ≤ max_depth.
    #[test]
    fn vertices_past_the_start_leave_the_rest_of_the_depth() {
        let s = Settings {
            max_depth: 2,
            ..Settings::default()
        };
        assert_eq!(s.past(1).max_depth, 1);
        assert_eq!(s.past(2).max_depth, 0);
        assert_eq!(s.past(3).max_depth, 0);
        assert_eq!(s.past(1).rr_depth, s.rr_depth, "only the depth changes");
        assert!(s.reaches(2) && !s.reaches(3));
    }
}
