//! The aware single-scattering gradient and Hessian at 3D occlusion boundaries
//! against the exact 3D reference (`study::exact3d`: emitter polygons minus the
//! occluders' central projections, Gauss–Legendre on the pieces, central differences
//! of it), in fog with σ_t ≥ 1 and g ≠ 0 (issue 12 item 2, in 3D): 30 penumbra
//! points in three scenes of our own.

use glam::{DMat3, DVec3};
use std::path::Path;
use volcache::pipeline::derivatives::{AwareSettings, aware};
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy::build;
use volcache::pipeline::world::World;
use volcache::progress::Progress;
use volcache::study::exact3d;
use volcache::volume::scene::Scene;

fn frobenius(m: DMat3) -> f64 {
    m.to_cols_array().iter().map(|e| e * e).sum::<f64>().sqrt()
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn scene(shapes: &str, sigma_t: f64, g: f64) -> Scene {
    let text = format!(
        r#"{{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
            "shapes": [{shapes}],
            "medium": {{"sigma_a": 0.1, "sigma_s": {}, "g": {g}}}}}"#,
        sigma_t - 0.1
    );
    Scene::from_json(&text, "occlusion in 3D", Path::new(".")).unwrap()
}

/// A square light above a black square occluder.
fn scene_a(sigma_t: f64, g: f64) -> Scene {
    scene(
        r#"{"quad": {"origin": [-0.5, 1, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]}, "emission": 3, "reflectance": 0},
           {"quad": {"origin": [-0.6, 0.55, -0.1], "u": [0.7, 0, 0], "v": [0, 0, 0.8]}, "reflectance": 0}"#,
        sigma_t,
        g,
    )
}

/// A tilted light beside two tilted black occluders.
fn scene_b(sigma_t: f64, g: f64) -> Scene {
    scene(
        r#"{"quad": {"origin": [-1, -0.4, -0.5], "u": [0.1, 0.9, 0], "v": [0, 0, 1]}, "emission": 3, "reflectance": 0},
           {"quad": {"origin": [-0.6, 0.0, -0.6], "u": [0.1, 0.5, 0.1], "v": [0.05, 0, 0.6]}, "reflectance": 0},
           {"quad": {"origin": [-0.55, -0.5, 0.1], "u": [0.0, 0.3, 0.0], "v": [0.1, 0, 0.5]}, "reflectance": 0}"#,
        sigma_t,
        g,
    )
}

/// A tilted light above a black box turned about the vertical (its silhouette
/// folds over the box's edges; its corners cross the light's edges).
fn scene_c(sigma_t: f64, g: f64) -> Scene {
    scene(
        r#"{"quad": {"origin": [-0.6, 1.1, -0.4], "u": [1.1, 0.2, 0], "v": [0, -0.1, 0.9]}, "emission": 3, "reflectance": 0},
           {"box": {"min": [-0.3, 0.35, -0.25], "max": [0.2, 0.6, 0.35], "rotate_y_deg": 25}, "reflectance": 0}"#,
        sigma_t,
        g,
    )
}

/// The share of the emitting triangles' area seen from `x` (a grid of points).
fn visible_share(scene: &Scene, x: DVec3) -> f64 {
    let (mut seen, mut all) = (0, 0);
    for t in scene
        .geometry
        .prims
        .iter()
        .filter(|t| scene.surfaces[t.shape as usize].emission.x > 0.0)
    {
        let n = 12;
        for i in 0..n {
            for j in 0..n - i {
                let y = t.p0 + t.e1 * ((i as f64 + 0.3) / n as f64) + t.e2 * ((j as f64 + 0.3) / n as f64);
                let d = y - x;
                all += 1;
                if !scene.occluded(x, d.normalize(), d.length() * (1.0 - 1e-9), None) {
                    seen += 1;
                }
            }
        }
    }
    seen as f64 / all as f64
}

/// Points of a jittered grid in the box `lo`–`hi` that see 5–95% of the light.
fn penumbra_points(scene: &Scene, lo: DVec3, hi: DVec3, want: usize) -> Vec<DVec3> {
    let n = 9;
    let mut out = vec![];
    for k in 0..n * n * n {
        let k = k * 31 % (n * n * n); // a stride coprime with the grid spreads them
        let c = DVec3::new((k / (n * n)) as f64, ((k / n) % n) as f64, (k % n) as f64) + 0.5;
        let x = lo + (hi - lo) * c / n as f64;
        let s = visible_share(scene, x);
        if (0.05..0.95).contains(&s) && out.len() < want {
            out.push(x);
        }
    }
    out
}

