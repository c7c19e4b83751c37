//! The 3D phase function integrated over the directions a triangle subtends, with
//! its gradient and Hessian in the receiving point x, where the lobe is too narrow
//! for one point of the triangle to stand for it.
//!
//! A proxy surface element contributes L T ∫ f dω over its directions. Taking f at
//! one point (the element's anchor) is a one-point rule whose error, differentiated
//! twice, grows as (ρ/s)² · f/s² for an element of angular radius ρ on a phase
//! that turns over the angular scale s: near the lobe s ≈ 1 − |g|, so at g = 0.99
//! and 4096 directions (ρ ≈ 0.03) the rule is off by orders of magnitude in the
//! gradient and Hessian wherever the lobe points into an emitter. Flatland has a
//! closed form (`phase_arc`); the sphere's HG phase over a spherical triangle has
//! none, so the triangle is split at its edges' midpoints (four similar pieces per
//! level, vertices fixed in space as the element's are) until each piece is small
//! against its own scale s — its angular distance to the lobe's axis plus the
//! lobe's width — and each piece is integrated over its area by a degree-5 rule
//! whose points are fixed in space, with exact derivatives in x of every term.
//! Elements small against their scale keep the caller's anchor rule (`None`), so
//! a wide lobe costs nothing and changes nothing; the narrow lobes measured
//! (g = 0.99, 4096 and 16384 directions) cost no measurable time: only the
//! elements near the lobe's axis are split.
//!
//! The ratios were chosen on `tests/forward_scattering_3d.rs`'s scene at 4096 and
//! 16384 directions (g = 0.99 Hessian, worst point): one-point pieces at ratio
//! 0.25 / 0.1 / 0.03 gave 1000× / 100× / 10× (the error fell as the ratio squared);
//! the degree-5 rule at 0.25 gave 10×, at 0.12 0.15; an element threshold of 0.05
//! instead of 0.03 left the g = 0.9 Hessian 1.6× off at 16384 directions (0.17).

use super::graded_rule::RADON7;
use super::lobe_boundary::{Lobe, solid_angle_density, with_edge_derivatives};
use super::phase::{G_MAX, Outgoing, phase_taylor_out};
use super::space::D3;
use super::taylor::Taylor2;
use super::transmittance::transmittance_taylor;
use glam::{DMat3, DVec3};
use std::collections::VecDeque;

/// An element is integrated piecewise ([`lobe_integral`]) where its angular radius
/// exceeds this fraction of its scale: the anchor's one-point rule errs by the
/// square of the ratio, and near the lobe that error does not cancel between
/// neighbours.
pub const USE_RATIO: f64 = 0.03;
/// A piece is split while its angular radius exceeds this fraction of its scale
/// (the degree-5 area rule errs by about its sixth power).
pub const SPLIT_RATIO: f64 = 0.12;
/// The closeness (see [`Resolution::at`]) below which pieces are split finer than
/// [`SPLIT_RATIO`], and the rate: the split ratio falls as its sixth root.
pub const CLOSE_SCALE: f64 = 1e-4;
/// The closeness below which [`Resolution::turn_by_edges`] is wanted: at 1.4e-3
/// (an emitter 0.01 away, light towards a point 2.6 away) the area rule's cross
/// term left the Hessian 2% off at g = 0.99 and 0.06% at g = 0.6, and its error
/// grows as 1/closeness; the edge form costs four more edge forms and area rules
/// per element (lamp_fog.json's placement: +33% time when taken for every close
/// element).
pub const TURN_CLOSE: f64 = 1e-3;
/// At most this many levels of splitting: 0.03 rad (a 4096-direction element) down
/// to 1.2e-4 rad, pieces for lobes down to 1 − |g| ≈ 1e-3; narrower lobes are
/// integrated at that resolution. Only pieces near the axis split further, so a
/// level adds a bounded number of pieces, not four times as many.
pub const MAX_LEVELS: u32 = 8;
/// Elements farther than this many lobe widths from the axis keep the anchor rule,
/// so that a coarse probe at g → ±1 does not integrate every element of the sphere
/// (`tests/extreme_grid.rs`' 3D renders, 32 directions: 58 s with every element,
/// 19 s with 100 widths, 11.5 s with the anchor rule alone). The tail matters far
/// out at g = 0.99 and 4096 directions: 30 widths left the Hessian's p90 at 1.7
/// instead of 0.08 (the true Hessian is a cancellation of 10⁴–10⁵).
pub const NEAR_AXIS: f64 = 100.0;

