//! The aware single-scattering gradient and Hessian at 3D occlusion boundaries
//! against the exact 3D reference (`study::exact3d`: emitter polygons minus the
//! occluders' central projections, Gauss–Legendre on the pieces, central differences
//! of it), in fog with σ_t ≥ 1 and g ≠ 0 (issue 12 item 2, in 3D).

use glam::{DMat3, DVec3};
use std::path::Path;
use volcache::pipeline::derivatives::{AwareSettings, aware};
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy::build;
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

fn scene(shapes: &str, sigma_t: f64, g: f64) -> Scene {
    let text = format!(
        r#"{{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}},
            "shapes": [{shapes}],
            "medium": {{"sigma_a": 0.1, "sigma_s": {}, "g": {g}}}}}"#,
        sigma_t - 0.1
    );
    Scene::from_json(&text, "occlusion in 3D", Path::new(".")).unwrap()
}

/// A square light above a black square occluder.
fn scene_a(sigma_t: f64, g: f64) -> Scene {
    scene(
        r#"{"quad": {"origin": [-0.5, 1, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]}, "emission": 3, "reflectance": 0},
           {"quad": {"origin": [-0.6, 0.55, -0.1], "u": [0.7, 0, 0], "v": [0, 0, 0.8]}, "reflectance": 0}"#,
        sigma_t,
        g,
    )
}

/// A tilted light beside two tilted black occluders.
fn scene_b(sigma_t: f64, g: f64) -> Scene {
    scene(
        r#"{"quad": {"origin": [-1, -0.4, -0.5], "u": [0.1, 0.9, 0], "v": [0, 0, 1]}, "emission": 3, "reflectance": 0},
           {"quad": {"origin": [-0.6, 0.0, -0.6], "u": [0.1, 0.5, 0.1], "v": [0.05, 0, 0.6]}, "reflectance": 0},
           {"quad": {"origin": [-0.55, -0.5, 0.1], "u": [0.0, 0.3, 0.0], "v": [0.1, 0, 0.5]}, "reflectance": 0}"#,
        sigma_t,
        g,
    )
}

/// The share of the emitting triangles' area seen from `x` (a grid of points).
fn visible_share(scene: &Scene, x: DVec3) -> f64 {
    let (mut seen, mut all) = (0, 0);
    for t in scene
        .geometry
        .prims
        .iter()
        .filter(|t| scene.surfaces[t.shape as usize].emission.x > 0.0)
    {
        let n = 12;
        for i in 0..n {
            for j in 0..n - i {
                let y = t.p0 + t.e1 * ((i as f64 + 0.3) / n as f64) + t.e2 * ((j as f64 + 0.3) / n as f64);
                let d = y - x;
                all += 1;
                if !scene.occluded(x, d.normalize(), d.length() * (1.0 - 1e-9), None) {
                    seen += 1;
                }
            }
        }
    }
    seen as f64 / all as f64
}

/// Points of a jittered grid in the box `lo`–`hi` that see 5–95% of the light.
fn penumbra_points(scene: &Scene, lo: DVec3, hi: DVec3, want: usize) -> Vec<DVec3> {
    let n = 9;
    let mut out = vec![];
    for k in 0..n * n * n {
        let k = k * 31 % (n * n * n); // a stride coprime with the grid spreads them
        let c = DVec3::new((k / (n * n)) as f64, ((k / n) % n) as f64, (k % n) as f64) + 0.5;
        let x = lo + (hi - lo) * c / n as f64;
        let s = visible_share(scene, x);
        if (0.05..0.95).contains(&s) && out.len() < want {
            out.push(x);
        }
    }
    out
}

type SceneFn = fn(f64, f64) -> Scene;

/// Relative gradient and Hessian errors of the aware single part at `x`.
fn errors(scene: &Scene, x: DVec3, omega_o: DVec3, rays: usize, seed: u64) -> (f64, f64) {
    let exact = exact3d::derivatives(scene, x, omega_o, 1e-4).luminance();
    let mut ps = ProbeSettings::with_rays::<volcache::core::space::D3>(rays);
    ps.settings.max_depth = 2;
    let lf = capture(scene, x, Outgoing::Direction(omega_o), &ps, seed, 0, &Progress::new()).unwrap();
    let aw = AwareSettings::default();
    let got = aware(&lf, &build(&lf, aw.rule), &aw).single.luminance();
    (
        (got.grad - exact.grad).length() / exact.grad.length(),
        frobenius(got.hess - exact.hess) / frobenius(exact.hess),
    )
}

/// Measured (10 points per scene, seeds 1–2): gradient median 6.7% / 4.3% at 4096
/// rays, 2.2% / 2.4% at 16384 (p90 5.1% / 9.4%): the proxy's discretisation,
/// falling with the ray count. The Hessian falls much less: median 9.1% / 22%, p90
/// 17% / 59% at 16384 rays (with the far-vertex rule instead of `pipeline::slide`:
/// median 10% / 19%, p90 24% / 61%). The phase and the transmittance are not what
/// holds it: with σ_t = 1e-3 and g = 0 the median is still 16%. Without the occluder
/// the aware Hessian equals the exact one at every ray count; with it, the aware
/// Hessian converges (4096 → 65536 rays) to a limit off in the mixed components
/// (e.g. H_xz −0.00018 against −0.00013). Where the shadow's edge meets the emitter's
/// edge, the visible region has a corner that slides along the emitter's edge as x
/// moves; a second derivative of the region's solid angle has a term at that corner,
/// and proxy vertices fixed in space cannot carry it (2D has no such corners). A
/// split of each direction triangle along both silhouette crossings of its sides
/// was tried and changed nothing measurable. The bounds keep today's accuracy from
/// getting worse; issue 12 asks for p90 < 15%.
#[test]
fn derivatives_at_3d_penumbrae() {
    let omega_o = DVec3::new(0.48, -0.6, 0.64);
    let rows: [(&str, SceneFn, f64, f64, DVec3, DVec3); 2] = [
        (
            "A",
            scene_a,
            1.0,
            0.6,
            DVec3::new(-1.0, -0.6, -1.0),
            DVec3::new(1.0, 0.4, 1.0),
        ),
        (
            "B",
            scene_b,
            2.0,
            -0.5,
            DVec3::new(-0.4, -0.8, -0.6),
            DVec3::new(0.6, 0.6, 0.8),
        ),
    ];
    for (name, make, sigma_t, g, lo, hi) in rows {
        let scene = make(sigma_t, g);
        let points = penumbra_points(&scene, lo, hi, 10);
        assert!(points.len() >= 8, "{name}: only {} penumbra points", points.len());
        for rays in [4096, 16384] {
            let (mut ge, mut he) = (vec![], vec![]);
            for seed in 1..=2 {
                for &x in &points {
                    let (a, b) = errors(&scene, x, omega_o, rays, seed);
                    ge.push(a);
                    he.push(b);
                }
            }
            let (gm, g90) = (percentile(&mut ge.clone(), 0.5), percentile(&mut ge, 0.9));
            let (hm, h90) = (percentile(&mut he.clone(), 0.5), percentile(&mut he, 0.9));
            println!(
                "{name} σ_t {sigma_t} g {g} rays {rays}: n {} ∇ median {gm:.4} p90 {g90:.4} | H median {hm:.4} p90 {h90:.4}",
                points.len()
            );
            if rays == 16384 {
                assert!(gm < 0.05 && g90 < 0.2, "{name}: gradient median {gm} p90 {g90}");
                assert!(hm < 0.35 && h90 < 0.9, "{name}: Hessian median {hm} p90 {h90}");
            }
        }
    }
}
