//! `volcache render3d --method ours|jarosz08`: placement (at ε, at a record count,
//! or read from a records file) and reconstruction of a 3D radiance cache.

use super::common::{check_spp, wrote};
use super::image3d::{CacheSummary, SurfaceSummary};
use clap::Args;
use std::path::PathBuf;
use volcache::core::metric::CacheMethod;
use volcache::output::write_json;
use volcache::pipeline::record::Cached;
use volcache::progress::Progress;
use volcache::volume::cached::{
    BudgetSettings, CacheSettings, CacheView, CachedRenderParams, Placement, RecordMemo, default_eps, image_after,
    place, place_surfaces, place_with_count, reconstruct,
};
use volcache::volume::cached_params::SurfaceCache;
use volcache::volume::records_file::{Loaded, RecordsFile, ValidFor};
use volcache::volume::render::{RenderParams, Rendered};
use volcache::volume::scene::Scene;
use volcache::volume::surface_cache::default_surface_eps;

/// Radiance-cache parameters of `render3d`, `figure compare3d` and `bench tradeoff3d`.
#[derive(Args, Debug, Clone)]
pub struct Cache3dArgs {
    /// Error threshold ε (ours: a volume, scene units³; jarosz08: a fraction).
    /// Default: a scene-relative start.
    #[arg(long)]
    pub eps: Option<f64>,
    /// Equal-count mode: search ε until the method places this many records (±1%).
    #[arg(long, conflicts_with = "eps")]
    pub caches: Option<usize>,
    /// Directions per cache point, stratified over the sphere (the paper: 16k).
    #[arg(long, default_value_t = 16384)]
    pub rays: usize,
    /// Ray-marched medium samples per direction.
    #[arg(long, default_value_t = 24)]
    pub steps: usize,
    /// Refinement of the march towards x: 0 spaces the samples evenly, k > 0 makes
    /// the first steps k/(e^k − 1) of the even step (see `pipeline::probe::March`).
    #[arg(long, default_value_t = <volcache::core::space::D3 as volcache::pipeline::dim::Dim>::PROBE_GRADING)]
    pub grading: f64,
    /// Recursive paths per probe hit and per medium sample.
    #[arg(long, default_value_t = 1)]
    pub paths: u32,
    /// Distance between march points along camera rays (default: scene size / 128).
    #[arg(long)]
    pub march_step: Option<f64>,
    /// Place records over the first N camera samples of each pixel only (default:
    /// all; with --time-budget, --spp; with --budget, one in eight): the others
    /// read the records, and a march point none covers is path traced (counted in
    /// the summary's `uncovered`). The records' count barely follows the camera
    /// samples, the placement's walk over their march points does.
    #[arg(long)]
    pub place_spp: Option<u32>,
    /// With --time-budget, --place-spp or --budget: the march step of the camera
    /// samples beyond the placed ones (default: --march-step). Coarser is cheaper
    /// per sample and as unbiased; whether it pays depends on the scene (README).
    #[arg(long)]
    pub image_march_step: Option<f64>,
    /// With --time-budget or --place-spp: only one in M of the camera samples
    /// beyond the placed ones marches (runs of 8 consecutive samples, which
    /// stratify the pixel, one run in M); the others sample the first surface
    /// alone, and the medium part is the mean over the marched ones (cheaper
    /// surface samples where the march is most of a sample's cost). `auto`: the
    /// adaptive split (`--image-split adaptive`, implied) also chooses M, by the
    /// image's and the medium part's equal-time errors relative to every sample
    /// marching, summed (the medium's may rise where the image gains more);
    /// without `auto` the split's summary table (`march_every`) only predicts
    /// each M's variance and cost.
    #[arg(long, value_name = "M|auto", value_parser = parse_march_every)]
    pub image_march_every: Option<MarchEveryArg>,
    /// How the camera samples beyond the placed ones march: `adaptive` takes the
    /// march step (Δ, 2Δ, 4Δ or 8Δ) and straight-light samples (n, n/2, n/4) of
    /// least variance × cost, measured on the placed samples, and without a time
    /// budget as many samples as cost what --spp's rest would have at Δ; `fixed`
    /// keeps --march-step (or --image-march-step). Default: adaptive with
    /// --time-budget or --budget (unless --image-march-step), else fixed.
    #[arg(long, value_enum)]
    pub image_split: Option<ImageSplitArg>,
    /// Reflected-light samples per camera sample at the first surface.
    #[arg(long, default_value_t = 4)]
    pub surface_paths: u32,
    /// Second-order interpolation (ours; also of the surface cache).
    #[arg(long)]
    pub second_order: bool,
    /// Sample the light arriving straight from the lights (emitters, sky, sun,
    /// delta lights) at every march point with this many samples (NEE and a
    /// phase-sampled ray, MIS), and cache only the rest: the records leave it out.
    /// Default: only delta lights and suns per point, the rest cached (the paper's
    /// split).
    #[arg(long)]
    pub direct_samples: Option<u32>,
    /// Russian roulette of the probes' phase-sampled paths by the phase's weight
    /// of each direction towards ω_o (`ProbeSettings::phase_roulette`: followed
    /// with probability min(1, C·f/f̄)); 0 turns it off. Unbiased; saves rays in
    /// anisotropic fog (see `volcache bench records`).
    #[arg(long, default_value_t = 0.0)]
    pub phase_roulette: f64,
    #[command(flatten)]
    pub record_noise: super::common::RecordNoiseArgs,
    /// Limit every record's radii to this multiple of its distance to the nearest
    /// surface edge it sees (a triangle's silhouette edge), where the light turns
    /// with the angle and no Taylor expansion reaches across, or to the nearest
    /// point light it sees (the scattered light peaks around it).
    /// Default: the paper's metric alone.
    #[arg(long)]
    pub edge_reach: Option<f64>,
    /// Limit every record's radii to this multiple of its distance to the nearest
    /// point light (no rays: the lights' positions alone): the scattered light
    /// grows as 1/ρ around a lamp, and no Taylor expansion of it reaches farther
    /// than the lamp is. Default: 2 (`pipeline::budget::VOLUME_LAMP_REACH`).
    #[arg(long, conflicts_with = "no_lamp_reach")]
    pub lamp_reach: Option<f64>,
    /// Let records reach past point lights (the metric alone decides), to measure
    /// what the lamp reach gains.
    #[arg(long)]
    pub no_lamp_reach: bool,
    /// A record serves only the points the camera sees within this half-angle
    /// (degrees) of it: the L_s it holds leaves towards the camera, a direction
    /// that turns fast near the camera, and a record near it would otherwise hand
    /// its value to points whose ω_o is tens of degrees away (anisotropic media
    /// only; README, "The eye cone"). Off by default.
    #[arg(long)]
    pub eye_cone: Option<f64>,
    /// Limit every record's radii by its multiple-scattering gradient's noise
    /// (`core::metric::gradient_noise_radius`): the radius at which that noise,
    /// integrated over the record's ball, adds the error ε allows the Hessian's
    /// term. Where a record's gradient is mostly noise (few directions, thick or
    /// forward-scattering fog) it then reaches less far. Ours only (Jarosz 2008
    /// measures no gradient noise). Off by default, also under --budget (README).
    #[arg(long)]
    pub gradient_noise_reach: bool,
    /// Light reflected by the first surface: path traced per camera sample
    /// (`none`), or its indirect part from an occlusion-aware second-order
    /// irradiance cache on the surfaces, direct light sampled per camera sample
    /// (`ours`).
    #[arg(long, value_enum, default_value_t = SurfaceCacheArg::None)]
    pub surface_cache: SurfaceCacheArg,
    /// Error threshold ε of the surface cache (a volume, scene units³). Default: a
    /// scene-relative start.
    #[arg(long)]
    pub surface_eps: Option<f64>,
    /// Seed of the records' light fields. `--seed` does not change it (it seeds the
    /// camera's samples): to measure how the records vary, sweep this too, or runs
    /// on different `--seed`s share one stream of light fields (README, deep_lamp
    /// at budget 4).
    #[arg(long, default_value_t = 1)]
    pub cache_seed: u64,
}

