//! The aware multiple-scattering gradient in anisotropic fog, in 2D and 3D, against
//! converged finite differences of the path tracer, on scenes of their own (issue 12
//! item 3: median vector error < 20%, no sign errors, at ≥ 8 points where the
//! gradient stands well above the reference's noise).
//!
//! A probe's medium sample m is seen from x along ω = (m − x)/r; with an anisotropic
//! phase what m sends towards x turns with ω as x moves. Holding each sample's light
//! fixed left out ∫K ∂_ωL ∇_x ω dm, log-divergent near x: gradients too long or too
//! short by factors (2D, g = 0.6: median vector error 1.57, lengths 0.8–4.5× the
//! reference; g = −0.5: 1.10, 0.13–1.1×; 3D fog box, g = 0.3, graded march: 1.1–2.4,
//! 2–3.4×). The probe now estimates each sample's direction gradient
//! (`pipeline::path::scattered_with_slope`) and the derivatives carry it
//! (`pipeline::derivatives::medium_point`). Each case also compares the gradient
//! without those slopes against the same reference.
//!
//! The references are the mean of 20 (2D, 40k spp) or 40 (3D, 16k spp) seeds,
//! stored in `tests/references/` (see `tests/stored`; they cost 170 s a run) and
//! checked live at two points per case on 4 (2D) or 8 (3D) fresh seeds: scaling a
//! stored case by 0.85 (2D) or 0.8 (3D) put a live point 4.4–4.5 standard
//! deviations off and failed;
//! points where their relative standard error is 0.1 or more are skipped (2D,
//! g = −0.5: two of twelve, gradients 0.046 and 0.076), the others' is 0.01–0.07
//! (2D) and 0.03–0.09 (3D). (With 4 and 8 seeds, as this test had before, it was
//! 0.02–0.44 and the medians, 0.12–0.39, measured mostly the reference.)
//! Median vector error over points and aware seeds 5–8 (each seed's own median in
//! brackets; seeds 9–12 in braces):
//! - 2D, 4096 directions: g = 0.6 0.116 (0.081–0.229) {0.146 (0.084–0.216)};
//!   g = −0.5 0.077 (0.064–0.102) {0.068 (0.067–0.098)}. At the 2D default of
//!   1024 directions (references of 20 seeds, seeds 5–12 pooled) 0.156 and 0.115.
//! - 3D, 4096 directions, the default even march: 0.140 (0.111–0.189) {0.138
//!   (0.119–0.153)}. It was 0.39 (lengths 0.34–0.62 of the reference, the same for
//!   every seed) before the gradient's kernel was smoothed over at most 0.3 of the
//!   march's first step (`derivatives::GRADIENT_SMOOTHING_CAP`).
//!
//! Without slopes the medians are 1.1–1.5. No component of a quarter of the
//! reference's length or more had its sign wrong.
//!
//! One 3D point, under the box and 0.1 inside its edge, was 0.41–0.61 off, every
//! seed alike (the mean of seeds 5–12 0.48 off, 0.59 of the reference's length),
//! unmoved by 4× the directions, 4× the steps, the clamp or the grading, and
//! without the floor or the box's reflection. The bridging shell pieces at the
//! box's edge carried their samples' sum over the vertex count (the value's
//! weight) into the derivatives too, while what the edge reveals as x moves is the
//! light next to it. Their gradients now carry the mean of the nearby samples of
//! their shell (`proxy::Element::revealed`; the Hessians keep the weight): that
//! point's seed mean is 0.29–0.33 off (seeds 5–8, 9–12), the worst of any point. Before: 3D median 0.154
//! {0.162}; 2D g = 0.6 0.106 {0.146}, g = −0.5 0.094 {0.085}; at 1024 directions
//! 0.160 and 0.130. With the pieces' own samples only, the 2D pieces (one sample
//! each) doubled their noise (g = 0.6: 0.157).
//! Bounds: the issue's 0.2 on the median over points and seeds, 0.25 on each
//! seed's, at most 0.3× the error without slopes, 0.4 on the aware seeds' mean at
//! every point (0.48 before the revealed light), at least 8 points checked.

use glam::{DVec2, DVec3};
use std::path::Path;
use volcache::core::space::{D2, D3, Space};
use volcache::pipeline::derivatives::{AwareSettings, ReferenceSettings, aware, reference};
use volcache::pipeline::dim::Dim;
use volcache::pipeline::path::Settings;
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy::build;
use volcache::pipeline::world::World;
use volcache::progress::Progress;

mod stored;

