//! `volcache bench`: figures printed and written as JSON (never asserted in tests).

use super::common::load_scene;
use clap::{Args, Subcommand};
use glam::DVec2;
use rayon::prelude::*;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use volcache::core::color::Rgb;
use volcache::core::rng::Sampler;
use volcache::flatland::geometry::{Segment, SegmentSet};
use volcache::flatland::scene::Scene;
use volcache::output::write_json;
use volcache::pipeline::bvh::Accel;
use volcache::pipeline::path::{Query, Settings, estimate};

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Ray–segment queries/s (with and without the BVH) and path samples/s.
    Flatland(FlatlandBench),
    /// 3D closest-hit and occlusion rays/s (a 158,802-triangle sphere and the shipped
    /// scenes, one thread and all) and BVH build times.
    Rays3d(super::bench_rays3d::Rays3dBench),
    /// Cost of one cache point: plain value, unaware and aware derivatives, per N.
    Derivatives(super::bench_derivs::DerivBench),
    /// One record of ours: cost and error (value, gradient, Hessian) against a
    /// converged record, per probe variant (directions × march steps).
    Records(super::bench_records::RecordsBench),
    /// Error vs time and vs cache count: ours, jarosz08 (ε swept) and pt (spp swept).
    Tradeoff(super::bench_tradeoff::TradeoffArgs),
    /// 3D error vs time and vs cache count: ours, jarosz08 (record counts swept) and
    /// pt (spp swept), with the speedup of ours over jarosz08 at equal error.
    Tradeoff3d(super::bench_tradeoff3d::Tradeoff3dArgs),
    /// 3D camera motion: a cache placed for one camera (with its records' moments
    /// over ω_o, and without) against a fresh cache for each orbited camera.
    Moments3d(super::bench_moments3d::Moments3dArgs),
}

#[derive(Args, Debug)]
pub struct FlatlandBench {
    /// Scene with many segments for the ray-casting figures.
    #[arg(long, default_value = "flatland_scenes/forest.json")]
    pub many: PathBuf,
    /// Scene for the path-tracing figures.
    #[arg(long, default_value = "flatland_scenes/windows.json")]
    pub pt_scene: PathBuf,
    /// Seconds to spend on each measurement (roughly).
    #[arg(long, default_value_t = 2.0)]
    pub seconds: f64,
    #[arg(long, default_value = "results/bench_flatland.json")]
    pub out: PathBuf,
}

#[derive(Serialize)]
struct RayFigures {
    scene: String,
    segments: usize,
    accel: String,
    /// Seconds to build the acceleration structure (best of five, one thread).
    build_seconds: f64,
    queries: u64,
    seconds: f64,
    queries_per_second_one_thread: f64,
    queries_per_second_all_threads: f64,
    /// Occlusion queries (length 2, a quarter of the forest's width).
    occluded_per_second_one_thread: f64,
    occluded_per_second_all_threads: f64,
}

#[derive(Serialize)]
struct PtFigures {
    scene: String,
    threads: usize,
    samples: u64,
    rays: u64,
    seconds: f64,
    samples_per_second: f64,
    rays_per_second: f64,
}

#[derive(Serialize)]
struct Crossover {
    segments: usize,
    bvh_queries_per_second: f64,
    linear_queries_per_second: f64,
}

#[derive(Serialize)]
struct Report {
    machine_threads: usize,
    ray_casting: Vec<RayFigures>,
    /// Random segment soups of growing size: where the BVH starts to pay off.
    bvh_crossover: Vec<Crossover>,
    path_tracing: PtFigures,
}

pub fn run(cmd: BenchCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        BenchCommand::Flatland(b) => flatland(b),
        BenchCommand::Rays3d(b) => super::bench_rays3d::run(b),
        BenchCommand::Derivatives(b) => super::bench_derivs::run(b),
        BenchCommand::Records(b) => super::bench_records::run(b),
        BenchCommand::Tradeoff(b) => super::bench_tradeoff::run(b),
        BenchCommand::Tradeoff3d(b) => super::bench_tradeoff3d::run(b),
        BenchCommand::Moments3d(b) => super::bench_moments3d::run(b),
    }
}

/// Random rays from inside the domain, fixed seed.
fn random_rays(scene: &Scene, n: usize) -> Vec<(DVec2, DVec2)> {
    let mut s = Sampler::new(42, 0);
    let size = scene.domain_max - scene.domain_min;
    (0..n)
        .map(|_| {
            let o = scene.domain_min + DVec2::new(s.next_f64(), s.next_f64()) * size;
            (o, DVec2::from_angle(std::f64::consts::TAU * s.next_f64()))
        })
        .collect()
}

/// Queries per second over `rays` (repeated for about `seconds`) on the current
/// rayon pool: closest hits, or occlusion up to the closest hit's distance when
/// `occlusion` (a shadow ray between two points, visible or not).
fn time_queries(set: &SegmentSet, rays: &[(DVec2, DVec2)], seconds: f64, occlusion: bool) -> (u64, f64) {
    let start = Instant::now();
    let mut n = 0u64;
    let mut hits = 0u64;
    while n == 0 || start.elapsed().as_secs_f64() < seconds {
        hits += rays
            .par_iter()
            .with_min_len(1024)
            .map(|&(o, d)| match occlusion {
                false => set.closest_hit(o, d, 0.0, f64::INFINITY, None).is_some() as u64,
                true => set.occluded(o, d, 0.0, 2.0, None) as u64,
            })
            .sum::<u64>();
        n += rays.len() as u64;
    }
    std::hint::black_box(hits);
    (n, start.elapsed().as_secs_f64())
}

