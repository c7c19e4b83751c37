//! `volcache merge3d`: join the tiles (or crops) of one 3D render, each written by
//! `render3d --tile i/n` (or `--crop`) in its own job, into the full image.
//!
//! The tiles' JSON summaries say which window of which image they cover; the merge
//! checks that they come from the same scene, method and image parameters, that the
//! windows tile the image exactly once, and, for cache methods, that they share one
//! records file (otherwise each tile placed its own records and the merge differs
//! from a full render near tile borders: reported, not refused). Costs add up: the
//! summary's seconds and rays are the sum over tiles, plus a shared placement once.

use super::common::{RENDER3D_BYTES_PER_PIXEL, check_exposure, check_plan, ensure_memory};
use super::image3d::{Summary3d, mean_luminance, output_paths, read_image, reference_errors, write_outputs};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use volcache::core::color::Rgb;
use volcache::limits;
use volcache::output::OutputPlan;
use volcache::progress::Progress;
use volcache::volume::render::Rendered;

#[derive(Args, Debug)]
pub struct Merge3dArgs {
    /// The tiles' JSON summaries (`<scene>_<method>_tile<i>of<n>.json`).
    #[arg(required = true)]
    pub tiles: Vec<PathBuf>,
    /// Output folder: <scene>_<method>.exr, _medium.exr, .png, .json.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Exposure in stops for the PNG (default: the tiles').
    #[arg(long, allow_hyphen_values = true)]
    pub exposure: Option<f64>,
    /// A reference EXR of the full image, for errors (as in `render3d`).
    #[arg(long)]
    pub reference: Option<PathBuf>,
}

fn read_summary(path: &Path) -> anyhow::Result<Summary3d> {
    let text = std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let de = &mut serde_json::Deserializer::from_str(&text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        anyhow::anyhow!(
            "{}: not a render3d summary: at `{}`: {}",
            path.display(),
            e.path(),
            e.inner()
        )
    })
}

