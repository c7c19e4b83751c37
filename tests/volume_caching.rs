//! 3D radiance caching (issue 6 §4): ours against Jarosz et al. 2008 at equal cache
//! count, agreement with the path tracer, records files and extreme parameters.
//! Hole-free, thread-independent placement is checked in both dimensions in
//! `dims_caching.rs`.

mod room3d;

use room3d::ROOM;
use std::path::Path;
use volcache::core::color::{Rgb, luminance};
use volcache::core::metric::CacheMethod;
use volcache::core::stats::ImageErrors;
use volcache::pipeline::placement::CountError;
use volcache::progress::Progress;
use volcache::volume::cached::{
    CacheSettings, CacheView, CachedRenderParams, RecordMemo, default_eps, march_reference, place, place_surfaces,
    reconstruct, render_cached,
};
use volcache::volume::records_file::{RecordsFile, ValidFor};
use volcache::volume::render::{RenderParams, render};
use volcache::volume::scene::Scene;
use volcache::volume::surface_cache::default_surface_eps;

fn load(name: &str) -> Scene {
    Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes3d").join(name)).unwrap()
}

fn scene(json: &str) -> Scene {
    Scene::from_json(json, "<test>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// A small image of `scene`: `w`×`h`, `spp` camera samples, march step scale/`k`.
fn params(scene: &Scene, w: usize, h: usize, spp: u32, k: f64) -> CachedRenderParams {
    let mut p = CachedRenderParams::from_scene(scene);
    (p.image.width, p.image.height, p.image.spp, p.image.seed) = (w, h, spp, 7);
    p.march_step = scene.scale / k;
    p.surface_paths = 1;
    p
}

fn settings(method: CacheMethod, scene: &Scene, rays: usize, steps: usize, seed: u64) -> CacheSettings {
    let mut cs = CacheSettings::new::<volcache::core::space::D3>(
        method,
        default_eps(method, scene),
        RenderParams::from_scene(scene).first_vertex_settings(),
    );
    cs.probe.rays = rays;
    cs.probe.steps = steps;
    cs.seed = seed;
    cs
}

fn errors(a: &[Rgb], b: &[Rgb]) -> ImageErrors {
    let pairs: Vec<(f64, f64)> = a.iter().zip(b).map(|(x, y)| (luminance(*x), luminance(*y))).collect();
    ImageErrors::of_luminance_pairs(&pairs)
}

/// The paper's comparison, scaled down: on the staircase room at equal cache count,
/// our records (occlusion-aware Hessian ellipsoids) reconstruct the in-scattered
/// light along camera rays better than Jarosz et al. 2008's (unaware gradient
/// balls), for several record seeds. Both are measured against the same camera
/// samples with L_s path traced at every march point (the march reference), so the
/// errors are the caches' own.
#[test]
fn ours_beats_jarosz08_at_equal_cache_count_on_the_staircase() {
    let s = load("staircase.json");
    let p = params(&s, 32, 24, 1, 64.0);
    // Two references with independent path samples: their mean is the reference, and
    // their difference measures its noise, which is taken out of the squared errors
    // (E|c − r|² = |c − L|² + σ_r²: the caches' own errors, not the reference's).
    let r1 = march_reference(&s, &p, 16, 1, &Progress::new()).unwrap().image.medium;
    let r2 = march_reference(&s, &p, 16, 2, &Progress::new()).unwrap().image.medium;
    let reference: Vec<Rgb> = r1.iter().zip(&r2).map(|(a, b)| (*a + *b) * 0.5).collect();
    let noise2 = errors(&r1, &r2).rmse.powi(2) / 4.0;
    eprintln!(
        "march reference: 2 × 16 paths per point, RMS noise {:.4e}",
        noise2.sqrt()
    );
    let mut sums = [0.0; 2];
    let mut ratios = Vec::new();
    // A count can be out of reach for a record seed: placement counts jump with ε
    // (seed 4 of Jarosz 2008 goes from 88 to 35 records within 1.2% of ε, nothing
    // between), and the search then reports an error. Such a seed is reported and
    // the next one compared instead.
    let mut unreachable = Vec::new();
    for seed in 1..=6 {
        if ratios.len() == 4 {
            break;
        }
        let mut rmse = [0.0; 2];
        for (k, method) in [CacheMethod::Ours, CacheMethod::Jarosz08].into_iter().enumerate() {
            let cs = settings(method, &s, 512, 12, seed);
            let r = match render_cached(&s, &p, &cs, Some(60), &mut RecordMemo::new(), &Progress::new()) {
                Ok(r) => r,
                Err(e @ CountError::Unreachable { .. }) => {
                    eprintln!("seed {seed} {method:?}: {e}");
                    unreachable.push((seed, method));
                    break;
                }
                Err(e) => panic!("{e}"),
            };
            let e = errors(&r.reconstruction.image.medium, &reference);
            let own = (e.rmse.powi(2) - noise2).max(0.0).sqrt();
            eprintln!(
                "seed {seed} {method:?}: {} records (ε {:.3e}), {} query points, medium RMSE {:.4e} \
                 (without the reference's noise {own:.4e}; mean {:.4e}), placement {:.2} s, {} rays",
                r.placement.record_count(),
                r.placement.eps,
                r.placement.query_points,
                e.rmse,
                e.mean_reference,
                r.placement.seconds,
                r.rays()
            );
            assert_eq!(r.reconstruction.uncovered, 0);
            // Within the equal-count search's acceptance (5%).
            assert!((r.placement.record_count() as f64 - 60.0).abs() <= 3.0);
            rmse[k] = own;
            assert!(e.rmse.powi(2) > 1.5 * noise2, "the reference is too noisy to judge");
        }
        if unreachable.last().is_none_or(|u| u.0 != seed) {
            sums[0] += rmse[0];
            sums[1] += rmse[1];
            ratios.push(rmse[0] / rmse[1]);
        }
    }
    assert!(
        ratios.len() == 4 && unreachable.len() <= 2,
        "unreachable: {unreachable:?}"
    );
    let ratio = sums[0] / sums[1];
    eprintln!("RMSE ours / jarosz08 per seed: {ratios:.3?}; of the means over seeds {ratio:.3}");
    // Measured: per seed (1, 2, 3, 5) 0.48, 0.67, 0.43, 0.37, of the means 0.46. Jarosz 2008's
    // error swings with its seed (1.6e-2 to 7e-2: a few records with wrong gradients
    // extrapolate far); ours stays at 1.3–1.6e-2.
    assert!(ratio < 0.7, "{ratios:?}");
    assert!(ratios.iter().all(|&r| r < 1.1), "{ratios:?}");
}

/// The cached image estimates what the path tracer does. With the same seed, the
/// path tracer and a cached render trace the same camera rays; per pixel, path
/// tracing's split of the image (first event a scattering or not) and the cached
/// render's medium part (∫ T L_s dt by the march) and surface part (T L_o) estimate
/// the same two integrals, so their differences average to zero over the image —
/// for the march reference (L_s path traced at the march points) exactly, for the
/// cache up to its interpolation error.
#[test]
fn cached_and_path_traced_images_agree_on_average() {
    let s = load("fog_box.json");
    let p = params(&s, 12, 12, 16, 64.0);
    // 16× the samples: the first 16 of each pixel are the cached render's camera rays.
    let mut many = p.image.clone();
    many.spp *= 16;
    let pt = render(&s, &many, &Progress::new()).unwrap();
    let reference = march_reference(&s, &p, 8, 1, &Progress::new()).unwrap().image;
    let cs = settings(CacheMethod::Ours, &s, 1024, 16, 1);
    let cached = render_cached(&s, &p, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap();
    let img = &cached.reconstruction.image;
    let surface = |v: &[Rgb], m: &[Rgb]| -> Vec<f64> { v.iter().zip(m).map(|(a, b)| luminance(*a - *b)).collect() };
    let medium = |m: &[Rgb]| -> Vec<f64> { m.iter().map(|c| luminance(*c)).collect() };
    // Mean and standard error of the per-pixel differences a − b.
    let diff = |a: &[f64], b: &[f64]| {
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        let n = d.len() as f64;
        let mu = d.iter().sum::<f64>() / n;
        let var = d.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (n - 1.0);
        (mu, (var / n).sqrt(), b.iter().sum::<f64>() / n)
    };
    let (pt_med, pt_surf) = (medium(&pt.medium), surface(&pt.values, &pt.medium));
    let checks = [
        (
            "march reference, medium",
            diff(&medium(&reference.medium), &pt_med),
            0.0,
        ),
        (
            "march reference, surface",
            diff(&surface(&reference.values, &reference.medium), &pt_surf),
            0.0,
        ),
        ("ours, medium", diff(&medium(&img.medium), &pt_med), 0.02),
        ("ours, surface", diff(&surface(&img.values, &img.medium), &pt_surf), 0.0),
    ];
    for (what, (mu, se, mean_pt), bias) in checks {
        eprintln!("{what}: mean difference to path tracing {mu:+.5} ± {se:.5} (path tracing's mean {mean_pt:.5})");
        assert!(mu.abs() < 4.0 * se + bias * mean_pt, "{what}");
    }
}

/// A records file round-trips exactly (the reconstruction from it is the same
/// image) and refuses another image size or scene with the reason. (Hole-free,
/// thread-independent placement is checked in both dimensions in `dims_caching.rs`.)
#[test]
fn records_file_round_trips() {
    let s = load("fog_box.json");
    let p = params(&s, 20, 20, 2, 48.0);
    for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        let cs = settings(method, &s, 256, 8, 3);
        let a = render_cached(&s, &p, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap();
        assert!(a.placement.record_count() > 5, "{method:?}");
        let file = RecordsFile::from_placement(&s, &p, method, &a.placement, None);
        let text = serde_json::to_string(&file).unwrap();
        let loaded = RecordsFile::parse(&text, "records.json").unwrap();
        let (back, cache) = (loaded.file, loaded.cache);
        assert_eq!(back, file);
        assert!(loaded.surfaces.is_none() && !text.contains("surfaces"));
        assert_eq!(cache.records(), a.placement.caches[0].records());
        assert_eq!(back.valid_for.mismatch(&ValidFor::of(&s, &p)), None);
        let second_order = false;
        let again = reconstruct(&s, &p, CacheView::records(&cache), second_order, &Progress::new()).unwrap();
        assert_eq!(again.image.values, a.reconstruction.image.values);
        // Another image size, or another scene, is refused with the reason.
        let mut other = p.clone();
        other.image.width = 21;
        assert!(
            back.valid_for
                .mismatch(&ValidFor::of(&s, &other))
                .unwrap()
                .contains("21x20")
        );
        let edited = scene(
            &serde_json::to_string(&s.desc)
                .unwrap()
                .replace("\"g\":0.3", "\"g\":0.31"),
        );
        assert!(
            back.valid_for
                .mismatch(&ValidFor::of(&edited, &p))
                .unwrap()
                .contains("another scene")
        );
    }
}

/// Bad records files name the file and the JSON path.
#[test]
fn bad_records_files_are_clear_errors() {
    let s = load("fog_box.json");
    let p = params(&s, 6, 6, 1, 16.0);
    let cs = settings(CacheMethod::Ours, &s, 64, 4, 1);
    let placed = place(&s, &p, &cs, &mut RecordMemo::new(), &Progress::new()).unwrap();
    let good = serde_json::to_value(RecordsFile::from_placement(&s, &p, CacheMethod::Ours, &placed, None)).unwrap();
    let check = |v: serde_json::Value, want: &str| {
        let Err(err) = RecordsFile::parse(&v.to_string(), "r.json") else {
            panic!("accepted")
        };
        assert!(err.starts_with("r.json") && err.contains(want), "{err}");
    };
    let mut v = good.clone();
    v["records"][0]["radii"][1] = serde_json::json!(-1.0);
    check(v, "records[0]");
    let mut v = good.clone();
    v["records"][0]["value"][2][0] = serde_json::json!(null);
    check(v, "records[0].value[2][0]");
    let mut v = good.clone();
    v["valid_for"]["colour"] = serde_json::json!(1);
    check(v, "valid_for");
    let mut v = good.clone();
    v["format"] = serde_json::json!("something else");
    check(v, "format");
    // Records that leave the straight light out say so, with a count in range.
    let mut v = good.clone();
    v["direct_samples"] = serde_json::json!(0);
    check(v, "direct_samples");
    let mut v = good.clone();
    v["direct_samples"] = serde_json::json!(3);
    let Ok(loaded) = RecordsFile::parse(&v.to_string(), "r.json") else {
        panic!("refused")
    };
    assert_eq!(loaded.file.direct_samples, Some(3));
    let Err(err) = RecordsFile::parse("{not json", "r.json") else {
        panic!("accepted")
    };
    assert!(err.starts_with("r.json"), "{err}");
}

/// The surface cache rides in the records file: read back, it is the placed one
/// (records, normals, listed occluders, costs) and reconstructs the same image;
/// a bent normal or a bad surface record is refused with its JSON path.
#[test]
fn records_file_round_trips_the_surface_cache() {
    let s = scene(ROOM);
    let mut p = params(&s, 16, 12, 2, 32.0);
    p.surface_eps = Some(default_surface_eps(&s));
    let cs = settings(CacheMethod::Ours, &s, 128, 4, 2);
    let progress = Progress::new();
    let placed = place(&s, &p, &cs, &mut RecordMemo::new(), &progress).unwrap();
    let surfaces = place_surfaces(&s, &p, &cs, &progress).unwrap().unwrap();
    assert!(surfaces.record_count() > 3, "{}", surfaces.record_count());
    let file = RecordsFile::from_placement(&s, &p, CacheMethod::Ours, &placed, Some(&surfaces));
    let text = serde_json::to_string(&file).unwrap();
    let loaded = RecordsFile::parse(&text, "records.json").unwrap();
    assert_eq!(loaded.file, file);
    let back = loaded.surface_cache(&s).unwrap();
    assert_eq!(back.cache.records(), surfaces.cache.records());
    assert_eq!((&back.normals, &back.near), (&surfaces.normals, &surfaces.near));
    assert_eq!(
        (back.eps, back.query_points, back.rays, back.seconds),
        (surfaces.eps, surfaces.query_points, surfaces.rays, surfaces.seconds)
    );
    let image = |sc| {
        let view = CacheView::records(&placed.caches[0]).with_surfaces(Some(sc));
        reconstruct(&s, &p, view, false, &progress).unwrap().image.values
    };
    assert_eq!(image(&back), image(&surfaces));
    let good = serde_json::to_value(&file).unwrap();
    let check = |v: serde_json::Value, want: &str| {
        let Err(err) = RecordsFile::parse(&v.to_string(), "r.json") else {
            panic!("accepted {want}")
        };
        assert!(err.starts_with("r.json") && err.contains(want), "{err}");
    };
    let mut v = good.clone();
    v["surfaces"]["records"][1]["normal"] = serde_json::json!([0.0, 1.0, 0.1]);
    check(v, "surfaces.records[1].normal");
    let mut v = good.clone();
    v["surfaces"]["records"][0]["record"]["radii"][2] = serde_json::json!(0.0);
    check(v, "surfaces.records[0].record.radii[2]");
    let mut v = good;
    v["surfaces"]["eps"] = serde_json::json!(-1.0);
    check(v, "surfaces.eps");
}

/// Users push parameters to the extremes: nothing turns into NaN, inf or a hang.
#[test]
fn finite_at_extremes() {
    let base = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes3d/fog_box.json")).unwrap();
    let variants = [
        ("g = 0.99", base.replace("\"g\": 0.3", "\"g\": 0.99")),
        ("g = -0.99", base.replace("\"g\": 0.3", "\"g\": -0.99")),
        (
            "thin",
            base.replace("\"sigma_s\": 0.35", "\"sigma_s\": 1e-6")
                .replace("\"sigma_a\": 0.05", "\"sigma_a\": 0"),
        ),
        (
            "thick",
            base.replace("\"sigma_s\": 0.35", "\"sigma_s\": 300")
                .replace("\"sigma_a\": 0.05", "\"sigma_a\": 700"),
        ),
    ];
    for (name, text) in variants {
        let s = scene(&text);
        let p = params(&s, 6, 6, 1, 24.0);
        for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
            for eps in [1e-12, 1e12] {
                let mut cs = settings(method, &s, 64, 4, 1);
                cs.eps = eps;
                cs.second_order = true;
                let r = render_cached(&s, &p, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap();
                let img = &r.reconstruction.image;
                assert!(
                    img.values
                        .iter()
                        .chain(&img.medium)
                        .all(|v| v.is_finite() && v.min_element() >= 0.0),
                    "{name} {method:?} ε {eps}"
                );
                assert_eq!(r.reconstruction.uncovered, 0, "{name} {method:?} ε {eps}");
            }
        }
    }
}

/// A scene without a medium pays nothing for caching: no query points, no records,
/// no probe rays, and the image is the path-traced surfaces.
#[test]
fn no_medium_no_cost() {
    let s = scene(
        r#"{ "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_deg": 40},
             "shapes": [{"quad": {"origin": [-2, -2, 0], "u": [4, 0, 0], "v": [0, 4, 0]}, "reflectance": 0.5}],
             "lights": [{"point": {"position": [0, 0, 1], "intensity": 1}}] }"#,
    );
    let p = params(&s, 8, 8, 1, 64.0);
    let cs = settings(CacheMethod::Ours, &s, 256, 8, 1);
    let r = render_cached(&s, &p, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap();
    assert_eq!(
        (r.placement.query_points, r.placement.record_count(), r.placement.rays),
        (0, 0, 0)
    );
    let img = &r.reconstruction.image;
    assert!(img.medium.iter().all(|&m| m == Rgb::ZERO));
    // A point light over a diffuse quad: both estimators are exact (NEE), on the same
    // camera rays: (ρ/π) I cosθ / r² at every pixel's sample.
    let pt = render(&s, &p.image, &Progress::new()).unwrap();
    for (a, b) in img.values.iter().zip(&pt.values) {
        assert!((*a - *b).abs().max_element() <= 1e-12 * b.max_element(), "{a} vs {b}");
    }
    assert!(img.values.iter().any(|v| v.x > 0.1));
}

/// Fog everywhere under an open sky: camera rays that miss the floor march through
/// unbounded fog. Past transmittance 10⁻³ the march keeps points by Russian
/// roulette, so placement visits the points the camera sees (before: 83,761 query
/// points and 41,713 records for an 8×6 image at σ_t = 0.65, 45 s), and the march
/// estimate of the medium part stays unbiased: its mean over the image agrees with
/// path tracing's.
#[test]
fn open_fog_places_records_where_the_camera_sees_and_stays_unbiased() {
    let s = scene(
        r#"{ "camera": {"position": [0, 1, 3], "look_at": [0, 0.8, 0], "fov_deg": 50},
             "shapes": [{"quad": {"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}, "reflectance": 0.6}],
             "lights": [{"point": {"position": [0.3, 1.6, -1.0], "intensity": 3}}],
             "medium": {"sigma_a": 0.05, "sigma_s": 0.6, "g": 0.4},
             "render": {"max_depth": 16} }"#,
    );
    let mut p = params(&s, 8, 6, 4, 128.0);
    let cs = settings(CacheMethod::Ours, &s, 64, 4, 1);
    let placed = place(&s, &p, &cs, &mut RecordMemo::new(), &Progress::new()).unwrap();
    let (records, points) = (placed.record_count(), placed.query_points);
    eprintln!("open fog: {records} records over {points} query points");
    // Without the roulette each of the 192 camera samples that misses the floor
    // marches its full 16,384 points.
    assert!(points < 20_000, "{records} records, {points} points");
    // Medium part: the march with path-traced L_s against path tracing, per pixel
    // means over the image (mean and standard error of the differences).
    (p.image.width, p.image.height, p.image.spp) = (16, 12, 64);
    let reference = march_reference(&s, &p, 4, 1, &Progress::new()).unwrap().image;
    let mut many = p.image.clone();
    many.spp = 4096;
    let pt = render(&s, &many, &Progress::new()).unwrap();
    let d: Vec<f64> = reference
        .medium
        .iter()
        .zip(&pt.medium)
        .map(|(a, b)| luminance(*a) - luminance(*b))
        .collect();
    let n = d.len() as f64;
    let mu = d.iter().sum::<f64>() / n;
    let se = (d.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    let mean = pt.medium.iter().map(|c| luminance(*c)).sum::<f64>() / n;
    eprintln!("medium part: march − pt = {mu:.3e} ± {se:.3e} (mean {mean:.3e})");
    assert!(mu.abs() < 4.0 * se + 0.01 * mean, "{mu} ± {se} of {mean}");
}

/// A memo shared by placements of two image sizes (the app's half-size preview,
/// then its full size) gives the full size the same records and image as a fresh
/// memo: light fields are memoised per point of one image, never handed to the
/// pixel of the same index in another size.
#[test]
fn a_memo_shared_across_image_sizes_changes_nothing() {
    let s = load("fog_box.json");
    let cs = settings(CacheMethod::Ours, &s, 128, 6, 1);
    let (small, full) = (params(&s, 10, 10, 1, 32.0), params(&s, 20, 20, 1, 32.0));
    let fresh = render_cached(&s, &full, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap();
    let mut memo = RecordMemo::new();
    render_cached(&s, &small, &cs, None, &mut memo, &Progress::new()).unwrap();
    let shared = render_cached(&s, &full, &cs, None, &mut memo, &Progress::new()).unwrap();
    assert_eq!(
        shared.placement.caches[0].records(),
        fresh.placement.caches[0].records()
    );
    assert_eq!(shared.reconstruction.image.values, fresh.reconstruction.image.values);
}
