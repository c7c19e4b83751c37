//! Stratified sampling (`Sampler::stratified`, `path::Sampling`): a pixel's or a
//! point's samples are one padded, Owen-scrambled Sobol' set. On scenes of our own
//! — a wide sky strip seen through a comb of thin slats (2D), an area lamp behind
//! a bar over a floor (3D) — the set's estimate keeps the independent samples'
//! mean (unbiased, against a converged reference) and spreads less over seeds:
//! the straight light from an emitter seen between occluders is a function with
//! jumps, whose stratified estimate converges ~1/n. Both the per-pixel direct
//! light of the caches (`direct_mean`) and the path tracer (`estimate`) are
//! checked; dimensions beyond the set's (later bounces) stay independent.

use glam::{DVec2, DVec3};
use std::path::Path;
use volcache::core::color::{Rgb, luminance};
use volcache::core::rng::Sampler;
use volcache::pipeline::lobe::Lobe;
use volcache::pipeline::path::{Query, Sampling, Settings, direct_at, direct_mean, estimate};
use volcache::pipeline::world::{VecOf, World};

/// A sky strip above a comb of seven thin slats in light fog: below the comb the
/// strip is seen through gaps, so the straight light has many jumps in angle.
fn comb_2d() -> volcache::flatland::scene::Scene {
    let mut segments = vec![
        r#"{"name": "sky", "a": [2, 1.5], "b": [-2, 1.5], "emission": [1.0, 0.9, 0.8], "two_sided": false}"#
            .to_string(),
        r#"{"name": "floor", "a": [-2, -1.5], "b": [2, -1.5], "reflectance": 0.5}"#.to_string(),
    ];
    for k in 0..7 {
        let x = -1.2 + 0.4 * k as f64;
        segments.push(format!(
            r#"{{"name": "slat {k}", "a": [{x}, 0.6], "b": [{}, 0.75], "reflectance": 0.3}}"#,
            x + 0.15
        ));
    }
    let json = format!(
        r#"{{"domain": {{"min": [-2, -1.5], "max": [2, 1.5]}}, "segments": [{}],
            "medium": {{"sigma_a": 0.05, "sigma_s": 0.4, "g": 0.4, "region": "domain"}},
            "render": {{"resolution": [32, 24], "spp": 16, "seed": 1}}}}"#,
        segments.join(",")
    );
    volcache::flatland::scene::Scene::from_json(&json, "<comb 2d>").unwrap_or_else(|e| panic!("{e}"))
}

