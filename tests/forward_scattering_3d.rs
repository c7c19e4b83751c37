//! Strong forward scattering aimed at an emitter in 3D (issue 12 item 6): the phase's
//! lobe (≈ 1 − |g| radians wide) points into an emitter and covers one or a few of
//! a 4096-direction probe's triangles. The aware single-scattering value, gradient
//! and Hessian against the exact 3D reference integrated about the lobe's axis
//! (`study::exact3d::single_scattering_about_lobe`, whose nodes follow the lobe;
//! central differences of it), on a scene of our own: a square emitter in fog, x
//! below it, ω_o from the emitter through x (or towards an eye beyond x).

use glam::{DMat3, DVec3};
use std::path::Path;
use volcache::core::phase::Outgoing;
use volcache::pipeline::derivatives::{AwareSettings, aware};
use volcache::pipeline::probe::{ProbeSettings, capture};
use volcache::pipeline::proxy::build;
use volcache::progress::Progress;
use volcache::study::exact3d;
use volcache::volume::scene::Scene;

fn frobenius(m: DMat3) -> f64 {
    m.to_cols_array().iter().map(|e| e * e).sum::<f64>().sqrt()
}

fn scene(sigma_s: f64, g: f64) -> Scene {
    let text = format!(
        r#"{{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
            "shapes": [{{"quad": {{"origin": [-0.5, 0.6, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]}},
                         "emission": 1, "reflectance": 0}}],
            "medium": {{"sigma_a": 0, "sigma_s": {sigma_s}, "g": {g}}}}}"#
    );
    Scene::from_json(&text, "forward scattering into an emitter", Path::new(".")).unwrap()
}

/// Points below the emitter, the fifth 0.1 from it (its lobe's spot is 1 mm wide).
const POINTS: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [0.3, -0.2, 0.1],
    [-0.2, 0.3, -0.15],
    [0.6, 0.1, 0.3],
    [0.1, 0.5, 0.05],
    [-0.7, -0.6, 0.4],
];

/// Where the lobe's axis meets the emitter (inside it, off its diagonal).
const AIM: DVec3 = DVec3::new(0.05, 0.6, 0.02);

