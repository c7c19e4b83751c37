//! The compare view's computation: a reference field and two cache methods (ours,
//! Jarosz 2008) on the same scene at equal cache count, by the protocol `volcache
//! figure compare` runs ([`crate::study::field_runs`]): `render_reference` for the
//! reference (its own seed, [`reference_seed`]), then per method the search for ε
//! ([`eps_for_count`]) and a fresh, timed run at it ([`timed_run`]), and
//! `field_errors` against the reference. The field settings are the scene's own (as
//! the command line's), at the compare resolution, so [`compare_command`] reproduces
//! the numbers.

use super::command::shell_quote;
use super::jobs::{Job, Notify, Priority, Reporter};
use crate::flatland::cached_field::{CacheMethod, CacheSettings, RecordInfo};
use crate::flatland::field::{Field, FieldErrors, FieldParams, field_errors};
use crate::flatland::scene::Scene;
use crate::pipeline::placement::CountError;
use crate::study::field_runs::{self, TimedRun, eps_for_count, timed_run};
use crate::study::reference2d::render_reference;
use crate::study::seeds::reference_seed;
use std::sync::Arc;

/// The methods compared, in the order shown.
pub const METHODS: [CacheMethod; 2] = [CacheMethod::Ours, CacheMethod::Jarosz08];

/// Parameters of the comparison (the side panel's "Compare"), small by default.
#[derive(Clone, Debug, PartialEq)]
pub struct CompareParams {
    /// Equal-count mode: records each method places (`--caches`).
    pub caches: usize,
    /// Directions per record (`--rays`).
    pub rays: usize,
    /// Ray-marched medium samples per direction (`--steps`).
    pub steps: usize,
    /// Resolution (`--res`); None: half the app's field resolution.
    pub res: Option<[usize; 2]>,
    /// Samples per pixel of the reference (`--ref-spp`).
    pub ref_spp: u32,
    /// The light straight from the lights sampled this many times per pixel, not
    /// cached (`--direct-samples`).
    pub direct_samples: Option<u32>,
    /// The point lights' once-scattered light sampled per pixel with this many
    /// directions, not cached (`--point-scatter`).
    pub point_scatter: Option<u32>,
    /// The pixels within a mean free path of a point light path traced with this
    /// many paths each, not read from records (`--near-light-paths`).
    pub near_light_paths: Option<u32>,
    /// Records reach no farther than this multiple of their distance to the
    /// nearest edge they see (`--edge-reach`).
    pub edge_reach: Option<f64>,
    /// Records reach no farther than this multiple of their distance to the
    /// nearest point light (`--lamp-reach`; off by default in 2D, as `caches`).
    pub lamp_reach: Option<f64>,
    /// Ours' records reach no farther than their gradient's noise allows at ε
    /// (`--gradient-noise-reach`; Jarosz 2008 measures no gradient noise).
    pub gradient_noise_reach: bool,
}

impl Default for CompareParams {
    fn default() -> Self {
        CompareParams {
            caches: 150,
            rays: 512,
            steps: 16,
            res: None,
            ref_spp: 256,
            direct_samples: None,
            point_scatter: None,
            near_light_paths: None,
            edge_reach: None,
            lamp_reach: None,
            gradient_noise_reach: false,
        }
    }
}

impl CompareParams {
    /// The field parameters of the comparison: the scene's render settings (as
    /// `figure compare`), at [`CompareParams::res`] or half of `app`'s resolution,
    /// with `app`'s seed.
    pub fn field_params(&self, scene: &Scene, app: &FieldParams) -> FieldParams {
        let [w, h] = self.res.unwrap_or([(app.width / 2).max(1), (app.height / 2).max(1)]);
        // Of L_s, what the cache holds, whatever the scene renders.
        let scene_fp = field_runs::cached_quantity(FieldParams::from_scene(scene));
        FieldParams {
            width: w.max(1),
            height: h.max(1),
            seed: app.seed,
            ..scene_fp
        }
    }

    /// The cache settings of `method` (as `volcache caches`' defaults with these
    /// rays, steps, seed, straight-light samples, once-scattered point-light
    /// directions, paths near point lights, edge and lamp reach, and gradient-noise
    /// reach, the last for ours only).
    pub fn cache_settings(&self, method: CacheMethod, fp: &FieldParams) -> CacheSettings {
        let mut cs = field_runs::cache_settings(method, 0.05, fp, self.rays, self.steps);
        cs.direct_samples = self.direct_samples.map(|n| n.max(1));
        cs.point_scatter = self.point_scatter.map(|n| n.max(1));
        cs.near_light_paths = self.near_light_paths.map(|n| n.max(1));
        cs.edge_reach = self.edge_reach.map(crate::limits::clamp_edge_reach);
        cs.lamp_reach = self.lamp_reach.map(crate::limits::clamp_edge_reach);
        cs.gradient_noise_reach = self.gradient_noise_reach && method == CacheMethod::Ours;
        cs
    }

    /// The reference's field parameters (the seed of `figure compare`).
    pub fn reference_params(&self, fp: &FieldParams) -> FieldParams {
        FieldParams {
            spp: self.ref_spp.max(1),
            seed: reference_seed(fp.seed),
            ..fp.clone()
        }
    }
}

/// What the comparison restarts for: the scene revision and the parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct CompareKey {
    pub revision: u64,
    pub fp: FieldParams,
    pub params: CompareParams,
}

