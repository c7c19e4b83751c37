//! A cache point's incoming light field (theory.md §3), in any dimension: N
//! stratified directions around a medium point x (a circle's arcs, a sphere's
//! Fibonacci set, jittered per (seed, item)) with their neighbours, each ray's
//! surface hit with the radiance leaving it towards x, and ray-marched medium samples
//! with recursive estimates of L_s.
//!
//! Parameters ([`ProbeSettings`]): `rays` (N), `paths` (recursive paths per hit and
//! per medium sample), `steps` (medium samples per ray over the march length),
//! `transmittance_cutoff`, `far_factor`, `jitter`, `settings` (the path tracer's).
//!
//! The march: every ray is cast first; the march length is the farthest point any
//! ray still has medium in front of it (its hit, or where it leaves the medium
//! region), capped where the transmittance falls below `transmittance_cutoff` and at
//! `far_factor` × the scene size, and `steps` samples are spread over that length
//! (so a room is sampled at room scale, not at the scale of the fog's mean free
//! path), refined towards x by `grading` ([`March`]). Medium sample i of ray k sits
//! at [`March::depth`](i, ξ_k) with the ray's own jitter ξ_k, so the i-th samples
//! of neighbouring rays form shells. (A single offset shared by
//! all rays makes the shells exact but correlates the rays' errors: a measured 17%
//! bias of the multiple-scattering value on occluder.json, gone with per-ray jitter.)
//!
//! Delta lights are kept apart for the direct part (theory.md §2). Escaped rays end
//! at the cut length and carry what the world says leaves along them (the sky in
//! 3D), scaled by T_true / exp(−σ_t(x)·length) so that the proxy's homogeneous
//! transmittance gives the true value through a bounded medium.
//!
//! L_s is wanted towards a fixed direction ω_o or towards a point (the camera of a
//! 3D render: [`Outgoing::TowardsPoint`]), in which case ω_o turns with x and the
//! derivatives include that turning.

use super::dim::Dim;
use super::lobe::Lobe;
use super::medium::Region;
use super::path::{PointLights, ScatteredSample, Settings, radiance_leaving, sample_at_each, scattered_with_slope};
use super::silhouette::{Cut, RayEnd, Silhouettes, find_edges};
use super::world::{DirectLight, Hit, World, ignore};
use crate::core::color::Rgb;
pub use crate::core::phase::Outgoing;
use crate::core::rng::{Sampler, mix64};
use crate::core::space::Space;
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;
use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ProbeSettings {
    /// Number of stratified directions N.
    pub rays: usize,
    /// Recursive paths per hit point and per medium sample.
    pub paths: u32,
    /// Medium samples per ray over the march length.
    pub steps: usize,
    /// Refinement k of the march towards x ([`March`]): 0 spaces the samples evenly;
    /// k > 0 makes the first steps k/(e^k − 1) of the even step and lets the step
    /// grow linearly with the depth.
    pub grading: f64,
    /// Stop marching where the transmittance from x falls below this.
    pub transmittance_cutoff: f64,
    /// Escaped rays end at this multiple of the scene size.
    pub far_factor: f64,
    /// Jitter of the directions in their strata, in [0, 1].
    pub jitter: f64,
    /// Also estimate how each medium sample's L_s turns with the direction it is
    /// seen from ([`ProbeRay::slopes`]; the aware derivatives use it, the unaware
    /// ones do not). No extra rays: the light samples and the path are reweighted.
    pub slopes: bool,
    /// Count the light arriving at a medium point straight from emitters, the sky
    /// and delta lights. False when the caller estimates that light itself at every
    /// point it serves ([`super::record::CacheSettings::direct_samples`]): then the
    /// light field holds only light that was reflected or scattered on its way.
    /// (A surface receiver says this itself, [`SurfaceReceiver::emitted`].)
    pub emitted: bool,
    /// Russian roulette of the expensive part of each ray's medium samples' L_s —
    /// the phase-sampled path beyond the light samples — by the phase's weight of
    /// the ray towards ω_o: followed with probability q = min(1, c · f/f̄) (f̄ the
    /// mean phase, 1/2π or 1/4π; weighted 1/q when followed), so that in
    /// anisotropic fog the directions whose light the phase scatters little
    /// towards ω_o cost less. The light samples (one shadow ray each) are always
    /// taken: zeroing whole samples made the gradients and Hessians of forest.json
    /// (g = 0.3) noisier than the rays saved. Nor the hits' reflected light: a
    /// rouletted hit beside a kept one is a radiance jump between neighbouring
    /// rays, which the aware derivatives take for an edge.
    /// Unbiased; c = 0 (the default) turns it off, and an isotropic phase (q = 1)
    /// never draws. Measured (`volcache bench records`, c = 1, records' error
    /// against a converged record, records/s at equal error for value, gradient
    /// and Hessian): shaded_lamp.json (g = 0.85) 52% of the rays saved, 1.31×,
    /// 1.43×, 1.47×; forest.json (g = 0.3) 11% saved, 0.94×, 0.99×, 1.10×; 3D
    /// lamp_fog.json (g = 0.8) 37% saved, 1.7× in value but 0.4× in gradient (dim
    /// points deep in the fog). Hence opt-in.
    /// Only for a light field that serves one ω_o (not harmonic moments, not a
    /// surface's irradiance).
    pub phase_roulette: f64,
    /// Whether the medium samples count the point lights' straight light. `Left`
    /// when the caller takes the light the point lights send through one
    /// scattering to every point it serves (`super::point_scatter`,
    /// [`super::record::CacheSettings::point_scatter`]): the records then hold the
    /// rest, without the log (2D) or 1/r (3D) peak around each light.
    pub point_lights: PointLights,
    /// The path tracer's settings for the light at x: its `max_depth` counts the
    /// vertices after x, so a hit or medium sample (one vertex after x) traces
    /// with [`Settings::past`](1) and counts only its emission when x has no
    /// vertex left. (A 3D record serves a camera ray's first vertex: its settings
    /// are the image's past 1.)
    pub settings: Settings,
}

