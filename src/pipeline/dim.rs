//! What the method needs of a dimension beyond the core's vector algebra
//! ([`Space`]): the phase function and Lambertian sampling of that dimension, its
//! direction sets (a stratified circle with its neighbours, a spherical Fibonacci set
//! with its spade triangulation) and the proxy's simplices (a segment in 2D, a
//! triangle in 3D) with their form factors. Implemented by the markers
//! [`D2`] and [`D3`]; everything above is written once over `S: Dim`.
//!
//! Random numbers: each sampling routine draws what its dimension needs (one number
//! for a direction on the circle, two on the sphere), so a path's stream is the same
//! whichever code asks for the direction.

use super::directions;
use crate::core::element::{segment_form_factor, segment_form_factor_clamped};
use crate::core::phase::{Hg2, Hg3, Outgoing};
use crate::core::phase_arc::phase_weighted_angle;
use crate::core::phase_patch::{Resolution, lobe_integral};
use crate::core::rng::Sampler;
use crate::core::segment_boundary::segment_lobe_integral;
use crate::core::space::{D2, D3, Space};
use crate::core::taylor::Taylor2;
use crate::core::triangle::{triangle_form_factor, triangle_form_factor_clamped};
use glam::{DVec2, DVec3};
use serde::Serialize;
use std::f64::consts::{FRAC_1_PI, TAU};
use std::fmt::Debug;

/// What a [`Dim::Simplex`] can hold.
pub trait Element: Copy + Debug + PartialEq + Send + Sync + Serialize {}
impl<T: Copy + Debug + PartialEq + Send + Sync + Serialize> Element for T {}

/// A dimension the method runs in.
pub trait Dim: Space<Vec: Serialize + Default> {
    /// Directions per cache record by default: the angular resolution at which more
    /// rays stop lowering a record's error at equal cost (see `ProbeSettings`).
    const PROBE_RAYS: usize;
    /// Default refinement of a probe's march towards x (`probe::March`), measured
    /// per dimension.
    const PROBE_GRADING: f64;
    /// The BVH's leaves (`bvh_build`): (a node of at most this many primitives is
    /// a leaf, a node of more than this many is split; in between the SAH decides).
    /// Measured per dimension: a segment test is a few multiplications, a
    /// triangle's many more, against the same box tests of a node.
    const BVH_LEAF: (usize, usize);
    /// Up to this many primitives a flat list answers ray queries, above it the
    /// BVH (`pipeline::bvh::Geometry::new`).
    const FLAT_LIST_MAX: usize;
    /// The Henyey–Greenstein phase function of this dimension.
    type Phase: Copy + Debug + PartialEq + Send + Sync;
    /// `DIM` values: the vertices of a proxy element (segment or triangle), or the
    /// indices of the directions it spans.
    type Simplex<T: Element>: Element + AsRef<[T]> + AsMut<[T]>;

    fn simplex<T: Element>(f: impl FnMut(usize) -> T) -> Self::Simplex<T>;

    fn phase(g: f64) -> Self::Phase;
    fn phase_g(p: &Self::Phase) -> f64;
    /// Phase value per unit measure for travel direction `travel` scattered into `w`.
    fn phase_eval(p: &Self::Phase, travel: Self::Vec, w: Self::Vec) -> f64;
    /// Exact sampling of the scattered direction (pdf = `phase_eval`).
    fn phase_sample(p: &Self::Phase, travel: Self::Vec, s: &mut Sampler) -> Self::Vec;

    /// Lambertian BRDF factor per unit reflectance: cos/2 (2D) or cos/π (3D).
    fn lambert(cos: f64) -> f64;
    /// A cosine-distributed direction around the unit `normal`, and its pdf.
    fn sample_cosine(normal: Self::Vec, s: &mut Sampler) -> (Self::Vec, f64);
    /// A direction uniform over the circle or sphere.
    fn sample_uniform(s: &mut Sampler) -> Self::Vec;
    /// A direction within `theta_max` (≤ π/2) of the unit `axis`, its angle θ to
    /// the axis uniform in [0, θ_max] (its side, or its azimuth, uniform too): a
    /// density ∝ 1/θ per solid angle in 3D (`super::lamp_aim`).
    fn sample_cone(axis: Self::Vec, theta_max: f64, s: &mut Sampler) -> Self::Vec;
    /// The density of [`Dim::sample_cone`] at unit `w` (zero outside the cone).
    fn cone_pdf(axis: Self::Vec, theta_max: f64, w: Self::Vec) -> f64;

