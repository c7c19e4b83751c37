//! Derivative methods for L_s at a medium point (theory.md §4–5), per part (direct:
//! delta lights; single: light from surfaces and the sky; multiple: light from the
//! medium), in any dimension:
//! - [`aware`]: value, gradient and Hessian from the occlusion-free proxy elements
//!   (the paper's method, [`super::proxy`]);
//! - [`unaware`]: value and gradient as Jarosz et al. 2008 (directions and the
//!   along-ray parametrisation fixed, visibility and measure ignored);
//! - [`reference`]: central finite differences of the path-traced L_s with common
//!   random numbers (the same streams at every stencil point);
//! - [`plain_estimate`]: the light field's Monte Carlo estimate (theory.md §3).

use super::dim::Dim;
use super::path::{Estimate, Parts, Query, Settings, estimate};
use super::probe::{Angular, LightField, MediumSample, Outgoing, ProbeRay};
use super::proxy::{Element, ElementKind, Proxy, RadianceRule};
use super::proxy_cut::{corner_at, corner_on_line};
use super::slide;
use super::world::{DirectLight, World};
use crate::core::color::{Rgb, luminance};
use crate::core::distance::distance;
use crate::core::element::{medium_form_factor_smoothed, medium_softening, near_distance};
use crate::core::metric::hessian_radiance_floor;
use crate::core::phase_patch::{Resolution, TURN_CLOSE};
use crate::core::space::Space;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use crate::core::transmittance::{transmittance_taylor, transmittance_taylor_rgb};
use crate::core::unaware::{UnawareRay, hit_distance_gradient};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// L_s with its derivatives, per part (theory.md §2).
pub type PartDerivs<S> = crate::core::taylor_rgb::PartDerivs<S>;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Occlusion-aware value, gradient and Hessian from proxy elements (ours).
    Aware,
    /// Occlusion-unaware value and gradient (Jarosz et al. 2008).
    Unaware,
    /// Central finite differences of path-traced L_s with common random numbers.
    Reference,
}

/// A method's answer at one point and what it cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Derivatives<S: Dim> {
    pub method: Method,
    pub at: S::Vec,
    pub parts: PartDerivs<S>,
    /// False for first-order methods (the Hessian fields are zero).
    pub has_hessian: bool,
    pub rays: u64,
    pub seconds: f64,
}

/// Settings of the occlusion-aware method.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AwareSettings {
    pub rule: RadianceRule,
    /// Near-field clamp of medium elements' form-factor derivatives, in units of
    /// the march step Δt.
    pub medium_clamp: f64,
    /// Integrate the phase (with the transmittance) over the surface elements it
    /// turns within (3D: `core::phase_patch`) instead of taking it at each element's
    /// anchor. On by default: at g = 0.99 aimed into an emitter it takes the
    /// gradient from 1000× to 1% off (`tests/forward_scattering_3d.rs`), at g = 0.7
    /// and 256 directions the Hessian's p90 from 8.6× to 0.95×; it costs ≈ 2–4% of
    /// a record on lamp_fog.json (g = 0.8, 4096 directions) and bounds its pieces by
    /// the probe's size. Off reproduces the anchor rule that the moments over ω_o
    /// (`moments_sum`) use, whose smooth basis functions it cannot split.
    pub lobe_integral: bool,
    /// Take f·T over the directions of 3D surface elements seen at a grazing
    /// angle or close to x ([`slide::mean_over_directions`]) instead of at their
    /// centroid. On by default: below an emitter it bounds the gradient's error
    /// next to the surface (σ_s = 1, g = 0.6: 21× → 10% at d = 1e-6,
    /// `tests/near_surface_3d.rs`). Off reproduces the centroid rule that the
    /// moments over ω_o (`moments_sum`) use.
    pub direction_mean: bool,
}

impl Default for AwareSettings {
    fn default() -> Self {
        AwareSettings {
            rule: RadianceRule::Farther,
            medium_clamp: 1.0,
            lobe_integral: true,
            direction_mean: true,
        }
    }
}

/// The direct part (delta lights) with closed-form derivatives, visibility fixed.
/// Transmittance uses the effective extinction −ln T / depth of the stored value
/// (exact for a homogeneous medium along the whole way, and for partial regions
/// whose boundary does not move with x).
pub fn direct_derivatives<S: Dim>(lf: &LightField<S>) -> TaylorRgb<S> {
    let x = lf.x;
    let mut sum = TaylorRgb::default();
    let n = (S::DIM - 1) as f64;
    for l in &lf.direct_lights {
        match *l {
            DirectLight::Point {
                position,
                intensity,
                transmittance,
            } => {
                // I·T/r^{d−1}: 1/r (2D) or 1/r² (3D).
                let r = S::length(position - x).max(1e-300);
                let phase = lf.angular_towards(x, position, 0.0);
                let h = r.powi(-(S::DIM as i32 - 1));
                let falloff = distance::<S>(x, position, 0.0).compose(h, -n * h / r, n * (n + 1.0) * h / (r * r));
                let t = [0, 1, 2].map(|c| {
                    let tr = transmittance[c];
                    if tr > 0.0 {
                        transmittance_taylor::<S>(-tr.ln() / r, x, position, 0.0)
                    } else {
                        Taylor2::zero()
                    }
                });
                sum += TaylorRgb::tint(phase * falloff, intensity * lf.sigma_s).mul_channels(t);
            }
            DirectLight::Directional {
                to_light,
                irradiance,
                depth,
                depth_grad,
                transmittance,
            } => {
                let f = lf.angular_fixed(x, to_light);
                let t = [0, 1, 2].map(|c| {
                    let tr = transmittance[c];
                    let sig = if tr > 0.0 && depth > 0.0 { -tr.ln() / depth } else { 0.0 };
                    Taylor2::new(
                        tr,
                        depth_grad * (-sig * tr),
                        S::outer(depth_grad, depth_grad) * (sig * sig * tr),
                    )
                });
                sum += TaylorRgb::tint(f, irradiance * lf.sigma_s).mul_channels(t);
            }
        }
    }
    sum
}

