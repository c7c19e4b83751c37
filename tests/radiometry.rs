//! The flatland path tracer and fields: convergence to a published value, fields
//! without a medium, cancellation. The closed forms that hold in both dimensions
//! (furnace, point light, single scattering, thread independence) are in
//! `dims_radiometry.rs`.

use glam::DVec2;
use volcache::flatland::field::{FieldParams, render_field};
use volcache::flatland::scene::Scene;
use volcache::pipeline::path::{Query, Settings, estimate};
use volcache::progress::Progress;

fn scene(json: &str) -> Scene {
    Scene::from_json(json, "test").unwrap()
}

/// The mean over independent seeds converges to the closed form, and the spread
/// of single estimates shrinks like 1/√N.
#[test]
fn estimates_are_unbiased_with_error_shrinking_as_inverse_sqrt_n() {
    let s = Scene::load(std::path::Path::new("flatland_scenes/point_in_fog.json")).unwrap();
    let want = 0.3234545; // benchmarks.md, c = 0.9, r = 1
    let x = DVec2::new(1.0, 0.0);
    let mut rms = Vec::new();
    for n in [250u32, 4000] {
        let seeds = 48;
        let vals: Vec<f64> = (0..seeds)
            .map(|seed| {
                estimate(&s, x, &Query::Fluence, &Settings::default(), n, seed, 0)
                    .mean
                    .total()
                    .x
            })
            .collect();
        let mean = vals.iter().sum::<f64>() / seeds as f64;
        let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64).sqrt();
        assert!(
            (mean - want).abs() < 4.0 * sd / (seeds as f64).sqrt(),
            "N={n}: mean {mean} ± {sd}"
        );
        rms.push((vals.iter().map(|v| (v - want).powi(2)).sum::<f64>() / seeds as f64).sqrt());
    }
    let ratio = rms[0] / rms[1];
    println!("rms error ratio for 16x samples: {ratio} (expected 4)");
    assert!((2.8..5.7).contains(&ratio), "error ratio {ratio}");
}

/// A scene without a medium has no L_s anywhere, and renders fluence everywhere.
#[test]
fn vacuum_scene_renders_without_a_medium() {
    let s = scene(
        r#"{ "domain": {"min": [-1,-1], "max": [1,1]},
        "segments": [{"a": [-1, 0.9], "b": [1, 0.9], "emission": 1}] }"#,
    );
    let mut p = FieldParams::from_scene(&s);
    (p.width, p.height, p.spp) = (8, 8, 2);
    let ls = render_field(&s, &p, &Progress::new()).unwrap();
    assert!(ls.field.valid.iter().all(|v| !v) && ls.field.values.iter().all(|v| *v == glam::DVec3::ZERO));
    p.quantity = volcache::flatland::scene_desc::Quantity::Fluence;
    let phi = render_field(&s, &p, &Progress::new()).unwrap();
    assert!(phi.field.valid.iter().all(|v| *v) && phi.field.values.iter().all(|v| v.x > 0.0));
}

/// Cancellation stops a render with an error instead of a partial field.
#[test]
fn cancelled_render_returns_cancelled() {
    let s = Scene::default_scene();
    let p = FieldParams::from_scene(&s);
    let progress = Progress::new();
    progress.cancel();
    assert!(render_field(&s, &p, &progress).is_err());
}