fn flatland(b: FlatlandBench) -> anyhow::Result<ExitCode> {
    let many = load_scene(Some(&b.many))?;
    let rays = random_rays(&many, 100_000);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let mut ray_casting = Vec::new();
    for accel in [Accel::Bvh, Accel::Linear] {
        let build = || {
            let start = Instant::now();
            let set = SegmentSet::with_accel(many.geometry.prims.clone(), accel);
            (start.elapsed().as_secs_f64(), set)
        };
        let (build_seconds, set) = one.install(|| {
            (0..5)
                .map(|_| build())
                .reduce(|a, b| (a.0.min(b.0), b.1))
                .expect("five builds")
        });
        // The flat list is ~10x slower: a tenth of the time gives as many digits.
        let t = if accel == Accel::Bvh {
            b.seconds
        } else {
            b.seconds / 4.0
        };
        let (n, secs) = one.install(|| time_queries(&set, &rays, t, false));
        let (na, sa) = time_queries(&set, &rays, t / 2.0, false);
        let (no, so) = one.install(|| time_queries(&set, &rays, t / 2.0, true));
        let (noa, soa) = time_queries(&set, &rays, t / 2.0, true);
        let f = RayFigures {
            scene: b.many.display().to_string(),
            segments: set.len(),
            accel: format!("{accel:?}"),
            build_seconds,
            queries: n,
            seconds: secs,
            queries_per_second_one_thread: n as f64 / secs,
            queries_per_second_all_threads: na as f64 / sa,
            occluded_per_second_one_thread: no as f64 / so,
            occluded_per_second_all_threads: noa as f64 / soa,
        };
        println!(
            "ray casting, {} segments, {:?} (build {:.2e} s): closest hit {:.3} M queries/s (1 thread), {:.3} M/s ({} threads); occluded {:.3} / {:.3} M/s",
            f.segments,
            accel,
            f.build_seconds,
            f.queries_per_second_one_thread / 1e6,
            f.queries_per_second_all_threads / 1e6,
            rayon::current_num_threads(),
            f.occluded_per_second_one_thread / 1e6,
            f.occluded_per_second_all_threads / 1e6,
        );
        ray_casting.push(f);
    }

    let mut bvh_crossover = Vec::new();
    for n in [2usize, 3, 4, 6, 8, 16, 24, 32, 64, 128] {
        let set = |accel| {
            let mut s = Sampler::new(9, n as u64);
            let segs = (0..n)
                .map(|_| {
                    let c = DVec2::new(s.next_f64(), s.next_f64()) * 2.0 - 1.0;
                    let d = DVec2::from_angle(std::f64::consts::TAU * s.next_f64()) * 0.15;
                    Segment::new(c - d, c + d, Rgb::ZERO, Rgb::ZERO, true)
                })
                .collect();
            SegmentSet::with_accel(segs, accel)
        };
        let rays = random_rays(&many, 20_000)
            .into_iter()
            .map(|(o, d)| {
                (
                    (o - many.domain_min) / (many.domain_max - many.domain_min) * 2.0 - 1.0,
                    d,
                )
            })
            .collect::<Vec<_>>();
        let t = b.seconds / 8.0;
        let (nb, sb) = one.install(|| time_queries(&set(Accel::Bvh), &rays, t, false));
        let (nl, sl) = one.install(|| time_queries(&set(Accel::Linear), &rays, t, false));
        let c = Crossover {
            segments: n,
            bvh_queries_per_second: nb as f64 / sb,
            linear_queries_per_second: nl as f64 / sl,
        };
        println!(
            "  {n:>4} segments: BVH {:.2} M/s, linear {:.2} M/s",
            c.bvh_queries_per_second / 1e6,
            c.linear_queries_per_second / 1e6
        );
        bvh_crossover.push(c);
    }

    let scene = load_scene(Some(&b.pt_scene))?;
    let q = Query::from_quantity(scene.desc.render.quantity, DVec2::X);
    let settings = Settings::default();
    let start = Instant::now();
    let mut batches = 0u64;
    let (mut samples, mut rays) = (0u64, 0u64);
    let size = scene.domain_max - scene.domain_min;
    while start.elapsed().as_secs_f64() < b.seconds {
        let per_batch = 256u64;
        let (s, r) = (0..per_batch)
            .into_par_iter()
            .map(|k| {
                let mut s = Sampler::new(7, batches * per_batch + k);
                let x = scene.domain_min + DVec2::new(s.next_f64(), s.next_f64()) * size;
                let e = estimate(&scene, x, &q, &settings, 16, 7, batches * per_batch + k);
                (e.samples, e.rays)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        samples += s;
        rays += r;
        batches += 1;
    }
    let secs = start.elapsed().as_secs_f64();
    let pt = PtFigures {
        scene: b.pt_scene.display().to_string(),
        threads: rayon::current_num_threads(),
        samples,
        rays,
        seconds: secs,
        samples_per_second: samples as f64 / secs,
        rays_per_second: rays as f64 / secs,
    };
    println!(
        "path tracing {} ({} threads): {:.0} samples/s, {:.3} M rays/s",
        pt.scene,
        pt.threads,
        pt.samples_per_second,
        pt.rays_per_second / 1e6
    );
    let report = Report {
        machine_threads: rayon::current_num_threads(),
        ray_casting,
        bvh_crossover,
        path_tracing: pt,
    };
    write_json(&b.out, &report)?;
    eprintln!("wrote {}", b.out.display());
    Ok(ExitCode::SUCCESS)
}