type SceneFn = fn(f64, f64) -> Scene;

/// Relative gradient and Hessian errors of the aware single part at `x`.
fn errors(scene: &Scene, x: DVec3, omega_o: DVec3, rays: usize, seed: u64) -> (f64, f64) {
    let exact = exact3d::derivatives(scene, x, omega_o, 1e-4).luminance();
    let mut ps = ProbeSettings::with_rays::<volcache::core::space::D3>(rays);
    ps.settings.max_depth = 2;
    let lf = capture(scene, x, Outgoing::Direction(omega_o), &ps, seed, 0, &Progress::new()).unwrap();
    let aw = AwareSettings::default();
    let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
    (
        (got.grad - exact.grad).length() / exact.grad.length(),
        frobenius(got.hess - exact.hess) / frobenius(exact.hess),
    )
}

/// Where a shadow's edge crosses an emitter's edge, the visible part of the emitter
/// has a corner that slides along the emitter's edge as x moves; proxy vertices
/// fixed in space there erred by O(Δθ²) in value but O(1) in the Hessian (2D has
/// no such corners). The proxy now follows the emitter's edge behind the
/// occluder's silhouette to that corner, which slides (`pipeline::proxy_cut`).
/// Measured over seeds 1–4 (10 points per scene), 4096 / 16384 directions, before →
/// after: gradient median A 3.9% / 1.5% → 0.54% / 0.10%, B 4.1% / 2.4% → 0.25% /
/// 0.05%, C 2.4% / 1.1% → 0.67% / 0.22% (p90 ≤ 2.2% after); Hessian median A 10% /
/// 8.5% → 0.92% / 0.31%, B 23% / 21% → 0.70% / 0.30%, C 8.1% / 7.9% → 2.5% /
/// 0.34%; Hessian p90 A 17% / 17% → 6.2% / 7.1%, B 90% / 57% → 8.6% / 4.1%, C 17% /
/// 14% → 5.9% / 3.0%. The worst point left (A, 92% for one seed at 16384) sees an
/// occluder's corner project onto the emitter's edge: two corners in one place.
/// Those were one orientation of the direction set: since each seed's set is
/// turned about z by a random azimuth (unbiased sets), seeds are orientations.
/// Over seeds 1–8 at 4096 directions, the Hessian's p90 per pair of seeds is A
/// 0.031–0.093, B 0.068–0.155, C 0.044–0.088, and over the three scenes' 30
/// points (issue 12's measure: ≥ 20 points in ≥ 2 scenes) 0.062–0.100; at 16384,
/// B 0.020–0.033. B's worst point, (0.1, −0.567, 0.722), is 23–28% off at every
/// orientation at 4096 and 0.2–2% at 16384 (one seed 23%): there the plate's
/// corner passes 0.006 rad inside the emitter's edge, about to cross it, a gap
/// a ninth of the rays' spacing (0.055 rad). A's worst, (−0.889, 0.122, 0.889),
/// is 10–300% off at 4096 (the "two corners in one place" above).
/// The test runs seeds 1–2; its bounds hold the measured worst with margin: the
/// pooled Hessian p90 bound is issue 12's (15%), each scene's p90 is bounded by
/// 0.2 (B's worst pair 0.155).
#[test]
fn derivatives_at_3d_penumbrae() {
    let rows: [Row; 3] = [
        (
            "A",
            scene_a,
            1.0,
            0.6,
            DVec3::new(-1.0, -0.6, -1.0),
            DVec3::new(1.0, 0.4, 1.0),
        ),
        (
            "B",
            scene_b,
            2.0,
            -0.5,
            DVec3::new(-0.4, -0.8, -0.6),
            DVec3::new(0.6, 0.6, 0.8),
        ),
        (
            "C",
            scene_c,
            1.5,
            0.3,
            DVec3::new(-1.0, -0.5, -1.0),
            DVec3::new(1.0, 0.3, 1.0),
        ),
    ];
    check(&rows, [0.02, 0.06, 0.05, 0.2], 0.15);
}

