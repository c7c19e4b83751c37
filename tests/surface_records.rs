//! Irradiance records on surfaces (issue 16 item 3, `pipeline::surface_record`):
//! ours' value, gradient and Hessian of a floor point's irradiance against the
//! exact direct irradiance (`study::exact3d::irradiance`: emitter polygons minus
//! the occluders' central projections, Gauss–Legendre, central differences), in
//! vacuum and in fog, unoccluded and in penumbrae; the indirect-only record against
//! the same capture with emission; the value against path-traced irradiance.

use glam::{DMat3, DVec3};
use std::path::Path;
use volcache::core::color::luminance;
use volcache::core::metric::CacheMethod;
use volcache::core::space::D3;
use volcache::pipeline::path::{Query, Settings, estimate};
use volcache::pipeline::probe::SurfaceReceiver;
use volcache::pipeline::record::CacheSettings;
use volcache::pipeline::surface_record::{SurfaceRecordData, compute_surface_record};
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

/// A black floor at y = −1 (the receiver), a square emitter at y = 1 facing down,
/// `others` (black occluders), in a medium of extinction `sigma_t` (none at 0).
fn scene(others: &str, sigma_t: f64, g: f64, walls: &str) -> Scene {
    let medium = if sigma_t > 0.0 {
        format!(
            r#", "medium": {{"sigma_a": {}, "sigma_s": {}, "g": {g}}}"#,
            0.2 * sigma_t,
            0.8 * sigma_t
        )
    } else {
        String::new()
    };
    let text = format!(
        r#"{{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
            "shapes": [
              {{"quad": {{"origin": [-3.37, -1, -2.77], "u": [0, 0, 6], "v": [6, 0, 0]}}, "reflectance": 0}},
              {{"quad": {{"origin": [-0.6, 1, -0.5], "u": [1.1, 0, 0], "v": [0, 0.15, 1]}}, "emission": [3, 2.5, 2], "reflectance": 0}}
              {others}{walls}]{medium}}}"#
    );
    Scene::from_json(&text, "surface records", Path::new(".")).unwrap()
}

const OCCLUDERS: &str = r#",
    {"quad": {"origin": [-0.5, 0.1, -0.7], "u": [0.6, 0, 0.1], "v": [0.05, 0, 0.8]}, "reflectance": 0},
    {"quad": {"origin": [0.3, -0.3, 0.0], "u": [0.5, 0.1, 0], "v": [0, 0, 0.6]}, "reflectance": 0}"#;

const UP: DVec3 = DVec3::Y;

fn floor_prim(scene: &Scene, x: DVec3) -> u32 {
    scene
        .closest_hit(x + UP * 0.5, -UP, 1.0, None)
        .expect("the floor is under every test point")
        .prim
}

fn record(scene: &Scene, x: DVec3, emitted: bool, (rays, depth): (usize, u32), seed: u64) -> SurfaceRecordData<D3> {
    let mut cs = CacheSettings::new::<D3>(CacheMethod::Ours, 1.0, Settings::default());
    cs.probe.rays = rays;
    cs.probe.settings.max_depth = depth;
    cs.seed = seed;
    let receiver = SurfaceReceiver {
        normal: UP,
        prim: floor_prim(scene, x),
        emitted,
    };
    compute_surface_record(scene, x, receiver, &cs, 0, &Progress::new()).unwrap()
}

/// Relative value, gradient and Hessian errors of the light from surfaces (the
/// emitter) against the exact direct irradiance, tangential parts (the floor's
/// normal is an axis, so the central differences' tangential stencil stays on it).
fn errors(scene: &Scene, x: DVec3, rays: usize, seed: u64) -> (f64, f64, f64) {
    let exact = exact3d::irradiance_derivatives(scene, x, UP, 1e-4).luminance();
    let p = DMat3::IDENTITY - DMat3::from_cols(DVec3::ZERO, UP, DVec3::ZERO);
    let (eg, eh) = (p * exact.grad, p * exact.hess * p);
    let got = record(scene, x, true, (rays, 2), seed).parts.single.luminance();
    (
        (got.value - exact.value).abs() / exact.value,
        (got.grad - eg).length() / eg.length(),
        frobenius(got.hess - eh) / frobenius(eh),
    )
}

/// The share of the emitter seen from `x` (a grid of points on it).
fn visible_share(scene: &Scene, x: DVec3) -> f64 {
    let (mut seen, mut all) = (0, 0);
    for i in 0..16 {
        for j in 0..16 {
            let y = DVec3::new(-0.6, 1.0, -0.5)
                + DVec3::new(1.1, 0.0, 0.0) * ((i as f64 + 0.5) / 16.0)
                + DVec3::new(0.0, 0.15, 1.0) * ((j as f64 + 0.5) / 16.0);
            let d = y - x;
            all += 1;
            seen += !scene.occluded(x + UP * 1e-9, d.normalize(), d.length() * (1.0 - 1e-9), None) as usize;
        }
    }
    seen as f64 / all as f64
}

