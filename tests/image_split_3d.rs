//! The adaptive split of a cached 3D image (`volume::image_split`): the camera
//! samples beyond the placed ones take the march step and straight-light samples
//! of least variance × cost, predicted from the placed samples' own statistics.
//! Checked on a scene of our own (a lamp over a slotted plate: a thin sheet of
//! light through forward-scattering fog): the predictions against measured
//! variances, thread-count determinism, and the equal-cost image's mean.

use std::path::Path;
use volcache::core::color::luminance;
use volcache::core::metric::CacheMethod;
use volcache::progress::Progress;
use volcache::volume::cached::{
    CacheSettings, CacheView, CachedRenderParams, Placement, RecordMemo, default_eps, place, reconstruct,
};
use volcache::volume::image_split::ImageSplit;
use volcache::volume::render::{RenderParams, Rendered};
use volcache::volume::scene::Scene;

const SLOT: &str = r#"{
  "camera": {"position": [0.2, 0.8, 3.0], "look_at": [0, 0.3, 0], "fov_deg": 30},
  "shapes": [
    {"quad": {"origin": [-1.5, 0, -1.5], "u": [0, 0, 3], "v": [3, 0, 0]}, "reflectance": 0},
    {"quad": {"origin": [-0.8, 0.9, -0.8], "u": [0.7, 0, 0], "v": [0, 0, 1.6]}, "reflectance": 0},
    {"quad": {"origin": [0.05, 0.9, -0.8], "u": [0.75, 0, 0], "v": [0, 0, 1.6]}, "reflectance": 0},
    {"quad": {"origin": [-0.3, 1.3, -0.3], "u": [0.6, 0, 0], "v": [0, 0, 0.6]},
     "reflectance": 0, "emission": [12, 11, 9], "two_sided": true}
  ],
  "medium": {"sigma_a": 0.1, "sigma_s": 0.9, "g": 0.7,
             "region": {"box": {"min": [-1.2, 0, -1.2], "max": [1.2, 1.2, 1.2]}}},
  "render": {"resolution": [12, 9], "spp": 4, "seed": 3, "max_depth": 8, "exposure": 0.0}
}"#;