impl ProbeSettings {
    /// The defaults for dimension `S` ([`Dim::PROBE_RAYS`] directions, [`Dim::PROBE_GRADING`]).
    pub fn default_for<S: Dim>() -> Self {
        Self::with_rays::<S>(S::PROBE_RAYS)
    }

    /// The defaults for dimension `S` with `rays` directions.
    pub fn with_rays<S: Dim>(rays: usize) -> Self {
        ProbeSettings {
            rays,
            paths: 1,
            steps: 24,
            grading: S::PROBE_GRADING,
            transmittance_cutoff: 1e-3,
            far_factor: 4.0,
            jitter: 1.0,
            slopes: true,
            emitted: true,
            phase_roulette: 0.0,
            point_lights: PointLights::Included,
            settings: Settings::default(),
        }
    }
}

/// The largest refinement per march step: adjacent steps' thicknesses differ by at
/// most e^0.375 ≈ 1.45, the default's growth at the CLI's 16 steps.
pub const MAX_GRADING_PER_STEP: f64 = 0.375;

/// The ray march of a light field: `steps` samples per ray over `length`, sample i
/// of a ray with jitter ξ at u = (i + ξ)/steps mapped to depth t = length·φ(u),
/// φ(u) = (e^{ku} − 1)/(e^k − 1) (φ(u) = u for k = 0), with thickness
/// Δt = length·φ'(u)/steps = Δt₀ + k·t/steps, Δt₀ = (length/steps)·k/(e^k − 1).
///
/// Why refine towards x: the multiple-scattering gradient is ∫K(z)∇L(x + z)dz with
/// a kernel ∝ 1/r^{d−1}, and a sharp feature of L (a shadow edge in the medium's own
/// radiance) at distance d from x weighs like ln(R/d): the part of it within the
/// first step is smoothed away. The samples keep each ray's uniform jitter in u, so
/// the march integrates any function of the depth without bias.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct March {
    pub length: f64,
    pub steps: usize,
    pub grading: f64,
    /// e^k − 1 of `grading` (0 for an even march), made once: every sample's depth
    /// and thickness divides by it (a 2D record takes ≈ 10⁵ of them).
    #[serde(skip)]
    grading_exp_m1: f64,
}