/// A scene, its σ_t and g, and the box its penumbra points are taken from.
type Row = (&'static str, SceneFn, f64, f64, DVec3, DVec3);

/// The gradient's and Hessian's median and p90 errors over each row's penumbra
/// points (seeds 1–2) at 4096 and 16384 directions, against `bounds` (gradient
/// median, p90, Hessian median, p90), and the Hessian's p90 over every row's
/// points against `pooled_h90`.
fn check(rows: &[Row], bounds: [f64; 4], pooled_h90: f64) {
    let omega_o = DVec3::new(0.48, -0.6, 0.64);
    let mut pooled: [Vec<f64>; 2] = [vec![], vec![]];
    for &(name, make, sigma_t, g, lo, hi) in rows {
        let scene = make(sigma_t, g);
        let points = penumbra_points(&scene, lo, hi, 10);
        assert!(points.len() >= 8, "{name}: only {} penumbra points", points.len());
        for (r, rays) in [4096, 16384].into_iter().enumerate() {
            let (mut ge, mut he) = (vec![], vec![]);
            for seed in 1..=2 {
                for &x in &points {
                    let (a, b) = errors(&scene, x, omega_o, rays, seed);
                    ge.push(a);
                    he.push(b);
                }
            }
            pooled[r].extend(&he);
            let (gm, g90) = (percentile(&mut ge.clone(), 0.5), percentile(&mut ge, 0.9));
            let (hm, h90) = (percentile(&mut he.clone(), 0.5), percentile(&mut he, 0.9));
            println!(
                "{name} σ_t {sigma_t} g {g} rays {rays}: n {} ∇ median {gm:.4} p90 {g90:.4} | H median {hm:.4} p90 {h90:.4}",
                points.len()
            );
            let [bgm, bg90, bhm, bh90] = bounds;
            assert!(gm < bgm && g90 < bg90, "{name} {rays}: gradient median {gm} p90 {g90}");
            assert!(hm < bhm && h90 < bh90, "{name} {rays}: Hessian median {hm} p90 {h90}");
        }
    }
    for (errors, rays) in pooled.iter_mut().zip([4096, 16384]) {
        let h90 = percentile(errors, 0.9);
        println!("all rows, rays {rays}: {} errors, Hessian p90 {h90:.4}", errors.len());
        assert!(
            h90 < pooled_h90,
            "rays {rays}: Hessian p90 {h90} over every row's points"
        );
    }
}

/// The same at the extremes issue 12 asks for: σ_t = 50 (the penumbrae 25–50 mean
/// free paths from the light) and g = ±0.99. Measured over seeds 1–4, median / p90
/// at 4096 and 16384 directions: gradient A σ_t 50 2.8% / 12%, 0.78% / 6.4%;
/// A g 0.99 0.86% / 2.1%, 0.19% / 0.90%; A g −0.99 0.30% / 2.6%, 0.09% / 1.1%;
/// B σ_t 50 0.79% / 10%, 0.22% / 3.0%. Hessian A σ_t 50 2.9% / 13%, 0.92% / 6.4%;
/// A g 0.99 1.7% / 5.8%, 0.48% / 6.6%; A g −0.99 0.36% / 7.0%, 0.12% / 11%;
/// B σ_t 50 1.1% / 12%, 0.37% / 4.5%. The Hessian's p90 bound is issue 12's.
/// Those were one orientation of the direction set. With each seed's set turned
/// (unbiased sets), the Hessian's p90 at 4096 directions per pair of seeds 1–8 is
/// A σ_t 50 0.135–0.196, B σ_t 50 0.107–0.189, A g 0.99 0.029–0.093, A g −0.99
/// 0.071–0.142: at σ_t = 50 and 4096 directions issue 12's 15% holds for seeds
/// 1–2 (0.145, 0.129) and 3 (A) or 4 (B) of the 7 pairs, not for every
/// orientation — an open edge of the method, left visible here rather than
/// bounded away.
#[test]
fn derivatives_at_3d_penumbrae_at_extremes() {
    let (lo_a, hi_a) = (DVec3::new(-1.0, -0.6, -1.0), DVec3::new(1.0, 0.4, 1.0));
    let rows: [Row; 4] = [
        ("A", scene_a, 50.0, 0.6, lo_a, hi_a),
        ("A", scene_a, 1.0, 0.99, lo_a, hi_a),
        ("A", scene_a, 1.0, -0.99, lo_a, hi_a),
        (
            "B",
            scene_b,
            50.0,
            -0.5,
            DVec3::new(-0.4, -0.8, -0.6),
            DVec3::new(0.6, 0.6, 0.8),
        ),
    ];
    check(&rows, [0.05, 0.2, 0.05, 0.15], 0.15);
}
