//! One radiance-cache record, in any dimension (theory.md §3–7): the light field at
//! a query point → its proxy → the method's derivatives → the value, gradient and
//! Hessian a record stores, and the Hessian its metric uses. Methods:
//! - `ours`: occlusion-aware gradient and Hessian ([`aware`]); the metric's Hessian
//!   is taken with a radiance floor (Schwarzhaupt et al. 2012, for black
//!   occluders), extent = the seed's Hessian ellipse (ellipsoid);
//! - `jarosz08`: occlusion-unaware gradient ([`unaware`]), extent = the gradient
//!   circle (ball).
//!
//! Both store the light field's plain Monte Carlo estimate as the value (unbiased),
//! so at equal record positions they differ only in derivatives and extents. (The
//! proxy's own value is 4–8% low where emitters' outlines cross its elements: the
//! farther-vertex rule darkens them.)

use super::derivatives::{
    AwareSettings, PartDerivs, aware_with_noise, scattered_value_variance, unaware, with_plain_values,
};
use super::dim::Dim;
use super::moments::{RecordMoments, combine, moment_derivs, weights_towards};
use super::path::{PointLights, Settings};
use super::probe::{LightField, Outgoing, ProbeSettings, capture};
use super::proxy::build;
use super::seen_ends::nearest_seen_end;
use super::silhouette::nearest_boundary;
use super::world::{DirectLight, World};
use crate::core::color::Rgb;
use crate::core::metric::{CacheMethod, MetricParams};
use crate::core::rng::mix64;
use crate::core::space::Space;
use crate::core::taylor::Taylor2;
use crate::progress::{Cancelled, Progress};
use serde::Serialize;
use std::time::Instant;

