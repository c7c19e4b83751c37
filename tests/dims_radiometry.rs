//! Radiometry of the path tracer against closed forms and quadrature, written once
//! and run in 2D and in 3D (theory.md §1, §9): the furnace, a point light in vacuum
//! and through an absorbing medium, single scattering along a ray, and images that
//! do not depend on the thread count. Statistical checks: within 4 standard errors,
//! with the standard error below a stated fraction of the value.

mod common;

use common::{Fixture, Spec};
use volcache::core::color::Rgb;
use volcache::core::rng::Sampler;
use volcache::core::space::{D2, D3};
use volcache::pipeline::path::{Query, Settings, estimate, estimate_with, radiance_path, sample_query};
use volcache::pipeline::world::{VecOf, World};

/// Per channel: within 4 standard errors of `want`, the standard error below
/// `rel_se` of it.
fn check(what: &str, (mean, se): (Rgb, Rgb), want: Rgb, rel_se: f64) {
    eprintln!("{what}: {mean} ± {se} (want {want})");
    for c in 0..3 {
        assert!(
            se[c] <= rel_se * want[c],
            "{what}: channel {c}: standard error {} above {rel_se} of {}",
            se[c],
            want[c]
        );
        assert!(
            (mean[c] - want[c]).abs() <= 4.0 * se[c],
            "{what}: channel {c}: {} vs {} ({:.1} standard errors)",
            mean[c],
            want[c],
            (mean[c] - want[c]).abs() / se[c]
        );
    }
}

/// Exactly (NEE is deterministic and nothing else contributes): 10⁻¹² relative.
fn exact(what: &str, got: Rgb, want: Rgb) {
    assert!(
        (got - want).abs().max_element() <= 1e-12 * want.max_element(),
        "{what}: {got} vs {want}"
    );
}

/// Mean and standard error of the query's total (all parts) at `x` from `n` samples.
fn total<W: World>(world: &W, x: VecOf<W>, q: Query<W::S>, n: u64, seed: u64, item: u64) -> (Rgb, Rgb) {
    let mut rays = 0;
    estimate_with(n, seed, item, |s| {
        sample_query(world, x, &q, &deep(), s, &mut rays).total()
    })
}

fn deep() -> Settings {
    Settings {
        max_depth: 100_000,
        rr_depth: 3,
        ..Default::default()
    }
}

/// A closed box whose walls all emit L_e and reflect ρ, filled with a non-absorbing
/// anisotropic chromatic medium: L = L_e/(1 − ρ) in every direction at every point
/// (here 1 per channel), so L_s = σ_s L; in vacuum the fluence is |S^{d−1}| L.
fn furnace<F: Fixture>() {
    let (le, rho) = (Rgb::new(0.4, 0.5, 0.7), Rgb::new(0.6, 0.5, 0.3));
    let l = le / (Rgb::ONE - rho);
    let sigma_s = Rgb::new(1.0, 0.8, 0.6);
    let fog = F::scene(&Spec {
        walls: Some((le, rho)),
        medium: Some((Rgb::ZERO, sigma_s, 0.5)),
        ..Spec::default()
    });
    let vacuum = F::scene(&Spec {
        walls: Some((le, rho)),
        ..Spec::default()
    });
    let name = |what: &str, k: usize| format!("{}D furnace, {what} at point {k}", F::DIM);
    // The centre, near a corner, a hair from a wall.
    let points = [[0.0, 0.0, 0.0], [0.9, -0.95, 0.3], [-0.999, 0.3, -0.5]];
    for (k, c) in points.into_iter().enumerate() {
        let x = F::point(c);
        let omega_o = F::axis(0);
        let ls = total(&fog, x, Query::InScattered { omega_o }, 60_000, 1, k as u64);
        check(&name("L_s", k), ls, sigma_s * l, 0.005);
        let phi = total(&vacuum, x, Query::Fluence, 30_000, 1, k as u64);
        check(&name("vacuum fluence", k), phi, l * F::SPHERE_MEASURE, 0.004);
        // The radiance itself, along random directions through the medium.
        let mut rays = 0;
        let est = estimate_with(40_000, 3, k as u64, |s| {
            let w = F::sample_uniform(s);
            radiance_path(&fog, x, w, None, None, &deep(), s, &mut rays).0
        });
        check(&name("L", k), est, l, 0.01);
    }
}