/// Relative value, gradient and Hessian errors of the aware single part.
fn errors(scene: &Scene, x: DVec3, out: Outgoing<DVec3>, seed: u64) -> [f64; 3] {
    let exact = exact3d::derivatives_about_lobe(scene, x, out, 1e-4).luminance();
    let mut ps = ProbeSettings::with_rays::<volcache::core::space::D3>(4096);
    ps.settings.max_depth = 2;
    let lf = capture(scene, x, out, &ps, seed, 0, &Progress::new()).unwrap();
    let aw = AwareSettings::default();
    let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
    [
        (got.value - exact.value).abs() / exact.value,
        (got.grad - exact.grad).length() / exact.grad.length(),
        frobenius(got.hess - exact.hess) / frobenius(exact.hess),
    ]
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// Measured, 6 points × 3 seeds at 4096 directions, before (one phase value at each
/// element's anchor) → after (the lobe's piecewise integral, `core::phase_patch`);
/// value max | gradient max | Hessian median, p90:
/// - g = 0.99: 195% | 1000× | 1.4e5×, 1.4e6× → 0.09% | 1.0% | 2.3%, 8.9%;
/// - g = 0.9: 1.5% | 2.9× | 9.2×, 113× → 1.0% | 7.4% | 4.7%, 12%;
/// - g = −0.95: 5.2% | 6.4× | 242×, 7100× → 0.5% | 4.7% | 4.1%, 14%;
/// - g = 0.99 towards an eye: 195% | 1200× | 1.9e5×, 1.9e6× → 0.09% | 1.2% | 3.8%, 17%;
/// - g = 0.99, σ_s = 2: 195% | 256× | 9300×, 8.8e4× → 0.05% | 0.14% | 0.15%, 0.53%.
///
/// Over seeds 1–12 the largest after-values are 0.23% | 3.2% | 2.3%, 11% (g 0.99),
/// 2.3% | 16% | 5.0%, 12% (g 0.9), 1.2% | 13% | 4.1%, 13% (g −0.95), 0.23% | 4.1% |
/// 3.2%, 16% (towards an eye), 0.18% | 0.63% | 0.11%, 0.67% (σ_s 2): the errors left
/// sit at the points far from the emitter's centre, at the level of the probe's
/// own discretisation (g = 0 there: gradient 1–5%). Bounds about 2–3× those.
/// Since the 3D proxy cuts its simplices at the emitter's silhouette and takes f·T
/// over the directions of grazing and close elements (seeds 1–3): 0.01% | 0.09% |
/// 0.41%, 3.1% (g 0.99); 0.13% | 0.65% | 0.14%, 0.52% (g 0.9); 0.06% | 0.40% |
/// 0.11%, 0.37% (g −0.95); 0.01% | 0.11% | 0.54%, 4.2% (towards an eye); 0.006% |
/// 0.012% | 0.026%, 0.15% (σ_s 2): the errors at the points far from the emitter's
/// centre were its rim's. (The bounds are kept; tightening them needs seeds 1–12.)
#[test]
fn a_lobe_aimed_into_an_emitter() {
    // (name, σ_s, g, outgoing): ω_o from the emitter through x; towards an eye
    // 3 below x on that line (the lobe's axis turns with x); g < 0 turns the lobe
    // back, so ω_o points into the emitter; σ_s = 2 makes the transmittance turn
    // across the lobe's element.
    type Out = fn(DVec3) -> Outgoing<DVec3>;
    let rows: [(&str, f64, f64, Out, [f64; 4]); 5] = [
        (
            "g 0.99",
            0.5,
            0.99,
            |x| Outgoing::Direction(x - AIM),
            [0.006, 0.08, 0.06, 0.3],
        ),
        (
            "g 0.9",
            0.5,
            0.9,
            |x| Outgoing::Direction(x - AIM),
            [0.05, 0.35, 0.12, 0.3],
        ),
        (
            "g −0.95",
            0.5,
            -0.95,
            |x| Outgoing::Direction(AIM - x),
            [0.03, 0.3, 0.1, 0.3],
        ),
        (
            "g 0.99 towards an eye",
            0.5,
            0.99,
            |x| Outgoing::TowardsPoint(x + (x - AIM).normalize() * 3.0),
            [0.006, 0.1, 0.08, 0.35],
        ),
        (
            "g 0.99 σ_s 2",
            2.0,
            0.99,
            |x| Outgoing::Direction(x - AIM),
            [0.005, 0.015, 0.005, 0.02],
        ),
    ];
    for (name, sigma_s, g, out, [value_max, grad_max, hess_median, hess_p90]) in rows {
        let scene = scene(sigma_s, g);
        let (mut ve, mut ge, mut he) = (vec![], vec![], vec![]);
        for p in POINTS {
            let x = DVec3::from(p);
            for seed in 1..=3 {
                let [v, d, h] = errors(&scene, x, out(x), seed);
                ve.push(v);
                ge.push(d);
                he.push(h);
            }
        }
        let max = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
        let (vm, gm) = (max(&ve), max(&ge));
        let (hm, h90) = (percentile(&mut he.clone(), 0.5), percentile(&mut he, 0.9));
        println!(
            "{name}: value max {vm:.2e} | ∇ max {gm:.2e} | H median {hm:.3e} p90 {h90:.3e} max {:.3e}",
            max(&he)
        );
        assert!(vm < value_max, "{name}: value error {vm}");
        assert!(gm < grad_max, "{name}: gradient error {gm}");
        assert!(
            hm < hess_median && h90 < hess_p90,
            "{name}: Hessian median {hm}, p90 {h90}"
        );
    }
}
