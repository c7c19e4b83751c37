//! 3D radiometry of the reference path tracer against published values
//! (`../shared/design/benchmarks.md`, 3D) and closed forms of 3D lights (sky, sun
//! cone, area light), each within four standard errors with standard errors below
//! 1%; crops. The checks that hold in both dimensions (furnace, point light, single
//! scattering, thread independence) are in `dims_radiometry.rs`.

use glam::DVec3;
use std::f64::consts::PI;
use std::path::Path;
use volcache::core::color::Rgb;
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
        ..Default::default()
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

/// A crop renders exactly the pixels of the full image (thread independence is
/// checked in both dimensions in `dims_radiometry.rs`).
#[test]
fn a_crop_renders_the_same_pixels_as_the_full_image() {
    let s = Scene::load(Path::new("scenes3d/fog_box.json")).unwrap();
    let mut p = RenderParams::from_scene(&s);
    (p.width, p.height, p.spp) = (40, 30, 3);
    let full = render(&s, &p, &Progress::new()).unwrap();
    assert!(full.values.iter().any(|v| v.max_element() > 0.0));
    let mut c = p.clone();
    c.crop = Some([10, 5, 25, 20]);
    let crop = render(&s, &c, &Progress::new()).unwrap();
    for j in 0..15 {
        for i in 0..15 {
            assert_eq!(crop.values[j * 15 + i], full.values[(j + 5) * 40 + i + 10]);
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