#[test]
fn furnace_2d() {
    furnace::<D2>();
}

#[test]
fn furnace_3d() {
    furnace::<D3>();
}

/// A point light in vacuum: fluence I/r^{d−1} (theory.md §1) from the delta-light
/// term alone, and a one-sided diffuse floor under it reflects
/// L = ρ (cosθ/2 or cosθ/π) I/r^{d−1} towards any viewer above it: both exact.
fn point_light_in_vacuum<F: Fixture>() {
    let (pos, i) = ([0.5, 0.25, -0.3], Rgb::new(1.0, 2.0, 3.0));
    let s = F::scene(&Spec {
        point_light: Some((pos, i)),
        ..Spec::default()
    });
    let light = F::point(pos);
    for r in [1e-3, 0.1, 1.0, 1.7] {
        let e = estimate(&s, light + F::axis(0) * r, &Query::Fluence, &deep(), 4, 0, 0);
        exact(
            &format!("{}D fluence at r = {r}", F::DIM),
            e.mean.direct,
            i / r.powi(F::DIM as i32 - 1),
        );
        assert_eq!(e.mean.single + e.mean.multiple, Rgb::ZERO);
    }
    let rho = Rgb::new(0.5, 0.25, 0.8);
    let (pos, i) = ([0.3, 1.2, 0.2], Rgb::new(2.0, 3.0, 1.0));
    let s = F::scene(&Spec {
        floor: Some(rho),
        point_light: Some((pos, i)),
        ..Spec::default()
    });
    let (eye, y) = (F::point([-1.0, 2.0, 2.0]), F::point([0.1, 0.0, -0.2]));
    let to_light = F::point(pos) - y;
    let r = F::length(to_light);
    let want = rho * F::lambert(to_light[1] / r) * i / r.powi(F::DIM as i32 - 1);
    let dir = (y - eye) / F::length(y - eye);
    let mut rays = 0;
    for k in 0..16 {
        let l = radiance_path(&s, eye, dir, None, None, &deep(), &mut Sampler::new(1, k), &mut rays).0;
        exact(&format!("{}D lit floor, sample {k}", F::DIM), l, want);
    }
}

#[test]
fn point_light_in_vacuum_2d() {
    point_light_in_vacuum::<D2>();
}

#[test]
fn point_light_in_vacuum_3d() {
    point_light_in_vacuum::<D3>();
}

/// The uncollided light of a point light through a purely absorbing chromatic
/// medium: fluence I e^{−σ_t r}/r^{d−1} per channel, exactly.
fn uncollided_point_light<F: Fixture>() {
    let (i, sigma_a) = (Rgb::new(1.3, 0.7, 2.0), Rgb::new(0.5, 1.0, 2.0));
    let s = F::scene(&Spec {
        point_light: Some(([0.0; 3], i)),
        medium: Some((sigma_a, Rgb::ZERO, 0.0)),
        ..Spec::default()
    });
    for r in [0.01, 0.5, 2.0, 4.0] {
        let e = estimate(&s, F::axis(1) * r, &Query::Fluence, &deep(), 2, 0, 0);
        let want = i * (-sigma_a * r).exp() / r.powi(F::DIM as i32 - 1);
        exact(
            &format!("{}D uncollided fluence at r = {r}", F::DIM),
            e.mean.total(),
            want,
        );
    }
}

#[test]
fn uncollided_point_light_2d() {
    uncollided_point_light::<D2>();
}

#[test]
fn uncollided_point_light_3d() {
    uncollided_point_light::<D3>();
}

/// Composite Simpson's rule of `f` on [0, len] with `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, len: f64, n: usize) -> f64 {
    let h = len / n as f64;
    let w = |k: usize| match k {
        0 => 1.0,
        k if k == n => 1.0,
        k if k % 2 == 1 => 4.0,
        _ => 2.0,
    };
    (0..=n).map(|k| w(k) * f(k as f64 * h)).sum::<f64>() * h / 3.0
}