/// How a cache is built.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CacheSettings {
    pub method: CacheMethod,
    /// Error threshold ε (theory.md §6: a length^{d−1}·… for ours, dimensionless for
    /// jarosz08; compare methods at equal record count).
    pub eps: f64,
    pub probe: ProbeSettings,
    pub aware: AwareSettings,
    /// Separate caches for single and multiple scattering.
    pub per_part: bool,
    /// Second-order interpolation (ours only; the baseline has no Hessian).
    pub second_order: bool,
    /// Fraction of the mean element radiance added to every element before the
    /// metric's Hessian.
    pub hessian_floor: f64,
    /// Seed of the records' light fields.
    pub seed: u64,
    /// Also store each record's harmonic moments over ω_o up to this band
    /// (`super::moments`), so that the cache serves any camera. (Left out of JSON
    /// when not asked for: a null there reads as a non-finite number.)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moment_bands: Option<usize>,
    /// Estimate the light arriving straight from the lights (emitters, sky, delta
    /// lights) at every point served, with this many samples of
    /// [`super::path::direct_at`] (NEE and a phase-sampled ray, MIS), and cache only
    /// the rest: the records' light fields leave it out ([`ProbeSettings::emitted`]).
    /// Its shadow edges and the peak around a light are where records extrapolate
    /// worst; per point they cost a few rays. None: the paper's split (only delta
    /// lights per point).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direct_samples: Option<u32>,
    /// With [`Self::direct_samples`], in 2D fields (`flatland::cached_field`; 3D
    /// images sample per march point and ignore it): raise the straight light's
    /// samples per point to this share of the placement's rays per point served
    /// (two rays a sample; at 128² points, scaled by (points/128²)^(2/3): see
    /// `super::budget::shared_direct_samples`), so that a scene whose records are dense, and costly
    /// per pixel, samples its straight light in proportion. Set by a 2D budget
    /// (`super::budget::flatland_direct_share`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direct_share: Option<f64>,
    /// Limit every radius of a record to this multiple of the distance from it to
    /// the nearest surface edge it sees (a segment's end, a triangle's silhouette
    /// edge; [`RecordData::nearest_edge`]). Around an edge the light turns with the
    /// angle seen from the edge, so its derivatives grow as 1/r and 1/r²: a record's
    /// Taylor expansion cannot be trusted farther than the edge is, whatever its
    /// Hessian says there (a Hessian taken beside the edge misses the turn). A
    /// visible point light counts as an edge: the light scattered once and again
    /// peaks around it. None: the paper's metric alone.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_reach: Option<f64>,
    /// Limit every radius of a record to this multiple of its distance to the
    /// nearest point light, seen or not (no rays: the lights' positions alone).
    /// Around a point light the light scattered once and again grows as 1/ρ (3D),
    /// and a Taylor expansion of 1/ρ converges only within ρ of its centre: a
    /// record beside the lamp, whose metric knows only its own derivatives,
    /// otherwise carries its peak value over a ball many times its distance to
    /// the lamp. On by default in 3D ([`super::budget::VOLUME_LAMP_REACH`]); None
    /// in 2D, whose peak is log(1/ρ) and whose budgets path trace the pixels
    /// near a point light instead ([`Self::near_light_paths`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lamp_reach: Option<f64>,
    /// A record placed for an eye (a camera) serves only the points the eye sees
    /// within this half-angle (degrees) of it (`super::eye_cone`): L_s towards
    /// the eye turns with x, and its expansion is singular at the eye. Anisotropic
    /// media only. Off by default (measured on deep_lamp, README).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eye_cone_deg: Option<f64>,
    /// Limit every radius of ours' records to
    /// [`crate::core::metric::gradient_noise_radius`] of their multiple-scattering
    /// gradient's noise ([`RecordData::multiple_grad_var`]): a record whose
    /// gradient is mostly noise extrapolates (with that gradient shrunk) no farther
    /// than its noise allows at ε. Off by default (the paper's metric alone).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub gradient_noise_reach: bool,
    /// Extrapolate with each record's multiple-scattering gradient shrunk by its own
    /// noise ([`RecordData::payload_to_extrapolate`]); its extent still follows the
    /// measured gradient. On by default: on a point light in thick g = 0.85 fog
    /// (`shaded_lamp.json`, 800 records, seeds 1–3) RMSE 0.365/0.399/0.419 →
    /// 0.322/0.338/0.341, relMSE halved; within 0.1% on occluder, windows, forest.
    pub shrink_noisy_gradients: bool,
    /// Take more light fields at a record (each of `probe.rays` directions, their
    /// derivatives averaged) until its value's estimated noise meets a target. None:
    /// one light field, the paper's record. Measured with 256 directions and a 10%
    /// target (README): the rays go to thick anisotropic fog (shaded_lamp) and not
    /// to thin fog (occluder, windows: +0.7% and no rays); on forest more records
    /// pay more than more rays. Not a default: no rule won on every scene.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub record_noise: Option<NoiseTarget>,
    /// Sample the point lights' light scattered once in the medium on its way to
    /// every point served, with this many directions per point
    /// (`super::point_scatter::once_scattered_point_lights`), and cache only the
    /// rest: the records' medium samples leave the point lights' straight light
    /// out ([`ProbeSettings::point_lights`]). Around a point light that light peaks
    /// as log(1/r) (2D) or 1/r (3D), a peak records extrapolate across. 2D fields
    /// of all light (one cache); others ignore it. None: cached.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point_scatter: Option<u32>,
    /// Path trace every point served within one mean free path of a point light
    /// (`super::point_scatter::near_light_radius`) whole, with this many paths,
    /// instead of reading it from the records: there the light scattered twice
    /// or more still peaks (log 1/r in 2D) and the records holding it are noisy.
    /// 2D fields of all light (one cache); others ignore it. None: cached.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub near_light_paths: Option<u32>,
}

/// When a record has enough light fields ([`CacheSettings::record_noise`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct NoiseTarget {
    /// The relative standard error of the record's value (the luminance of its
    /// scattered light, [`super::derivatives::scattered_value_variance`]) to reach.
    pub relative: f64,
    /// The most light fields a record takes (≥ 1).
    pub max_light_fields: u32,
}