impl March {
    /// The refinement is capped at [`MAX_GRADING_PER_STEP`] × `steps`: a few steps
    /// with the default k would put all but the last sample within a few per cent
    /// of the march length (4 steps at k = 6: depths ≤ 0.22 L) and leave the rest
    /// to one sample's noise.
    pub fn new(length: f64, steps: usize, grading: f64) -> Self {
        let steps = steps.max(1);
        let grading = if grading.is_finite() {
            grading.clamp(0.0, 30.0)
        } else {
            0.0
        };
        let grading = grading.min(MAX_GRADING_PER_STEP * steps as f64);
        March {
            length,
            steps,
            grading,
            grading_exp_m1: grading.exp_m1(),
        }
    }

    /// k/(e^k − 1), 1 at k = 0.
    fn first_ratio(&self) -> f64 {
        let k = self.grading;
        if k < 1e-9 { 1.0 } else { k / self.grading_exp_m1 }
    }

    /// The even step length/steps (the first step is [`Self::thickness_at`](0)).
    pub fn even_step(&self) -> f64 {
        self.length / self.steps as f64
    }

    /// Depth of sample i of a ray with jitter `offset` ∈ [0, 1).
    pub fn depth(&self, i: usize, offset: f64) -> f64 {
        let u = (i as f64 + offset) / self.steps as f64;
        let k = self.grading;
        if k < 1e-9 {
            self.length * u
        } else {
            self.length * (k * u).exp_m1() / self.grading_exp_m1
        }
    }

    /// Thickness of the sample at depth t.
    pub fn thickness_at(&self, t: f64) -> f64 {
        self.even_step() * self.first_ratio() + self.grading * t.max(0.0) / self.steps as f64
    }
}

/// Where a probe ray met a surface, and the radiance leaving it towards x.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SurfaceHit<S: Dim> {
    pub point: S::Vec,
    pub prim: u32,
    /// Unit normal on the side facing x.
    pub normal: S::Vec,
    /// L_o(h → x): emission (active side) plus the reflected estimate.
    pub radiance: Rgb,
    /// Where the hit primitive's visible silhouette lies next to this ray, when a
    /// neighbouring ray sees something else ([`super::silhouette`]).
    pub edge: Option<S::Vec>,
}

/// One ray of the light field.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProbeRay<S: Dim> {
    pub dir: S::Vec,
    /// Distance to the hit, or where the ray was cut (transmittance or far limit).
    pub length: f64,
    pub hit: Option<SurfaceHit<S>>,
    /// Radiance carried by the end point of an escaped ray (see the module docs).
    pub escaped: Rgb,
    /// Medium samples: L_s(m, −dir) (σ_s included) at [`March::depth`](i, offset);
    /// zero outside the medium region.
    pub samples: Vec<Rgb>,
    /// Per medium sample and channel, ∇_dir L_s(m, −dir) (σ_s included; tangent to
    /// the sphere at `dir`): how the sample's light turns as x moves and sees m
    /// along another direction. Empty when not estimated (isotropic phase, or
    /// [`ProbeSettings::slopes`] off): zero.
    pub slopes: Vec<[S::Vec; 3]>,
    /// Jitter of this ray's medium samples, in [0, 1).
    pub offset: f64,
}

impl<S: Dim> ProbeRay<S> {
    /// End point, its distance from x and the radiance it carries.
    pub fn end(&self, x: S::Vec) -> (S::Vec, f64, Rgb) {
        match &self.hit {
            Some(h) => (h.point, S::length(h.point - x), h.radiance),
            None => (x + self.dir * self.length, self.length, self.escaped),
        }
    }
}

/// A medium sample as the derivatives weigh it ([`LightField::medium_sample`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumSample<S: Dim> {
    pub at: S::Vec,
    /// Its distance from x along the ray.
    pub depth: f64,
    /// L_s·Δt (σ_s included).
    pub light: Rgb,
    /// ∇_dir of `light` per channel (see [`ProbeRay::slopes`]).
    pub slope: [S::Vec; 3],
}