    /// Componentwise minimum, maximum, product and reciprocal (for bounding boxes).
    fn min(a: Self::Vec, b: Self::Vec) -> Self::Vec;
    fn max(a: Self::Vec, b: Self::Vec) -> Self::Vec;
    fn mul(a: Self::Vec, b: Self::Vec) -> Self::Vec;
    fn recip(a: Self::Vec) -> Self::Vec;
    fn splat(v: f64) -> Self::Vec;
    fn min_element(a: Self::Vec) -> f64;
    fn max_element(a: Self::Vec) -> f64;
    fn any_nan(a: Self::Vec) -> bool;
    /// Half the boundary measure of a box of extent `e`: the surface-area heuristic's
    /// cost of a node (half perimeter in 2D, half area in 3D).
    fn half_boundary(e: Self::Vec) -> f64;

    /// `n` stratified unit directions, jittered in their strata by `jitter` ∈ [0, 1]
    /// from streams of `seed`.
    fn directions(n: usize, jitter: f64, seed: u64) -> Vec<Self::Vec>;
    /// The simplices joining neighbouring directions (neighbouring rays in 2D, the
    /// triangulation of the sphere in 3D), counter-clockwise / outward.
    fn neighbours(dirs: &[Self::Vec]) -> Vec<Self::Simplex<u32>>;
    /// `n` stratified unit directions over the half circle or hemisphere on the side
    /// of the unit `normal` (a surface point's probe).
    fn hemisphere(n: usize, normal: Self::Vec, jitter: f64, seed: u64) -> Vec<Self::Vec>;
    /// Their neighbours: an open chain (2D), a triangulated disc (3D).
    fn hemisphere_neighbours(dirs: &[Self::Vec], normal: Self::Vec) -> Vec<Self::Simplex<u32>>;
    /// The angle (solid angle) spanned by unit directions.
    fn direction_measure(dirs: Self::Simplex<Self::Vec>) -> f64;
    /// The vertices reordered so that their form factor seen from `x` is positive.
    fn orient(x: Self::Vec, v: Self::Simplex<Self::Vec>) -> Self::Simplex<Self::Vec>;
    /// The angle (solid angle) a segment (triangle) subtends at `x`, with its
    /// gradient and Hessian in x (theory.md §5).
    fn form_factor(v: Self::Simplex<Self::Vec>, x: Self::Vec) -> Taylor2<Self>;
    /// [`Dim::form_factor`] with one clamping distance of the derivatives' vertex
    /// (edge) terms, shared by every element of a sum so that terms cancel exactly
    /// where elements meet.
    fn form_factor_clamped(v: Self::Simplex<Self::Vec>, x: Self::Vec, r_min: f64) -> Taylor2<Self>;
    /// ∫ f dω over the simplex's directions (an oriented simplex), with its
    /// derivatives, where a closed form exists (2D: `core::phase_arc`); `None` in 3D,
    /// where the phase is taken at the element's anchor.
    fn phase_weighted_form(
        g: f64,
        v: Self::Simplex<Self::Vec>,
        x: Self::Vec,
        out: Outgoing<Self::Vec>,
    ) -> Option<Taylor2<Self>>;
    /// ∫ f T dω over the simplex's directions (an oriented simplex), per channel of
    /// the extinction, with its derivatives, where the phase's lobe turns within the
    /// simplex (3D: `core::phase_patch`, split pieces as fine as `res` and a
    /// degree-5 area rule); `None` where one point of the simplex serves, and in
    /// 2D (the closed form [`Dim::phase_weighted_form`] integrates the phase
    /// there) but next to a surface (`res.boundary`: `core::segment_boundary`).
    fn lobe_integral(
        g: f64,
        v: Self::Simplex<Self::Vec>,
        x: Self::Vec,
        out: Outgoing<Self::Vec>,
        sigma_t: [f64; 3],
        res: Resolution,
    ) -> Option<[Taylor2<Self>; 3]>;
}

/// The componentwise operations of [`Dim`] for a glam vector type (the same names in
/// 2D and 3D).
macro_rules! box_ops {
    ($v:ty) => {
        #[inline]
        fn min(a: $v, b: $v) -> $v {
            a.min(b)
        }
        #[inline]
        fn max(a: $v, b: $v) -> $v {
            a.max(b)
        }
        #[inline]
        fn mul(a: $v, b: $v) -> $v {
            a * b
        }
        #[inline]
        fn recip(a: $v) -> $v {
            a.recip()
        }
        #[inline]
        fn splat(v: f64) -> $v {
            <$v>::splat(v)
        }
        #[inline]
        fn min_element(a: $v) -> f64 {
            a.min_element()
        }
        #[inline]
        fn max_element(a: $v) -> f64 {
            a.max_element()
        }
        #[inline]
        fn any_nan(a: $v) -> bool {
            a.is_nan_mask().any()
        }
    };
}