/// Floor points on a jittered grid that see 5–95% of the emitter.
fn penumbra_points(scene: &Scene, want: usize) -> Vec<DVec3> {
    let n = 24;
    let mut out = vec![];
    for k in 0..n * n {
        let k = k * 31 % (n * n);
        let (i, j) = ((k / n) as f64 + 0.5, (k % n) as f64 + 0.5);
        let x = DVec3::new(-1.5 + 3.0 * i / n as f64, -1.0, -1.5 + 3.0 * j / n as f64);
        let s = visible_share(scene, x);
        if (0.05..0.95).contains(&s) && out.len() < want {
            out.push(x);
        }
    }
    out
}

/// Unoccluded, in vacuum: the record's irradiance and its tangential derivatives
/// are the closed form's up to the proxy's discretisation, which falls with the
/// ray count. Measured at these 4 points (value / gradient / Hessian, worst), on
/// the streams this test draws (seed 1): 16384 rays 1.0% / 2.8% / 1.4%; seeds 1–4
/// 1.7% / 3.0% / 2.8% — the bound has little margin on its one fixed seed (the
/// result is deterministic). On an earlier stream salt: 1024 rays 9.0% / 19% / 19%,
/// 4096 rays 1.5% / 9.4% / 5.7%.
#[test]
fn an_unoccluded_emitter_gives_the_exact_irradiance_derivatives() {
    let s = scene("", 0.0, 0.0, "");
    let mut worst: f64 = 0.0;
    for x in [
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(0.7, -1.0, -0.4),
        DVec3::new(-1.3, -1.0, 0.9),
        DVec3::new(1.6, -1.0, 1.2),
    ] {
        let (v, g, h) = errors(&s, x, 16384, 1);
        println!("unoccluded {x}: value {v:.2e} ∇ {g:.2e} H {h:.2e}");
        worst = worst.max(v).max(g).max(h);
    }
    assert!(worst < 0.03, "worst relative error {worst}");
}

/// Penumbrae of two occluders, in vacuum and in fog (σ_t = 1, g = 0.6), 10 floor
/// points at 16384 rays. Measured over seeds 1–4 (vacuum / fog): value median
/// 0.8% / 0.9%; gradient median 0.07% / 0.07%, p90 0.8% / 1.0%; Hessian median
/// 0.16% / 0.30%, p90 2.9% / 2.2%. Before the proxy followed the emitter's edge to
/// the corner where a shadow's edge crosses it (`pipeline::proxy_cut::Corner`,
/// `tests/hessian_occlusion_3d.rs`), seeds 1–2: gradient median 5.5% / 2.7%, p90
/// 26% / 29%; Hessian median 44% / 31%, p90 103% / 96%. The test runs seeds 1–2.
#[test]
fn derivatives_in_penumbrae_on_a_floor() {
    for (sigma_t, g) in [(0.0, 0.0), (1.0, 0.6)] {
        let s = scene(OCCLUDERS, sigma_t, g, "");
        let points = penumbra_points(&s, 10);
        assert!(points.len() >= 8, "only {} penumbra points", points.len());
        let (mut ve, mut ge, mut he) = (vec![], vec![], vec![]);
        for seed in 1..=2 {
            for &x in &points {
                let (v, g, h) = errors(&s, x, 16384, seed);
                ve.push(v);
                ge.push(g);
                he.push(h);
            }
        }
        let vm = percentile(&mut ve, 0.5);
        let (gm, g90) = (percentile(&mut ge.clone(), 0.5), percentile(&mut ge, 0.9));
        let (hm, h90) = (percentile(&mut he.clone(), 0.5), percentile(&mut he, 0.9));
        println!(
            "σ_t {sigma_t} g {g}: n {} value median {vm:.4} | ∇ median {gm:.4} p90 {g90:.4} | H median {hm:.4} p90 {h90:.4}",
            points.len()
        );
        assert!(vm < 0.015, "value median {vm}");
        assert!(gm < 0.005 && g90 < 0.03, "gradient median {gm} p90 {g90}");
        assert!(hm < 0.01 && h90 < 0.08, "Hessian median {hm} p90 {h90}");
    }
}

