//! `CacheSettings::direct_samples`: the light arriving straight from the lights is
//! sampled at every pixel and the records cache only the rest (2D). On a scene of
//! our own — a tilted area emitter, a reflective floor, two occluders casting
//! penumbrae into anisotropic fog, a point light — the split is exact (what the
//! records leave out is what the per-pixel estimate adds) and the field is better at
//! a low record count, where records extrapolating across shadow edges held it.

use glam::DVec2;
use volcache::core::color::{Rgb, luminance};
use volcache::core::rng::Sampler;
use volcache::flatland::cached_field::{CacheMethod, CacheSettings, RecordMemo, render_cached};
use volcache::flatland::field::{Field, FieldParams, field_errors, render_field};
use volcache::flatland::scene::Scene;
use volcache::pipeline::lobe::Lobe;
use volcache::pipeline::path::direct_at;
use volcache::pipeline::placement::CountError;
use volcache::pipeline::probe::Outgoing;
use volcache::pipeline::record::compute_record;
use volcache::pipeline::world::{VecOf, World};
use volcache::progress::Progress;
use volcache::volume::cached::RecordMemo as RecordMemo3;

const SCENE: &str = r#"{
  "domain": {"min": [-1, -1], "max": [1, 1]},
  "segments": [
    {"name": "lamp", "a": [0.55, 0.85], "b": [-0.15, 0.7], "emission": 5.0, "two_sided": false},
    {"name": "floor", "a": [-1, -0.8], "b": [1, -0.8], "reflectance": 0.7},
    {"name": "left", "a": [-0.5, 0.2], "b": [-0.05, 0.28], "reflectance": 0.4},
    {"name": "right", "a": [0.25, -0.1], "b": [0.6, -0.05], "reflectance": 0.0}
  ],
  "lights": [{"type": "point", "position": [-0.7, -0.3], "intensity": 0.4}],
  "medium": {"sigma_a": 0.15, "sigma_s": 1.2, "g": 0.5, "region": "everywhere"},
  "render": {"resolution": [64, 64], "spp": 64, "seed": 1}
}"#;

fn scene() -> Scene {
    Scene::from_json(SCENE, "<direct_per_point>").unwrap_or_else(|e| panic!("{e}"))
}

fn settings(seed: u64, direct_samples: Option<u32>) -> CacheSettings {
    let mut cs = CacheSettings::new::<volcache::core::space::D2>(CacheMethod::Ours, 0.05, Default::default());
    cs.probe.rays = 1024;
    cs.probe.steps = 8;
    cs.seed = seed;
    cs.direct_samples = direct_samples;
    cs
}

/// At points in light, in penumbra and in shadow: a record made without the
/// lights' straight light holds L_s minus exactly what `direct_at` estimates
/// there (σ_s × its mean, delta lights apart, which no record holds). The two
/// records share their directions and paths, so their difference is the light
/// field's own estimate of the straight light: it agrees with 40,000 samples of
/// `direct_at` to its angular discretisation's error.
#[test]
fn records_leave_out_what_the_pixels_add() {
    let s = scene();
    let omega_o = DVec2::new(0.6, -0.8);
    let points = [
        DVec2::new(0.1, 0.5),
        DVec2::new(-0.2, 0.05),
        DVec2::new(0.45, -0.35),
        DVec2::new(-0.75, -0.6),
        DVec2::new(0.8, 0.2),
        DVec2::new(0.0, -0.6),
    ];
    let worst = worst_split_miss(&s, &points, omega_o, |ds| settings(3, ds), 77);
    assert!(worst < 1.0, "worst {worst}");
}

/// Over `points`, the worst of |left out − added| / (1% of added + 3e-3): what a
/// record made without the straight light (`settings(Some(1))`) misses of one made
/// with it (`settings(None)`; the same directions and paths), against what a point
/// adds, σ_s × (the mean of 40,000 `direct_at` samples − the delta lights, which no
/// record holds). `stream`: the samples' seed.
fn worst_split_miss<W: World>(
    world: &W,
    points: &[VecOf<W>],
    omega_o: VecOf<W>,
    settings: impl Fn(Option<u32>) -> CacheSettings,
    stream: u64,
) -> f64
where
    VecOf<W>: std::fmt::Debug,
{
    let progress = Progress::new();
    let mut worst: f64 = 0.0;
    for (k, &x) in points.iter().enumerate() {
        let value = |cs: &CacheSettings| {
            let r = compute_record(world, x, Outgoing::Direction(omega_o), cs, k as u64, &progress).unwrap();
            luminance((r.parts.single + r.parts.multiple).value())
        };
        let left_out = value(&settings(None)) - value(&settings(Some(1)));
        let m = world.medium_at(x).unwrap();
        let lobe = Lobe::Phase {
            phase: m.phase,
            travel: -omega_o,
        };
        let (mut sampler, mut rays) = (Sampler::new(stream, k as u64), 0);
        let n = 40_000;
        let mut sum = Rgb::ZERO;
        for _ in 0..n {
            sum += direct_at(world, x, &lobe, None, &mut sampler, &mut rays);
        }
        let delta = world.direct_part(x, &lobe, &mut sampler, &mut rays);
        let added = luminance((sum / n as f64 - delta) * m.sigma_s);
        let miss = (left_out - added).abs();
        println!("{x:?}: records leave out {left_out:.5}, points add {added:.5} (difference {miss:.2e})");
        worst = worst.max(miss / (0.01 * added + 0.003));
    }
    worst
}

