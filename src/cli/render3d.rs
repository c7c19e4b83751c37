//! `volcache render3d`: render a 3D scene by volumetric path tracing (`pt`) or from
//! a radiance cache (`ours`, `jarosz08`), to linear EXR (image and medium part),
//! tone-mapped PNG and a JSON summary (time, rays, records, errors against a
//! reference). `--crop` / `--tile i/n` render a window of the full image with the
//! full image's samples, so tiles from separate jobs merge (`merge3d`) into the
//! full render; cache methods share their records through `--records-out` /
//! `--records-in`.

use super::common::{
    ProgressUi, RENDER3D_BYTES_PER_PIXEL, cancelled, check_exposure, check_plan, check_range, check_spp, ensure_memory,
    parse_res,
};
use super::image3d::{
    CacheSummary, Summary3d, mean_luminance, medium_path, output_paths, parse_crop, parse_tile, reference_errors,
    set_window, write_outputs,
};
use super::render3d_cache::{Cache3dArgs, RecordsArgs, run_cached};
use clap::{Args, ValueEnum};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use volcache::core::metric::CacheMethod;
use volcache::limits;
use volcache::output::OutputPlan;
use volcache::pipeline::budget::{MAX_BUDGET, MIN_BUDGET};
use volcache::pipeline::path::Sampling;
use volcache::volume::cached::budget_settings;
use volcache::volume::records_file::scene_hash;
use volcache::volume::render::{RenderParams, Rendered, ray_cast_rate, render};
use volcache::volume::scene::Scene;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Reference volumetric path tracing.
    Pt,
    /// Second-order occlusion-aware radiance caching (Hessian ellipsoids).
    Ours,
    /// Jarosz et al. 2008 radiance caching (occlusion-unaware gradients, balls).
    Jarosz08,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Pt => "pt",
            Method::Ours => "ours",
            Method::Jarosz08 => "jarosz08",
        }
    }

    /// The cache method, None for path tracing.
    fn cache_method(self) -> Option<CacheMethod> {
        match self {
            Method::Pt => None,
            Method::Ours => Some(CacheMethod::Ours),
            Method::Jarosz08 => Some(CacheMethod::Jarosz08),
        }
    }
}

/// Render a 3D scene by path tracing or from a radiance cache.
#[derive(Args, Debug)]
#[command(about = "Render a 3D scene (path tracing or radiance caching) to EXR, PNG and a JSON summary")]
pub struct Render3dArgs {
    /// Scene JSON (see scenes3d/).
    pub scene: PathBuf,
    #[arg(long, value_enum, default_value = "pt")]
    pub method: Method,
    /// Samples per pixel (pt default: the scene's; caches: camera samples, default 4;
    /// with --time-budget: the most, default unlimited).
    #[arg(long, conflicts_with = "budget")]
    pub spp: Option<u32>,
    /// Resolution WxH (default: the scene's render block).
    #[arg(long, value_parser = parse_res)]
    pub res: Option<[u32; 2]>,
    /// Seed of the per-(pixel, sample) random streams.
    #[arg(long)]
    pub seed: Option<u64>,
    /// How a pixel's camera samples draw their random numbers: independent by
    /// default in 3D; stratified spreads the pixel position and the first light
    /// and lobe samples, as pbrt-v4's samplers do (`path::Sampling`).
    #[arg(long, value_enum, default_value = "independent")]
    pub sampling: Sampling,
    /// Leave out the legs that paths and records' paths aim near point lamps
    /// (`pipeline::lamp_aim`): only to measure what they gain.
    #[arg(long)]
    pub no_aimed_legs: bool,
    /// Stop adding camera samples before a pass that would exceed this many seconds
    /// in all. Cache methods: the records' placement counts, and --spp is the camera
    /// samples placement visits (default 4); the time left adds camera samples
    /// (interpolation is cheap), points no record covers being path traced.
    #[arg(long, conflicts_with = "budget")]
    pub time_budget: Option<f64>,
    /// One budget for ours (`pipeline::budget::VOLUME`): B = 1 is ε a quarter of
    /// the scene's default, 256 directions per record and 64 camera samples per
    /// pixel; a budget k times larger costs k times as much by the error model's
    /// count (measured at 48×36: 1.5–2.3× per 4×, as a record's fixed cost does not
    /// grow with its directions), spent where the model says it pays (ε,
    /// directions and camera samples, so that their errors fall alike). Sets
    /// --eps, --rays and --spp; the straight light is sampled at every march
    /// point (--direct-samples 4 unless given) and the records are placed over
    /// one camera sample in eight (--place-spp unless given).
    #[arg(long, conflicts_with_all = ["eps", "caches", "rays", "records_in"])]
    pub budget: Option<f64>,
    /// Render only the pixels [x0, x1) × [y0, y1) of the full image (same samples as
    /// the full render, so crops tile it; cache methods: when they reconstruct from
    /// the full image's records, --records-in, else they place records for the crop).
    #[arg(long, value_parser = parse_crop, conflicts_with = "tile")]
    pub crop: Option<[usize; 4]>,
    /// Render tile i of n (0 ≤ i < n): rows [i·H/n, (i+1)·H/n). Outputs are named
    /// `<scene>_<method>_tile<i>of<n>.*`; `volcache merge3d` joins them.
    #[arg(long, value_parser = parse_tile)]
    pub tile: Option<[usize; 2]>,
    #[command(flatten)]
    pub cache: Cache3dArgs,
    #[command(flatten)]
    pub records: RecordsArgs,
    /// A reference EXR of the same window (e.g. a long `--method pt` render): RMSE and
    /// relMSE of the image, and of its medium part when `<reference>_medium.exr` exists.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Exposure in stops for the PNG.
    #[arg(long, allow_hyphen_values = true)]
    pub exposure: Option<f64>,
    /// Also measure closest-hit throughput on this many random rays (JSON: rays3d).
    #[arg(long)]
    pub bench_rays: Option<u64>,
    /// Output folder: <scene>_<method>.exr, _medium.exr, .png, .json.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    #[arg(long)]
    pub quiet: bool,
}

