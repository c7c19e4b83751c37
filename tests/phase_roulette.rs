//! Probe rays' recursive estimates rouletted by the phase towards ω_o
//! (`ProbeSettings::phase_roulette`): unbiased, cheaper in anisotropic fog, and no
//! change at all in isotropic fog. Scenes of our own, 2D and 3D, forward and
//! backward scattering.

use glam::{DVec2, DVec3};
use volcache::core::metric::CacheMethod;
use volcache::core::space::{D2, D3};
use volcache::pipeline::probe::Outgoing;
use volcache::pipeline::record::{CacheSettings, Cached, compute_record};
use volcache::pipeline::world::{VecOf, World};
use volcache::progress::Progress;

/// A point light and an emitting segment beside a plate, over a floor.
fn scene2d(g: f64) -> volcache::flatland::scene::Scene {
    let json = format!(
        r#"{{
  "domain": {{"min": [-1, -1], "max": [1, 1]}},
  "segments": [
    {{"name": "floor", "a": [-1, -0.9], "b": [1, -0.9], "reflectance": 0.5}},
    {{"name": "plate", "a": [-0.3, 0.2], "b": [0.3, 0.35], "reflectance": 0.6}},
    {{"name": "lamp", "a": [-0.9, 0.8], "b": [-0.5, 0.9], "emission": 4.0}}
  ],
  "lights": [{{"type": "point", "position": [0.5, 0.5], "intensity": 1.0}}],
  "medium": {{"sigma_a": 0.2, "sigma_s": 1.6, "g": {g}, "region": "everywhere"}},
  "render": {{"resolution": [32, 32], "spp": 4, "seed": 1}}
}}"#
    );
    volcache::flatland::scene::Scene::from_json(&json, "<phase_roulette>").unwrap_or_else(|e| panic!("{e}"))
}

