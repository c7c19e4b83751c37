//! `volcache figure gradients`: the paper's gradient figure (Marco et al. 2018).
//!
//! For each of aware (ours), unaware (Jarosz et al. 2008) and reference (central
//! finite differences), the gradient of L_s's luminance at the centres of an N × N
//! grid over the scene's domain and at M points along a line, separately for the
//! single- and multiple-scattering parts and for the total (which includes the
//! direct part, zero without point or collimated lights).
//!
//! The study itself (one shared light field per point for aware and unaware, the
//! reference as two half-sample batches whose spread estimates its noise, seeds per
//! point index) is [`volcache::study::gradients`]; this command sizes it from the
//! options, draws it and writes it.
//!
//! Outputs in `--out DIR` (all written atomically, none when cancelled):
//! `gradients_{single,multiple,total}.png`, `profile_{single,multiple,total}.png`
//! and `gradients.json`. Points outside the medium (L_s undefined) are left blank in
//! the panels, break the profile lines and are `null` in the JSON.

use super::common::{ProgressUi, load_scene, parse_point, scene_stem, wrote};
use super::figure_draw::{self, FigureText};
use clap::{Args, ValueEnum};
use glam::DVec2;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use volcache::figure::GradientStyle;
use volcache::output::{write_json, write_png};
use volcache::pipeline::derivatives::{AwareSettings, ReferenceSettings};
use volcache::pipeline::path::Settings;
use volcache::pipeline::probe::ProbeSettings;
use volcache::pipeline::world::World;
use volcache::study::gradient_summary::Summary;
use volcache::study::gradients::{CostOut, GradientStudy, Line, METHODS, PointOut, grid_points, line_points};

/// Parse `X0,Y0,X1,Y1` as a segment of non-zero length.
pub fn parse_line(s: &str) -> Result<Line, String> {
    let v: Vec<&str> = s.split(',').collect();
    if v.len() != 4 {
        return Err(format!("expected X0,Y0,X1,Y1, got `{s}`"));
    }
    let from = parse_point(&format!("{},{}", v[0], v[1]))?;
    let to = parse_point(&format!("{},{}", v[2], v[3]))?;
    if from == to {
        return Err(format!("the line `{s}` has zero length"));
    }
    Ok(Line { from, to })
}

#[derive(Clone, Copy, Debug, ValueEnum, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum StyleArg {
    /// Each grid point fills its cell (as in the paper).
    Cells,
    /// One arrow per grid point on a dark background.
    Arrows,
    /// Cells with dark arrows on top.
    CellsAndArrows,
}

impl From<StyleArg> for GradientStyle {
    fn from(s: StyleArg) -> Self {
        match s {
            StyleArg::Cells => GradientStyle::Cells,
            StyleArg::Arrows => GradientStyle::Arrows,
            StyleArg::CellsAndArrows => GradientStyle::CellsAndArrows,
        }
    }
}

#[derive(Args, Debug)]
pub struct GradientArgs {
    /// Scene JSON (default: the embedded occluder scene).
    pub scene: Option<PathBuf>,
    /// The sampling line X0,Y0,X1,Y1 (world units) of the profile plots.
    #[arg(long, value_parser = parse_line, allow_hyphen_values = true)]
    pub line: Line,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Grid points per side over the scene's domain (cell centres).
    #[arg(long, default_value_t = 16)]
    pub grid: usize,
    /// Points along the line, end points included.
    #[arg(long, default_value_t = 24)]
    pub line_samples: usize,
    /// Directions per light field (aware and unaware share one per point).
    #[arg(long, default_value_t = 2048)]
    pub rays: usize,
    /// Ray-marched medium samples per ray (aware, unaware).
    #[arg(long, default_value_t = 24)]
    pub steps: usize,
    /// Path samples per stencil point of the finite-difference reference, grid points.
    #[arg(long, default_value_t = 4000)]
    pub ref_spp: u32,
    /// The same along the line (default: 4 × --ref-spp; the profiles are few points
    /// and are read closely).
    #[arg(long)]
    pub line_ref_spp: Option<u32>,
    /// Finite-difference step as a fraction of the scene size (as `probe`).
    #[arg(long, default_value_t = ReferenceSettings::default().relative_step)]
    pub fd_step: f64,
    /// Base seed (default: the scene's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// How the gradient panels show the grid.
    #[arg(long, value_enum, default_value = "cells-and-arrows")]
    pub style: StyleArg,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// The scattering parts shown: (key, caption).
const PARTS: [(&str, &str); 3] = [
    ("single", "single scattering"),
    ("multiple", "multiple scattering"),
    ("total", "total (direct + single + multiple)"),
];

#[derive(Serialize)]
struct Params {
    grid: usize,
    line_from: [f64; 2],
    line_to: [f64; 2],
    line_samples: usize,
    rays: usize,
    steps: usize,
    paths: u32,
    ref_spp: u32,
    line_ref_spp: u32,
    /// The reference runs twice at half the samples (noise estimate).
    ref_spp_per_half: u32,
    line_ref_spp_per_half: u32,
    fd_step_relative: f64,
    fd_step: f64,
    seed: u64,
    omega_o_deg: f64,
    max_depth: u32,
    aware: AwareSettings,
    style: StyleArg,
    threads: usize,
}

#[derive(Serialize)]
struct Totals {
    /// The points' costs, summed.
    #[serde(flatten)]
    cost: CostOut,
    /// Wall-clock time of the whole command (points run in parallel).
    wall_seconds: f64,
}

#[derive(Serialize)]
struct Report<'a> {
    volcache_version: &'a str,
    scene: &'a str,
    description: &'a str,
    /// What the numbers are.
    quantity: &'a str,
    methods: [(&'a str, &'a str); 3],
    params: Params,
    /// Errors against the reference on the grid.
    summary_grid: Summary,
    /// Errors against the reference along the line.
    summary_line: Summary,
    totals: Totals,
    grid: Vec<PointOut>,
    line: Vec<PointOut>,
    outputs: Vec<String>,
}

