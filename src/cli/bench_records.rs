//! `volcache bench records`: what one record of ours costs and how accurate it is,
//! per probe variant (directions × march steps), against a converged record
//! ([`volcache::study::record_cost`]). 2D and 3D scenes alike.
//!
//! Points: `--points` uniform random points (fixed seed) in the scene's medium —
//! the 2D domain, or the 3D scene's bounds (a point inside a closed object is not
//! excluded; none of the committed results has one). ω_o: the 2D field's, or
//! towards the 3D camera. Settings: the library's record defaults with the
//! scene's path depth, `--direct-samples` and the variant's directions and steps.

use super::common::{AnyScene, load_any_scene, scene_stem};
use clap::Args;
use glam::{DVec2, DVec3};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::core::metric::CacheMethod;
use volcache::core::rng::Sampler;
use volcache::core::space::{D2, D3};
use volcache::output::write_json;
use volcache::pipeline::probe::Outgoing;
use volcache::pipeline::record::CacheSettings;
use volcache::pipeline::world::{VecOf, World};
use volcache::progress::{Cancelled, Progress};
use volcache::study::record_cost::{PointCost, Variant, VariantSummary, measure, reference, summarise, truth};

#[derive(Args, Debug)]
pub struct RecordsBench {
    /// Scene JSON, 2D or 3D (default: the embedded 2D occluder scene).
    pub scene: Option<PathBuf>,
    /// Output JSON (default: results/bench_records_<scene>.json).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Probe variants as RAYSxSTEPS (or RAYSxSTEPSgK with the march's refinement
    /// K), comma-separated; the first is the baseline.
    #[arg(long, value_delimiter = ',', default_values_t = ["1024x16".to_string(), "512x16".to_string(), "2048x8".to_string(), "1024x8".to_string()])]
    pub variants: Vec<String>,
    /// The converged record's probe (RAYSxSTEPS), and how many independent batches
    /// of it are averaged.
    #[arg(long, default_value = "16384x32")]
    pub reference: String,
    #[arg(long, default_value_t = 2)]
    pub reference_batches: usize,
    /// Random points in the medium.
    #[arg(long, default_value_t = 6)]
    pub points: usize,
    /// Seeds per variant and point.
    #[arg(long, default_value_t = 6)]
    pub seeds: usize,
    /// Estimate the light straight from the lights per point with this many
    /// samples and cache only the rest (as `caches --direct-samples`).
    #[arg(long)]
    pub direct_samples: Option<u32>,
    /// Also judge the variants' gradients against central differences of path
    /// tracing (common random numbers) with this many paths per stencil point, in
    /// `--truth-batches` independent batches; the step is `--truth-step` × the
    /// scene's size.
    #[arg(long)]
    pub truth_spp: Option<u32>,
    #[arg(long, default_value_t = 4)]
    pub truth_batches: usize,
    #[arg(long, default_value_t = 2e-3)]
    pub truth_step: f64,
    /// The probes' phase roulette c (`ProbeSettings::phase_roulette`; 0: off), for
    /// the variants (the converged record keeps the library's default).
    #[arg(long)]
    pub phase_roulette: Option<f64>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

fn parse_variant(s: &str) -> anyhow::Result<Variant> {
    let bad = || anyhow::anyhow!("a probe variant is RAYSxSTEPS or RAYSxSTEPSgK (e.g. 1024x16, 1024x16g0), got {s:?}");
    let (r, rest) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (k, grading) = match rest.split_once('g') {
        Some((k, g)) => (k, Some(g.trim().parse::<f64>().map_err(|_| bad())?)),
        None => (rest, None),
    };
    let rays: usize = r.trim().parse().map_err(|_| bad())?;
    let steps: usize = k.trim().parse().map_err(|_| bad())?;
    anyhow::ensure!((3..=1 << 20).contains(&rays), "rays in {s:?} must lie in 3..=1048576");
    anyhow::ensure!((1..=4096).contains(&steps), "steps in {s:?} must lie in 1..=4096");
    if let Some(g) = grading {
        let (lo, hi) = volcache::limits::GRADING;
        anyhow::ensure!((lo..=hi).contains(&g), "the grading in {s:?} must lie in {lo}..={hi}");
    }
    Ok(Variant { rays, steps, grading })
}

#[derive(Serialize)]
struct PointReport {
    point: Vec<f64>,
    /// The converged record's relative noise.
    reference_noise: volcache::study::record_cost::RelErrors,
    reference_value: f64,
    /// Per variant.
    costs: Vec<PointCost>,
}

#[derive(Serialize)]
struct Report {
    volcache_version: &'static str,
    scene: String,
    threads: usize,
    seeds: usize,
    seed: u64,
    reference: Variant,
    reference_batches: usize,
    direct_samples: Option<u32>,
    note: &'static str,
    summary: Vec<VariantSummary>,
    points: Vec<PointReport>,
}

/// The measurement over `points`, for any dimension.
struct Plan<'a> {
    cs: CacheSettings,
    variants: &'a [Variant],
    reference: Variant,
    a: &'a RecordsBench,
}

