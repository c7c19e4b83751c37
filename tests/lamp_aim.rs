//! Legs aimed near point lamps (`pipeline::lamp_aim`), against exact references.
//!
//! A point lamp of intensity I in an unbounded isotropic medium: the fluence of
//! light scattered exactly n times, φ_n = 4π I σ_s^n K^{*(n+1)} (φ₀ = I e^{−σ_t r}/r²;
//! each scattering emits σ_s φ/(4π) per unit solid angle), with the kernel
//! K(r) = e^{−σ_t r}/(4πr²), is radial, and K's Fourier transform is
//! arctan(k/σ_t)/k, so φ_n(r) = 4π I σ_s^n/(2π² r) ∫₀^∞ k sin(kr) (arctan(k/σ_t)/k)^{n+1} dk
//! — a one-dimensional quadrature. A medium point's L_s has as multiple part
//! σ_s/(4π) Σ φ_n over the orders a path of `max_depth` vertices reaches.
//!
//! Deep in fog (2.5 mean free paths from the lamp), next to it (0.75) and in thin
//! fog, the aimed legs must be within 4 standard errors with a small standard
//! error; without them (`aimed_legs: false`) the standard error is far larger, or —
//! where it lies — the mean misses by far more. 11 mean free paths from the lamp,
//! the legs that sample it beyond their first mean free path (`pipeline::point_leg`)
//! must find its once-scattered light.

mod common;

use common::{Fixture, Spec};
use std::f64::consts::PI;
use volcache::core::color::{Rgb, luminance};
use volcache::core::space::{D2, D3};
use volcache::pipeline::path::{Query, Settings, sample_query};

/// ∫₀^U g(u) du by the midpoint rule with `n` pieces.
fn midpoint(g: impl Fn(f64) -> f64, upper: f64, n: usize) -> f64 {
    let du = upper / n as f64;
    (0..n).map(|i| g((i as f64 + 0.5) * du)).sum::<f64>() * du
}

/// φ₁ + … + φ_orders at distance `r` (orders 1 or 2) per unit intensity.
fn exact_fluence(sigma_t: f64, sigma_s: f64, r: f64, orders: usize) -> f64 {
    let a = sigma_t * r;
    let (upper, n) = (4000.0, 4_000_000);
    // Order 1: ∫ sin(kr) arctan²(k/σ)/k dk = ∫ sin(au) arctan²u/u du
    //   = π³/8 − ∫ sin(au) (π²/4 − arctan²u)/u du, whose integrand falls as 1/u²
    //   (the tail past U, ≈ π cos(aU)/(aU²), is below 10⁻⁷ here).
    let rest = midpoint(|u| (a * u).sin() * (PI * PI / 4.0 - u.atan().powi(2)) / u, upper, n);
    let j1 = PI.powi(3) / 8.0 - rest;
    let mut phi = 4.0 * PI * sigma_s / (2.0 * PI * PI * r) * j1;
    if orders >= 2 {
        // Order 2: ∫ sin(kr) arctan³(k/σ)/k² dk = (1/σ) ∫ sin(au) arctan³u/u² du.
        let j2 = midpoint(|u| (a * u).sin() * u.atan().powi(3) / (u * u), upper, n) / sigma_t;
        phi += 4.0 * PI * sigma_s * sigma_s / (2.0 * PI * PI * r) * j2;
    }
    phi
}

const INTENSITY: Rgb = Rgb::new(4.0, 3.5, 3.0);

fn scene<F: Fixture>(sigma_a: f64, sigma_s: f64, g: f64) -> F::W {
    F::scene(&Spec {
        point_light: Some(([0.0, 0.0, 0.0], INTENSITY)),
        medium: Some((Rgb::splat(sigma_a), Rgb::splat(sigma_s), g)),
        ..Spec::default()
    })
}

