//! The aware single-scattering gradient next to a surface in 3D (issue 12 item 4),
//! and the derivatives at random points of a room with an occluder, against exact
//! references (`study::exact3d`), on scenes of our own.

use glam::{DMat3, DVec3};
use std::path::Path;
use volcache::core::phase::Outgoing;
use volcache::core::space::D3;
use volcache::pipeline::derivatives::{AwareSettings, aware};
use volcache::pipeline::probe::{LightField, ProbeSettings, capture};
use volcache::pipeline::proxy::build;
use volcache::progress::Progress;
use volcache::study::exact3d;
use volcache::volume::scene::Scene;

/// Seeds per point in the tests; their bounds are ≈ 2–3× the worst of seeds 1–4
/// (1–8 for `derivatives_next_to_an_emitter`).
const SEEDS: u64 = 2;

fn probe(scene: &Scene, x: DVec3, out: Outgoing<DVec3>, rays: usize, seed: u64) -> LightField<D3> {
    let mut ps = ProbeSettings::with_rays::<D3>(rays);
    ps.settings.max_depth = 2;
    capture(scene, x, out, &ps, seed, 0, &Progress::new()).unwrap()
}

fn below_an_emitter(sigma_s: f64, g: f64) -> Scene {
    let text = format!(
        r#"{{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
            "shapes": [{{"quad": {{"origin": [-0.5, 0.6, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]}},
                         "emission": 1, "reflectance": 0}}],
            "medium": {{"sigma_a": 0, "sigma_s": {sigma_s}, "g": {g}}}}}"#
    );
    Scene::from_json(&text, "below an emitter", Path::new(".")).unwrap()
}