/// The light a surface element sends to x, T L F (no phase, no σ_s), with
/// derivatives. (Medium elements: [`medium_shell_contribution`], and bridging
/// shell pieces beyond the near field the end of [`element_contribution`].)
pub fn element_incident<S: Dim>(lf: &LightField<S>, e: &Element<S>) -> TaylorRgb<S> {
    debug_assert_eq!(e.kind, ElementKind::Surface);
    let soft = near_distance(e.size());
    // The angle (solid angle), unclamped. Every vertex is a ray's end or a
    // silhouette, never nearer than the nearest surface, and the elements' vertex
    // terms cancel in pairs along a chain only if each vertex is treated alike in
    // both; a clamp scaled by each element's size broke that next to surfaces (a
    // long silhouette element clamped a near vertex its short neighbour did not:
    // gradient 26× off at 1e-5 from an emitter).
    let form = surface_form_factor(lf, e);
    TaylorRgb::tint(form, e.radiance).mul_channels(transmittance_taylor_rgb::<S>(lf.sigma_t, lf.x, e.anchor, soft))
}

/// A surface element's angle (solid angle) from x, unclamped, with its
/// derivatives; where a vertex is a corner sliding along a near silhouette
/// ([`super::proxy_cut::Corner`]), they follow the slide: central differences of
/// the closed form with the vertex placed anew at each x (the step far below the
/// element's distance, O(h²) ≈ 1e-8 relative).
fn surface_form_factor<S: Dim>(lf: &LightField<S>, e: &Element<S>) -> Taylor2<S> {
    let fixed = || S::form_factor_clamped(e.v, lf.x, 0.0);
    let Some(corner) = e.corner else { return fixed() };
    let v = e.v.as_ref();
    let Some(q) = corner_at::<S>(&corner, lf.x) else {
        return fixed();
    };
    let k = (0..v.len())
        .min_by(|&i, &j| S::length(v[i] - q).total_cmp(&S::length(v[j] - q)))
        .expect("a simplex has vertices");
    let near = v.iter().map(|&p| S::length(p - lf.x)).fold(f64::INFINITY, f64::min);
    let h = 1e-4 * near;
    let [ff] = Taylor2::central_differences_compact(
        |xp| {
            let moved = S::simplex(|i| {
                if i == k {
                    corner_on_line::<S>(&corner, xp).unwrap_or(v[k])
                } else {
                    v[i]
                }
            });
            [S::form_factor_clamped(moved, xp, 0.0).value]
        },
        lf.x,
        h,
    );
    ff
}

/// A 3D surface element whose farthest vertex is this much farther from x than its
/// nearest is seen at a grazing angle: it takes f·T over its directions
/// ([`slide::mean_over_directions`]) instead of at its centroid, and the lobe's
/// integral (whose pieces are integrated over their area, poor where 1/r³ varies
/// a thousandfold across a piece) leaves it alone.
const GRAZING_RATIO: f64 = 0.3;

/// The largest angular radius of an element, as a fraction of its angular
/// distance from the phase lobe's axis plus the lobe's width, for which
/// [`slide::mean_over_directions`]' seven directions resolve the lobe.
const MEAN_RESOLVES: f64 = 0.25;

/// A 3D surface element nearer x than this fraction of the probe's median ray
/// length takes f·T over its directions too. Why: the centroid rule's error is
/// second order in the element's angle, but differentiated it grows as 1/r, and
/// next to a surface every element is at r ≈ d: below an emitter at g = 0.6 the
/// gradient was 2% off at d = 1e-3, 19% at 1e-4, 21× at 1e-6 with the centroid
/// rule there, 1.2%, 7.7%, 10% with the mean (0.01 and 0.03 measured alike; the
/// mean costs ≈ 19 × 7 evaluations of f·T, so it is kept to where it matters).
const CLOSE_RATIO: f64 = 0.02;

