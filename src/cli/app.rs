//! `volcache app [SCENE]` (and `volcache` alone): the interactive workbench.

use super::common::parse_point;
use clap::Args;
use glam::DVec2;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::app::StartOptions;

#[derive(Args, Debug, Default)]
pub struct AppArgs {
    /// Scene JSON (default: the embedded occluder scene).
    pub scene: Option<PathBuf>,
    /// Place the probe at X,Y.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub probe: Option<DVec2>,
    /// Show the gradient overlay.
    #[arg(long)]
    pub gradients: bool,
    /// Compute the finite-difference reference at the probe (--probe, or --pixel in 3D).
    #[arg(long)]
    pub reference: bool,
    /// False colour (log luminance, with a colour bar) instead of tone mapping.
    #[arg(long)]
    pub false_color: bool,
    /// 3D scenes: how the view renders.
    #[arg(long, value_enum)]
    pub method: Option<volcache::app::render3d_job::Method3d>,
    /// 3D scenes: the view's width in pixels (the height follows the scene's aspect).
    #[arg(long)]
    pub width: Option<usize>,
    /// 3D scenes: place the probe on the camera ray through image point U,V
    /// (fractions of the width and height, 0,0 top left), mid-way through the fog.
    #[arg(long, value_parser = parse_point)]
    pub pixel: Option<DVec2>,
    /// Write this file once everything asked for is computed (for scripts).
    #[arg(long)]
    pub ready_file: Option<PathBuf>,
}

pub fn run(a: AppArgs) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(
        !a.reference || a.probe.is_some() || a.pixel.is_some(),
        "--reference needs a probe: --probe X,Y (2D) or --pixel U,V (3D)"
    );
    let start = StartOptions {
        probe: a.probe,
        gradients: a.gradients,
        reference: a.reference,
        false_color: a.false_color,
        ready_file: a.ready_file,
        method3d: a.method,
        view_width: a.width,
        pixel: a.pixel,
    };
    volcache::app::run(a.scene.as_deref(), start)
}
