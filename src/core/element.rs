//! Proxy elements (theory.md §5): the form factor F_j(x) of an occlusion-free element
//! seen from the receiving point x, with its gradient and Hessian in x. An element's
//! contribution is L_j = f · T · L_o · F (phase: [`crate::core::phase::phase_taylor`],
//! transmittance: [`crate::core::transmittance::transmittance_taylor`]; combine the
//! [`Taylor2`] factors with `*`).
//!
//! - 2D surface segment [a, b] ([`segment_form_factor`]): the signed angle it
//!   subtends, F = atan2(a'×b', a'·b') with a' = a − x, b' = b − x. **Sign:** F > 0
//!   when b' is counter-clockwise from a' as seen from x, so the segments of a closed
//!   polygon traversed counter-clockwise around x (outward normals on the right of
//!   a → b) sum to 2π, and to 0 for x outside.
//! - 3D surface triangle ([`triangle_form_factor`]): signed solid angle; positive
//!   when the right-handed normal (v1 − v0) × (v2 − v0) points away from x, so a
//!   closed mesh with outward normals sums to 4π around x (theory.md §5).
//! - Medium piece of area A (2D) or volume V (3D) centred at c
//!   ([`medium_form_factor`]): F = A/r or V/r² (theory.md §1 table); σ_s is the
//!   caller's.
//!
//! **Near an element (theory.md §7).** The angle of a vertex p seen from x has
//! derivatives of order 1/|p − x| and 1/|p − x|² (in 3D the edge terms grow like the
//! inverse distance to the edge). Each vertex (2D) or edge (3D) term is evaluated as
//! if x were at least [`near_distance`]`(size)` = [`NEAR_FRACTION`] · size from that
//! vertex or edge, moving x away along the same direction (size = segment length, or
//! longest triangle edge); exactly on the vertex or edge, the term is dropped (its
//! average over a small circle around it vanishes). The form factor's *value* is never
//! clamped. With r = near_distance(size): |∇F| ≤ 2/r and ‖H F‖ ≤ 2√2/r² for a segment,
//! |∇Ω| ≤ 6/r and ‖H Ω‖ ≲ 30/r² for a triangle (tested), and the closed forms are
//! exact away from the clamp zones. For the phase and transmittance factors of a
//! surface element pass `soft = near_distance(size)`; for a medium piece,
//! `soft = medium_softening::<S>(measure)`. Valid for coordinates below ~1e150 in
//! magnitude (squared lengths must not overflow).
//!
//! Medium pieces are softened instead (see [`medium_softening`]): r → √(r² + ε²) with
//! ε chosen so that F at the piece's centre equals the exact average of 1/r^{d−1}
//! over a ball of the same measure. Smooth everywhere, with zero gradient at the centre
//! as symmetry demands, and a relative change ε²/r² ≪ 1 for pieces far from x.

pub use super::distance::{NEAR_FRACTION, near_distance};
pub use super::triangle::triangle_form_factor;

use super::distance::{MIN_DISTANCE, Offset, distance_from};
use super::space::{D2, Space};
use super::taylor::Taylor2;
use glam::{DMat2, DVec2};

/// Gradient and Hessian in x of θ(x) = angle of d = p − x, with |d| clamped to at
/// least `r_min`: ∇θ = (d_y, −d_x)/|d|², H = [[2d_xd_y, d_y²−d_x²], [·, −2d_xd_y]]/|d|⁴.
fn vertex_angle_derivatives(p: DVec2, x: DVec2, r_min: f64) -> (DVec2, DMat2) {
    let mut d = p - x;
    let l2 = d.length_squared();
    if l2 == 0.0 {
        return (DVec2::ZERO, DMat2::ZERO);
    }
    if l2 < r_min * r_min {
        d *= r_min / l2.sqrt();
    }
    let inv = 1.0 / d.length_squared();
    let (hxx, hxy) = (2.0 * d.x * d.y * inv * inv, (d.y * d.y - d.x * d.x) * inv * inv);
    (
        DVec2::new(d.y, -d.x) * inv,
        DMat2::from_cols(DVec2::new(hxx, hxy), DVec2::new(hxy, -hxx)),
    )
}

