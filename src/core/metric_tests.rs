//! Tests of the cache extents: the seed's radii with hand-computed values, every
//! clamp of theory.md §7, eigenvector and rotation covariance, and no NaN/inf.

use super::*;
use crate::core::rng::Sampler;
use crate::core::space::{D2, D3};
use glam::{DMat2, DMat3, DVec2, DVec3};
use std::f64::consts::{PI, TAU};

/// Wide clamps, no anisotropy or gradient limit: the bare seed formulas.
fn open(eps: f64) -> MetricParams {
    MetricParams {
        eps,
        r_min: 1e-9,
        r_max: 1e9,
        max_anisotropy: f64::INFINITY,
        luminance_floor: 0.0,
        limit_by_gradient: false,
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

fn radii2(e: &Extent<D2>) -> [f64; 2] {
    [e.radii.x, e.radii.y]
}

#[test]
fn seed_radius_2d_hand_value() {
    // (4·2·0.1/(π·0.5))^{1/4} = 0.5092958178940651^{1/4} = 0.8447778681174765.
    let e = second_order_extent::<D2>(2.0, DMat2::from_diagonal(DVec2::splat(0.5)), DVec2::ZERO, &open(0.1));
    for r in radii2(&e) {
        assert!(close(r, 0.8447778681174765, 1e-14), "{r}");
        assert!(close(r, (4.0 * 2.0 * 0.1 / (PI * 0.5)).powf(0.25), 1e-14));
    }
    assert!(e.is_isotropic());
    // A negative eigenvalue counts by its magnitude.
    let e = second_order_extent::<D2>(2.0, DMat2::from_diagonal(DVec2::splat(-0.5)), DVec2::ZERO, &open(0.1));
    assert!(close(e.radii.x, 0.8447778681174765, 1e-14));
}

#[test]
fn seed_radius_3d_hand_value() {
    // (15·2·0.1/(4π·0.5))^{1/5} = 0.477464829275686^{1/5} = 0.862557939976747.
    let e = second_order_extent::<D3>(2.0, DMat3::from_diagonal(DVec3::splat(0.5)), DVec3::ZERO, &open(0.1));
    for r in e.radii.to_array() {
        assert!(close(r, 0.862557939976747, 1e-14), "{r}");
        assert!(close(r, (15.0 * 2.0 * 0.1 / (4.0 * PI * 0.5)).powf(0.2), 1e-14));
    }
}

#[test]
fn radii_follow_their_eigenvalues() {
    // λ_x = 8, λ_y = 0.5: the x radius is (1/16)^{1/4} = ½ of the y radius.
    let h = DMat2::from_diagonal(DVec2::new(8.0, 0.5));
    let e = second_order_extent::<D2>(2.0, h, DVec2::ZERO, &open(0.1));
    // Ascending eigenvalues: column 0 is ±y (λ = 0.5), column 1 is ±x (λ = 8).
    assert!(e.axes.col(0).y.abs() > 1.0 - 1e-15 && e.axes.col(1).x.abs() > 1.0 - 1e-15);
    assert!(close(e.radii.x, 0.8447778681174765, 1e-14));
    assert!(close(e.radii.y, 0.42238893405873823, 1e-14));
    assert!(close(e.anisotropy(), 2.0, 1e-14));
    // Along x the extent reaches 0.422, along y 0.845.
    assert!(e.contains(DVec2::ZERO, DVec2::new(0.42, 0.0)));
    assert!(!e.contains(DVec2::ZERO, DVec2::new(0.43, 0.0)));
    assert!(e.contains(DVec2::ZERO, DVec2::new(0.0, 0.84)));
    let q = DVec2::new(3.0, -1.0);
    assert!(close(
        e.distance2(q, q + DVec2::new(0.0, 0.8447778681174765)),
        1.0,
        1e-13
    ));
    assert_eq!(e.tent_weight(q, q), 1.0);
}

#[test]
fn clamps_at_the_extremes() {
    let p = MetricParams::scene_relative(10.0, 0.1);
    p.validate().unwrap();
    let (lo, hi) = (p.r_min, p.r_max);
    let iso = |l: f64, lam: f64, p: &MetricParams| {
        second_order_extent::<D2>(l, DMat2::IDENTITY * lam, DVec2::ZERO, p)
            .radii
            .x
    };
    assert_eq!(iso(2.0, 1e-30, &p), hi); // λ → 0
    assert_eq!(iso(2.0, 0.0, &p), hi); // λ = 0
    assert_eq!(iso(1e-300, 0.5, &p), lo); // L → 0
    assert_eq!(iso(0.0, 0.5, &p), lo); // L = 0
    assert_eq!(iso(-3.0, 0.5, &p), lo); // L < 0 (noisy estimate)
    assert_eq!(iso(0.0, 0.0, &p), lo); // 0/0: the safe side
    assert_eq!(iso(2.0, 1e300, &p), lo); // λ huge
    assert_eq!(iso(1e300, 1e-300, &p), hi);
    let with_eps = |eps: f64| MetricParams { eps, ..p };
    assert_eq!(iso(2.0, 0.5, &with_eps(1e-300)), lo); // ε → 0
    assert_eq!(iso(2.0, 0.5, &with_eps(0.0)), lo); // ε = 0
    assert_eq!(iso(2.0, 0.5, &with_eps(1e300)), hi); // ε huge
    // Moderate inputs are untouched by the clamps.
    assert!(close(iso(2.0, 0.5, &p), 0.8447778681174765, 1e-14));
    // The luminance floor replaces L below it.
    let floored = MetricParams {
        luminance_floor: 2.0,
        ..p
    };
    assert!(close(iso(0.0, 0.5, &floored), 0.8447778681174765, 1e-14));
    // First order: R = εL/‖∇L‖ = 0.1·2/5 = 0.04; ∇L = 0 ⇒ r_max; L = 0 ⇒ r_min.
    let f = |l: f64, g: DVec2, p: &MetricParams| first_order_extent::<D2>(l, g, p).radii.x;
    assert!(close(f(2.0, DVec2::new(3.0, 4.0), &p), 0.04, 1e-15));
    assert!(first_order_extent::<D2>(2.0, DVec2::new(3.0, 4.0), &p).is_isotropic());
    assert_eq!(f(2.0, DVec2::ZERO, &p), hi);
    assert_eq!(f(0.0, DVec2::new(3.0, 4.0), &p), lo);
    assert_eq!(f(0.0, DVec2::ZERO, &p), lo);
    assert_eq!(f(2.0, DVec2::new(3.0, 4.0), &with_eps(0.0)), lo);
    assert_eq!(f(2.0, DVec2::new(1e300, 1e300), &p), lo);
    assert_eq!(f(2.0, DVec2::new(1e-300, 0.0), &p), hi);
    assert_eq!(f(1e300, DVec2::new(5e-324, 0.0), &with_eps(1e300)), hi);
    // ε > 1: the gradient limit R ≤ L/‖∇L‖ = 0.4 binds.
    assert!(close(f(2.0, DVec2::new(3.0, 4.0), &with_eps(3.0)), 0.4, 1e-15));
    let unlimited = MetricParams {
        limit_by_gradient: false,
        ..with_eps(3.0)
    };
    assert!(close(f(2.0, DVec2::new(3.0, 4.0), &unlimited), 1.2, 1e-15));
    let d3 = first_order_extent::<D3>(2.0, DVec3::new(0.0, 3.0, 4.0), &p);
    assert!(close(d3.radii.z, 0.04, 1e-15) && d3.is_isotropic());
}

/// The radius of `e` along the unit direction `dir` (one of its axes).
fn reach<S: Space>(e: &Extent<S>, dir: S::Vec) -> f64 {
    1.0 / e.distance2(S::zero(), dir).sqrt()
}

#[test]
fn anisotropy_clamp_raises_the_short_axes() {
    // λ ratio 10⁸ ⇒ raw radius ratio 100 in 2D; clamped to 4.
    let p = MetricParams {
        max_anisotropy: 4.0,
        ..open(0.1)
    };
    let h = DMat2::from_diagonal(DVec2::new(1.0, 1e-8));
    let e = second_order_extent::<D2>(2.0, h, DVec2::ZERO, &p);
    let long = (4.0 * 2.0 * 0.1 / (PI * 1e-8)).powf(0.25);
    // The small eigenvalue has an absolute error of order ulp(largest) (the 2D closed
    // form's mean − radius cancels), i.e. ~1e-8 relative here.
    assert!(close(reach(&e, DVec2::Y), long, 1e-8), "long axis unchanged");
    assert!(close(reach(&e, DVec2::X), long / 4.0, 1e-8), "short axis raised");
    assert!(close(e.anisotropy(), 4.0, 1e-14));
    // 3D: the two short axes are raised, the long one kept.
    let h = DMat3::from_diagonal(DVec3::new(1.0, 1e-10, 1.0));
    let e = second_order_extent::<D3>(2.0, h, DVec3::ZERO, &p);
    let long = (15.0 * 2.0 * 0.1 / (4.0 * PI * 1e-10)).powf(0.2);
    assert!(close(reach(&e, DVec3::Y), long, 1e-13));
    assert!(close(reach(&e, DVec3::X), long / 4.0, 1e-13) && close(reach(&e, DVec3::Z), long / 4.0, 1e-13));
    assert!(close(e.anisotropy(), 4.0, 1e-13));
}

#[test]
fn gradient_limit_keeps_first_order_term_below_l() {
    // L = 1, ∇L = (10, 0): R_x ≤ 1/10; the long y axis follows to ≤ 4·0.1.
    let p = MetricParams {
        max_anisotropy: 4.0,
        limit_by_gradient: true,
        ..open(0.1)
    };
    let h = DMat2::IDENTITY * 1e-6;
    let e = second_order_extent::<D2>(1.0, h, DVec2::new(10.0, 0.0), &p);
    assert!(close(reach(&e, DVec2::X), 0.1, 1e-14), "{:?}", e.radii);
    assert!(close(reach(&e, DVec2::Y), 0.4, 1e-14), "{:?}", e.radii);
    // Without the limit both radii are the seed's.
    let free = MetricParams {
        limit_by_gradient: false,
        ..p
    };
    let e = second_order_extent::<D2>(1.0, h, DVec2::new(10.0, 0.0), &free);
    assert!(close(reach(&e, DVec2::X), (4.0 * 0.1 / (PI * 1e-6)).powf(0.25), 1e-14));
    // The limit is on the component along each axis: ∇L along the long axis only.
    let h = DMat2::from_diagonal(DVec2::new(1.0, 0.1)); // long axis y, ratio 10^{1/4} < 4
    let e = second_order_extent::<D2>(1.0, h, DVec2::new(0.0, 2.0), &p);
    let short = (4.0 * 0.1 / PI).powf(0.25);
    assert!(close(reach(&e, DVec2::Y), 0.5, 1e-14), "{:?}", e.radii);
    assert!(close(reach(&e, DVec2::X), short, 1e-14), "{:?}", e.radii);
}

fn random_rotation2(s: &mut Sampler) -> DMat2 {
    DMat2::from_angle(TAU * s.next_f64())
}

fn random_rotation3(s: &mut Sampler) -> DMat3 {
    let axis = DVec3::new(s.next_f64() - 0.5, s.next_f64() - 0.5, s.next_f64() - 0.5);
    DMat3::from_axis_angle(axis.normalize(), TAU * s.next_f64())
}

/// Extents of (H, g) and of the rotated (QHQᵀ, Qg) agree: d_rot(Qu) = d(u); the
/// axes are the Hessian's eigenvectors (the rotated ellipse is the rotated one).
#[test]
fn rotation_covariance_and_eigenvectors() {
    let mut s = Sampler::new(11, 0);
    let p = MetricParams::scene_relative(4.0, 0.05);
    for _ in 0..500 {
        let mut u = || 2.0 * s.next_f64() - 1.0;
        let l = 0.5 + u().abs();
        let lam2 = DVec2::new(u() * 10.0, u() * 0.3);
        let g2 = DVec2::new(u(), u()) * 3.0;
        let lam3 = DVec3::new(u() * 10.0, u() * 0.3, u() * 2.0);
        let g3 = DVec3::new(u(), u(), u()) * 3.0;
        let (q2, q3) = (random_rotation2(&mut s), random_rotation3(&mut s));
        let base2 = second_order_extent::<D2>(l, DMat2::from_diagonal(lam2), g2, &p);
        let rot2 = second_order_extent::<D2>(l, q2 * DMat2::from_diagonal(lam2) * q2.transpose(), q2 * g2, &p);
        let base3 = second_order_extent::<D3>(l, DMat3::from_diagonal(lam3), g3, &p);
        let rot3 = second_order_extent::<D3>(l, q3 * DMat3::from_diagonal(lam3) * q3.transpose(), q3 * g3, &p);
        for _ in 0..8 {
            let v2 = DVec2::new(s.next_f64() - 0.5, s.next_f64() - 0.5);
            let (a, b) = (base2.distance2(DVec2::ZERO, v2), rot2.distance2(DVec2::ZERO, q2 * v2));
            assert!(close(b, a, 1e-9), "2D {a} vs {b}");
            let v3 = DVec3::new(s.next_f64() - 0.5, s.next_f64() - 0.5, s.next_f64() - 0.5);
            let (a, b) = (base3.distance2(DVec3::ZERO, v3), rot3.distance2(DVec3::ZERO, q3 * v3));
            assert!(close(b, a, 1e-9), "3D {a} vs {b}");
        }
        // Each axis of the rotated extent is an eigenvector of the rotated Hessian.
        let h3 = q3 * DMat3::from_diagonal(lam3) * q3.transpose();
        for k in 0..3 {
            let e = rot3.axes.col(k);
            let he = h3 * e;
            assert!((he - e * he.dot(e)).length() <= 1e-12 * 10.0, "not an eigenvector");
        }
    }
}

#[test]
fn extent_geometry() {
    // Axes rotated by 90°: column 0 = y, column 1 = −x; radii (1, 2).
    let e = Extent::<D2> {
        axes: DMat2::from_cols(DVec2::Y, -DVec2::X),
        radii: DVec2::new(1.0, 2.0),
    };
    let c = DVec2::new(1.0, 1.0);
    assert!(close(e.distance2(c, c + DVec2::new(2.0, 0.0)), 1.0, 1e-15));
    assert!(close(e.distance2(c, c + DVec2::new(0.0, 0.5)), 0.25, 1e-15));
    assert!(e.contains(c, c + DVec2::new(1.9, 0.0)) && !e.contains(c, c + DVec2::new(0.0, 1.0)));
    assert!(close(e.tent_weight(c, c + DVec2::new(0.0, 0.5)), 0.5, 1e-15));
    assert_eq!(e.tent_weight(c, c + DVec2::new(5.0, 0.0)), 0.0);
    assert_eq!(e.distance2(c, DVec2::NAN), f64::INFINITY);
    assert_eq!((e.bounding_radius(), e.min_radius()), (2.0, 1.0));
    assert!(!e.is_isotropic() && Extent::<D3>::isotropic(0.3).is_isotropic());
    assert!((e.half_widths() - DVec2::new(2.0, 1.0)).length() < 1e-15);
    // A 45° ellipse with radii (1, 3): h = sqrt((1² + 3²)/2) on both axes.
    let r = DMat2::from_angle(PI / 4.0);
    let e = Extent::<D2> {
        axes: r,
        radii: DVec2::new(1.0, 3.0),
    };
    assert!((e.half_widths() - DVec2::splat(5f64.sqrt())).length() < 1e-14);
}

#[test]
fn params_validation() {
    let p = MetricParams::scene_relative(2.0, 0.1);
    assert_eq!((p.r_min, p.r_max, p.max_anisotropy), (2e-3, 0.5, 4.0));
    assert!(p.validate().is_ok());
    assert!(MetricParams { eps: f64::NAN, ..p }.validate().is_err());
    assert!(MetricParams { eps: -1.0, ..p }.validate().is_err());
    assert!(MetricParams { r_min: 0.0, ..p }.validate().is_err());
    assert!(MetricParams { r_max: 1e-4, ..p }.validate().is_err());
    assert!(
        MetricParams {
            r_max: f64::INFINITY,
            ..p
        }
        .validate()
        .is_err()
    );
    assert!(
        MetricParams {
            max_anisotropy: 0.5,
            ..p
        }
        .validate()
        .is_err()
    );
    assert!(
        MetricParams {
            max_anisotropy: f64::INFINITY,
            ..p
        }
        .validate()
        .is_ok()
    );
    assert!(
        MetricParams {
            luminance_floor: -1.0,
            ..p
        }
        .validate()
        .is_err()
    );
    assert!(MetricParams::scene_relative(f64::NAN, 0.1).validate().is_err());
}

/// A magnitude 10^[-300, 300], sometimes 0, NaN, ±∞ or subnormal, of either sign.
fn wild(s: &mut Sampler) -> f64 {
    let sign = if s.next_f64() < 0.5 { -1.0 } else { 1.0 };
    match s.next_index(40) {
        0 => 0.0,
        1 => f64::NAN,
        2 => f64::INFINITY * sign,
        3 => 5e-324 * sign,
        4 => f64::MAX * sign,
        _ => sign * 10f64.powf(600.0 * s.next_f64() - 300.0),
    }
}

fn check_extent<S: Space>(e: &Extent<S>, p: &MetricParams) {
    for k in 0..S::DIM {
        let r = e.radii[k];
        assert!(
            r.is_finite() && r >= p.r_min && r <= p.r_max,
            "radius {r} out of bounds"
        );
    }
    assert!(
        e.anisotropy() <= p.max_anisotropy * (1.0 + 1e-12),
        "anisotropy {}",
        e.anisotropy()
    );
    assert!(S::mat_is_finite(e.axes));
    let ortho = S::frobenius(S::transpose(e.axes) * e.axes - S::identity());
    assert!(ortho < 1e-12, "axes not orthonormal: {ortho:e}");
    assert!(S::vec_is_finite(e.half_widths()));
}

#[test]
fn never_nan_for_wild_inputs() {
    let mut s = Sampler::new(12, 0);
    for i in 0..20_000 {
        let mut p = MetricParams::scene_relative(10f64.powi(i % 7 - 3), 10f64.powf(6.0 * s.next_f64() - 4.0));
        p.limit_by_gradient = i % 2 == 0;
        p.luminance_floor = if i % 5 == 0 { 1e-3 } else { 0.0 };
        let l = wild(&mut s);
        let (a, b, c) = (wild(&mut s), wild(&mut s), wild(&mut s));
        let h2 = DMat2::from_cols(DVec2::new(a, b), DVec2::new(b, c));
        let g2 = DVec2::new(wild(&mut s), wild(&mut s));
        check_extent(&second_order_extent::<D2>(l, h2, g2, &p), &p);
        check_extent(&first_order_extent::<D2>(l, g2, &p), &p);
        let (d, e, f) = (wild(&mut s), wild(&mut s), wild(&mut s));
        let h3 = DMat3::from_cols(DVec3::new(a, b, c), DVec3::new(b, d, e), DVec3::new(c, e, f));
        let g3 = DVec3::new(wild(&mut s), wild(&mut s), wild(&mut s));
        check_extent(&second_order_extent::<D3>(l, h3, g3, &p), &p);
        check_extent(&first_order_extent::<D3>(l, g3, &p), &p);
        // Non-finite input gives the smallest extent.
        if !(l.is_finite() && h3.is_finite() && g3.is_finite()) {
            assert_eq!(second_order_extent::<D3>(l, h3, g3, &p).bounding_radius(), p.r_min);
        }
    }
    // Invalid parameters still give finite extents.
    let bad = MetricParams {
        eps: f64::NAN,
        r_min: -1.0,
        r_max: f64::NAN,
        max_anisotropy: f64::NAN,
        luminance_floor: f64::NAN,
        limit_by_gradient: true,
    };
    let e = second_order_extent::<D2>(1.0, DMat2::IDENTITY, DVec2::X, &bad);
    assert!(e.radii.is_finite() && e.radii.min_element() > 0.0);
}

/// At the gradient-noise radius the noise's error integrated over the ball,
/// ∫ σ |u·e| dV (a midpoint rule in polar / spherical coordinates), is εL/2, in
/// 2D and 3D; it falls as σ^{−1/(d+1)}; exact gradients and bad input are safe.
#[test]
fn gradient_noise_radius_spends_the_seeds_error() {
    let p = open(0.02);
    let (l, var) = (3.0, 0.5);
    let sigma: f64 = 0.5f64.sqrt();
    let n = 400;
    let h = |k: usize| (k as f64 + 0.5) / n as f64;
    // 2D: ∫_0^R r² dr ∫ |cos φ| dφ.
    let r2 = gradient_noise_radius::<D2>(l, var, &p);
    let radial2: f64 = (0..n).map(|k| (h(k) * r2).powi(2) * r2 / n as f64).sum();
    let angular2: f64 = (0..n).map(|k| (TAU * h(k)).cos().abs() * TAU / n as f64).sum();
    assert!(close(sigma * radial2 * angular2, p.eps * l / 2.0, 1e-4), "2D");
    // 3D: ∫_0^R r³ dr ∫ |cos θ| sin θ dθ dφ.
    let r3 = gradient_noise_radius::<D3>(l, var, &p);
    let radial3: f64 = (0..n).map(|k| (h(k) * r3).powi(3) * r3 / n as f64).sum();
    let polar: f64 = (0..n)
        .map(|k| (PI * h(k)).cos().abs() * (PI * h(k)).sin() * PI / n as f64)
        .sum();
    assert!(close(sigma * radial3 * polar * TAU, p.eps * l / 2.0, 1e-4), "3D");
    let quarter = gradient_noise_radius::<D3>(l, var * 16.0, &p);
    assert!(close(quarter, r3 * 4f64.powf(-0.25), 1e-12));
    assert_eq!(gradient_noise_radius::<D3>(l, 0.0, &p), f64::INFINITY);
    for (l, var) in [
        (f64::NAN, 1.0),
        (1.0, f64::NAN),
        (1.0, f64::INFINITY),
        (0.0, 1.0),
        (f64::INFINITY, 1.0),
    ] {
        assert_eq!(gradient_noise_radius::<D2>(l, var, &p), p.r_min, "{l} {var}");
    }
    assert_eq!(gradient_noise_radius::<D2>(1.0, 1e300, &p), p.r_min);
}
