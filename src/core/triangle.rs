//! The 3D surface element: the signed solid angle Ω of a triangle seen from the
//! receiving point x, with gradient and Hessian in x (theory.md §5).
//!
//! Value (Van Oosterom & Strackee 1983), with a, b, c the vertices relative to x:
//!   tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|),
//! Ω ∈ (−2π, 2π], positive when (v1 − v0) × (v2 − v0) points away from x.
//!
//! Gradient: Ω is the potential of a unit current loop around the triangle, so ∇Ω is
//! a sum over the directed edges p → q (relative vectors a = p − x, b = q − x) of the
//! Biot–Savart field of a straight segment,
//!   e(a, b) = (a × b) k,   k = (|a| + |b|) / (|a||b| (|a||b| + a·b)),
//! and the Hessian is the sum of the edge Jacobians
//!   ∂e/∂x = (a × b) ∇kᵀ + k [b − a]ₓ,
//!   ∇k = k [ (â + b̂) ((|a| + |b|)/P − 1/(|a| + |b|)) + â/|a| + b̂/|b| ],
//! with P = |a||b| + a·b = |a||b| |â + b̂|²/2 evaluated without cancellation (P → 0
//! only on the edge itself). One edge's Jacobian is not symmetric; the closed loop's
//! sum is, and the result is symmetrised, which only matters where clamping acted.
//!
//! Near an edge (theory.md §7): each edge term is evaluated with x moved to at least
//! `near_distance(longest edge)` from that edge segment (see `element` module docs).

use super::distance::{MIN_DISTANCE, near_distance};
use super::space::{D3, Space};
use super::taylor::Taylor2;
use glam::{DMat3, DVec3};

/// [v]ₓ, the matrix of δ ↦ v × δ.
fn skew(v: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, v.z, -v.y),
        DVec3::new(-v.z, 0.0, v.x),
        DVec3::new(v.y, -v.x, 0.0),
    )
}

