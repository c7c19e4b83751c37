//! Radiometry of the flatland path tracer against closed forms (theory.md §9).

use glam::DVec2;
use std::f64::consts::TAU;
use volcache::core::phase::Hg2;
use volcache::flatland::field::{FieldParams, render_field};
use volcache::flatland::scene::Scene;
use volcache::pipeline::path::{Query, Settings, estimate, estimate_radiance};
use volcache::progress::Progress;

fn scene(json: &str) -> Scene {
    Scene::from_json(json, "test").unwrap()
}

/// 2D point light in vacuum: fluence I / r, exactly (it is evaluated analytically).
#[test]
fn point_light_in_vacuum_gives_i_over_r() {
    let s = scene(
        r#"{ "domain": {"min": [-2,-2], "max": [2,2]},
        "lights": [{"type": "point", "position": [0.5, 0.25], "intensity": [1, 2, 3]}] }"#,
    );
    assert!(s.medium.is_none());
    for r in [1e-3, 0.1, 1.0, 1.7] {
        let e = estimate(
            &s,
            DVec2::new(0.5 + r, 0.25),
            &Query::Fluence,
            &Settings::default(),
            4,
            0,
            0,
        );
        for c in 0..3 {
            let want = (c + 1) as f64 / r;
            assert!(
                (e.mean.direct[c] - want).abs() < 1e-12 * want,
                "r={r}: {}",
                e.mean.direct
            );
        }
        assert_eq!(e.mean.single + e.mean.multiple, glam::DVec3::ZERO);
    }
}

/// Uncollided fluence of a point source of power P in an absorbing medium:
/// P e^{−σ_t r} / (2π r), per channel.
#[test]
fn uncollided_fluence_in_a_medium() {
    let p = 3.0;
    let s = scene(&format!(
        r#"{{ "domain": {{"min": [-5,-5], "max": [5,5]}},
        "lights": [{{"type": "point", "position": [0, 0], "intensity": {}}}],
        "medium": {{"sigma_a": [0.5, 1.0, 2.0], "sigma_s": 0}} }}"#,
        p / TAU
    ));
    for r in [0.01, 0.5, 2.0, 4.0] {
        let e = estimate(&s, DVec2::new(0.0, r), &Query::Fluence, &Settings::default(), 2, 0, 0);
        for (c, sig) in [0.5, 1.0, 2.0].into_iter().enumerate() {
            let want = p * (-sig * r).exp() / (TAU * r);
            assert!(
                (e.mean.total()[c] - want).abs() < 1e-12 * want,
                "r={r} c={c}: {} vs {want}",
                e.mean.total()[c]
            );
        }
    }
}

/// Single scattering from a point light (anisotropic medium) along one ray, against
/// an independent quadrature of ∫ T σ_s f I T / r dt.
#[test]
fn single_scattering_matches_quadrature() {
    let (sig_s, sig_a, g, i0) = (0.8, 0.2, 0.5, 1.3);
    let s = scene(&format!(
        r#"{{ "domain": {{"min": [-5,-5], "max": [5,5]}},
        "lights": [{{"type": "point", "position": [0, 0], "intensity": {i0}}}],
        "medium": {{"sigma_a": {sig_a}, "sigma_s": {sig_s}, "g": {g}}} }}"#
    ));
    let x = DVec2::new(1.0, 0.5);
    let w = DVec2::new(-0.8, 1.0).normalize();
    let hg = Hg2::new(g);
    let sig_t = sig_a + sig_s;
    let integrand = |t: f64| {
        let p = x + w * t;
        let r = p.length();
        (-sig_t * t).exp() * sig_s * hg.eval(p / r, -w) * i0 * (-sig_t * r).exp() / r
    };
    // Composite Simpson on [0, 40] (e^{−40} is negligible).
    let n = 400_000;
    let h = 40.0 / n as f64;
    let quad = (0..=n)
        .map(|k| {
            let wgt = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            wgt * integrand(k as f64 * h)
        })
        .sum::<f64>()
        * h
        / 3.0;
    let settings = Settings {
        max_depth: 1,
        rr_depth: 100,
    };
    let (mean, se) = estimate_radiance(&s, x, w, &settings, 400_000, 5);
    println!("single scattering: MC {} ± {} vs quadrature {quad}", mean.x, se.x);
    assert!((mean.x - quad).abs() < 4.0 * se.x, "MC {} ± {} vs {quad}", mean.x, se.x);
    assert!(se.x < 0.01 * quad);
}