/// Per-sample luminance of L_s's multiple part at `x` (looking along +y).
fn samples<F: Fixture>(world: &F::W, x: [f64; 3], aimed: bool, depth: u32, n: u64, seed: u64) -> Vec<f64> {
    let settings = Settings {
        aimed_legs: aimed,
        max_depth: depth,
        ..Settings::default()
    };
    let q = Query::InScattered {
        omega_o: F::point([0.0, 1.0, 0.0]),
    };
    let mut rays = 0;
    (0..n)
        .map(|k| {
            let mut s = settings.sample_stream(seed, 0, k);
            luminance(sample_query(world, F::point(x), &q, &settings, &mut s, &mut rays).multiple)
        })
        .collect()
}

/// (mean, standard error, max/mean).
fn stats(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt(), v.iter().cloned().fold(0.0, f64::max) / mean)
}

/// One case: σ_a, σ_s, the distance from the lamp, and bounds measured over seeds
/// 1–3 at depths 1 and 2 (every bound has margin over its measurement).
struct Case {
    name: &'static str,
    sigma_a: f64,
    sigma_s: f64,
    r: f64,
    /// Largest relative standard error of the aimed estimate (measured 0.0165,
    /// 0.0055, 0.0106).
    max_rel_se: f64,
    /// Largest relative error of the aimed estimate (measured 0.023, 0.0051,
    /// 0.0098).
    max_rel_err: f64,
    /// Without aimed legs the standard error is at least this many times larger
    /// (measured ≥ 1.8, ≥ 2.9, ≥ 1.5), unless the mean is more than 6 of its own
    /// standard errors off.
    min_gain: f64,
}

const CASES: [Case; 3] = [
    // 2.5 mean free paths from the lamp, albedo 0.96.
    Case {
        name: "deep",
        sigma_a: 0.1,
        sigma_s: 2.4,
        r: 1.0,
        max_rel_se: 0.025,
        max_rel_err: 0.05,
        min_gain: 1.4,
    },
    // 0.75 mean free paths from it.
    Case {
        name: "near",
        sigma_a: 0.1,
        sigma_s: 2.4,
        r: 0.3,
        max_rel_se: 0.008,
        max_rel_err: 0.015,
        min_gain: 2.2,
    },
    // Thin fog, 0.55 mean free paths.
    Case {
        name: "thin",
        sigma_a: 0.05,
        sigma_s: 0.5,
        r: 1.0,
        max_rel_se: 0.016,
        max_rel_err: 0.03,
        min_gain: 1.2,
    },
];

const SAMPLES: u64 = 40_000;

fn seeds() -> u64 {
    std::env::var("SEEDS").map_or(2, |v| v.parse().unwrap())
}

#[test]
fn aimed_legs_match_the_exact_orders_of_scattering() {
    for c in &CASES {
        let world = scene::<D3>(c.sigma_a, c.sigma_s, 0.0);
        let x = [c.r * 0.6, c.r * 0.8, 0.0];
        for depth in [1, 2] {
            let exact = exact_fluence(c.sigma_a + c.sigma_s, c.sigma_s, c.r, depth as usize);
            let want = c.sigma_s / (4.0 * PI) * exact * luminance(INTENSITY);
            for seed in 1..=seeds() {
                let (m, se, peak) = stats(&samples::<D3>(&world, x, true, depth, SAMPLES, seed));
                let (pm, pse, ppeak) = stats(&samples::<D3>(&world, x, false, depth, SAMPLES, seed));
                let what = format!("{} depth {depth} seed {seed}", c.name);
                eprintln!(
                    "{what}: exact {want:.5}; aimed {:+.4} rel se {:.4} max/mean {peak:.0}; plain {:+.4} rel se {:.4} max/mean {ppeak:.0}",
                    m / want - 1.0,
                    se / want,
                    pm / want - 1.0,
                    pse / want
                );
                assert!(
                    se / want <= c.max_rel_se,
                    "{what}: relative standard error {}",
                    se / want
                );
                assert!((m / want - 1.0).abs() <= c.max_rel_err, "{what}: {m} vs {want}");
                assert!(
                    (m - want).abs() <= 4.0 * se,
                    "{what}: {:.1} standard errors off",
                    (m - want).abs() / se
                );
                let off = (pm - want).abs() / pse.max(f64::MIN_POSITIVE);
                assert!(
                    pse >= c.min_gain * se || off > 6.0,
                    "{what}: plain legs are as good: standard error {pse} vs {se}"
                );
            }
        }
    }
}