/// One proxy element's contribution σ_s f T L F with its derivatives.
pub fn element_contribution<S: Dim>(lf: &LightField<S>, e: &Element<S>, settings: &AwareSettings) -> TaylorRgb<S> {
    let medium_clamp = settings.medium_clamp;
    let soft = near_distance(e.size());
    let s = lf.sigma_s;
    let times_sigma_s = |t: [Taylor2<S>; 3]| [t[0] * s.x, t[1] * s.y, t[2] * s.z];
    if e.kind == ElementKind::Surface {
        // 2D next to a surface, with a phase that turns: f·T integrated over the
        // segment with its derivatives at the ends (`core::segment_boundary`; the
        // product of the phase's closed form and the transmittance's mean missed
        // ∫ f T dθ on grazing segments: 10–12% off from d = 1e-5 to 1e-8).
        let v = e.v.as_ref();
        let (near, far) = v.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &q| {
            let r = S::length(q - lf.x);
            (lo.min(r), hi.max(r))
        });
        let close_2d = S::DIM == 2
            && near > 0.0
            && near < CLOSE_RATIO * lf.median_length
            && e.far_plane.is_none()
            && lf.angular == Angular::Phase
            && lf.g != 0.0
            && settings.lobe_integral;
        if close_2d {
            let sigma_t = [lf.sigma_t.x, lf.sigma_t.y, lf.sigma_t.z];
            // (No pieces in 2D: the segment's integral refines itself.)
            let res = Resolution {
                boundary: true,
                ..Resolution::at(0, near / lf.median_length)
            };
            if let Some(ft) = S::lobe_integral(lf.g, e.v, lf.x, lf.outgoing(), sigma_t, res) {
                return TaylorRgb::tint(Taylor2::constant(1.0), e.radiance).mul_channels(times_sigma_s(ft));
            }
        }
        // Where the phase integrates in closed form over the element (2D), it does:
        // a lobe narrower than the element (g → ±1) is then exact.
        if let Some(pw) =
            S::phase_weighted_form(lf.g, e.v, lf.x, lf.outgoing()).filter(|_| lf.angular == Angular::Phase)
        {
            let t = match e.far_plane {
                Some(plane) => slide::vertex_rule(lf, e, plane, soft, false),
                None if v.len() == 2 && lf.sigma_t.max_element() > 0.0 => slide::transmittance_mean(lf, v[0], v[1]),
                None => transmittance_taylor_rgb::<S>(lf.sigma_t, lf.x, e.anchor, soft),
            };
            return TaylorRgb::tint(pw, e.radiance).mul_channels(times_sigma_s(t));
        }
        // 3D pieces of one surface seen at a grazing angle, or close to x, whose
        // f·T is taken over their directions (below).
        let grazing = v.len() == 3 && far > (1.0 + GRAZING_RATIO) * near && e.far_plane.is_none();
        // A grazing element within which the lobe turns little takes the mean; one
        // the lobe is narrow against (g → ±1) still needs the lobe's integral. A
        // close one takes the lobe's integral in its edge form whenever g ≠ 0
        // (below), grazing or not: the edge terms cancel only between elements
        // that all use it (with grazing close elements on the mean, g = 0.6
        // below an emitter kept a Hessian error growing as 1/d: 2.4% at 1e-6).
        let close = v.len() == 3 && near < CLOSE_RATIO * lf.median_length && e.far_plane.is_none();
        let mean_first = grazing && !close && slide::lobe_resolved(lf, v, MEAN_RESOLVES);
        // A lobe narrower than the element (3D, g → ±1) is not sampled at one point:
        // the element is split where the lobe turns within it and f·T integrated
        // over the pieces (`core::phase_patch`; T too: it turns across the element
        // as much as the lobe's place in it does).
        if settings.lobe_integral && e.far_plane.is_none() && lf.angular == Angular::Phase && !mean_first {
            let sigma_t = [lf.sigma_t.x, lf.sigma_t.y, lf.sigma_t.z];
            // At most a quarter as many pieces per element as the probe has
            // directions, so the integral's cost follows the probe's: a 32-direction
            // probe at g = 0.999 split its elements into ≈ 3000 pieces each and ran
            // 30× slower (`tests/extreme_grid.rs`); 4096 directions at g = 0.99 need
            // ≈ 500 around the lobe's axis.
            let max_pieces = (lf.rays.len() / 4).clamp(16, 1024);
            // Next to a surface the derivatives take the edge form (see
            // `core::lobe_boundary`; a vertex at x itself keeps the area rule).
            let closeness = near / lf.median_length;
            let res = Resolution {
                boundary: close && near > 0.0,
                turn_by_edges: close && near > 0.0 && closeness < TURN_CLOSE,
                ..Resolution::at(max_pieces, closeness)
            };
            if let Some(ft) = S::lobe_integral(lf.g, e.v, lf.x, lf.outgoing(), sigma_t, res) {
                return TaylorRgb::tint(Taylor2::constant(1.0), e.radiance).mul_channels(times_sigma_s(ft));
            }
        }
        if let Some(plane) = e.far_plane {
            // An occlusion boundary: f·T by the vertex rule with the near vertices
            // sliding on the far surface (see `slide`).
            let ft = slide::vertex_rule(lf, e, plane, soft, true);
            return TaylorRgb::tint(surface_form_factor(lf, e), e.radiance).mul_channels(times_sigma_s(ft));
        }
        // f·T over the directions of a grazing or close piece, not at its centroid.
        let varies = lf.sigma_t.max_element() > 0.0 || !lf.angular_is_constant();
        let moment = matches!(lf.angular, Angular::Moment(_));
        // (A vertex at x itself, a point on a surface, keeps the centroid rule:
        // its directions are undefined.)
        if settings.direction_mean && (grazing || close) && varies && !moment && near > 0.0 {
            let ft = slide::mean_over_directions(lf, v);
            return TaylorRgb::tint(surface_form_factor(lf, e), e.radiance).mul_channels(times_sigma_s(ft));
        }
    }
    if let Some(c) = medium_shell_contribution(lf, e, medium_clamp) {
        return c.mul_channels(times_sigma_s([Taylor2::constant(1.0); 3]));
    }
    let phase = lf.angular_towards(lf.x, e.anchor, soft);
    if e.kind == ElementKind::Surface {
        return element_incident(lf, e).mul_channels(times_sigma_s([phase; 3]));
    }
    // A bridging shell piece beyond the near field: its kernel σ_s f T F once (F
    // the angle or solid angle; the thickness Δt is in the piece's radiance), the
    // light it carries twice. Its value and Hessian carry its samples' weight
    // (`radiance`); its gradient (what its edges reveal or hide as x moves) the
    // light next to the edge (`revealed`, when the proxy found one). With the
    // weight, the gradient under a box's edge was 0.59 of the converged
    // reference. (The gradients of T and f follow the revealed light too; beside
    // the form factor's, which moves with the edge, they are small.) The Hessian
    // with the revealed light was not adopted: nothing checks the multiple part's
    // Hessian against a reference, and the caches it shapes got worse — relMSE
    // 0.047 → 0.062 and 0.069 → 0.109 in tests/gradient_noise.rs, 3D
    // fog_box.json's medium RMSE up to 1.11×. With the gradient alone: 2D shipped
    // scenes within ±1.5% (one run of shaded_lamp.json 1.46×, its reference as
    // noisy as the error), 3D fog_box.json and lamp_fog.json 1.01–1.04× (issue
    // 16's extrapolation).
    let kernel = TaylorRgb::tint(S::form_factor(e.v, lf.x), Rgb::ONE)
        .mul_channels(transmittance_taylor_rgb::<S>(lf.sigma_t, lf.x, e.anchor, soft))
        .mul_channels(times_sigma_s([phase; 3]));
    let weight = [e.radiance.x, e.radiance.y, e.radiance.z];
    let shown = e.revealed.unwrap_or(e.radiance);
    let shown = [shown.x, shown.y, shown.z];
    // Its samples' light turns with the direction x sees them from, as in
    // `medium_point`: K·∇_ωL·∇_x ω, whatever light the gradient carries.
    let slope = bridging_slope(lf, e);
    let mut c = kernel;
    for (((ch, k), (w, l)), g) in c
        .channels
        .iter_mut()
        .zip(kernel.channels)
        .zip(weight.into_iter().zip(shown))
        .zip(slope)
    {
        *ch = k * w;
        ch.grad = k.grad * l + turning::<S>(lf.x, e.anchor, g, k.value);
    }
    c
}