/// Whether the first surface's reflected light comes from a surface cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SurfaceCacheArg {
    None,
    Ours,
}

/// Which camera samples beyond the placed ones march (`--image-march-every`):
/// one in a given count, or one in the count the adaptive split chooses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MarchEveryArg {
    Every(u32),
    Auto,
}

fn parse_march_every(s: &str) -> Result<MarchEveryArg, String> {
    match s {
        "auto" => Ok(MarchEveryArg::Auto),
        _ => s
            .parse()
            .map(MarchEveryArg::Every)
            .map_err(|_| format!("expected a whole number or `auto`, got `{s}`")),
    }
}

/// How the camera samples beyond the placed ones march (`--image-split`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ImageSplitArg {
    Adaptive,
    Fixed,
}

/// How `render3d` shares records between jobs.
#[derive(Args, Debug, Clone)]
pub struct RecordsArgs {
    /// Reconstruct from these records (from `--records-out` for this image) instead
    /// of placing.
    #[arg(long, conflicts_with_all = ["eps", "caches", "records_out", "edge_reach", "lamp_reach", "no_lamp_reach", "eye_cone"])]
    pub records_in: Option<PathBuf>,
    /// Write the placed records here (JSON), for tiles rendered in other jobs.
    #[arg(long)]
    pub records_out: Option<PathBuf>,
    /// With --records-out: place and write the records, render no image.
    #[arg(long, requires = "records_out")]
    pub place_only: bool,
}