/// Single scattering (paths of one vertex) from a point light along one ray through
/// an anisotropic medium, against Simpson quadrature of
/// ∫ σ_s e^{−σ_t t} f(μ) I e^{−σ_t r}/r^{d−1} dt, with the Henyey–Greenstein phase
/// function written out here from theory.md §1:
/// f(μ) = (1 − g²) / (|S^{d−1}| (1 + g² − 2gμ)^{d/2}).
fn single_scattering_matches_quadrature<F: Fixture>() {
    let (sa, ss, g, i) = (0.3, 0.5, 0.5, 2.0);
    let s = F::scene(&Spec {
        point_light: Some(([0.0, 1.0, 0.0], Rgb::splat(i))),
        medium: Some((Rgb::splat(sa), Rgb::splat(ss), g)),
        ..Spec::default()
    });
    let (o, light) = (F::point([-2.0, 0.0, 0.0]), F::point([0.0, 1.0, 0.0]));
    let d = F::point([1.0, 0.3, 0.2]);
    let d = d / F::length(d);
    let st = sa + ss;
    let hg = |mu: f64| (1.0 - g * g) / (F::SPHERE_MEASURE * (1.0 + g * g - 2.0 * g * mu).powf(F::DIM as f64 / 2.0));
    let integrand = |t: f64| {
        let to = light - (o + d * t);
        let r = F::length(to);
        ss * (-st * t).exp() * hg(F::dot(d, to) / r) * i * (-st * r).exp() / r.powi(F::DIM as i32 - 1)
    };
    // e^{−0.8·60} is negligible.
    let want = simpson(integrand, 60.0, 200_000);
    let settings = Settings {
        max_depth: 1,
        rr_depth: 3,
        ..Default::default()
    };
    let mut rays = 0;
    let est = estimate_with(200_000, 5, 0, |smp| {
        radiance_path(&s, o, d, None, None, &settings, smp, &mut rays).0
    });
    check(&format!("{}D single scattering", F::DIM), est, Rgb::splat(want), 0.005);
}

#[test]
fn single_scattering_matches_quadrature_2d() {
    single_scattering_matches_quadrature::<D2>();
}

#[test]
fn single_scattering_matches_quadrature_3d() {
    single_scattering_matches_quadrature::<D3>();
}

/// A thin, non-absorbing, unbounded fog cannot keep paths scattering forever far
/// away: they leave the world sphere and end (bounded cost per sample).
fn thin_unbounded_fog_terminates_paths<F: Fixture>() {
    let s = F::scene(&Spec {
        ceiling: Some(Rgb::ONE),
        medium: Some((Rgb::ZERO, Rgb::splat(1e-6), 0.0)),
        ..Spec::default()
    });
    let q = Query::InScattered { omega_o: F::axis(0) };
    let e = estimate(&s, F::point([0.0; 3]), &q, &Settings::default(), 1000, 0, 0);
    assert!(e.rays < 10 * 1000, "{}D: {} rays for 1000 samples", F::DIM, e.rays);
    assert!(e.mean.total().x > 0.0 && e.mean.total().x.is_finite());
}

#[test]
fn thin_unbounded_fog_terminates_paths_2d() {
    thin_unbounded_fog_terminates_paths::<D2>();
}

#[test]
fn thin_unbounded_fog_terminates_paths_3d() {
    thin_unbounded_fog_terminates_paths::<D3>();
}

/// The same seed gives the same field (image) bit for bit with one and two threads.
fn renders_do_not_depend_on_threads<F: Fixture>() {
    let (s, _) = F::fog_scene();
    let (a, b) = (F::render(&s, 1), F::render(&s, 2));
    assert!(a.values.iter().any(|v| v.max_element() > 0.0));
    assert_eq!(a, b, "{}D: the render differs between 1 and 2 threads", F::DIM);
}

#[test]
fn renders_do_not_depend_on_threads_2d() {
    renders_do_not_depend_on_threads::<D2>();
}

#[test]
fn renders_do_not_depend_on_threads_3d() {
    renders_do_not_depend_on_threads::<D3>();
}
