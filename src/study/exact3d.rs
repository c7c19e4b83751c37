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

use super::exact2d::gauss_legendre;
use crate::core::color::Rgb;
use crate::core::space::D3;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use crate::pipeline::world::World;
use crate::volume::scene::Scene;
use glam::DVec3;

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
    let Some(m) = scene.medium_at(x) else {
        return Rgb::ZERO;
    };
    arriving(scene, x, |w| m.phase.eval(-omega_o, w)) * m.sigma_s
}

/// The irradiance ∫ L max(0, n·ω) dω that the emitting triangles send to `x` on a
/// receiver with unit normal `n` directly (through the medium, if any). The
/// integrand is smooth where no emitter crosses the receiver's horizon.
pub fn irradiance(scene: &Scene, x: DVec3, n: DVec3) -> Rgb {
    arriving(scene, x, |w| n.dot(w).max(0.0))
}

/// ∫ weight(ω) T L_e dω over the emitters' parts `x` sees, ω the direction from x.
fn arriving(scene: &Scene, x: DVec3, weight: impl Fn(DVec3) -> f64) -> Rgb {
    let gl = gauss_legendre(NODES);
    let mut sum = Rgb::ZERO;
    for (e, t) in scene.geometry.prims.iter().enumerate() {
        let surface = &scene.surfaces[t.shape as usize];
        let facing = t.normal.dot(x - t.p0) > 0.0;
        if surface.emission == Rgb::ZERO || !(facing || surface.two_sided) {
            continue;
        }
        for piece in visible_pieces(scene, x, e) {
            for i in 1..piece.len() - 1 {
                let (a, b, c) = (piece[0], piece[i], piece[i + 1]);
                // Each fan triangle split into SPLIT² similar pieces.
                for (p0, p1, p2) in split(a, b, c) {
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
                            sum += surface.emission * scene.transmittance(x, w, r) * (weight(w) * cos / (r * r) * jac);
                        }
                    }
                }
            }
        }
    }
    sum
}

/// Triangle (a, b, c) as SPLIT² similar triangles.
fn split(a: DVec3, b: DVec3, c: DVec3) -> Vec<(DVec3, DVec3, DVec3)> {
    let k = SPLIT as f64;
    let at = |i: usize, j: usize| a + (b - a) * (i as f64 / k) + (c - a) * (j as f64 / k);
    let mut out = vec![];
    for i in 0..SPLIT {
        for j in 0..SPLIT - i {
            out.push((at(i, j), at(i + 1, j), at(i, j + 1)));
            if i + j + 1 < SPLIT {
                out.push((at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)));
            }
        }
    }
    out
}

/// Value, gradient and Hessian of [`single_scattering`] by central differences with
/// step `h` (exact to O(h²) where no visibility event is within h).
pub fn derivatives(scene: &Scene, x: DVec3, omega_o: DVec3, h: f64) -> TaylorRgb<D3> {
    let channels = Taylor2::central_differences(|p| single_scattering(scene, p, omega_o).to_array(), x, h);
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
}