impl Cache3dArgs {
    /// What a budget sets beside the options given (`render3d --budget`, `bench
    /// tradeoff3d --budgets`): its straight-light samples and placed camera samples
    /// unless given, and the adaptive split of the camera samples beyond the placed
    /// ones when there are some and neither --image-march-step nor
    /// --image-march-every is given.
    pub fn budget_defaults(&mut self, s: &BudgetSettings) {
        self.direct_samples.get_or_insert(s.direct_samples);
        let placed = *self.place_spp.get_or_insert(s.place_spp);
        let chosen_share = matches!(self.image_march_every, None | Some(MarchEveryArg::Auto));
        if self.image_march_step.is_none() && chosen_share && placed < s.spp {
            self.image_split.get_or_insert(ImageSplitArg::Adaptive);
        }
    }

    /// Cache and march settings for `method` on `scene`, checked.
    pub fn settings(
        &self,
        scene: &Scene,
        image: &RenderParams,
        method: CacheMethod,
    ) -> anyhow::Result<(CacheSettings, CachedRenderParams)> {
        let finite_pos = |v: f64| v.is_finite() && v > 0.0;
        anyhow::ensure!(
            (4..=1 << 20).contains(&self.rays),
            "--rays must be between 4 and 1048576"
        );
        anyhow::ensure!((1..=4096).contains(&self.steps), "--steps must be between 1 and 4096");
        let (lo, hi) = volcache::limits::GRADING;
        anyhow::ensure!(
            (lo..=hi).contains(&self.grading),
            "--grading must be between {lo} and {hi}"
        );
        anyhow::ensure!((1..=1024).contains(&self.paths), "--paths must be between 1 and 1024");
        if let Some(n) = self.direct_samples {
            anyhow::ensure!((1..=4096).contains(&n), "--direct-samples must be between 1 and 4096");
        }
        if let Some(k) = self.edge_reach {
            super::common::check_range("--edge-reach", k, volcache::limits::EDGE_REACH)?;
        }
        if let Some(k) = self.lamp_reach {
            super::common::check_range("--lamp-reach", k, volcache::limits::EDGE_REACH)?;
        }
        if let Some(a) = self.eye_cone {
            super::common::check_range("--eye-cone", a, volcache::limits::EYE_CONE_DEG)?;
        }
        super::common::check_range("--phase-roulette", self.phase_roulette, (0.0, 100.0))?;
        self.record_noise.check()?;
        anyhow::ensure!(
            (1..=1024).contains(&self.surface_paths),
            "--surface-paths must be between 1 and 1024"
        );
        let mut cp = CachedRenderParams::from_scene(scene);
        cp.image = image.clone();
        cp.surface_paths = self.surface_paths;
        if let Some(d) = self.march_step {
            anyhow::ensure!(finite_pos(d), "--march-step must be a positive distance");
            cp.march_step = d;
        }
        if let Some(n) = self.place_spp {
            check_spp("--place-spp", n, volcache::limits::MAX_SPP)?;
            anyhow::ensure!(
                n <= image.spp,
                "--place-spp {n} is more than the image's {} camera samples per pixel",
                image.spp
            );
            cp.place_spp = Some(n);
        }
        if let Some(d) = self.image_march_step {
            anyhow::ensure!(
                image.time_budget.is_some() || self.place_spp.is_some(),
                "--image-march-step sets the march of the camera samples beyond the placed ones: give --time-budget or --place-spp"
            );
            anyhow::ensure!(finite_pos(d), "--image-march-step must be a positive distance");
            cp.image_march_step = Some(d);
        }
        if let Some(every) = self.image_march_every {
            anyhow::ensure!(
                image.time_budget.is_some() || self.place_spp.is_some(),
                "--image-march-every sets which camera samples beyond the placed ones march: give --time-budget or --place-spp"
            );
            match every {
                MarchEveryArg::Every(m) => {
                    anyhow::ensure!(
                        (1..=1024).contains(&m),
                        "--image-march-every must be between 1 and 1024, got {m}"
                    );
                    cp.image_march_every = Some(m);
                }
                MarchEveryArg::Auto => {
                    anyhow::ensure!(
                        self.image_march_step.is_none() && self.image_split != Some(ImageSplitArg::Fixed),
                        "--image-march-every auto is chosen by the adaptive split, which chooses the march step too: not beside --image-march-step or --image-split fixed"
                    );
                    cp.adapt_march_share = true;
                }
            }
        }
        let fixed_share = matches!(self.image_march_every, Some(MarchEveryArg::Every(_)));
        cp.adapt_image = match self.image_split {
            _ if cp.adapt_march_share => {
                anyhow::ensure!(
                    image.time_budget.is_some() || self.place_spp.is_some_and(|n| n < image.spp),
                    "--image-march-every auto splits the camera samples beyond the placed ones: give --time-budget, or --place-spp below --spp"
                );
                true
            }
            Some(ImageSplitArg::Adaptive) => {
                anyhow::ensure!(
                    self.image_march_step.is_none() && !fixed_share,
                    "--image-split adaptive chooses how the camera samples beyond the placed ones march: give it or --image-march-step / --image-march-every, not both"
                );
                anyhow::ensure!(
                    image.time_budget.is_some() || self.place_spp.is_some_and(|n| n < image.spp),
                    "--image-split adaptive splits the camera samples beyond the placed ones: give --time-budget, or --place-spp below --spp"
                );
                true
            }
            Some(ImageSplitArg::Fixed) => false,
            None => image.time_budget.is_some() && self.image_march_step.is_none() && !fixed_share,
        };
        if self.surface_cache == SurfaceCacheArg::Ours {
            let e = self.surface_eps.unwrap_or_else(|| default_surface_eps(scene));
            let (lo, hi) = volcache::limits::EPS;
            anyhow::ensure!(
                e.is_finite() && (lo..=hi).contains(&e),
                "--surface-eps must lie between {lo:e} and {hi:e}, got {e}"
            );
            cp.surface_eps = Some(e);
        } else {
            anyhow::ensure!(self.surface_eps.is_none(), "--surface-eps needs --surface-cache ours");
        }
        let eps = self.eps.unwrap_or_else(|| default_eps(method, scene));
        let (lo, hi) = volcache::limits::EPS;
        anyhow::ensure!(
            eps.is_finite() && (lo..=hi).contains(&eps),
            "--eps must lie between {lo:e} and {hi:e}, got {eps}"
        );
        if let Some(n) = self.caches {
            anyhow::ensure!(n > 0, "--caches must be at least 1");
        }
        let mut cs = CacheSettings::new::<volcache::core::space::D3>(method, eps, image.first_vertex_settings());
        cs.probe.rays = self.rays;
        cs.probe.steps = self.steps;
        cs.probe.grading = self.grading;
        cs.probe.paths = self.paths;
        cs.second_order = self.second_order;
        cs.direct_samples = self.direct_samples;
        cs.edge_reach = self.edge_reach;
        if self.no_lamp_reach {
            cs.lamp_reach = None;
        } else if let Some(k) = self.lamp_reach {
            cs.lamp_reach = Some(k);
        }
        cs.eye_cone_deg = self.eye_cone;
        cs.gradient_noise_reach = self.gradient_noise_reach;
        cs.probe.phase_roulette = self.phase_roulette;
        cs.record_noise = self.record_noise.target();
        cs.seed = self.cache_seed;
        Ok((cs, cp))
    }
}

