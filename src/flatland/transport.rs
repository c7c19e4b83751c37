//! Reference estimators (unidirectional volumetric path tracing in flatland).
//!
//! Quantities (theory.md §1–2), at a point x:
//! - in-scattered radiance L_s(x, ω_o) = σ_s ∫ f(−ω·ω_o) L_i(x, ω) dω, split into
//!   **direct** (point and collimated lights at x), **single** (light arriving at x
//!   from surfaces: emitters seen directly and light reflected by surfaces) and
//!   **multiple** (light arriving at x from the medium itself);
//! - fluence φ(x) = ∫ L_i(x, ω) dω, split the same way;
//! - irradiance on a (virtual) sensor with normal n, ∫ L_i cos dω, used to measure
//!   reflected power;
//! - radiance L_i(x, ω) along one ray.
//!
//! Paths use free-flight sampling, NEE to every light (MIS with lobe sampling for
//! emitting segments), and Russian roulette. Each sample draws from its own stream
//! derived from (seed, item, sample), so results do not depend on threads.

use super::lights::{Lobe, direct_lights, emitter_nee, emitter_pdf, power_heuristic};
use super::medium::Flight;
use super::scene::Scene;
use super::scene_desc::{Part, Quantity};
use crate::core::color::Rgb;
use crate::core::rng::Sampler;
use glam::DVec2;
use serde::Serialize;

/// Path-tracing settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Settings {
    /// Maximum number of path vertices after the query point.
    pub max_depth: u32,
    /// Russian roulette starts at this vertex.
    pub rr_depth: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            max_depth: 1024,
            rr_depth: 3,
        }
    }
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

    pub fn get(&self, part: Part) -> Rgb {
        match part {
            Part::All => self.total(),
            Part::Direct => self.direct,
            Part::Single => self.single,
            Part::Multiple => self.multiple,
        }
    }

    fn scaled(self, k: Rgb) -> Parts {
        Parts {
            direct: self.direct * k,
            single: self.single * k,
            multiple: self.multiple * k,
        }
    }
}

/// What a path met first: this decides which part its light belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FirstEvent {
    Scatter,
    Surface,
    Escape,
}

/// Radiance arriving at `p` from direction `dir`, by a path starting with the ray
/// p + t·dir. `lobe_pdf` is the pdf with which `dir` was sampled at `p` where `p`
/// also did emitter NEE with MIS (None: no MIS, e.g. a fixed direction).
#[allow(clippy::too_many_arguments)] // the path state is spelled out; bundling it hides nothing
pub fn radiance_path(
    scene: &Scene,
    start: DVec2,
    dir: DVec2,
    skip: Option<u32>,
    lobe_pdf: Option<f64>,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> (Rgb, FirstEvent) {
    let (mut p, mut dir, mut skip, mut pdf_prev) = (start, dir, skip, lobe_pdf);
    let mut beta = Rgb::ONE;
    let mut l = Rgb::ZERO;
    let mut first = None;
    for depth in 1..=settings.max_depth {
        *rays += 1;
        let hit = scene.geometry.closest_hit(p, dir, f64::INFINITY, skip);
        // An unbounded medium ends at the world disc: paths leaving it escape, so a
        // thin non-absorbing fog cannot keep a path scattering far away forever.
        let s_max = hit.map_or_else(|| scene.world_exit(p, dir), |h| h.t);
        let flight = match &scene.medium {
            Some(m) => m.sample_flight(p, dir, s_max, s),
            None => Flight::Pass { weight: Rgb::ONE },
        };
        let last = depth == settings.max_depth;
        let lobe = match flight {
            Flight::Scatter { t, weight } => {
                first.get_or_insert(FirstEvent::Scatter);
                beta *= weight;
                p += dir * t;
                skip = None;
                let m = scene.medium.as_ref().expect("scattering needs a medium");
                Lobe::Phase {
                    hg: m.phase,
                    travel: dir,
                }
            }
            Flight::Pass { weight } => {
                beta *= weight;
                let Some(h) = hit else {
                    first.get_or_insert(FirstEvent::Escape);
                    break;
                };
                first.get_or_insert(FirstEvent::Surface);
                let seg = &scene.geometry.segments[h.segment as usize];
                let (normal, active) = seg.facing_dir(dir);
                if !active {
                    break;
                }
                if seg.is_emitter() {
                    let w = pdf_prev.map_or(1.0, |pb| power_heuristic(pb, emitter_pdf(scene, p, h.segment)));
                    l += beta * seg.emission * w;
                }
                if seg.reflectance == Rgb::ZERO {
                    break;
                }
                p = seg.point_at(h.u);
                skip = Some(h.segment);
                Lobe::Lambert {
                    normal,
                    reflectance: seg.reflectance,
                }
            }
        };
        l += beta * (direct_lights(scene, p, &lobe, skip, rays) + emitter_nee(scene, p, &lobe, skip, !last, s, rays));
        if last {
            break;
        }
        let (w, weight, pdf) = lobe.sample(s);
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
    (l, first.unwrap_or(FirstEvent::Escape))
}

/// One sample of ∫ value(ω) L_i(x, ω) dω at `x` for a lobe, times `prefactor`, in
/// parts. `skip` is the segment `x` lies on, if any.
#[allow(clippy::too_many_arguments)] // the vertex state is spelled out
pub fn sample_at(
    scene: &Scene,
    x: DVec2,
    lobe: &Lobe,
    skip: Option<u32>,
    prefactor: Rgb,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> Parts {
    let mut parts = Parts {
        direct: direct_lights(scene, x, lobe, skip, rays),
        single: emitter_nee(scene, x, lobe, skip, true, s, rays),
        multiple: Rgb::ZERO,
    };
    let (w, weight, pdf) = lobe.sample(s);
    let (l, first) = radiance_path(scene, x, w, skip, Some(pdf), settings, s, rays);
    match first {
        FirstEvent::Scatter => parts.multiple += weight * l,
        FirstEvent::Surface => parts.single += weight * l,
        FirstEvent::Escape => {}
    }
    parts.scaled(prefactor)
}

/// One sample of the radiance reflected by segment `seg` at its point `p` towards
/// the side with unit normal `normal` (emission not included).
pub fn sample_reflected(
    scene: &Scene,
    p: DVec2,
    seg: u32,
    normal: DVec2,
    settings: &Settings,
    s: &mut Sampler,
    rays: &mut u64,
) -> Rgb {
    let reflectance = scene.geometry.segments[seg as usize].reflectance;
    if reflectance == Rgb::ZERO {
        return Rgb::ZERO;
    }
    let lobe = Lobe::Lambert { normal, reflectance };
    sample_at(scene, p, &lobe, Some(seg), Rgb::ONE, settings, s, rays).total()
}

/// What to estimate at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Query {
    /// L_s(x, ω_o), zero outside the medium.
    InScattered {
        omega_o: DVec2,
    },
    Fluence,
    /// ∫ L_i(x, ω) max(0, n·ω) dω on a virtual sensor with unit normal n.
    Irradiance {
        normal: DVec2,
    },
}

impl Query {
    pub fn from_quantity(q: Quantity, omega_o: DVec2) -> Query {
        match q {
            Quantity::Ls => Query::InScattered { omega_o },
            Quantity::Fluence => Query::Fluence,
        }
    }

    /// Is the query defined at `x`? (L_s needs a medium.)
    pub fn defined_at(&self, scene: &Scene, x: DVec2) -> bool {
        match self {
            Query::InScattered { .. } => scene.medium_at(x).is_some(),
            _ => true,
        }
    }
}

/// One sample of the query at `x`.
pub fn sample_query(scene: &Scene, x: DVec2, q: &Query, settings: &Settings, s: &mut Sampler, rays: &mut u64) -> Parts {
    match *q {
        Query::InScattered { omega_o } => match scene.medium_at(x) {
            Some(m) => {
                let lobe = Lobe::Phase {
                    hg: m.phase,
                    travel: -omega_o,
                };
                sample_at(scene, x, &lobe, None, m.sigma_s, settings, s, rays)
            }
            None => Parts::default(),
        },
        Query::Fluence => sample_at(scene, x, &Lobe::Uniform, None, Rgb::ONE, settings, s, rays),
        Query::Irradiance { normal } => {
            // Lambert with ρ = 2 has value max(0, n·ω): the cosine-weighted integral.
            let lobe = Lobe::Lambert {
                normal,
                reflectance: Rgb::splat(2.0),
            };
            sample_at(scene, x, &lobe, None, Rgb::ONE, settings, s, rays)
        }
    }
}

/// Mean and standard error of an estimate, per part and channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Estimate {
    pub mean: Parts,
    pub std_error: Parts,
    pub samples: u64,
    pub rays: u64,
}

/// Running sums for [`Estimate`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Accumulator {
    sum: [Rgb; 3],
    sum2: [Rgb; 3],
    n: u64,
    rays: u64,
}