/// Without `emitted`, a record holds only indirect light: with every surface black
/// nothing is reflected, so the light from surfaces is exactly zero, and the light
/// from the medium is the same, bit for bit, as the capture with emission (the same
/// streams).
#[test]
fn an_indirect_record_leaves_out_exactly_the_direct_light() {
    let s = scene(OCCLUDERS, 1.0, 0.3, "");
    let x = DVec3::new(0.2, -1.0, 0.3);
    let with = record(&s, x, true, (1024, 2), 3);
    let without = record(&s, x, false, (1024, 2), 3);
    assert!(with.parts.single.value().x > 0.0);
    assert_eq!(without.parts.single.value(), DVec3::ZERO);
    assert_eq!(without.parts.multiple, with.parts.multiple);
    assert!(without.parts.multiple.value().x > 0.0);
}

/// The value against path-traced irradiance at the point, in fog with coloured
/// walls (reflections and in-scattering included, full path depth).
#[test]
fn the_value_is_the_path_traced_irradiance() {
    let walls = r#",
        {"quad": {"origin": [-1.5, -1, -1.5], "u": [0, 0, 3], "v": [0, 2.5, 0]}, "reflectance": 0.8},
        {"quad": {"origin": [1.5, -1, -1.5], "u": [0, 2.5, 0], "v": [0, 0, 3]}, "reflectance": [0.2, 0.7, 0.5]}"#;
    let s = scene(OCCLUDERS, 0.7, 0.5, walls);
    for x in [DVec3::new(0.2, -1.0, 0.3), DVec3::new(-1.1, -1.0, -0.8)] {
        let e = estimate(
            &s,
            x + UP * 1e-9,
            &Query::Irradiance { normal: UP },
            &Settings::default(),
            20_000,
            11,
            0,
        );
        let (mean, se) = (luminance(e.mean.total()), luminance(e.total_std_error));
        let values: Vec<f64> = (1..=4)
            .map(|seed| luminance(record(&s, x, true, (4096, 1024), seed).irradiance().value()))
            .collect();
        let m = values.iter().sum::<f64>() / 4.0;
        let sd = (values.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / 3.0).sqrt();
        println!("{x}: record {m:.5} ± {sd:.5} (4 seeds) vs path traced {mean:.5} ± {se:.5}");
        // Measured 0.9 and 0.2 combined standard errors apart (the path tracer's and
        // the 4 records' mean's).
        let sigma = (se * se + sd * sd / 4.0).sqrt();
        assert!(
            (m - mean).abs() < 4.0 * sigma,
            "{x}: record {m} vs path traced {mean} (σ {sigma})"
        );
    }
}

/// The same record in 2D (the method is one, generic over the dimension): a floor
/// point's irradiance from a lone emitting segment, L·|cos φ_a − cos φ_b| for the
/// directions φ to its ends, with its tangential derivatives by central
/// differences. Measured at 4096 rays (3 points, worst): value 2.4e-3 (the plain
/// estimate), gradient 2.7e-7, Hessian 1.0e-6 — the 2D proxy of a lone segment is
/// exact.
#[test]
fn a_2d_floor_point_gets_the_closed_form_irradiance() {
    use glam::DVec2;
    use volcache::core::space::D2;
    let json = r#"{ "domain": {"min": [-2, -1.5], "max": [2, 1.5]},
        "segments": [
          {"name": "emitter", "a": [0.45, 0.8], "b": [-0.5, 0.95], "emission": 2.0, "two_sided": true},
          {"name": "floor", "a": [-2, -1], "b": [2, -1], "reflectance": 0}
        ],
        "render": {"resolution": [16, 16], "spp": 1, "seed": 1} }"#;
    let s = volcache::flatland::scene::Scene::from_json(json, "<test>").unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (DVec2::new(0.45, 0.8), DVec2::new(-0.5, 0.95));
    let exact = |x: DVec2| {
        let (da, db) = ((a - x).normalize(), (b - x).normalize());
        2.0 * (da.x - db.x).abs()
    };
    let mut worst: [f64; 3] = [0.0; 3];
    for x in [DVec2::new(0.0, -1.0), DVec2::new(0.8, -1.0), DVec2::new(-1.4, -1.0)] {
        let h = 1e-4;
        let (e, ep, em) = (exact(x), exact(x + DVec2::X * h), exact(x - DVec2::X * h));
        let (grad, hess) = ((ep - em) / (2.0 * h), (ep - 2.0 * e + em) / (h * h));
        let prim = s.closest_hit(x + DVec2::Y * 0.5, -DVec2::Y, 1.0, None).unwrap().prim;
        let mut cs = CacheSettings::new::<D2>(CacheMethod::Ours, 1.0, Settings::default());
        cs.probe.rays = 4096;
        let receiver = SurfaceReceiver {
            normal: DVec2::Y,
            prim,
            emitted: true,
        };
        let r = compute_surface_record(&s, x, receiver, &cs, 0, &Progress::new()).unwrap();
        let got = r.parts.single.luminance();
        let errs = [
            (got.value - e).abs() / e,
            (got.grad.x - grad).abs() / grad.abs().max(0.1 * e),
            (got.hess.x_axis.x - hess).abs() / hess.abs().max(0.1 * e),
        ];
        println!(
            "2D {x}: exact {e:.6} {grad:.6} {hess:.6}, got {} {} {}: errors {errs:?}",
            got.value, got.grad, got.hess
        );
        assert_eq!((got.grad.y, got.hess.y_axis.y), (0.0, 0.0), "tangential parts only");
        for (w, e) in worst.iter_mut().zip(errs) {
            *w = w.max(e);
        }
    }
    assert!(
        worst[0] < 0.01 && worst[1] < 1e-4 && worst[2] < 1e-4,
        "worst errors {worst:?}"
    );
}

