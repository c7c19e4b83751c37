//! `volcache figure gradients`: the paper's gradient figure (Marco et al. 2018).
//!
//! For each of aware (ours), unaware (Jarosz et al. 2008) and reference (central
//! finite differences), the gradient of L_s's luminance at the centres of an N × N
//! grid over the scene's domain and at M points along a line, separately for the
//! single- and multiple-scattering parts and for the total (which includes the
//! direct part, zero without point or collimated lights).
//!
//! - aware and unaware are evaluated on **one shared light field** per point
//!   (`--rays` directions), so their differences are the methods', not the noise's;
//! - the reference is the average of two independent runs at half the samples each
//!   (same total cost as one run), and half their difference, |∇₁ − ∇₂| / 2,
//!   estimates the RMS error of the reference gradient: written per point and
//!   summarised (median relative to |∇L|) in the JSON and under the figures, so a
//!   reader can tell a method's error from the reference's own noise;
//! - every point's random streams derive from `--seed` and the point's index (grid
//!   points 0.., line points 2³² + 0..), so results do not depend on the thread
//!   count, and the grid does not change the line's numbers.
//!
//! Outputs in `--out DIR` (all written atomically, none when cancelled):
//! `gradients_{single,multiple,total}.png`, `profile_{single,multiple,total}.png`
//! and `gradients.json`. Points outside the medium (L_s undefined) are left blank in
//! the panels, break the profile lines and are `null` in the JSON.

use super::common::{ProgressUi, load_scene, parse_point, scene_stem, wrote};
use super::figure_draw::{self, FigureText};
use clap::{Args, Subcommand, ValueEnum};
use glam::{DMat2, DVec2};
use rayon::prelude::*;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use volcache::core::rng::mix64;
use volcache::core::space::D2;
use volcache::core::taylor::Taylor2;
use volcache::core::taylor_rgb::TaylorRgb;
use volcache::figure::GradientStyle;
use volcache::flatland::derivatives::{self, AwareSettings, PartDerivs, ReferenceSettings};
use volcache::flatland::probe::{ProbeSettings, capture};
use volcache::flatland::proxy;
use volcache::flatland::scene::Scene;
use volcache::flatland::transport::Settings;
use volcache::output::{write_json, write_png};
use volcache::progress::{Cancelled, Progress};

#[derive(Subcommand, Debug)]
pub enum FigureCommand {
    /// The paper's gradient figure: ∇L_s by ours (aware), Jarosz 2008 (unaware) and
    /// finite differences (reference) on a grid and along a line, per scattering part.
    Gradients(GradientArgs),
    /// Reference, ours and Jarosz 2008 side by side at equal cache count: fields, cache
    /// distributions and error maps, with records, rays, time and RMSE in the captions.
    Compare(super::figure_compare::CompareArgs),
    /// 3D: reference, ours and Jarosz 2008 at equal cache count and path tracing at
    /// equal time, with zoomed insets, records projected into the image, error maps
    /// and the numbers.
    Compare3d(super::figure_compare3d::Compare3dArgs),
}

/// A segment `X0,Y0,X1,Y1` in world units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    pub from: DVec2,
    pub to: DVec2,
}

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

/// The methods in panel order: (key, panel caption).
pub const METHODS: [(&str, &str); 3] = [
    ("aware", "ours (aware)"),
    ("unaware", "Jarosz 2008 (unaware)"),
    ("reference", "reference (finite differences)"),
];

fn part_of(p: &PartDerivs, key: &str) -> TaylorRgb<D2> {
    match key {
        "direct" => p.direct,
        "single" => p.single,
        "multiple" => p.multiple,
        _ => p.total(),
    }
}

/// Luminance value, gradient and (if the method has one) Hessian of one part.
#[derive(Serialize, Clone, Copy, Debug)]
pub struct TaylorOut {
    pub value: f64,
    pub gradient: [f64; 2],
    /// Row-major; None for first-order methods.
    pub hessian: Option<[[f64; 2]; 2]>,
}

impl TaylorOut {
    fn new(t: &Taylor2<D2>, hessian: bool) -> Self {
        let h: DMat2 = t.hess;
        TaylorOut {
            value: t.value,
            gradient: t.grad.to_array(),
            // Symmetric, so columns and rows agree; written row-major anyway.
            hessian: hessian.then_some([[h.x_axis.x, h.y_axis.x], [h.x_axis.y, h.y_axis.y]]),
        }
    }