impl CacheSettings {
    /// Defaults for dimension `S` ([`ProbeSettings::default_for`]); `paths` are the
    /// path settings of the light at the points the records serve: a 2D field's
    /// (its points start their paths), a 3D image's past its camera rays' first
    /// vertex (`volume::render::RenderParams::first_vertex_settings`), so that a
    /// cached image and its path-traced reference trace as deep.
    pub fn new<S: Dim>(method: CacheMethod, eps: f64, paths: Settings) -> Self {
        CacheSettings {
            method,
            eps,
            probe: ProbeSettings {
                settings: paths,
                ..ProbeSettings::default_for::<S>()
            },
            aware: AwareSettings::default(),
            per_part: false,
            second_order: false,
            hessian_floor: 0.01,
            seed: 1,
            moment_bands: None,
            direct_samples: None,
            direct_share: None,
            edge_reach: None,
            lamp_reach: (S::DIM == 3).then_some(super::budget::VOLUME_LAMP_REACH),
            eye_cone_deg: None,
            gradient_noise_reach: false,
            shrink_noisy_gradients: true,
            record_noise: None,
            point_scatter: None,
            near_light_paths: None,
        }
    }

    /// Whether a record can hold any light: its hits' and medium samples' light
    /// (when its paths may reach a vertex past the record's point) or the
    /// emitters and sky its rays see straight (`extended_lights`: the world has
    /// some; unless the straight light is sampled at every point served). A 3D
    /// image at `max_depth` 1 of a scene lit by point lamps holds only their
    /// straight light at its camera rays' points: records would all be black, and
    /// of the smallest extent (L = 0), one per query point, so placement places
    /// none and every point is estimated on its own (that straight light, as path
    /// tracing has it).
    pub fn records_hold_light(&self, extended_lights: bool) -> bool {
        self.probe.settings.reaches(1) || (extended_lights && self.probe.emitted && self.direct_samples.is_none())
    }

    pub fn metric(&self, scene_scale: f64) -> MetricParams {
        MetricParams::scene_relative(scene_scale, self.eps)
    }
}

/// The cached quantities a record can feed: single + multiple scattering, or one
/// of them (per-part caches).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cached {
    Scattered,
    Single,
    Multiple,
}

impl Cached {
    /// This quantity from the single and multiple parts (values, derivatives or
    /// moments alike).
    fn of<T: std::ops::Add<Output = T>>(self, single: T, multiple: T) -> T {
        match self {
            Cached::Scattered => single + multiple,
            Cached::Single => single,
            Cached::Multiple => multiple,
        }
    }
}

/// What one light field gives a record, kept to re-derive extents for another ε.
#[derive(Clone, Debug)]
pub struct RecordData<S: Dim> {
    /// Value (the plain estimate) and derivatives, per part.
    pub parts: PartDerivs<S>,
    /// Luminance Hessians the metric uses (with the radiance floor; zero for
    /// jarosz08), per [`Cached`] quantity.
    pub metric_hessians: [S::Mat; 3],
    /// The luminance of the same floored light's value, per [`Cached`] quantity
    /// (zero for jarosz08): what the metric measures a record that saw no light at
    /// all with ([`RecordData::metric_luminance`]).
    pub floored_values: [f64; 3],
    /// Jarosz 2008's: the luminance gradient of its floored light, whose radius
    /// it sets (zero for ours, whose metric takes the floored Hessian).
    pub floored_grads: [S::Vec; 3],
    /// Per basis function of the moments over ω_o, value and derivatives per part
    /// (empty unless asked for: [`CacheSettings::moment_bands`]).
    pub moments: Vec<PartDerivs<S>>,
    /// The moments' weights for the ω_o the record was made for.
    pub placed_weights: Vec<f64>,
    /// That ω_o (unit).
    pub placed_omega: S::Vec,
    pub rays: u64,
    /// Wall time of the capture and derivatives.
    pub seconds: f64,
    /// Of `seconds`: capturing the light field (its rays and their recursive
    /// estimates); the rest is the proxy, the derivatives and the extent's checks.
    pub capture_seconds: f64,
    /// Distance from the record's point to the nearest surface edge its light
    /// field sees, where the surface ends (a visibility boundary's silhouette
    /// point, [`super::silhouette::nearest_boundary`]; also the ends the rays
    /// passed between, [`super::seen_ends::nearest_seen_end`]), or to the
    /// nearest point light it sees if that is nearer; +∞ when it sees none or
    /// when [`CacheSettings::edge_reach`] is not asked for.
    pub nearest_edge: f64,
    /// Noise variance of the multiple part's luminance gradient from its medium
    /// samples (ours, [`super::derivatives::aware_with_noise`]; 0 for Jarosz 2008).
    pub multiple_grad_var: f64,
    /// Noise variance of the scattered light's value (luminance of single +
    /// multiple, the plain estimate's: [`super::derivatives::scattered_value_variance`]),
    /// of the mean of its light fields under [`CacheSettings::record_noise`].
    pub value_var: f64,
}