/// Which angular factor weights the light arriving at a light field's point x.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Angular<V> {
    /// The phase towards ω_o: L_s at a medium point.
    Phase,
    /// Basis function k of the harmonic moments over ω_o (`super::moments`).
    Moment(usize),
    /// The cosine max(0, n·ω) of a surface with unit normal n: the irradiance it
    /// receives (σ_s is then 1).
    Cosine(V),
}

/// A point on a surface as a light field's receiver (irradiance caching,
/// Schwarzhaupt et al. 2012).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceReceiver<V> {
    /// Unit normal of the side that receives.
    pub normal: V,
    /// The primitive the point lies on (its rays skip it).
    pub prim: u32,
    /// Also the light that arrives unscattered from emitters, the sky and delta
    /// lights. Without it only the indirect light is captured (light reflected by
    /// surfaces or scattered by the medium on its way), which a surface cache holds
    /// beside direct lighting sampled per pixel: direct light has the sharp shadows
    /// that interpolation would blur.
    pub emitted: bool,
}

/// The light field at one point.
#[derive(Clone, Debug, Serialize)]
pub struct LightField<S: Dim> {
    pub x: S::Vec,
    /// Direction L_s is wanted towards (at x, when it turns towards `eye`).
    pub omega_o: S::Vec,
    /// The point ω_o turns towards as x moves (a camera), if any.
    pub eye: Option<S::Vec>,
    pub rays: Vec<ProbeRay<S>>,
    /// Neighbouring directions (indices into `rays`), oriented.
    pub simplices: Vec<S::Simplex<u32>>,
    /// Where a hit surface's silhouette cuts simplex edges (3D; in 2D where the hit
    /// vertex could not move to it, [`super::silhouette::find_edges`]); sorted by
    /// ray pair.
    pub cuts: Vec<Cut<S::Vec>>,
    /// Where a farther surface's edge crosses a cut simplex edge beyond its cut
    /// (3D; [`super::silhouette::Silhouettes::far_cuts`]), sorted by ray pair.
    pub far_cuts: Vec<Cut<S::Vec>>,
    /// Where the ray-marched medium samples sit and how thick each is.
    pub march: March,
    /// Delta lights seen from x, analytically.
    pub direct_lights: Vec<DirectLight<S>>,
    /// σ_s, σ_t at x (zero without a medium).
    pub sigma_s: Rgb,
    pub sigma_t: Rgb,
    pub g: f64,
    /// Which angular factor weights the light arriving at x (`super::moments`).
    pub angular: Angular<S::Vec>,
    /// The median length of the rays: the distance at which x's surroundings lie,
    /// against which an element counts as near x ([`super::derivatives`]).
    pub median_length: f64,
    /// Ray-casting queries spent.
    pub cost_rays: u64,
    pub seconds: f64,
}

impl<S: Dim> LightField<S> {
    /// Depth of medium sample i of `ray`.
    pub fn sample_depth(&self, ray: &ProbeRay<S>, i: usize) -> f64 {
        self.march.depth(i, ray.offset)
    }

    /// Thickness Δt of medium sample i of `ray` (its weight in ∫ dt).
    pub fn sample_thickness(&self, ray: &ProbeRay<S>, i: usize) -> f64 {
        self.march.thickness_at(self.sample_depth(ray, i))
    }

    /// Medium sample `i` of ray `ray`: where it is, its L_s·Δt and that light's
    /// direction gradient per channel times Δt (zero when not estimated); None
    /// where the ray ended before shell i.
    pub fn medium_sample(&self, ray: usize, i: usize) -> Option<MediumSample<S>> {
        let (at, depth, light, dt) = self.medium_point(ray, i)?;
        let slope = self.rays[ray]
            .slopes
            .get(i)
            .map_or([S::zero(); 3], |g| g.map(|v| v * dt));
        Some(MediumSample {
            at,
            depth,
            light,
            slope,
        })
    }