impl Dim for D2 {
    const PROBE_RAYS: usize = 1024;
    /// The measured default of `ProbeSettings::grading` in 2D (see `probe::March`).
    ///
    /// Measured on the 2D caches (`volcache caches --method ours --caches N`, 1024 rays,
    /// 16 steps, 128×128, against 2048 spp): occluder.json at 800 records RMSE 7.8e-3
    /// for seeds 1, 2, 3 at k = 6 against 1.45–1.93e-2 at k = 0 (400 records: 1.0e-2
    /// against 1.39–2.52e-2), at 1.35–1.6× the time; windows.json 7.3e-3 against
    /// 7.6e-3 at 800 records (its short rays now keep more medium samples: 1.8× the
    /// paths). The multiple-scattering gradient against finite differences of path
    /// tracing (tests/derivatives.rs, 12 points): median vector error 0.56 at k = 0,
    /// 0.23 at k = 3, 0.15 at k = 6, 0.25 at k = 9.
    const PROBE_GRADING: f64 = 6.0;
    /// One pinned core, the 402-segment forest (`bench flatland`, three runs each):
    /// closest hits 5.10–5.23 M/s with (4, 16), 5.89–5.94 with (2, 8), 6.06–6.11
    /// with (1, 4), 6.15–6.18 with (1, 2).
    const BVH_LEAF: (usize, usize) = (1, 2);
    /// `bench flatland`'s random segment soups, one pinned core, with those leaves:
    /// the tree answers 46.4 / 41.1 / 37.2 / 25.6 M closest hits/s at 2 / 3 / 4 / 6
    /// segments, the flat list 44.8 / 32.8 / 28.7 / 21.8 (with leaves of up to 16,
    /// the list was faster up to 6).
    const FLAT_LIST_MAX: usize = 2;
    type Phase = Hg2;
    type Simplex<T: Element> = [T; 2];

    fn simplex<T: Element>(f: impl FnMut(usize) -> T) -> [T; 2] {
        std::array::from_fn(f)
    }
    fn phase(g: f64) -> Hg2 {
        Hg2::new(g)
    }
    fn phase_g(p: &Hg2) -> f64 {
        p.g
    }
    #[inline]
    fn phase_eval(p: &Hg2, travel: DVec2, w: DVec2) -> f64 {
        p.eval(travel, w)
    }
    #[inline]
    fn phase_sample(p: &Hg2, travel: DVec2, s: &mut Sampler) -> DVec2 {
        p.sample(travel, s.next_f64())
    }
    #[inline]
    fn lambert(cos: f64) -> f64 {
        0.5 * cos
    }
    #[inline]
    fn sample_cosine(normal: DVec2, s: &mut Sampler) -> (DVec2, f64) {
        // pdf cosθ/2 on the half circle: sinθ uniform in [−1, 1].
        let sin_t = 2.0 * s.next_f64() - 1.0;
        let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
        (normal * cos_t + normal.perp() * sin_t, 0.5 * cos_t)
    }
    fn sample_uniform(s: &mut Sampler) -> DVec2 {
        DVec2::from_angle(TAU * s.next_f64())
    }
    fn sample_cone(axis: DVec2, theta_max: f64, s: &mut Sampler) -> DVec2 {
        DVec2::from_angle(theta_max * (2.0 * s.next_f64() - 1.0)).rotate(axis)
    }
    fn cone_pdf(axis: DVec2, theta_max: f64, w: DVec2) -> f64 {
        let theta = axis.perp_dot(w).atan2(axis.dot(w)).abs();
        if theta <= theta_max && theta_max > 0.0 {
            0.5 / theta_max
        } else {
            0.0
        }
    }
    box_ops!(DVec2);
    fn half_boundary(e: DVec2) -> f64 {
        e.x + e.y
    }
    fn directions(n: usize, jitter: f64, seed: u64) -> Vec<DVec2> {
        directions::circle(n, jitter, seed)
    }
    fn neighbours(dirs: &[DVec2]) -> Vec<[u32; 2]> {
        let n = dirs.len() as u32;
        (0..n).map(|k| [k, (k + 1) % n]).collect()
    }
    fn hemisphere(n: usize, normal: DVec2, jitter: f64, seed: u64) -> Vec<DVec2> {
        directions::half_circle(n, normal, jitter, seed)
    }
    fn hemisphere_neighbours(dirs: &[DVec2], _: DVec2) -> Vec<[u32; 2]> {
        (1..dirs.len() as u32).map(|k| [k - 1, k]).collect()
    }
    fn direction_measure([a, b]: [DVec2; 2]) -> f64 {
        a.perp_dot(b).atan2(a.dot(b)).abs()
    }
    fn orient(x: DVec2, [a, b]: [DVec2; 2]) -> [DVec2; 2] {
        if (a - x).perp_dot(b - x) >= 0.0 { [a, b] } else { [b, a] }
    }
    fn form_factor([a, b]: [DVec2; 2], x: DVec2) -> Taylor2<D2> {
        segment_form_factor(a, b, x)
    }

