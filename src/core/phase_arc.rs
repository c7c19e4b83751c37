//! The flatland phase function integrated over the arc of directions a segment
//! subtends, with its gradient and Hessian in the receiving point x.
//!
//! A proxy surface element contributes L T ∫ f dθ over its directions. Taking f at
//! one point of the element (its anchor) is a one-point rule, fine where f is
//! smooth on the element's scale; with g → ±1 the lobe is 1 − |g| radians wide and
//! the rule's error, differentiated twice, grows as 1/(1 − |g|)²: at g = 0.99 and
//! 4096 rays, Hessians 30–6000× off where the lobe points into an emitter. In
//! flatland the integral has a closed form: with ψ the scattering angle, μ = cos ψ,
//! and k = (1 + g)/(1 − g),
//!
//!   ∫ f dψ = arg(cos(ψ/2) + i k sin(ψ/2)) / π   (continuous in ψ),
//!
//! so a segment's phase-weighted angle is the argument of a product of two such
//! numbers, free of cancellation for any g; its derivatives follow from those of the
//! end directions, f(ψ_b) ∇ψ_b − f(ψ_a) ∇ψ_a, as for the plain angle.

use super::phase::{G_MAX, Outgoing, hg_of_mu};
use super::space::{D2, Space};
use super::taylor::Taylor2;
use glam::{DMat2, DVec2};
use std::f64::consts::PI;

/// The angle of `d` seen from x = d's origin, with its gradient and Hessian in x
/// (d = p − x for a fixed p).
fn angle_of(d: DVec2) -> Taylor2<D2> {
    let r2 = d.length_squared();
    let (dx, dy) = (d.x, d.y);
    let grad = DVec2::new(dy, -dx) / r2;
    let (hxx, hyy, hxy) = (2.0 * dx * dy, -2.0 * dx * dy, dy * dy - dx * dx);
    let hess = DMat2::from_cols_array(&[hxx, hxy, hxy, hyy]) / (r2 * r2);
    Taylor2::new(d.y.atan2(d.x), grad, hess)
}