    /// [`Self::medium_sample`] without the slope (the proxy's vertices): where it
    /// is, its depth, L_s·Δt, and Δt.
    #[inline]
    pub fn medium_point(&self, ray: usize, i: usize) -> Option<(S::Vec, f64, Rgb, f64)> {
        let r = &self.rays[ray];
        let light = *r.samples.get(i)?;
        let depth = self.sample_depth(r, i);
        let dt = self.march.thickness_at(depth);
        Some((self.x + r.dir * depth, depth, light * dt, dt))
    }

    /// Where L_s leaves towards, for the derivative core.
    pub fn outgoing(&self) -> Outgoing<S::Vec> {
        self.eye
            .map_or(Outgoing::Direction(self.omega_o), Outgoing::TowardsPoint)
    }

    /// The angle (solid angle) per ray, 2π/N (4π/N); half that over a surface's
    /// half circle (hemisphere).
    pub fn ray_measure(&self) -> f64 {
        let half = matches!(self.angular, Angular::Cosine(_));
        S::SPHERE_MEASURE / if half { 2.0 } else { 1.0 } / self.rays.len() as f64
    }
}

/// Capture the light field at `x` for L_s towards `out` (a fixed direction, or a
/// point such as a camera). Deterministic for (seed, item) whatever the thread count.
#[allow(clippy::too_many_arguments)] // the capture's inputs are spelled out
pub fn capture<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    out: Outgoing<<W::S as Space>::Vec>,
    ps: &ProbeSettings,
    seed: u64,
    item: u64,
    progress: &Progress,
) -> Result<LightField<W::S>, Cancelled> {
    let unit = |v: <W::S as Space>::Vec| {
        let l = W::S::length(v);
        if l > 0.0 { v / l } else { W::S::axis(0) }
    };
    let (omega_o, eye) = match out {
        Outgoing::Direction(w) => (w, None),
        Outgoing::TowardsPoint(e) => (unit(e - x), Some(e)),
    };
    let dirs = W::S::directions(ray_count::<W::S>(ps), ps.jitter, directions_seed(seed, item));
    let simplices = W::S::neighbours(&dirs);
    let importance = (ps.phase_roulette > 0.0).then_some(omega_o);
    let mut lf = trace_field(world, x, (dirs, simplices), None, importance, ps, seed, item, progress)?;
    (lf.omega_o, lf.eye) = (omega_o, eye);
    Ok(lf)
}

/// Capture the light field over the hemisphere a surface point receives from, for
/// its irradiance ([`Angular::Cosine`]; σ_s = 1, no phase): the receiver's rays
/// skip its primitive, and without `emitted` the light arriving straight from
/// emitters, the sky and delta lights is left out. Deterministic for (seed, item)
/// whatever the thread count.
#[allow(clippy::too_many_arguments)] // the capture's inputs are spelled out
pub fn capture_surface<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    receiver: SurfaceReceiver<<W::S as Space>::Vec>,
    ps: &ProbeSettings,
    seed: u64,
    item: u64,
    progress: &Progress,
) -> Result<LightField<W::S>, Cancelled> {
    let normal = receiver.normal;
    let dirs = W::S::hemisphere(ray_count::<W::S>(ps), normal, ps.jitter, directions_seed(seed, item));
    let simplices = W::S::hemisphere_neighbours(&dirs, normal);
    // Rays skip the receiver's primitive, and leave from a hair above it: a
    // neighbour in its plane (or the silhouette test's rays, which skip the hit's
    // primitive instead) must not meet it at a rounding-level distance.
    let above = x + normal * (1e-9 * world.scale());
    let mut lf = trace_field(
        world,
        above,
        (dirs, simplices),
        Some(receiver),
        None,
        ps,
        seed,
        item,
        progress,
    )?;
    lf.omega_o = normal;
    lf.sigma_s = Rgb::ONE;
    lf.g = 0.0;
    lf.angular = Angular::Cosine(normal);
    Ok(lf)
}

/// Directions of a light field: at least a simplex's worth.
fn ray_count<S: Dim>(ps: &ProbeSettings) -> usize {
    ps.rays.max(S::DIM + 1)
}