    fn form_factor_clamped([a, b]: [DVec2; 2], x: DVec2, r_min: f64) -> Taylor2<D2> {
        segment_form_factor_clamped(a, b, x, r_min)
    }

    fn phase_weighted_form(g: f64, [a, b]: [DVec2; 2], x: DVec2, out: Outgoing<DVec2>) -> Option<Taylor2<D2>> {
        Some(phase_weighted_angle(g, a, b, x, out))
    }

    fn lobe_integral(
        g: f64,
        v: [DVec2; 2],
        x: DVec2,
        out: Outgoing<DVec2>,
        sigma_t: [f64; 3],
        res: Resolution,
    ) -> Option<[Taylor2<D2>; 3]> {
        // The phase has a closed form over a segment (`phase_weighted_form`);
        // next to a surface f·T is integrated with derivatives at the ends.
        if res.boundary {
            segment_lobe_integral(g, v, x, out, sigma_t)
        } else {
            None
        }
    }
}

impl Dim for D3 {
    const PROBE_RAYS: usize = 4096;
    /// The measured default of `ProbeSettings::grading` in 3D: an even march. On the
    /// staircase (`bench tradeoff3d`, 80×60, 4 spp, 1024 rays × 24 steps, 1024-spp
    /// reference) k = 6 traced 1.6–2.1× the rays (the stairs' short rays keep more
    /// samples) and took 2.2–2.4× the time for no gain at equal count (medium RMSE
    /// 2.18e-2 / 1.85e-2 at 100 / 400 records, against 2.07e-2 / 1.75e-2 at k = 0,
    /// both near the reference's noise): at equal time k = 0 wins. (The 3D
    /// multiple-scattering gradient used to lengthen with k — on fog_box
    /// |aware|/|reference| 1.12–1.6 at k = 0, 2.0–3.4 at k = 6 — because each medium
    /// sample's light was held fixed as x turns the direction it is seen from; with
    /// the samples' direction slopes (`path::scattered_with_slope`) it is 0.75–1.04
    /// at k = 0 and 0.78–1.07 at k = 6, median vector error 0.22 and 0.12 against
    /// 8 finite-difference references (their own relative standard error
    /// 0.07–0.13), 4 points × 2 seeds: k = 6 is now the more accurate record at
    /// 2.2× the cost; the equal-time comparison was not repeated. Against converged
    /// references — 12 points, 48 × 16k spp, seeds 5–8 — k = 0 was 0.39 off, its
    /// kernel smoothed over the whole first step; with the gradient's smoothing capped
    /// at 0.3 of the step (`derivatives::GRADIENT_SMOOTHING_CAP`) it is 0.15, against
    /// 0.11 at k = 6 for 1.7× the probe's time.)
    const PROBE_GRADING: f64 = 0.0;
    /// The 158,802-triangle sphere (`bench rays3d`, one pinned core): (2, 8) traced
    /// 5.5 M closest hits/s against 6.6–7.0 with (4, 16), and built in 0.053 s
    /// against 0.040.
    const BVH_LEAF: (usize, usize) = (4, 16);
    /// Taken over from 2D's first crossover, not measured in 3D: a tree of up to
    /// 16 triangles is one leaf behind one box test anyway.
    const FLAT_LIST_MAX: usize = 6;
    type Phase = Hg3;
    type Simplex<T: Element> = [T; 3];

