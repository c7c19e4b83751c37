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
            let mut ps = ProbeSettings::with_rays::<volcache::core::space::D2>(4096);
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
/// ray count. Measured (4 seeds, 4096 rays): at most 3.5% (σ_t 20) and 7.2% (σ_t 50)
/// with escaped rays pushed behind the hits, the last hit standing short of the
/// emitter's end; below 0.05% with the end found exactly (`pipeline::silhouette`).
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
            assert!(errs.iter().all(|&e| e < 0.01), "σ_t {sigma} at ({px}, {py}): {errs:?}");
        }
    }
}

/// The aware gradient and Hessian below an emitter, d = 1e-2 … 1e-8 from it
/// (issue 12 item 4). History: a ray grazing the emitter met it at r ≈ d/Δθ, and
/// that hit ended the chain of surface elements in place of the emitter's end: the
/// error grew as 1/d (σ_t = 1e-4, g = 0: 46% at 1e-3, 6× at 1e-4, 3200× at 1e-7).
/// Fixed by the exact ends (`pipeline::silhouette`) and one clamp for all surface
/// form factors; then g = 0.99 by the phase integrated per element
/// (`core::phase_arc`); then thick fog by averaging a grazing piece's
/// transmittance over its directions (`slide::transmittance_mean`), which left
/// σ_t 1, g 0.6 and σ_t 20, g 0.9 at 10–12% from 1e-5 to 1e-8 — against a
/// reference that was itself wrong there (uniform panels: ∂_y L = 2.375 at
/// d = 1e-6, σ_t 1, g 0.6, where an independent 40-digit quadrature gives
/// 2.77192; `exact2d` now halves its panels until the distance changes at most
/// 2×). Now the segments next to x integrate f·T with derivatives at their ends
/// (`core::segment_boundary`). Measured (seeds 1–4, 4096 rays), the gradient within
/// 0.035% in every row at every d (σ_t 1, g 0.6: ≤ 0.013%), the Hessian within
/// 0.2% where the reference can tell but 2% (g −0.99, 1e-2), 3.8% (g −0.99, 1e-7)
/// and 3.5% (towards an eye, 1e-8); the bounds are ≈ 3× the worst, at least 1e-3.
#[test]
fn derivatives_next_to_an_emitter() {
    // (σ_t, g, towards an eye, gradient bound, Hessian bounds per d; infinite:
    // not checked — in thin fog the Hessian is tiny and the reference's central
    // differences with a step d·1e-2 carry more rounding than it below 1e-4, and
    // at g = −0.99, 1e-8 they differ by 26% from the estimate, unexplained)
    let no = f64::INFINITY;
    let rows: [(f64, f64, bool, f64, [f64; 7]); 6] = [
        (1e-4, 0.0, false, 1e-3, [1e-3, 1e-3, 5e-3, no, no, no, no]),
        (1e-4, 0.99, false, 1e-3, [1e-3, 1e-3, 3e-3, no, no, no, no]),
        (1.0, 0.6, false, 1e-3, [1e-3, 3e-3, 1e-3, 1e-3, 1e-3, 2e-3, 5e-3]),
        (1.0, -0.99, false, 1e-3, [0.06, 2e-3, 1e-3, 2e-3, 6e-3, 0.12, no]),
        (20.0, 0.9, false, 1e-3, [1e-3, 1e-3, 3e-3, 1e-3, 1e-3, 1e-3, 1e-3]),
        (1.0, 0.6, true, 1e-3, [1e-3, 2e-3, 1e-3, 1e-3, 1e-3, 0.02, 0.1]),
    ];
    let frob = |m: glam::DMat2| (m.x_axis.length_squared() + m.y_axis.length_squared()).sqrt();
    for (sigma, g, eye, grad_bound, hess_bounds) in rows {
        let text = format!(
            r#"{{"domain": {{"min": [-1, -1], "max": [1, 1]}},
                "segments": [{{"a": [0.5, 0.3], "b": [-0.5, 0.3], "emission": 1, "reflectance": 0}}],
                "medium": {{"sigma_a": 0, "sigma_s": {sigma}, "g": {g}}}}}"#
        );
        let scene = Scene::from_json(&text, "below an emitter").unwrap();
        for (k, hess_bound) in hess_bounds.into_iter().enumerate() {
            let d = 10f64.powi(-(k as i32) - 2);
            let x = DVec2::new(0.1, 0.3 - d);
            let eye_at = DVec2::new(0.7, -1.5);
            let (out, omega_o) = if eye {
                (Outgoing::TowardsPoint(eye_at), (eye_at - x).normalize())
            } else {
                (Outgoing::Direction(DVec2::new(0.6, 0.8)), DVec2::new(0.6, 0.8))
            };
            let exact = if eye {
                // ω_o turns with x: central differences of the value with it.
                let channels = volcache::core::taylor::Taylor2::central_differences(
                    |p| exact2d::single_scattering(&scene, p, (eye_at - p).normalize()).to_array(),
                    x,
                    d * 1e-2,
                );
                volcache::core::taylor_rgb::TaylorRgb { channels }.luminance()
            } else {
                exact2d::derivatives(&scene, x, omega_o, d * 1e-2).luminance()
            };
            let (mut ge, mut he) = (0.0f64, 0.0f64);
            for seed in [1, 2] {
                let mut ps = ProbeSettings::with_rays::<volcache::core::space::D2>(4096);
                ps.settings.max_depth = 2;
                let lf = capture(&scene, x, out, &ps, seed, 0, &Progress::new()).unwrap();
                let aw = AwareSettings::default();
                let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
                ge = ge.max((got.grad - exact.grad).length() / exact.grad.length());
                he = he.max(frob(got.hess - exact.hess) / frob(exact.hess));
            }
            println!("σ_t {sigma}, g {g}, eye {eye}, d {d:e}: ∇ error {ge:.2e}, H error {he:.2e}");
            assert!(ge < grad_bound, "σ_t {sigma}, g {g}, eye {eye}, d {d:e}: ∇ error {ge}");
            assert!(he < hess_bound, "σ_t {sigma}, g {g}, eye {eye}, d {d:e}: H error {he}");
        }
    }
}