/// x at d below a 1 × 1 emitter (off its centre), light leaving along ω_o away
/// from it (the lobe's axis meets it at x's foot) or towards an eye 2.6 away;
/// 4096 directions. Measured (seeds 1–8, worst), gradient error at every d from
/// 1e-1 to 1e-8: ≤ 0.27% in every row (0.02% in thin fog and ≤ 0.01% at σ_s = 1,
/// g 0 or 0.6 along ω_o, below 1e-1; 0.04% or less at g 0.99 along ω_o; ≤ 0.06%
/// towards the eye). Hessian error (Frobenius) where the reference can tell it:
/// ≤ 3.2% at 1e-1 and 1.3–5.5% towards the eye at g 0.99, 1e-2 (seeds 1–2: 3.0%,
/// 3.9%); elsewhere ≤ 0.7%; it
/// follows the reference's own noise (central differences of a quadrature with
/// steps 1e-2 d and 3e-2 d differ by 1%, 9%, 90% at g 0.99, d = 1e-6, 1e-7,
/// 1e-8, and by 0.2% and more below 1e-3 at σ_s = 1e-4, whose Hessian is tiny):
/// there it is not checked. Towards the eye the Hessian's error depends on the
/// direction set's orientation (one random turn about z per seed): over seeds
/// 1–8 it is either ≈ 1e-4 or ≈ 4e-3 at every d from 1e-3 to 1e-7 (seeds 1 and
/// 3 the latter); before the sets were turned, every seed had the one
/// orientation, whose error at 1e-4 was ≈ 1e-4, and that d's bounds were 1e-3.
/// Worst of seeds 1–8 there: 4.3e-3 (g 0.6), 5.4e-3 (g 0.99), 3.1e-3 (g −0.9).
///
/// History. Before stop 36 the probe's lowest rays met the emitter ≈ d/Δθ from
/// x's foot and the proxy ended there (1700–6800× off at 1e-6); the silhouette
/// cuts (`pipeline::proxy_cut`) and f·T over the directions of grazing and close
/// elements (`slide::mean_over_directions`) on bands where the distance halves
/// took that to 0.02% (g 0). At σ_s = 1 the transmittance's share of the
/// gradient, ∫ T′(r)/r dr over the grazing directions, grows as ln(1/d); the
/// reference's panels are graded by distance too (`exact3d::
/// single_scattering_about_lobe`): at d = 1e-6, ∂_y L = 20.7736 by it and by an
/// independent polar integral. With g ≠ 0 the elements near x, all at r ≈ d,
/// took the lobe's area rule, whose error of each element's share (∝ 1/d for the
/// gradient, 1/d² for the Hessian) did not cancel between neighbours: gradient
/// 0.78%, 7.8%, 77% at 1e-4, 1e-5, 1e-6 (g 0.99), Hessian 92× at 1e-3 (g 0.99),
/// 4%, 33%, 14× at 1e-5, 1e-6, 1e-7 (g 0.6). Now their derivatives are edge
/// integrals (`core::lobe_boundary`), whose inner edges cancel exactly.
#[test]
fn derivatives_next_to_an_emitter() {
    // (σ_s, g, towards the eye, bounds per d = 1e-1 … 1e-8 on the gradient's and
    // the Hessian's errors; infinite: not checked)
    let no = f64::INFINITY;
    type Row = (f64, f64, bool, [f64; 8], [f64; 8]);
    let rows: [Row; 7] = [
        (
            1e-4,
            0.0,
            false,
            [1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 4e-3],
            [3e-3, 3e-3, 3e-3, no, no, no, no, no],
        ),
        (
            1.0,
            0.0,
            false,
            [1e-3; 8],
            [0.01, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 2e-3, 0.02],
        ),
        (
            1.0,
            0.6,
            false,
            [8e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3],
            [0.08, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 5e-3, 0.05],
        ),
        (
            1.0,
            0.99,
            false,
            [1e-3; 8],
            [0.015, 1e-3, 1e-3, 1e-3, 4e-3, 0.04, no, no],
        ),
        (
            1.0,
            0.6,
            true,
            [8e-3, 1e-3, 1.5e-3, 1.5e-3, 1.5e-3, 1e-3, 1e-3, 1e-3],
            [0.08, 2e-3, 0.02, 0.012, 0.012, 0.012, 0.012, 0.1],
        ),
        (
            1.0,
            0.99,
            true,
            [1e-3; 8],
            [0.02, 0.08, 0.02, 0.015, 0.015, 0.04, no, no],
        ),
        (
            1.0,
            -0.9,
            true,
            [1.5e-3, 1e-3, 1.5e-3, 1.5e-3, 1e-3, 1e-3, 1e-3, 1e-3],
            [0.01, 1e-3, 0.01, 0.01, 0.01, 0.01, 0.01, 0.025],
        ),
    ];
    for (sigma_s, g, eye, grad_bounds, hess_bounds) in rows {
        let scene = below_an_emitter(sigma_s, g);
        let out = if eye {
            Outgoing::TowardsPoint(DVec3::new(0.3, -2.0, 0.2))
        } else {
            Outgoing::Direction(DVec3::new(0.1, -1.0, 0.05))
        };
        for k in 0..8 {
            let d = 10f64.powi(-(k as i32) - 1);
            let x = DVec3::new(0.13, 0.6 - d, -0.07);
            let exact = exact3d::derivatives_about_lobe(&scene, x, out, d * 1e-2).luminance();
            let (mut grad, mut hess) = (0.0f64, 0.0f64);
            for seed in 1..=SEEDS {
                let lf = probe(&scene, x, out, 4096, seed);
                let aw = AwareSettings::default();
                let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
                assert!(
                    (got.value - exact.value).abs() < 2e-3 * exact.value,
                    "σ_s {sigma_s} g {g} d {d:e}: value {} against {}",
                    got.value,
                    exact.value
                );
                grad = grad.max((got.grad - exact.grad).length() / exact.grad.length());
                hess = hess.max(frobenius(got.hess - exact.hess) / frobenius(exact.hess));
            }
            let (gb, hb) = (grad_bounds[k], hess_bounds[k]);
            println!(
                "σ_s {sigma_s} g {g} eye {eye} d {d:e}: gradient error {grad:.2e}, Hessian {hess:.2e} (bound {hb})"
            );
            assert!(
                grad < gb,
                "σ_s {sigma_s} g {g} eye {eye} d {d:e}: gradient error {grad:e}"
            );
            assert!(
                hess < hb,
                "σ_s {sigma_s} g {g} eye {eye} d {d:e}: Hessian error {hess:e}"
            );
        }
    }
}

fn frobenius(m: DMat3) -> f64 {
    m.to_cols_array().iter().map(|e| e * e).sum::<f64>().sqrt()
}

