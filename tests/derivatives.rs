//! The 2D derivative methods (theory.md §4–5) against the finite-difference
//! reference near occlusion boundaries, under rigid motions and at extremes. The
//! closed-form check of a lone emitter's form factor runs in both dimensions in
//! `dims_derivatives.rs`.

use glam::{DMat2, DVec2};
use volcache::core::space::D2;
use volcache::pipeline::derivatives::{self, AwareSettings, ReferenceSettings};
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy;

type PartDerivs = derivatives::PartDerivs<D2>;
use volcache::flatland::scene::Scene;
use volcache::progress::Progress;

fn aware_at(scene: &Scene, x: DVec2, rays: usize, seed: u64) -> PartDerivs {
    let ps = ProbeSettings {
        rays,
        ..ProbeSettings::default_for::<D2>()
    };
    let lf = capture(scene, x, Outgoing::Direction(DVec2::X), &ps, seed, 0, &Progress::new()).unwrap();
    let aw = AwareSettings::default();
    derivatives::aware(&lf, &proxy::build(&lf, aw.rule), &aw)
}

fn unaware_at(scene: &Scene, x: DVec2, rays: usize, seed: u64) -> PartDerivs {
    let ps = ProbeSettings {
        rays,
        ..ProbeSettings::default_for::<D2>()
    };
    let lf = capture(scene, x, Outgoing::Direction(DVec2::X), &ps, seed, 0, &Progress::new()).unwrap();
    derivatives::unaware(&lf)
}