/// Strong forward scattering aimed into an emitter (issue 12 item 6): the HG lobe at
/// g = 0.99 is 0.01 rad wide, a few elements at 4096 rays, and the phase taken at
/// each element's anchor gave Hessians 30–6000× off (gradients 2–10%). With the
/// phase integrated over each element in closed form (`core::phase_arc`), measured
/// over 6 points, seeds 1–3, 4096 rays: gradient at most 0.042%; Hessian median
/// 2.6%, p90 18%, max 78% (one seed at 0.1 from the emitter: the transmittance is
/// still taken at each element's anchor, and where the lobe sits in an element
/// matters there).
#[test]
fn forward_scattering_into_an_emitter() {
    let text = r#"{"domain": {"min": [-1, -1], "max": [1, 1]},
        "segments": [{"a": [0.5, 0.6], "b": [-0.5, 0.6], "emission": 1, "reflectance": 0}],
        "medium": {"sigma_a": 0, "sigma_s": 0.5, "g": 0.99}}"#;
    let scene = Scene::from_json(text, "forward scattering into an emitter").unwrap();
    let (mut ge, mut he) = (vec![], vec![]);
    for (px, py) in [
        (0.0, 0.0),
        (0.3, -0.2),
        (-0.2, 0.3),
        (0.6, 0.1),
        (0.1, 0.5),
        (-0.7, -0.6),
    ] {
        let x = DVec2::new(px, py);
        // ω_o from the emitter through x: the lobe points into the emitter.
        let omega_o = (x - DVec2::new(0.05, 0.6)).normalize();
        let exact = exact2d::derivatives(&scene, x, omega_o, 1e-4).luminance();
        for seed in 1..=3 {
            let mut ps = ProbeSettings::with_rays::<volcache::core::space::D2>(4096);
            ps.settings.max_depth = 2;
            let lf = capture(&scene, x, Outgoing::Direction(omega_o), &ps, seed, 0, &Progress::new()).unwrap();
            let aw = AwareSettings::default();
            let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
            let h = got.hess - exact.hess;
            let frob = |m: glam::DMat2| (m.x_axis.length_squared() + m.y_axis.length_squared()).sqrt();
            ge.push((got.grad - exact.grad).length() / exact.grad.length());
            he.push(frob(h) / frob(exact.hess));
        }
    }
    let max = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
    println!("∇ errors {ge:.5?}\nH errors {he:.4?}");
    assert!(max(&ge) < 0.003, "gradient errors {ge:?}");
    he.sort_by(f64::total_cmp);
    let (median, p90) = (he[he.len() / 2], he[(he.len() * 9) / 10]);
    assert!(median < 0.08 && p90 < 0.6, "Hessian median {median}, p90 {p90}: {he:?}");
}