/// One method's result and cost.
#[derive(Clone, Debug)]
pub struct MethodRun {
    pub method: CacheMethod,
    /// ε found by the equal-count search.
    pub eps: f64,
    /// Every record (of every cache).
    pub records: Vec<RecordInfo>,
    pub field: Field,
    /// Rays of the timed run (placement + per-pixel direct part).
    pub rays: u64,
    /// Seconds of the timed run (placement + reconstruction).
    pub seconds: f64,
    pub errors: FieldErrors,
    /// The records' own noise relative to their values
    /// (`pipeline::placement::ValueNoise::relative`).
    pub records_noise: Option<f64>,
}

impl MethodRun {
    pub fn is_finite(&self) -> bool {
        self.eps.is_finite()
            && self.seconds.is_finite()
            && self.errors.rmse.is_finite()
            && self.errors.relmse.is_finite()
    }
}

/// The comparison so far: the reference, then one run per method as it lands.
#[derive(Clone, Debug)]
pub struct CompareResult {
    pub fp: FieldParams,
    pub reference: Field,
    pub ref_spp: u32,
    pub ref_rays: u64,
    pub ref_seconds: f64,
    pub runs: Vec<MethodRun>,
}

impl CompareResult {
    pub fn run(&self, method: CacheMethod) -> Option<&MethodRun> {
        self.runs.iter().find(|r| r.method == method)
    }

    /// Every method has run.
    pub fn is_complete(&self) -> bool {
        self.runs.len() == METHODS.len()
    }
}

pub fn method_label(m: CacheMethod) -> &'static str {
    match m {
        CacheMethod::Ours => "ours",
        CacheMethod::Jarosz08 => "Jarosz 2008",
    }
}

/// Reference, then each method; a result is sent after each step.
pub fn spawn_compare(scene: Arc<Scene>, key: &CompareKey, notify: Notify) -> Job<Arc<CompareResult>> {
    let (fp, params) = (key.fp.clone(), key.params.clone());
    Job::spawn(
        "compare",
        Priority::Background,
        notify,
        move |r: &Reporter<Arc<CompareResult>>| {
            let rp = params.reference_params(&fp);
            r.stage(format!(
                "compare: reference {}×{} @ {} spp",
                rp.width, rp.height, rp.spp
            ));
            // At full precision, as `figure compare` measures (its store keeps f64).
            let (reference, _) = render_reference(&scene, &rp, r.progress())?;
            r.add_rays(reference.rays);
            let mut res = CompareResult {
                fp: fp.clone(),
                reference: reference.field,
                ref_spp: rp.spp,
                ref_rays: reference.rays,
                ref_seconds: reference.seconds,
                runs: Vec::new(),
            };
            r.send(Arc::new(res.clone()));
            let target = params.caches.max(1);
            for method in METHODS {
                let name = method_label(method);
                let run = || -> Result<MethodRun, CountError> {
                    let cs = params.cache_settings(method, &fp);
                    r.stage(format!("compare: {name}, searching ε for {target} records"));
                    let found = eps_for_count(&scene, &fp, &cs, target, r.progress())?;
                    let eps = found.eps;
                    r.add_rays(found.rays);
                    r.stage(format!("compare: {name}, timed run at ε = {eps:.3e}"));
                    let cs = CacheSettings { eps, ..cs };
                    let TimedRun { cached: f, seconds } = timed_run(&scene, &fp, &cs, r.progress())?;
                    let rays = f.placement_rays + f.reconstruction_rays;
                    r.add_rays(rays);
                    Ok(MethodRun {
                        method,
                        eps,
                        records: f.records.concat(),
                        errors: field_errors(&f.field, &res.reference),
                        records_noise: f.records_relative_noise,
                        field: f.field,
                        rays,
                        seconds,
                    })
                };
                match run() {
                    Ok(run) => res.runs.push(run),
                    Err(CountError::Cancelled(c)) => return Err(c),
                    // Out of reach for this method: say so and compare the others.
                    Err(e) => r.stage(format!("compare: {name}: {e}")),
                }
                r.send(Arc::new(res.clone()));
            }
            Ok(())
        },
    )
}

/// `volcache figure compare` reproducing the comparison (`scene`: None for the
/// embedded default scene).
pub fn compare_command(scene: Option<&str>, fp: &FieldParams, p: &CompareParams, out: &str) -> String {
    let cs = p.cache_settings(CacheMethod::Ours, fp);
    let mut direct = cs
        .direct_samples
        .map_or(String::new(), |n| format!(" --direct-samples {n}"));
    if let Some(n) = cs.point_scatter {
        direct += &format!(" --point-scatter {n}");
    }
    if let Some(n) = cs.near_light_paths {
        direct += &format!(" --near-light-paths {n}");
    }
    let mut reach = cs.edge_reach.map_or(String::new(), |k| format!(" --edge-reach {k}"));
    if let Some(k) = cs.lamp_reach {
        reach += &format!(" --lamp-reach {k}");
    }
    if cs.gradient_noise_reach {
        reach += " --gradient-noise-reach";
    }
    format!(
        "volcache figure compare{} --caches {} --rays {} --steps {}{direct}{reach} --res {}x{} --ref-spp {} --seed {} --out {}",
        scene.map_or(String::new(), |s| format!(" {}", shell_quote(s))),
        p.caches.max(1),
        p.rays.max(3),
        p.steps.max(1),
        fp.width,
        fp.height,
        p.ref_spp.max(1),
        fp.seed,
        shell_quote(out)
    )
}
