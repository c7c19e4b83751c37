//! A 3D cache survives camera motion with its records' moments over ω_o
//! (pipeline::moments, study::moments3d), on a scene of our own with strongly
//! forward-scattering fog (g = 0.8) and an area lamp, so that ω_o matters: after an
//! orbit, the first camera's records read as stored are stale (measurably worse
//! than the same records' moments), while their moments, extended where the new
//! view needs records, are about as good as a fresh cache for a seventh of its new
//! records.

use std::path::Path;
use volcache::core::metric::CacheMethod;
use volcache::progress::Progress;
use volcache::study::moments3d::{first_views, moved_view, orbited};
use volcache::volume::cached::{CacheSettings, CachedRenderParams};
use volcache::volume::render::{RenderParams, render};
use volcache::volume::scene::Scene;

const LAMP_FOG: &str = r#"{
  "camera": {"position": [0, 1.4, 4.0], "look_at": [0, 0.8, 0], "fov_deg": 45},
  "shapes": [
    {"quad": {"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}, "reflectance": 0.5},
    {"box": {"min": [-0.3, 0, -0.3], "max": [0.3, 0.9, 0.3]}, "reflectance": 0.6},
    {"quad": {"origin": [-1.2, 1.6, -0.9], "u": [0.5, 0, 0], "v": [0, -0.3, 0.5]},
     "reflectance": 0, "emission": [30, 24, 14], "two_sided": true}
  ],
  "medium": {"sigma_a": 0.05, "sigma_s": 0.5, "g": 0.8,
             "region": {"box": {"min": [-1.5, 0, -1.5], "max": [1.5, 1.8, 1.5]}}},
  "render": {"resolution": [32, 24], "spp": 1, "seed": 3, "max_depth": 16}
}"#;

#[test]
fn moments_keep_a_cache_valid_when_the_camera_orbits() {
    let scene = Scene::from_json(LAMP_FOG, "lamp_fog.json", Path::new(".")).unwrap();
    let mut cp = CachedRenderParams::from_scene(&scene);
    cp.image.spp = 2;
    let mut cs =
        CacheSettings::new::<volcache::core::space::D3>(CacheMethod::Ours, 8e-3, cp.image.first_vertex_settings());
    cs.probe.rays = 256;
    cs.probe.steps = 8;
    cs.moment_bands = Some(6);
    let progress = Progress::new();
    let first = first_views(&scene, &cs, &cp, &progress).unwrap();
    eprintln!("first view: {} records", first.with_moments.1.records);
    for yaw in [20.0, 70.0] {
        let moved = orbited(&scene, yaw);
        let reference = render(
            &moved,
            &RenderParams {
                spp: 512,
                seed: 99,
                ..cp.image.clone()
            },
            &progress,
        )
        .unwrap();
        let runs = moved_view(&moved, yaw, &cs, &cp, &first, &reference, &progress).unwrap();
        for r in &runs {
            eprintln!(
                "yaw {yaw}: {:>9} {} records ({} new), medium RMSE {:.4e}",
                r.mode, r.records, r.new_records, r.medium_errors.rmse
            );
        }
        let (fresh, moments, stale) = (&runs[0], &runs[1], &runs[2]);
        let e = |r: &volcache::study::moments3d::MotionRun| r.medium_errors.rmse;
        // The same records and new points; only ω_o's treatment differs.
        assert!(
            e(stale) > 1.15 * e(moments),
            "yaw {yaw}: stale {} vs moments {}",
            e(stale),
            e(moments)
        );
        // Measured over cache seeds 1–2 at yaws 20° and 70°: stale / moments 1.31–1.85;
        // moments / fresh 0.60–1.53 — a fresh cache of 256-ray records is itself
        // that noisy (its RMSE varies 1.7× between seeds), so this bound is loose.
        assert!(
            e(moments) < 2.0 * e(fresh),
            "yaw {yaw}: moments {} vs fresh {}",
            e(moments),
            e(fresh)
        );
        assert!(
            moments.new_records * 3 < fresh.records,
            "yaw {yaw}: the first records were not reused"
        );
    }
}