/// Random points in the fog of a room (black floor, a black box below a two-sided
/// emitter, g = 0.5), ω_o fixed: the aware single part's gradient and Hessian
/// against the exact reference with visibility (`exact3d::derivatives`). Measured
/// (16 points), median and p90 of the relative errors, before (seeds 1–2) → after
/// (seeds 1–4) the silhouette cuts: 1024 directions ∇ 35%, 84% → 2.8%, 20%;
/// H 33%, 85% → 2.8%, 20%; 4096 directions ∇ 7.8%, 33% → 0.9%, 3.2%; H 8.4%, 34% →
/// 0.9%, 3.2%.
/// Before, the elements between a hit vertex and a neighbour that misses ended at
/// the vertex (or at one point of the silhouette where it could move), leaving
/// the emitter's rim out.
#[test]
fn derivatives_in_a_room() {
    let text = r#"{
  "camera": {"position": [0, 1.2, 3.5], "look_at": [0, 0.7, 0], "fov_deg": 50},
  "shapes": [
    {"quad": {"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}, "reflectance": 0},
    {"box": {"min": [-0.2, 0.5, -0.3], "max": [0.3, 0.7, 0.2]}, "reflectance": 0},
    {"quad": {"origin": [-0.6, 1.5, -0.5], "u": [0.7, 0, 0], "v": [0, -0.2, 0.6]},
     "reflectance": 0, "emission": [20, 18, 14], "two_sided": true}
  ],
  "medium": {"sigma_a": 0.05, "sigma_s": 0.8, "g": 0.5,
             "region": {"box": {"min": [-1.5, 0, -1.5], "max": [1.5, 1.8, 1.5]}}}
}"#;
    let scene = Scene::from_json(text, "room", Path::new(".")).unwrap();
    let omega_o = DVec3::new(0.3, -0.4, 0.866).normalize();
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let points: Vec<DVec3> = (0..16)
        .map(|_| DVec3::new(-1.2 + 2.4 * next(), 0.05 + 1.3 * next(), -1.2 + 2.4 * next()))
        .collect();
    let exact: Vec<_> = points
        .iter()
        .map(|&x| exact3d::derivatives(&scene, x, omega_o, 1e-3).luminance())
        .collect();
    // (directions, gradient median, p90, Hessian median, p90)
    for (rays, bounds) in [(1024, [0.08, 0.45, 0.08, 0.45]), (4096, [0.025, 0.08, 0.025, 0.08])] {
        let (mut ge, mut he) = (vec![], vec![]);
        for (&x, exact) in points.iter().zip(&exact) {
            for seed in 1..=SEEDS {
                let lf = probe(&scene, x, Outgoing::Direction(omega_o), rays, seed);
                let aw = AwareSettings::default();
                let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
                let floor = 1e-3 * exact.value;
                ge.push((got.grad - exact.grad).length() / exact.grad.length().max(floor));
                he.push(frobenius(got.hess - exact.hess) / frobenius(exact.hess).max(floor));
            }
        }
        let percentile = |v: &mut Vec<f64>, p: f64| {
            v.sort_by(f64::total_cmp);
            v[((v.len() - 1) as f64 * p).round() as usize]
        };
        let got = [
            percentile(&mut ge, 0.5),
            percentile(&mut ge, 0.9),
            percentile(&mut he, 0.5),
            percentile(&mut he, 0.9),
        ];
        println!(
            "{rays} directions: ∇ median {:.4} p90 {:.4} | H median {:.4} p90 {:.4}",
            got[0], got[1], got[2], got[3]
        );
        for (g, b) in got.iter().zip(bounds) {
            assert!(*g < b, "{rays} directions: {got:?} against {bounds:?}");
        }
    }
}

/// The proxy's surface elements tile the sphere of directions (4π) and the pieces
/// carrying the emitter cover its exact solid angle: the cut pieces fill each
/// simplex they split. Measured at 4096 directions: the tiling to 1e-12; the
/// emitter's 6.163518 sr covered as 6.163497 at d = 1e-2, 6.271216 exactly (to
/// 1e-6) at 1e-3 (before the cuts 6.199 there, and 6.2625 with cuts that stopped
/// at the quad's diagonal).
#[test]
fn cut_pieces_tile_the_directions() {
    use volcache::core::triangle::triangle_form_factor;
    use volcache::pipeline::proxy::{ElementKind, elements};
    let scene = below_an_emitter(1e-4, 0.0);
    for d in [1e-2, 1e-3, 1e-5] {
        let x = DVec3::new(0.13, 0.6 - d, -0.07);
        let corners = [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]].map(|[a, b]| DVec3::new(a, 0.6, b));
        let solid = |v: [DVec3; 3]| triangle_form_factor(v, x).value.abs();
        let exact = solid([corners[0], corners[1], corners[2]]) + solid([corners[0], corners[2], corners[3]]);
        let lf = probe(&scene, x, Outgoing::Direction(-DVec3::Y), 4096, 1);
        assert!(!lf.cuts.is_empty(), "d {d:e}: no cuts");
        let surface: Vec<_> = elements(&lf, Default::default())
            .into_iter()
            .filter(|e| e.kind == ElementKind::Surface)
            .collect();
        let all: f64 = surface.iter().map(|e| solid(e.v)).sum();
        let emitter: f64 = surface.iter().filter(|e| e.radiance.x > 0.5).map(|e| solid(e.v)).sum();
        println!("d {d:e}: all {all:.12} | emitter {emitter:.6} of {exact:.6}");
        assert!(
            (all - 4.0 * std::f64::consts::PI).abs() < 1e-9,
            "d {d:e}: the elements cover {all} sr"
        );
        assert!(
            (emitter - exact).abs() < 2e-5 * exact,
            "d {d:e}: emitter {emitter} of {exact}"
        );
    }
}
