//! What a cache record costs and how accurate it is (issue 16, "cheaper records"):
//! at fixed points, ours' record (value, gradient and Hessian of the luminance of
//! the cached single + multiple scattering) by several probe variants (directions
//! × march steps), over independent seeds, against a converged record — the mean
//! of independent batches of a much larger probe, whose spread states its own noise.
//!
//! A variant's efficiency against a baseline is (t_b · e_b²)/(t_v · e_v²) per
//! quantity, e² the mean over points of the squared relative error: the factor by
//! which the variant makes more records per second at the baseline's error, if its
//! error falls as 1/√cost (as Monte Carlo noise does).

use crate::core::space::Space;
use crate::core::taylor::Taylor2;
use crate::pipeline::derivatives;
use crate::pipeline::probe::Outgoing;
use crate::pipeline::record::{CacheSettings, Cached, compute_record};
use crate::pipeline::world::{VecOf, World};
use crate::progress::{Cancelled, Progress};
use serde::Serialize;

/// A probe variant: directions per record, march samples per direction and, if
/// given, the march's refinement towards x (else the settings').
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Variant {
    pub rays: usize,
    pub steps: usize,
    pub grading: Option<f64>,
}

impl Variant {
    /// `cs` with this variant's probe.
    pub fn apply(&self, cs: &CacheSettings) -> CacheSettings {
        let mut c = cs.clone();
        c.probe.rays = self.rays.max(3);
        c.probe.steps = self.steps.max(1);
        if let Some(k) = self.grading {
            c.probe.grading = k;
        }
        c
    }

    /// RAYSxSTEPS, with gK when the grading is given.
    pub fn label(&self) -> String {
        match self.grading {
            Some(k) => format!("{}x{}g{k}", self.rays, self.steps),
            None => format!("{}x{}", self.rays, self.steps),
        }
    }
}

/// Relative errors of a record's luminance, its gradient (vector) and Hessian
/// (Frobenius), root mean square over seeds, each divided by the reference's norm.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RelErrors {
    pub value: f64,
    pub gradient: f64,
    pub hessian: f64,
}

impl RelErrors {
    fn as_array(&self) -> [f64; 3] {
        [self.value, self.gradient, self.hessian]
    }
}

/// One variant at one point.
#[derive(Clone, Debug, Serialize)]
pub struct PointCost {
    /// Mean wall-clock seconds and rays per record, and of the seconds those of
    /// the light field's capture.
    pub seconds: f64,
    pub capture_seconds: f64,
    pub rays: f64,
    pub errors: RelErrors,
    /// Against the finite-difference gradient (when measured): the records'
    /// relative rms error, and their mean's (the estimator's bias, up to the
    /// mean's own noise, `gradient_mean_noise`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gradient_vs_truth: Option<TruthErrors>,
}

/// A variant's gradients against the finite-difference truth, relative to its
/// norm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TruthErrors {
    pub rms: f64,
    pub mean: f64,
    pub mean_noise: f64,
}

/// The gradient of the cached luminance by central differences of path tracing
/// (common random numbers): the mean of `batches` independent batches, and its
/// noise (their spread / √batches).
#[derive(Clone, Copy, Debug)]
pub struct Truth<V> {
    pub gradient: V,
    pub noise: f64,
}

/// [`Truth`] at `x`: `batches` batches of [`derivatives::reference`] with step `h`
/// and `spp` paths per stencil point.
#[allow(clippy::too_many_arguments)] // the stencil's inputs are spelled out
pub fn truth<W: World>(
    world: &W,
    x: VecOf<W>,
    out: Outgoing<VecOf<W>>,
    cs: &CacheSettings,
    (h, spp, batches): (f64, u32, usize),
    seed: u64,
) -> Truth<VecOf<W>> {
    let batches = batches.max(2);
    let grads: Vec<VecOf<W>> = (0..batches)
        .map(|b| {
            let d = derivatives::reference(
                world,
                x,
                out,
                h,
                spp,
                &cs.probe.settings,
                seed.wrapping_add(b as u64),
                false,
            );
            (d.parts.single + d.parts.multiple).luminance().grad
        })
        .collect();
    let mean = grads.iter().fold(W::S::zero(), |a, &g| a + g) / batches as f64;
    let var = grads.iter().map(|&g| W::S::length_squared(g - mean)).sum::<f64>() / (batches - 1) as f64;
    Truth {
        gradient: mean,
        noise: (var / batches as f64).sqrt() / W::S::length(mean).max(f64::MIN_POSITIVE),
    }
}

/// The converged record at a point.
#[derive(Clone, Debug)]
pub struct Reference<S: Space> {
    pub mean: Taylor2<S>,
    /// The mean's own relative noise (batches' spread / √batches).
    pub noise: RelErrors,
}