/// A fog box over a floor, lit by a quad lamp beside a box.
fn scene3d(g: f64) -> volcache::volume::scene::Scene {
    let json = format!(
        r#"{{
  "camera": {{"position": [0, 1.2, 3.5], "look_at": [0, 0.7, 0], "fov_deg": 45}},
  "shapes": [
    {{"quad": {{"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}}, "name": "floor", "reflectance": 0.5}},
    {{"box": {{"min": [-0.2, 0, -0.2], "max": [0.3, 0.8, 0.3]}}, "name": "box", "reflectance": 0.6}},
    {{"quad": {{"origin": [-1.0, 1.5, -0.8], "u": [0.5, 0, 0], "v": [0, -0.2, 0.5]}}, "name": "lamp",
      "reflectance": 0, "emission": [20, 18, 14], "two_sided": true}}
  ],
  "medium": {{"sigma_a": 0.1, "sigma_s": 0.9, "g": {g}, "region": {{"box": {{"min": [-1.5, 0, -1.5], "max": [1.5, 1.8, 1.5]}}}}}},
  "render": {{"resolution": [16, 12], "spp": 4, "seed": 3, "max_depth": 16}}
}}"#
    );
    volcache::volume::scene::Scene::from_json(&json, "<phase_roulette 3d>", std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn settings<S: volcache::pipeline::dim::Dim>(rays: usize, steps: usize, seed: u64, c: f64) -> CacheSettings {
    let mut cs = CacheSettings::new::<S>(CacheMethod::Ours, 0.05, Default::default());
    cs.probe.rays = rays;
    cs.probe.steps = steps;
    cs.probe.phase_roulette = c;
    cs.seed = seed;
    cs
}

/// Per seed (`n` seeds), a record's cached luminance, and the rays of all.
fn values<W: World>(
    world: &W,
    x: VecOf<W>,
    out: Outgoing<VecOf<W>>,
    (rays, steps, c): (usize, usize, f64),
    n: u64,
) -> (Vec<f64>, u64) {
    let p = Progress::new();
    let (mut v, mut cost) = (Vec::new(), 0);
    for seed in 0..n {
        let cs = settings::<W::S>(rays, steps, 500 + seed, c);
        let r = compute_record(world, x, out, &cs, 7, &p).unwrap();
        let l = r.payload(Cached::Scattered).luminance().value;
        assert!(l.is_finite());
        v.push(l);
        cost += r.rays;
    }
    (v, cost)
}

/// The rouletted and the full records, seed by seed (the same directions and
/// hits), differ by less than 4 standard errors of their mean difference and 3%
/// of the value (measured: see the printout); the rouletted ones cost at most
/// `max_cost` × the rays.
fn check<W: World>(
    world: &W,
    points: &[VecOf<W>],
    out: impl Fn(VecOf<W>) -> Outgoing<VecOf<W>>,
    probe: (usize, usize),
    max_cost: f64,
) where
    VecOf<W>: std::fmt::Debug,
{
    for &x in points {
        let n = 64;
        let (v1, c1) = values(world, x, out(x), (probe.0, probe.1, 1.0), n);
        let (v0, c0) = values(world, x, out(x), (probe.0, probe.1, 0.0), n);
        let d: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
        let mean_d = d.iter().sum::<f64>() / n as f64;
        let var_d = d.iter().map(|e| (e - mean_d).powi(2)).sum::<f64>() / (n - 1) as f64;
        let se = (var_d / n as f64).sqrt();
        let m0 = v0.iter().sum::<f64>() / n as f64;
        let cost = c1 as f64 / c0 as f64;
        println!(
            "{x:?}: full {m0:.5e}, rouletted − full {mean_d:+.3e} ± {se:.1e} ({:+.2} s.e., {:+.2}%), rays {cost:.2}×",
            mean_d / se,
            100.0 * mean_d / m0
        );
        assert!(mean_d.abs() < 4.0 * se, "{x:?}: difference {mean_d} (s.e. {se})");
        assert!(mean_d.abs() < 0.03 * m0, "{x:?}: difference {mean_d} of {m0}");
        assert!(cost < max_cost, "{x:?}: the rouletted records cost {cost:.2}× the rays");
    }
}

#[test]
fn unbiased_and_cheaper_in_2d_forward_and_backward() {
    let points = [DVec2::new(0.1, 0.0), DVec2::new(-0.6, 0.4), DVec2::new(0.6, -0.5)];
    for g in [0.8, -0.8] {
        let s = scene2d(g);
        let w = DVec2::new(0.6, -0.8);
        check(&s, &points, |_| Outgoing::Direction(w), (256, 8), 0.8);
    }
}

#[test]
fn unbiased_and_cheaper_in_3d() {
    let s = scene3d(0.8);
    let eye = s.camera.position;
    let points = [DVec3::new(0.2, 1.0, 0.6), DVec3::new(-0.8, 0.4, 0.2)];
    check(&s, &points, |_| Outgoing::TowardsPoint(eye), (256, 16), 0.8);
}

/// With an isotropic phase no ray is rouletted: the same records bit for bit.
#[test]
fn isotropic_fog_is_untouched() {
    let s = scene2d(0.0);
    let p = Progress::new();
    let x = DVec2::new(0.1, 0.0);
    let out = Outgoing::Direction(DVec2::new(0.6, -0.8));
    let a = compute_record(&s, x, out, &settings::<D2>(128, 8, 3, 1.0), 1, &p).unwrap();
    let b = compute_record(&s, x, out, &settings::<D2>(128, 8, 3, 0.0), 1, &p).unwrap();
    assert_eq!(a.parts, b.parts);
    assert_eq!(a.rays, b.rays);
    let s3 = scene3d(0.0);
    let x3 = DVec3::new(0.2, 1.0, 0.6);
    let out3 = Outgoing::TowardsPoint(s3.camera.position);
    let a = compute_record(&s3, x3, out3, &settings::<D3>(64, 4, 3, 1.0), 1, &p).unwrap();
    let b = compute_record(&s3, x3, out3, &settings::<D3>(64, 4, 3, 0.0), 1, &p).unwrap();
    assert_eq!(a.parts, b.parts);
}
