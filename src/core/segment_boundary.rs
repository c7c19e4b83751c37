//! Flatland's counterpart of `core::lobe_boundary`: ∫ f T dθ over a segment next
//! to a surface, with its derivatives as terms at the segment's ends.
//!
//! Why: `phase_arc` integrates the phase exactly, but the transmittance was taken
//! as its mean over the segment's directions and multiplied in; where both turn
//! across a grazing segment (σ_t = 1, g = 0.6, or σ_t = 20, g = 0.9 below an
//! emitter) the product of means missed ∫ f T dθ and the gradient stayed 10–12%
//! off from d = 1e-5 to 1e-8 (`tests/exact_single_2d.rs`).
//!
//! With F(y − x) = f T n·(y − x)/|y − x|² over the line (dθ = F/(f T) ds), the
//! derivative along the line is −[F ν] at the ends, the one along its normal
//! Σ_ends F q + σ ∫ F ρ ds (q = ν·(y − x)/h, ρ = r/h; the line's points moved with x
//! so that they keep their directions), and once more for ∫ F ρ: every derivative
//! is a term at the ends, which two neighbours share with opposite ν and so cancel
//! exactly, but a σ² integral that is not differentiated. The integrals are taken
//! by Gauss–Legendre on pieces small against their distance and the lobe. With
//! ω_o turning with x (light towards a point), central differences in its angle.

use super::graded_rule::GAUSS5;
use super::phase::{G_MAX, Outgoing, phase_taylor_out};
use super::space::D2;
use super::taylor::Taylor2;
use super::transmittance::transmittance_taylor;
use glam::{DMat2, DVec2};

/// A piece is halved while its length exceeds this fraction of its nearest end's
/// distance, or its angle this fraction of its angle from the lobe's axis plus the
/// lobe's width.
const RATIO: f64 = 0.05;
const LEVELS: u32 = 40;

/// F at y with its derivatives in x (ω_o held along `w`), for the line's unit
/// normal `n` facing away from x.
fn integrand(g: f64, w: DVec2, sigma_t: f64, n: DVec2, y: DVec2, x: DVec2) -> Taylor2<D2> {
    let d = y - x;
    let r2 = d.length_squared().max(1e-300);
    let nd = n.dot(d);
    // n·d/r²: ∂_x d = −I, ∂_x r^{-2} = 2 d/r⁴.
    let grad = -n / r2 + d * (2.0 * nd / (r2 * r2));
    let outer = |a: DVec2, b: DVec2| DMat2::from_cols(a * b.x, a * b.y); // a bᵀ
    let hess = (outer(n, d) + outer(d, n)) * (-2.0 / (r2 * r2)) + outer(d, d) * (8.0 * nd / (r2 * r2 * r2))
        - DMat2::IDENTITY * (2.0 * nd / (r2 * r2));
    let density = Taylor2::new(nd / r2, grad, hess);
    phase_taylor_out::<D2>(g, x, y, Outgoing::Direction(w), 0.0)
        * density
        * transmittance_taylor::<D2>(sigma_t, x, y, 0.0)
}

/// ∫F ds, ∫F ρ ds and ∫F ρ² ds over a–b (values only).
fn moments(g: f64, w: DVec2, sigma_t: f64, n: DVec2, a: DVec2, b: DVec2, x: DVec2) -> [f64; 3] {
    let axis = if g > 0.0 { -w } else { w };
    let width = 1.0 - g.abs();
    let angle = |p: DVec2, q: DVec2| p.perp_dot(q).atan2(p.dot(q)).abs();
    let mut sum = [0.0; 3];
    let mut stack = vec![(a, b, 0u32)];
    while let Some((p, q, level)) = stack.pop() {
        let (rp, rq) = ((p - x).length(), (q - x).length());
        let span = angle(p - x, q - x);
        let mid = (p - x) / rp + (q - x) / rq;
        let off = (angle(mid, axis) - 0.5 * span).max(0.0);
        let coarse = (q - p).length() > RATIO * rp.min(rq) || span > RATIO * (off + width);
        if coarse && level < LEVELS {
            let m = 0.5 * (p + q);
            stack.extend([(m, q, level + 1), (p, m, level + 1)]);
            continue;
        }
        let len = (q - p).length();
        for (t, wt) in GAUSS5 {
            let y = p + (q - p) * t;
            let d = y - x;
            let (r, h) = (d.length(), n.dot(d));
            let f = integrand(g, w, sigma_t, n, y, x).value * wt * len;
            let rho = r / h;
            sum[0] += f;
            sum[1] += f * rho;
            sum[2] += f * rho * rho;
        }
    }
    sum
}

