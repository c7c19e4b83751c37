//! `CacheSettings::gradient_noise_reach`: a record whose multiple-scattering
//! gradient is mostly noise reaches no farther than that noise allows at ε
//! (`core::metric::gradient_noise_radius`). On a scene of our own — a point light
//! under a flat shade in thick, strongly forward-scattering fog — records of a few
//! hundred directions shrink their noisy gradients away and, at the metric's
//! radii, extrapolate the light's sharp falloff as a constant; limited, they do not.

mod common;

use volcache::flatland::cached_field::{CacheMethod, CacheSettings, RecordMemo, render_cached};
use volcache::flatland::field::{FieldParams, field_errors, render_field};
use volcache::flatland::scene::Scene;
use volcache::progress::Progress;

/// 9 mean free paths across the domain's short side, albedo 0.93, g = 0.9; the
/// shade throws the light's cone downwards onto a floor.
const SHADED_POINT: &str = r#"{
  "domain": {"min": [-1, -1], "max": [1, 0.8]},
  "segments": [
    {"name": "shade", "a": [-0.35, 0.45], "b": [0.3, 0.5], "reflectance": 0.4},
    {"name": "floor", "a": [-1, -1], "b": [1, -1], "reflectance": 0.3}
  ],
  "lights": [{"type": "point", "position": [-0.05, 0.3], "intensity": 1.2}],
  "medium": {"sigma_a": 0.35, "sigma_s": 4.65, "g": 0.9, "region": "everywhere"},
  "render": {"resolution": [48, 40], "spp": 16, "seed": 1}
}"#;

fn settings(seed: u64, reach: bool) -> CacheSettings {
    let mut cs = CacheSettings::new::<volcache::core::space::D2>(CacheMethod::Ours, 0.025, Default::default());
    (cs.probe.rays, cs.probe.steps, cs.seed) = (256, 16, seed);
    cs.gradient_noise_reach = reach;
    cs
}

/// At ε 0.025 and 256 directions (a 2D budget 1's): the reach binds where the
/// gradients are noisy, so placement needs more records to cover the field
/// (seeds 1–4: 398 / 316 / 335 / 385 → 769 / 711 / 742 / 742, 1.9–2.25×), every
/// record stays finite and no pixel is left uncovered.
#[test]
fn noisy_gradients_reach_less_far_in_2d() {
    let s = Scene::from_json(SHADED_POINT, "<shaded point>").unwrap_or_else(|e| panic!("{e}"));
    let fp = FieldParams::from_scene(&s);
    let run = |reach| {
        let c = render_cached(
            &s,
            &fp,
            &settings(1, reach),
            None,
            &mut RecordMemo::new(),
            &Progress::new(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(c.uncovered_pixels, 0);
        let records = c.records.concat();
        assert!(
            records
                .iter()
                .all(|r| r.radii.iter().all(|x| x.is_finite() && *x > 0.0))
        );
        (records.len(), c.field)
    };
    let ((without, _), (with, field)) = (run(false), run(true));
    println!("records {without} without the reach, {with} with it");
    assert!(with as f64 >= 1.4 * without as f64, "{without} -> {with}");
    let reference = render_field(&s, &FieldParams { spp: 64, ..fp.clone() }, &Progress::new())
        .unwrap()
        .field;
    assert!(field_errors(&field, &reference).rmse.is_finite());
}

/// `render3d --gradient-noise-reach` turns it on (the summary's settings say so),
/// also beside `--budget`, which leaves it off; on a lamp in forward-scattering
/// fog it places more records (budget ¼ at 12×9, seed 1).
#[test]
fn render3d_takes_the_gradient_noise_reach() {
    let d = tempfile::tempdir().unwrap();
    let scene = d.path().join("hanging.json");
    std::fs::write(&scene, common::HANGING_LAMP_3D).unwrap();
    let run = |extra: &[&str]| -> serde_json::Value {
        let out = d.path().join(format!("out{}", extra.len()));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_volcache"))
            .args([
                "render3d", "--method", "ours", "--budget", "0.25", "--res", "12x9", "--quiet", "--out",
            ])
            .arg(&out)
            .arg(&scene)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&std::fs::read(out.join("hanging_ours.json")).unwrap()).unwrap()
    };
    let (off, on) = (run(&[]), run(&["--gradient-noise-reach"]));
    assert!(
        off["cache"]["settings"].get("gradient_noise_reach").is_none(),
        "{}",
        off["cache"]["settings"]
    );
    assert_eq!(on["cache"]["settings"]["gradient_noise_reach"], true);
    let count = |v: &serde_json::Value| v["cache"]["records"].as_u64().unwrap();
    println!("records {} without the reach, {} with it", count(&off), count(&on));
    assert!(count(&on) > count(&off));
}
