//! Radiance caching in 2D (theory.md §6–8): the equal-count mode and the paper's
//! claims at equal cache count and equal cost. Hole-free, thread-independent
//! placement is checked in both dimensions in `dims_caching.rs`.

use glam::DVec2;
use volcache::flatland::cached_field::{CacheMethod, CacheSettings, CachedField, RecordMemo, render_cached};
use volcache::flatland::field::{Field, FieldParams, field_errors, render_field};
use volcache::flatland::scene::Scene;
use volcache::pipeline::placement::CountError;
use volcache::progress::Progress;

fn load(path: &str) -> Scene {
    Scene::load(std::path::Path::new(path)).unwrap()
}

fn params(scene: &Scene, w: usize, h: usize) -> FieldParams {
    let mut fp = FieldParams::from_scene(scene);
    (fp.width, fp.height) = (w, h);
    fp
}

fn settings(method: CacheMethod, seed: u64) -> CacheSettings {
    let mut cs = CacheSettings::new::<volcache::core::space::D2>(method, 0.05, Default::default());
    cs.probe.rays = 512;
    cs.probe.steps = 8;
    cs.seed = seed;
    cs
}

fn reference(scene: &Scene, fp: &FieldParams, spp: u32) -> Field {
    render_field(
        scene,
        &FieldParams {
            spp,
            seed: 999,
            ..fp.clone()
        },
        &Progress::new(),
    )
    .unwrap()
    .field
}

/// A field of `k` records. Counts jump with ε (`CountError::Unreachable`), and the
/// error's advice is another record seed: so does this, up to three times (at 8
/// graded steps Jarosz 2008 jumped from 75 to 99 records on the occluder for one
/// seed of three).
fn at_count(scene: &Scene, fp: &FieldParams, method: CacheMethod, seed: u64, k: usize) -> CachedField {
    let mut last = None;
    for retry in 0..3 {
        match render_cached(
            scene,
            fp,
            &settings(method, seed + 1000 * retry),
            Some(k),
            &mut RecordMemo::new(),
            &Progress::new(),
        ) {
            Ok(f) => return f,
            Err(e @ CountError::Unreachable { .. }) => last = Some(e),
            Err(e) => panic!("{e}"),
        }
    }
    panic!("{method:?} seed {seed}: {}", last.unwrap())
}

#[test]
fn equal_count_mode_hits_the_target() {
    let scene = load("flatland_scenes/occluder.json");
    let fp = params(&scene, 40, 40);
    for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        let f = at_count(&scene, &fp, method, 1, 60);
        assert!(
            (f.record_count() as f64 - 60.0).abs() <= 1.0,
            "{method:?}: {} records",
            f.record_count()
        );
    }
}

/// A count no ε reaches is an error naming the nearest count, not a field with far
/// fewer records: around a point light in fog with no surfaces, Jarosz 2008's
/// gradients are near zero, its circles reach the maximum radius, and the count
/// stays small whatever ε (it returned 9 records for 100 without a word).
#[test]
fn an_unreachable_count_is_an_error() {
    let scene = load("flatland_scenes/point_in_fog.json");
    let mut fp = params(&scene, 32, 32);
    fp.quantity = volcache::flatland::scene_desc::Quantity::Ls;
    let cs = settings(CacheMethod::Jarosz08, 1);
    let r = render_cached(&scene, &fp, &cs, Some(100), &mut RecordMemo::new(), &Progress::new());
    match r {
        Err(CountError::Unreachable { target, best, eps }) => {
            assert_eq!(target, 100);
            assert!(best < 95 && eps.is_finite(), "{best} records at ε {eps}");
        }
        Err(e) => panic!("{e}"),
        Ok(f) => panic!("{} records for a target of 100", f.record_count()),
    }
}

/// Distance from p to the line through a and b.
fn line_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = (b - a).normalize();
    (p - a).perp_dot(d).abs()
}

