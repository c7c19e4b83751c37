//! 3D occlusion-aware derivatives (issue 6 §4): the aware / unaware methods against
//! finite differences of the path tracer (anisotropic media, a camera's turning ω_o,
//! the fog box's penumbra) and at extremes. The closed-form form-factor check and
//! the proxy's closure run in both dimensions in `dims_derivatives.rs`.

use glam::DVec3;
use std::path::Path;
use volcache::core::color::luminance;
use volcache::core::space::D3;
use volcache::core::taylor_rgb::TaylorRgb;
use volcache::pipeline::derivatives::{AwareSettings, aware, reference, unaware};
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy::{RadianceRule, build};
use volcache::pipeline::world::World;
use volcache::progress::Progress;

type LightField = volcache::pipeline::probe::LightField<D3>;

/// Central differences of the path-traced L_s (all parts) with common random
/// numbers: value and gradient.
fn reference_gradient_towards(
    s: &Scene,
    x: DVec3,
    out: Outgoing<DVec3>,
    h: f64,
    spp: u32,
    settings: &Settings,
    seed: u64,
) -> TaylorRgb<D3> {
    reference(s, x, out, h, spp, settings, seed, false).parts.total()
}

fn reference_gradient(
    s: &Scene,
    x: DVec3,
    omega_o: DVec3,
    h: f64,
    spp: u32,
    settings: &Settings,
    seed: u64,
) -> TaylorRgb<D3> {
    reference_gradient_towards(s, x, Outgoing::Direction(omega_o), h, spp, settings, seed)
}
use volcache::pipeline::path::Settings;
use volcache::volume::scene::Scene;

fn scene(json: &str) -> Scene {
    Scene::from_json(json, "<test>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

const SIGMA_S: f64 = 1e-3;
const L_E: f64 = 3.0;

/// A lone one-sided emissive quad (y = 1, |x|, |z| ≤ 1, shining down) in a thin
/// isotropic medium filling space.
fn lone_quad() -> Scene {
    scene(&format!(
        r#"{{ "camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
            "shapes": [{{"quad": {{"origin": [-1, 1, -1], "u": [2, 0, 0], "v": [0, 0, 2]}},
                "reflectance": 0, "emission": {L_E}, "two_sided": false}}],
            "medium": {{"sigma_a": 0, "sigma_s": {SIGMA_S}, "g": 0}} }}"#
    ))
}

fn probe(scene: &Scene, x: DVec3, omega_o: DVec3, ps: &ProbeSettings, seed: u64) -> LightField {
    capture(scene, x, Outgoing::Direction(omega_o), ps, seed, 0, &Progress::new()).expect("not cancelled")
}

/// An anisotropic medium (g = 0.5) around the lone quad: the aware value and gradient
/// (phase derivatives included) against central differences of the path tracer.
#[test]
fn anisotropic_single_scattering_against_finite_differences() {
    let s = scene(&format!(
        r#"{{ "camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
            "shapes": [{{"quad": {{"origin": [-1, 1, -1], "u": [2, 0, 0], "v": [0, 0, 2]}},
                "reflectance": 0, "emission": {L_E}, "two_sided": false}}],
            "medium": {{"sigma_a": 0, "sigma_s": {SIGMA_S}, "g": 0.5}} }}"#
    ));
    let omega_o = DVec3::new(0.3, -0.5, 0.8).normalize();
    let ps = ProbeSettings {
        rays: 16384,
        steps: 4,
        ..ProbeSettings::default_for::<D3>()
    };
    for x in [DVec3::new(0.2, 0.0, 0.1), DVec3::new(1.3, -0.2, 0.5)] {
        let lf = probe(&s, x, omega_o, &ps, 1);
        let ours = aware(&lf, &build(&lf, RadianceRule::Farther), &AwareSettings::default())
            .total()
            .luminance();
        let fd = reference_gradient(&s, x, omega_o, 0.01, 100_000, &Settings::default(), 5).luminance();
        let ev = (ours.value - fd.value).abs() / fd.value;
        let eg = (ours.grad - fd.grad).length() / fd.grad.length();
        eprintln!(
            "g = 0.5, x = {x}: aware {:.4e} ∇ {:.6}, FD {:.4e} ∇ {:.6} (value err {:.1}%, ∇ err {:.1}%)",
            ours.value,
            ours.grad,
            fd.value,
            fd.grad,
            100.0 * ev,
            100.0 * eg
        );
        assert!(ev < 0.10 && eg < 0.10, "value err {ev}, gradient err {eg}");
    }
}

