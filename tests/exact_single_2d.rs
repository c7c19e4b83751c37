//! Aware single-scattering derivatives against the exact 2D reference
//! (`study::exact2d`: visibility intervals + Gauss–Legendre, central differences of
//! it), where the paper's proxy is most likely to go wrong.

use glam::DVec2;
use volcache::flatland::scene::Scene;
use volcache::pipeline::derivatives::{AwareSettings, aware};
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy::build;
use volcache::progress::Progress;
use volcache::study::exact2d;

/// The aware single-scattering gradient's relative error at `x`, per seed.
fn gradient_errors(scene: &Scene, x: DVec2, omega_o: DVec2, seeds: u64) -> Vec<f64> {
    let exact = exact2d::derivatives(scene, x, omega_o, 1e-4).luminance();
    (0..seeds)
        .map(|seed| {
            // The single part needs no deep paths: at albedo 1 and σ_t 50 they
            // would cost minutes.
            let mut ps = ProbeSettings::with_rays(4096);
            ps.settings.max_depth = 2;
            let lf = capture(scene, x, Outgoing::Direction(omega_o), &ps, seed, 0, &Progress::new()).unwrap();
            let aw = AwareSettings::default();
            let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
            (got.grad - exact.grad).length() / exact.grad.length()
        })
        .collect()
}

/// Thick fog beside an emitter's end (issue 12 item 5): rays that leave the scene
/// used to end at the march's cut length, ln(1000)/σ_t, in front of the emitter, and
/// the element joining the emitter's silhouette to that invented point carried the
/// emitter with the near point's derivatives: 40–200% off at σ_t = 50, whatever the
/// ray count. Measured now (4 seeds, 4096 rays): at most 3.5% (σ_t 20), 7.2% (σ_t
/// 50), the size of the farther-vertex rule's value deficit at the silhouette.
#[test]
fn gradients_beside_an_emitter_in_thick_fog() {
    for sigma in [20.0, 50.0] {
        let text = format!(
            r#"{{"domain": {{"min": [-1, -1], "max": [1, 1]}},
                "segments": [{{"a": [0.5, 0.3], "b": [-0.5, 0.3], "emission": 1, "reflectance": 0}},
                             {{"a": [-1, 0.15], "b": [0.0, 0.15], "reflectance": 0}}],
                "medium": {{"sigma_a": 0, "sigma_s": {sigma}}}}}"#
        );
        let scene = Scene::from_json(&text, "emitter in thick fog").unwrap();
        for (px, py) in [(0.6, 0.2), (0.7, 0.2), (0.6, 0.1), (0.75, 0.15), (0.55, 0.25)] {
            let errs = gradient_errors(&scene, DVec2::new(px, py), DVec2::X, 4);
            println!("σ_t {sigma} at ({px}, {py}): ∇ errors {errs:.3?}");
            assert!(errs.iter().all(|&e| e < 0.12), "σ_t {sigma} at ({px}, {py}): {errs:?}");
        }
    }
}