/// Luminance of the cached scattering (single + multiple) of ours' record at `x`
/// with `cs` (stream `id`), its seconds (all, and the capture's) and rays.
pub fn record_luminance<W: World>(
    world: &W,
    x: VecOf<W>,
    out: Outgoing<VecOf<W>>,
    cs: &CacheSettings,
    id: u64,
    progress: &Progress,
) -> Result<Sampled<W::S>, Cancelled> {
    let r = compute_record(world, x, out, cs, id, progress)?;
    Ok(Sampled {
        luminance: r.payload(Cached::Scattered).luminance(),
        seconds: r.seconds,
        capture_seconds: r.capture_seconds,
        rays: r.rays,
    })
}

/// One record as [`record_luminance`] sees it.
pub struct Sampled<S: Space> {
    pub luminance: Taylor2<S>,
    pub seconds: f64,
    pub capture_seconds: f64,
    pub rays: u64,
}

/// Squared distances of `a` from `b` in value, gradient and Hessian.
fn squared_diff<S: Space>(a: &Taylor2<S>, b: &Taylor2<S>) -> [f64; 3] {
    [
        (a.value - b.value).powi(2),
        S::length_squared(a.grad - b.grad),
        S::frobenius(a.hess - b.hess).powi(2),
    ]
}

/// Norms of `t`'s value, gradient and Hessian (at least the smallest positive
/// number, so that a zero reference gives a large, finite relative error).
fn norms<S: Space>(t: &Taylor2<S>) -> [f64; 3] {
    [t.value.abs(), S::length(t.grad), S::frobenius(t.hess)].map(|n| n.max(f64::MIN_POSITIVE))
}

fn relative(sq: [f64; 3], n: usize, norm: [f64; 3]) -> RelErrors {
    let r = |k: usize| (sq[k] / n.max(1) as f64).sqrt() / norm[k];
    RelErrors {
        value: r(0),
        gradient: r(1),
        hessian: r(2),
    }
}

/// The converged record at `x`: the mean of `batches` records with `cs` (seeds
/// `cs.seed` + 1000 + b, never a variant's), and its noise from their spread.
pub fn reference<W: World>(
    world: &W,
    x: VecOf<W>,
    out: Outgoing<VecOf<W>>,
    cs: &CacheSettings,
    batches: usize,
    id: u64,
    progress: &Progress,
) -> Result<Reference<W::S>, Cancelled> {
    let batches = batches.max(2);
    let mut runs = Vec::with_capacity(batches);
    for b in 0..batches {
        let mut c = cs.clone();
        c.seed = cs.seed.wrapping_add(1000 + b as u64);
        runs.push(record_luminance(world, x, out, &c, id, progress)?.luminance);
    }
    let k = 1.0 / batches as f64;
    let mut mean = runs[0];
    mean.value = runs.iter().map(|t| t.value).sum::<f64>() * k;
    mean.grad = runs.iter().fold(W::S::zero(), |a, t| a + t.grad) * k;
    mean.hess = runs.iter().fold(W::S::zero_mat(), |a, t| a + t.hess) * k;
    let mut sq = [0.0; 3];
    for t in &runs {
        for (s, d) in sq.iter_mut().zip(squared_diff(t, &mean)) {
            *s += d;
        }
    }
    // The sample variance over batches divided by their number: the mean's variance.
    let n = (batches * (batches - 1)) as f64;
    let noise = relative(sq.map(|s| s / n), 1, norms(&mean));
    Ok(Reference { mean, noise })
}

/// `variant`'s records at `x` over `seeds` seeds (`cs.seed` + 0..seeds) against
/// `reference`.
#[allow(clippy::too_many_arguments)] // the measurement's inputs are spelled out
pub fn measure<W: World>(
    world: &W,
    x: VecOf<W>,
    out: Outgoing<VecOf<W>>,
    cs: &CacheSettings,
    variant: Variant,
    seeds: usize,
    id: u64,
    reference: &Reference<W::S>,
    truth: Option<&Truth<VecOf<W>>>,
    progress: &Progress,
) -> Result<PointCost, Cancelled> {
    let c0 = variant.apply(cs);
    let seeds = seeds.max(1);
    let (mut sq, mut seconds, mut capture, mut rays) = ([0.0; 3], 0.0, 0.0, 0u64);
    let mut grads = Vec::with_capacity(seeds);
    for k in 0..seeds {
        let mut c = c0.clone();
        c.seed = cs.seed.wrapping_add(k as u64);
        let r = record_luminance(world, x, out, &c, id, progress)?;
        for (a, d) in sq.iter_mut().zip(squared_diff(&r.luminance, &reference.mean)) {
            *a += d;
        }
        grads.push(r.luminance.grad);
        seconds += r.seconds;
        capture += r.capture_seconds;
        rays += r.rays;
    }
    let gradient_vs_truth = truth.map(|t| {
        let norm = W::S::length(t.gradient).max(f64::MIN_POSITIVE);
        let n = seeds as f64;
        let mean = grads.iter().fold(W::S::zero(), |a, &g| a + g) / n;
        let ms = grads.iter().map(|&g| W::S::length_squared(g - t.gradient)).sum::<f64>() / n;
        let spread = grads.iter().map(|&g| W::S::length_squared(g - mean)).sum::<f64>() / (n - 1.0).max(1.0);
        TruthErrors {
            rms: ms.sqrt() / norm,
            mean: W::S::length(mean - t.gradient) / norm,
            mean_noise: (spread / n).sqrt() / norm,
        }
    });
    Ok(PointCost {
        seconds: seconds / seeds as f64,
        capture_seconds: capture / seeds as f64,
        rays: rays as f64 / seeds as f64,
        errors: relative(sq, seeds, norms(&reference.mean)),
        gradient_vs_truth,
    })
}