/// The summary fields every method fills the same way.
pub fn summary(scene: &Scene, method: Method, params: &RenderParams, img: &Rendered) -> Summary3d {
    Summary3d {
        volcache_version: env!("CARGO_PKG_VERSION").into(),
        scene: scene.source.clone(),
        scene_hash: scene_hash(scene),
        description: scene.desc.description.clone(),
        method: method.name().into(),
        params: params.clone(),
        window: params.window(),
        threads: rayon::current_num_threads(),
        spp: img.spp,
        seconds: img.seconds,
        rays: img.rays,
        rays_per_second: img.rays as f64 / img.seconds.max(1e-9),
        samples: (img.width * img.height) as u64 * img.spp as u64,
        samples_per_second: (img.width * img.height) as f64 * img.spp as f64 / img.seconds.max(1e-9),
        relative_std_error: img.relative_std_error(),
        mean_luminance: mean_luminance(&img.values),
        exposure: scene.desc.render.exposure,
        triangles: scene.geometry.len(),
        rays3d_closest_hit_per_second: None,
        cache: None,
        budget: None,
        errors: None,
        exr: String::new(),
        medium_exr: String::new(),
        png: String::new(),
    }
}

pub fn run(a: Render3dArgs) -> anyhow::Result<ExitCode> {
    let scene = Scene::load(&a.scene)?;
    let stem = a
        .scene
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let mut params = RenderParams::from_scene(&scene);
    let mut cache = a.cache.clone();
    params.settings.sampling = a.sampling;
    params.settings.aimed_legs = !a.no_aimed_legs;
    if let Some([w, h]) = a.res {
        (params.width, params.height) = (w as usize, h as usize);
    }
    if let Some(b) = a.time_budget {
        anyhow::ensure!(
            b.is_finite() && b > 0.0,
            "--time-budget must be a positive number of seconds"
        );
        params.time_budget = Some(b);
        anyhow::ensure!(
            a.spp.is_none() || a.cache.place_spp.is_none() || a.method == Method::Pt,
            "--spp beside --time-budget is the camera samples placement visits: give it or --place-spp, not both"
        );
        params.spp = match a.method {
            Method::Pt => a.spp.unwrap_or(1 << 24),
            // --spp is then the camera samples placement visits; more follow.
            _ => 1 << 24,
        };
    } else if let Some(b) = a.budget {
        check_range("--budget", b, (MIN_BUDGET, MAX_BUDGET))?;
        anyhow::ensure!(
            a.method == Method::Ours,
            "--budget schedules ours (its error model was measured for ours), not --method {}: give --spp (and --eps or --caches)",
            a.method.name()
        );
        let s = budget_settings(&scene, b);
        (cache.eps, cache.rays, params.spp) = (Some(s.eps), s.rays, s.spp);
        cache.budget_defaults(&s);
    } else if let Some(s) = a.spp {
        check_spp("--spp", s, limits::MAX_SPP)?;
        params.spp = s;
    } else if a.method != Method::Pt {
        params.spp = 4;
    }
    anyhow::ensure!(params.spp > 0, "--spp must be at least 1");
    params.seed = a.seed.unwrap_or(params.seed);
    let tile_suffix = set_window(&mut params, a.crop, a.tile)?;
    let exposure = a.exposure.unwrap_or(scene.desc.render.exposure);
    check_exposure(exposure)?;
    ensure_memory(params.width * params.height, RENDER3D_BYTES_PER_PIXEL, "the image")?;
    let base = a.out.join(format!(
        "{stem}_{}{}",
        a.method.name(),
        tile_suffix.clone().unwrap_or_default()
    ));
    check_plan(&plan(&a, &scene, &base))?;

    let [x0, y0, x1, y1] = params.window();
    let label = format!("{stem} {}x{} {}", x1 - x0, y1 - y0, a.method.name());
    let ui = ProgressUi::new(&label, !a.quiet);
    let progress = ui.progress.clone();
    let result: Result<(Option<Rendered>, Option<CacheSummary>), anyhow::Error> = match a.method.cache_method() {
        None => render(&scene, &params, &progress)
            .map(|img| (Some(img), None))
            .map_err(anyhow::Error::from),
        Some(m) => {
            // With a time budget the camera samples placement visits are --spp's or
            // --place-spp's (the rest added as the time allows).
            let place_spp = a.time_budget.map(|_| a.cache.place_spp.or(a.spp).unwrap_or(4));
            run_cached(&scene, (&params, place_spp), m, &cache, &a.records, &progress).map(|(img, c)| (img, Some(c)))
        }
    };
    ui.finish();
    let (img, cache) = match result {
        Ok(r) => r,
        Err(e) if e.is::<volcache::progress::Cancelled>() => return cancelled(),
        Err(e) => return Err(e),
    };
    let Some(img) = img else {
        if let Some(c) = &cache {
            eprintln!(
                "placed {} records (ε = {:.3e}) in {:.2} s; no image rendered (--place-only)",
                c.records, c.eps, c.placement_seconds
            );
        }
        return Ok(ExitCode::SUCCESS);
    };
    let mut summary = summary(&scene, a.method, &params, &img);
    summary.cache = cache;
    summary.budget = a.budget;
    summary.exposure = exposure;
    summary.rays3d_closest_hit_per_second = a.bench_rays.map(|n| ray_cast_rate(&scene, n.max(1), params.seed));
    if let Some(r) = &a.reference {
        summary.errors = Some(reference_errors(&img, r)?);
    }
    report(&summary, &img);
    write_outputs(&base, &img, exposure, &mut summary, &progress)
}