/// The luminance of the scattered light's value (single + multiple): what a
/// record of all scattered light caches, and what its `value_var` is of.
fn scattered_luminance<S: Dim>(parts: &PartDerivs<S>) -> f64 {
    (parts.single + parts.multiple).luminance().value
}

impl<S: Dim> RecordData<S> {
    /// The luminance of the scattered light's value, whose noise variance is
    /// [`RecordData::value_var`].
    pub fn scattered_luminance(&self) -> f64 {
        scattered_luminance(&self.parts)
    }

    /// [`RecordData::payload`] with the multiple part's gradient G shrunk by its
    /// noise variance v ([`RecordData::multiple_grad_var`]): × max(0, 1 − v/|G|²),
    /// the positive-part James–Stein factor, which estimates |E G|²/|G|² (what
    /// minimises the expected error of extrapolating with a scaled G) from E|G|² =
    /// |E G|² + v. In thick forward-scattering fog a record's multiple-scattering
    /// gradient at 1024 rays is mostly noise away from the lights, and extrapolating
    /// with it doubled the error of the zero-order value there.
    pub fn payload_to_extrapolate(&self, q: Cached) -> crate::core::taylor_rgb::TaylorRgb<S> {
        let mut m = self.parts.multiple;
        let g2 = <S as Space>::length_squared(m.luminance().grad);
        let shrink = if g2 > 0.0 {
            (1.0 - self.multiple_grad_var / g2).max(0.0)
        } else {
            1.0
        };
        for ch in &mut m.channels {
            ch.grad = ch.grad * shrink;
        }
        q.of(self.parts.single, m)
    }

    /// The value and derivatives of a cached quantity.
    pub fn payload(&self, q: Cached) -> crate::core::taylor_rgb::TaylorRgb<S> {
        q.of(self.parts.single, self.parts.multiple)
    }

    /// The moments of a cached quantity (empty without moments).
    pub fn moment_payload(&self, q: Cached) -> RecordMoments<S> {
        let moments: Vec<_> = self
            .moments
            .iter()
            .map(|p: &PartDerivs<S>| q.of(p.single, p.multiple))
            .collect();
        let as_placed = combine(&moments, &self.placed_weights);
        RecordMoments {
            moments,
            as_placed,
            placed_omega: self.placed_omega,
        }
    }

    pub fn metric_hessian(&self, q: Cached) -> S::Mat {
        self.metric_hessians[q as usize]
    }