/// K·∇_ωL·∇_x ω for light L seen from x at `p` with direction gradient `slope`
/// and kernel value `k` (∇_x ω = −(I − ωωᵀ)/r).
pub(super) fn turning<S: Dim>(x: S::Vec, p: S::Vec, slope: S::Vec, k: f64) -> S::Vec {
    let r = S::length(p - x);
    if r <= 0.0 {
        return S::zero();
    }
    let w = (p - x) / r;
    // Only the slope's part across ω turns (it is tangent already, up to rounding).
    (slope - w * S::dot(slope, w)) * (-k / r)
}

/// The phase towards `c` softened at a = 2ε within a of x, exact beyond 2a, and
/// blended smoothly (C², quintic smootherstep in the distance) in between.
/// Softening it everywhere bent a strong lobe far away (at g = 0.9 a lobe softened
/// at ε is ≈ 10× lower at 3ε), and the shells' flux at the walls then missed the
/// surfaces' exact one. The radius was measured in a furnace at g = ±0.9 (4 seeds,
/// 3 points per dimension): a = ε left the Hessians 3× noisier, a = 4ε bent the
/// lobe at walls 0.4 away (a false gradient of 0.6·L_s per unit length).
/// `exact` is the phase towards `c` softened only at `soft` (the caller has it).
fn near_field_phase<S: Dim>(lf: &LightField<S>, c: S::Vec, soft: f64, eps: f64, exact: Taylor2<S>) -> Taylor2<S> {
    let x = lf.x;
    let a = 2.0 * eps;
    let r = S::length(c - x);
    let smooth = || lf.angular_towards(x, c, a.max(soft));
    if lf.angular_is_constant() || r >= 2.0 * a {
        return exact;
    }
    if r <= a {
        return smooth();
    }
    // w = smootherstep((r − a)/a): 0 at a, 1 at 2a, with zero first and second
    // derivatives at both ends.
    let s = (r - a) / a;
    let w = s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
    let dw = 30.0 * s * s * (1.0 - s) * (1.0 - s) / a;
    let d2w = 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s) / (a * a);
    let w = distance::<S>(x, c, 0.0).compose(w, dw, d2w);
    let (e, m) = (exact, smooth());
    m + w * (e - m)
}

/// An ordinary shell piece's f·T·L·F (no σ_s) — `None` for surfaces and for
/// bridging pieces outside the near field.
///
/// Its derivatives are those of one kernel smoothed at the march resolution ε,
/// phase included: f_ε·T·m/r_ε^{d−1} with r_ε = √(r² + ε²) and f_ε the phase
/// softened near x ([`near_field_phase`]).
/// Summed over the shells around x, the exact kernel's gradient is only a principal
/// value: the ball of radius ε around x leaves the term −L(x)∫f(ω)ω dω (the phase's
/// mean cosine, ∝ g along ω_o) that the smoothed form factor alone did not cancel.
/// In a furnace (L_s constant) at g = 0.6 that was a false gradient ≈ g·L_s; the
/// smoothed kernel is integrable with its derivatives, so the shells' sum tends to
/// the true one. The value stays the exact f·T·F.
fn medium_shell_contribution<S: Dim>(lf: &LightField<S>, e: &Element<S>, medium_clamp: f64) -> Option<TaylorRgb<S>> {
    if e.kind != ElementKind::Medium {
        return None;
    }
    let x = lf.x;
    let nearest =
        e.v.as_ref()
            .iter()
            .map(|&p| S::length(p - x))
            .fold(f64::INFINITY, f64::min);
    if e.bridging && nearest >= medium_clamp * lf.march.thickness_at(nearest) {
        return None;
    }
    // A piece is its samples, each with 1/d of its measure: each ray's samples are
    // jittered uniformly along it, so their sum integrates any kernel without bias
    // (a piece's centroid is not uniformly jittered: the mean of d offsets).
    let soft = near_distance(e.size());
    if e.bridging {
        let light = (e.radiance, bridging_slope(lf, e));
        return Some(medium_point(lf, e.anchor, e.dir_measure, light, soft, medium_clamp));
    }
    let share = e.dir_measure / S::DIM as f64;
    let mut sum = TaylorRgb::<S>::default();
    for m in element_samples(lf, e).filter(|m| m.light != Rgb::ZERO) {
        sum += medium_point(lf, m.at, share, (m.light, m.slope), soft, medium_clamp);
    }
    Some(sum)
}

/// A medium element's vertices' samples (those present: a ray that ended before
/// the shell has none).
fn element_samples<'a, S: Dim>(lf: &'a LightField<S>, e: &'a Element<S>) -> impl Iterator<Item = MediumSample<S>> + 'a {
    let shell = e.shell;
    e.rays
        .as_ref()
        .iter()
        .filter_map(move |&j| shell.and_then(|i| lf.medium_sample(j as usize, i as usize)))
}