/// How finely [`lobe_integral`] splits an element: at most `max_pieces` pieces,
/// each with an angular radius at most `split_ratio` times its scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolution {
    pub max_pieces: usize,
    pub split_ratio: f64,
    /// The element lies next to a surface: it is integrated even where one point
    /// of it would serve, and its derivatives along its plane take their edge
    /// form (`core::lobe_boundary`), so that they cancel exactly between
    /// neighbours.
    pub boundary: bool,
    /// With light towards a point, the cross term of ω_o's turn in the Hessian
    /// takes the edge form too (five edge forms instead of one; see
    /// [`lobe_integral`]): wanted where the element is far closer to x than the
    /// probe's typical ray length ([`TURN_CLOSE`]).
    pub turn_by_edges: bool,
}

impl Resolution {
    /// For an element whose nearest point lies `closeness` times the probe's
    /// typical ray length from x: [`SPLIT_RATIO`], and finer where the element is
    /// closer than [`CLOSE_SCALE`]. Why: next to a surface (distance d) every
    /// element near the lobe's axis lies at r ≈ d, and its share of the gradient
    /// (∝ 1/d) cancels against its neighbours' down to the true gradient, which
    /// stays finite; a piece's rule errs by a fixed fraction of its share (the
    /// sixth power of the ratio), so the error of the sum grew as 1/d: below an
    /// emitter at g = 0.99 the gradient was 0.8%, 7.8%, 77% off at d = 1e-4, 1e-5,
    /// 1e-6 (`tests/near_surface_3d.rs`). A ratio ∝ closeness^(1/6) keeps that
    /// error flat in d, at a cost (pieces ∝ ratio⁻²) only next to a surface.
    pub fn at(max_pieces: usize, closeness: f64) -> Self {
        let finer = (closeness.max(0.0) / CLOSE_SCALE).powf(1.0 / 6.0);
        Resolution {
            max_pieces,
            split_ratio: SPLIT_RATIO * finer.min(1.0),
            boundary: false,
            turn_by_edges: false,
        }
    }
}

/// The angle between two unit vectors, accurate for small angles.
fn angle(a: DVec3, b: DVec3) -> f64 {
    2.0 * (0.5 * (a - b).length()).min(1.0).asin()
}

/// The direction of the phase lobe's axis seen from `x`: ω = −ω_o for g > 0 (light
/// arriving from behind, scattered forward), ω_o for g < 0.
fn lobe_axis(g: f64, x: DVec3, out: Outgoing<DVec3>) -> Option<DVec3> {
    Some(axis_along(g, leaving(x, out)?))
}

/// The unit direction light leaves `x` along (ω_o, held fixed in x).
fn leaving(x: DVec3, out: Outgoing<DVec3>) -> Option<DVec3> {
    match out {
        Outgoing::Direction(w) => w,
        Outgoing::TowardsPoint(e) => e - x,
    }
    .try_normalize()
}

/// The lobe's axis for light leaving along the unit vector w: the direction
/// towards which f peaks (−w forward, w backward).
fn axis_along(g: f64, w: DVec3) -> DVec3 {
    if g > 0.0 { -w } else { w }
}

/// The triangle's angular radius about its centroid's direction and the angular
/// distance from its nearest point to the axis (≥ 0), seen from `x`.
fn reach(v: [DVec3; 3], x: DVec3, axis: DVec3) -> Option<(f64, f64)> {
    let dirs = v.map(|p| (p - x).normalize_or_zero());
    let c = (dirs[0] + dirs[1] + dirs[2]).try_normalize()?;
    let rho = dirs.iter().map(|&d| angle(c, d)).fold(0.0, f64::max);
    Some((rho, (angle(c, axis) - rho).max(0.0)))
}

/// Whether triangle `v` seen from `x` is too large for one point of it to stand for
/// the phase's lobe around `axis` of width `width`.
fn needs_split(v: [DVec3; 3], x: DVec3, axis: DVec3, width: f64, ratio: f64) -> bool {
    reach(v, x, axis).is_some_and(|(rho, off)| rho > ratio * (off + width))
}