/// A 2D room of its own: a two-sided emitter on the left, a slanted reflective
/// occluder in front of it, a floor, fog everywhere with phase g.
fn flatland_json(g: f64) -> String {
    format!(
        r#"{{ "domain": {{"min": [-1, -1], "max": [1, 1]}},
            "segments": [
              {{"name": "emitter", "a": [-0.8, -0.3], "b": [-0.8, 0.3], "emission": 5.0, "two_sided": true}},
              {{"name": "occluder", "a": [-0.35, -0.15], "b": [-0.2, 0.35], "reflectance": 0.5}},
              {{"name": "floor", "a": [-1, -0.8], "b": [1, -0.8], "reflectance": 0.6}}
            ],
            "medium": {{"sigma_a": 0.1, "sigma_s": 0.9, "g": {g}, "region": "everywhere"}},
            "render": {{"resolution": [64, 64], "spp": 16, "seed": 1}} }}"#
    )
}

/// A 3D room of its own: floor and back wall, a small emitter high on the left
/// shining down, a box occluder below it, fog in a box with phase g.
fn volume_json(g: f64) -> String {
    format!(
        r#"{{ "camera": {{"position": [0, 1, 4], "look_at": [0, 1, 0], "fov_deg": 40}},
            "shapes": [
              {{"quad": {{"origin": [-1.5, 0, -1.5], "u": [0, 0, 3], "v": [3, 0, 0]}}, "reflectance": 0.6}},
              {{"quad": {{"origin": [-1.5, 0, -1.5], "u": [3, 0, 0], "v": [0, 2.5, 0]}}, "reflectance": 0.5}},
              {{"box": {{"min": [-0.7, 0.6, -0.4], "max": [-0.2, 0.9, 0.3]}}, "reflectance": 0.5}},
              {{"quad": {{"origin": [-0.9, 1.8, -0.3], "u": [0.6, 0, 0], "v": [0, 0, 0.6]}},
                "reflectance": 0, "emission": [12, 10, 8], "two_sided": false}}
            ],
            "medium": {{"sigma_a": 0.05, "sigma_s": 0.45, "g": {g},
                        "region": {{"box": {{"min": [-1.5, 0, -1.5], "max": [1.5, 2.5, 1.5]}}}}}},
            "render": {{"resolution": [32, 32], "spp": 16, "seed": 1, "max_depth": 32}} }}"#
    )
}

/// The multiple-scattering luminance gradient's reference at x: the mean of `seeds`
/// finite-difference estimates from `first_seed` on, and its relative standard error.
fn reference_gradient<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    spp: u32,
    seeds: u64,
    first_seed: u64,
) -> (<W::S as Space>::Vec, f64) {
    let out = Outgoing::Direction(<W::S as Space>::axis(0));
    let h = ReferenceSettings::default().relative_step * world.scale();
    let settings = Settings {
        max_depth: MAX_DEPTH,
        ..Settings::default()
    };
    let refs: Vec<_> = (first_seed..first_seed + seeds)
        .map(|s| {
            reference(world, x, out, h, spp, &settings, s, false)
                .parts
                .multiple
                .luminance()
                .grad
        })
        .collect();
    let n = seeds as f64;
    let mean = refs.iter().fold(<W::S as Space>::zero(), |a, &b| a + b) / n;
    let var: f64 = refs
        .iter()
        .map(|&r| <W::S as Space>::length_squared(r - mean))
        .sum::<f64>()
        / (n - 1.0);
    (mean, (var / n).sqrt() / <W::S as Space>::length(mean))
}

fn components<S: Space>(v: S::Vec) -> Vec<f64> {
    (0..S::DIM).map(|i| S::dot(v, S::axis(i))).collect()
}

fn from_components<S: Space>(c: &[f64]) -> S::Vec {
    c.iter().enumerate().fold(S::zero(), |v, (i, &ci)| v + S::axis(i) * ci)
}

/// The references' path depth (part of their stored key).
const MAX_DEPTH: u32 = 32;

/// The stored references' first seed.
const REFERENCE_SEED: u64 = 101;

/// The references at `points` (gradient, relative standard error), stored in
/// `tests/references/<name>.json` while the scene and settings are the same
/// (`tests/stored`); computed and not stored otherwise.
fn references<W: World>(
    world: &W,
    scene_json: &str,
    points: &[<W::S as Space>::Vec],
    spp: u32,
    seeds: u64,
    name: &str,
) -> Vec<(<W::S as Space>::Vec, f64)> {
    let key = format!(
        "scene {scene_json}\npoints {points:?}\nluminance gradient of multiple scattering towards axis 0, \
         {spp} spp x seeds {REFERENCE_SEED}..{}, max depth {MAX_DEPTH}, relative step {}",
        REFERENCE_SEED + seeds,
        ReferenceSettings::default().relative_step
    );
    let stored: Vec<(Vec<f64>, f64)> = stored::load_or_compute(name, &key, || {
        points
            .iter()
            .map(|&x| {
                let (mean, se) = reference_gradient(world, x, spp, seeds, REFERENCE_SEED);
                (components::<W::S>(mean), se)
            })
            .collect()
    });
    stored.iter().map(|(c, se)| (from_components::<W::S>(c), *se)).collect()
}