/// One medium point's f·T·L·F (no σ_s; `radiance` carries its thickness Δt), with
/// the exact value, the gradient of the kernel smoothed at ε = medium_clamp × the
/// march's first step (at most [`GRADIENT_SMOOTHING_CAP`] of the even step), and
/// the Hessian of the kernel smoothed at medium_clamp × its even step. Each scale
/// is one constant per light field, so that each is the derivative of one kernel
/// (a scale following the local Δt is not: its own derivative is missing, and at
/// k = 6 the phase's mean-cosine term came back, 1.5·L_s along ω_o in a furnace at
/// g = 0.6).
///
/// Why two scales: with the march refined towards x ([`super::probe::March`]), the
/// gradient's kernel (∝ 1/r^d, log-singular over a sharp feature) wants the fine
/// steps there, while the Hessian's (∝ 1/r^{d+1}) only turns them into noise:
/// ‖H‖/L_s 150–3700 in a furnace (zero) at k = 6–9, against 0.2–0.6 when smoothed at
/// the even step as before.
///
/// `light` is the point's radiance and its gradient with respect to the direction
/// it is seen from (per channel): x sees p along ω = (p − x)/r, which turns as x
/// moves (∇_x ω = −(I − ωωᵀ)/r), so K·L gains K·∇_ωL·∇_x ω, with K the gradient's
/// smoothed kernel (the derivative of the whole smoothed term, as the kernel's
/// own part is).
fn medium_point<S: Dim>(
    lf: &LightField<S>,
    p: S::Vec,
    dir_measure: f64,
    (radiance, slope): (Rgb, [S::Vec; 3]),
    soft: f64,
    medium_clamp: f64,
) -> TaylorRgb<S> {
    let x = lf.x;
    let r = S::length(p - x);
    let t = transmittance_taylor_rgb::<S>(lf.sigma_t, x, p, soft);
    // The exact phase, once: the value's, and the kernels' beyond their near field.
    let phase = lf.angular_towards(x, p, soft);
    let local = lf.march.thickness_at(r);
    let kernel = |scale: f64| smoothed_kernel(lf, p, dir_measure, soft, phase, local, medium_clamp * scale);
    let (fine, even) = smoothing_scales(&lf.march);
    let fine_kernel = kernel(fine);
    let mut c = TaylorRgb::tint(fine_kernel, radiance).mul_channels(t);
    for ((ch, tc), g) in c.channels.iter_mut().zip(&t).zip(slope) {
        ch.grad += turning::<S>(x, p, g, fine_kernel.value * tc.value);
    }
    // Beyond HESSIAN_SCALE_REACH smoothing lengths the two kernels' Hessians differ
    // by < 0.1% ((ε/r)²; the phase is exact beyond 4ε): one evaluation is enough.
    if even > fine && r < HESSIAN_SCALE_REACH * medium_clamp * even {
        let coarse = TaylorRgb::tint(kernel(even), radiance).mul_channels(t);
        for (ch, h) in c.channels.iter_mut().zip(coarse.channels) {
            ch.hess = h.hess;
        }
    }
    // The exact value.
    let exact = dir_measure * phase.value;
    for (ch, (tc, rad)) in c
        .channels
        .iter_mut()
        .zip(t.iter().zip([radiance.x, radiance.y, radiance.z]))
    {
        ch.value = exact * tc.value * rad;
    }
    c
}

/// A bridging medium piece's direction gradient: its samples' sum over the vertex
/// count, as its radiance ([`super::proxy`]).
fn bridging_slope<S: Dim>(lf: &LightField<S>, e: &Element<S>) -> [S::Vec; 3] {
    let mut sum = [S::zero(); 3];
    for m in element_samples(lf, e) {
        for (c, v) in sum.iter_mut().zip(m.slope) {
            *c += v;
        }
    }
    sum.map(|v| v / S::DIM as f64)
}

/// See [`medium_point`].
pub(super) const HESSIAN_SCALE_REACH: f64 = 32.0;

/// The gradient's smoothing length is at most this fraction of the even step (times
/// `medium_clamp`). An even march (3D's default) has its first step as long as the
/// others, and a kernel smoothed over a whole step drops the near field's share of
/// ∇L_ms (∝ ε·∇L_s): against converged finite-difference references (12 points in
/// tests/anisotropic_multiple_scattering.rs's 3D room, seeds 5–8, 4096 directions)
/// the median vector error was 0.39 at 1× the step (lengths 0.34–0.62 of the
/// reference), 0.15 at 0.3×, 0.18 at 0.1×, 0.31 at 0.03× (noise, two sign errors);
/// a march graded at k = 6, whose first step is 0.015× the even one, gave 0.11 at
/// 1.7× the probe's time. Graded marches (2D's default) are unaffected. In 3D
/// caches (4096 directions, 64² pixels, against a build without the cap) the
/// medium's RMSE was within ±3% on fog_box.json (three seeds) and staircase.json
/// (one), but 4–13% higher on lamp_fog.json (g = 0.8, three seeds), 70% of the
/// squared error in the 1% of pixels around
/// the lamp, where longer gradients extrapolate further across its peak (16384
/// directions without the cap gave the same rise): issue 16's extrapolation.
pub(super) const GRADIENT_SMOOTHING_CAP: f64 = 0.3;

/// The smoothing lengths of a medium point's kernel per `medium_clamp`: the
/// gradient's (the first step, capped) and the Hessian's (the even step).
pub(super) fn smoothing_scales(march: &super::probe::March) -> (f64, f64) {
    let even = march.even_step();
    (march.thickness_at(0.0).min(GRADIENT_SMOOTHING_CAP * even), even)
}