    pub fn grad(&self) -> DVec2 {
        DVec2::from_array(self.gradient)
    }
}

/// One method's answer at a point, per part (luminance).
#[derive(Serialize, Clone, Copy, Debug)]
pub struct MethodOut {
    pub direct: TaylorOut,
    pub single: TaylorOut,
    pub multiple: TaylorOut,
    pub total: TaylorOut,
}

impl MethodOut {
    fn new(p: &PartDerivs, hessian: bool) -> Self {
        let f = |k| TaylorOut::new(&part_of(p, k).luminance(), hessian);
        MethodOut {
            direct: f("direct"),
            single: f("single"),
            multiple: f("multiple"),
            total: f("total"),
        }
    }

    pub fn part(&self, key: &str) -> &TaylorOut {
        match key {
            "direct" => &self.direct,
            "single" => &self.single,
            "multiple" => &self.multiple,
            _ => &self.total,
        }
    }
}

/// |∇₁ − ∇₂| / 2 of the reference's two half-sample runs, per part: an estimate of
/// the RMS error of the reference gradient (a one-sample estimate: noisy itself).
#[derive(Serialize, Clone, Copy, Debug)]
pub struct NoiseOut {
    pub single: f64,
    pub multiple: f64,
    pub total: f64,
}

impl NoiseOut {
    pub fn part(&self, key: &str) -> f64 {
        match key {
            "single" => self.single,
            "multiple" => self.multiple,
            _ => self.total,
        }
    }
}

/// What a point cost.
#[derive(Serialize, Clone, Copy, Debug, Default)]
pub struct CostOut {
    /// Light field capture (shared by aware and unaware).
    pub capture_rays: u64,
    pub capture_seconds: f64,
    /// Proxy construction and evaluation of the aware derivatives.
    pub aware_seconds: f64,
    pub unaware_seconds: f64,
    pub reference_rays: u64,
    pub reference_seconds: f64,
}

/// Everything computed at one point.
#[derive(Serialize, Clone, Debug)]
pub struct PointOut {
    /// Position along the line in [0, 1] (line points only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub s: Option<f64>,
    pub at: [f64; 2],
    pub inside_medium: bool,
    /// The seed all of this point's streams derive from.
    pub seed: u64,
    pub aware: Option<MethodOut>,
    pub unaware: Option<MethodOut>,
    pub reference: Option<MethodOut>,
    pub reference_gradient_noise: Option<NoiseOut>,
    pub cost: CostOut,
}

impl PointOut {
    pub fn method(&self, key: &str) -> Option<&MethodOut> {
        match key {
            "aware" => self.aware.as_ref(),
            "unaware" => self.unaware.as_ref(),
            _ => self.reference.as_ref(),
        }
    }
}

/// Settings shared by all points.
struct Job<'a> {
    scene: &'a Scene,
    omega_o: DVec2,
    ps: ProbeSettings,
    aw: AwareSettings,
    relative_step: f64,
    progress: &'a Progress,
}

fn average(a: &PartDerivs, b: &PartDerivs) -> PartDerivs {
    PartDerivs {
        direct: (a.direct + b.direct).scale(0.5),
        single: (a.single + b.single).scale(0.5),
        multiple: (a.multiple + b.multiple).scale(0.5),
    }
}

fn half_difference(a: &PartDerivs, b: &PartDerivs, key: &str) -> f64 {
    0.5 * (part_of(a, key).luminance().grad - part_of(b, key).luminance().grad).length()
}