/// Points recomputed live on fresh seeds against the stored references.
const LIVE_POINTS: usize = 2;
const LIVE_SEED: u64 = 9001;

/// The code must still compute the stored references in expectation: the
/// `LIVE_POINTS` best-converged points are recomputed on `live_seeds` fresh seeds
/// and must agree with the stored means within four standard deviations of their
/// difference (`stored::agrees`).
fn check_references_live<W: World>(
    world: &W,
    points: &[<W::S as Space>::Vec],
    refs: &[(<W::S as Space>::Vec, f64)],
    spp: u32,
    seeds: u64,
    live_seeds: u64,
    what: &str,
) {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| refs[a].1.total_cmp(&refs[b].1));
    for &i in order.iter().take(LIVE_POINTS) {
        let (stored_mean, stored_rel_se) = refs[i];
        let (live, _) = reference_gradient(world, points[i], spp, live_seeds, LIVE_SEED);
        let stored_se = stored_rel_se * <W::S as Space>::length(stored_mean);
        let (ok, z) = stored::agrees(
            &components::<W::S>(live),
            live_seeds as usize,
            &components::<W::S>(stored_mean),
            stored_se,
            seeds as usize,
        );
        eprintln!(
            "{what} x = {:?}: live reference {live:.4?} against stored {stored_mean:.4?}: {z:.2} s.d.",
            points[i]
        );
        assert!(
            ok,
            "{what} x = {:?}: the live reference {live:?} is {z:.1} standard deviations from the stored \
             {stored_mean:?}: the path tracer changed what it computes, or the stored file is wrong",
            points[i]
        );
    }
}