/// The stream of a light field's direction jitter, for (seed, item).
fn directions_seed(seed: u64, item: u64) -> u64 {
    mix64(seed ^ mix64(item.wrapping_add(0x9e37)))
}

/// A light field's directions and their neighbours.
type Directions<S> = (Vec<<S as Space>::Vec>, Vec<<S as Dim>::Simplex<u32>>);

/// The rays of a light field at `x` along `dirs` (with their neighbours), at a
/// medium point (`surface` None) or a surface receiver: its rays skip its
/// primitive; without `emitted` hits lose their emission, escaped rays the sky and
/// x its delta lights; and hits carry T_true / exp(−σ_t(x)·t), as escaped rays do,
/// since a surface may lie outside a bounded medium and look into it (a medium
/// point's hits do not: see the module docs). The field's ω_o is left to the caller;
/// `importance` is ω_o when rays' recursive estimates are rouletted by the phase
/// towards it ([`ProbeSettings::phase_roulette`]).
#[allow(clippy::too_many_arguments)] // the capture's inputs are spelled out
fn trace_field<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    (dirs, simplices): Directions<W::S>,
    surface: Option<SurfaceReceiver<<W::S as Space>::Vec>>,
    importance: Option<<W::S as Space>::Vec>,
    ps: &ProbeSettings,
    seed: u64,
    item: u64,
    progress: &Progress,
) -> Result<LightField<W::S>, Cancelled> {
    let start = std::time::Instant::now();
    let skip = surface.map(|r| r.prim);
    let emitted = surface.map_or(ps.emitted, |r| r.emitted);
    let medium = world.medium();
    let at_x = world.medium_at(x);
    let sigma_t_x = at_x.map_or(Rgb::ZERO, |m| m.sigma_t);
    let far = ps.far_factor * world.scale();
    let limit = match medium.map_or(0.0, |m| m.sigma_t.min_element()) {
        sig if sig > 0.0 => (-ps.transmittance_cutoff.ln() / sig).min(far),
        _ => far,
    };
    let n = dirs.len();
    // Pass 1: every ray's hit and how far it still has medium in front of it.
    let hits: Vec<(Option<Hit>, f64)> = dirs
        .par_iter()
        .map(|&dir| {
            let hit = world.closest_hit(x, dir, f64::INFINITY, skip);
            let end = hit.map_or(limit, |h| h.t.min(limit));
            let medium_end = medium.map_or(0.0, |m| {
                m.region.pieces(x, dir, end).into_iter().last().map_or(0.0, |(_, b)| b)
            });
            (hit, medium_end)
        })
        .collect();
    let march_len = hits.iter().map(|h| h.1).fold(0.0, f64::max).min(limit);
    let march = March::new(if march_len > 0.0 { march_len } else { limit }, ps.steps, ps.grading);
    let t_cut = march.length;
    let paths = ps.paths.max(1);
    // What the light at the field's hits and medium samples may trace: they are
    // one vertex after x (None: x has none left, and they count nothing but
    // emission, as a path's last vertex does).
    let beyond = ps.settings.reaches(1).then(|| ps.settings.past(1));
    type Traced<S> = Result<(ProbeRay<S>, u64), Cancelled>;
    let rays: Vec<Traced<W::S>> = dirs
        .par_iter()
        .zip(&hits)
        .enumerate()
        .map(|(k, (&dir, &(hit, _)))| {
            progress.check()?;
            let mut s = Sampler::new2(seed, item, k as u64);
            let offset = s.next_f64();
            let mut rays = 1u64;
            let keep = keep_probability::<W>(at_x, importance, dir, ps.phase_roulette);
            let hit_record = hit.map(|h| {
                let (sp, mut radiance) = match beyond {
                    Some(settings) => radiance_leaving(world, &h, dir, paths, &settings, &mut s, &mut rays),
                    None => {
                        let sp = world.surface(&h, dir);
                        let emitted = if sp.active { sp.emission } else { Rgb::ZERO };
                        (sp, emitted)
                    }
                };
                if !emitted && sp.active {
                    radiance -= sp.emission;
                }
                if surface.is_some() {
                    radiance *= model_correction(world, x, dir, h.t, sigma_t_x);
                }
                SurfaceHit {
                    point: sp.point,
                    prim: h.prim,
                    normal: sp.normal,
                    radiance,
                    edge: None,
                }
            });
            let length = hit.map_or(t_cut, |h| h.t);
            let escaped = match hit {
                None if emitted => escaped_radiance(world, x, dir, length, sigma_t_x),
                _ => Rgb::ZERO,
            };
            let mut samples = Vec::new();
            let mut slopes = Vec::new();
            let mut scattered = Vec::new();
            if let Some(m) = medium {
                let with_slopes = ps.slopes && W::S::phase_g(&m.phase) != 0.0;
                let lobe = Lobe::Phase {
                    phase: m.phase,
                    travel: dir,
                };
                let mut i = 0;
                loop {
                    let t = march.depth(i, offset);
                    if i >= march.steps || t >= length.min(t_cut) {
                        break;
                    }
                    let p = x + dir * t;
                    // The first samples weigh most in the gradient (its kernel's Δt/r
                    // is ≈ 1/ξ at an even march's first step): never rouletted.
                    let keep = if i < UNROULETTED_SAMPLES { 1.0 } else { keep };
                    let mut sum = Rgb::ZERO;
                    // Outside the medium, or with no vertex left past x, a sample is dark.
                    let traced = beyond.as_ref().filter(|_| m.contains(p));
                    if let Some(beyond) = traced
                        && with_slopes
                    {
                        for _ in 0..paths {
                            let one = scattered_with_slope(
                                world,
                                p,
                                m.phase,
                                dir,
                                (keep, ps.point_lights),
                                beyond,
                                &mut s,
                                &mut rays,
                            );
                            sum += one.value;
                            scattered.push((i, one));
                        }
                        sum = sum * m.sigma_s / paths as f64;
                    } else if let Some(beyond) = traced {
                        for _ in 0..paths {
                            let each = &mut ignore;
                            sum += sample_at_each(
                                world,
                                p,
                                &lobe,
                                None,
                                (keep, ps.point_lights),
                                beyond,
                                &mut s,
                                &mut rays,
                                each,
                            )
                            .0
                            .total();
                        }
                        sum = sum * m.sigma_s / paths as f64;
                    }
                    samples.push(sum);
                    i += 1;
                }
                if with_slopes {
                    slopes = slopes_with_baseline::<W::S>(&scattered, samples.len(), m.sigma_s / paths as f64);
                }
            }
            let ray = ProbeRay {
                dir,
                length,
                hit: hit_record,
                escaped,
                samples,
                slopes,
                offset,
            };
            Ok((ray, rays))
        })
        .collect();
    let mut out = Vec::with_capacity(n);
    let mut cost = 0;
    for r in rays {
        let (ray, c) = r?;
        out.push(ray);
        cost += c;
    }
    let ends: Vec<_> = out
        .iter()
        .map(|r| RayEnd {
            dir: r.dir,
            prim: r.hit.as_ref().map(|h| h.prim),
            point: r.hit.as_ref().map_or(x, |h| h.point),
            length: r.length,
        })
        .collect();
    let Silhouettes {
        moved,
        cuts,
        far_cuts,
        rays: c,
    } = find_edges(world, x, &ends, &simplices);
    cost += c;
    for (ray, edge) in out.iter_mut().zip(moved) {
        if let Some(h) = ray.hit.as_mut() {
            h.edge = edge;
        }
    }
    let (direct_lights, c) = if emitted {
        world.direct_lights(x)
    } else {
        (Vec::new(), 0)
    };
    let mut lengths: Vec<f64> = out.iter().map(|r| r.length).collect();
    let median_length = if lengths.is_empty() {
        0.0
    } else {
        let mid = lengths.len() / 2;
        *lengths.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    Ok(LightField {
        x,
        omega_o: W::S::axis(0),
        eye: None,
        rays: out,
        simplices,
        cuts,
        far_cuts,
        march,
        direct_lights,
        sigma_s: at_x.map_or(Rgb::ZERO, |m| m.sigma_s),
        sigma_t: sigma_t_x,
        g: at_x.map_or(0.0, |m| m.g()),
        angular: Angular::Phase,
        median_length,
        cost_rays: cost + c,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Medium samples of each ray nearest x whose paths are always followed
/// ([`ProbeSettings::phase_roulette`]).
const UNROULETTED_SAMPLES: usize = 2;

/// The probability q with which a ray's medium samples follow their phase-sampled
/// paths ([`ProbeSettings::phase_roulette`]): min(1, c·f/f̄), f the phase of the
/// medium at x scattering the ray's light (arriving along −`dir`) into ω_o. One
/// without a medium at x, without `importance`, or for c ≤ 0. At least 1e-3, so a
/// followed path's weight 1/q stays bounded (g → 1).
fn keep_probability<W: World>(
    at_x: Option<&super::medium::Medium<W::S, W::Region>>,
    importance: Option<<W::S as Space>::Vec>,
    dir: <W::S as Space>::Vec,
    c: f64,
) -> f64 {
    let (Some(m), Some(omega_o)) = (at_x, importance) else {
        return 1.0;
    };
    if c.is_nan() || c <= 0.0 || W::S::phase_g(&m.phase) == 0.0 {
        return 1.0;
    }
    let f = W::S::phase_eval(&m.phase, -dir, omega_o);
    let q = c * f * W::S::SPHERE_MEASURE;
    if q.is_finite() { q.clamp(1e-3, 1.0) } else { 1.0 }
}

/// Each medium sample's direction gradient (σ_s·`scale` applied) from its paths'
/// [`ScatteredSample`]s, the score term's baseline being the mean of the ray's other
/// paths (leave-one-out: independent of the path it serves, so unbiased). Without it
/// the score ∇ln f times a path's whole radiance made the gradients near x, where
/// the kernel's 1/r weighs most, 2× noisier in a furnace (2D, g = 0.6).
fn slopes_with_baseline<S: Dim>(
    scattered: &[(usize, ScatteredSample<S::Vec>)],
    samples: usize,
    scale: Rgb,
) -> Vec<[S::Vec; 3]> {
    let n = scattered.len();
    let total = scattered.iter().fold(Rgb::ZERO, |a, (_, p)| a + p.path);
    let mut out = vec![[S::zero(); 3]; samples];
    for (i, p) in scattered {
        let b = if n > 1 {
            (total - p.path) / (n - 1) as f64
        } else {
            Rgb::ZERO
        };
        for (c, v) in out[*i].iter_mut().zip(p.gradient(b)) {
            *c += v;
        }
    }
    for g in &mut out {
        for (c, k) in g.iter_mut().zip([scale.x, scale.y, scale.z]) {
            *c = *c * k;
        }
    }
    out
}

/// What an escaped probe ray carries, corrected for the proxy's homogeneous
/// transmittance model (zero where the correction is not representable).
fn escaped_radiance<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    dir: <W::S as Space>::Vec,
    length: f64,
    sigma_t_x: Rgb,
) -> Rgb {
    let sky = world.escaped_probe(dir);
    if sky == Rgb::ZERO {
        return Rgb::ZERO;
    }
    let t_true = world.transmittance(x, dir, world.world_exit(x, dir));
    sky * true_over_model(t_true, sigma_t_x, length)
}

/// T_true(x → x + t·dir) / exp(−σ_t(x)·t): what makes the proxy's homogeneous
/// transmittance give the true one (zero where that is not representable).
fn model_correction<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    dir: <W::S as Space>::Vec,
    t: f64,
    sigma_t_x: Rgb,
) -> Rgb {
    true_over_model(world.transmittance(x, dir, t), sigma_t_x, t)
}

/// `t_true` / exp(−σ_t(x)·t), zero where the model's transmittance underflows.
fn true_over_model(t_true: Rgb, sigma_t_x: Rgb, t: f64) -> Rgb {
    let t_model = (-sigma_t_x * t).exp();
    Rgb::select(t_model.cmpgt(Rgb::splat(1e-200)), t_true / t_model, Rgb::ZERO)
}