    /// The luminance the metric measures a record of `q` with, `l` being its
    /// value's: `l`, or, where the record saw no light at all (every part zero), its floored
    /// light's, whose Hessian the metric takes. Why: with L = 0 every extent is the
    /// smallest, so a region that is truly dark (fog around a sealed lamp, a 3D
    /// image's records at max_depth 1 in a scene lit by an area light it does not
    /// see) took one record per query point: a 16×12 image of a sealed lamp did
    /// not finish in 5 minutes. Measured with the floor's unit radiance, the
    /// extent is the geometric one irradiance caching gives (Ward's, Schwarzhaupt
    /// et al.'s floored Hessian), and serving zero there is right.
    /// Jarosz 2008's radius, ε L / |∇L|, is measured with its floored light's
    /// value and gradient alike.
    pub fn metric_luminance(&self, q: Cached, l: Taylor2<S>) -> Taylor2<S> {
        // Only a record dark in every part: one part alone can be zero where the
        // others are not (single scattering in a lamp's shadow, `per_part`), and
        // there the edge of that zero is near.
        if l.value == 0.0 && self.parts.sees_no_light() {
            let k = q as usize;
            let grad = if S::length(self.floored_grads[k]) > 0.0 {
                self.floored_grads[k]
            } else {
                l.grad
            };
            Taylor2 {
                value: self.floored_values[k],
                grad,
                hess: l.hess,
            }
        } else {
            l
        }
    }
}

/// The seed of record `id`'s light fields: its k-th light field is `probe::capture`
/// at this seed and item k (k > 0 only with [`CacheSettings::record_noise`]).
pub fn light_field_seed(cs: &CacheSettings, id: u64) -> u64 {
    mix64(cs.seed ^ mix64(id))
}

/// The light field at query point `x` (stream `id`) and what the method derives.
pub fn compute_record<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    out: Outgoing<<W::S as Space>::Vec>,
    cs: &CacheSettings,
    id: u64,
    progress: &Progress,
) -> Result<RecordData<W::S>, Cancelled> {
    let start = Instant::now();
    // Jarosz et al. 2008 hold each sample's light fixed: no slopes to pay for.
    let probe = ProbeSettings {
        slopes: cs.probe.slopes && cs.method == CacheMethod::Ours,
        emitted: cs.probe.emitted && cs.direct_samples.is_none(),
        point_lights: match cs.point_scatter {
            Some(_) => PointLights::Left,
            None => cs.probe.point_lights,
        },
        // Moments serve every ω_o: no direction may be rouletted by one ω_o's phase.
        phase_roulette: if cs.moment_bands.is_some() {
            0.0
        } else {
            cs.probe.phase_roulette
        },
        ..cs.probe
    };
    let seed = light_field_seed(cs, id);
    let mut lf = capture(world, x, out, &probe, seed, 0, progress)?;
    // Only a placement that limits reach by it pays for the boundary's check.
    let (nearest_edge, edge_rays) = match cs.edge_reach {
        Some(k) => {
            // Silhouettes where vertices moved (2D) and where edges were cut (3D).
            let moved = lf
                .rays
                .iter()
                .filter_map(|r| r.hit.as_ref().and_then(|h| h.edge.map(|e| (h.point, h.normal, e))));
            let cut = lf.cuts.iter().filter_map(|c| {
                let h = lf.rays[c.from as usize].hit.as_ref()?;
                Some((h.point, h.normal, c.point))
            });
            let ends: Vec<_> = moved.chain(cut).collect();
            let (edge, rays) = nearest_boundary(world, x, &ends);
            let (light, light_rays) = nearest_point_light(world, &lf, probe.emitted);
            let near = edge.min(light);
            // Ends the rays passed between; only nearer ones that can bind matter.
            let binding = cs.metric(world.scale()).r_max / k;
            let (seen, seen_rays) = nearest_seen_end(world, x, near.min(binding));
            (near.min(seen), rays + light_rays + seen_rays)
        }
        None => (f64::INFINITY, 0),
    };
    let (mut capture_seconds, mut rays) = (lf.seconds, lf.cost_rays + edge_rays);
    let mut derived = derive(&mut lf, cs);
    // Summed over the light fields taken; that of their mean is var_sum / n².
    let mut var_sum = scattered_value_variance(&lf);
    let mut light_fields = 1.0;
    if let Some(target) = cs.record_noise {
        // Independent light fields (streams 1, 2, …) until the mean's standard
        // error, √(Σ var)/n, is within the target.
        let mut fields = vec![derived];
        while fields.len() < target.max_light_fields as usize {
            let n = fields.len() as f64;
            let value: f64 = fields.iter().map(Derived::scattered_luminance).sum::<f64>() / n;
            if var_sum.sqrt() / n <= target.relative * value.abs() {
                break;
            }
            let mut more = capture(world, x, out, &probe, seed, fields.len() as u64, progress)?;
            var_sum += scattered_value_variance(&more);
            (capture_seconds, rays) = (capture_seconds + more.seconds, rays + more.cost_rays);
            fields.push(derive(&mut more, cs));
        }
        light_fields = fields.len() as f64;
        derived = Derived::mean(&fields);
    }
    let Derived {
        parts,
        metric_hessians,
        floored_values,
        floored_grads,
        moments,
        placed_weights,
        multiple_grad_var,
    } = derived;
    Ok(RecordData {
        parts,
        metric_hessians,
        floored_values,
        floored_grads,
        moments,
        placed_weights,
        placed_omega: {
            let l = <W::S as Space>::length(lf.omega_o);
            if l > 0.0 {
                lf.omega_o / l
            } else {
                <W::S as Space>::axis(0)
            }
        },
        rays,
        seconds: start.elapsed().as_secs_f64(),
        capture_seconds,
        nearest_edge,
        multiple_grad_var,
        value_var: var_sum / (light_fields * light_fields),
    })
}