pub fn run(a: GradientArgs) -> anyhow::Result<ExitCode> {
    let wall = Instant::now();
    let scene = load_scene(a.scene.as_deref())?;
    let stem = scene_stem(a.scene.as_deref());
    anyhow::ensure!((1..=256).contains(&a.grid), "--grid must be between 1 and 256");
    anyhow::ensure!(
        (1..=4096).contains(&a.line_samples),
        "--line-samples must be between 1 and 4096"
    );
    anyhow::ensure!(a.rays >= 3, "--rays must be at least 3");
    anyhow::ensure!(a.steps >= 1, "--steps must be at least 1");
    anyhow::ensure!(a.ref_spp >= 2, "--ref-spp must be at least 2 (two halves)");
    let line_ref_spp = a.line_ref_spp.unwrap_or(a.ref_spp.saturating_mul(4));
    anyhow::ensure!(line_ref_spp >= 2, "--line-ref-spp must be at least 2 (two halves)");
    super::common::check_range("--fd-step", a.fd_step, volcache::limits::FD_STEP)?;
    let r = &scene.desc.render;
    let seed = a.seed.unwrap_or(r.seed);
    let omega_o_deg = r.omega_o_deg;
    let ps = ProbeSettings {
        rays: a.rays,
        steps: a.steps,
        settings: Settings {
            max_depth: r.max_depth,
            ..Settings::default()
        },
        ..ProbeSettings::default_for::<volcache::core::space::D2>()
    };
    let aw = AwareSettings::default();

    let grid = grid_points(&scene, a.grid);
    let line = line_points(a.line, a.line_samples);
    let ui = ProgressUi::new(
        &format!("{stem}: gradients at {} + {} points", grid.len(), line.len()),
        !a.quiet,
    );
    let study = GradientStudy {
        scene: &scene,
        omega_o: DVec2::from_angle(omega_o_deg.to_radians()),
        ps,
        aw,
        relative_step: a.fd_step,
    };
    let results = study.run(&grid, &line, seed, a.ref_spp, line_ref_spp, &ui.progress);
    ui.finish();
    let Ok((grid_out, line_out)) = results else {
        return Ok(cancelled_exit());
    };

    let style: GradientStyle = a.style.into();
    let line_seg = (a.line.from, a.line.to);
    let half = |spp: u32| spp.div_ceil(2).max(1);
    let summary_grid = Summary::of(&grid_out);
    let summary_line = Summary::of(&line_out);
    let h = a.fd_step * scene.scale();
    let mut images = Vec::new();
    for (part, part_caption) in PARTS {
        let ps = summary_grid.part(part);
        let text = FigureText {
            title: format!(
                "∇L_s, {part_caption}: {stem} — luminance gradient on a {0}×{0} grid",
                a.grid
            ),
            footer: vec![
                format!(
                    "ours and Jarosz 2008: one shared light field of {} rays × {} march steps per point;  reference: central differences, h = {}, {} paths per stencil point (common random numbers), seed {seed}",
                    a.rays,
                    a.steps,
                    short(h),
                    a.ref_spp
                ),
                format!(
                    "median over the grid vs reference — angle error: ours {:.1}°, Jarosz {:.1}°;  |∇ − ∇ref|/|∇ref|: ours {}, Jarosz {};  reference's own noise ≈ {} of |∇ref|",
                    ps.aware.median_angle_error_deg,
                    ps.unaware.median_angle_error_deg,
                    pct(ps.aware.median_relative_vector_error),
                    pct(ps.unaware.median_relative_vector_error),
                    pct(ps.reference_median_relative_noise),
                ),
            ],
        };
        let panels = METHODS
            .iter()
            .map(|(key, caption)| (caption.to_string(), figure_draw::samples(&grid_out, key, part)))
            .collect::<Vec<_>>();
        let img = figure_draw::gradient_grid_figure(&panels, &scene, line_seg, style, &text);
        images.push((a.out.join(format!("gradients_{part}.png")), img));

        let pl = summary_line.part(part);
        let text = FigureText {
            title: format!(
                "∇L_s, {part_caption}, along the line ({}, {}) → ({}, {}): {stem}",
                short(a.line.from.x),
                short(a.line.from.y),
                short(a.line.to.x),
                short(a.line.to.y)
            ),
            footer: vec![
                format!(
                    "{} points; {} rays per light field; reference: {} paths per stencil point, h = {}; dotted: reference ± 1σ, σ estimated per point from two independent half-sample runs",
                    a.line_samples,
                    a.rays,
                    line_ref_spp,
                    short(h)
                ),
                format!(
                    "median |∇ − ∇ref|/|∇ref| along the line: ours {}, Jarosz {};  reference's own noise ≈ {} of |∇ref|",
                    pct(pl.aware.median_relative_vector_error),
                    pct(pl.unaware.median_relative_vector_error),
                    pct(pl.reference_median_relative_noise),
                ),
            ],
        };
        let x_label = format!(
            "s (fraction of the way from ({}, {}) to ({}, {}))",
            short(a.line.from.x),
            short(a.line.from.y),
            short(a.line.to.x),
            short(a.line.to.y)
        );
        let img = figure_draw::profile_figure(&line_out, part, &x_label, &text);
        images.push((a.out.join(format!("profile_{part}.png")), img));
    }
    let json_path = a.out.join("gradients.json");
    let mut outputs: Vec<String> = images.iter().map(|(p, _)| p.display().to_string()).collect();
    outputs.push(json_path.display().to_string());

    let totals = Totals {
        cost: CostOut::total(grid_out.iter().chain(&line_out)),
        wall_seconds: wall.elapsed().as_secs_f64(),
    };
    let report = Report {
        volcache_version: env!("CARGO_PKG_VERSION"),
        scene: &scene.source,
        description: &scene.desc.description,
        quantity: "luminance of the in-scattered radiance L_s (towards omega_o) with its gradient and Hessian \
                   with respect to the point; parts: direct (point/collimated lights), single (from surfaces), \
                   multiple (from the medium), total = sum; null outside the medium",
        methods: METHODS,
        params: Params {
            grid: a.grid,
            line_from: a.line.from.to_array(),
            line_to: a.line.to.to_array(),
            line_samples: a.line_samples,
            rays: a.rays,
            steps: a.steps,
            paths: ps.paths,
            ref_spp: a.ref_spp,
            line_ref_spp,
            ref_spp_per_half: half(a.ref_spp),
            line_ref_spp_per_half: half(line_ref_spp),
            fd_step_relative: a.fd_step,
            fd_step: h,
            seed,
            omega_o_deg,
            max_depth: r.max_depth,
            aware: aw,
            style: a.style,
            threads: rayon::current_num_threads(),
        },
        summary_grid,
        summary_line,
        totals,
        grid: grid_out,
        line: line_out,
        outputs,
    };
    for (path, img) in &images {
        wrote(path, write_png(path, img))?;
    }
    wrote(&json_path, write_json(&json_path, &report))?;
    print_summary(&report.summary_grid, "grid");
    print_summary(&report.summary_line, "line");
    eprintln!(
        "{:.1} s: {} light-field rays, {} reference rays",
        report.totals.wall_seconds, report.totals.cost.capture_rays, report.totals.cost.reference_rays
    );
    Ok(ExitCode::SUCCESS)
}

fn print_summary(s: &Summary, what: &str) {
    for (part, _) in PARTS {
        let p = s.part(part);
        eprintln!(
            "{what:>4} {part:>8}: median |∇ − ∇ref|/|∇ref| ours {:>6}, Jarosz {:>6}; angle ours {:>5.1}°, Jarosz {:>5.1}°; reference noise {:>6}",
            pct(p.aware.median_relative_vector_error),
            pct(p.unaware.median_relative_vector_error),
            p.aware.median_angle_error_deg,
            p.unaware.median_angle_error_deg,
            pct(p.reference_median_relative_noise)
        );
    }
}

fn cancelled_exit() -> ExitCode {
    eprintln!("cancelled: no output written (existing files left untouched)");
    ExitCode::from(130)
}

fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{:.0}%", 100.0 * v)
    } else {
        "n/a".into()
    }
}

/// A short decimal for captions.
fn short(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}