/// What a render that overran its time budget by more than 5% says about why:
/// a cache method's records, and the camera samples its placement visited, are
/// rendered whatever the budget; a path tracer's first sample per pixel is too.
fn over_budget(s: &Summary3d) -> Option<String> {
    let budget = s.params.time_budget?;
    if s.seconds <= 1.05 * budget {
        return None;
    }
    let head = format!("note: --time-budget {budget} s exceeded ({:.3} s in all):", s.seconds);
    Some(match &s.cache {
        Some(c) => {
            let surfaces = c.surfaces.as_ref().map_or(0.0, |x| x.seconds);
            let records = c.placement_seconds + surfaces;
            format!(
                "{head} the records took {records:.1} s{} and the {} camera samples per pixel they were placed \
                 over, which are always rendered, the rest; a larger --eps (or --surface-eps), fewer --rays or \
                 fewer --spp fit a budget this short",
                if surfaces > 0.0 {
                    format!(" ({surfaces:.1} s of it surface records)")
                } else {
                    String::new()
                },
                c.placed_spp
            )
        }
        None => format!(
            "{head} a pass is shortened to fit but at least one sample per pixel is rendered ({} rendered); \
             a smaller --res or a --crop fits a budget this short",
            s.spp
        ),
    })
}

/// What a render reads (the scene, its meshes, records and reference) and writes.
fn plan(a: &Render3dArgs, scene: &Scene, base: &Path) -> OutputPlan {
    let mut plan = OutputPlan::new();
    plan.input("the scene", &a.scene);
    let dir = a.scene.parent().unwrap_or(Path::new("."));
    for (i, s) in scene.desc.shapes.iter().enumerate() {
        if let Some(m) = &s.mesh {
            plan.input(format!("the mesh of shapes[{i}]"), &dir.join(&m.path));
        }
    }
    if let Some(r) = &a.records.records_in {
        plan.input("--records-in", r);
    }
    if let Some(r) = &a.reference {
        plan.input("--reference", r).input("--reference", &medium_path(r));
    }
    if let Some(r) = &a.records.records_out {
        plan.output("--records-out", r);
    }
    if !a.records.place_only {
        for p in output_paths(base) {
            plan.output(format!("--out {}", a.out.display()), &p);
        }
    }
    plan
}

fn report(s: &Summary3d, img: &Rendered) {
    eprintln!(
        "{} spp in {:.2} s: {} rays ({:.2} M rays/s), relative std error {:.2}%",
        img.spp,
        s.seconds,
        s.rays,
        s.rays_per_second / 1e6,
        100.0 * s.relative_std_error
    );
    if let Some(c) = &s.cache {
        eprintln!(
            "cache: {} records (ε = {:.3e}) over {} query points; placement {:.2} s ({:.1} records/s), \
             reconstruction {:.2} s{}",
            c.records,
            c.eps,
            c.query_points,
            c.placement_seconds,
            c.records_per_second,
            c.reconstruction_seconds,
            if c.uncovered > 0 {
                format!("; {} query points uncovered", c.uncovered)
            } else {
                String::new()
            }
        );
    }
    if let Some(note) = over_budget(s) {
        eprintln!("{note}");
    }
    if let Some(b) = s.rays3d_closest_hit_per_second {
        eprintln!("ray casting: {:.2} M closest-hit rays/s", b / 1e6);
    }
    if let Some(e) = &s.errors {
        eprintln!(
            "against {}: RMSE {:.4e}, relMSE {:.4e}{}",
            e.reference,
            e.total.rmse,
            e.total.relmse,
            e.medium
                .map_or(String::new(), |m| format!("; medium part RMSE {:.4e}", m.rmse))
        );
    }
}