impl Plan<'_> {
    fn run<W: World>(
        &self,
        world: &W,
        points: &[VecOf<W>],
        out: impl Fn(VecOf<W>) -> Outgoing<VecOf<W>>,
        coords: impl Fn(VecOf<W>) -> Vec<f64>,
    ) -> Result<Vec<PointReport>, Cancelled> {
        let progress = Progress::new();
        let mut reports = Vec::new();
        for (k, &x) in points.iter().enumerate() {
            let id = k as u64;
            let r = reference(
                world,
                x,
                out(x),
                &self.reference.apply(&self.cs),
                self.a.reference_batches,
                id,
                &progress,
            )?;
            let truth = self.a.truth_spp.map(|spp| {
                let h = self.a.truth_step * world.scale();
                let seed = volcache::study::seeds::reference_seed(self.cs.seed) ^ (id << 20);
                truth(world, x, out(x), &self.cs, (h, spp, self.a.truth_batches), seed)
            });
            if let Some(t) = &truth {
                eprintln!("  finite-difference gradient noise {:.1}%", 100.0 * t.noise);
            }
            let mut costs = Vec::new();
            for &variant in self.variants {
                let mut cs = self.cs.clone();
                if let Some(c) = self.a.phase_roulette {
                    cs.probe.phase_roulette = c;
                }
                let c = measure(
                    world,
                    x,
                    out(x),
                    &cs,
                    variant,
                    self.a.seeds,
                    id,
                    &r,
                    truth.as_ref(),
                    &progress,
                )?;
                costs.push(c);
            }
            eprintln!(
                "point {}/{}: value {:.4e} (reference noise {:.2}%)",
                k + 1,
                points.len(),
                r.mean.value,
                100.0 * r.noise.value
            );
            reports.push(PointReport {
                point: coords(x),
                reference_noise: r.noise,
                reference_value: r.mean.value,
                costs,
            });
        }
        Ok(reports)
    }
}

/// The first `n` points drawn by `draw` where `keep` holds (at most 1000·n draws),
/// from a fixed stream.
fn random_points<V: Copy>(n: usize, seed: u64, draw: impl Fn(&mut Sampler) -> V, keep: impl Fn(V) -> bool) -> Vec<V> {
    let mut s = Sampler::new2(seed, 0x2EC0, 0);
    let mut out = Vec::new();
    for _ in 0..n * 1000 {
        if out.len() >= n {
            break;
        }
        let p = draw(&mut s);
        if keep(p) {
            out.push(p);
        }
    }
    out
}