/// The three methods at `x`; `seed` is the point's own.
fn compute_point(job: &Job, x: DVec2, s: Option<f64>, seed: u64, ref_spp: u32) -> Result<PointOut, Cancelled> {
    job.progress.check()?;
    let mut out = PointOut {
        s,
        at: x.to_array(),
        inside_medium: job.scene.medium_at(x).is_some(),
        seed,
        aware: None,
        unaware: None,
        reference: None,
        reference_gradient_noise: None,
        cost: CostOut::default(),
    };
    if !out.inside_medium {
        return Ok(out);
    }
    let lf = capture(job.scene, x, job.omega_o, &job.ps, seed, 0, job.progress)?;
    out.cost.capture_rays = lf.cost_rays;
    out.cost.capture_seconds = lf.seconds;

    let t = Instant::now();
    let elements = proxy::build(&lf, job.aw.rule);
    let aware = derivatives::aware(&lf, &elements, &job.aw);
    out.cost.aware_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let unaware = derivatives::unaware(&lf);
    out.cost.unaware_seconds = t.elapsed().as_secs_f64();
    drop(lf);
    job.progress.check()?;

    // Two independent halves: their mean is the reference, their spread its noise.
    let rs = ReferenceSettings {
        spp: ref_spp.div_ceil(2).max(1),
        relative_step: job.relative_step,
    };
    let r =
        [1u64, 2].map(|k| derivatives::reference(job.scene, x, job.omega_o, &rs, &job.ps.settings, mix64(seed ^ k)));
    let reference = average(&r[0].parts, &r[1].parts);
    out.cost.reference_rays = r.iter().map(|d| d.rays).sum();
    out.cost.reference_seconds = r.iter().map(|d| d.seconds).sum();

    out.aware = Some(MethodOut::new(&aware, true));
    out.unaware = Some(MethodOut::new(&unaware, false));
    out.reference = Some(MethodOut::new(&reference, true));
    out.reference_gradient_noise = Some(NoiseOut {
        single: half_difference(&r[0].parts, &r[1].parts, "single"),
        multiple: half_difference(&r[0].parts, &r[1].parts, "multiple"),
        total: half_difference(&r[0].parts, &r[1].parts, "total"),
    });
    Ok(out)
}

/// The seed of grid point `k` (`line` false) or line point `k`.
pub fn point_seed(seed: u64, k: usize, line: bool) -> u64 {
    let index = k as u64 + if line { 1 << 32 } else { 0 };
    mix64(seed ^ mix64(index))
}

/// Cell centres of an n × n grid over the domain, row by row from the bottom.
pub fn grid_points(scene: &Scene, n: usize) -> Vec<DVec2> {
    let (lo, size) = (scene.domain_min, scene.domain_max - scene.domain_min);
    (0..n * n)
        .map(|k| lo + size * DVec2::new((k % n) as f64 + 0.5, (k / n) as f64 + 0.5) / n as f64)
        .collect()
}

/// m points from `from` to `to`, end points included, with their s ∈ [0, 1].
pub fn line_points(line: Line, m: usize) -> Vec<(f64, DVec2)> {
    (0..m)
        .map(|i| {
            let s = if m > 1 { i as f64 / (m - 1) as f64 } else { 0.5 };
            (s, line.from.lerp(line.to, s))
        })
        .collect()
}

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

/// Error of a method's gradient against the reference's, summarised by medians over
/// the points inside the medium where the reference gradient is nonzero.
#[derive(Serialize, Default, Clone, Copy)]
pub struct ErrorSummary {
    pub points: usize,
    /// Angle between the method's and the reference's gradient, degrees.
    pub median_angle_error_deg: f64,
    /// ||∇| − |∇_ref|| / |∇_ref|.
    pub median_relative_magnitude_error: f64,
    /// |∇ − ∇_ref| / |∇_ref|.
    pub median_relative_vector_error: f64,
}

#[derive(Serialize, Default, Clone, Copy)]
pub struct PartSummary {
    pub aware: ErrorSummary,
    pub unaware: ErrorSummary,
    /// Median over points of (reference noise estimate) / |∇_ref|: relative errors
    /// of the methods near this level are indistinguishable from the reference's own.
    pub reference_median_relative_noise: f64,
}

#[derive(Serialize)]
struct Summary {
    single: PartSummary,
    multiple: PartSummary,
    total: PartSummary,
}

#[derive(Serialize)]
struct Totals {
    capture_rays: u64,
    capture_seconds: f64,
    aware_seconds: f64,
    unaware_seconds: f64,
    reference_rays: u64,
    reference_seconds: f64,
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

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn angle_deg(a: DVec2, b: DVec2) -> f64 {
    a.perp_dot(b).atan2(a.dot(b)).abs().to_degrees()
}

pub fn summarize_part(points: &[PointOut], part: &str) -> PartSummary {
    let valid: Vec<(&PointOut, DVec2)> = points
        .iter()
        .filter_map(|p| {
            let r = p.reference.as_ref()?.part(part).grad();
            (r.length() > 0.0 && r.is_finite()).then_some((p, r))
        })
        .collect();
    let errors = |key: &str| {
        let pairs: Vec<(DVec2, DVec2)> = valid
            .iter()
            .filter_map(|(p, r)| Some((p.method(key)?.part(part).grad(), *r)))
            .collect();
        ErrorSummary {
            points: pairs.len(),
            median_angle_error_deg: median(pairs.iter().map(|(g, r)| angle_deg(*g, *r)).collect()),
            median_relative_magnitude_error: median(
                pairs
                    .iter()
                    .map(|(g, r)| (g.length() - r.length()).abs() / r.length())
                    .collect(),
            ),
            median_relative_vector_error: median(pairs.iter().map(|(g, r)| (*g - *r).length() / r.length()).collect()),
        }
    };
    PartSummary {
        aware: errors("aware"),
        unaware: errors("unaware"),
        reference_median_relative_noise: median(
            valid
                .iter()
                .filter_map(|(p, r)| Some(p.reference_gradient_noise?.part(part) / r.length()))
                .collect(),
        ),
    }
}

fn summarize(points: &[PointOut]) -> Summary {
    Summary {
        single: summarize_part(points, "single"),
        multiple: summarize_part(points, "multiple"),
        total: summarize_part(points, "total"),
    }
}

pub fn run(cmd: FigureCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        FigureCommand::Gradients(a) => gradients(a),
        FigureCommand::Compare(a) => super::figure_compare::run(a),
        FigureCommand::Compare3d(a) => super::figure_compare3d::run(a),
    }
}