/// What the method derives from one light field for a record.
struct Derived<S: Dim> {
    parts: PartDerivs<S>,
    metric_hessians: [S::Mat; 3],
    floored_values: [f64; 3],
    floored_grads: [S::Vec; 3],
    moments: Vec<PartDerivs<S>>,
    placed_weights: Vec<f64>,
    multiple_grad_var: f64,
}

impl<S: Dim> Derived<S> {
    /// The luminance of the scattered light's value (single + multiple).
    fn scattered_luminance(&self) -> f64 {
        scattered_luminance(&self.parts)
    }

    /// The mean of independent light fields' (the gradient's noise variance that of
    /// the mean: Σ v / n²).
    fn mean(fields: &[Self]) -> Self {
        let n = fields.len() as f64;
        let mut metric_hessians = [S::zero_mat(); 3];
        for (k, h) in metric_hessians.iter_mut().enumerate() {
            *h = fields.iter().fold(S::zero_mat(), |a, d| a + d.metric_hessians[k]) * (1.0 / n);
        }
        let floored_values = [0, 1, 2].map(|k| fields.iter().map(|d| d.floored_values[k]).sum::<f64>() / n);
        let floored_grads = [0, 1, 2].map(|k| fields.iter().fold(S::zero(), |a, d| a + d.floored_grads[k]) * (1.0 / n));
        let moments = (0..fields[0].moments.len())
            .map(|k| PartDerivs::mean(&fields.iter().map(|d| d.moments[k]).collect::<Vec<_>>()))
            .collect();
        Derived {
            parts: PartDerivs::mean(&fields.iter().map(|d| d.parts).collect::<Vec<_>>()),
            metric_hessians,
            floored_values,
            floored_grads,
            moments,
            placed_weights: fields[0].placed_weights.clone(),
            multiple_grad_var: fields.iter().map(|d| d.multiple_grad_var).sum::<f64>() / (n * n),
        }
    }
}

