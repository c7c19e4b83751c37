//! Exact single scattering in 3D, to judge estimators and derivatives by: the light
//! emitting triangles send to a medium point x directly,
//!
//!   L_ss(x, ω_o) = σ_s ∫_{visible emitter} f(−ω·ω_o) T(x, y) L_e cos θ_y / r² dA_y,
//!
//! over the part of each emitter that x sees. Visibility is exact: every other
//! triangle (clipped to the slab between x and the emitter's plane) is projected
//! from x onto that plane, and its convex image is cut out of the emitter's
//! polygon; what remains is a set of convex polygons whose vertices move smoothly
//! with x, integrated by a collapsed (Duffy) Gauss–Legendre rule on a fan of
//! triangles. The integrand is smooth there, so central differences of this
//! deterministic value give the gradient and Hessian ([`derivatives`]).
//!
//! The same integral with the cosine of a receiver in place of the phase is the
//! exact direct irradiance of a surface point ([`irradiance`]).
//!
//! Meant for scenes of emitters and black occluders (reflected light and delta lights
//! are not included) in a homogeneous medium covering x and the emitters.

use super::exact2d::{gauss_legendre, graded_to_distance};
use crate::core::color::Rgb;
use crate::core::phase::Outgoing;
use crate::core::space::D3;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use crate::pipeline::world::World;
use crate::volume::scene::Scene;
use glam::DVec3;
use std::f64::consts::TAU;

/// Nodes per direction of the collapsed rule, and the subdivisions per polygon
/// edge (small pieces keep the 1/r² integrand near its polynomial fit).
const NODES: usize = 10;
const SPLIT: usize = 4;

/// A convex polygon in 3D (its vertices in order, in one plane).
type Polygon = Vec<DVec3>;

