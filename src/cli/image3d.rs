//! What every 3D render writes and how it is read back: linear EXR of the image and
//! of its medium part, a tone-mapped PNG, and a JSON summary ([`Summary3d`]) that
//! `merge3d` and the comparison figures read; errors against a reference EXR; the
//! `--crop` / `--tile` windows.

use super::common::{self, exr_bytes, png_bytes};
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use volcache::core::color::{Rgb, luminance};
use volcache::core::stats::{ImageErrors, luminance_errors};
use volcache::figure::tonemap;
use volcache::output::{image_field, read_exr};
use volcache::progress::Progress;
use volcache::volume::cached::CacheSettings;
use volcache::volume::render::{RenderParams, Rendered};

/// What a cache method placed and what it cost (absent for path tracing).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CacheSummary {
    pub settings: serde_json::Value,
    pub eps: f64,
    pub records: usize,
    pub target_records: Option<usize>,
    pub query_points: u64,
    /// The camera samples of each pixel the placement visited (`--place-spp`;
    /// 0 in summaries written before it was recorded).
    #[serde(default)]
    pub placed_spp: u32,
    pub march_step: f64,
    /// The march step of the camera samples beyond the placed ones, when coarser
    /// (`--image-march-step`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_march_step: Option<f64>,
    /// One camera sample in this many beyond the placed ones marched
    /// (`--image-march-every`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_march_every: Option<u32>,
    /// How the camera samples beyond the placed ones marched, when chosen from
    /// the placed ones' statistics (`--image-split adaptive`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_split: Option<volcache::volume::image_split::ImageSplit>,
    /// Every split those statistics predicted (variance and cost ratios).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub image_split_candidates: Vec<volcache::volume::image_split::ImageSplit>,
    pub surface_paths: u32,
    /// The records' own noise relative to their values, when they were placed
    /// here (`pipeline::placement::ValueNoise`): an error shared by every march
    /// point a record serves, which `relative_std_error` (the camera samples')
    /// does not show.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub records_relative_noise: Option<f64>,
    pub placement_seconds: f64,
    pub placement_rays: u64,
    pub records_per_second: f64,
    pub reconstruction_seconds: f64,
    pub reconstruction_rays: u64,
    /// Query points no visible record covered (zero unless records came from a
    /// window that does not contain this render's).
    pub uncovered: u64,
    /// The records file read (`--records-in`) or written (`--records-out`).
    pub records_in: Option<String>,
    pub records_out: Option<String>,
    /// The surface cache, when the reflected light was read from one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surfaces: Option<SurfaceSummary>,
}

/// A surface cache's records and what placing them cost.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SurfaceSummary {
    pub eps: f64,
    pub records: usize,
    pub query_points: u64,
    pub seconds: f64,
    pub rays: u64,
}

impl CacheSummary {
    pub fn settings_json(cs: &CacheSettings) -> serde_json::Value {
        serde_json::to_value(cs).unwrap_or_default()
    }
}

/// Errors of the image (and of its medium part, when the reference has one).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceErrors {
    pub reference: String,
    pub total: ImageErrors,
    pub medium: Option<ImageErrors>,
}

/// The JSON summary of one render (a whole image, a crop or a tile).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary3d {
    pub volcache_version: String,
    pub scene: String,
    pub scene_hash: String,
    pub description: String,
    /// pt, ours or jarosz08.
    pub method: String,
    pub params: RenderParams,
    /// Window [x0, y0, x1, y1] of the full image this render covers.
    pub window: [usize; 4],
    pub threads: usize,
    pub spp: u32,
    pub seconds: f64,
    pub rays: u64,
    pub rays_per_second: f64,
    /// Camera samples (pixels × spp) and their rate.
    pub samples: u64,
    pub samples_per_second: f64,
    /// RMS per-pixel standard error over the mean (luminance).
    pub relative_std_error: f64,
    pub mean_luminance: f64,
    /// Exposure of the PNG, in stops.
    pub exposure: f64,
    pub triangles: usize,
    /// Closest-hit queries per second on random rays (--bench-rays).
    pub rays3d_closest_hit_per_second: Option<f64>,
    pub cache: Option<CacheSummary>,
    /// `--budget`, when it set ε, the directions and the camera samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budget: Option<f64>,
    pub errors: Option<ReferenceErrors>,
    /// Files, relative to the summary's folder.
    pub exr: String,
    pub medium_exr: String,
    pub png: String,
}

/// Parse `i/n` (0 ≤ i < n).
pub fn parse_tile(s: &str) -> Result<[usize; 2], String> {
    let (i, n) = s.split_once('/').ok_or_else(|| format!("expected i/n, got `{s}`"))?;
    let p = |v: &str| v.trim().parse::<usize>().map_err(|e| format!("`{v}` in `{s}`: {e}"));
    let (i, n) = (p(i)?, p(n)?);
    if n == 0 || i >= n {
        return Err(format!("expected 0 <= i < n, got `{s}`"));
    }
    Ok([i, n])
}