/// L_s towards a camera close by (g = 0.5): ω_o turns as x moves, and the aware
/// derivatives with `Outgoing::TowardsPoint` follow the path tracer's central
/// differences of what the camera sees, where the same light field differentiated
/// with ω_o held fixed does not.
#[test]
fn towards_a_camera_the_turning_of_omega_o_is_differentiated() {
    let s = scene(&format!(
        r#"{{ "camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
            "shapes": [{{"quad": {{"origin": [-1, 1, -1], "u": [2, 0, 0], "v": [0, 0, 2]}},
                "reflectance": 0, "emission": {L_E}, "two_sided": false}}],
            "medium": {{"sigma_a": 0, "sigma_s": {SIGMA_S}, "g": 0.5}} }}"#
    ));
    let ps = ProbeSettings {
        rays: 16384,
        steps: 4,
        ..ProbeSettings::default_for::<D3>()
    };
    for (x, eye) in [
        (DVec3::new(0.2, 0.0, 0.1), DVec3::new(0.2, -0.9, 0.5)),
        (DVec3::new(0.9, -0.3, 0.4), DVec3::new(0.3, -1.0, 0.0)),
    ] {
        let lf = capture(&s, x, Outgoing::TowardsPoint(eye), &ps, 1, 0, &Progress::new()).unwrap();
        let elements = build(&lf, RadianceRule::Farther);
        let turning = aware(&lf, &elements, &AwareSettings::default()).total().luminance();
        let mut fixed_lf = lf.clone();
        fixed_lf.eye = None;
        let fixed = aware(&fixed_lf, &elements, &AwareSettings::default())
            .total()
            .luminance();
        let jarosz = unaware(&lf).total().luminance();
        let fd = reference_gradient_towards(
            &s,
            x,
            Outgoing::TowardsPoint(eye),
            0.01,
            100_000,
            &Settings::default(),
            5,
        )
        .luminance();
        let err = |g: DVec3| (g - fd.grad).length() / fd.grad.length();
        eprintln!(
            "camera at {eye}, x = {x}: L_s {:.4e} (FD {:.4e}); ∇ err: towards the camera {:.1}%, ω_o fixed {:.1}%, \
             unaware {:.1}%",
            turning.value,
            fd.value,
            100.0 * err(turning.grad),
            100.0 * err(fixed.grad),
            100.0 * err(jarosz.grad)
        );
        assert!((turning.value - fixed.value).abs() <= 1e-12 * fixed.value);
        assert!(
            err(turning.grad) < 0.1,
            "gradient towards the camera off by {}",
            err(turning.grad)
        );
        assert!(err(fixed.grad) > 2.0 * err(turning.grad));
    }
}

#[test]
fn finite_at_extremes() {
    let s = lone_quad();
    let ps = ProbeSettings {
        rays: 1024,
        steps: 3,
        ..ProbeSettings::default_for::<D3>()
    };
    for x in [
        DVec3::new(0.0, 1.0 - 1e-9, 0.0), // just below the emitter
        DVec3::new(1.0, 1.0 - 1e-7, 1.0), // under its corner
        DVec3::new(1.0, 1.0, 0.0),        // in its plane, on its edge
        DVec3::new(3.0, 1.0, 0.0),        // in its plane, beside it
        DVec3::new(1e3, -1e3, 2e3),       // far away
        DVec3::new(0.0, 1.0 + 1e-6, 0.0), // behind it (dark side)
    ] {
        let lf = probe(&s, x, DVec3::new(0.3, -0.4, 0.5).normalize(), &ps, 3);
        for rule in [RadianceRule::Farther, RadianceRule::Average] {
            let p = aware(&lf, &build(&lf, rule), &AwareSettings::default());
            assert!(p.is_finite(), "x = {x}: {p:?}");
        }
        assert!(unaware(&lf).is_finite(), "x = {x}");
    }
}

