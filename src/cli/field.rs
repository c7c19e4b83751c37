//! `volcache field`: render a scene's radiance field to PNG (+ EXR, JSON).

use super::common::{
    FIELD_BYTES_PER_PIXEL, ProgressUi, cancelled, check_angle, check_exposure, check_plan, check_spp, ensure_memory,
    exr_bytes, load_scene, out_path, parse_res, png_bytes, scene_stem, write_outputs,
};
use clap::{Args, ValueEnum};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::core::color::luminance;
use volcache::figure::{FieldStyle, field_figure};
use volcache::flatland::field::{FieldParams, RenderedField, render_field};
use volcache::flatland::scene_desc::{Part, Quantity};
use volcache::limits;
use volcache::output::OutputPlan;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum QuantityArg {
    Ls,
    Fluence,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum PartArg {
    All,
    Direct,
    Single,
    Multiple,
}

impl From<QuantityArg> for Quantity {
    fn from(q: QuantityArg) -> Self {
        match q {
            QuantityArg::Ls => Quantity::Ls,
            QuantityArg::Fluence => Quantity::Fluence,
        }
    }
}

impl From<PartArg> for Part {
    fn from(p: PartArg) -> Self {
        match p {
            PartArg::All => Part::All,
            PartArg::Direct => Part::Direct,
            PartArg::Single => Part::Single,
            PartArg::Multiple => Part::Multiple,
        }
    }
}

#[derive(Args, Debug)]
pub struct FieldArgs {
    /// Scene JSON (default: the embedded occluder scene).
    pub scene: Option<PathBuf>,
    /// Resolution WxH (default: the scene's render block).
    #[arg(long, value_parser = parse_res)]
    pub res: Option<[u32; 2]>,
    /// Samples per pixel.
    #[arg(long)]
    pub spp: Option<u32>,
    #[arg(long)]
    pub seed: Option<u64>,
    #[arg(long, value_enum)]
    pub quantity: Option<QuantityArg>,
    #[arg(long, value_enum)]
    pub part: Option<PartArg>,
    /// Outgoing direction ω_o of L_s in degrees (matters for g ≠ 0).
    #[arg(long, allow_hyphen_values = true)]
    pub omega_o: Option<f64>,
    /// Exposure in stops for the tone-mapped PNG.
    #[arg(long, allow_hyphen_values = true)]
    pub exposure: Option<f64>,
    /// False colour (log luminance, with a colour bar) instead of tone mapping.
    #[arg(long)]
    pub false_color: bool,
    /// PNG output (default: out/<scene>.png).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Linear float EXR of the field.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// JSON summary (parameters, time, rays, samples/s).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// The JSON summary of a field render.
#[derive(Serialize)]
pub struct FieldSummary<'a> {
    pub volcache_version: &'a str,
    pub scene: &'a str,
    pub description: &'a str,
    pub params: &'a FieldParams,
    pub threads: usize,
    pub seconds: f64,
    pub rays: u64,
    pub samples: u64,
    pub samples_per_second: f64,
    pub rays_per_second: f64,
    /// Mean over valid pixels of standard error / value (luminance).
    pub mean_relative_std_error: f64,
    /// Pixels where the quantity is defined (L_s: inside the medium); the luminance
    /// statistics are over them, and 0 when there are none.
    pub valid_pixels: usize,
    pub luminance_min: f64,
    pub luminance_max: f64,
    pub luminance_mean: f64,
    pub png: Option<String>,
    pub exr: Option<String>,
}

pub fn run(a: FieldArgs) -> anyhow::Result<ExitCode> {
    let scene = load_scene(a.scene.as_deref())?;
    let stem = scene_stem(a.scene.as_deref());
    let mut params = FieldParams::from_scene(&scene);
    if let Some([w, h]) = a.res {
        (params.width, params.height) = (w as usize, h as usize);
    }
    if let Some(s) = a.spp {
        check_spp("--spp", s, limits::MAX_SPP)?;
        params.spp = s;
    }
    params.seed = a.seed.unwrap_or(params.seed);
    params.quantity = a.quantity.map_or(params.quantity, Into::into);
    params.part = a.part.map_or(params.part, Into::into);
    params.omega_o_deg = a.omega_o.unwrap_or(params.omega_o_deg);
    let exposure = a.exposure.unwrap_or(scene.desc.render.exposure);
    check_angle("--omega-o", params.omega_o_deg)?;
    check_exposure(exposure)?;
    ensure_memory(params.width * params.height, FIELD_BYTES_PER_PIXEL, "the field")?;

    let png = out_path(a.out, &stem, ".png");
    let mut plan = OutputPlan::new();
    if let Some(s) = &a.scene {
        plan.input("the scene", s);
    }
    plan.output("--out", &png);
    if let Some(e) = &a.exr {
        plan.output("--exr", e);
    }
    if let Some(j) = &a.json {
        plan.output("--json", j);
    }
    check_plan(&plan)?;

    let label = format!("{stem} {}x{} @ {} spp", params.width, params.height, params.spp);
    let ui = ProgressUi::new(&label, !a.quiet);
    let progress = ui.progress.clone();
    let result = render_field(&scene, &params, &progress);
    ui.finish();
    let Ok(rendered) = result else {
        return cancelled();
    };

    let style = if a.false_color {
        FieldStyle::FalseColor { log: true, range: None }
    } else {
        FieldStyle::Tonemapped { exposure }
    };
    let title = format!(
        "{stem}: {} ({:?}), {} spp",
        quantity_label(params.quantity),
        params.part,
        params.spp
    );
    let pix = field_figure(&rendered.field, Some(&scene), &style, Some(&title));
    let mut files = vec![(png.clone(), png_bytes(&png, &pix)?)];
    if let Some(exr) = &a.exr {
        files.push((exr.clone(), exr_bytes(exr, &rendered.field)?));
    }
    let summary = summarize(
        &scene.source,
        &scene.desc.description,
        &params,
        &rendered,
        Some(&png),
        a.exr.as_deref(),
    );
    eprintln!(
        "{:.2} s, {} rays ({:.3} M rays/s), {:.0} samples/s, mean relative std error {:.2}%",
        summary.seconds,
        summary.rays,
        summary.rays_per_second / 1e6,
        summary.samples_per_second,
        100.0 * summary.mean_relative_std_error
    );
    let json = match &a.json {
        Some(j) => Some((j.as_path(), serde_json::to_value(&summary)?)),
        None => None,
    };
    write_outputs(files, json, &progress)
}

pub(super) fn quantity_label(q: Quantity) -> &'static str {
    match q {
        Quantity::Ls => "L_s",
        Quantity::Fluence => "fluence",
    }
}