fn slot() -> Scene {
    Scene::from_json(SLOT, "<slot>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// The same with a floor that reflects: its light, path traced with one sample
/// per camera sample, is most of the pixels' variance.
fn lit_slot() -> Scene {
    let json = SLOT.replacen(
        r#""v": [3, 0, 0]}, "reflectance": 0}"#,
        r#""v": [3, 0, 0]}, "reflectance": 0.2}"#,
        1,
    );
    assert_ne!(json, SLOT);
    Scene::from_json(&json, "<lit slot>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

fn params(scene: &Scene, spp: u32, seed: u64) -> CachedRenderParams {
    let mut p = CachedRenderParams::from_scene(scene);
    (p.image.width, p.image.height, p.image.spp, p.image.seed) = (12, 9, spp, seed);
    p.march_step = scene.scale / 48.0;
    p.surface_paths = 1;
    p
}

/// Ours' records with the straight light sampled per point (4 samples), placed
/// over `p`'s camera samples.
fn placed(scene: &Scene, p: &CachedRenderParams) -> Placement {
    let mut cs = CacheSettings::new::<volcache::core::space::D3>(
        CacheMethod::Ours,
        default_eps(CacheMethod::Ours, scene) * 4.0,
        RenderParams::from_scene(scene).first_vertex_settings(),
    );
    (cs.probe.rays, cs.probe.steps, cs.direct_samples) = (256, 8, Some(4));
    place(scene, p, &cs, &mut RecordMemo::new(), &Progress::new()).unwrap()
}

/// Σ over pixels of the camera samples' variance (luminance of the total).
fn pixel_variance(img: &Rendered) -> f64 {
    img.std_error.iter().map(|se| se * se * img.spp as f64).sum()
}

/// The placed samples predict what a coarser march (K = 4) and fewer
/// straight-light samples (1 of 4) add to a camera sample's variance: measured
/// on renders that take them for every sample, the ratios agree within the
/// estimates' noise. Seeds 1–4 (32 samples per pixel, 108 pixels): predicted /
/// measured 0.97–1.05 for K = 4 (ratios 1.27–1.66), 0.95–1.13 for one sample
/// (1.05–1.33).
#[test]
fn the_placed_samples_predict_the_added_variance() {
    let s = slot();
    let progress = Progress::new();
    for seed in [1, 2, 3, 4] {
        let p = params(&s, 32, seed);
        let placement = placed(&s, &p);
        let view = CacheView::of(&placement);
        // The candidates' table: placed over all 32 samples, one more split.
        let mut adapt = p.clone();
        (adapt.image.spp, adapt.place_spp, adapt.adapt_image) = (33, Some(32), true);
        let table = reconstruct(&s, &adapt, view, false, &progress)
            .unwrap()
            .split_candidates;
        let find = |k: u32, n: u32| -> ImageSplit {
            *table
                .iter()
                .find(|c| c.march_factor == k && c.direct_samples == Some(n) && c.march_every == 1)
                .unwrap_or_else(|| panic!("no candidate K = {k}, n = {n} in {table:?}"))
        };
        let fine = pixel_variance(&reconstruct(&s, &p, view, false, &progress).unwrap().image);
        let mut coarse = p.clone();
        coarse.march_step *= 4.0;
        let k4 = pixel_variance(&reconstruct(&s, &coarse, view, false, &progress).unwrap().image);
        let one = CacheView {
            direct_samples: Some(1),
            ..view
        };
        let n1 = pixel_variance(&reconstruct(&s, &p, one, false, &progress).unwrap().image);
        let (pk, pn) = (find(4, 4).variance_ratio, find(1, 1).variance_ratio);
        let (mk, mn) = (k4 / fine, n1 / fine);
        println!("seed {seed}: K = 4 predicted {pk:.3} measured {mk:.3}; n = 1 predicted {pn:.3} measured {mn:.3}");
        assert!(
            pk > 1.02 && pn > 1.02,
            "the scene must make both add variance: {pk} {pn}"
        );
        for (what, pred, meas) in [("K = 4", pk, mk), ("n = 1", pn, mn)] {
            assert!(
                (pred / meas - 1.0).abs() < 0.25,
                "{what}: predicted variance ratio {pred:.3}, measured {meas:.3}"
            );
        }
        // Cost: fewer rays per sample as predicted (rays only; the prediction adds
        // a ray's worth per march point).
        assert!(find(4, 4).cost_ratio < 0.5 && find(1, 1).cost_ratio < 0.8, "{table:?}");
    }
}

/// An adaptive render is the same image whatever the thread count, and at equal
/// cost its mean matches the fixed march's within their noise.
#[test]
fn adaptive_split_is_deterministic_and_unbiased() {
    let s = slot();
    let progress = Progress::new();
    let p = params(&s, 16, 5);
    let placement = placed(&s, &p);
    let view = CacheView::of(&placement);
    let mut adapt = p.clone();
    (adapt.place_spp, adapt.adapt_image) = (Some(4), true);
    let pool = |n: usize| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let one = pool(1).install(|| reconstruct(&s, &adapt, view, false, &progress).unwrap());
    let two = pool(2).install(|| reconstruct(&s, &adapt, view, false, &progress).unwrap());
    assert_eq!(one.image.values, two.image.values);
    assert_eq!(one.split, two.split);
    let split = one.split.expect("an adaptive render says its split");
    assert!(one.image.spp >= 16 && split.cost_ratio <= 1.0, "{split:?}");
    let fixed = reconstruct(&s, &p, view, false, &progress).unwrap();
    let mean = |img: &Rendered| img.values.iter().map(|v| luminance(*v)).sum::<f64>() / img.values.len() as f64;
    let se = |img: &Rendered| img.std_error.iter().map(|e| e * e).sum::<f64>().sqrt() / img.values.len() as f64;
    let (a, b) = (mean(&one.image), mean(&fixed.image));
    let tol = 4.0 * (se(&one.image).powi(2) + se(&fixed.image).powi(2)).sqrt();
    println!(
        "split {split:?}: {} samples, mean {a:.5} vs fixed {b:.5} (± {tol:.5}); rays {} vs {}",
        one.image.spp, one.image.rays, fixed.image.rays
    );
    assert!((a - b).abs() < tol, "{a} vs {b} ± {tol}");
    // Equal cost: the rays (which the prediction counts, with a ray's worth per
    // march point) stay near the fixed render's.
    let r = one.image.rays as f64 / fixed.image.rays as f64;
    assert!((0.6..1.3).contains(&r), "rays ratio {r}");
}

/// The placed samples predict what marching one later camera sample in four does
/// to the image's variance (the first surface sampled by all, the medium part by
/// a quarter): measured on a render that takes it, against the fine render of as
/// many samples, within the estimates' noise; and its mean matches the fine one.
/// (A stride — every fourth sample — held the marched ones to a quarter of the
/// pixel's scrambled Sobol' set: measured 0.72–0.90× the prediction, its
/// standard error blind to it.)
#[test]
fn the_placed_samples_predict_the_march_share() {
    let s = lit_slot();
    let progress = Progress::new();
    let mut log_ratio = 0.0;
    for seed in [1, 2, 3, 4] {
        let p = params(&s, 33, seed);
        let placement = placed(&s, &p);
        let view = CacheView::of(&placement);
        let mut adapt = p.clone();
        (adapt.place_spp, adapt.adapt_image) = (Some(32), true);
        let table = reconstruct(&s, &adapt, view, false, &progress)
            .unwrap()
            .split_candidates;
        let find = |m: u32| -> ImageSplit {
            *table
                .iter()
                .find(|c| c.march_factor == 1 && c.direct_samples == Some(4) && c.march_every == m)
                .unwrap_or_else(|| panic!("no candidate m = {m} in {table:?}"))
        };
        let fine = reconstruct(&s, &p, view, false, &progress).unwrap().image;
        // Sample 0 placed, then 1, 5, …, 29 of the 32 later ones march: 9 of 33.
        let mut share = p.clone();
        (share.place_spp, share.image_march_every) = (Some(1), Some(4));
        let shared = reconstruct(&s, &share, view, false, &progress).unwrap().image;
        // The variance is linear in m: interpolate the table at m = 33/9.
        let m_eff = 33.0 / 9.0;
        let predicted = 1.0 + (find(4).variance_ratio - 1.0) * (m_eff - 1.0) / 3.0;
        let measured = pixel_variance(&shared) / pixel_variance(&fine);
        println!(
            "seed {seed}: m = 4 table {:?}; predicted {predicted:.3} measured {measured:.3}; rays {} vs {}",
            find(4),
            shared.rays,
            fine.rays
        );
        assert!(
            predicted > 1.1,
            "the scene must make the share add variance: {predicted}"
        );
        assert!(
            (0.6..1.6).contains(&(predicted / measured)),
            "predicted variance ratio {predicted:.3}, measured {measured:.3}"
        );
        log_ratio += (predicted / measured).ln() / 4.0;
        assert!(find(4).cost_ratio < 0.6 && (shared.rays as f64) < 0.6 * fine.rays as f64);
        let mean = |img: &Rendered| img.values.iter().map(|v| luminance(*v)).sum::<f64>() / img.values.len() as f64;
        let se = |img: &Rendered| img.std_error.iter().map(|e| e * e).sum::<f64>().sqrt() / img.values.len() as f64;
        let (a, b) = (mean(&shared), mean(&fine));
        let tol = 4.0 * (se(&shared).powi(2) + se(&fine).powi(2)).sqrt();
        assert!((a - b).abs() < tol, "{a} vs {b} ± {tol}");
    }
    // Over the four seeds (the medium's variance from 9 marched samples a pixel is
    // a noisy measurement: seeds 1–12 gave predicted / measured 0.73–1.23 each,
    // geometric means of four 0.97, 1.01, 1.03).
    let mean_ratio = log_ratio.exp();
    assert!(
        (0.88..1.12).contains(&mean_ratio),
        "predicted / measured over seeds 1–4: {mean_ratio:.3}"
    );
}

/// Thin emitting strips on a black wall behind fog, seen by the camera: a pixel's
/// light from the first surface is all in whether its camera sample hits a strip
/// (most of the variance, and nearly free: the camera ray alone), the medium's
/// needs the march (the strips' light sampled at every point).
const STRIPS: &str = r#"{
  "camera": {"position": [0, 0.6, 3.0], "look_at": [0, 0.6, 0], "fov_deg": 30},
  "shapes": [
    {"quad": {"origin": [-1.5, 0, -1.5], "u": [0, 0, 3], "v": [3, 0, 0]}, "reflectance": 0},
    {"quad": {"origin": [-0.62, 0.2, -1], "u": [0.05, 0, 0], "v": [0, 0.8, 0]}, "reflectance": 0, "emission": [6, 6, 6]},
    {"quad": {"origin": [-0.21, 0.2, -1], "u": [0.05, 0, 0], "v": [0, 0.8, 0]}, "reflectance": 0, "emission": [6, 6, 6]},
    {"quad": {"origin": [0.2, 0.2, -1], "u": [0.05, 0, 0], "v": [0, 0.8, 0]}, "reflectance": 0, "emission": [6, 6, 6]},
    {"quad": {"origin": [0.61, 0.2, -1], "u": [0.05, 0, 0], "v": [0, 0.8, 0]}, "reflectance": 0, "emission": [6, 6, 6]}
  ],
  "medium": {"sigma_a": 0.05, "sigma_s": 0.4, "g": 0.5,
             "region": {"box": {"min": [-1.2, 0, -0.9], "max": [1.2, 1.2, 1.2]}}},
  "render": {"resolution": [12, 9], "spp": 4, "seed": 3, "max_depth": 8, "exposure": 0.0}
}"#;

/// Asked to choose the march share (`adapt_march_share`), the split takes one
/// where the first surface's light is most of the variance (the lit floor) and
/// none where the medium's is all of it (black surfaces); the chosen render is
/// the same whatever the thread count, its mean matches the fine render's within
/// their noise, and at about the same rays its image's variance is lower than
/// the split's without a share.
#[test]
fn the_march_share_is_chosen_where_the_surface_holds_the_variance() {
    let progress = Progress::new();
    let pool = |n: usize| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let lit = Scene::from_json(STRIPS, "<strips>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let black = slot();
    for seed in [1, 2] {
        let p = params(&lit, 16, seed);
        let placement = placed(&lit, &p);
        let view = CacheView::of(&placement);
        let mut unshared = p.clone();
        (unshared.place_spp, unshared.adapt_image) = (Some(4), true);
        let auto = CachedRenderParams {
            adapt_march_share: true,
            ..unshared.clone()
        };
        let one = pool(1).install(|| reconstruct(&lit, &auto, view, false, &progress).unwrap());
        let two = pool(2).install(|| reconstruct(&lit, &auto, view, false, &progress).unwrap());
        assert_eq!((&one.image.values, one.split), (&two.image.values, two.split));
        let split = one.split.expect("an adaptive render says its split");
        let plain = reconstruct(&lit, &unshared, view, false, &progress).unwrap();
        let fine = reconstruct(&lit, &p, view, false, &progress).unwrap().image;
        let mean = |img: &Rendered| img.values.iter().map(|v| luminance(*v)).sum::<f64>() / img.values.len() as f64;
        let se2 = |img: &Rendered| img.std_error.iter().map(|e| e * e).sum::<f64>();
        let (a, b) = (mean(&one.image), mean(&fine));
        let tol = 4.0 * (se2(&one.image) + se2(&fine)).sqrt() / fine.values.len() as f64;
        let variance = se2(&one.image) / se2(&plain.image);
        let rays = one.image.rays as f64 / plain.image.rays as f64;
        println!(
            "seed {seed}: auto {split:?}, {} samples; plain {:?}, {} samples; variance of the mean {variance:.3}×, rays {rays:.3}×; mean {a:.5} vs fine {b:.5} ± {tol:.5}",
            one.image.spp, plain.split, plain.image.spp
        );
        assert!(split.march_every > 1, "{split:?}");
        assert!((a - b).abs() < tol, "{a} vs {b} ± {tol}");
        assert!((0.6..1.3).contains(&rays), "rays ratio {rays}");
        assert!(variance < 0.8, "image variance {variance:.3}× the unshared split's");
        // Black surfaces: the medium is the image, a share would only add variance.
        let q = params(&black, 16, seed);
        let placement = placed(&black, &q);
        let mut auto = q.clone();
        (auto.place_spp, auto.adapt_image, auto.adapt_march_share) = (Some(4), true, true);
        let r = reconstruct(&black, &auto, CacheView::of(&placement), false, &progress).unwrap();
        assert_eq!(r.split.map(|s| s.march_every), Some(1), "{:?}", r.split);
    }
}