/// The method's value, derivatives, metric Hessians and moments from one light
/// field (left as given).
fn derive<S: Dim>(lf: &mut LightField<S>, cs: &CacheSettings) -> Derived<S> {
    let zero = S::zero_mat();
    let proxy = (cs.method == CacheMethod::Ours).then(|| build(lf, cs.aware.rule));
    let mut multiple_grad_var = 0.0;
    let (parts, metric_hessians, floored_values, floored_grads) = match &proxy {
        Some(proxy) => {
            let (parts, floored, var) = aware_with_noise(lf, proxy, &cs.aware, cs.hessian_floor);
            multiple_grad_var = var;
            let floored = floored.unwrap_or(parts);
            let each = [floored.single + floored.multiple, floored.single, floored.multiple].map(|t| t.luminance());
            (parts, each.map(|l| l.hess), each.map(|l| l.value), [S::zero(); 3])
        }
        None => {
            let parts = unaware(lf);
            // Only a light field that saw nothing pays for its floored twin.
            let floored = match parts.sees_no_light() {
                true => unaware(&floored_light(lf)),
                false => parts,
            };
            let each = [floored.total(), floored.single, floored.multiple].map(|t| t.luminance());
            (parts, [zero; 3], each.map(|l| l.value), each.map(|l| l.grad))
        }
    };
    let parts = with_plain_values(parts, lf);
    let (moments, placed_weights) = match cs.moment_bands {
        Some(bands) => (
            moment_derivs(lf, proxy.as_ref(), &cs.aware, bands),
            weights_towards::<S>(lf.g, bands, lf.omega_o),
        ),
        None => (Vec::new(), Vec::new()),
    };
    Derived {
        parts,
        metric_hessians,
        floored_values,
        floored_grads,
        moments,
        placed_weights,
        multiple_grad_var,
    }
}

/// The light field with unit radiance added to every hit and escaped ray, as the
/// metric's radiance floor adds it to every proxy element of a black light field
/// (`crate::core::metric::hessian_radiance_floor`): what Jarosz 2008 measures a
/// record that saw no light with.
fn floored_light<S: Dim>(lf: &LightField<S>) -> LightField<S> {
    let mut floored = lf.clone();
    for r in &mut floored.rays {
        match &mut r.hit {
            Some(h) => h.radiance += Rgb::ONE,
            None => r.escaped += Rgb::ONE,
        }
    }
    floored
}

/// Distance from the light field's point to the nearest point light it sees, +∞
/// without one, and the shadow rays this cost: none when the light field holds
/// its delta lights (`held`: it was captured with the light arriving straight
/// from the lights), one per light otherwise. Around a point light the light
/// scattered once and again peaks as the first scattering events crowd towards
/// it (their density grows as 1/r^{d−1}), so, as at a surface's edge, no Taylor
/// expansion reaches farther than the light is.
fn nearest_point_light<W: World>(world: &W, lf: &super::probe::LightField<W::S>, held: bool) -> (f64, u64) {
    let found;
    let (lights, rays) = if held {
        (&lf.direct_lights, 0)
    } else {
        found = world.direct_lights(lf.x);
        (&found.0, found.1)
    };
    let nearest = lights
        .iter()
        .filter_map(|l| match l {
            DirectLight::Point { position, .. } => Some(<W::S as Space>::length(*position - lf.x)),
            DirectLight::Directional { .. } => None,
        })
        .fold(f64::INFINITY, f64::min);
    (nearest, rays)
}

/// One record, for figures and JSON (a simplex holds one value per axis).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RecordInfo<S: Dim> {
    pub position: S::Vec,
    /// Unit axes of the extent and their radii.
    pub axes: S::Simplex<S::Vec>,
    pub radii: S::Simplex<f64>,
    pub luminance: f64,
    pub rays: u64,
}

impl<S: Dim> RecordInfo<S> {
    pub fn of(r: &crate::core::cache::Record<S, crate::core::taylor_rgb::TaylorRgb<S>>) -> Self {
        RecordInfo {
            position: r.position,
            axes: S::simplex(|j| S::col(r.extent.axes, j)),
            radii: S::simplex(|j| r.extent.radii[j]),
            luminance: crate::core::color::luminance(r.value.value()),
            rays: r.cost_rays,
        }
    }
}
