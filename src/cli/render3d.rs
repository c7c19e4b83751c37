//! `volcache render3d`: render a 3D scene to linear EXR, tone-mapped PNG and a JSON
//! summary (time, rays, samples/s, ray-casting throughput).

use super::common::{ProgressUi, parse_res, wrote};
use clap::{Args, ValueEnum};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::figure::tonemap;
use volcache::flatland::field::Field;
use volcache::output::{write_exr, write_json, write_png};
use volcache::volume::render::{RenderParams, Rendered, ray_cast_rate, render};
use volcache::volume::scene::Scene;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Reference volumetric path tracing.
    Pt,
    /// Second-order occlusion-aware radiance caching (not implemented yet).
    Ours,
    /// Jarosz et al. 2008 radiance caching (not implemented yet).
    Jarosz08,
}

/// Render a 3D scene (volumetric path tracing) to EXR, PNG and a JSON summary.
#[derive(Args, Debug)]
#[command(about = "Render a 3D scene (volumetric path tracing) to EXR, PNG and a JSON summary")]
pub struct Render3dArgs {
    /// Scene JSON (see scenes3d/).
    pub scene: PathBuf,
    #[arg(long, value_enum, default_value = "pt")]
    pub method: Method,
    /// Samples per pixel (with --time-budget: the most; default there: unlimited).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Resolution WxH (default: the scene's render block).
    #[arg(long, value_parser = parse_res)]
    pub res: Option<[u32; 2]>,
    /// Seed of the per-(pixel, sample) random streams.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Stop adding samples before a pass that would exceed this many seconds.
    #[arg(long)]
    pub time_budget: Option<f64>,
    /// Render only the pixels [x0, x1) × [y0, y1) of the full image (same samples as
    /// the full render, so crops tile it).
    #[arg(long, value_parser = parse_crop)]
    pub crop: Option<[usize; 4]>,
    /// Exposure in stops for the PNG.
    #[arg(long, allow_hyphen_values = true)]
    pub exposure: Option<f64>,
    /// Also measure closest-hit throughput on this many random rays (JSON: rays3d).
    #[arg(long)]
    pub bench_rays: Option<u64>,
    /// Output folder: <scene>_<method>.exr, .png, .json.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    #[arg(long)]
    pub quiet: bool,
}