/// 11 mean free paths from the lamp the light scattered twice comes mostly from
/// legs that pass within a few mean free paths of it far from their start, where
/// free flight seldom scatters (e^−σt): legs sample the lamp there too
/// (`pipeline::point_leg`). Measured over seeds 1–8 at 400,000 samples: −3.5% …
/// +2.5%, within 1.7 standard errors (relative 0.020–0.038); sampling only legs
/// that pass within one mean free path gave −7% … −28%, at 0.6–9.4 of standard
/// errors that lie (−15% or worse on seeds 1–2).
///
/// Three scatterings (depth 2) are still low there, −12% … −16% at 3–5 standard
/// errors, and are not asserted: they come from path vertices near the lamp, which
/// free flight places with probability ∝ e^−σt whatever the legs sample.
#[test]
fn legs_far_from_their_start_find_the_lamp() {
    let (sigma_a, sigma_s, r) = (0.1, 2.4, 4.4);
    let world = scene::<D3>(sigma_a, sigma_s, 0.0);
    let exact = exact_fluence(sigma_a + sigma_s, sigma_s, r, 1);
    let want = sigma_s / (4.0 * PI) * exact * luminance(INTENSITY);
    for seed in 1..=seeds() {
        let (m, se, peak) = stats(&samples::<D3>(
            &world,
            [r * 0.6, r * 0.8, 0.0],
            true,
            1,
            10 * SAMPLES,
            seed,
        ));
        eprintln!(
            "far seed {seed}: exact {want:.6}; {:+.4} ({:.1} se), rel se {:.4}, max/mean {peak:.0}",
            m / want - 1.0,
            (m - want) / se,
            se / want
        );
        assert!(se / want <= 0.06, "seed {seed}: relative standard error {}", se / want);
        assert!((m / want - 1.0).abs() <= 0.08, "seed {seed}: {m} vs {want}");
        assert!(
            (m - want).abs() <= 4.0 * se,
            "seed {seed}: {:.1} standard errors off",
            (m - want).abs() / se
        );
    }
}

/// With anisotropic phases (where the legs' shares weigh the phase against the
/// cone) the aimed estimate agrees with the plain one in thin fog, where the
/// plain one's standard error is honest.
#[test]
fn aimed_legs_agree_with_plain_paths_for_anisotropic_phases() {
    for g in [0.6, -0.9] {
        let world = scene::<D3>(0.05, 0.5, g);
        let x = [0.6, 0.8, 0.0];
        for seed in 1..=seeds() {
            let (m, se, _) = stats(&samples::<D3>(&world, x, true, 3, 4 * SAMPLES, seed));
            let (pm, pse, _) = stats(&samples::<D3>(&world, x, false, 3, 4 * SAMPLES, seed + 10));
            let both = (se * se + pse * pse).sqrt();
            eprintln!("g = {g} seed {seed}: aimed {m:.5} ± {se:.5}, plain {pm:.5} ± {pse:.5}");
            assert!(
                (m - pm).abs() <= 4.0 * both,
                "g = {g} seed {seed}: {m} vs {pm} (± {both})"
            );
            assert!(se <= 0.02 * m, "g = {g} seed {seed}: standard error {se} of {m}");
        }
    }
}

/// 2D has no tail to bound: its paths draw exactly what they drew before.
#[test]
fn flatland_paths_are_not_aimed() {
    let world = scene::<D2>(0.1, 2.4, 0.6);
    let a = samples::<D2>(&world, [0.6, 0.8, 0.0], true, 8, 2_000, 1);
    let b = samples::<D2>(&world, [0.6, 0.8, 0.0], false, 8, 2_000, 1);
    assert_eq!(a, b);
}