/// The edge p → q's share of ∇Ω and of its Jacobian, with x kept at least `r_min`
/// from the segment [p, q].
fn edge_term(p: DVec3, q: DVec3, x: DVec3, r_min: f64) -> (DVec3, DMat3) {
    let e = q - p;
    let le2 = e.length_squared();
    let t = if le2 > 0.0 {
        ((x - p).dot(e) / le2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    // Exact endpoints when clamped: p + e·1 need not round to q.
    let nearest = if t <= 0.0 {
        p
    } else if t >= 1.0 {
        q
    } else {
        p + e * t
    };
    let mut off = x - nearest;
    if t > 0.0 && t < 1.0 {
        // Beside the edge the offset is perpendicular to it; remove the rounding noise
        // along the edge, which dominates when x is (almost) on it.
        off -= e * (off.dot(e) / le2);
    }
    let rho = off.length();
    let x = if rho >= r_min {
        x
    } else if rho > 0.0 {
        nearest + off * (r_min / rho)
    } else {
        return (DVec3::ZERO, DMat3::ZERO);
    };
    let (a, b) = (p - x, q - x);
    let (la, lb) = (a.length(), b.length());
    // a × b = a × (q − p): no cancellation when the edge is small and far from x.
    let (ua, ub) = (a / la, b / lb);
    let s = ua + ub;
    let pp = la * lb * 0.5 * s.length_squared();
    if pp.is_nan() || pp <= 0.0 {
        return (DVec3::ZERO, DMat3::ZERO);
    }
    let sum = la + lb;
    let k = sum / (la * lb * pp);
    let axb = a.cross(e);
    let dk = (s * (sum / pp - 1.0 / sum) + ua / la + ub / lb) * k;
    (axb * k, D3::outer(axb, dk) + skew(e) * k)
}

/// The signed solid angle of the triangle `v` seen from `x`, with gradient and
/// Hessian in x. A closed mesh with outward normals gives 4π around x, 0 outside.
pub fn triangle_form_factor(v: [DVec3; 3], x: DVec3) -> Taylor2<D3> {
    let size = (v[1] - v[0])
        .length()
        .max((v[2] - v[1]).length())
        .max((v[0] - v[2]).length());
    triangle_form_factor_clamped(v, x, near_distance(size))
}

/// The solid angle of the triangle `v` seen from x (Van Oosterom and Strackee),
/// positive where (v1 − v0) × (v2 − v0) faces away from x.
pub fn signed_solid_angle(v: [DVec3; 3], x: DVec3) -> f64 {
    let (a, b, c) = (v[0] - x, v[1] - x, v[2] - x);
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    // a·(b × c) = a·((v1 − v0) × (v2 − v0)): edge vectors do not depend on x and do
    // not cancel for small, distant triangles.
    let num = a.dot((v[1] - v[0]).cross(v[2] - v[0]));
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * num.atan2(den)
}

/// [`triangle_form_factor`] with an explicit clamping distance `r_min` for the edge
/// terms of the derivatives (the value is exact). Triangles that share an edge must
/// clamp it alike for their derivatives to cancel along it (a proxy's chain of
/// surface elements), so callers that sum a mesh pass one `r_min` for all.
pub fn triangle_form_factor_clamped(v: [DVec3; 3], x: DVec3, r_min: f64) -> Taylor2<D3> {
    let value = signed_solid_angle(v, x);
    let r_min = r_min.max(MIN_DISTANCE);
    let mut grad = DVec3::ZERO;
    let mut jac = DMat3::ZERO;
    for (p, q) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
        let (g, j) = edge_term(p, q, x, r_min);
        grad += g;
        jac += j;
    }
    Taylor2::new(value, grad, D3::symmetrize(jac))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Sampler;
    use crate::core::testing::*;
    use num_dual::DualNum;
    use std::f64::consts::{PI, TAU};

    /// Van Oosterom–Strackee written directly, for AD.
    fn solid_angle_ref(v: [DVec3; 3], xs: &[HD]) -> HD {
        let rel = |p: DVec3| [-xs[0] + p.x, -xs[1] + p.y, -xs[2] + p.z];
        let (a, b, c) = (rel(v[0]), rel(v[1]), rel(v[2]));
        let dot = |u: &[HD; 3], w: &[HD; 3]| u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
        let (la, lb, lc) = (dot(&a, &a).sqrt(), dot(&b, &b).sqrt(), dot(&c, &c).sqrt());
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let n = e1.cross(e2);
        let num = a[0] * n.x + a[1] * n.y + a[2] * n.z;
        let den = la * lb * lc + dot(&a, &b) * lc + dot(&a, &c) * lb + dot(&b, &c) * la;
        atan2_hd(num, den) * 2.0
    }

    fn segment_distance(p: DVec3, q: DVec3, x: DVec3) -> f64 {
        let e = q - p;
        let t = if e.length_squared() > 0.0 {
            ((x - p).dot(e) / e.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (x - p - e * t).length()
    }

    fn unclamped(v: [DVec3; 3], x: DVec3) -> bool {
        let size = (v[1] - v[0])
            .length()
            .max((v[2] - v[1]).length())
            .max((v[0] - v[2]).length());
        let r = near_distance(size);
        (0..3).all(|k| segment_distance(v[k], v[(k + 1) % 3], x) > r)
    }

    #[test]
    fn solid_angle_matches_ad() {
        let mut s = Sampler::new(51, 0);
        let mut worst = 0.0f64;
        let mut n = 0;
        for i in 0..4000 {
            let mut v = [
                random_vec::<D3>(&mut s, 2.0),
                random_vec::<D3>(&mut s, 2.0),
                random_vec::<D3>(&mut s, 2.0),
            ];
            let mut x = random_vec::<D3>(&mut s, 1.0);
            match i % 4 {
                // Edge-on: x in the triangle's plane (inside or outside it).
                0 => {
                    let (w0, w1) = (s.next_f64() * 3.0 - 1.0, s.next_f64() * 3.0 - 1.0);
                    x = v[0] + (v[1] - v[0]) * w0 + (v[2] - v[0]) * w1;
                }
                // Small and far.
                1 => {
                    let c = DVec3::new(5.0, 1.0, -2.0);
                    v = v.map(|p| c + p * 1e-3);
                }
                // 1.5 to 10 clamping radii from an edge or a vertex: large derivatives.
                2 => {
                    let size = (v[1] - v[0])
                        .length()
                        .max((v[2] - v[1]).length())
                        .max((v[0] - v[2]).length());
                    let on_edge = v[0].lerp(v[1], 1.2 * s.next_f64() - 0.1);
                    x = on_edge + random_unit::<D3>(&mut s) * near_distance(size) * (1.5 + 8.5 * s.next_f64());
                }
                _ => {}
            }
            if !unclamped(v, x) {
                continue;
            }
            let got = triangle_form_factor(v, x);
            let want = ad_taylor::<D3>(|xs| solid_angle_ref(v, xs), x);
            let mut e = rel_err(&got, &want);
            if i % 4 == 0 {
                // In the plane the value is 0 or ±2π (a branch choice); compare derivatives.
                e = rel_err_derivs(&got, &want);
            }
            assert!(e < 1e-9, "{v:?} {x}: {e:e}\n{got:?}\n{want:?}");
            if e > worst {
                eprintln!(
                    "case {} e {e:e} value {} |g| {} |H| {}",
                    i % 4,
                    want.value,
                    want.grad.length(),
                    D3::frobenius(want.hess)
                );
            }
            worst = worst.max(e);
            n += 1;
        }
        // The worst cases are small distant triangles: the edge terms (~L/r²) cancel to
        // ~A/r³, costing a factor ≈ r/L of precision (r/L = 5e3 here).
        eprintln!("triangle_form_factor max rel AD error: {worst:e} over {n} cases");
        assert!(n > 3000 && worst < 1e-10);
    }

    /// L_j = f · T · L_o · Ω for a triangle (theory.md §5), against AD of the product.
    #[test]
    fn triangle_contribution_matches_ad() {
        use crate::core::phase::phase_taylor;
        use crate::core::transmittance::transmittance_taylor;
        let mut s = Sampler::new(56, 0);
        let mut worst = 0.0f64;
        for i in 0..1000 {
            let (g, sigma) = ([-0.99, 0.0, 0.5, 0.99][i % 4], [1e-6, 0.5, 1e3][i % 3]);
            let reach = if sigma > 100.0 { 0.01 } else { 1.0 };
            let x = random_vec::<D3>(&mut s, 1.0);
            let v = [0, 1, 2].map(|_| x + random_vec::<D3>(&mut s, reach));
            if !unclamped(v, x) {
                continue;
            }
            let size = (v[1] - v[0])
                .length()
                .max((v[2] - v[1]).length())
                .max((v[0] - v[2]).length());
            let soft = near_distance(size);
            let (c, w) = ((v[0] + v[1] + v[2]) / 3.0, random_unit::<D3>(&mut s));
            let got = phase_taylor::<D3>(g, x, c, w, soft)
                * transmittance_taylor::<D3>(sigma, x, c, soft)
                * triangle_form_factor(v, x)
                * 2.5;
            let want = ad_taylor::<D3>(
                |xs| {
                    phase_ref::<D3>(g, xs, c, w, soft)
                        * transmittance_ref::<D3>(sigma, xs, c, soft)
                        * solid_angle_ref(v, xs)
                        * 2.5
                },
                x,
            );
            let e = rel_err(&got, &want);
            assert!(e < 1e-9, "g={g} σ={sigma}: {e:e}\n{got:?}\n{want:?}");
            worst = worst.max(e);
        }
        eprintln!("triangle contribution f·T·Ω·L max rel AD error: {worst:e}");
        assert!(worst < 1e-10);
    }

    fn icosahedron() -> Vec<[DVec3; 3]> {
        let phi = (1.0 + 5f64.sqrt()) / 2.0;
        let mut v = Vec::new();
        for (s1, s2) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
            v.push(DVec3::new(0.0, s1, s2 * phi));
            v.push(DVec3::new(s1, s2 * phi, 0.0));
            v.push(DVec3::new(s2 * phi, 0.0, s1));
        }
        let edge = |a: DVec3, b: DVec3| ((a - b).length() - 2.0).abs() < 1e-9;
        let mut faces = Vec::new();
        for i in 0..12 {
            for j in i + 1..12 {
                for k in j + 1..12 {
                    if edge(v[i], v[j]) && edge(v[j], v[k]) && edge(v[i], v[k]) {
                        faces.push(orient_outward([v[i], v[j], v[k]]));
                    }
                }
            }
        }
        assert_eq!(faces.len(), 20);
        faces
    }

    fn orient_outward(t: [DVec3; 3]) -> [DVec3; 3] {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        if n.dot(t[0] + t[1] + t[2]) > 0.0 {
            t
        } else {
            [t[0], t[2], t[1]]
        }
    }

    fn cube() -> Vec<[DVec3; 3]> {
        let mut faces = Vec::new();
        for k in 0..3 {
            for sgn in [-1.0, 1.0] {
                let c = DVec3::AXES[k] * sgn;
                let (u, w) = (DVec3::AXES[(k + 1) % 3], DVec3::AXES[(k + 2) % 3]);
                let (p00, p10, p11, p01) = (c - u - w, c + u - w, c + u + w, c - u + w);
                faces.push(orient_outward([p00, p10, p11]));
                faces.push(orient_outward([p00, p11, p01]));
            }
        }
        faces
    }

    fn check_closed(mesh: &[[DVec3; 3]], x: DVec3, total: f64) {
        let parts: Vec<_> = mesh.iter().map(|t| triangle_form_factor(*t, x)).collect();
        let sum: Taylor2<D3> = parts.iter().copied().sum();
        let gscale: f64 = parts.iter().map(|p| p.grad.length()).sum();
        let hscale: f64 = parts.iter().map(|p| D3::frobenius(p.hess)).sum();
        assert!((sum.value - total).abs() < 1e-12, "{} vs {total}", sum.value);
        assert!(sum.grad.length() <= 1e-13 * gscale, "{:?} vs {gscale}", sum.grad);
        assert!(D3::frobenius(sum.hess) <= 1e-13 * hscale, "{:?} vs {hscale}", sum.hess);
    }

    #[test]
    fn closed_mesh_sum_rule() {
        let mut s = Sampler::new(52, 0);
        for trial in 0..200 {
            let base = if trial % 2 == 0 { icosahedron() } else { cube() };
            // Radially perturbed copies stay closed surfaces with winding number 1.
            let mut radius = std::collections::HashMap::new();
            let mesh: Vec<[DVec3; 3]> = base
                .iter()
                .map(|t| {
                    t.map(|p| {
                        let key = (p * 1e6).round().as_i64vec3().to_array();
                        *radius.entry(key).or_insert_with(|| 0.7 + 0.6 * s.next_f64()) * p
                    })
                })
                .collect();
            check_closed(&mesh, random_vec::<D3>(&mut s, 0.3), 4.0 * PI);
            check_closed(&mesh, DVec3::new(4.0, -3.0, 2.5) + random_vec::<D3>(&mut s, 1.0), 0.0);
        }
    }

    #[test]
    fn near_and_degenerate_inputs_are_finite_and_bounded() {
        let mut s = Sampler::new(53, 0);
        for i in 0..20000 {
            let scale = 10f64.powi((i % 9) * 10 - 40);
            let p0 = random_vec::<D3>(&mut s, scale);
            let p1 = random_vec::<D3>(&mut s, scale);
            let t = s.next_f64();
            let p2 = match i % 5 {
                0 => p0.lerp(p1, 3.0 * t - 1.0), // collinear
                1 => p0,                         // repeated vertex
                _ => random_vec::<D3>(&mut s, scale),
            };
            let v = if i % 17 == 0 { [p0; 3] } else { [p0, p1, p2] };
            let x = match (i / 5) % 6 {
                0 => v[0],
                1 => v[1].lerp(v[2], t),
                2 => v[2].lerp(v[0], t) + random_vec::<D3>(&mut s, 1e-9 * scale),
                3 => v[0] + random_vec::<D3>(&mut s, 1e-9 * scale),
                4 => (v[0] + v[1] + v[2]) / 3.0, // on the triangle
                _ => random_vec::<D3>(&mut s, scale),
            };
            let f = triangle_form_factor(v, x);
            assert!(f.is_finite() && f.value.abs() <= TAU, "{v:?} {x}: {f:?}");
            let size = (v[1] - v[0])
                .length()
                .max((v[2] - v[1]).length())
                .max((v[0] - v[2]).length());
            let r = near_distance(size);
            assert!(f.grad.length() <= 6.0 / r, "{v:?} {x}: {f:?} r={r}");
            assert!(D3::frobenius(f.hess) <= 30.0 / (r * r), "{v:?} {x}: {f:?} r={r}");
        }
    }

    #[test]
    fn finite_differences_converge_at_second_order() {
        let mut s = Sampler::new(54, 0);
        let mut checked = 0;
        for _ in 0..30 {
            let v = [0, 1, 2].map(|_| random_vec::<D3>(&mut s, 1.0) + DVec3::new(0.0, 0.0, 3.0));
            let x = random_vec::<D3>(&mut s, 0.5);
            checked += assert_fd_order2::<D3>(|y| triangle_form_factor(v, y), x, 0.05) as usize;
        }
        assert!(checked > 25, "only {checked} measurable cases");
    }

    #[test]
    fn derivatives_rotate_and_translate_with_the_scene() {
        let mut s = Sampler::new(55, 0);
        for _ in 0..200 {
            let rot = DMat3::from_axis_angle(random_unit::<D3>(&mut s), TAU * s.next_f64());
            let shift = random_vec::<D3>(&mut s, 10.0);
            let v = [0, 1, 2].map(|_| random_vec::<D3>(&mut s, 2.0));
            let x = random_vec::<D3>(&mut s, 1.0);
            let f = triangle_form_factor(v, x);
            let g = triangle_form_factor(v.map(|p| rot * p + shift), rot * x + shift);
            let moved = Taylor2::<D3>::new(f.value, rot * f.grad, rot * f.hess * rot.transpose());
            assert!(rel_err(&g, &moved) < 1e-9, "{g:?} vs {moved:?}");
        }
    }
}