/// At equal cache count, ours has a lower RMSE than Jarosz et al. 2008 on both
/// scenes for every seed (measured ratios ~0.27 on the occluder and ~0.67 on the
/// windows, seed-to-seed spread ~0.05; bounds 0.5 and 0.85), and on the occluder it puts
/// more records along the penumbra wedges (the lines through the emitter's and
/// the occluder's ends).
#[test]
fn ours_beats_jarosz08_at_equal_count() {
    for (path, (w, h), k) in [
        ("flatland_scenes/occluder.json", (48, 48), 90),
        ("flatland_scenes/windows.json", (110, 72), 150),
    ] {
        let scene = load(path);
        let fp = params(&scene, w, h);
        let reference = reference(&scene, &fp, 2048);
        let mut ratios = Vec::new();
        for seed in 1..=3 {
            let ours = at_count(&scene, &fp, CacheMethod::Ours, seed, k);
            let theirs = at_count(&scene, &fp, CacheMethod::Jarosz08, seed, k);
            let (eo, et) = (
                field_errors(&ours.field, &reference),
                field_errors(&theirs.field, &reference),
            );
            println!(
                "{path} seed {seed}: ours {} records RMSE {:.4e}; jarosz08 {} records RMSE {:.4e}",
                ours.record_count(),
                eo.rmse,
                theirs.record_count(),
                et.rmse
            );
            ratios.push(eo.rmse / et.rmse);
            if path.contains("occluder") {
                let edges = [(-0.3, -0.35), (-0.3, 0.35), (0.3, -0.35), (0.3, 0.35)];
                let band = |f: &CachedField| {
                    let recs = &f.records[0];
                    let near = recs
                        .iter()
                        .filter(|r| {
                            r.position.y < 0.25
                                && edges.iter().any(|&(e, o)| {
                                    line_distance(r.position, DVec2::new(e, 0.75), DVec2::new(o, 0.25)) < 0.1
                                })
                        })
                        .count();
                    near as f64 / recs.len() as f64
                };
                let (bo, bt) = (band(&ours), band(&theirs));
                println!(
                    "  records within 0.1 of a penumbra edge: ours {:.1}%, jarosz08 {:.1}%",
                    100.0 * bo,
                    100.0 * bt
                );
                assert!(bo > 1.2 * bt, "ours {bo} vs jarosz08 {bt}");
            }
        }
        let worst = ratios.iter().cloned().fold(0.0, f64::max);
        let bound = if path.contains("occluder") { 0.5 } else { 0.85 };
        assert!(worst < bound, "{path}: RMSE ratio ours/jarosz08 up to {worst}");
    }
}

/// Both caches beat path tracing at equal cost on windows.json (cost measured in
/// rays traced, which unlike seconds is deterministic).
#[test]
fn caches_beat_path_tracing_at_equal_rays() {
    let scene = load("flatland_scenes/windows.json");
    let fp = params(&scene, 110, 72);
    let reference = reference(&scene, &fp, 2048);
    for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        let c = at_count(&scene, &fp, method, 1, 120);
        let rays = c.placement_rays + c.reconstruction_rays;
        // Path tracing spp with at least the cache's rays.
        let probe = render_field(&scene, &FieldParams { spp: 1, ..fp.clone() }, &Progress::new()).unwrap();
        let spp = ((rays as f64 / probe.rays as f64).ceil() as u32).max(1);
        let pt = render_field(
            &scene,
            &FieldParams {
                spp,
                seed: 5,
                ..fp.clone()
            },
            &Progress::new(),
        )
        .unwrap();
        let (ec, ep) = (field_errors(&c.field, &reference), field_errors(&pt.field, &reference));
        println!(
            "{method:?}: {rays} rays RMSE {:.4e}; pt {spp} spp {} rays RMSE {:.4e}",
            ec.rmse, pt.rays, ep.rmse
        );
        assert!(pt.rays >= rays);
        assert!(ec.rmse < ep.rmse, "{method:?}: cache {} vs pt {}", ec.rmse, ep.rmse);
    }
}

/// A point light shaded by a short wall in thick forward-scattering fog, a scene of
/// our own like the one issue 16 measured: records extrapolating across the peak
/// around the light went negative and were clamped to black pixels. A record
/// whose expansion is negative at a pixel now contributes its lower-order
/// estimate there, so no pixel with light around it comes out black.
#[test]
fn negative_extrapolations_leave_no_black_pixels() {
    let scene = Scene::from_json(
        r#"{ "domain": { "min": [-2, -2], "max": [2, 2] },
             "segments": [ { "a": [-0.5, -0.3], "b": [0.5, -0.3], "reflectance": 0.3 } ],
             "lights": [ { "type": "point", "position": [0, 0], "intensity": 1 } ],
             "medium": { "sigma_a": 0.2, "sigma_s": 2, "g": 0.8, "region": "everywhere" },
             "render": { "omega_o_deg": 90 } }"#,
        "<shade>",
    )
    .unwrap();
    let fp = params(&scene, 64, 64);
    let reference = reference(&scene, &fp, 256);
    let mut worst = (0, 0.0f64);
    for (method, seed) in [
        (CacheMethod::Ours, 1),
        (CacheMethod::Ours, 2),
        (CacheMethod::Jarosz08, 1),
    ] {
        let mut cs = settings(method, seed);
        cs.eps = if method == CacheMethod::Ours { 1.0 } else { 0.1 };
        let c = render_cached(&scene, &fp, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap();
        let black = (c.field.values.iter().zip(&reference.values))
            .filter(|(v, r)| v.max_element() <= 0.0 && r.min_element() > 0.0)
            .count();
        let e = field_errors(&c.field, &reference);
        eprintln!(
            "{method:?} seed {seed}: {} records, {black} black pixels, RMSE {:.4e} (mean {:.4e})",
            c.record_count(),
            e.rmse,
            e.mean_reference
        );
        worst = (worst.0.max(black), worst.1.max(e.rmse / e.mean_reference));
    }
    assert_eq!(worst.0, 0, "black pixels");
}