fn reference(s: &Scene, fp: &FieldParams) -> Field {
    render_field(
        s,
        &FieldParams {
            spp: 2048,
            seed: 999,
            ..fp.clone()
        },
        &Progress::new(),
    )
    .unwrap()
    .field
}

/// At 40 records on a 64² field, sampling the straight light per pixel (64
/// samples) beats caching it, for every record seed, and the field keeps the
/// reference's mean (nothing counted twice or lost).
#[test]
fn sampling_the_straight_light_per_pixel_beats_caching_it_at_a_low_count() {
    let s = scene();
    let mut fp = FieldParams::from_scene(&s);
    (fp.width, fp.height) = (64, 64);
    let reference = reference(&s, &fp);
    let mean = |f: &Field| f.values.iter().map(|&v| luminance(v)).sum::<f64>() / f.values.len() as f64;
    for seed in 1..=3 {
        let run = |ds| {
            render_cached(
                &s,
                &fp,
                &settings(seed, ds),
                Some(40),
                &mut RecordMemo::new(),
                &Progress::new(),
            )
            .unwrap_or_else(|e| panic!("{e}"))
        };
        let (cached, sampled) = (run(None), run(Some(64)));
        let (ec, es) = (
            field_errors(&cached.field, &reference),
            field_errors(&sampled.field, &reference),
        );
        let (mr, ms) = (mean(&reference), mean(&sampled.field));
        println!(
            "seed {seed}: cached {} records RMSE {:.4e}; per pixel {} records RMSE {:.4e}; mean {ms:.5} vs {mr:.5}",
            cached.record_count(),
            ec.rmse,
            sampled.record_count(),
            es.rmse
        );
        assert!(es.rmse < 0.8 * ec.rmse, "seed {seed}: {} vs {}", es.rmse, ec.rmse);
        assert!((ms - mr).abs() < 0.03 * mr, "seed {seed}: mean {ms} vs {mr}");
    }
}

