//! `volcache bench rays3d`: 3D ray-casting throughput, printed and written as JSON.
//!
//! Closest-hit and occlusion queries per second, on one thread and on all, for the
//! benchmark sphere (a UV sphere of 158,802 triangles made in code, origins uniform
//! in [−2, 2]³, directions uniform: the set-up `scripts/embree_mitsuba_compare.py` gives
//! Embree) and for each shipped scene (origins uniform in the scene's bounds), plus
//! the time to build the acceleration structure (one thread and all threads, best
//! of a few). Also probe-like rays (issue 13: a record's N rays all start at one
//! point): 16,384 Fibonacci directions from each of 32 points, traced in the order
//! the probe makes them and sorted by direction (Morton order of the octahedral map),
//! to measure whether sorting a probe's rays pays.

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use volcache::core::rng::Sampler;
use volcache::core::space::D3;
use volcache::output::write_json;
use volcache::pipeline::bvh::Geometry;
use volcache::pipeline::dim::Dim;
use volcache::volume::mesh::{Triangle, uv_sphere};
use volcache::volume::scene::Scene;

#[derive(clap::Args, Debug)]
pub struct Rays3dBench {
    /// Scenes besides the sphere (their triangles; origins in their bounds).
    #[arg(long, num_args = 0.., default_values = ["scenes3d/fog_box.json", "scenes3d/mesh_in_fog.json", "scenes3d/staircase.json"])]
    pub scenes: Vec<PathBuf>,
    /// Rays per measurement.
    #[arg(long, default_value_t = 2_000_000)]
    pub rays: u64,
    /// The sphere's latitude bands and longitude segments (2·s·(b − 1) triangles).
    #[arg(long, default_value_t = 200)]
    pub bands: usize,
    #[arg(long, default_value_t = 399)]
    pub segments: usize,
    /// Only the sphere, on one thread (for profiling and the comparison script).
    #[arg(long)]
    pub sphere_only: bool,
    #[arg(long, default_value = "results/bench_rays3d.json")]
    pub out: PathBuf,
}

#[derive(Serialize)]
struct Figures {
    scene: String,
    triangles: usize,
    build_seconds: f64,
    build_seconds_all_threads: Option<f64>,
    /// `Geometry::layout_hash` (the tree, bit for bit): compare builds across versions.
    layout_hash: String,
    rays: u64,
    closest_hit_rays_per_second_one_thread: f64,
    occluded_rays_per_second_one_thread: f64,
    closest_hit_rays_per_second_all_threads: Option<f64>,
    occluded_rays_per_second_all_threads: Option<f64>,
    /// Share of the rays that hit (the same for both queries).
    hit_fraction: f64,
    /// Closest hits of probe rays on one thread: in the probe's (Fibonacci) order,
    /// and sorted by direction.
    probe_rays_per_second_one_thread: f64,
    probe_rays_sorted_per_second_one_thread: f64,
}

#[derive(Serialize)]
struct Report {
    machine_threads: usize,
    scenes: Vec<Figures>,
}

/// Ray k of a run: origin uniform in [lo, hi], direction uniform on the sphere.
fn ray(lo: DVec3, hi: DVec3, seed: u64, k: u64) -> (DVec3, DVec3) {
    let mut s = Sampler::new(seed, k);
    let o = lo + (hi - lo) * DVec3::new(s.next_f64(), s.next_f64(), s.next_f64());
    let z = 1.0 - 2.0 * s.next_f64();
    let phi = std::f64::consts::TAU * s.next_f64();
    let r = (1.0 - z * z).max(0.0).sqrt();
    (o, DVec3::new(r * phi.cos(), r * phi.sin(), z))
}

/// Rays per second and hits of one query over `rays` on the current rayon pool.
/// The rays are made beforehand, so only the queries are timed (as for Embree in
/// `scripts/embree_mitsuba_compare.py`, whose rays numpy makes).
fn rate(rays: &[(DVec3, DVec3)], query: impl Fn(DVec3, DVec3) -> bool + Sync) -> (f64, u64) {
    let start = Instant::now();
    let hits: u64 = rays
        .par_iter()
        .with_min_len(4096)
        .map(|&(o, d)| query(o, d) as u64)
        .sum();
    (rays.len() as f64 / start.elapsed().as_secs_f64().max(1e-9), hits)
}

/// Build time (best of five, on the current rayon pool) and the geometry.
fn build(tris: &[Triangle]) -> (f64, Geometry<D3, Triangle>) {
    let mut best = f64::INFINITY;
    let mut geometry = None;
    for _ in 0..5 {
        let t = tris.to_vec();
        let start = Instant::now();
        let g = Geometry::new(t);
        best = best.min(start.elapsed().as_secs_f64());
        geometry = Some(g);
    }
    (best, geometry.expect("three builds"))
}

/// The Morton code of a unit direction's octahedral map, 16 bits per coordinate.
fn direction_key(d: DVec3) -> u32 {
    let n = d.x.abs() + d.y.abs() + d.z.abs();
    let (mut u, mut v) = (d.x / n, d.y / n);
    if d.z < 0.0 {
        (u, v) = ((1.0 - v.abs()) * u.signum(), (1.0 - u.abs()) * v.signum());
    }
    let spread = |a: f64| {
        let mut x = ((a + 1.0) * 0.5 * 65535.0).clamp(0.0, 65535.0) as u32;
        x = (x | (x << 8)) & 0x00ff_00ff;
        x = (x | (x << 4)) & 0x0f0f_0f0f;
        x = (x | (x << 2)) & 0x3333_3333;
        (x | (x << 1)) & 0x5555_5555
    };
    spread(u) | (spread(v) << 1)
}