/// The pieces of triangle `v` (seen from `x`) small against the phase lobe's scale,
/// split as above and in the triangle's orientation; `None` when the triangle needs
/// no split (g = 0, or small against the lobe's scale).
fn lobe_pieces(g: f64, v: [DVec3; 3], x: DVec3, out: Outgoing<DVec3>, res: Resolution) -> Option<Vec<[DVec3; 3]>> {
    if g == 0.0 {
        return None;
    }
    let g = g.clamp(-G_MAX, G_MAX);
    let axis = lobe_axis(g, x, out)?;
    let width = 1.0 - g.abs();
    let (rho, off) = reach(v, x, axis)?;
    if !res.boundary && (off > NEAR_AXIS * width || rho <= USE_RATIO * (off + width)) {
        return None;
    }
    // Breadth first, so that a budget cut leaves the pieces evenly refined.
    let mut pieces = vec![];
    let mut queue = VecDeque::from([(v, 0)]);
    let mut count = 1;
    while let Some((t, level)) = queue.pop_front() {
        if level < MAX_LEVELS && count + 3 <= res.max_pieces && needs_split(t, x, axis, width, res.split_ratio) {
            count += 3;
            let m = [0.5 * (t[0] + t[1]), 0.5 * (t[1] + t[2]), 0.5 * (t[2] + t[0])];
            queue.extend([
                ([t[0], m[0], m[2]], level + 1),
                ([m[0], t[1], m[1]], level + 1),
                ([m[2], m[1], t[2]], level + 1),
                ([m[0], m[1], m[2]], level + 1),
            ]);
        } else {
            pieces.push(t);
        }
    }
    Some(pieces)
}

/// ∫ f(−ω·ω_o) T(x, y(ω)) dω over the directions from `x` to the triangle `v`
/// (oriented so that its solid angle is positive), per channel of the extinction
/// `sigma_t`, with gradients and Hessians in x; `None` where the triangle needs no
/// split ([`lobe_pieces`]). Each piece is integrated over its area by Radon's
/// degree-5 rule on f · T · n·(y − x)/|y − x|³ with the points fixed in space: the
/// lobe's integral over a chain of elements is almost constant in x (the lobe's
/// spot moves within the emitter) while each piece's share turns over the lobe's
/// width, so the pieces' errors must be small against a cancellation of 10⁴–10⁵ in
/// the Hessian; a one-point rule (solid angle × f at the centroid) needed pieces
/// 8× smaller for the same error. Phase and transmittance are not softened: a
/// softening length fixed per element shifts the lobe's peak by ε²/w² and, varying
/// between neighbours, broke that cancellation (values 0.5%, gradients 5–30% off).
/// At most `res.max_pieces` pieces (split breadth first): the caller bounds the
/// cost by its probe's resolution.
pub fn lobe_integral(
    g: f64,
    v: [DVec3; 3],
    x: DVec3,
    out: Outgoing<DVec3>,
    sigma_t: [f64; 3],
    res: Resolution,
) -> Option<[Taylor2<D3>; 3]> {
    let pieces = lobe_pieces(g, v, x, out, res)?;
    if !res.boundary {
        return Some(area_rule(g, &pieces, x, out, sigma_t));
    }
    // The plane's normal facing away from x, and the sign of the oriented integral.
    let cross = (v[1] - v[0]).cross(v[2] - v[0]);
    let n = cross.try_normalize()?;
    let sign = if n.dot(v[0] - x) >= 0.0 { 1.0 } else { -1.0 };
    // x in the element's plane (seen edge-on, or on it): no height to move along.
    let near = v.iter().map(|&p| (p - x).length()).fold(f64::INFINITY, f64::min);
    let height = n.dot(v[0] - x).abs();
    if height.is_nan() || height <= 1e-9 * near {
        return Some(area_rule(g, &pieces, x, out, sigma_t));
    }
    let g = g.clamp(-G_MAX, G_MAX);
    let held = leaving(x, out)?;
    // The edge form with light leaving along w (the held ω_o, or ω_o turned).
    let edge_form = |w: DVec3| {
        let lobe = Lobe {
            g,
            out: w,
            axis: axis_along(g, w),
            width: 1.0 - g.abs(),
            sigma_t,
        };
        with_edge_derivatives(&lobe, v, &pieces, n * sign, x).map(|t| t * sign)
    };
    let edges = edge_form(held);
    let Outgoing::TowardsPoint(e) = out else {
        return Some(edges);
    };
    // With ω_o turning with x (light towards e), its turn's share is the area
    // rule's difference between the turning and the held direction (their values
    // are equal), except the cross term ∇_x(∂_ω J)·∇ω, whose every element's share
    // grows as 1/d like the plain derivatives: it is taken from the edge form at
    // ω_o turned by ±δ along two tangents, in place of the area rule's.
    let turning = area_rule(g, &pieces, x, out, sigma_t);
    let held_area = area_rule(g, &pieces, x, Outgoing::Direction(held), sigma_t);
    if !res.turn_by_edges {
        return Some(std::array::from_fn(|ch| edges[ch] + (turning[ch] - held_area[ch])));
    }
    let delta = 1e-3 * (1.0 - g.abs()).max(1e-3);
    let (t1, t2) = held.any_orthonormal_pair();
    // ∇ω_o = −(I − ω ωᵀ)/R; c_k = ∇ω_oᵀ t_k (t_k ⊥ ω: −t_k/R).
    let reach = (e - x).length();
    let mut cross_edges = [DMat3::ZERO; 3];
    let mut cross_area = [DMat3::ZERO; 3];
    for t in [t1, t2] {
        let (plus, minus) = ((held + t * delta).normalize(), (held - t * delta).normalize());
        let c = -t / reach;
        let (ep, em) = (edge_form(plus), edge_form(minus));
        let ap = area_rule(g, &pieces, x, Outgoing::Direction(plus), sigma_t);
        let am = area_rule(g, &pieces, x, Outgoing::Direction(minus), sigma_t);
        for ch in 0..3 {
            let outer = |a: DVec3| DMat3::from_cols(a * c.x, a * c.y, a * c.z);
            let ge = (ep[ch].grad - em[ch].grad) / (2.0 * delta);
            let ga = (ap[ch].grad - am[ch].grad) / (2.0 * delta);
            cross_edges[ch] += outer(ge) + outer(ge).transpose();
            cross_area[ch] += outer(ga) + outer(ga).transpose();
        }
    }
    Some(std::array::from_fn(|ch| {
        let mut t = edges[ch] + (turning[ch] - held_area[ch]);
        t.hess += cross_edges[ch] - cross_area[ch];
        t
    }))
}