/// Flatland furnace: L = L_e / (1 − ρ) everywhere; with a non-absorbing medium
/// L_s = σ_s L, in vacuum the fluence is 2π L.
#[test]
fn furnace_with_and_without_medium() {
    let base = std::fs::read_to_string("flatland_scenes/furnace.json").unwrap();
    let with = scene(&base);
    let mut desc = with.desc.clone();
    desc.medium = None;
    let without = Scene::from_desc(desc, "furnace-vacuum").unwrap();
    let settings = Settings::default();
    for (k, x) in [DVec2::ZERO, DVec2::new(0.9, -0.95), DVec2::new(-0.999, 0.3)]
        .into_iter()
        .enumerate()
    {
        let e = estimate(
            &with,
            x,
            &Query::InScattered { omega_o: DVec2::X },
            &settings,
            60_000,
            1,
            k as u64,
        );
        let se = e.std_error.single.x.hypot(e.std_error.multiple.x);
        assert!(
            (e.mean.total().x - 2.0).abs() < 4.0 * se && se < 0.01,
            "L_s at {x}: {} ± {se}",
            e.mean.total().x
        );
        let e = estimate(&without, x, &Query::Fluence, &settings, 20_000, 1, k as u64);
        let se = e.std_error.single.x;
        assert!(
            (e.mean.total().x - 2.0 * TAU).abs() < 4.0 * se && se < 0.05,
            "φ at {x}: {} ± {se}",
            e.mean.total().x
        );
    }
}

/// The mean over independent seeds converges to the closed form, and the spread
/// of single estimates shrinks like 1/√N.
#[test]
fn estimates_are_unbiased_with_error_shrinking_as_inverse_sqrt_n() {
    let s = Scene::load(std::path::Path::new("flatland_scenes/point_in_fog.json")).unwrap();
    let want = 0.3234545; // benchmarks.md, c = 0.9, r = 1
    let x = DVec2::new(1.0, 0.0);
    let mut rms = Vec::new();
    for n in [250u32, 4000] {
        let seeds = 48;
        let vals: Vec<f64> = (0..seeds)
            .map(|seed| {
                estimate(&s, x, &Query::Fluence, &Settings::default(), n, seed, 0)
                    .mean
                    .total()
                    .x
            })
            .collect();
        let mean = vals.iter().sum::<f64>() / seeds as f64;
        let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64).sqrt();
        assert!(
            (mean - want).abs() < 4.0 * sd / (seeds as f64).sqrt(),
            "N={n}: mean {mean} ± {sd}"
        );
        rms.push((vals.iter().map(|v| (v - want).powi(2)).sum::<f64>() / seeds as f64).sqrt());
    }
    let ratio = rms[0] / rms[1];
    println!("rms error ratio for 16x samples: {ratio} (expected 4)");
    assert!((2.8..5.7).contains(&ratio), "error ratio {ratio}");
}

/// Same seed, bit-identical field with 1 and 2 threads.
#[test]
fn fields_are_deterministic_across_thread_counts() {
    let s = Scene::load(std::path::Path::new("flatland_scenes/windows.json")).unwrap();
    let mut p = FieldParams::from_scene(&s);
    (p.width, p.height, p.spp) = (22, 15, 4);
    let render = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render_field(&s, &p, &Progress::new()).unwrap())
    };
    let (a, b) = (render(1), render(2));
    assert_eq!(a.field, b.field);
    assert_eq!(a.rays, b.rays);
    assert!(a.field.values.iter().any(|v| v.x > 0.0));
}

/// A scene without a medium has no L_s anywhere, and renders fluence everywhere.
#[test]
fn vacuum_scene_renders_without_a_medium() {
    let s = scene(
        r#"{ "domain": {"min": [-1,-1], "max": [1,1]},
        "segments": [{"a": [-1, 0.9], "b": [1, 0.9], "emission": 1}] }"#,
    );
    let mut p = FieldParams::from_scene(&s);
    (p.width, p.height, p.spp) = (8, 8, 2);
    let ls = render_field(&s, &p, &Progress::new()).unwrap();
    assert!(ls.field.valid.iter().all(|v| !v) && ls.field.values.iter().all(|v| *v == glam::DVec3::ZERO));
    p.quantity = volcache::flatland::scene_desc::Quantity::Fluence;
    let phi = render_field(&s, &p, &Progress::new()).unwrap();
    assert!(phi.field.valid.iter().all(|v| *v) && phi.field.values.iter().all(|v| v.x > 0.0));
}

/// Cancellation stops a render with an error instead of a partial field.
#[test]
fn cancelled_render_returns_cancelled() {
    let s = Scene::default_scene();
    let p = FieldParams::from_scene(&s);
    let progress = Progress::new();
    progress.cancel();
    assert!(render_field(&s, &p, &progress).is_err());
}

/// A thin, non-absorbing, unbounded fog cannot keep paths scattering forever far
/// away: they leave the world disc and end (no hang, bounded cost per sample).
#[test]
fn thin_unbounded_fog_terminates_paths() {
    let s = scene(
        r#"{ "domain": {"min": [-1,-1], "max": [1,1]},
        "segments": [{"a": [-0.5, 0.9], "b": [0.5, 0.9], "emission": 1}],
        "medium": {"sigma_a": 0, "sigma_s": 1e-6} }"#,
    );
    let e = estimate(
        &s,
        DVec2::ZERO,
        &Query::InScattered { omega_o: DVec2::X },
        &Settings::default(),
        1000,
        0,
        0,
    );
    assert!(e.rays < 10 * 1000, "{} rays for 1000 samples", e.rays);
    assert!(e.mean.total().x > 0.0 && e.mean.total().x.is_finite());
}