/// f_ε·F_ε/Δt of a medium point of thickness Δt (F = Ω r^{d−1} Δt / r_ε^{d−1}),
/// smoothed at ε = `smoothing` (or the piece's own size), value included; `phase`
/// is the exact phase towards p ([`near_field_phase`]).
fn smoothed_kernel<S: Dim>(
    lf: &LightField<S>,
    p: S::Vec,
    dir_measure: f64,
    soft: f64,
    phase: Taylor2<S>,
    step: f64,
    smoothing: f64,
) -> Taylor2<S> {
    let x = lf.x;
    let r = S::length(p - x);
    let n = S::DIM as i32 - 1;
    let measure = dir_measure * r.powi(n) * step;
    let eps = smoothing.max(medium_softening::<S>(measure));
    let form = Taylor2 {
        value: measure / (r * r + eps * eps).powf(0.5 * n as f64),
        ..medium_form_factor_smoothed::<S>(p, measure, x, smoothing)
    };
    form * near_field_phase(lf, p, soft, eps, phase) * (1.0 / step)
}

/// Elements summed per parallel task: the partial sums are added in a fixed order,
/// so the result is the same bit for bit whatever the thread count.
pub(super) const SUM_CHUNK: usize = 2048;

/// Ours: value, gradient and Hessian of L_s from the proxy elements.
pub fn aware<S: Dim>(lf: &LightField<S>, proxy: &Proxy<S>, settings: &AwareSettings) -> PartDerivs<S> {
    aware_with_floor(lf, proxy, settings, 0.0).0
}

/// [`aware`], and the same with [`hessian_radiance_floor`]`(floor_fraction)` added
/// to the radiance of every element (the metric's Hessian, theory.md §7; `None`
/// when nothing is added). The floor is not added to the shells' samples: a
/// uniformly lit medium has no curvature of its own away from surfaces, and on the
/// staircase (160×120, 4096 rays, ε = 0.69, cache seeds 1–3) flooring them too
/// placed 5–15% more records for a 4–16% higher medium RMSE (equal at ε = 0.15).
///
/// The shell pieces that bridge no occluder are summed per medium sample: a sample
/// is a vertex of every piece around its ray in its shell (six in 3D, two in 2D), and
/// evaluating it once with their shares of measure added (1/d of each, as each
/// piece's sum over its vertices gives it) costs a sixth (a half) of evaluating it
/// per piece; its smoothing distance is the pieces' sizes averaged by share.
pub fn aware_with_floor<S: Dim>(
    lf: &LightField<S>,
    proxy: &Proxy<S>,
    settings: &AwareSettings,
    floor_fraction: f64,
) -> (PartDerivs<S>, Option<PartDerivs<S>>) {
    let (plain, floored, _) = aware_with_noise(lf, proxy, settings, floor_fraction);
    (plain, floored)
}

/// [`aware_with_floor`], and the noise variance of the multiple part's luminance
/// gradient from its medium samples ([`neighbour_variance`] of the rays' shares;
/// the bridging elements' shares are not counted).
pub fn aware_with_noise<S: Dim>(
    lf: &LightField<S>,
    proxy: &Proxy<S>,
    settings: &AwareSettings,
    floor_fraction: f64,
) -> (PartDerivs<S>, Option<PartDerivs<S>>, f64) {
    let clamp = settings.medium_clamp;
    let floor = hessian_radiance_floor(proxy.radiance_sum, proxy.count, floor_fraction);
    let shares = &proxy.shares;
    let element_sums: Vec<Sums<S>> = proxy
        .chunks(SUM_CHUNK)
        .into_par_iter()
        .map(|chunk| {
            let mut sums = Sums::default();
            for e in chunk {
                if e.radiance != Rgb::ZERO {
                    sums.add(e.kind, false, element_contribution(lf, e, settings));
                }
                if let Some(f) = floor {
                    let floored = Element {
                        radiance: e.radiance + f,
                        revealed: e.revealed.map(|r| r + f),
                        ..*e
                    };
                    sums.add(e.kind, true, element_contribution(lf, &floored, settings));
                }
            }
            sums
        })
        .collect();
    let sigma_s = [lf.sigma_s.x, lf.sigma_s.y, lf.sigma_s.z].map(Taylor2::constant);
    let sample_sums: Vec<(Sums<S>, Vec<S::Vec>)> = lf
        .rays
        .par_chunks(RAY_CHUNK)
        .enumerate()
        .map(|(c, rays)| {
            let mut sums = Sums::default();
            let mut per_ray = Vec::with_capacity(rays.len());
            for (j, r) in (c * RAY_CHUNK..).zip(rays) {
                let before = sums.multiple.luminance().grad;
                for i in 0..r.samples.len() {
                    let Some((measure, size)) = shares.of(j, i) else {
                        continue;
                    };
                    let m = lf.medium_sample(j, i).expect("a shared sample is present");
                    if m.light == Rgb::ZERO {
                        continue;
                    }
                    let point = medium_point(lf, m.at, measure, (m.light, m.slope), near_distance(size), clamp);
                    let c = point.mul_channels(sigma_s);
                    sums.multiple += c;
                    // No floor here (see the doc above).
                    if floor.is_some() {
                        sums.floored_multiple += c;
                    }
                }
                per_ray.push(sums.multiple.luminance().grad - before);
            }
            (sums, per_ray)
        })
        .collect();
    let mut total = Sums::default();
    for s in element_sums {
        total += s;
    }
    let mut per_ray = Vec::with_capacity(lf.rays.len());
    for (s, g) in sample_sums {
        total += s;
        per_ray.extend(g);
    }
    let grad_var = neighbour_variance(lf, &per_ray, |a, b| S::length_squared(a - b));
    let direct = direct_derivatives(lf);
    let plain = PartDerivs {
        direct,
        single: total.single,
        multiple: total.multiple,
    };
    let floored = floor.map(|_| PartDerivs {
        direct,
        single: total.floored_single,
        multiple: total.floored_multiple,
    });
    (plain, floored, grad_var)
}