pub fn summarize<'a>(
    scene: &'a str,
    description: &'a str,
    params: &'a FieldParams,
    r: &RenderedField,
    png: Option<&std::path::Path>,
    exr: Option<&std::path::Path>,
) -> FieldSummary<'a> {
    let lum: Vec<f64> = r
        .field
        .values
        .iter()
        .zip(&r.field.valid)
        .filter(|(_, v)| **v)
        .map(|(c, _)| luminance(*c))
        .collect();
    let samples = (params.width * params.height) as u64 * params.spp as u64;
    let secs = r.seconds.max(1e-9);
    FieldSummary {
        volcache_version: env!("CARGO_PKG_VERSION"),
        scene,
        description,
        params,
        threads: rayon::current_num_threads(),
        seconds: r.seconds,
        rays: r.rays,
        samples,
        samples_per_second: samples as f64 / secs,
        rays_per_second: r.rays as f64 / secs,
        mean_relative_std_error: r.mean_relative_error(),
        valid_pixels: lum.len(),
        luminance_min: lum.iter().cloned().reduce(f64::min).unwrap_or(0.0),
        luminance_max: lum.iter().cloned().reduce(f64::max).unwrap_or(0.0),
        // (0.0 + …: an empty sum is −0.0.)
        luminance_mean: 0.0 + lum.iter().sum::<f64>() / lum.len().max(1) as f64,
        png: png.map(|p| p.display().to_string()),
        exr: exr.map(|p| p.display().to_string()),
    }
}