/// Fraction of the fog box's area light visible from x (16×16 grid).
fn visible_fraction(s: &Scene, x: DVec3) -> f64 {
    let mut vis = 0;
    for i in 0..16 {
        for j in 0..16 {
            let y = DVec3::new(
                -0.25 + 0.5 * (i as f64 + 0.5) / 16.0,
                1.985,
                -0.25 + 0.5 * (j as f64 + 0.5) / 16.0,
            );
            let d = y - x;
            if !s.occluded(x, d.normalize(), d.length(), None) {
                vis += 1;
            }
        }
    }
    vis as f64 / 256.0
}

#[test]
fn aware_gradient_against_finite_differences_in_fog_box_penumbra() {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes3d/fog_box.json")).unwrap();
    // As shipped (g = 0.3), and isotropic: the proxy keeps each medium sample's
    // L_s(m → x) fixed as x moves, which ignores its dependence on the direction to x
    // when g ≠ 0 (the multiple part's gradient is the less accurate there).
    for (name, text) in [
        ("g = 0.3", text.clone()),
        ("g = 0", text.replace("\"g\": 0.3", "\"g\": 0.0")),
    ] {
        fog_box_penumbra(name, &scene(&text));
    }
}

fn fog_box_penumbra(name: &str, s: &Scene) {
    // Penumbra points of the occluder's volumetric shadow: half the light visible.
    let mut points = Vec::new();
    for y in [0.35, 0.7] {
        let cands: Vec<DVec3> = (0..200)
            .map(|k| DVec3::new(-0.95 + 1.9 * k as f64 / 199.0, y, -0.3))
            .collect();
        let best = cands
            .iter()
            .copied()
            .filter(|&x| {
                let f = visible_fraction(s, x);
                f > 0.3 && f < 0.7
            })
            .min_by(|a, b| {
                (visible_fraction(s, *a) - 0.5)
                    .abs()
                    .total_cmp(&(visible_fraction(s, *b) - 0.5).abs())
            });
        if let Some(x) = best {
            points.push(x);
        }
    }
    assert!(!points.is_empty(), "no penumbra point found");
    let omega_o = DVec3::new(0.0, 0.0, 1.0);
    let ps = ProbeSettings {
        rays: 16384,
        steps: 64,
        ..ProbeSettings::default_for::<D3>()
    };
    let settings = Settings::default();
    for (k, &x) in points.iter().enumerate() {
        let lf = probe(s, x, omega_o, &ps, 11 + k as u64);
        let ours = aware(&lf, &build(&lf, RadianceRule::Farther), &AwareSettings::default());
        let jarosz = unaware(&lf);
        let fd = reference_gradient(s, x, omega_o, 0.02, 40_000, &settings, 5).luminance();
        let (a, u) = (ours.total().luminance(), jarosz.total().luminance());
        let cos = |g: DVec3| g.dot(fd.grad) / (g.length() * fd.grad.length());
        let rel = |g: DVec3| (g - fd.grad).length() / fd.grad.length();
        eprintln!(
            "fog_box ({name}) x = {x:.3} (visible {:.2}): L_s aware {:.4e} (single {:.4e}, multiple {:.4e}), unaware {:.4e}, path-traced {:.4e}\n  \
             ∇ aware {:.4} (cos {:.3}, rel err {:.2}), unaware {:.4} (cos {:.3}, rel err {:.2}), FD {:.4}; probe {} rays, {:.2}s",
            visible_fraction(s, x),
            a.value,
            luminance(ours.single.value()),
            luminance(ours.multiple.value()),
            u.value,
            fd.value,
            a.grad,
            cos(a.grad),
            rel(a.grad),
            u.grad,
            cos(u.grad),
            rel(u.grad),
            fd.grad,
            lf.cost_rays,
            lf.seconds
        );
        assert!(ours.is_finite());
        assert!(
            (a.value - fd.value).abs() < 0.1 * fd.value,
            "value {} vs {}",
            a.value,
            fd.value
        );
        assert!(cos(a.grad) > 0.8, "aware gradient direction off: cos {}", cos(a.grad));
        assert!(rel(a.grad) < 0.7, "aware gradient off: rel err {}", rel(a.grad));
    }
}