/// The aware multiple-scattering luminance gradient of one probe.
fn aware_gradient<W: World>(
    world: &W,
    x: <W::S as Space>::Vec,
    ps: &ProbeSettings,
    seed: u64,
) -> (<W::S as Space>::Vec, f64) {
    let out = Outgoing::Direction(<W::S as Space>::axis(0));
    let lf = capture(world, x, out, ps, seed, 0, &Progress::new()).unwrap();
    let aw = AwareSettings::default();
    let m = aware(&lf, &build(&lf, aw.rule), &aw).multiple.luminance();
    (m.grad, m.value)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

const AWARE_SEEDS: std::ops::Range<u64> = 5..9;

/// Bound on the error of the aware seeds' mean gradient at every point: no point
/// may stay systematically off (see the module's note).
const WORST_POINT: f64 = 0.4;

/// Points where the reference's relative standard error is this or more are not
/// checked: the gradient there is not well above the reference's noise.
const MAX_REFERENCE_NOISE: f64 = 0.1;

/// Checks the aware gradient with slopes against the reference at `points` (see
/// the module's note for the bounds).
fn check<W: World>(
    world: &W,
    points: &[<W::S as Space>::Vec],
    refs: &[(<W::S as Space>::Vec, f64)],
    ps: &ProbeSettings,
    what: &str,
) {
    let d = <W::S as Space>::DIM;
    let seeds = AWARE_SEEDS.count();
    let (mut per_seed, mut all_with, mut all_without) = (vec![vec![]; seeds], vec![], vec![]);
    let (mut sign_errors, mut checked, mut worst_mean) = (vec![], 0, 0.0f64);
    for (&x, &(r, se)) in points.iter().zip(refs) {
        if se >= MAX_REFERENCE_NOISE {
            eprintln!("{what} x = {x:?}: skipped, the reference's relative standard error is {se:.3}");
            continue;
        }
        checked += 1;
        let rel = |g| <W::S as Space>::length(g - r) / <W::S as Space>::length(r);
        let mut line = format!("{what} x = {x:?}: reference {r:.4?} (rel. s.e. {se:.3}) | with slopes");
        let mut mean = <W::S as Space>::zero();
        for (k, seed) in AWARE_SEEDS.enumerate() {
            let (with, value) = aware_gradient(world, x, ps, seed);
            mean += with / seeds as f64;
            let (without, value_without) = aware_gradient(world, x, &ProbeSettings { slopes: false, ..*ps }, seed);
            // The slopes replay NEE on cloned streams: the value's own draws are untouched.
            assert_eq!(
                value, value_without,
                "{what} x = {x:?}: the value changed with the slopes"
            );
            for i in 0..d {
                let e = <W::S as Space>::axis(i);
                let (ri, gi) = (<W::S as Space>::dot(r, e), <W::S as Space>::dot(with, e));
                if ri.abs() >= 0.25 * <W::S as Space>::length(r) && ri * gi <= 0.0 {
                    sign_errors.push(format!("x = {x:?} seed {seed} component {i}: {gi} against {ri}"));
                }
            }
            line += &format!(" {:.3}", rel(with));
            per_seed[k].push(rel(with));
            all_with.push(rel(with));
            all_without.push(rel(without));
        }
        eprintln!("{line} | their mean {:.3}", rel(mean));
        worst_mean = worst_mean.max(rel(mean));
    }
    let seed_medians: Vec<f64> = per_seed.into_iter().map(median).collect();
    let (with, without) = (median(all_with), median(all_without));
    eprintln!(
        "{what}: median error {with:.3} (per seed {seed_medians:.3?}), without slopes {without:.3}, \
         worst point's seed mean {worst_mean:.3}"
    );
    assert!(checked >= 8, "{what}: only {checked} points with a converged reference");
    assert!(sign_errors.is_empty(), "{what}: sign errors {sign_errors:?}");
    assert!(with < 0.2, "{what}: median gradient error {with}");
    for m in seed_medians {
        assert!(m < 0.25, "{what}: one seed's median gradient error {m}");
    }
    assert!(with < 0.3 * without, "{what}: {with} with slopes, {without} without");
    assert!(
        worst_mean < WORST_POINT,
        "{what}: the aware seeds' mean gradient is {worst_mean} off at one point"
    );
}

const POINTS_2D: [[f64; 2]; 12] = [
    [-0.5, 0.0],
    [0.0, 0.1],
    [0.2, -0.3],
    [-0.5, 0.5],
    [0.4, 0.4],
    [-0.1, -0.5],
    [-0.6, -0.5],
    [0.6, -0.6],
    [0.0, 0.6],
    [-0.65, 0.2],
    [-0.3, -0.3],
    [0.5, 0.1],
];

fn check_2d(g: f64, name: &str) {
    let points: Vec<DVec2> = POINTS_2D.iter().map(|p| DVec2::from(*p)).collect();
    let json = flatland_json(g);
    let scene = volcache::flatland::scene::Scene::from_json(&json, "<test>").unwrap_or_else(|e| panic!("{e}"));
    let what = format!("2D g = {g}");
    let (spp, seeds) = (40_000, 20);
    let refs = references(&scene, &json, &points, spp, seeds, name);
    check_references_live(&scene, &points, &refs, spp, seeds, 4, &what);
    check(&scene, &points, &refs, &ProbeSettings::with_rays::<D2>(4096), &what);
}

#[test]
fn multiple_scattering_gradient_in_forward_scattering_fog_2d() {
    check_2d(0.6, "anisotropic_multiple_scattering_2d_g0.6");
}

#[test]
fn multiple_scattering_gradient_in_backward_scattering_fog_2d() {
    check_2d(-0.5, "anisotropic_multiple_scattering_2d_g-0.5");
}

#[test]
fn multiple_scattering_gradient_in_anisotropic_fog_3d() {
    let points: Vec<DVec3> = [
        [0.3, 0.8, 0.2],
        [-0.5, 1.4, 0.4],
        [-0.6, 1.5, 0.0],
        [0.0, 1.6, 0.0],
        [-1.0, 1.2, 0.2],
        [-0.45, 1.0, 0.0],
        [-0.6, 0.3, 0.0],
        [0.2, 1.2, -0.5],
        [-1.2, 0.5, 0.5],
        [0.6, 1.0, 0.6],
        [-0.2, 1.3, 0.6],
        [-0.8, 0.8, -0.8],
    ]
    .iter()
    .map(|p| DVec3::from(*p))
    .collect();
    let json = volume_json(0.5);
    let scene =
        volcache::volume::scene::Scene::from_json(&json, "<test>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let what = "3D g = 0.5";
    let (spp, seeds) = (16_384, 40);
    let refs = references(
        &scene,
        &json,
        &points,
        spp,
        seeds,
        "anisotropic_multiple_scattering_3d_g0.5",
    );
    check_references_live(&scene, &points, &refs, spp, seeds, 8, what);
    // The 3D defaults: 4096 directions, an even march.
    check(
        &scene,
        &points,
        &refs,
        &ProbeSettings::with_rays::<D3>(<D3 as Dim>::PROBE_RAYS),
        what,
    );
}
