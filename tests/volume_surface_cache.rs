//! The surface cache of a 3D render (issue 16 item 3, `volume::surface_cache`): on
//! a room of its own (coloured walls, a box under a ceiling lamp, fog), the first
//! surfaces' reflected light from indirect-irradiance records plus per-pixel direct
//! light against the path tracer's, and the placement's independence of the thread
//! count.

use std::path::Path;
use volcache::core::color::{Rgb, luminance};
use volcache::core::metric::CacheMethod;
use volcache::core::stats::ImageErrors;
use volcache::progress::Progress;
use volcache::volume::cached::{
    CacheSettings, CachedRender, CachedRenderParams, RecordMemo, default_eps, march_reference, render_cached,
};
use volcache::volume::render::{RenderParams, Rendered};
use volcache::volume::scene::Scene;
use volcache::volume::surface_cache::default_surface_eps;

fn room() -> Scene {
    let json = r#"{
      "camera": {"position": [0, 1.2, 4.2], "look_at": [0, 0.8, 0], "fov_deg": 50},
      "shapes": [
        {"quad": {"origin": [-1.5, 0, -1.5], "u": [0, 0, 3], "v": [3, 0, 0]}, "reflectance": 0.7},
        {"quad": {"origin": [-1.5, 0, -1.5], "u": [3, 0, 0], "v": [0, 2.5, 0]}, "reflectance": 0.6},
        {"quad": {"origin": [-1.5, 0, -1.5], "u": [0, 2.5, 0], "v": [0, 0, 3]}, "reflectance": [0.7, 0.2, 0.15]},
        {"quad": {"origin": [1.5, 0, -1.5], "u": [0, 0, 3], "v": [0, 2.5, 0]}, "reflectance": [0.15, 0.6, 0.2]},
        {"quad": {"origin": [-1.5, 2.5, -1.5], "u": [3, 0, 0], "v": [0, 0, 3]}, "reflectance": 0.5},
        {"box": {"min": [-0.5, 0, -0.6], "max": [0.3, 0.9, 0.2]}, "reflectance": 0.6},
        {"quad": {"origin": [-0.4, 2.49, -0.4], "u": [0.8, 0, 0], "v": [0, 0, 0.8]}, "emission": 8, "reflectance": 0}
      ],
      "medium": {"sigma_a": 0.02, "sigma_s": 0.15, "g": 0.3,
                 "region": {"box": {"min": [-1.5, 0, -1.5], "max": [1.5, 2.5, 1.5]}}},
      "render": {"resolution": [32, 24], "spp": 4, "seed": 1, "max_depth": 16}
    }"#;
    Scene::from_json(json, "<surface cache room>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

fn params(scene: &Scene, surface_eps: Option<f64>) -> CachedRenderParams {
    let mut p = CachedRenderParams::from_scene(scene);
    (p.image.width, p.image.height, p.image.spp, p.image.seed) = (32, 24, 4, 7);
    p.march_step = scene.scale / 32.0;
    p.surface_eps = surface_eps;
    p
}

fn settings(scene: &Scene, seed: u64) -> CacheSettings {
    let mut cs = CacheSettings::new::<volcache::core::space::D3>(
        CacheMethod::Ours,
        default_eps(CacheMethod::Ours, scene),
        RenderParams::from_scene(scene).first_vertex_settings(),
    );
    cs.probe.rays = 1024;
    cs.probe.steps = 12;
    cs.seed = seed;
    cs
}

fn cached(scene: &Scene, p: &CachedRenderParams, seed: u64) -> CachedRender {
    render_cached(
        scene,
        p,
        &settings(scene, seed),
        None,
        &mut RecordMemo::new(),
        &Progress::new(),
    )
    .unwrap()
}

/// T·L_o of the first surfaces: the image less its medium part.
fn surface_part(image: &Rendered) -> Vec<Rgb> {
    image.values.iter().zip(&image.medium).map(|(v, m)| *v - *m).collect()
}

/// The surfaces' light at the camera samples of [`params`], 512 reflected-light
/// paths per surface and 16 per march point.
fn surface_reference(s: &Scene) -> Vec<Rgb> {
    let mut pr = params(s, None);
    pr.surface_paths = 512;
    surface_part(&march_reference(s, &pr, 16, 99, &Progress::new()).unwrap().image)
}

fn errors(a: &[Rgb], b: &[Rgb]) -> ImageErrors {
    let pairs: Vec<(f64, f64)> = a.iter().zip(b).map(|(x, y)| (luminance(*x), luminance(*y))).collect();
    ImageErrors::of_luminance_pairs(&pairs)
}

/// With the surface cache, the image's error falls well below the path-traced
/// surfaces' at the same camera samples, for several record seeds. The reference
/// shares the camera samples (`march_reference` with 512 reflected-light paths per
/// surface and 16 per march point), so that pixel integration, common to both, does
/// not hide the surfaces' estimators; the medium part is the same cache in both.
/// Measured (seeds 1–2): the surfaces' RMSE 0.0260 path traced (4 paths per camera
/// sample), 0.0099 with 42–43 surface records (0.38×); the mean surface light
/// +0.6% / +0.7% of the reference's. (Before the records' extents followed ε in
/// the tangent plane: 0.0114–0.0117 with 45 records, +0.3% / +0.8%.)
#[test]
fn the_surface_cache_takes_the_surfaces_noise_out() {
    let s = room();
    let reference = surface_reference(&s);
    for seed in 1..=2 {
        let plain = cached(&s, &params(&s, None), seed);
        let with = cached(&s, &params(&s, Some(default_surface_eps(&s))), seed);
        let sc = with.surfaces.as_ref().expect("a surface cache was asked for");
        let (e0, e1) = (
            errors(&surface_part(&plain.reconstruction.image), &reference).rmse,
            errors(&surface_part(&with.reconstruction.image), &reference).rmse,
        );
        println!(
            "seed {seed}: surfaces' RMSE {e0:.4} path traced, {e1:.4} with {} surface records ({:.1} s, {} medium records)",
            sc.record_count(),
            sc.seconds,
            with.placement.record_count()
        );
        let mean = |v: &[Rgb]| v.iter().map(|c| luminance(*c)).sum::<f64>() / v.len() as f64;
        let bias = mean(&surface_part(&with.reconstruction.image)) / mean(&reference) - 1.0;
        println!("seed {seed}: mean surface light {bias:+.4} of the reference's");
        assert!(
            bias.abs() < 0.03,
            "seed {seed}: the surface cache's mean is {bias:+} off"
        );
        assert!(sc.record_count() > 0);
        assert_eq!(plain.placement.record_count(), with.placement.record_count());
        assert!(e1 < 0.6 * e0, "seed {seed}: {e1} with the surface cache, {e0} without");
    }
}

/// The surface cache and the image do not depend on the thread count.
#[test]
fn the_surface_cache_is_the_same_on_any_thread_count() {
    let s = room();
    let p = params(&s, Some(default_surface_eps(&s)));
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| cached(&s, &p, 3))
    };
    let (a, b) = (run(1), run(2));
    let (sa, sb) = (a.surfaces.unwrap(), b.surfaces.unwrap());
    assert_eq!(sa.record_count(), sb.record_count());
    for (x, y) in sa.cache.records().iter().zip(sb.cache.records()) {
        assert_eq!((x.position, x.value), (y.position, y.value));
    }
    assert_eq!(a.reconstruction.image.values, b.reconstruction.image.values);
}