fn gradients(a: GradientArgs) -> anyhow::Result<ExitCode> {
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
        ..Default::default()
    };
    let aw = AwareSettings::default();

    let grid = grid_points(&scene, a.grid);
    let line = line_points(a.line, a.line_samples);
    let ui = ProgressUi::new(
        &format!("{stem}: gradients at {} + {} points", grid.len(), line.len()),
        !a.quiet,
    );
    let progress = &ui.progress;
    progress.start((grid.len() + line.len()) as u64);
    let job = Job {
        scene: &scene,
        omega_o: DVec2::from_angle(omega_o_deg.to_radians()),
        ps,
        aw,
        relative_step: a.fd_step,
        progress,
    };
    // Line first: few points, shown closely; then the grid.
    let tasks: Vec<(bool, usize, Option<f64>, DVec2)> = line
        .iter()
        .enumerate()
        .map(|(k, &(s, x))| (true, k, Some(s), x))
        .chain(grid.iter().enumerate().map(|(k, &x)| (false, k, None, x)))
        .collect();
    let results: Result<Vec<PointOut>, Cancelled> = tasks
        .par_iter()
        .map(|&(on_line, k, s, x)| {
            let spp = if on_line { line_ref_spp } else { a.ref_spp };
            let r = compute_point(&job, x, s, point_seed(seed, k, on_line), spp);
            progress.advance(1);
            r
        })
        .collect();
    let cancelled = results.is_err() || progress.is_cancelled();
    ui.finish();
    let Ok(mut results) = results else {
        return Ok(cancelled_exit());
    };
    if cancelled {
        return Ok(cancelled_exit());
    }
    let grid_out = results.split_off(line.len());
    let line_out = results;

    let style: GradientStyle = a.style.into();
    let line_seg = (a.line.from, a.line.to);
    let half = |spp: u32| spp.div_ceil(2).max(1);
    let summary_grid = summarize(&grid_out);
    let summary_line = summarize(&line_out);
    let h = a.fd_step * scene.scale();
    let mut images = Vec::new();
    for (part, part_caption) in PARTS {
        let ps = summary_grid_part(&summary_grid, part);
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

        let pl = summary_line_part(&summary_line, part);
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

    let sum = |f: fn(&CostOut) -> f64| grid_out.iter().chain(&line_out).map(|p| f(&p.cost)).sum::<f64>();
    let totals = Totals {
        capture_rays: grid_out.iter().chain(&line_out).map(|p| p.cost.capture_rays).sum(),
        capture_seconds: sum(|c| c.capture_seconds),
        aware_seconds: sum(|c| c.aware_seconds),
        unaware_seconds: sum(|c| c.unaware_seconds),
        reference_rays: grid_out.iter().chain(&line_out).map(|p| p.cost.reference_rays).sum(),
        reference_seconds: sum(|c| c.reference_seconds),
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
        report.totals.wall_seconds, report.totals.capture_rays, report.totals.reference_rays
    );
    Ok(ExitCode::SUCCESS)
}

fn summary_grid_part(s: &Summary, part: &str) -> PartSummary {
    match part {
        "single" => s.single,
        "multiple" => s.multiple,
        _ => s.total,
    }
}

fn summary_line_part(s: &Summary, part: &str) -> PartSummary {
    summary_grid_part(s, part)
}

fn print_summary(s: &Summary, what: &str) {
    for (part, _) in PARTS {
        let p = summary_grid_part(s, part);
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