/// The signed angle F ∈ [−π, π] subtended at `x` by the segment [a, b] (positive when
/// b − x is counter-clockwise from a − x), with ∇F = ∇θ_b − ∇θ_a and H F = Hθ_b − Hθ_a
/// (theory.md §5), clamped near the endpoints as described in the module docs.
pub fn segment_form_factor(a: DVec2, b: DVec2, x: DVec2) -> Taylor2<D2> {
    segment_form_factor_clamped(a, b, x, near_distance((b - a).length()))
}

/// [`segment_form_factor`] with an explicit clamping distance `r_min` for the
/// derivatives (the value is exact): callers whose elements sample a field at some
/// resolution (ray-marched medium shells) bound the near field by that resolution.
pub fn segment_form_factor_clamped(a: DVec2, b: DVec2, x: DVec2, r_min: f64) -> Taylor2<D2> {
    let (pa, pb) = (a - x, b - x);
    let value = pa.perp_dot(pb).atan2(pa.dot(pb));
    let r_min = r_min.max(MIN_DISTANCE);
    let (ga, ha) = vertex_angle_derivatives(a, x, r_min);
    let (gb, hb) = vertex_angle_derivatives(b, x, r_min);
    Taylor2::new(value, gb - ga, hb - ha)
}

/// Softening length ε of a medium piece of the given measure (area in 2D, volume in
/// 3D): with ρ the radius of the ball of that measure, ε = ρ/2 (2D) or ρ/√3 (3D), the
/// values for which measure/ε^{d−1} equals the average of 1/r^{d−1} over that ball
/// from its centre (2πρ in 2D, 4πρ in 3D).
pub fn medium_softening<S: Space>(measure: f64) -> f64 {
    let d = S::DIM as f64;
    let rho = (measure.max(0.0) / S::BALL_VOLUME).powf(1.0 / d);
    rho * d.powf(-1.0 / (d - 1.0))
}

/// The form factor of a medium piece centred at `c` with area (2D) or volume (3D)
/// `measure`: F = measure / r^{d−1} with r = √(|c − x|² + ε²) and ε from
/// [`medium_softening`]. Multiply by σ_s for the in-scattering weight.
pub fn medium_form_factor<S: Space>(c: S::Vec, measure: f64, x: S::Vec) -> Taylor2<S> {
    let m = measure.max(0.0);
    if m == 0.0 {
        return Taylor2::zero();
    }
    let r = distance_from(&Offset::<S>::new(x, c, medium_softening::<S>(m)));
    let n = (S::DIM - 1) as f64;
    let h = m / r.value.powi(S::DIM as i32 - 1);
    r.compose(h, -n * h / r.value, n * (n + 1.0) * h / (r.value * r.value))
}

