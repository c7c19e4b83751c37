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
    /// Compute the finite-difference reference at the probe.
    #[arg(long, requires = "probe")]
    pub reference: bool,
    /// False colour (log luminance, with a colour bar) instead of tone mapping.
    #[arg(long)]
    pub false_color: bool,
    /// Write this file once everything asked for is computed (for scripts).
    #[arg(long)]
    pub ready_file: Option<PathBuf>,
}

pub fn run(a: AppArgs) -> anyhow::Result<ExitCode> {
    let start = StartOptions {
        probe: a.probe,
        gradients: a.gradients,
        reference: a.reference,
        false_color: a.false_color,
        ready_file: a.ready_file,
    };
    volcache::app::run(a.scene.as_deref(), start)
}
