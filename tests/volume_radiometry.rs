//! 3D radiometry of the reference path tracer against closed forms, quadrature and
//! published values (`../shared/design/benchmarks.md`, 3D), each within four
//! standard errors with standard errors below 1%; and thread-independent images.

use glam::DVec3;
use std::f64::consts::PI;
use std::path::Path;
use volcache::core::color::Rgb;
use volcache::core::phase::Hg3;
use volcache::pipeline::path::{Query, Settings, estimate_with as estimate, radiance_path, sample_query};
use volcache::progress::Progress;
use volcache::volume::render::{RenderParams, render};
use volcache::volume::scene::Scene;

fn scene(json: &str) -> Scene {
    Scene::from_json(json, "<test>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

const CAMERA: &str = r#""camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}"#;

/// Mean within 4 standard errors of `want` (per channel), and the error below 1%.
fn check(what: &str, (mean, se): (Rgb, Rgb), want: Rgb) {
    eprintln!("{what}: {mean} ± {se} (want {want})");
    for c in 0..3 {
        assert!(
            se[c] < 0.01 * want[c],
            "{what}: std error {} not below 1% of {}",
            se[c],
            want[c]
        );
        assert!(
            (mean[c] - want[c]).abs() < 4.0 * se[c],
            "{what}: channel {c}: {} vs {} ({:.1} std errors)",
            mean[c],
            want[c],
            (mean[c] - want[c]).abs() / se[c]
        );
    }
}

/// A diffuse quad lit by a point light in vacuum: L = (ρ/π) I cosθ / r², exactly
/// (NEE is deterministic and the bounce escapes).
#[test]
fn point_light_on_a_diffuse_quad_is_exact() {
    let s = scene(&format!(
        r#"{{ {CAMERA}, "shapes": [{{"quad": {{"origin": [-5, 0, -5], "u": [0, 0, 10], "v": [10, 0, 0]}},
            "reflectance": [0.5, 0.25, 0.8], "two_sided": false}}],
            "lights": [{{"point": {{"position": [0.3, 1.2, 0.2], "intensity": [2, 3, 1]}}}}] }}"#
    ));
    let (cam, y) = (DVec3::new(-1.0, 2.0, 2.0), DVec3::new(0.1, 0.0, -0.2));
    let d = DVec3::new(0.3, 1.2, 0.2) - y;
    let want = Rgb::new(0.5, 0.25, 0.8) / PI * Rgb::new(2.0, 3.0, 1.0) * (d.y / d.length()) / d.length_squared();
    let mut rays = 0;
    for k in 0..16 {
        let mut smp = volcache::core::rng::Sampler::new(1, k);
        let l = radiance_path(
            &s,
            cam,
            (y - cam).normalize(),
            None,
            None,
            &Settings::default(),
            &mut smp,
            &mut rays,
        )
        .0;
        assert!(
            (l - want).abs().max_element() < 1e-12 * want.max_element(),
            "{l} vs {want}"
        );
    }
}