pub fn run(a: RecordsBench) -> anyhow::Result<ExitCode> {
    let variants = a
        .variants
        .iter()
        .map(|s| parse_variant(s))
        .collect::<anyhow::Result<Vec<_>>>()?;
    anyhow::ensure!(!variants.is_empty(), "--variants needs at least one RAYSxSTEPS");
    let reference_variant = parse_variant(&a.reference)?;
    anyhow::ensure!((1..=64).contains(&a.points), "--points must lie in 1..=64");
    anyhow::ensure!((2..=1000).contains(&a.seeds), "--seeds must lie in 2..=1000");
    anyhow::ensure!(
        (2..=64).contains(&a.reference_batches),
        "--reference-batches must lie in 2..=64"
    );
    let scene = load_any_scene(a.scene.as_deref())?;
    let stem = scene_stem(a.scene.as_deref());
    let out_path = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("results/bench_records_{stem}.json")));
    let cancelled = |_| anyhow::Error::from(Cancelled);
    let reports = match &scene {
        AnyScene::Flat(s) => {
            let fp = volcache::flatland::field::FieldParams::from_scene(s);
            let mut cs = CacheSettings::new::<D2>(CacheMethod::Ours, 1.0, fp.settings);
            cs.direct_samples = a.direct_samples;
            cs.seed = a.seed;
            let (lo, hi) = (s.domain_min, s.domain_max);
            let pts = random_points(
                a.points,
                a.seed,
                |r| lo + (hi - lo) * DVec2::new(r.next_f64(), r.next_f64()),
                |p| s.medium_at(p).is_some(),
            );
            anyhow::ensure!(
                !pts.is_empty(),
                "{}: no point of the domain lies in the medium",
                s.source
            );
            let w = DVec2::from_angle(fp.omega_o_deg.to_radians());
            let plan = Plan {
                cs,
                variants: &variants,
                reference: reference_variant,
                a: &a,
            };
            plan.run(&**s, &pts, |_| Outgoing::Direction(w), |p| p.to_array().to_vec())
                .map_err(cancelled)?
        }
        AnyScene::Volume(s) => {
            let image = volcache::volume::render::RenderParams::from_scene(s);
            let mut cs = CacheSettings::new::<D3>(CacheMethod::Ours, 1.0, image.first_vertex_settings());
            cs.direct_samples = a.direct_samples;
            cs.seed = a.seed;
            let (lo, hi) = (s.bounds.min, s.bounds.max);
            let pts = random_points(
                a.points,
                a.seed,
                |r| lo + (hi - lo) * DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()),
                |p| s.medium_at(p).is_some(),
            );
            anyhow::ensure!(!pts.is_empty(), "no point of the scene's bounds lies in its medium");
            let eye = s.camera.position;
            let plan = Plan {
                cs,
                variants: &variants,
                reference: reference_variant,
                a: &a,
            };
            plan.run(&**s, &pts, |_| Outgoing::TowardsPoint(eye), |p| p.to_array().to_vec())
                .map_err(cancelled)?
        }
    };
    // Per variant, its costs at every point.
    let costs: Vec<Vec<PointCost>> = (0..variants.len())
        .map(|v| reports.iter().map(|p| p.costs[v].clone()).collect())
        .collect();
    let summary = summarise(&variants, &costs);
    println!(
        "records of ours, {stem}: {} points × {} seeds, reference {} × {} batches, {} threads",
        reports.len(),
        a.seeds,
        reference_variant.label(),
        a.reference_batches,
        rayon::current_num_threads()
    );
    println!(
        "{:>11} {:>9} {:>8} {:>11} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9}   median over points: {:>7} {:>7} {:>7}",
        "variant",
        "ms/rec",
        "capture",
        "rays/rec",
        "e_val",
        "e_grad",
        "e_hess",
        "eff_val",
        "eff_grad",
        "eff_hess",
        "val",
        "grad",
        "hess"
    );
    for s in &summary {
        println!(
            "{:>11} {:>9.2} {:>7.0}% {:>11.0} {:>8.4} {:>8.4} {:>8.4} {:>9.2} {:>9.2} {:>9.2}   {:>26.2} {:>7.2} {:>7.2}",
            s.variant.label(),
            1e3 * s.seconds_per_record,
            100.0 * s.capture_share,
            s.rays_per_record,
            s.rms_errors.value,
            s.rms_errors.gradient,
            s.rms_errors.hessian,
            s.efficiency.value,
            s.efficiency.gradient,
            s.efficiency.hessian,
            s.median_efficiency.value,
            s.median_efficiency.gradient,
            s.median_efficiency.hessian
        );
    }
    if a.truth_spp.is_some() {
        println!("gradients against central differences of path tracing (medians over points, relative to |∇|):");
        println!(
            "{:>11} {:>9} {:>12} {:>11}",
            "variant", "rms", "mean's err", "its noise"
        );
        for (v, variant) in variants.iter().enumerate() {
            let med = |f: &dyn Fn(&volcache::study::record_cost::TruthErrors) -> f64| {
                let mut x: Vec<f64> = reports
                    .iter()
                    .filter_map(|p| p.costs[v].gradient_vs_truth.as_ref().map(f))
                    .collect();
                x.sort_by(f64::total_cmp);
                x.get(x.len() / 2).copied().unwrap_or(f64::NAN)
            };
            println!(
                "{:>11} {:>9.3} {:>12.3} {:>11.3}",
                variant.label(),
                med(&|t| t.rms),
                med(&|t| t.mean),
                med(&|t| t.mean_noise)
            );
        }
    }
    let report = Report {
        volcache_version: env!("CARGO_PKG_VERSION"),
        scene: stem,
        threads: rayon::current_num_threads(),
        seeds: a.seeds,
        seed: a.seed,
        reference: reference_variant,
        reference_batches: a.reference_batches,
        direct_samples: a.direct_samples,
        note: "errors: root mean square over seeds of the record's luminance value, gradient (vector) and \
               Hessian (Frobenius) minus the converged record's, relative to its norm; summary: root of the \
               mean over points of the squared relative errors; efficiency: (t_base e_base^2)/(t e^2), records \
               per second at the baseline's error relative to the baseline's (the first variant). Wall-clock \
               seconds on a possibly shared machine.",
        summary,
        points: reports,
    };
    write_json(&out_path, &report)?;
    eprintln!("wrote {}", out_path.display());
    Ok(ExitCode::SUCCESS)
}