/// A smaller ε gives more surface records: their extents follow ε in the tangent
/// plane (`pipeline::surface_record::close_normal`; with the normal axis open
/// they were held at r_max / 4, and on the staircase the count stopped growing
/// below ε ≈ the default / 16). Measured (seeds 1–2): 42 / 103 / 242 records
/// at ε, ε/16, ε/256, surfaces' RMSE 0.0099 / 0.0096 / 0.0097. Same reference
/// as above.
#[test]
fn surface_records_follow_eps() {
    let s = room();
    let reference = surface_reference(&s);
    let e0 = default_surface_eps(&s);
    for seed in 1..=2 {
        let runs: Vec<(usize, f64)> = [1.0, 1.0 / 16.0, 1.0 / 256.0]
            .iter()
            .map(|f| {
                let with = cached(&s, &params(&s, Some(e0 * f)), seed);
                let n = with.surfaces.as_ref().unwrap().record_count();
                (n, errors(&surface_part(&with.reconstruction.image), &reference).rmse)
            })
            .collect();
        println!("seed {seed}: (surface records, surfaces' RMSE) at ε, ε/16, ε/256: {runs:?}");
        // K ∝ ε^−2/5 on surfaces: ×3 per 16× (measured ×2.3–2.5).
        for w in runs.windows(2) {
            assert!(w[1].0 as f64 > 1.8 * w[0].0 as f64, "seed {seed}: records {runs:?}");
        }
        // Here the records' noise (512 directions) is most of the error: it only
        // must not rise as the records shrink (measured 0.97–0.98×).
        assert!(runs[2].1 < 1.02 * runs[0].1, "seed {seed}: {runs:?}");
    }
}
