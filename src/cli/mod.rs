//! Command-line definitions (clap) and dispatch.

mod app;
mod bench;
mod bench_derivs;
mod bench_moments3d;
mod bench_rays3d;
mod bench_records;
mod bench_tradeoff;
mod bench_tradeoff3d;
mod caches;
mod caches_figures;
mod common;
mod field;
mod figure;
mod figure_compare;
mod figure_compare3d;
mod figure_draw;
mod figure_gradients;
mod image3d;
mod merge3d;
mod probe;
mod probe_args;
mod probe_common;
mod probe_derivs;
mod probe_sensor;
mod render3d;
mod render3d_cache;
mod setup3d;

use clap::{Parser, Subcommand};
pub use common::cancelled;
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "volcache",
    version,
    about = "Second-order occlusion-aware volumetric radiance caching: a research workbench"
)]
pub struct Cli {
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, global = true)]
    threads: Option<usize>,
    /// Without a command: the interactive workbench on the default scene.
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// The interactive workbench (a window): the field, probe inspector, overlays, editing.
    App(app::AppArgs),
    /// Render a scene's radiance field (L_s or fluence) to PNG, and optionally EXR and JSON.
    Field(field::FieldArgs),
    /// Estimate L_s (or fluence) and its parts at points of a 2D or 3D scene, or the mean
    /// irradiance over a sensor (`--sensor`), printed as a table or JSON.
    Probe(probe_args::ProbeArgs),
    /// Reconstruct the field from a radiance cache (ours, jarosz08) or path tracing (pt), with
    /// the cache distribution, the error map against a reference and the costs.
    Caches(caches::CachesArgs),
    /// Benchmarks that print figures and write JSON.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Figures of the paper, computed and drawn (PNG + JSON with every number).
    #[command(subcommand)]
    Figure(figure::FigureCommand),
    Render3d(render3d::Render3dArgs),
    /// Join the tiles of a 3D render (`render3d --tile i/n`) into the full image.
    Merge3d(merge3d::Merge3dArgs),
}

pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build_global()?;
    }
    let Some(command) = cli.command else {
        return app::run(app::AppArgs::default());
    };
    match command {
        Command::App(a) => app::run(a),
        Command::Field(a) => field::run(a),
        Command::Probe(a) => probe::run(a),
        Command::Caches(a) => caches::run(a),
        Command::Bench(b) => bench::run(b),
        Command::Figure(f) => figure::run(f),
        Command::Render3d(a) => render3d::run(a),
        Command::Merge3d(a) => merge3d::run(a),
    }
}