/// A variant over all points: mean seconds and rays per record, the mean over
/// points of each squared relative error (as its root), and the efficiency
/// against the baseline (one for the baseline itself).
#[derive(Clone, Debug, Serialize)]
pub struct VariantSummary {
    pub variant: Variant,
    pub seconds_per_record: f64,
    /// The share of a record's time spent capturing its light field.
    pub capture_share: f64,
    pub rays_per_record: f64,
    pub rms_errors: RelErrors,
    /// Records per second at the baseline's error, relative to the baseline's.
    pub efficiency: RelErrors,
    /// The same per point, median over points (robust to a point whose error one
    /// firefly holds).
    pub median_efficiency: RelErrors,
}

/// Summaries of `costs[v][p]` (variant v, point p); variant 0 is the baseline.
/// Nothing without variants.
pub fn summarise(variants: &[Variant], costs: &[Vec<PointCost>]) -> Vec<VariantSummary> {
    if costs.is_empty() {
        return Vec::new();
    }
    let stats = |pc: &[PointCost]| {
        let n = pc.len().max(1) as f64;
        let secs = pc.iter().map(|c| c.seconds).sum::<f64>() / n;
        let rays = pc.iter().map(|c| c.rays).sum::<f64>() / n;
        let mut e2 = [0.0; 3];
        for c in pc {
            for (a, e) in e2.iter_mut().zip(c.errors.as_array()) {
                *a += e * e / n;
            }
        }
        (secs, rays, e2)
    };
    let (t0, _, e0) = stats(&costs[0]);
    let per_point = |pc: &[PointCost], k: usize| {
        let mut r: Vec<f64> = pc
            .iter()
            .zip(&costs[0])
            .map(|(c, b)| {
                let (eb, ev) = (b.errors.as_array()[k], c.errors.as_array()[k]);
                (b.seconds * eb * eb) / (c.seconds * ev * ev).max(f64::MIN_POSITIVE)
            })
            .collect();
        r.sort_by(f64::total_cmp);
        match r.len() {
            0 => f64::NAN,
            n if n % 2 == 1 => r[n / 2],
            n => 0.5 * (r[n / 2 - 1] + r[n / 2]),
        }
    };
    variants
        .iter()
        .zip(costs)
        .map(|(&variant, pc)| {
            let (t, rays, e2) = stats(pc);
            let capture = pc.iter().map(|c| c.capture_seconds).sum::<f64>() / pc.len().max(1) as f64;
            let eff = |k: usize| (t0 * e0[k]) / (t * e2[k]).max(f64::MIN_POSITIVE);
            VariantSummary {
                variant,
                seconds_per_record: t,
                capture_share: capture / t.max(f64::MIN_POSITIVE),
                rays_per_record: rays,
                rms_errors: RelErrors {
                    value: e2[0].sqrt(),
                    gradient: e2[1].sqrt(),
                    hessian: e2[2].sqrt(),
                },
                efficiency: RelErrors {
                    value: eff(0),
                    gradient: eff(1),
                    hessian: eff(2),
                },
                median_efficiency: RelErrors {
                    value: per_point(pc, 0),
                    gradient: per_point(pc, 1),
                    hessian: per_point(pc, 2),
                },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cost(seconds: f64, e: f64) -> PointCost {
        PointCost {
            gradient_vs_truth: None,
            capture_seconds: seconds,
            seconds,
            rays: 1.0,
            errors: RelErrors {
                value: e,
                gradient: 2.0 * e,
                hessian: 3.0 * e,
            },
        }
    }

    /// Half the time at equal error is twice the records per second; twice the
    /// error at equal time a quarter (error ∝ 1/√cost); the baseline is one.
    #[test]
    fn efficiency_is_records_per_second_at_equal_error() {
        let v = |rays| Variant {
            rays,
            steps: 8,
            grading: None,
        };
        let costs = vec![
            vec![cost(2.0, 0.1), cost(4.0, 0.2)],
            vec![cost(1.0, 0.1), cost(2.0, 0.2)],
            vec![cost(2.0, 0.2), cost(4.0, 0.4)],
        ];
        let s = summarise(&[v(64), v(32), v(16)], &costs);
        for (k, want) in [(0, 1.0), (1, 2.0), (2, 0.25)] {
            for e in [s[k].efficiency, s[k].median_efficiency] {
                for got in e.as_array() {
                    assert!((got - want).abs() < 1e-12, "variant {k}: {got} vs {want}");
                }
            }
        }
        assert!((s[1].seconds_per_record - 1.5).abs() < 1e-12);
        assert!((s[0].rms_errors.value - (0.025f64).sqrt()).abs() < 1e-12);
    }
}