/// The part of `poly` where `dist(p) ≥ 0` (Sutherland–Hodgman, one plane).
fn clip(poly: &[DVec3], dist: impl Fn(DVec3) -> f64) -> Polygon {
    let mut out = vec![];
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (da, db) = (dist(a), dist(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

/// `poly` minus the convex polygon `hole` (both in the plane with normal `n`), as
/// disjoint convex pieces: the parts outside each of the hole's edges in turn.
fn subtract(poly: Polygon, hole: &[DVec3], n: DVec3) -> Vec<Polygon> {
    // The hole's orientation about n decides which side of an edge is inside.
    let orient = (1..hole.len() - 1)
        .map(|i| (hole[i] - hole[0]).cross(hole[i + 1] - hole[0]).dot(n))
        .sum::<f64>()
        .signum();
    let mut rest = poly;
    let mut pieces = vec![];
    for i in 0..hole.len() {
        let (a, b) = (hole[i], hole[(i + 1) % hole.len()]);
        let inside = |p: DVec3| orient * (b - a).cross(p - a).dot(n);
        let outside = clip(&rest, |p| -inside(p));
        if outside.len() >= 3 {
            pieces.push(outside);
        }
        rest = clip(&rest, inside);
        if rest.len() < 3 {
            return pieces;
        }
    }
    pieces
}

/// The visible convex pieces of triangle `e` (with normal `n`) seen from `x`.
fn visible_pieces(scene: &Scene, x: DVec3, e: usize) -> Vec<Polygon> {
    let tris = &scene.geometry.prims;
    let t = &tris[e];
    let n = t.normal;
    let h = n.dot(t.p0 - x); // signed height of the plane above x
    let mut pieces = vec![vec![t.p0, t.p0 + t.e1, t.p0 + t.e2]];
    for (i, q) in tris.iter().enumerate() {
        if i == e {
            continue;
        }
        // Its part strictly between x and the plane (s = fraction of the height).
        let s = |p: DVec3| n.dot(p - x) / h;
        let tri = [q.p0, q.p0 + q.e1, q.p0 + q.e2];
        let slab = clip(&clip(&tri, |p| s(p) - 1e-9), |p| (1.0 - 1e-12) - s(p));
        if slab.len() < 3 {
            continue;
        }
        let image: Polygon = slab.iter().map(|&p| x + (p - x) / s(p)).collect();
        pieces = pieces.into_iter().flat_map(|p| subtract(p, &image, n)).collect();
    }
    pieces
}

/// L_ss(x, ω_o) from the emitting triangles (zero outside the medium).
pub fn single_scattering(scene: &Scene, x: DVec3, omega_o: DVec3) -> Rgb {
    single_scattering_split(scene, x, omega_o, SPLIT)
}

/// [`single_scattering`] with each fan triangle split into `split`² pieces: a phase
/// lobe narrower than a piece (g → ±1, width ≈ 1 − |g| radians) needs more.
pub fn single_scattering_split(scene: &Scene, x: DVec3, omega_o: DVec3, split: usize) -> Rgb {
    let Some(m) = scene.medium_at(x) else {
        return Rgb::ZERO;
    };
    arriving(scene, x, split, |w| m.phase.eval(-omega_o, w)) * m.sigma_s
}

/// The irradiance ∫ L max(0, n·ω) dω that the emitting triangles send to `x` on a
/// receiver with unit normal `n` directly (through the medium, if any). The
/// integrand is smooth where no emitter crosses the receiver's horizon.
pub fn irradiance(scene: &Scene, x: DVec3, n: DVec3) -> Rgb {
    arriving(scene, x, SPLIT, |w| n.dot(w).max(0.0))
}

/// The radiance triangle `e` emits towards `x`: `None` where it emits nothing or
/// `x` lies behind a one-sided emitter.
fn emission_towards(scene: &Scene, e: usize, x: DVec3) -> Option<Rgb> {
    let t = &scene.geometry.prims[e];
    let surface = &scene.surfaces[t.shape as usize];
    let facing = t.normal.dot(x - t.p0) > 0.0;
    (surface.emission != Rgb::ZERO && (facing || surface.two_sided)).then_some(surface.emission)
}

/// ∫ weight(ω) T L_e dω over the emitters' parts `x` sees, ω the direction from x.
fn arriving(scene: &Scene, x: DVec3, split_by: usize, weight: impl Fn(DVec3) -> f64) -> Rgb {
    let gl = gauss_legendre(NODES);
    let mut sum = Rgb::ZERO;
    for (e, t) in scene.geometry.prims.iter().enumerate() {
        let Some(emission) = emission_towards(scene, e, x) else {
            continue;
        };
        for piece in visible_pieces(scene, x, e) {
            for i in 1..piece.len() - 1 {
                let (a, b, c) = (piece[0], piece[i], piece[i + 1]);
                // Each fan triangle split into split_by² similar pieces.
                for (p0, p1, p2) in split(a, b, c, split_by) {
                    let area2 = (p1 - p0).cross(p2 - p0).length();
                    for &(zu, wu) in &gl {
                        let u = 0.5 * (zu + 1.0);
                        for &(zv, wv) in &gl {
                            let v = 0.5 * (zv + 1.0);
                            // Duffy: (u, v) ↦ (u, u v) maps the square onto the triangle.
                            let y = p0 + (p1 - p0) * (u * (1.0 - v)) + (p2 - p0) * (u * v);
                            let d = y - x;
                            let r = d.length();
                            let w = d / r;
                            let cos = t.normal.dot(w).abs();
                            let jac = 0.25 * wu * wv * u * area2;
                            sum += emission * scene.transmittance(x, w, r) * (weight(w) * cos / (r * r) * jac);
                        }
                    }
                }
            }
        }
    }
    sum
}

/// Triangle (a, b, c) as n² similar triangles.
fn split(a: DVec3, b: DVec3, c: DVec3, n: usize) -> Vec<(DVec3, DVec3, DVec3)> {
    let k = n as f64;
    let at = |i: usize, j: usize| a + (b - a) * (i as f64 / k) + (c - a) * (j as f64 / k);
    let mut out = vec![];
    for i in 0..n {
        for j in 0..n - i {
            out.push((at(i, j), at(i + 1, j), at(i, j + 1)));
            if i + j + 1 < n {
                out.push((at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)));
            }
        }
    }
    out
}

/// L_ss(x, ω_o) from the emitting triangles of a scene *without occluders*,
/// integrated in polar coordinates (θ, φ) about the phase lobe's axis (−ω_o for
/// g ≥ 0, ω_o for g < 0) instead of over fixed pieces of the emitters: the nodes
/// follow the lobe as x moves, so a lobe far narrower than any split of the emitter
/// (g → ±1: width ≈ 1 − |g| radians) is resolved and the value stays smooth in x
/// to near rounding (central differences of [`single_scattering`] at g = 0.99 move
/// by orders of magnitude between 32² and 64² pieces). For each φ the half-plane
/// through the axis meets a triangle in one θ interval (a convex spherical
/// polygon); θ is integrated on panels graded towards the axis, φ on panels between
/// the azimuths of the triangle's vertices (where the interval's ends change edge).
pub fn single_scattering_about_lobe(scene: &Scene, x: DVec3, omega_o: DVec3) -> Rgb {
    let Some(m) = scene.medium_at(x) else {
        return Rgb::ZERO;
    };
    let g = m.phase.g;
    let axis = if g >= 0.0 { -omega_o } else { omega_o }.normalize();
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1);
    let gl = gauss_legendre(16);
    let width = (1.0 - g.abs()).max(1e-6);
    let mut sum = Rgb::ZERO;
    for (e, t) in scene.geometry.prims.iter().enumerate() {
        let Some(emission) = emission_towards(scene, e, x) else {
            continue;
        };
        let v = [t.p0, t.p0 + t.e1, t.p0 + t.e2];
        let azimuth = |p: DVec3| {
            let d = p - x;
            d.dot(e2).atan2(d.dot(e1))
        };
        // The θ interval of the half-plane at azimuth φ.
        let interval = |phi: f64| -> Option<(f64, f64)> {
            let u = e1 * phi.cos() + e2 * phi.sin();
            let n = axis.cross(u);
            let dist = v.map(|p| n.dot(p - x));
            let mut ends = vec![];
            for i in 0..3 {
                let (a, b) = (i, (i + 1) % 3);
                if (dist[a] > 0.0) != (dist[b] > 0.0) {
                    ends.push(v[a] + (v[b] - v[a]) * (dist[a] / (dist[a] - dist[b])));
                }
            }
            if ends.len() < 2 {
                return None;
            }
            // Clip the segment to the half-plane's side (component along u ≥ 0).
            let (p, q) = (ends[0] - x, ends[1] - x);
            let (sp, sq) = (p.dot(u), q.dot(u));
            let (p, q) = match (sp >= 0.0, sq >= 0.0) {
                (true, true) => (p, q),
                (false, false) => return None,
                (true, false) => (p, p + (q - p) * (sp / (sp - sq))),
                (false, true) => (q, p + (q - p) * (sp / (sp - sq))),
            };
            let theta = |d: DVec3| d.dot(u).max(0.0).atan2(d.dot(axis));
            let (a, b) = (theta(p), theta(q));
            Some((a.min(b), a.max(b)))
        };
        let mut cuts: Vec<f64> = v.iter().map(|&p| azimuth(p)).collect();
        cuts.sort_by(f64::total_cmp);
        cuts.push(cuts[0] + TAU);
        for k in 0..3 {
            let (lo, hi) = (cuts[k], cuts[k + 1]);
            let panels = 24;
            for pnl in 0..panels {
                let (a, b) = (
                    lo + (hi - lo) * pnl as f64 / panels as f64,
                    lo + (hi - lo) * (pnl + 1) as f64 / panels as f64,
                );
                for &(z, wz) in &gl {
                    let phi = 0.5 * (a + b) + 0.5 * (b - a) * z;
                    let Some((t0, t1)) = interval(phi) else { continue };
                    let u = e1 * phi.cos() + e2 * phi.sin();
                    // θ panels: geometric from width/64 up, so the lobe's core and its
                    // θ⁻³ tail each see nodes on their own scale.
                    let mut edges = vec![t0];
                    let mut c = width / 64.0;
                    while c < t1 {
                        if c > t0 {
                            edges.push(c);
                        }
                        c *= 1.5;
                    }
                    edges.push(t1);
                    let edges = graded_to_distance(&edges, |th| {
                        t.normal.dot(t.p0 - x) / t.normal.dot(axis * th.cos() + u * th.sin())
                    });
                    let mut inner = Rgb::ZERO;
                    for w in edges.windows(2) {
                        for &(zt, wt) in &gl {
                            let th = 0.5 * (w[0] + w[1]) + 0.5 * (w[1] - w[0]) * zt;
                            let dir = axis * th.cos() + u * th.sin();
                            let r = t.normal.dot(t.p0 - x) / t.normal.dot(dir);
                            let f = m.phase.eval(-omega_o, dir);
                            inner += scene.transmittance(x, dir, r) * (f * th.sin() * 0.5 * (w[1] - w[0]) * wt);
                        }
                    }
                    sum += emission * inner * (0.5 * (b - a) * wz);
                }
            }
        }
    }
    sum * m.sigma_s
}

/// Value, gradient and Hessian of [`single_scattering_about_lobe`] by central
/// differences with step `h`, for light leaving along a fixed direction or towards
/// a point (then ω_o, and the lobe's axis, turn with x).
pub fn derivatives_about_lobe(scene: &Scene, x: DVec3, out: Outgoing<DVec3>, h: f64) -> TaylorRgb<D3> {
    let omega_o = |p: DVec3| match out {
        Outgoing::Direction(w) => w.normalize(),
        Outgoing::TowardsPoint(e) => (e - p).normalize(),
    };
    let channels =
        Taylor2::central_differences(|p| single_scattering_about_lobe(scene, p, omega_o(p)).to_array(), x, h);
    TaylorRgb { channels }
}

/// Value, gradient and Hessian of [`single_scattering`] by central differences with
/// step `h` (exact to O(h²) where no visibility event is within h).
pub fn derivatives(scene: &Scene, x: DVec3, omega_o: DVec3, h: f64) -> TaylorRgb<D3> {
    derivatives_split(scene, x, omega_o, h, SPLIT)
}

/// [`derivatives`] of [`single_scattering_split`].
pub fn derivatives_split(scene: &Scene, x: DVec3, omega_o: DVec3, h: f64, split: usize) -> TaylorRgb<D3> {
    let channels = Taylor2::central_differences(|p| single_scattering_split(scene, p, omega_o, split).to_array(), x, h);
    TaylorRgb { channels }
}

/// Value, gradient and Hessian of [`irradiance`] (normal held) by central
/// differences with step `h`.
pub fn irradiance_derivatives(scene: &Scene, x: DVec3, n: DVec3, h: f64) -> TaylorRgb<D3> {
    let channels = Taylor2::central_differences(|p| irradiance(scene, p, n).to_array(), x, h);
    TaylorRgb { channels }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn scene(shapes: &str, sigma_s: f64) -> Scene {
        let text = format!(
            r#"{{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
                "shapes": [{shapes}],
                "medium": {{"sigma_a": 0, "sigma_s": {sigma_s}}}}}"#
        );
        Scene::from_json(&text, "exact3d test", Path::new(".")).unwrap()
    }

    /// A lone square emitter in a nearly transparent, isotropic medium, seen from a
    /// point on its axis: σ_s L_e Ω/4π with Ω the square's solid angle (closed form:
    /// 4 asin(a² / (a² + 4h²)) for side a at height h).
    #[test]
    fn a_lone_square_gives_its_solid_angle() {
        let s = scene(
            r#"{"quad": {"origin": [-0.5, 1, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]}, "emission": 2, "reflectance": 0}"#,
            1e-9,
        );
        let got = single_scattering(&s, DVec3::ZERO, DVec3::X).x;
        let omega = 4.0 * (1.0f64 / (1.0 + 4.0)).asin();
        let want = 1e-9 * 2.0 * omega / (4.0 * std::f64::consts::PI);
        // Measured 1.1e-9 (10 × 10 nodes on 4² pieces of each fan triangle).
        assert!((got / want - 1.0).abs() < 1e-8, "{got} vs {want}");
    }

    /// An occluder covering half the square exactly (its shadow's edge through the
    /// square's centre line) halves the light (by symmetry).
    #[test]
    fn a_half_occluder_halves_it() {
        let light =
            r#"{"quad": {"origin": [-0.5, 1, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]}, "emission": 2, "reflectance": 0}"#;
        let blocker = r#"{"quad": {"origin": [0, 0.5, -1], "u": [1, 0, 0], "v": [0, 0, 2]}, "reflectance": 0}"#;
        let (open, half) = (scene(light, 1e-9), scene(&format!("{light}, {blocker}"), 1e-9));
        let (a, b) = (
            single_scattering(&open, DVec3::ZERO, DVec3::X).x,
            single_scattering(&half, DVec3::ZERO, DVec3::X).x,
        );
        assert!((b / a - 0.5).abs() < 1e-10, "{b} vs {a}");
    }

    /// The integral about the lobe's axis equals the one over fixed pieces where both
    /// resolve the phase (g = 0.6, −0.5), x in front of a square and beside it
    /// (the axis then misses the emitter).
    #[test]
    fn the_integral_about_the_lobe_matches_the_pieces() {
        let light =
            r#"{"quad": {"origin": [-0.5, 1, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]}, "emission": 2, "reflectance": 0}"#;
        for g in [0.6, -0.5] {
            let text = format!(
                r#"{{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
                    "shapes": [{light}], "medium": {{"sigma_a": 0.2, "sigma_s": 0.8, "g": {g}}}}}"#
            );
            let s = Scene::from_json(&text, "exact3d test", Path::new(".")).unwrap();
            for (x, w) in [
                (DVec3::new(0.1, 0.2, -0.1), DVec3::new(0.2, -1.0, 0.1)),
                (DVec3::new(1.5, 0.3, 0.2), DVec3::new(-0.3, -0.5, 0.8)),
            ] {
                let w = w.normalize();
                let (a, b) = (
                    single_scattering_split(&s, x, w, 16).x,
                    single_scattering_about_lobe(&s, x, w).x,
                );
                // Measured ≤ 1.2e-14.
                assert!((a / b - 1.0).abs() < 1e-11, "g {g}, x {x}: {a} vs {b}");
            }
        }
    }
}