/// 3D, a room of our own: a tilted two-sided lamp over a floor, a box between them
/// casting a penumbra into a box of fog (g = 0.5), a point light. What the records
/// leave out is what the march points add, as in 2D, to the light field's own
/// angular error: at 16384 directions the worst point of record seeds 9, 10 and 12
/// came to 0.65 of the bound (at 2048 a lamp filling 0.36 sr was 6% low for all
/// three seeds, the Fibonacci sets' shared discretisation, gone at 16384).
const ROOM: &str = r#"{
  "camera": {"position": [0, 1.2, 3.5], "look_at": [0, 0.7, 0], "fov_deg": 50},
  "shapes": [
    {"quad": {"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}, "reflectance": 0.6},
    {"box": {"min": [-0.2, 0.5, -0.3], "max": [0.3, 0.7, 0.2]}, "reflectance": 0.4},
    {"quad": {"origin": [-0.6, 1.5, -0.5], "u": [0.7, 0, 0], "v": [0, -0.2, 0.6]},
     "reflectance": 0, "emission": [20, 18, 14], "two_sided": true}
  ],
  "lights": [{"point": {"position": [1.0, 0.4, 0.5], "intensity": 1.5}}],
  "medium": {"sigma_a": 0.05, "sigma_s": 0.8, "g": 0.5, "region": {"box": {"min": [-1.5, 0, -1.5], "max": [1.5, 1.8, 1.5]}}},
  "render": {"resolution": [32, 24], "spp": 4, "seed": 5, "max_depth": 12}
}"#;

#[test]
fn records_leave_out_what_the_march_points_add_3d() {
    use glam::DVec3;
    let s = volcache::volume::scene::Scene::from_json(ROOM, "<room>", std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let omega_o = DVec3::new(0.3, -0.4, 0.866).normalize();
    let settings = |ds| {
        let mut cs = CacheSettings::new::<volcache::core::space::D3>(CacheMethod::Ours, 1.0, Default::default());
        cs.probe.rays = 16384;
        cs.probe.steps = 4;
        cs.seed = 9;
        cs.direct_samples = ds;
        cs
    };
    let points = [
        DVec3::new(0.0, 1.0, 0.0),   // between lamp and box, in light
        DVec3::new(0.05, 0.35, 0.0), // under the box: shadow and penumbra
        DVec3::new(0.6, 0.3, -0.4),  // near the penumbra's edge
        DVec3::new(-0.5, 0.4, -0.6), // below the lamp, facing it
    ];
    let worst = worst_split_miss(&s, &points, omega_o, settings, 78);
    assert!(worst < 1.0, "worst {worst}");
}

/// 3D images of the room at 32 records: the medium part against a march reference
/// on the same camera samples (two independent 16-path references, their noise
/// taken out), with the straight light sampled at every march point (8 samples)
/// and with it cached: per-point sampling is better for every record seed, and by
/// about 0.7× on average (0.61 measured with 3D silhouette cuts). The count was 30
/// until the 3D proxy cut its simplices at silhouettes: record seed 4 then placed
/// 32 records or fewer than 28.5 at any ε (the count is not monotone in ε), and
/// the search rightly reported that it missed. Such a seed is not compared (an
/// equal-count comparison has no count to compare at), and at least ten of the
/// twelve must be: since a bridging shell piece's gradient carries the light next
/// to the occluder's edge, record seed 10 places no count within 5% of 32 (the
/// nearest is 35); moving the count instead (33: seed 10 again; 34: seed 6's
/// cached image lucky, ratio 0.98) is not a fix.
#[test]
fn per_point_straight_light_in_3d_images() {
    use volcache::volume::cached::{CachedRenderParams, march_reference, render_cached};
    let s = volcache::volume::scene::Scene::from_json(ROOM, "<room>", std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut p = CachedRenderParams::from_scene(&s);
    (p.image.width, p.image.height, p.image.spp) = (24, 18, 2);
    p.march_step = s.scale / 48.0;
    p.surface_paths = 1;
    let lum = |v: &[Rgb]| -> Vec<f64> { v.iter().map(|c| luminance(*c)).collect() };
    let rms =
        |a: &[f64], b: &[f64]| (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
    let r1 = lum(&march_reference(&s, &p, 32, 1, &Progress::new()).unwrap().image.medium);
    let r2 = lum(&march_reference(&s, &p, 32, 2, &Progress::new()).unwrap().image.medium);
    let reference: Vec<f64> = r1.iter().zip(&r2).map(|(a, b)| 0.5 * (a + b)).collect();
    let noise2 = rms(&r1, &r2).powi(2) / 4.0;
    let mut ratios = Vec::new();
    for seed in 1..=12 {
        let error = |ds| {
            let mut cs = CacheSettings::new::<volcache::core::space::D3>(
                CacheMethod::Ours,
                1.0,
                p.image.first_vertex_settings(),
            );
            (cs.probe.rays, cs.probe.steps, cs.seed, cs.direct_samples) = (512, 8, seed, ds);
            match render_cached(&s, &p, &cs, Some(32), &mut RecordMemo3::new(), &Progress::new()) {
                Ok(r) => {
                    let e2 = rms(&lum(&r.reconstruction.image.medium), &reference).powi(2);
                    Ok(((e2 - noise2).max(0.0).sqrt(), r.placement.record_count()))
                }
                Err(e @ CountError::Unreachable { .. }) => Err(e),
                Err(e) => panic!("{e}"),
            }
        };
        let ((cached, kc), (sampled, ks)) = match (error(None), error(Some(8))) {
            (Ok(c), Ok(p)) => (c, p),
            (Err(e), _) | (_, Err(e)) => {
                println!("seed {seed}: not compared, {e}");
                continue;
            }
        };
        println!(
            "seed {seed}: cached {kc} records {cached:.4e}, per point {ks} records {sampled:.4e} (reference noise {:.2e})",
            noise2.sqrt()
        );
        ratios.push(sampled / cached);
    }
    // Measured since the revealed light (seeds 1-9, 11, 12; 10 not compared): 0.41,
    // 0.60, 0.45, 0.35, 0.41, 0.69, 0.30, 0.47, 0.52, 0.33, 0.72 (mean 0.48).
    // Before it (seeds 1-12): 0.71, 0.83, 0.69, 0.94, 0.68, 0.56, 0.66, 0.67, 0.62,
    // 0.70, 0.46, 0.87 (mean 0.70); with 30 records the cached image's error swings
    // with the records' luck (the same seeds before the emitter sample's draws
    // changed order gave 0.68, 0.45, 0.77, 0.44, 0.37, 0.62), so twelve seeds, not
    // four. The per-point estimate's own noise (8 samples per point, 2 camera
    // samples) is part of it.
    assert!(ratios.len() >= 10, "only {} seeds at 32 records", ratios.len());
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!(mean < 0.75 && ratios.iter().all(|&r| r < 0.95), "{ratios:?}");
}