/// An area lamp above a bar over a floor, in a fog box.
fn lamp_bar_3d() -> volcache::volume::scene::Scene {
    let json = r#"{
  "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov_deg": 45},
  "shapes": [
    {"quad": {"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}, "name": "floor", "reflectance": 0.5},
    {"box": {"min": [-0.8, 1.0, -0.1], "max": [0.8, 1.1, 0.1]}, "name": "bar", "reflectance": 0.4},
    {"quad": {"origin": [-0.6, 1.8, -0.6], "u": [1.2, 0, 0], "v": [0, 0, 1.2]}, "name": "lamp",
     "reflectance": 0, "emission": [6, 5, 4], "two_sided": true}
  ],
  "medium": {"sigma_a": 0.05, "sigma_s": 0.5, "g": 0.3,
             "region": {"box": {"min": [-2, 0, -2], "max": [2, 2, 2]}}},
  "render": {"resolution": [16, 12], "spp": 4, "seed": 1, "max_depth": 16}
}"#;
    volcache::volume::scene::Scene::from_json(json, "<lamp bar 3d>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// Mean and spread (standard deviation over seeds) of `f(seed)`'s luminance.
fn over_seeds(seeds: u64, f: impl Fn(u64) -> Rgb) -> (f64, f64) {
    let v: Vec<f64> = (0..seeds).map(|s| luminance(f(s))).collect();
    let mean = v.iter().sum::<f64>() / seeds as f64;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64;
    (mean, var.sqrt())
}

/// The stratified set's spread against independent samples' at equal count, and
/// both means against a converged reference within four standard errors of the
/// mean over seeds.
fn compare<W: World>(what: &str, world: &W, x: VecOf<W>, lobe: &Lobe<W::S>, n: u32) -> f64 {
    let seeds = 128;
    let strat = over_seeds(seeds, |seed| {
        let mut rays = 0;
        direct_mean(world, x, (lobe, Rgb::ONE), n, &mut Sampler::new(seed, 1), &mut rays)
    });
    let indep = over_seeds(seeds, |seed| {
        let mut rays = 0;
        let sum = (0..n).fold(Rgb::ZERO, |a, k| {
            a + direct_at(world, x, lobe, None, &mut Sampler::new2(seed, 2, k as u64), &mut rays)
        });
        sum / n as f64
    });
    let mut rays = 0;
    let reference = luminance(
        (0..200_000u64).fold(Rgb::ZERO, |a, k| {
            a + direct_at(world, x, lobe, None, &mut Sampler::new2(99, 3, k), &mut rays)
        }) / 200_000.0,
    );
    let ratio = strat.1 / indep.1;
    eprintln!(
        "{what}: reference {reference:.5}, stratified {:.5} ± {:.5}, independent {:.5} ± {:.5} (spread ratio {ratio:.3})",
        strat.0, strat.1, indep.0, indep.1
    );
    let se = |spread: f64| spread / (seeds as f64).sqrt() + 2.0 * indep.1 / (200_000.0 / n as f64).sqrt();
    assert!(
        (strat.0 - reference).abs() < 4.0 * se(strat.1),
        "{what}: stratified mean off"
    );
    assert!(
        (indep.0 - reference).abs() < 4.0 * se(indep.1),
        "{what}: independent mean off"
    );
    ratio
}

/// `direct_mean`'s 64 samples at points below the comb (in the slats' shadows
/// and between them), above and beside it, 48 seeds: spread ratios measured
/// 0.25–0.28, 0.36–0.47, 0.03–0.04 and 0.14 (four sets of seeds); asserted below
/// 0.6 at every point (independent samples: 1 ± 0.15).
#[test]
fn direct_mean_spreads_less_and_stays_unbiased_2d() {
    let s = comb_2d();
    let lobe = Lobe::Phase {
        phase: s.medium_at(DVec2::ZERO).unwrap().phase,
        travel: DVec2::new(0.6, -0.8),
    };
    for x in [
        DVec2::new(0.05, 0.2),
        DVec2::new(-0.9, -0.6),
        DVec2::new(0.5, 1.0),
        DVec2::new(1.6, 0.0),
    ] {
        let r = compare(&format!("2D x = {x}"), &s, x, &lobe, 64);
        assert!(r < 0.6, "2D x = {x}: stratified spread {r:.3} of independent");
    }
}

/// The same in 3D under the lamp and the bar (the quad lamp is two triangles:
/// one draw picks the triangle and places the point, `Emitters::pick_remapped`):
/// spread ratios measured 0.30–0.39, 0.06–0.08 and 0.29–0.36 (four sets of
/// seeds); asserted below 0.6.
#[test]
fn direct_mean_spreads_less_and_stays_unbiased_3d() {
    let s = lamp_bar_3d();
    let lobe = Lobe::Phase {
        phase: s.medium_at(DVec3::new(0.0, 0.5, 0.0)).unwrap().phase,
        travel: DVec3::new(0.0, -0.6, -0.8),
    };
    for x in [
        DVec3::new(0.0, 0.5, 0.0),
        DVec3::new(0.7, 0.9, 0.3),
        DVec3::new(-1.2, 0.3, 0.5),
    ] {
        let r = compare(&format!("3D x = {x}"), &s, x, &lobe, 64);
        assert!(r < 0.6, "3D x = {x}: stratified spread {r:.3} of independent");
    }
}

/// The path tracer's estimate of L_s with 128 samples, stratified and
/// independent, over 128 seeds at points below, above and beside the comb: both
/// unbiased against 65,536 independent samples; the stratified spread measured
/// 0.68–0.73 and 0.58–0.65 of the independent one where the straight light
/// weighs (three sets of seeds), asserted below 0.85 (later bounces stay
/// independent: at the floor's corner, 0.71–0.78, only the mean is checked).
#[test]
fn path_tracing_spreads_less_and_stays_unbiased_2d() {
    let s = comb_2d();
    let q = Query::InScattered {
        omega_o: DVec2::new(0.6, -0.8),
    };
    let with = |sampling| Settings {
        sampling,
        ..Default::default()
    };
    for (x, bound) in [
        (DVec2::new(0.05, 0.2), Some(0.85)),
        (DVec2::new(0.5, 1.0), Some(0.85)),
        (DVec2::new(-0.9, -0.6), None),
    ] {
        let reference = estimate(&s, x, &q, &with(Sampling::Independent), 65_536, 77, 0);
        let want = luminance(reference.mean.total());
        let ref_se = luminance(reference.std_error.total());
        let seeds = 128;
        let run = |sampling| {
            over_seeds(seeds, |seed| {
                estimate(&s, x, &q, &with(sampling), 128, seed, 5).mean.total()
            })
        };
        let (strat, indep) = (run(Sampling::Stratified), run(Sampling::Independent));
        eprintln!(
            "PT x = {x}: reference {want:.5} ± {ref_se:.5}, stratified {:.5} ± {:.5}, independent {:.5} ± {:.5}",
            strat.0, strat.1, indep.0, indep.1
        );
        for (name, (mean, spread)) in [("stratified", strat), ("independent", indep)] {
            let se = spread / (seeds as f64).sqrt() + ref_se;
            assert!(
                (mean - want).abs() < 4.0 * se,
                "PT x = {x}: {name} mean {mean} vs {want}"
            );
        }
        if let Some(bound) = bound {
            let r = strat.1 / indep.1;
            assert!(r < bound, "PT x = {x}: stratified spread {r:.3} of independent");
        }
    }
}