/// Closest-hit rays/s on the current pool of probe rays from 32 points uniform in
/// [lo, hi], 16,384 directions each: in the probe's order and sorted by
/// [`direction_key`] (best of two interleaved rounds each; the sort is not timed).
fn probe_rates(g: &Geometry<D3, Triangle>, lo: DVec3, hi: DVec3, t_min: f64) -> (f64, f64) {
    let dirs = D3::directions(16_384, 1.0, 3);
    let mut sorted = dirs.clone();
    sorted.sort_by_key(|&d| direction_key(d));
    let points: Vec<DVec3> = (0..32).map(|k| ray(lo, hi, 12, k).0).collect();
    let time = |dirs: &[DVec3]| {
        let start = Instant::now();
        let hits: usize = points
            .iter()
            .map(|&x| {
                dirs.iter()
                    .filter(|&&d| g.closest_hit(x, d, t_min, f64::INFINITY, None).is_some())
                    .count()
            })
            .sum();
        let rate = (points.len() * dirs.len()) as f64 / start.elapsed().as_secs_f64().max(1e-9);
        (rate, hits)
    };
    let (mut best, mut best_sorted) = (0.0f64, 0.0f64);
    for _ in 0..2 {
        let (a, hits) = time(&dirs);
        let (b, hits_sorted) = time(&sorted);
        assert_eq!(hits, hits_sorted, "the order changes no hit");
        (best, best_sorted) = (best.max(a), best_sorted.max(b));
    }
    (best, best_sorted)
}

fn measure(name: String, tris: &[Triangle], lo: DVec3, hi: DVec3, n_rays: u64, all_threads: bool) -> Figures {
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let (build_seconds, g) = one.install(|| build(tris));
    let build_all = all_threads.then(|| build(tris).0);
    let t_min = 1e-9 * (hi - lo).length();
    let closest = |o, d| g.closest_hit(o, d, t_min, f64::INFINITY, None).is_some();
    let occluded = |o, d| g.occluded(o, d, t_min, f64::INFINITY, None);
    let rays: Vec<(DVec3, DVec3)> = (0..n_rays).into_par_iter().map(|k| ray(lo, hi, 11, k)).collect();
    let (c1, hits) = one.install(|| rate(&rays, closest));
    let (o1, hits_o) = one.install(|| rate(&rays, occluded));
    let (p1, p1_sorted) = one.install(|| probe_rates(&g, lo, hi, t_min));
    assert_eq!(hits, hits_o, "closest hit and occlusion disagree on {name}");
    let (call, oall) = if all_threads {
        (Some(rate(&rays, closest).0), Some(rate(&rays, occluded).0))
    } else {
        (None, None)
    };
    let f = Figures {
        scene: name,
        triangles: tris.len(),
        build_seconds,
        build_seconds_all_threads: build_all,
        layout_hash: format!("{:016x}", g.layout_hash()),
        rays: n_rays,
        closest_hit_rays_per_second_one_thread: c1,
        occluded_rays_per_second_one_thread: o1,
        closest_hit_rays_per_second_all_threads: call,
        occluded_rays_per_second_all_threads: oall,
        hit_fraction: hits as f64 / n_rays as f64,
        probe_rays_per_second_one_thread: p1,
        probe_rays_sorted_per_second_one_thread: p1_sorted,
    };
    let all = |v: Option<f64>| v.map_or(String::new(), |v| format!(", {:.2} M/s all threads", v / 1e6));
    let build_all = build_all.map_or(String::new(), |b| format!(", {b:.4} s all threads"));
    println!(
        "{} ({} triangles, build {:.4} s 1 thread{}, layout {}): closest hit {:.2} M rays/s 1 thread{}; occluded {:.2} M rays/s 1 thread{}; {:.0}% hit",
        f.scene,
        f.triangles,
        f.build_seconds,
        build_all,
        f.layout_hash,
        c1 / 1e6,
        all(call),
        o1 / 1e6,
        all(oall),
        100.0 * f.hit_fraction
    );
    println!(
        "  probe rays (32 points x 16384 directions, closest hit, 1 thread): {:.2} M rays/s in the probe's order, {:.2} M rays/s sorted by direction",
        p1 / 1e6,
        p1_sorted / 1e6
    );
    f
}

pub fn run(b: Rays3dBench) -> anyhow::Result<ExitCode> {
    let sphere = uv_sphere(b.bands, b.segments, 0);
    let name = format!("uv sphere {}x{}", b.bands, b.segments);
    let mut scenes = vec![measure(
        name,
        &sphere,
        DVec3::splat(-2.0),
        DVec3::splat(2.0),
        b.rays,
        !b.sphere_only,
    )];
    if !b.sphere_only {
        for path in &b.scenes {
            let scene = Scene::load(path)?;
            let (lo, hi) = (scene.bounds.min, scene.bounds.max);
            scenes.push(measure(
                path.display().to_string(),
                &scene.geometry.prims,
                lo,
                hi,
                b.rays,
                true,
            ));
        }
    }
    let report = Report {
        machine_threads: rayon::current_num_threads(),
        scenes,
    };
    write_json(&b.out, &report)?;
    eprintln!("wrote {}", b.out.display());
    Ok(ExitCode::SUCCESS)
}