/// Closed box whose walls emit L_e and reflect ρ, filled with a non-absorbing
/// anisotropic medium: L = L_e / (1 − ρ) in every direction.
#[test]
fn furnace() {
    let wall = |o: [f64; 3], u: [f64; 3], v: [f64; 3]| {
        format!(
            r#"{{"quad": {{"origin": {o:?}, "u": {u:?}, "v": {v:?}}}, "reflectance": [0.6, 0.5, 0.3], "emission": [0.4, 0.5, 0.7]}}"#
        )
    };
    let walls = [
        wall([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
        wall([-1.0, -1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
        wall([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]),
        wall([1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]),
        wall([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
        wall([-1.0, 1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
    ]
    .join(",");
    let s = scene(&format!(
        r#"{{ "camera": {{"position": [0, 0, 0.5], "look_at": [0, 0, 0], "fov_deg": 40}}, "shapes": [{walls}],
            "medium": {{"sigma_a": 0, "sigma_s": [1.0, 0.8, 0.6], "g": 0.5}} }}"#
    ));
    let settings = Settings {
        max_depth: 100_000,
        rr_depth: 3,
    };
    let x = DVec3::new(0.2, -0.3, 0.1);
    let mut rays = 0;
    let est = estimate(160_000, 3, 0, |smp| {
        let w = DVec3::new(smp.next_f64() - 0.5, smp.next_f64() - 0.5, smp.next_f64() - 0.5).normalize();
        radiance_path(&s, x, w, None, None, &settings, smp, &mut rays).0
    });
    check("furnace", est, Rgb::new(0.4 / 0.4, 0.5 / 0.5, 0.7 / 0.7));
}

/// Single scattering (max_depth 1) from a point light along one ray, g = 0.5,
/// against Simpson quadrature of σ_s e^{−σ_t t} f(μ) I e^{−σ_t r} / r² dt.
#[test]
fn single_scattering_matches_quadrature() {
    let (sa, ss, g, i) = (0.3, 0.5, 0.5, 2.0);
    let s = scene(&format!(
        r#"{{ {CAMERA}, "lights": [{{"point": {{"position": [0, 1, 0], "intensity": {i}}}}}],
            "medium": {{"sigma_a": {sa}, "sigma_s": {ss}, "g": {g}}} }}"#
    ));
    let (o, d, light) = (DVec3::new(-2.0, 0.0, 0.0), DVec3::X, DVec3::Y);
    let hg = Hg3::new(g);
    let f = |t: f64| {
        let p = o + d * t;
        let to = light - p;
        let r = to.length();
        ss * (-(sa + ss) * t).exp() * hg.eval(d, to / r) * i * (-(sa + ss) * r).exp() / (r * r)
    };
    let (n, len) = (200_000, 60.0);
    let h = len / n as f64;
    let want = (0..=n)
        .map(|k| {
            f(k as f64 * h)
                * if k == 0 || k == n {
                    1.0
                } else if k % 2 == 1 {
                    4.0
                } else {
                    2.0
                }
        })
        .sum::<f64>()
        * h
        / 3.0;
    let settings = Settings {
        max_depth: 1,
        rr_depth: 3,
    };
    let mut rays = 0;
    let est = estimate(200_000, 5, 0, |smp| {
        radiance_path(&s, o, d, None, None, &settings, smp, &mut rays).0
    });
    check("single scattering", est, Rgb::splat(want));
}

/// Reflectance or transmittance of a medium box under a collimated beam (a sun of
/// zero angular radius, irradiance 1, travelling along −z): the irradiance on a
/// virtual sensor just outside the boundary, facing the medium.
fn boundary_flux(albedo: f64, zmin: f64, sensor_z: f64, normal_z: f64, n: u64) -> (Rgb, Rgb) {
    let s = scene(&format!(
        r#"{{ {CAMERA}, "lights": [{{"sun": {{"direction": [0, 0, -1], "irradiance": 1}}}}],
            "medium": {{"sigma_a": {}, "sigma_s": {albedo},
                        "region": {{"box": {{"min": [-1e4, -1e4, {zmin}], "max": [1e4, 1e4, 0]}}}}}} }}"#,
        1.0 - albedo
    ));
    let settings = Settings {
        max_depth: 1_000_000,
        rr_depth: 3,
    };
    let (x, nrm) = (DVec3::new(0.0, 0.0, sensor_z), DVec3::new(0.0, 0.0, normal_z));
    let mut rays = 0;
    estimate(n, 11, 0, |smp| {
        sample_query(&s, x, &Query::Irradiance { normal: nrm }, &settings, smp, &mut rays).total()
    })
}

#[test]
fn half_space_reflectance() {
    for (a, r) in [(0.5, 0.11522588), (0.9, 0.41494748)] {
        let est = boundary_flux(a, -1e4, 1e-9, -1.0, 400_000);
        check(&format!("half-space R({a})"), est, Rgb::splat(r));
    }
}

#[test]
fn slab_reflectance_and_transmittance() {
    check(
        "slab R",
        boundary_flux(1.0, -1.0, 1e-9, -1.0, 200_000),
        Rgb::splat(0.34133),
    );
    check(
        "slab T",
        boundary_flux(1.0, -1.0, -1.0 - 1e-9, 1.0, 200_000),
        Rgb::splat(0.65867),
    );
}

#[test]
fn images_are_identical_with_one_and_two_threads() {
    let s = Scene::load(Path::new("scenes3d/fog_box.json")).unwrap();
    let mut p = RenderParams::from_scene(&s);
    (p.width, p.height, p.spp) = (40, 30, 3);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render(&s, &p, &Progress::new()).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.spp, 3);
    assert!(a.values.iter().any(|v| v.max_element() > 0.0));
    assert_eq!(a.values, b.values);
    assert_eq!(a.std_error, b.std_error);
    assert_eq!(a.rays, b.rays);
    // A crop renders exactly the same pixels as the full image.
    let mut c = p.clone();
    c.crop = Some([10, 5, 25, 20]);
    let crop = render(&s, &c, &Progress::new()).unwrap();
    for j in 0..15 {
        for i in 0..15 {
            assert_eq!(crop.values[j * 15 + i], a.values[(j + 5) * 40 + i + 10]);
        }
    }
}

/// A diffuse floor under a constant sky and a sun with a 10° cone, in vacuum: the
/// cone's irradiance is exactly E cosθ_axis (its first moment lies along the axis),
/// so L = (ρ/π)(π L_sky + E cosθ). Exercises sky and cone NEE with MIS.
#[test]
fn sky_and_sun_cone_light_a_floor() {
    let s = scene(&format!(
        r#"{{ {CAMERA}, "shapes": [{{"quad": {{"origin": [-5, 0, -5], "u": [0, 0, 10], "v": [10, 0, 0]}},
            "reflectance": 0.6, "two_sided": false}}],
            "lights": [{{"sky": {{"radiance": [0.3, 0.2, 0.1]}}}},
                       {{"sun": {{"direction": [0.3, -1, 0.2], "irradiance": 2, "angular_radius_deg": 10}}}}] }}"#
    ));
    let cos_axis = 1.0 / DVec3::new(0.3, -1.0, 0.2).length();
    let want = (Rgb::new(0.3, 0.2, 0.1) * PI + Rgb::splat(2.0 * cos_axis)) * (0.6 / PI);
    let (cam, y) = (DVec3::new(0.5, 1.0, 2.0), DVec3::new(0.2, 0.0, -0.1));
    let mut rays = 0;
    let est = estimate(100_000, 13, 0, |smp| {
        radiance_path(
            &s,
            cam,
            (y - cam).normalize(),
            None,
            None,
            &Settings::default(),
            smp,
            &mut rays,
        )
        .0
    });
    check("sky + sun cone on a floor", est, want);
}

/// Irradiance under a one-sided emitting square (side 1, height ½, facing down) at
/// its centre, against the closed-form point-to-parallel-rectangle form factor
/// (four corner rectangles). Exercises emitter NEE with MIS against BRDF sampling.
#[test]
fn area_light_irradiance_matches_the_form_factor() {
    let s = scene(&format!(
        r#"{{ {CAMERA}, "shapes": [{{"quad": {{"origin": [-0.5, 0.5, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]}},
            "emission": [2, 1, 0.5], "two_sided": false}}] }}"#
    ));
    let corner = |x: f64, y: f64| {
        let (ax, ay) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / ax * (y / ax).atan() + y / ay * (x / ay).atan()) / (2.0 * PI)
    };
    let f = 4.0 * corner(1.0, 1.0); // a = b = ½ at height ½
    let want = Rgb::new(2.0, 1.0, 0.5) * (PI * f);
    let mut rays = 0;
    let est = estimate(40_000, 17, 0, |smp| {
        sample_query(
            &s,
            DVec3::ZERO,
            &Query::Irradiance { normal: DVec3::Y },
            &Settings::default(),
            smp,
            &mut rays,
        )
        .total()
    });
    check("area light irradiance", est, want);
}