/// ∫ f T dθ over a–b (ω_o held along `w`), oriented as `phase_arc` does (negative
/// where b lies clockwise of a), with derivatives in x from the ends' terms.
fn held(g: f64, w: DVec2, sigma_t: f64, a: DVec2, b: DVec2, x: DVec2) -> Option<Taylor2<D2>> {
    let t = (b - a).try_normalize()?;
    let mut n = t.perp();
    if n.dot(a - x) < 0.0 {
        n = -n;
    }
    let h = n.dot(a - x);
    let near = (a - x).length().min((b - x).length());
    if h.is_nan() || h <= 1e-9 * near {
        return None;
    }
    let sign = if (a - x).perp_dot(b - x) >= 0.0 { 1.0 } else { -1.0 };
    let sigma = sigma_t.max(0.0);
    let [m0, m1, m2] = moments(g, w, sigma, n, a, b, x);
    let (mut flux, mut flux_grad) = (DVec2::ZERO, DMat2::ZERO);
    let (mut fq, mut fq_n, mut fqr) = (0.0, 0.0, 0.0);
    for (y, nu) in [(a, -t), (b, t)] {
        let f = integrand(g, w, sigma, n, y, x);
        let d = y - x;
        let (along, hy, r) = (nu.dot(d), n.dot(d), d.length());
        let q = along / hy;
        flux += nu * f.value;
        flux_grad += DMat2::from_cols(f.grad * nu.x, f.grad * nu.y);
        fq += f.value * q;
        fq_n += n.dot(f.grad) * q + f.value * along / (hy * hy);
        fqr += f.value * q * r / hy;
    }
    let grad = -flux + n * (fq + sigma * m1);
    let nn = DMat2::from_cols(n * n.x, n * n.y);
    let tangent = DMat2::IDENTITY - nn;
    let m = -flux_grad;
    let tt = tangent * m * tangent;
    let tt = (tt + tt.transpose()) * 0.5;
    let tn = tangent * m.transpose() * n;
    let col_n = DMat2::from_cols(tn * n.x, tn * n.y);
    let h_nn = fq_n + sigma * (fqr + sigma * m2);
    let hess = tt + col_n + col_n.transpose() + nn * h_nn;
    Some(Taylor2::new(m0, grad, hess) * sign)
}

/// ∫ f T dθ over the directions from `x` to the segment a–b per channel of the
/// extinction, with its derivatives as terms at the ends (see the module docs);
/// `None` where x lies on the segment's line.
pub fn segment_lobe_integral(
    g: f64,
    [a, b]: [DVec2; 2],
    x: DVec2,
    out: Outgoing<DVec2>,
    sigma_t: [f64; 3],
) -> Option<[Taylor2<D2>; 3]> {
    let g = g.clamp(-G_MAX, G_MAX);
    let angle_of = |w: DVec2| w.y.atan2(w.x);
    let from_angle = |phi: f64| DVec2::new(phi.cos(), phi.sin());
    let per_channel = |w: DVec2| -> Option<[Taylor2<D2>; 3]> {
        let mut out = [Taylor2::zero(); 3];
        for (o, &st) in out.iter_mut().zip(&sigma_t) {
            *o = held(g, w, st, a, b, x)?;
        }
        Some(out)
    };
    match out {
        Outgoing::Direction(w) => per_channel(w.try_normalize()?),
        Outgoing::TowardsPoint(e) => {
            // J(x, φ(x)) with φ the angle of e − x: central differences in φ.
            let u = e - x;
            let phi = angle_of(u);
            let delta = 1e-3 * (1.0 - g.abs()).max(1e-3);
            let (j, jp, jm) = (
                per_channel(from_angle(phi))?,
                per_channel(from_angle(phi + delta))?,
                per_channel(from_angle(phi - delta))?,
            );
            // ∇_x φ and its Hessian (φ = atan2(u_y, u_x), u = e − x).
            let r2 = u.length_squared();
            let dphi = DVec2::new(u.y, -u.x) / r2;
            let (hxx, hxy) = (2.0 * u.x * u.y, u.y * u.y - u.x * u.x);
            let hphi = DMat2::from_cols_array(&[hxx, hxy, hxy, -hxx]) / (r2 * r2);
            let outer = |p: DVec2, q: DVec2| DMat2::from_cols(p * q.x, p * q.y);
            Some(std::array::from_fn(|c| {
                let d1 = (jp[c] - jm[c]) * (0.5 / delta);
                let d2 = (jp[c].value - 2.0 * j[c].value + jm[c].value) / (delta * delta);
                let grad = j[c].grad + dphi * d1.value;
                let hess =
                    j[c].hess + outer(d1.grad, dphi) + outer(dphi, d1.grad) + outer(dphi, dphi) * d2 + hphi * d1.value;
                Taylor2::new(j[c].value, grad, hess)
            }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::phase_arc::phase_weighted_angle;

    fn max_abs(m: DMat2) -> f64 {
        m.to_cols_array().iter().map(|e| e.abs()).fold(0.0, f64::max)
    }

    /// In a vacuum the value and derivatives are `phase_arc`'s closed form, for
    /// light along a direction and towards a point, either orientation, g from
    /// −0.9 to 0.99; in fog they are those of the value (central differences).
    #[test]
    fn agrees_with_the_closed_form_and_its_own_value() {
        let (a, b) = (DVec2::new(-0.3, 0.5), DVec2::new(0.4, 0.55));
        let x = DVec2::new(0.05, 0.1);
        for g in [0.0, 0.6, -0.9, 0.99] {
            for out in [
                Outgoing::Direction(DVec2::new(0.2, -1.0).normalize()),
                Outgoing::TowardsPoint(DVec2::new(0.5, -2.0)),
            ] {
                for (p, q) in [(a, b), (b, a)] {
                    let got = segment_lobe_integral(g, [p, q], x, out, [0.0; 3]).unwrap()[0];
                    let want = phase_weighted_angle(g, p, q, x, out);
                    eprintln!("g {g}: {got:?}\n   vs {want:?}");
                    assert!((got.value - want.value).abs() < 1e-9 * want.value.abs());
                    assert!((got.grad - want.grad).length() < 1e-6 * want.grad.length());
                    assert!(max_abs(got.hess - want.hess) < 1e-4 * max_abs(want.hess));
                    let fog = |x: DVec2| segment_lobe_integral(g, [p, q], x, out, [1.5; 3]).unwrap()[0];
                    let fd = Taylor2::<D2>::central_differences(|x| [fog(x).value], x, 1e-4)[0];
                    let got = fog(x);
                    assert!((got.grad - fd.grad).length() < 1e-6 * fd.grad.length());
                    assert!(max_abs(got.hess - fd.hess) < 1e-4 * max_abs(fd.hess));
                }
            }
        }
    }
}