fn parse_crop(s: &str) -> Result<[usize; 4], String> {
    let v: Vec<usize> = s
        .split(',')
        .map(|p| p.trim().parse::<usize>().map_err(|e| format!("`{p}` in `{s}`: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x0, y0, x1, y1] if x0 < x1 && y0 < y1 => Ok([x0, y0, x1, y1]),
        [_, _, _, _] => Err(format!("expected x0 < x1 and y0 < y1, got `{s}`")),
        _ => Err(format!("expected x0,y0,x1,y1, got `{s}`")),
    }
}

#[derive(Serialize)]
struct Summary<'a> {
    volcache_version: &'a str,
    scene: &'a str,
    description: &'a str,
    method: Method,
    params: &'a RenderParams,
    threads: usize,
    spp: u32,
    seconds: f64,
    rays: u64,
    samples: u64,
    samples_per_second: f64,
    rays_per_second: f64,
    /// RMS per-pixel standard error over the mean (luminance).
    relative_std_error: f64,
    mean_luminance: f64,
    triangles: usize,
    /// Closest-hit queries per second on random rays (--bench-rays).
    rays3d_closest_hit_per_second: Option<f64>,
    exr: String,
    png: String,
}

pub fn run(a: Render3dArgs) -> anyhow::Result<ExitCode> {
    if a.method != Method::Pt {
        anyhow::bail!(
            "--method {} is not implemented yet (issue 6): only --method pt renders for now",
            a.method
                .to_possible_value()
                .map_or("?".into(), |v| v.get_name().to_string())
        );
    }
    let scene = Scene::load(&a.scene)?;
    let stem = a
        .scene
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let mut params = RenderParams::from_scene(&scene);
    if let Some([w, h]) = a.res {
        (params.width, params.height) = (w as usize, h as usize);
    }
    if let Some(b) = a.time_budget {
        anyhow::ensure!(
            b.is_finite() && b > 0.0,
            "--time-budget must be a positive number of seconds"
        );
        params.time_budget = Some(b);
        params.spp = a.spp.unwrap_or(1 << 24);
    } else if let Some(s) = a.spp {
        params.spp = s;
    }
    anyhow::ensure!(params.spp > 0, "--spp must be at least 1");
    params.seed = a.seed.unwrap_or(params.seed);
    if let Some(c) = a.crop {
        anyhow::ensure!(
            c[2] <= params.width && c[3] <= params.height,
            "--crop {c:?} exceeds the image ({}x{})",
            params.width,
            params.height
        );
        params.crop = Some(c);
    }
    let exposure = a.exposure.unwrap_or(scene.desc.render.exposure);
    anyhow::ensure!(exposure.is_finite(), "--exposure must be finite");

    let [x0, y0, x1, y1] = params.window();
    let label = format!("{stem} {}x{} pt", x1 - x0, y1 - y0);
    let ui = ProgressUi::new(&label, !a.quiet);
    let result = render(&scene, &params, &ui.progress);
    ui.finish();
    let Ok(img) = result else {
        eprintln!("cancelled: no output written (existing files left untouched)");
        return Ok(ExitCode::from(130));
    };
    let bench = a.bench_rays.map(|n| ray_cast_rate(&scene, n.max(1), params.seed));

    let base = a.out.join(format!("{stem}_pt"));
    let (exr, png, json) = (
        base.with_extension("exr"),
        base.with_extension("png"),
        base.with_extension("json"),
    );
    wrote(&exr, write_exr(&exr, &as_field(&img)))?;
    wrote(&png, write_png(&png, &tonemapped(&img, exposure)?))?;
    let samples = (img.width * img.height) as u64 * img.spp as u64;
    let secs = img.seconds.max(1e-9);
    let n = img.values.len().max(1) as f64;
    let summary = Summary {
        volcache_version: env!("CARGO_PKG_VERSION"),
        scene: &scene.source,
        description: &scene.desc.description,
        method: a.method,
        params: &params,
        threads: rayon::current_num_threads(),
        spp: img.spp,
        seconds: img.seconds,
        rays: img.rays,
        samples,
        samples_per_second: samples as f64 / secs,
        rays_per_second: img.rays as f64 / secs,
        relative_std_error: img.relative_std_error(),
        mean_luminance: img
            .values
            .iter()
            .map(|v| volcache::core::color::luminance(*v))
            .sum::<f64>()
            / n,
        triangles: scene.triangles.len(),
        rays3d_closest_hit_per_second: bench,
        exr: exr.display().to_string(),
        png: png.display().to_string(),
    };
    eprintln!(
        "{} spp in {:.2} s: {} rays ({:.2} M rays/s), {:.0} samples/s, relative std error {:.2}%",
        img.spp,
        img.seconds,
        img.rays,
        summary.rays_per_second / 1e6,
        summary.samples_per_second,
        100.0 * summary.relative_std_error
    );
    if let Some(b) = bench {
        eprintln!("ray casting: {:.2} M closest-hit rays/s", b / 1e6);
    }
    wrote(&json, write_json(&json, &summary))?;
    Ok(ExitCode::SUCCESS)
}

/// The image as a field (the EXR writer's type); its world rectangle is unused.
fn as_field(img: &Rendered) -> Field {
    let mut f = Field::new(img.width, img.height, glam::DVec2::ZERO, glam::DVec2::ONE);
    f.values.clone_from(&img.values);
    f
}

fn tonemapped(img: &Rendered, exposure: f64) -> anyhow::Result<tiny_skia::Pixmap> {
    let mut pm = tiny_skia::Pixmap::new(img.width as u32, img.height as u32)
        .ok_or_else(|| anyhow::anyhow!("cannot make a {}x{} image", img.width, img.height))?;
    for (px, v) in pm.pixels_mut().iter_mut().zip(&img.values) {
        let [r, g, b] = tonemap(*v, exposure);
        *px = tiny_skia::PremultipliedColorU8::from_rgba(r, g, b, 255).expect("opaque");
    }
    Ok(pm)
}