impl Accumulator {
    pub fn push(&mut self, p: &Parts) {
        for (k, v) in [p.direct, p.single, p.multiple].into_iter().enumerate() {
            self.sum[k] += v;
            self.sum2[k] += v * v;
        }
        self.n += 1;
    }

    pub fn add_rays(&mut self, r: u64) {
        self.rays += r;
    }

    pub fn estimate(&self) -> Estimate {
        let n = self.n.max(1) as f64;
        let mean: Vec<Rgb> = self.sum.iter().map(|s| *s / n).collect();
        let se: Vec<Rgb> = (0..3)
            .map(|k| {
                let var = (self.sum2[k] / n - mean[k] * mean[k]).max(Rgb::ZERO) * (n / (n - 1.0).max(1.0));
                (var / n).powf(0.5)
            })
            .collect();
        Estimate {
            mean: Parts {
                direct: mean[0],
                single: mean[1],
                multiple: mean[2],
            },
            std_error: Parts {
                direct: se[0],
                single: se[1],
                multiple: se[2],
            },
            samples: self.n,
            rays: self.rays,
        }
    }
}

/// Estimate the query at `x` with `spp` samples; `item` selects the random streams
/// (e.g. the pixel index), so equal (seed, item) give identical results.
pub fn estimate(scene: &Scene, x: DVec2, q: &Query, settings: &Settings, spp: u32, seed: u64, item: u64) -> Estimate {
    let mut acc = Accumulator::default();
    if !q.defined_at(scene, x) {
        return acc.estimate();
    }
    let mut rays = 0;
    for k in 0..spp {
        let mut s = Sampler::new2(seed, item, k as u64);
        acc.push(&sample_query(scene, x, q, settings, &mut s, &mut rays));
    }
    acc.add_rays(rays);
    let mut e = acc.estimate();
    e.samples = spp as u64;
    e
}

/// Estimate the radiance L_i(x, ω) arriving at `x` from direction `w`.
pub fn estimate_radiance(scene: &Scene, x: DVec2, w: DVec2, settings: &Settings, spp: u32, seed: u64) -> (Rgb, Rgb) {
    let mut acc = Accumulator::default();
    let mut rays = 0;
    for k in 0..spp {
        let mut s = Sampler::new2(seed, 0, k as u64);
        let (l, _) = radiance_path(scene, x, w.normalize(), None, None, settings, &mut s, &mut rays);
        acc.push(&Parts {
            direct: l,
            ..Default::default()
        });
    }
    let e = acc.estimate();
    (e.mean.direct, e.std_error.direct)
}