/// Parse `x0,y0,x1,y1` with x0 < x1, y0 < y1.
pub fn parse_crop(s: &str) -> Result<[usize; 4], String> {
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

/// Tile i of n: a band of whole rows, [floor(i·H/n), floor((i+1)·H/n)). Bands of
/// rows keep each tile's work balanced and tile the image exactly.
pub fn tile_window([i, n]: [usize; 2], width: usize, height: usize) -> anyhow::Result<[usize; 4]> {
    anyhow::ensure!(
        n <= height,
        "--tile {i}/{n}: the image has only {height} rows, so at most {height} tiles"
    );
    Ok([0, i * height / n, width, (i + 1) * height / n])
}

/// The window of `params` from `--crop` or `--tile`, checked against the image.
pub fn set_window(
    params: &mut RenderParams,
    crop: Option<[usize; 4]>,
    tile: Option<[usize; 2]>,
) -> anyhow::Result<Option<String>> {
    if let Some(c) = crop {
        anyhow::ensure!(
            c[2] <= params.width && c[3] <= params.height,
            "--crop {c:?} exceeds the image ({}x{})",
            params.width,
            params.height
        );
        params.crop = Some(c);
    }
    Ok(match tile {
        Some(t) => {
            params.crop = Some(tile_window(t, params.width, params.height)?);
            Some(format!("_tile{}of{}", t[0], t[1]))
        }
        None => None,
    })
}

pub fn tonemapped(width: usize, height: usize, values: &[Rgb], exposure: f64) -> anyhow::Result<tiny_skia::Pixmap> {
    let mut pm = tiny_skia::Pixmap::new(width as u32, height as u32)
        .ok_or_else(|| anyhow::anyhow!("cannot make a {width}x{height} image"))?;
    for (px, v) in pm.pixels_mut().iter_mut().zip(values) {
        let [r, g, b] = tonemap(*v, exposure);
        *px = tiny_skia::PremultipliedColorU8::from_rgba(r, g, b, 255).expect("opaque");
    }
    Ok(pm)
}

/// Read an EXR as RGB values, checking its size.
pub fn read_image(path: &Path, width: usize, height: usize) -> anyhow::Result<Vec<Rgb>> {
    let (w, h, px) = read_exr(path)?;
    anyhow::ensure!(
        (w, h) == (width, height),
        "{}: the image is {w}x{h}, expected {width}x{height}",
        path.display()
    );
    Ok(px
        .iter()
        .map(|p| Rgb::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect())
}

/// The medium-part EXR beside an image EXR: `x.exr` → `x_medium.exr`.
pub fn medium_path(exr: &Path) -> PathBuf {
    let stem = exr
        .file_stem()
        .map_or("image".into(), |s| s.to_string_lossy().into_owned());
    exr.with_file_name(format!("{stem}_medium.exr"))
}

/// Errors of `img` against the reference EXR (and its `_medium.exr`, if present).
pub fn reference_errors(img: &Rendered, reference: &Path) -> anyhow::Result<ReferenceErrors> {
    let total = read_image(reference, img.width, img.height).context("--reference")?;
    let med_path = medium_path(reference);
    let medium = if med_path.exists() {
        Some(luminance_errors(
            &img.medium,
            &read_image(&med_path, img.width, img.height)?,
        ))
    } else {
        None
    };
    Ok(ReferenceErrors {
        reference: reference.display().to_string(),
        total: luminance_errors(&img.values, &total),
        medium,
    })
}

/// The files a 3D render writes: `<base>.exr`, `<base>_medium.exr`, `<base>.png`,
/// and the summary `<base>.json` (last).
pub fn output_paths(base: &Path) -> [PathBuf; 4] {
    let exr = base.with_extension("exr");
    [
        medium_path(&exr),
        base.with_extension("png"),
        base.with_extension("json"),
        exr,
    ]
}

/// Write `<base>.exr`, `<base>_medium.exr`, `<base>.png` and `<base>.json` as a set
/// (the summary last, naming the others with their hashes; its file names are
/// filled in here). Returns the exit code (130 when Ctrl-C came).
pub fn write_outputs(
    base: &Path,
    img: &Rendered,
    exposure: f64,
    summary: &mut Summary3d,
    progress: &Progress,
) -> anyhow::Result<ExitCode> {
    let [med, png, json, exr] = output_paths(base);
    let name = |p: &Path| {
        p.file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned())
    };
    (summary.exr, summary.medium_exr, summary.png) = (name(&exr), name(&med), name(&png));
    let files = vec![
        (
            exr.clone(),
            exr_bytes(&exr, &image_field(img.width, img.height, &img.values))?,
        ),
        (
            med.clone(),
            exr_bytes(&med, &image_field(img.width, img.height, &img.medium))?,
        ),
        (
            png.clone(),
            png_bytes(&png, &tonemapped(img.width, img.height, &img.values, exposure)?)?,
        ),
    ];
    common::write_outputs(files, Some((&json, serde_json::to_value(&*summary)?)), progress)
}

/// Mean luminance of an image.
pub fn mean_luminance(values: &[Rgb]) -> f64 {
    values.iter().map(|v| luminance(*v)).sum::<f64>() / values.len().max(1) as f64
}