/// A medium piece sampled at resolution `eps` (e.g. the ray-marching step): the
/// value is the exact measure/r^{d−1} (clamped at [`MIN_DISTANCE`]), the gradient and
/// Hessian are those of the kernel softened to r = √(|c − x|² + eps²). The softened
/// kernel's Laplacian integrates to zero over the plane/space, so a constant field
/// sampled densely at that resolution gives a zero Hessian, where the raw 1/r^{d−1}
/// kernel would add a positive near-field bias (its Laplacian is positive off the
/// origin and the balancing singular part is never sampled).
pub fn medium_form_factor_smoothed<S: Space>(c: S::Vec, measure: f64, x: S::Vec, eps: f64) -> Taylor2<S> {
    let m = measure.max(0.0);
    if m == 0.0 {
        return Taylor2::zero();
    }
    let soft = eps.max(medium_softening::<S>(m));
    let r = distance_from(&Offset::<S>::new(x, c, soft));
    let n = (S::DIM - 1) as f64;
    let h = m / r.value.powi(S::DIM as i32 - 1);
    let mut t = r.compose(h, -n * h / r.value, n * (n + 1.0) * h / (r.value * r.value));
    let exact = S::length(c - x).max(MIN_DISTANCE);
    t.value = m / exact.powi(S::DIM as i32 - 1);
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::phase::phase_taylor;
    use crate::core::rng::Sampler;
    use crate::core::space::D3;
    use crate::core::testing::*;
    use crate::core::transmittance::transmittance_taylor;
    use glam::DVec3;
    use num_dual::DualNum;
    use std::f64::consts::{PI, TAU};

    fn segment_ref(a: DVec2, b: DVec2, xs: &[HD]) -> HD {
        let (ax, ay) = (-xs[0] + a.x, -xs[1] + a.y);
        let (bx, by) = (-xs[0] + b.x, -xs[1] + b.y);
        atan2_hd(ax * by - ay * bx, ax * bx + ay * by)
    }

    /// True when no endpoint is within the clamping distance (closed forms exact).
    fn unclamped(a: DVec2, b: DVec2, x: DVec2) -> bool {
        let r = near_distance((b - a).length());
        (a - x).length() > r && (b - x).length() > r
    }

    #[test]
    fn segment_matches_ad() {
        let mut s = Sampler::new(41, 0);
        let mut worst = 0.0f64;
        for i in 0..3000 {
            let a = random_vec::<D2>(&mut s, 2.0);
            let b = match i % 4 {
                // Seen edge-on: x on the segment's line, outside it.
                0 => a + (a - DVec2::ZERO) * s.next_f64(),
                1 => a + random_vec::<D2>(&mut s, 1e-3),
                _ => random_vec::<D2>(&mut s, 2.0),
            };
            let x = if i % 4 == 0 {
                DVec2::ZERO
            } else {
                random_vec::<D2>(&mut s, 1.0)
            };
            if !unclamped(a, b, x) {
                continue;
            }
            let got = segment_form_factor(a, b, x);
            let want = ad_taylor::<D2>(|xs| segment_ref(a, b, xs), x);
            let e = rel_err(&got, &want);
            assert!(e < 1e-9, "{a} {b} {x}: {e:e}\n{got:?}\n{want:?}");
            worst = worst.max(e);
        }
        eprintln!("segment_form_factor max rel AD error: {worst:e}");
        assert!(worst < 1e-10);
    }

    fn medium_ref<S: Space>(c: S::Vec, m: f64, xs: &[HD]) -> HD {
        let eps = medium_softening::<S>(m);
        let mut r2 = HD::from(eps * eps);
        for k in 0..S::DIM {
            let dk = -xs[k] + c[k];
            r2 += dk * dk;
        }
        r2.powf(-0.5 * (S::DIM - 1) as f64) * m
    }

    fn medium_ad<S: Space>(seed: u64) -> f64 {
        let mut s = Sampler::new(seed, 0);
        let mut worst = 0.0f64;
        for i in 0..1000 {
            let m = 10f64.powf(-6.0 + 6.0 * s.next_f64());
            let x = random_vec::<S>(&mut s, 1.0);
            let c = if i % 5 == 0 {
                x + random_vec::<S>(&mut s, 1e-9)
            } else {
                random_vec::<S>(&mut s, 1.0)
            };
            let got = medium_form_factor::<S>(c, m, x);
            let want = ad_taylor::<S>(|xs| medium_ref::<S>(c, m, xs), x);
            worst = worst.max(rel_err(&got, &want));
        }
        worst
    }

    #[test]
    fn medium_matches_ad_and_ball_average() {
        let e2 = medium_ad::<D2>(42);
        let e3 = medium_ad::<D3>(43);
        eprintln!("medium_form_factor max rel AD error: 2D {e2:e}, 3D {e3:e}");
        assert!(e2 < 1e-10 && e3 < 1e-10);
        // At the centre: the exact ball average (2πρ, 4πρ), zero gradient.
        let rho = 0.3;
        let f2 = medium_form_factor::<D2>(DVec2::ONE, PI * rho * rho, DVec2::ONE);
        assert!((f2.value - TAU * rho).abs() < 1e-14 && f2.grad == DVec2::ZERO);
        let f3 = medium_form_factor::<D3>(DVec3::ONE, 4.0 * PI * rho.powi(3) / 3.0, DVec3::ONE);
        assert!((f3.value - 4.0 * PI * rho).abs() < 1e-13 && f3.grad == DVec3::ZERO);
        // Far away: A/r and V/r² (relative change ε²/r²).
        let far = medium_form_factor::<D3>(DVec3::new(10.0, 0.0, 0.0), 1e-3, DVec3::ZERO);
        let eps = medium_softening::<D3>(1e-3);
        assert!((far.value / 1e-5 - 1.0).abs() <= eps * eps / 100.0);
        assert_eq!(medium_form_factor::<D2>(DVec2::ONE, 0.0, DVec2::ONE), Taylor2::zero());
    }

    /// A random star-shaped polygon around the origin, counter-clockwise.
    fn star_polygon(s: &mut Sampler, n: usize) -> Vec<DVec2> {
        (0..n)
            .map(|k| {
                // Gaps below 3π/4: every edge stays ≥ 0.5 cos(3π/8) ≈ 0.19 from the origin.
                let t = TAU * (k as f64 + 0.5 * s.next_f64()) / n as f64;
                DVec2::from_angle(t) * (0.5 + s.next_f64())
            })
            .collect()
    }

    #[test]
    fn closed_polygon_sum_rule() {
        let mut s = Sampler::new(44, 0);
        for trial in 0..200 {
            let n = 4 + trial % 40;
            let poly = star_polygon(&mut s, n);
            for (x, total) in [(random_vec::<D2>(&mut s, 0.1), TAU), (DVec2::new(3.0, 1.0), 0.0)] {
                let parts: Vec<_> = (0..n)
                    .map(|k| segment_form_factor(poly[k], poly[(k + 1) % n], x))
                    .collect();
                let sum: Taylor2<D2> = parts.iter().copied().sum();
                let gscale: f64 = parts.iter().map(|p| p.grad.length()).sum();
                let hscale: f64 = parts.iter().map(|p| D2::frobenius(p.hess)).sum();
                assert!((sum.value - total).abs() < 1e-12, "n={n}: {}", sum.value);
                assert!(sum.grad.length() <= 1e-13 * gscale, "{:?} vs {gscale}", sum.grad);
                assert!(D2::frobenius(sum.hess) <= 1e-13 * hscale, "{:?} vs {hscale}", sum.hess);
            }
        }
    }

    #[test]
    fn segment_near_and_degenerate_inputs_are_finite_and_bounded() {
        let mut s = Sampler::new(45, 0);
        for i in 0..20000 {
            let scale = 10f64.powi((i % 9) * 10 - 40);
            let a = random_vec::<D2>(&mut s, scale);
            let b = match i % 5 {
                0 => a,
                1 => a + random_vec::<D2>(&mut s, 1e-12 * scale),
                _ => random_vec::<D2>(&mut s, scale),
            };
            let t = s.next_f64();
            let x = match (i / 5) % 5 {
                0 => a,
                1 => b + random_vec::<D2>(&mut s, 1e-9 * scale),
                2 => a.lerp(b, t) + random_vec::<D2>(&mut s, 1e-9 * scale),
                3 => a.lerp(b, t),
                _ => random_vec::<D2>(&mut s, scale),
            };
            let f = segment_form_factor(a, b, x);
            assert!(f.is_finite() && f.value.abs() <= PI, "{a} {b} {x}: {f:?}");
            let r = near_distance((b - a).length());
            assert!(f.grad.length() <= 2.0 / r * (1.0 + 1e-12), "{a} {b} {x}: {f:?}");
            assert!(
                D2::frobenius(f.hess) <= 2.0 * 2f64.sqrt() / (r * r),
                "{a} {b} {x}: {f:?}"
            );
        }
        // Within 1e-9 of the interior (far from the endpoints) the closed form is exact.
        let (a, b) = (DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0));
        let x = DVec2::new(0.3, 1e-9);
        let want = ad_taylor::<D2>(|xs| segment_ref(a, b, xs), x);
        assert!(rel_err(&segment_form_factor(a, b, x), &want) < 1e-12);
        // The clamp is continuous across its radius and bounds the derivatives there.
        let r = near_distance(2.0);
        let dir = DVec2::new(0.6, 0.8);
        let inside = segment_form_factor(a, b, a + dir * r * (1.0 - 1e-9));
        let outside = segment_form_factor(a, b, a + dir * r * (1.0 + 1e-9));
        assert!(rel_err_derivs(&inside, &outside) < 1e-7);
        let deep = segment_form_factor(a, b, a + dir * 1e-9);
        // Only the far endpoint's term differs (x moved by ≈ r): |Δ| ≪ |∇F| ≈ 1/r.
        assert!((deep.grad - inside.grad).length() < 1e-2 * inside.grad.length());
    }

    #[test]
    fn finite_differences_converge_at_second_order() {
        let mut s = Sampler::new(46, 0);
        let mut checked = 0;
        for _ in 0..30 {
            let (a, b) = (
                random_vec::<D2>(&mut s, 1.0) + DVec2::X * 3.0,
                random_vec::<D2>(&mut s, 1.0) + DVec2::Y * 3.0,
            );
            let x = random_vec::<D2>(&mut s, 0.5);
            checked += assert_fd_order2::<D2>(|y| segment_form_factor(a, b, y), x, 0.05) as usize;
            let c = random_vec::<D2>(&mut s, 1.0) + DVec2::X * 2.0;
            checked += assert_fd_order2::<D2>(|y| medium_form_factor::<D2>(c, 0.01, y), x, 0.05) as usize;
            let c3 = random_vec::<D3>(&mut s, 1.0) + DVec3::X * 2.0;
            let x3 = random_vec::<D3>(&mut s, 0.5);
            checked += assert_fd_order2::<D3>(|y| medium_form_factor::<D3>(c3, 0.01, y), x3, 0.05) as usize;
        }
        assert!(checked > 80, "only {checked} measurable cases");
    }

    /// L_j = f · T · L_o · F for a segment (theory.md §5) through the product rule,
    /// against AD of the whole expression; x also just outside the clamping radius.
    #[test]
    fn segment_contribution_matches_ad() {
        let mut s = Sampler::new(48, 0);
        let mut worst = 0.0f64;
        for i in 0..2000 {
            let (g, sigma) = ([-0.99, 0.0, 0.5, 0.99][i % 4], [1e-6, 0.5, 1e3][i % 3]);
            let a = random_vec::<D2>(&mut s, 1.0);
            let b = a + random_vec::<D2>(&mut s, 0.3);
            let size = (b - a).length();
            let soft = near_distance(size);
            let mut x = a + random_vec::<D2>(&mut s, 0.5);
            if i % 5 == 0 {
                // 1.5 to 10 clamping radii from an endpoint: large but exact derivatives.
                x = a + random_unit::<D2>(&mut s) * soft * (1.5 + 8.5 * s.next_f64());
            }
            if sigma > 100.0 {
                x = a + (x - a) * 0.01;
            }
            if !unclamped(a, b, x) {
                continue;
            }
            let far = if (a - x).length() > (b - x).length() { a } else { b };
            let (c, w, l_o) = ((a + b) * 0.5, random_unit::<D2>(&mut s), 0.7);
            let got = phase_taylor::<D2>(g, x, c, w, soft)
                * transmittance_taylor::<D2>(sigma, x, c, soft)
                * segment_form_factor(a, b, x)
                * l_o;
            let want = ad_taylor::<D2>(
                |xs| {
                    phase_ref::<D2>(g, xs, c, w, soft)
                        * transmittance_ref::<D2>(sigma, xs, c, soft)
                        * segment_ref(a, b, xs)
                        * l_o
                },
                x,
            );
            let e = rel_err(&got, &want);
            assert!(
                e < 1e-9,
                "g={g} σ={sigma} {a} {b} {x} far {far}: {e:e}\n{got:?}\n{want:?}"
            );
            worst = worst.max(e);
        }
        eprintln!("segment contribution f·T·F·L max rel AD error: {worst:e}");
        assert!(worst < 1e-10);
    }

    #[test]
    fn derivatives_rotate_and_translate_with_the_scene() {
        let mut s = Sampler::new(47, 0);
        for _ in 0..200 {
            let rot = DMat2::from_angle(TAU * s.next_f64());
            let shift = random_vec::<D2>(&mut s, 10.0);
            let (a, b, x) = (
                random_vec::<D2>(&mut s, 2.0),
                random_vec::<D2>(&mut s, 2.0),
                random_vec::<D2>(&mut s, 1.0),
            );
            let m = |p: DVec2| rot * p + shift;
            for (f, g) in [
                (segment_form_factor(a, b, x), segment_form_factor(m(a), m(b), m(x))),
                (
                    medium_form_factor::<D2>(a, 0.1, x),
                    medium_form_factor::<D2>(m(a), 0.1, m(x)),
                ),
            ] {
                let moved = Taylor2::<D2>::new(f.value, rot * f.grad, rot * f.hess * rot.transpose());
                assert!(rel_err(&g, &moved) < 1e-10, "{g:?} vs {moved:?}");
            }
        }
    }
}