/// The variance of Σ_j g_j, the rays' shares of a gradient, from the differences
/// of neighbouring rays (the light field's simplices' edges): a stratified sum's
/// variance is the sum of its strata's, and two neighbours differ by their noise
/// (E|g_a − g_b|²/2 = their mean variance) plus the integrand's smooth change
/// across one stratum, which the estimate counts as noise (it errs high).
fn neighbour_variance<S: Dim, T: Copy>(
    lf: &LightField<S>,
    shares: &[T],
    squared_difference: impl Fn(T, T) -> f64,
) -> f64 {
    let (mut sum, mut edges) = (0.0, 0usize);
    for t in &lf.simplices {
        let v = t.as_ref();
        // A pair (2D) has one edge, a triangle (3D) three.
        let pairs = if v.len() == 2 { 1 } else { v.len() };
        for a in 0..pairs {
            let (i, j) = (v[a] as usize, v[(a + 1) % v.len()] as usize);
            if let (Some(&gi), Some(&gj)) = (shares.get(i), shares.get(j)) {
                sum += squared_difference(gi, gj) / 2.0;
                edges += 1;
            }
        }
    }
    if edges == 0 {
        0.0
    } else {
        shares.len() as f64 * sum / edges as f64
    }
}

/// The noise variance of the plain estimate's luminance of the scattered light
/// (single + multiple: what a record caches and takes as its value), from the
/// rays' shares of it ([`neighbour_variance`]; where neighbouring rays see
/// different things, an edge counts as noise).
pub fn scattered_value_variance<S: Dim>(lf: &LightField<S>) -> f64 {
    let measure = lf.ray_measure();
    let mut samples = Vec::new();
    let shares: Vec<f64> = lf
        .rays
        .iter()
        .map(|r| {
            let (mut single, mut multiple) = ([Taylor2::<S>::zero(); 3], [Taylor2::<S>::zero(); 3]);
            unaware_ray(lf, r, measure, &mut samples).accumulate(&mut single, &mut multiple);
            luminance(Rgb::from_array(std::array::from_fn(|c| {
                single[c].value + multiple[c].value
            })))
        })
        .collect();
    neighbour_variance(lf, &shares, |a, b| (a - b) * (a - b))
}

/// Rays summed per parallel task (see [`SUM_CHUNK`]).
pub(super) const RAY_CHUNK: usize = 64;

/// Per part sums of [`aware_with_floor`], plain and floored.
#[derive(Clone, Copy, Default)]
struct Sums<S: Dim> {
    single: TaylorRgb<S>,
    multiple: TaylorRgb<S>,
    floored_single: TaylorRgb<S>,
    floored_multiple: TaylorRgb<S>,
}

impl<S: Dim> Sums<S> {
    fn add(&mut self, kind: ElementKind, floored: bool, c: TaylorRgb<S>) {
        match (kind, floored) {
            (ElementKind::Surface, false) => self.single += c,
            (ElementKind::Medium, false) => self.multiple += c,
            (ElementKind::Surface, true) => self.floored_single += c,
            (ElementKind::Medium, true) => self.floored_multiple += c,
        }
    }
}

impl<S: Dim> std::ops::AddAssign for Sums<S> {
    fn add_assign(&mut self, o: Self) {
        self.single += o.single;
        self.multiple += o.multiple;
        self.floored_single += o.floored_single;
        self.floored_multiple += o.floored_multiple;
    }
}

/// Jarosz et al. 2008: each ray's direction and its samples' relative position along
/// the ray fixed; the hit point slides on the hit surface's tangent, so only the
/// transmittance (through the distance s to the surface) changes: ∇s = −n/(n·ω).
/// Medium samples sit at fixed fractions u of s, with thickness Δu·s. Escaped rays
/// have a fixed length. The measure and visibility are treated as constant. First
/// order only.
pub fn unaware<S: Dim>(lf: &LightField<S>) -> PartDerivs<S> {
    let measure = lf.ray_measure();
    let (mut single, mut multiple) = ([Taylor2::<S>::zero(); 3], [Taylor2::<S>::zero(); 3]);
    let mut samples = Vec::new();
    for r in &lf.rays {
        unaware_ray(lf, r, measure, &mut samples).accumulate(&mut single, &mut multiple);
    }
    let mut direct = direct_derivatives(lf);
    for ch in &mut direct.channels {
        ch.hess = S::zero_mat();
    }
    PartDerivs {
        direct,
        single: TaylorRgb { channels: single },
        multiple: TaylorRgb { channels: multiple },
    }
}

/// A ray's medium samples as [`UnawareRay`] takes them: depth, light and thickness.
pub(super) fn fill_ray_samples<S: Dim>(lf: &LightField<S>, r: &ProbeRay<S>, samples: &mut Vec<(f64, Rgb, f64)>) {
    samples.clear();
    samples.extend(
        r.samples
            .iter()
            .enumerate()
            .map(|(i, l)| (lf.sample_depth(r, i), *l, lf.sample_thickness(r, i))),
    );
}