/// ∫ f T dω over `pieces` (one plane) by Radon's rule on each, per channel.
fn area_rule(g: f64, pieces: &[[DVec3; 3]], x: DVec3, out: Outgoing<DVec3>, sigma_t: [f64; 3]) -> [Taylor2<D3>; 3] {
    let grey = sigma_t[0] == sigma_t[1] && sigma_t[1] == sigma_t[2];
    let mut sum = [Taylor2::zero(); 3];
    for &t in pieces {
        let cross = (t[1] - t[0]).cross(t[2] - t[0]);
        let area = 0.5 * cross.length();
        let Some(n) = cross.try_normalize() else { continue };
        for (b, w) in RADON7 {
            let y = t[0] * b[0] + t[1] * b[1] + t[2] * b[2];
            let base = phase_taylor_out::<D3>(g, x, y, out, 0.0) * solid_angle_density(n, y, x) * (w * area);
            if grey {
                let ft = base * transmittance_taylor::<D3>(sigma_t[0], x, y, 0.0);
                for s in &mut sum {
                    *s += ft;
                }
            } else {
                for (s, &st) in sum.iter_mut().zip(&sigma_t) {
                    *s += base * transmittance_taylor::<D3>(st, x, y, 0.0);
                }
            }
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::phase::hg_of_mu;
    use crate::core::triangle::triangle_form_factor_clamped;

    /// The phase-weighted solid angle by brute force: f at the centroids of a fine
    /// uniform split (n² pieces) times their solid angles.
    fn brute(g: f64, v: [DVec3; 3], x: DVec3, w_o: DVec3, n: usize) -> f64 {
        let at =
            |i: usize, j: usize| v[0] + (v[1] - v[0]) * (i as f64 / n as f64) + (v[2] - v[0]) * (j as f64 / n as f64);
        let mut sum = 0.0;
        let mut piece = |t: [DVec3; 3]| {
            let c = (t[0] + t[1] + t[2]) / 3.0 - x;
            let f = hg_of_mu::<D3>(g, -c.normalize().dot(w_o)).0;
            sum += f * triangle_form_factor_clamped(t, x, 0.0).value;
        };
        for i in 0..n {
            for j in 0..n - i {
                piece([at(i, j), at(i + 1, j), at(i, j + 1)]);
                if i + j + 1 < n {
                    piece([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
        }
        sum
    }

    /// [`lobe_integral`] in a vacuum: ∫ f dω with its derivatives.
    fn phase_weighted_solid_angle(g: f64, v: [DVec3; 3], x: DVec3, out: Outgoing<DVec3>) -> Option<Taylor2<D3>> {
        lobe_integral(g, v, x, out, [0.0; 3], Resolution::at(4096, 1.0)).map(|s| s[0])
    }

    fn triangle() -> [DVec3; 3] {
        [
            DVec3::new(-0.02, 1.0, -0.02),
            DVec3::new(0.03, 1.0, -0.01),
            DVec3::new(0.0, 1.0, 0.03),
        ]
    }

    /// The lobe pointing into the triangle: the split rule's value matches a 512²
    /// uniform split, where the one-point rule is off by a factor.
    #[test]
    fn a_narrow_lobe_into_the_triangle_is_integrated() {
        let (x, g) = (DVec3::new(0.001, 0.0, 0.002), 0.99);
        let w_o = (x - DVec3::new(0.0, 1.0, 0.0)).normalize();
        let v = triangle();
        let got = phase_weighted_solid_angle(g, v, x, Outgoing::Direction(w_o)).unwrap();
        let want = brute(g, v, x, w_o, 512);
        let one_point = brute(g, v, x, w_o, 1);
        // Measured 9e-7 (the one-point rule: 2.06×).
        assert!((got.value / want - 1.0).abs() < 1e-5, "{} vs {want}", got.value);
        assert!((one_point / want - 1.0).abs() > 0.5, "{one_point} vs {want}");
        // Lobes narrower than the deepest split stay finite, whatever g.
        for g in [0.999_999, 1.0, -1.0, G_MAX] {
            let t = phase_weighted_solid_angle(g, v, x, Outgoing::Direction(g.signum() * w_o)).unwrap();
            let all = [t.value]
                .into_iter()
                .chain(t.grad.to_array())
                .chain(t.hess.to_cols_array());
            assert!(all.into_iter().all(f64::is_finite), "g {g}: {t:?}");
        }
    }

    /// The gradient and Hessian are those of the rule's value (central differences of
    /// the same split, which does not change within the step here), in every channel
    /// of a coloured extinction; a channel equals the grey integral of its extinction.
    #[test]
    fn its_derivatives_are_the_values_derivatives() {
        let (g, sigma_t) = (-0.97, [0.5, 1.0, 3.0]);
        let v = triangle();
        let e = DVec3::new(0.0, 1.0, 0.0);
        let x = DVec3::new(0.004, 0.1, -0.003);
        for out in [
            Outgoing::Direction((e - x).normalize()),
            Outgoing::TowardsPoint(DVec3::new(0.1, 3.0, 0.2)),
        ] {
            let got = lobe_integral(g, v, x, out, sigma_t, Resolution::at(4096, 1.0)).unwrap();
            let fd = Taylor2::<D3>::central_differences(
                |p| {
                    lobe_integral(g, v, p, out, sigma_t, Resolution::at(4096, 1.0))
                        .unwrap()
                        .map(|t| t.value)
                },
                x,
                1e-5,
            );
            for (k, (got, fd)) in got.iter().zip(&fd).enumerate() {
                let max_abs = |m: DMat3| m.to_cols_array().iter().map(|e| e.abs()).fold(0.0, f64::max);
                assert!(
                    (got.grad - fd.grad).length() < 1e-4 * fd.grad.length(),
                    "{:?} vs {:?}",
                    got.grad,
                    fd.grad
                );
                assert!(
                    max_abs(got.hess - fd.hess) < 1e-3 * max_abs(fd.hess),
                    "{:?} vs {:?}",
                    got.hess,
                    fd.hess
                );
                let grey = lobe_integral(g, v, x, out, [sigma_t[k]; 3], Resolution::at(4096, 1.0)).unwrap()[0];
                assert_eq!(got.value, grey.value);
                assert_eq!(got.hess, grey.hess);
            }
        }
    }

    /// Isotropic fog, elements small against the lobe and elements far from it keep
    /// the anchor rule.
    #[test]
    fn wide_lobes_need_no_split() {
        let v = triangle();
        let x = DVec3::ZERO;
        assert!(phase_weighted_solid_angle(0.0, v, x, Outgoing::Direction(DVec3::Y)).is_none());
        // g = 0.5 with the lobe into a triangle a tenth the size (ρ ≈ 0.003 rad).
        let c = (v[0] + v[1] + v[2]) / 3.0;
        let small = v.map(|p| c + (p - c) * 0.1);
        assert!(phase_weighted_solid_angle(0.5, small, x, Outgoing::Direction(-DVec3::Y)).is_none());
        assert!(phase_weighted_solid_angle(0.5, v, x, Outgoing::Direction(-DVec3::Y)).is_some());
        assert!(phase_weighted_solid_angle(0.99, v, x, Outgoing::Direction(DVec3::X)).is_none());
    }
}