pub fn run(a: Merge3dArgs) -> anyhow::Result<ExitCode> {
    let tiles: Vec<(PathBuf, Summary3d)> = a
        .tiles
        .iter()
        .map(|p| read_summary(p).map(|s| (p.clone(), s)))
        .collect::<anyhow::Result<_>>()?;
    let (first_path, first) = &tiles[0];
    let mut full_params = first.params.clone();
    full_params.crop = None;
    let (w, h) = (full_params.width, full_params.height);
    // The summaries are inputs like any other: their image must fit in memory.
    if let Some(why) = limits::resolution_problem(w.min(u32::MAX as usize) as u32, h.min(u32::MAX as usize) as u32) {
        anyhow::bail!("{}: params: the image {why}", first_path.display());
    }
    ensure_memory(w * h, RENDER3D_BYTES_PER_PIXEL, "the merged image")?;
    let stem = Path::new(&first.scene)
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let base = a.out.join(format!("{stem}_{}", first.method));
    let mut plan = OutputPlan::new();
    for (p, t) in &tiles {
        let dir = p.parent().unwrap_or(Path::new("."));
        plan.input("a tile", p)
            .input("a tile", &dir.join(&t.exr))
            .input("a tile", &dir.join(&t.medium_exr));
    }
    if let Some(r) = &a.reference {
        plan.input("--reference", r);
    }
    for p in output_paths(&base) {
        plan.output(format!("--out {}", a.out.display()), &p);
    }
    check_plan(&plan)?;
    let mut cover = vec![0u8; w * h];
    let mut values = vec![Rgb::ZERO; w * h];
    let mut medium = vec![Rgb::ZERO; w * h];
    let (mut seconds, mut rays, mut var_sum) = (0.0, 0u64, 0.0);
    for (path, t) in &tiles {
        let mut p = t.params.clone();
        p.crop = None;
        let same = t.scene_hash == first.scene_hash && t.method == first.method && p == full_params;
        anyhow::ensure!(
            same,
            "{} is not a tile of the same render as {} (scene, method or image parameters differ)",
            path.display(),
            first_path.display()
        );
        let [x0, y0, x1, y1] = t.window;
        anyhow::ensure!(
            x0 < x1 && y0 < y1 && x1 <= w && y1 <= h,
            "{}: window {:?} outside the {w}x{h} image",
            path.display(),
            t.window
        );
        let dir = path.parent().unwrap_or(Path::new("."));
        let (tw, th) = (x1 - x0, y1 - y0);
        let v = read_image(&dir.join(&t.exr), tw, th)?;
        let m = read_image(&dir.join(&t.medium_exr), tw, th)?;
        for j in 0..th {
            for i in 0..tw {
                let k = (y0 + j) * w + x0 + i;
                cover[k] += 1;
                values[k] = v[j * tw + i];
                medium[k] = m[j * tw + i];
            }
        }
        seconds += t.seconds;
        rays += t.rays;
        let rms_se = t.relative_std_error * t.mean_luminance;
        var_sum += rms_se * rms_se * (tw * th) as f64;
    }
    if let Some(k) = cover.iter().position(|&c| c != 1) {
        anyhow::bail!(
            "the tiles do not cover the {w}x{h} image exactly once: pixel ({}, {}) is covered {} times",
            k % w,
            k / w,
            cover[k]
        );
    }
    let mut cache = first.cache.clone();
    if let Some(c) = &mut cache {
        let shared = tiles.iter().all(|(_, t)| {
            t.cache
                .as_ref()
                .is_some_and(|tc| tc.records_in.is_some() && tc.records == c.records && tc.eps == c.eps)
        });
        if shared {
            // Every tile reconstructed from the same records (the surface cache's too,
            // when they have one): placement counted once.
            seconds += c.placement_seconds + c.surfaces.as_ref().map_or(0.0, |s| s.seconds);
            rays += c.placement_rays + c.surfaces.as_ref().map_or(0, |s| s.rays);
        } else {
            eprintln!(
                "note: the tiles placed their own records (no shared --records-in): near tile borders the \
                 merged image differs from a full render"
            );
        }
        c.reconstruction_seconds = tiles
            .iter()
            .filter_map(|(_, t)| t.cache.as_ref())
            .map(|c| c.reconstruction_seconds)
            .sum();
        c.reconstruction_rays = tiles
            .iter()
            .filter_map(|(_, t)| t.cache.as_ref())
            .map(|c| c.reconstruction_rays)
            .sum();
        c.uncovered = tiles
            .iter()
            .filter_map(|(_, t)| t.cache.as_ref())
            .map(|c| c.uncovered)
            .sum();
    }
    let img = Rendered {
        width: w,
        height: h,
        std_error: vec![0.0; w * h],
        values,
        medium,
        spp: first.spp,
        rays,
        seconds,
    };
    let mean = mean_luminance(&img.values);
    let mut summary = Summary3d {
        params: full_params,
        window: [0, 0, w, h],
        seconds,
        rays,
        rays_per_second: rays as f64 / seconds.max(1e-9),
        samples: (w * h) as u64 * first.spp as u64,
        samples_per_second: (w * h) as f64 * first.spp as f64 / seconds.max(1e-9),
        relative_std_error: if mean > 0.0 {
            (var_sum / (w * h) as f64).sqrt() / mean
        } else {
            0.0
        },
        mean_luminance: mean,
        cache,
        errors: None,
        ..first.clone()
    };
    if let Some(r) = &a.reference {
        summary.errors = Some(reference_errors(&img, r)?);
    }
    eprintln!(
        "merged {} tiles into {w}x{h}: {:.2} s, {} rays in all",
        tiles.len(),
        seconds,
        rays
    );
    summary.exposure = a.exposure.unwrap_or(first.exposure);
    check_exposure(summary.exposure)?;
    let exposure = summary.exposure;
    write_outputs(&base, &img, exposure, &mut summary, &Progress::new())
}
