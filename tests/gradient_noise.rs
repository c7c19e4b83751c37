//! Records extrapolate with their multiple-scattering gradient shrunk by its own
//! noise (`CacheSettings::shrink_noisy_gradients`,
//! `RecordData::payload_to_extrapolate`). On a scene of our own — a point light
//! beside a tilted plate in thick, forward-scattering fog over a floor — the noise
//! estimate follows the gradient's spread over record seeds, and shrinking lowers
//! the field's error at equal records. In 3D, on a lamp hanging in forward-scattering
//! fog, the noise estimate follows the spread too.

mod common;

use glam::{DVec2, DVec3};
use volcache::core::color::luminance;
use volcache::core::space::{D2, Space};
use volcache::flatland::cached_field::{CacheMethod, CacheSettings, RecordMemo, render_cached};
use volcache::flatland::field::{FieldParams, field_errors, render_field};
use volcache::flatland::scene::Scene;
use volcache::pipeline::dim::Dim;
use volcache::pipeline::probe::Outgoing;
use volcache::pipeline::record::compute_record;
use volcache::pipeline::world::{VecOf, World};
use volcache::progress::Progress;

fn scene() -> Scene {
    common::noisy_fog_2d()
}

fn settings<S: Dim>(seed: u64, shrink: bool) -> CacheSettings {
    let mut cs = CacheSettings::new::<S>(CacheMethod::Ours, 0.05, Default::default());
    cs.probe.rays = 1024;
    cs.probe.steps = 16;
    cs.seed = seed;
    cs.shrink_noisy_gradients = shrink;
    cs
}

/// The estimated noise variance of the multiple part's luminance gradient,
/// averaged over `n` record seeds, against that gradient's spread over the same
/// seeds, at each point; every ratio within `bounds`.
fn estimate_follows_spread<W: World>(
    world: &W,
    points: &[VecOf<W>],
    out: impl Fn(VecOf<W>) -> VecOf<W>,
    rays: usize,
    n: u64,
    bounds: std::ops::Range<f64>,
) where
    VecOf<W>: std::fmt::Debug,
{
    let progress = Progress::new();
    for &x in points {
        let (mut grads, mut estimated) = (Vec::new(), 0.0);
        for seed in 0..n {
            let mut cs = settings::<W::S>(100 + seed, true);
            cs.probe.rays = rays;
            let r = compute_record(world, x, Outgoing::Direction(out(x)), &cs, 0, &progress).unwrap();
            grads.push(r.parts.multiple.luminance().grad);
            estimated += r.multiple_grad_var / n as f64;
        }
        let mean = grads.iter().fold(W::S::zero(), |a, &g| a + g) * (1.0 / n as f64);
        let spread = grads.iter().map(|&g| W::S::length_squared(g - mean)).sum::<f64>() / (n - 1) as f64;
        let ratio = estimated / spread;
        println!(
            "{x:?}: |mean gradient|² {:.3e}, spread {spread:.3e}, estimated {estimated:.3e} (ratio {ratio:.2})",
            W::S::length_squared(mean)
        );
        assert!(
            bounds.contains(&ratio),
            "{x:?}: estimated {estimated:.3e} vs spread {spread:.3e}"
        );
    }
}

/// At points near and far from the light, in the plate's shadow and beside it,
/// over 24 record seeds of 1024 directions. Measured ratios 1.58, 1.49, 1.20, 0.84
/// (the estimate counts the integrand's change across a stratum as noise, so it
/// may err high; a residual against the neighbours' mean, which removes that
/// change to first order, gave the same ratios within 0.03: here the excess is not
/// that change); bounds 0.5–4.
#[test]
fn the_noise_estimate_follows_the_gradients_spread() {
    let points = [
        DVec2::new(0.4, 0.1),
        DVec2::new(-0.5, -0.4),
        DVec2::new(-0.1, 0.8),
        DVec2::new(0.6, -0.6),
    ];
    estimate_follows_spread(&scene(), &points, |_| DVec2::new(0.6, -0.8), 1024, 24, 0.5..4.0);
}

/// The same in 3D, on a lamp hanging in g = 0.85 fog, where the gradient of a
/// record of 256 directions is mostly noise (|mean|² a tenth of the spread or
/// less): under the lamp, beside it, low under it, far and high in a corner,
/// towards the camera. Measured over three sets of 24 seeds, 256 and 1024 directions: ratios
/// 0.71–1.44 (mean 1.07), so the estimate does not err high next to the lamp and
/// the gradient-noise reach's extra records there answer real noise; bounds
/// 0.5–2.
#[test]
fn the_noise_estimate_follows_the_gradients_spread_in_3d() {
    let camera = DVec3::new(0.3, 1.0, 3.2);
    let points = [
        DVec3::new(-0.05, 0.95, 0.05),
        DVec3::new(0.35, 1.2, 0.05),
        DVec3::new(-0.05, 0.4, 0.05),
        DVec3::new(0.8, 0.5, 0.6),
        DVec3::new(-0.9, 1.6, -0.8),
    ];
    estimate_follows_spread(
        &common::hanging_lamp_3d(),
        &points,
        |x| (camera - x).normalize(),
        256,
        24,
        0.5..2.0,
    );
}

/// 96² field, 150 records, against a 2048-spp path-traced reference: shrinking
/// lowers the relative error for every record seed (measured relMSE ratios 0.65,
/// 0.68, 0.66 for seeds 1–3 when written, 0.59, 0.78, 0.64 since; bound 0.8: seed
/// 2 has little margin left, and a change to the 2D paths' random numbers can move
/// it past — 0.81 on seed 1 with 3D's far legs tried in 2D) and the RMSE over the
/// seeds (0.97, 0.79, 1.03 per seed: the brightest pixels, next to the light, hold
/// the RMSE and single seeds swing there).
#[test]
fn shrinking_noisy_gradients_lowers_the_error() {
    let s = scene();
    let fp = FieldParams::from_scene(&s);
    let reference = render_field(
        &s,
        &FieldParams {
            spp: 2048,
            seed: 999,
            ..fp.clone()
        },
        &Progress::new(),
    )
    .unwrap()
    .field;
    let (mut raw_sq, mut shrunk_sq) = (0.0, 0.0);
    for seed in 1..=3 {
        // Shrinking changes what a record extrapolates, not the record or where
        // placement puts it: both runs share one memo, the second computes nothing.
        let mut memo = RecordMemo::new();
        let mut run = |shrink| {
            let c = render_cached(
                &s,
                &fp,
                &settings::<D2>(seed, shrink),
                Some(150),
                &mut memo,
                &Progress::new(),
            )
            .unwrap_or_else(|e| panic!("{e}"));
            field_errors(&c.field, &reference)
        };
        let raw = run(false);
        let shrunk = run(true);
        let mean = reference.values.iter().map(|&v| luminance(v)).sum::<f64>() / reference.values.len() as f64;
        println!(
            "seed {seed}: RMSE {:.4e} → {:.4e}, relMSE {:.4e} → {:.4e} (mean {mean:.4})",
            raw.rmse, shrunk.rmse, raw.relmse, shrunk.relmse
        );
        assert!(
            shrunk.relmse < 0.8 * raw.relmse,
            "seed {seed}: relMSE {} vs {}",
            shrunk.relmse,
            raw.relmse
        );
        raw_sq += raw.rmse * raw.rmse;
        shrunk_sq += shrunk.rmse * shrunk.rmse;
    }
    assert!(shrunk_sq < raw_sq, "summed squared RMSE {shrunk_sq} vs {raw_sq}");
}