fn frobenius(m: DMat2) -> f64 {
    (m.x_axis.length_squared() + m.y_axis.length_squared()).sqrt()
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// Near occlusion boundaries (penumbrae of the occluder, the windows' frames, the
/// stairs), the aware single-scattering derivatives (light from surfaces, where
/// occlusion changes live) are far closer to the reference than the unaware ones,
/// and within stated bounds. The multiple-scattering gradient too, since the shells'
/// smoothed kernel and the graded march (`pipeline::probe::March`): measured over
/// aware seeds 5–8 against the mean of two 40k-spp references, median vector error
/// 0.137–0.182 (0.56 with an even march and the exact kernel), max 0.26–0.34, and
/// cos(aware, reference) ≥ 0.978 at every point (the reference's own seed-to-seed
/// spread is 0.01–0.2 of its length).
#[test]
fn aware_beats_unaware_near_occlusion_boundaries() {
    let cases = [
        (
            "flatland_scenes/occluder.json",
            vec![
                (0.45, 0.0),
                (-0.45, 0.0),
                (0.5, -0.3),
                (-0.55, -0.4),
                (0.42, 0.1),
                (0.6, 0.2),
            ],
        ),
        (
            "flatland_scenes/windows.json",
            vec![
                (0.8, 0.45),
                (1.2, 0.75),
                (0.5, 0.15),
                (-1.9, 0.6),
                (-1.85, 1.2),
                (0.85, 2.4),
            ],
        ),
    ];
    let rs = ReferenceSettings {
        spp: 40_000,
        relative_step: 1e-2,
    };
    let (mut aware_err, mut unaware_err, mut hess_err, mut multi_err) = (vec![], vec![], vec![], vec![]);
    for (path, points) in cases {
        let scene = Scene::load(std::path::Path::new(path)).unwrap();
        for (x, y) in points {
            let x = DVec2::new(x, y);
            let reference =
                derivatives::reference_at(&scene, x, Outgoing::Direction(DVec2::X), &rs, &Default::default(), 11).parts;
            let (aw, un) = (aware_at(&scene, x, 4096, 5), unaware_at(&scene, x, 4096, 5));
            let (r, a, u) = (
                reference.single.luminance(),
                aw.single.luminance(),
                un.single.luminance(),
            );
            let rel = |g: DVec2, want: DVec2| (g - want).length() / want.length();
            let h = frobenius(a.hess - r.hess) / frobenius(r.hess);
            let (rm, am) = (reference.multiple.luminance(), aw.multiple.luminance());
            println!(
                "{path} {x}: single ∇ ref {:.4} aware {:.4} unaware {:.4} | aware H err {h:.3} | multiple ∇ ref {:.4} aware {:.4}",
                r.grad, a.grad, u.grad, rm.grad, am.grad
            );
            aware_err.push(rel(a.grad, r.grad));
            unaware_err.push(rel(u.grad, r.grad));
            hess_err.push(h);
            multi_err.push(rel(am.grad, rm.grad));
            let cos = am.grad.dot(rm.grad) / (am.grad.length() * rm.grad.length());
            assert!(
                cos > 0.9,
                "{path} {x}: multiple-scattering gradient points elsewhere (cos {cos})"
            );
        }
    }
    let a_med = percentile(&mut aware_err.clone(), 0.5);
    let u_med = percentile(&mut unaware_err.clone(), 0.5);
    let a_90 = percentile(&mut aware_err, 0.9);
    let h_med = percentile(&mut hess_err.clone(), 0.5);
    let h_90 = percentile(&mut hess_err, 0.9);
    let m_med = percentile(&mut multi_err, 0.5);
    println!(
        "single scattering, relative gradient error: aware median {a_med:.3} p90 {a_90:.3}; unaware median {u_med:.3}; \
         aware Hessian median {h_med:.3} p90 {h_90:.3}; (multiple, aware median {m_med:.3})"
    );
    assert!(a_med < 0.3 * u_med, "aware {a_med} vs unaware {u_med}");
    // Bounds from measurements, with margin for noise (see the issue note).
    assert!(a_med < 0.15, "aware median relative gradient error {a_med}");
    assert!(a_90 < 0.4, "aware p90 relative gradient error {a_90}");
    assert!(h_med < 0.5, "aware median Hessian error {h_med}");
    assert!(m_med < 0.25, "aware median multiple-scattering gradient error {m_med}");
}

/// More directions, smaller error against the exact single scattering
/// (`study::exact2d`) in and around the occluder's penumbra, with a black occluder
/// so that single scattering is the emitter's light alone. Measured (4 seeds, 3
/// points): mean relative gradient error 0.0112 at N = 128, 0.0002 at N = 4096.
/// Before the exact silhouettes (`pipeline::silhouette`) the N = 128 error was
/// dominated by the last hit's offset from the true edge (0.088 against a
/// finite-difference reference; 0.027 with them).
#[test]
fn aware_error_shrinks_with_more_rays() {
    let text = std::fs::read_to_string("flatland_scenes/occluder.json")
        .unwrap()
        .replace(r#""reflectance": 0.5"#, r#""reflectance": 0.0"#);
    let scene = Scene::from_json(&text, "black occluder").unwrap();
    let points = [DVec2::new(0.45, 0.0), DVec2::new(-0.5, -0.3), DVec2::new(0.6, 0.2)];
    let err = |rays: usize| -> f64 {
        points
            .iter()
            .map(|&x| {
                let r = volcache::study::exact2d::derivatives(&scene, x, DVec2::X, 1e-4).luminance();
                let errs: f64 = (0..4)
                    .map(|seed| {
                        let a = aware_at(&scene, x, rays, seed).single.luminance();
                        (a.grad - r.grad).length() / r.grad.length()
                    })
                    .sum();
                errs / 4.0
            })
            .sum::<f64>()
            / points.len() as f64
    };
    let (coarse, fine) = (err(128), err(4096));
    println!("mean relative single-scattering gradient error: N=128 {coarse:.4}, N=4096 {fine:.4}");
    assert!(fine < 0.5 * coarse, "N=128: {coarse}, N=4096: {fine}");
    assert!(fine < 0.003, "N=4096: {fine}");
}

/// Translating and rotating the whole scene moves and rotates the derivatives.
#[test]
fn derivatives_follow_rigid_motions_of_the_scene() {
    let text = std::fs::read_to_string("flatland_scenes/occluder.json").unwrap();
    let scene = Scene::from_json(&text, "occluder").unwrap();
    let angle = 0.7f64;
    let shift = DVec2::new(3.0, -2.0);
    let rot = glam::DMat2::from_angle(angle);
    let map = |p: [f64; 2]| (rot * DVec2::from_array(p) + shift).to_array();
    let mut desc = scene.desc.clone();
    for s in &mut desc.segments {
        s.a = s.a.map(map);
        s.b = s.b.map(map);
    }
    // A domain containing the moved scene.
    desc.domain.min = [shift.x - 2.0, shift.y - 2.0];
    desc.domain.max = [shift.x + 2.0, shift.y + 2.0];
    let moved = Scene::from_desc(desc, "moved").unwrap();
    for x in [DVec2::new(0.45, 0.0), DVec2::new(-0.6, 0.5)] {
        let a = aware_at(&scene, x, 8192, 1).single.luminance();
        let b = aware_at(&moved, rot * x + shift, 8192, 1).single.luminance();
        let g = rot * a.grad;
        assert!((b.value - a.value).abs() < 0.02 * a.value, "{} vs {}", b.value, a.value);
        assert!((b.grad - g).length() < 0.05 * g.length(), "{} vs {}", b.grad, g);
        let h = rot * a.hess * rot.transpose();
        assert!(frobenius(b.hess - h) < 0.1 * frobenius(h), "{:?} vs {:?}", b.hess, h);
    }
}

/// Every method returns finite numbers at extreme points and parameters.
#[test]
fn derivatives_are_finite_at_extremes() {
    for (g, sig) in [(0.99, 1e-6), (-0.99, 1e3), (0.0, 50.0)] {
        let scene = Scene::from_json(
            &format!(
                r#"{{ "domain": {{"min": [-1, -1], "max": [1, 1]}},
                 "segments": [{{"a": [-0.5, 0.5], "b": [0.5, 0.5], "emission": 1, "reflectance": 0.5}},
                              {{"a": [-0.3, 0], "b": [0.3, 0], "reflectance": 0.8}}],
                 "lights": [{{"type": "point", "position": [0, -0.5], "intensity": 1}}],
                 "medium": {{"sigma_a": {sig}, "sigma_s": {sig}, "g": {g}}} }}"#
            ),
            "extreme",
        )
        .unwrap();
        // On a segment, a hair's breadth from an endpoint, on the point light.
        for x in [
            DVec2::new(0.1, 0.0),
            DVec2::new(0.3 + 1e-9, 1e-9),
            DVec2::new(0.0, -0.5),
            DVec2::new(0.0, 0.4999999),
        ] {
            let a = aware_at(&scene, x, 256, 1);
            let u = unaware_at(&scene, x, 256, 1);
            assert!(a.is_finite() && u.is_finite(), "g={g} σ={sig} x={x}: {a:?}");
        }
    }
}