/// One ray of [`unaware`] (`samples`: a buffer for its samples' depth, light and
/// thickness).
fn unaware_ray<'a, S: Dim>(
    lf: &LightField<S>,
    r: &ProbeRay<S>,
    measure: f64,
    samples: &'a mut Vec<(f64, Rgb, f64)>,
) -> UnawareRay<'a, S> {
    fill_ray_samples(lf, r, samples);
    let f = lf.angular_fixed(lf.x, r.dir);
    UnawareRay::<S> {
        sigma_t: lf.sigma_t,
        weight: lf.sigma_s * (f.value * measure),
        weight_log_grad: if f.value > 0.0 { f.grad / f.value } else { S::zero() },
        grad_s: r.hit.map_or(S::zero(), |h| hit_distance_gradient::<S>(h.normal, r.dir)),
        length: r.length,
        end_radiance: r.hit.map_or(r.escaped, |h| h.radiance),
        samples,
    }
}

/// The plain Monte Carlo estimate of L_s from the light field, per part.
pub fn plain_estimate<S: Dim>(lf: &LightField<S>) -> Parts {
    let p = unaware(lf);
    Parts {
        direct: p.direct.value(),
        single: p.single.value(),
        multiple: p.multiple.value(),
    }
}

/// `parts` with the light field's plain estimate as their values (a record's
/// value: unbiased, whatever the method's derivatives).
pub fn with_plain_values<S: Dim>(parts: PartDerivs<S>, lf: &LightField<S>) -> PartDerivs<S> {
    with_values(parts, plain_estimate(lf).as_array())
}

/// `parts` with `values` (direct, single, multiple) as their values.
pub fn with_values<S: Dim>(mut parts: PartDerivs<S>, values: [Rgb; 3]) -> PartDerivs<S> {
    for (part, value) in [&mut parts.direct, &mut parts.single, &mut parts.multiple]
        .into_iter()
        .zip(values)
    {
        for (c, ch) in part.channels.iter_mut().enumerate() {
            ch.value = value[c];
        }
    }
    parts
}

/// Finite-difference reference settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReferenceSettings {
    /// Samples per stencil point.
    pub spp: u32,
    /// Step h as a fraction of the scene size.
    pub relative_step: f64,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            spp: 20_000,
            relative_step: 4e-3,
        }
    }
}

/// Central differences of the path-traced L_s at x, per part: ±h on each axis for
/// the gradient (and the diagonal of the Hessian), and with `hessian` the four
/// diagonal points of each pair of axes for the mixed terms; every point with the
/// same random streams. With ω_o turning towards a point, each stencil point
/// scatters towards it (the derivative of what a camera sees).
#[allow(clippy::too_many_arguments)] // the stencil's inputs are spelled out
pub fn reference<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    out: Outgoing<<W::S as Space>::Vec>,
    h: f64,
    spp: u32,
    settings: &Settings,
    seed: u64,
    hessian: bool,
) -> Derivatives<W::S> {
    type S<W> = <W as World>::S;
    let start = std::time::Instant::now();
    // Independent samples: the reference states its standard errors (the app's
    // noise flags, the studies' bounds), which a stratified set would overstate.
    let settings = &Settings {
        sampling: super::path::Sampling::Independent,
        ..*settings
    };
    let d = S::<W>::DIM;
    let e = |i: usize| S::<W>::axis(i);
    let mut offsets = vec![S::<W>::zero()];
    for i in 0..d {
        offsets.extend([e(i), -e(i)]);
    }
    if hessian {
        for i in 0..d {
            for j in i + 1..d {
                offsets.extend([e(i) + e(j), e(i) - e(j), -e(i) + e(j), -e(i) - e(j)]);
            }
        }
    }
    let est: Vec<Estimate> = offsets
        .par_iter()
        .map(|&o| {
            let p = x + o * h;
            let omega_o = match out {
                Outgoing::Direction(w) => w,
                Outgoing::TowardsPoint(eye) => {
                    let v = eye - p;
                    let l = S::<W>::length(v);
                    if l > 0.0 { v / l } else { S::<W>::axis(0) }
                }
            };
            estimate(world, p, &Query::InScattered { omega_o }, settings, spp, seed, 0)
        })
        .collect();
    let part = |get: &dyn Fn(&Estimate) -> Rgb| -> TaylorRgb<S<W>> {
        let v: Vec<Rgb> = est.iter().map(get).collect();
        let channel = |c: usize| {
            let f = |k: usize| v[k][c];
            let (mut grad, mut hess) = (S::<W>::zero(), S::<W>::zero_mat());
            let mut k = 1 + 2 * d;
            for i in 0..d {
                let (p, m) = (f(1 + 2 * i), f(2 + 2 * i));
                grad += e(i) * ((p - m) / (2.0 * h));
                hess += S::<W>::outer(e(i), e(i)) * ((p - 2.0 * f(0) + m) / (h * h));
                for j in (i + 1..d).filter(|_| hessian) {
                    let hij = (f(k) - f(k + 1) - f(k + 2) + f(k + 3)) / (4.0 * h * h);
                    hess += (S::<W>::outer(e(i), e(j)) + S::<W>::outer(e(j), e(i))) * hij;
                    k += 4;
                }
            }
            if !hessian {
                hess = S::<W>::zero_mat();
            }
            Taylor2::new(f(0), grad, hess)
        };
        TaylorRgb {
            channels: [channel(0), channel(1), channel(2)],
        }
    };
    Derivatives {
        method: Method::Reference,
        at: x,
        parts: PartDerivs {
            direct: part(&|e| e.mean.direct),
            single: part(&|e| e.mean.single),
            multiple: part(&|e| e.mean.multiple),
        },
        has_hessian: hessian,
        rays: est.iter().map(|e| e.rays).sum(),
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// [`reference`] with the step and samples of `rs` (h relative to the scene size),
/// Hessian included.
pub fn reference_at<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    out: Outgoing<<W::S as Space>::Vec>,
    rs: &ReferenceSettings,
    settings: &Settings,
    seed: u64,
) -> Derivatives<W::S> {
    reference(
        world,
        x,
        out,
        rs.relative_step * world.scale(),
        rs.spp,
        settings,
        seed,
        true,
    )
}