    fn simplex<T: Element>(f: impl FnMut(usize) -> T) -> [T; 3] {
        std::array::from_fn(f)
    }
    fn phase(g: f64) -> Hg3 {
        Hg3::new(g)
    }
    fn phase_g(p: &Hg3) -> f64 {
        p.g
    }
    #[inline]
    fn phase_eval(p: &Hg3, travel: DVec3, w: DVec3) -> f64 {
        p.eval(travel, w)
    }
    #[inline]
    fn phase_sample(p: &Hg3, travel: DVec3, s: &mut Sampler) -> DVec3 {
        let (u1, u2) = (s.next_f64(), s.next_f64());
        p.sample(travel, u1, u2)
    }
    #[inline]
    fn lambert(cos: f64) -> f64 {
        cos * FRAC_1_PI
    }
    #[inline]
    fn sample_cosine(normal: DVec3, s: &mut Sampler) -> (DVec3, f64) {
        // A uniform disc point lifted to the hemisphere.
        let (u1, u2) = (s.next_f64(), s.next_f64());
        let r = u1.sqrt();
        let phi = TAU * u2;
        let z = (1.0 - u1).max(0.0).sqrt();
        let (t, b) = normal.any_orthonormal_pair();
        let w = (t * (r * phi.cos()) + b * (r * phi.sin()) + normal * z).normalize();
        (w, normal.dot(w).max(0.0) * FRAC_1_PI)
    }
    fn sample_uniform(s: &mut Sampler) -> DVec3 {
        let (u1, u2) = (s.next_f64(), s.next_f64());
        let z = 1.0 - 2.0 * u1;
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * (TAU * u2).cos(), r * (TAU * u2).sin(), z)
    }
    fn sample_cone(axis: DVec3, theta_max: f64, s: &mut Sampler) -> DVec3 {
        let (u1, u2) = (s.next_f64(), s.next_f64());
        let (sin_t, cos_t) = (theta_max * u1).sin_cos();
        let (sin_p, cos_p) = (TAU * u2).sin_cos();
        let (t, b) = axis.any_orthonormal_pair();
        (axis * cos_t + t * (sin_t * cos_p) + b * (sin_t * sin_p)).normalize()
    }
    fn cone_pdf(axis: DVec3, theta_max: f64, w: DVec3) -> f64 {
        // θ from its sine and cosine: accurate next to the axis, where the
        // density peaks (acos of a cosine near one is not).
        let sin_t = axis.cross(w).length();
        let theta = sin_t.atan2(axis.dot(w));
        if theta <= theta_max && theta_max > 0.0 {
            // p(θ) = 1/θ_max over dω = sinθ dθ dφ; finite on the axis itself.
            1.0 / (TAU * theta_max * sin_t.max(1e-12))
        } else {
            0.0
        }
    }
    box_ops!(DVec3);
    fn half_boundary(e: DVec3) -> f64 {
        e.x * e.y + e.y * e.z + e.z * e.x
    }
    fn directions(n: usize, jitter: f64, seed: u64) -> Vec<DVec3> {
        directions::fibonacci(n, jitter, seed)
    }
    fn neighbours(dirs: &[DVec3]) -> Vec<[u32; 3]> {
        directions::triangulate(dirs).expect("stratified directions triangulate")
    }
    fn hemisphere(n: usize, normal: DVec3, jitter: f64, seed: u64) -> Vec<DVec3> {
        directions::hemisphere(n, normal, jitter, seed)
    }
    fn hemisphere_neighbours(dirs: &[DVec3], normal: DVec3) -> Vec<[u32; 3]> {
        directions::triangulate_hemisphere(dirs, normal).expect("stratified directions triangulate")
    }
    fn direction_measure([a, b, c]: [DVec3; 3]) -> f64 {
        directions::solid_angle(a, b, c).abs()
    }
    fn orient(x: DVec3, [a, b, c]: [DVec3; 3]) -> [DVec3; 3] {
        if (a - x).dot((b - a).cross(c - a)) >= 0.0 {
            [a, b, c]
        } else {
            [a, c, b]
        }
    }
    fn form_factor(v: [DVec3; 3], x: DVec3) -> Taylor2<D3> {
        triangle_form_factor(v, x)
    }

    fn form_factor_clamped(v: [DVec3; 3], x: DVec3, r_min: f64) -> Taylor2<D3> {
        triangle_form_factor_clamped(v, x, r_min)
    }

    fn phase_weighted_form(_: f64, _: [DVec3; 3], _: DVec3, _: Outgoing<DVec3>) -> Option<Taylor2<D3>> {
        None
    }

    fn lobe_integral(
        g: f64,
        v: [DVec3; 3],
        x: DVec3,
        out: Outgoing<DVec3>,
        sigma_t: [f64; 3],
        res: Resolution,
    ) -> Option<[Taylor2<D3>; 3]> {
        lobe_integral(g, v, x, out, sigma_t, res)
    }
}