/// ∫ f(−ω·ω_o) dθ over the directions ω from `x` to the segment `a`–`b`, oriented
/// so that b lies counter-clockwise of a (the result is negative otherwise).
pub fn phase_weighted_angle(g: f64, a: DVec2, b: DVec2, x: DVec2, out: Outgoing<DVec2>) -> Taylor2<D2> {
    let g = g.clamp(-G_MAX, G_MAX);
    let k = (1.0 + g) / (1.0 - g);
    let (ta, tb) = (angle_of(a - x), angle_of(b - x));
    // θ_o, the angle of ω_o (fixed, or turning towards a point e as x moves).
    let to = match out {
        Outgoing::Direction(w) => Taylor2::constant(w.y.atan2(w.x)),
        Outgoing::TowardsPoint(e) => angle_of(e - x),
    };
    // Scattering angle ψ = θ − θ_o − π (μ = −ω·ω_o = cos ψ).
    let psi = |t: Taylor2<D2>| Taylor2::new(t.value - to.value - PI, t.grad - to.grad, t.hess - to.hess);
    let (pa, mut pb) = (psi(ta), psi(tb));
    // The sweep from a to b as a continuous angle: atan2's branch cut at ±π would
    // turn z(ψ_b) into −z(ψ_b) (measured: value 0 for a segment straddling −x).
    let mut sweep = pb.value - pa.value;
    sweep -= (sweep / (2.0 * PI)).round() * 2.0 * PI;
    pb.value = pa.value + sweep;
    let z = |p: f64| DVec2::new((0.5 * p).cos(), k * (0.5 * p).sin());
    let (za, zb) = (z(pa.value), z(pb.value));
    // arg(z_b · conj(z_a)).
    // A sweep shorter than a half turn integrates to less than 1 in magnitude, so the
    // argument in (−π, π] is unambiguous; only rounding can flip the sign near 0.
    let value = (za.x * zb.y - za.y * zb.x).atan2(za.x * zb.x + za.y * zb.y) / PI;
    let value = if sweep >= 0.0 { value.max(0.0) } else { value.min(0.0) };
    let end = |p: Taylor2<D2>| {
        let (f, df_dmu, _) = hg_of_mu::<D2>(g, p.value.cos());
        let df = -df_dmu * p.value.sin(); // df/dψ
        (p.grad * f, <D2 as Space>::outer(p.grad, p.grad) * df + p.hess * f)
    };
    let ((gb, hb), (ga, ha)) = (end(pb), end(pa));
    Taylor2::new(value, gb - ga, hb - ha)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Midpoint sum of f over the arc, fine enough to be exact to ~1e-10.
    fn numeric(g: f64, a: DVec2, b: DVec2, x: DVec2, w_o: DVec2) -> f64 {
        let (t0, t1) = ((a - x).y.atan2((a - x).x), (b - x).y.atan2((b - x).x));
        let mut dt = t1 - t0;
        if dt > PI {
            dt -= 2.0 * PI;
        } else if dt < -PI {
            dt += 2.0 * PI;
        }
        let n = 400_000;
        (0..n)
            .map(|i| {
                let t = t0 + dt * (i as f64 + 0.5) / n as f64;
                hg_of_mu::<D2>(g, -DVec2::from_angle(t).dot(w_o)).0
            })
            .sum::<f64>()
            * dt
            / n as f64
    }

    #[test]
    fn matches_the_numeric_integral_and_its_differences() {
        let x = DVec2::new(0.1, -0.2);
        let w_o = DVec2::new(0.6, -0.8);
        for g in [0.0, 0.5, -0.7, 0.99, -0.999] {
            for (a, b) in [
                (DVec2::new(1.0, 0.5), DVec2::new(-0.5, 1.0)),
                (DVec2::new(-0.8, -0.3), DVec2::new(-0.2, -1.4)),
                (DVec2::new(0.7, -0.9), DVec2::new(0.72, -0.7)),
                // straddling −x, where atan2 jumps from π to −π
                (DVec2::new(-1.0, 0.1), DVec2::new(-1.0, -0.6)),
                (DVec2::new(-1.0, -0.6), DVec2::new(-1.0, 0.1)),
            ] {
                let t = phase_weighted_angle(g, a, b, x, Outgoing::Direction(w_o));
                let want = numeric(g, a, b, x, w_o);
                assert!(
                    (t.value - want).abs() < 1e-8 * want.abs().max(1e-3),
                    "g {g}: {} vs {want}",
                    t.value
                );
                let fd = Taylor2::<D2>::central_differences(
                    |p| [phase_weighted_angle(g, a, b, p, Outgoing::Direction(w_o)).value],
                    x,
                    1e-5,
                )[0];
                let scale = fd.grad.length().max(1e-9);
                assert!(
                    (t.grad - fd.grad).length() < 1e-5 * scale,
                    "g {g}: {:?} vs {:?}",
                    t.grad,
                    fd.grad
                );
                let hs = fd
                    .hess
                    .to_cols_array()
                    .iter()
                    .fold(0.0f64, |m, e| m.max(e.abs()))
                    .max(1e-9);
                let dh = (t.hess - fd.hess)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f64, |m, e| m.max(e.abs()));
                assert!(dh < 1e-3 * hs, "g {g}: {:?} vs {:?}", t.hess, fd.hess);
            }
        }
    }

    /// Towards a point, ω_o turns with x: the derivatives include it.
    #[test]
    fn towards_a_point_matches_differences() {
        let (a, b, x, e) = (
            DVec2::new(1.0, 0.5),
            DVec2::new(-0.5, 1.0),
            DVec2::new(0.1, -0.2),
            DVec2::new(3.0, -2.0),
        );
        let t = phase_weighted_angle(0.8, a, b, x, Outgoing::TowardsPoint(e));
        let fd = Taylor2::<D2>::central_differences(
            |p| [phase_weighted_angle(0.8, a, b, p, Outgoing::TowardsPoint(e)).value],
            x,
            1e-5,
        )[0];
        assert!((t.grad - fd.grad).length() < 1e-6 * fd.grad.length());
        assert!(
            (t.hess - fd.hess)
                .to_cols_array()
                .iter()
                .all(|d| d.abs() < 1e-4 * fd.hess.x_axis.length())
        );
    }
}