/// `path::direct_at` (what a surface cache leaves to each pixel) is the exact
/// direct light: with a white Lambertian lobe its mean is E_direct/π, in vacuum and
/// in fog, lit and in penumbrae (MIS between NEE and the lobe's ray, transmittance
/// of the unscattered way). Measured within 1.3 standard errors at 6 points.
#[test]
fn the_per_pixel_direct_light_is_the_exact_direct_irradiance() {
    use volcache::core::rng::Sampler;
    use volcache::pipeline::lobe::Lobe;
    use volcache::pipeline::path::direct_at;
    for sigma_t in [0.0, 1.0] {
        let s = scene(OCCLUDERS, sigma_t, 0.6, "");
        for x in [DVec3::new(0.1, -1.0, 0.2), DVec3::new(-0.9, -1.0, 0.6)]
            .into_iter()
            .chain(penumbra_points(&s, 1))
        {
            let want = luminance(exact3d::irradiance(&s, x, UP)) / std::f64::consts::PI;
            let lobe = Lobe::Lambert {
                normal: UP,
                reflectance: DVec3::ONE,
            };
            let prim = floor_prim(&s, x);
            let (n, mut sum, mut sum2, mut rays) = (40_000, 0.0, 0.0, 0);
            for k in 0..n {
                let mut smp = Sampler::new2(5, 7, k);
                let v = luminance(direct_at(&s, x, &lobe, Some(prim), &mut smp, &mut rays));
                sum += v;
                sum2 += v * v;
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
            println!("σ_t {sigma_t} {x}: direct {mean:.5} ± {se:.5}, exact {want:.5}");
            assert!(
                (mean - want).abs() < 4.0 * se + 1e-3 * want,
                "{x}: {mean} ± {se} vs {want}"
            );
        }
    }
}

/// A floor outside a bounded fog layer, lit through it: the record's light from
/// surfaces is the exact direct irradiance through the layer (the proxy's
/// homogeneous transmittance is σ_t at the receiver, zero here; each hit carries
/// the true transmittance's ratio to it). Measured: within 0.5%, 0.8%, 1.7% at 3
/// points; without the ratio they would be 1/T too high (T = e^{−1.5·1.3} ≈ 1/7
/// straight up).
#[test]
fn a_floor_below_a_fog_layer_gets_the_attenuated_irradiance() {
    let text = r#"{"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40},
        "shapes": [
          {"quad": {"origin": [-3.37, -1, -2.77], "u": [0, 0, 6], "v": [6, 0, 0]}, "reflectance": 0},
          {"quad": {"origin": [-0.6, 1, -0.5], "u": [1.1, 0, 0], "v": [0, 0.15, 1]}, "emission": [3, 2.5, 2], "reflectance": 0}
        ],
        "medium": {"sigma_a": 0.3, "sigma_s": 1.2, "g": 0.5,
                   "region": {"box": {"min": [-4, -0.5, -4], "max": [4, 0.8, 4]}}}}"#;
    let s = Scene::from_json(text, "fog layer", Path::new(".")).unwrap();
    for x in [
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(0.7, -1.0, -0.4),
        DVec3::new(-1.3, -1.0, 0.9),
    ] {
        let exact = luminance(exact3d::irradiance(&s, x, UP));
        let got = luminance(record(&s, x, true, (4096, 2), 1).parts.single.value());
        println!("fog layer {x}: record {got:.5}, exact {exact:.5}");
        assert!((got / exact - 1.0).abs() < 0.03, "{x}: {got} vs {exact}");
    }
}
