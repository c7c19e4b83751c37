//! The aware single-scattering Hessian at occlusion boundaries against the exact 2D
//! reference (`study::exact2d`: visibility intervals + Gauss–Legendre, central
//! differences of it), in fog thick enough (σ_t ≥ 1) and anisotropic enough (g ≠ 0)
//! that phase × transmittance varies across the proxy's elements (issue 12 item 2).

use glam::{DMat2, DVec2};
use volcache::flatland::scene::Scene;
use volcache::pipeline::derivatives::{AwareSettings, aware};
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy::build;
use volcache::pipeline::world::World;
use volcache::progress::Progress;
use volcache::study::exact2d;

fn frobenius(m: DMat2) -> f64 {
    (m.x_axis.length_squared() + m.y_axis.length_squared()).sqrt()
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// The share of the emitter segment `a`–`b` seen from `x` (129 points).
fn visible_share(scene: &Scene, x: DVec2, a: DVec2, b: DVec2) -> f64 {
    let n = 129;
    let seen = (0..n)
        .filter(|&i| {
            let y = a.lerp(b, (i as f64 + 0.5) / n as f64);
            let d = y - x;
            !scene.occluded(x, d.normalize(), d.length() * (1.0 - 1e-9), None)
        })
        .count();
    seen as f64 / n as f64
}

/// Points of a grid over `lo`–`hi` that see between 5% and 95% of the emitter: the
/// penumbra, where the proxy's bridging elements carry the occluder's edge.
fn penumbra_points(scene: &Scene, emitter: (DVec2, DVec2), lo: DVec2, hi: DVec2, want: usize) -> Vec<DVec2> {
    let mut out = vec![];
    let n = 24;
    for i in 0..n {
        for j in 0..n {
            // A stride coprime with the grid spreads the points over it.
            let k = (i * n + j) * 7 % (n * n);
            let x = lo + (hi - lo) * DVec2::new((k / n) as f64 + 0.5, (k % n) as f64 + 0.5) / n as f64;
            let s = visible_share(scene, x, emitter.0, emitter.1);
            if (0.05..0.95).contains(&s) && out.len() < want {
                out.push(x);
            }
        }
    }
    out
}

fn hessian_errors(scene: &Scene, points: &[DVec2], omega_o: DVec2, rays: usize, seed: u64) -> Vec<f64> {
    points
        .iter()
        .map(|&x| {
            let exact = exact2d::derivatives(scene, x, omega_o, 1e-4).luminance();
            let mut ps = ProbeSettings::with_rays::<volcache::core::space::D2>(rays);
            ps.settings.max_depth = 2;
            let lf = capture(scene, x, Outgoing::Direction(omega_o), &ps, seed, 0, &Progress::new()).unwrap();
            let aw = AwareSettings::default();
            let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
            frobenius(got.hess - exact.hess) / frobenius(exact.hess)
        })
        .collect()
}

fn scene_a(sigma: f64, g: f64) -> (Scene, (DVec2, DVec2)) {
    let text = format!(
        r#"{{"domain": {{"min": [-1, -1], "max": [1, 1]}},
            "segments": [{{"a": [0.4, 0.8], "b": [-0.4, 0.8], "emission": 1, "reflectance": 0}},
                         {{"a": [-0.2, 0.4], "b": [0.15, 0.4], "reflectance": 0}}],
            "medium": {{"sigma_a": 0.1, "sigma_s": {sigma}, "g": {g}}}}}"#
    );
    let e = (DVec2::new(0.4, 0.8), DVec2::new(-0.4, 0.8));
    (Scene::from_json(&text, "occluder under an emitter").unwrap(), e)
}

fn scene_b(sigma: f64, g: f64) -> (Scene, (DVec2, DVec2)) {
    let text = format!(
        r#"{{"domain": {{"min": [-1, -1], "max": [1, 1]}},
            "segments": [{{"a": [-0.9, -0.3], "b": [-0.9, 0.5], "emission": 2, "reflectance": 0}},
                         {{"a": [-0.5, 0.3], "b": [-0.4, -0.05], "reflectance": 0}},
                         {{"a": [-0.3, -0.2], "b": [-0.2, -0.6], "reflectance": 0}}],
            "medium": {{"sigma_a": 0.0, "sigma_s": {sigma}, "g": {g}}}}}"#
    );
    let e = (DVec2::new(-0.9, -0.3), DVec2::new(-0.9, 0.5));
    (
        Scene::from_json(&text, "slanted occluders beside a wall light").unwrap(),
        e,
    )
}

type SceneFn = fn(f64, f64) -> (Scene, (DVec2, DVec2));

/// The aware Hessian at 12 penumbra points in each of two scenes, σ_t from 1 to 50
/// and g from −0.99 to 0.99, against the exact reference's central differences.
/// A bridging element once evaluated f·T at its far vertex only: median 12% and p90
/// 21% (σ_t 1–2, g 0.6 / −0.5), unchanged from 4096 to 16384 rays. With the vertex
/// rule and the near vertices sliding on the far surface (`pipeline::slide`),
/// measured over seeds 1–3: worst row p90 0.31% and max 0.72% at 1024 rays (σ_t 50,
/// g 0), p90 ≤ 0.07% at 4096 rays; before, at 4096 rays, p90 2.6–49% and max up to
/// 84% (σ_t 50, g 0), medians 1.2–12%.
#[test]
fn hessian_at_penumbrae() {
    let omega_o = DVec2::new(0.6, -0.8);
    let rows: [(&str, SceneFn, f64, f64, DVec2, DVec2); 6] = [
        ("A", scene_a, 1.0, 0.6, DVec2::new(-0.8, -0.8), DVec2::new(0.8, 0.35)),
        ("B", scene_b, 2.0, -0.5, DVec2::new(-0.6, -0.9), DVec2::new(0.9, 0.9)),
        ("A", scene_a, 1.0, 0.99, DVec2::new(-0.8, -0.8), DVec2::new(0.8, 0.35)),
        ("B", scene_b, 1.0, -0.99, DVec2::new(-0.6, -0.9), DVec2::new(0.9, 0.9)),
        ("A", scene_a, 50.0, 0.9, DVec2::new(-0.3, 0.1), DVec2::new(0.3, 0.35)),
        ("B", scene_b, 50.0, 0.0, DVec2::new(-0.6, -0.2), DVec2::new(-0.3, 0.4)),
    ];
    for (name, make, sigma, g, lo, hi) in rows {
        let (scene, e) = make(sigma, g);
        let points = penumbra_points(&scene, e, lo, hi, 12);
        assert!(points.len() >= 10, "{name}: only {} penumbra points", points.len());
        for rays in [1024, 4096] {
            let mut errs = vec![];
            for seed in 1..=3 {
                errs.extend(hessian_errors(&scene, &points, omega_o, rays, seed));
            }
            let med = percentile(&mut errs.clone(), 0.5);
            let p90 = percentile(&mut errs.clone(), 0.9);
            let max = percentile(&mut errs, 1.0);
            println!(
                "{name} σ_t {sigma} g {g} rays {rays}: n {} median {med:.5} p90 {p90:.5} max {max:.5}",
                points.len()
            );
            // 3× and 4× the worst measured, far below the issue's 15% p90.
            assert!(
                p90 < 0.01 && max < 0.03,
                "{name} σ_t {sigma} g {g} rays {rays}: p90 {p90} max {max}"
            );
        }
    }
}