/// The surface cache of a records file, for a render with `--surface-cache ours`
/// (`asked`: its `--surface-eps`, if given, which must be the file's).
fn file_surfaces(
    loaded: &Loaded,
    scene: &Scene,
    asked: Option<f64>,
    path: &std::path::Path,
) -> anyhow::Result<SurfaceCache> {
    let Some(surfaces) = loaded.surface_cache(scene) else {
        anyhow::bail!(
            "--records-in {}: the file holds no surface records (write it with --records-out and \
             --surface-cache ours), but the render asks for --surface-cache ours",
            path.display()
        );
    };
    if let Some(e) = asked.filter(|&e| e != surfaces.eps) {
        anyhow::bail!(
            "--records-in {}: its surface records were placed with --surface-eps {}, not {e}",
            path.display(),
            surfaces.eps
        );
    }
    Ok(surfaces)
}

/// The straight light's samples per point for records read from a file: none if
/// its records hold that light (then asking for samples is an error: they would
/// count it twice), else the file's count or the one asked for.
fn file_direct_samples(file: Option<u32>, asked: Option<u32>, path: &std::path::Path) -> anyhow::Result<Option<u32>> {
    match (file, asked) {
        (None, Some(_)) => anyhow::bail!(
            "--records-in {}: its records hold the light straight from the lights, so --direct-samples \
             cannot apply (place them with --direct-samples to sample that light per point)",
            path.display()
        ),
        (Some(n), asked) => Ok(Some(asked.unwrap_or(n))),
        (None, None) => Ok(None),
    }
}

/// Place (or load) and reconstruct (`place_spp`: the camera samples placement
/// visits, when the image takes more within a time budget). Returns no image with
/// `--place-only`.
pub fn run_cached(
    scene: &Scene,
    (image, place_spp): (&RenderParams, Option<u32>),
    method: CacheMethod,
    a: &Cache3dArgs,
    records: &RecordsArgs,
    progress: &Progress,
) -> anyhow::Result<(Option<Rendered>, CacheSummary)> {
    let (cs, mut cp) = a.settings(scene, image, method)?;
    if let Some(p) = place_spp {
        check_spp("--spp", p, volcache::limits::MAX_SPP)?;
        cp.place_spp = Some(p);
    }
    let mut loaded_surfaces = None;
    let placement = match &records.records_in {
        Some(path) => {
            let loaded = RecordsFile::load(path).map_err(|e| anyhow::anyhow!("--records-in {e}"))?;
            let file = &loaded.file;
            anyhow::ensure!(
                file.method == method,
                "--records-in {}: the records were placed by {:?}, not {:?}",
                path.display(),
                file.method,
                method
            );
            if let Some(why) = file.valid_for.mismatch(&ValidFor::of(scene, &cp)) {
                anyhow::bail!("--records-in {}: {why}", path.display());
            }
            if cp.surface_eps.is_some() {
                loaded_surfaces = Some(file_surfaces(&loaded, scene, a.surface_eps, path)?);
            }
            Placement {
                caches: vec![loaded.cache],
                cached: vec![Cached::Scattered],
                moments: vec![Vec::new()],
                eps: loaded.file.eps,
                query_points: loaded.file.query_points,
                rays: loaded.file.placement_rays,
                seconds: loaded.file.placement_seconds,
                direct_samples: file_direct_samples(loaded.file.direct_samples, a.direct_samples, path)?,
                // The file does not say how noisy its records are.
                value_noise: Default::default(),
                // The file is valid for this camera (`ValidFor::mismatch`).
                eye_cone: volcache::volume::cached::eye_cone(scene, &cp, loaded.file.eye_cone_deg),
            }
        }
        None => {
            let mut memo = RecordMemo::new();
            match a.caches {
                Some(n) => place_with_count(scene, &cp, &cs, n, &mut memo, progress)?,
                None => place(scene, &cp, &cs, &mut memo, progress)?,
            }
        }
    };
    // The surface records: from the file, or placed here (before a records file is
    // written, which carries them, even with --place-only).
    let surfaces = match loaded_surfaces {
        Some(s) => Some(s),
        None => place_surfaces(scene, &cp, &cs, progress)?,
    };
    if let Some(path) = &records.records_out {
        let file = RecordsFile::from_placement(scene, &cp, method, &placement, surfaces.as_ref());
        wrote(path, write_json(path, &file))?;
    }
    let mut summary = CacheSummary {
        settings: CacheSummary::settings_json(&cs),
        eps: placement.eps,
        records: placement.record_count(),
        target_records: a.caches,
        query_points: placement.query_points,
        placed_spp: cp.placed_spp(),
        march_step: cp.march_step,
        image_march_step: cp.image_march_step,
        image_march_every: cp.image_march_every,
        image_split: None,
        image_split_candidates: Vec::new(),
        surface_paths: cp.surface_paths,
        records_relative_noise: placement.value_noise.relative(),
        placement_seconds: placement.seconds,
        placement_rays: placement.rays,
        records_per_second: placement.record_count() as f64 / placement.seconds.max(1e-9),
        reconstruction_seconds: 0.0,
        reconstruction_rays: 0,
        uncovered: 0,
        records_in: records.records_in.as_ref().map(|p| p.display().to_string()),
        records_out: records.records_out.as_ref().map(|p| p.display().to_string()),
        surfaces: surfaces.as_ref().map(|s| SurfaceSummary {
            eps: s.eps,
            records: s.record_count(),
            query_points: s.query_points,
            seconds: s.seconds,
            rays: s.rays,
        }),
    };
    if records.place_only {
        return Ok((None, summary));
    }
    let second_order = cs.second_order && method == CacheMethod::Ours;
    let view = CacheView::of(&placement).with_surfaces(surfaces.as_ref());
    // A time budget is the whole method's: what records took here is not left for
    // the image (records read from a file were paid for by the run that placed them).
    let spent = if records.records_in.is_none() {
        placement.seconds + surfaces.as_ref().map_or(0.0, |s| s.seconds)
    } else {
        0.0
    };
    let r = reconstruct(scene, &image_after(&cp, spent), view, second_order, progress)?;
    summary.reconstruction_seconds = r.image.seconds;
    summary.reconstruction_rays = r.image.rays;
    summary.uncovered = r.uncovered;
    summary.image_split = r.split;
    summary.image_split_candidates = r.split_candidates;
    let mut img = r.image;
    // The image's cost is the whole method's: placement (when it was done here, not
    // read from a file shared by tiles) plus reconstruction.
    if records.records_in.is_none() {
        img.seconds += placement.seconds;
        img.rays += placement.rays;
        if let Some(s) = &surfaces {
            img.seconds += s.seconds;
            img.rays += s.rays;
        }
    }
    Ok((Some(img), summary))
}
