//! Radiance caching over a 2D field (theory.md §6–8): the field's pixel centres
//! inside the medium, in a fixed coarse-to-fine order, are the query points of the
//! pipeline's placement (`pipeline::placement`); every pixel is then reconstructed
//! from the records that cover and see it.
//!
//! The direct part (delta lights) is singular at shadow and beam edges and cheap:
//! it is evaluated per pixel, never cached (theory.md §2). The cached quantity is
//! single + multiple scattering, in one cache, or one cache per part (`per_part`).
//! With `direct_samples`, all light arriving straight from the lights (emitters too)
//! is sampled per pixel and the records hold only the rest (a field of all parts).
//! With `point_scatter`, so is the point lights' light scattered once on its way
//! (`pipeline::point_scatter`): its peak around each light is not cached.
//! With `near_light_paths`, the pixels within a mean free path of a point light
//! are path traced whole. They stay query points: records placed there serve the
//! pixels just outside (without them, `shaded_lamp.json`'s ring at 1–2 mean free
//! paths went from RMSE 0.48 to 0.60, and the placement's time did not fall).

use super::field::{Field, FieldParams};
use super::lights::Lobe;
use super::scene::Scene;
use super::scene_desc::Part;
use crate::core::cache::placement_order;
use crate::core::color::Rgb;
pub use crate::core::metric::CacheMethod;
use crate::core::rng::Sampler;
use crate::core::space::D2;
use crate::pipeline::budget::shared_direct_samples;
use crate::pipeline::path::direct_mean;
use crate::pipeline::path::{Query, Settings, estimate_cancellable};
use crate::pipeline::placement::{
    CountError, Placement, QueryPoint, QuerySource, interpolate, place, place_with_count,
};
use crate::pipeline::point_scatter::{near_a_point_light, near_light_radius, once_scattered_point_lights};
use crate::pipeline::probe::Outgoing;
use crate::pipeline::record::Cached;
use crate::pipeline::sight::{Near, near_table};
use crate::pipeline::world::World;
use crate::progress::{Cancelled, Progress};
use glam::DVec2;
use rayon::prelude::*;
use serde::Serialize;

pub use crate::pipeline::record::CacheSettings;

/// What a budget sets for ours on a scene (`budget_settings`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BudgetSettings {
    pub eps: f64,
    /// Directions per record.
    pub rays: usize,
    /// Where the scene has lights with an extent: the straight light's least
    /// samples per pixel and its share of the placement's rays
    /// (`CacheSettings::direct_samples`, `CacheSettings::direct_share`).
    pub direct: Option<(u32, f64)>,
    /// `CacheSettings::edge_reach`.
    pub edge_reach: f64,
    /// `CacheSettings::point_scatter`, where the scene has point lights in fog.
    pub point_scatter: Option<u32>,
    /// `CacheSettings::near_light_paths`, where the scene has point lights in fog
    /// at least ten mean free paths across (`near_light_radius` > 0).
    pub near_light_paths: Option<u32>,
}

/// What budget `b` (`pipeline::budget::FLATLAND`) sets for ours on `scene`: ε,
/// directions and the edge reach, and the straight light's samples where the
/// scene has emitting segments (a delta light's straight light is per pixel at
/// every budget: samples of it would repeat it), and the point lights'
/// once-scattered light per pixel, and paths for the pixels near them, where the
/// scene has point lights in fog.
pub fn budget_settings(scene: &Scene, b: f64) -> BudgetSettings {
    use crate::pipeline::budget::{
        FLATLAND_DIRECT_MIN_SAMPLES, flatland_direct_share, flatland_edge_reach, flatland_near_light_paths,
        flatland_point_scatter, schedule,
    };
    let (eps, rays) = schedule(b);
    let extended_lights = !scene.emitters.prims.is_empty();
    let scattering = scene.medium.as_ref().is_some_and(|m| m.sigma_s != Rgb::ZERO);
    let lamps_in_fog = scattering && !scene.point_lights.is_empty();
    BudgetSettings {
        eps,
        rays,
        direct: extended_lights.then(|| (FLATLAND_DIRECT_MIN_SAMPLES, flatland_direct_share(b))),
        edge_reach: flatland_edge_reach(b),
        point_scatter: lamps_in_fog.then(|| flatland_point_scatter(b)),
        near_light_paths: (lamps_in_fog && near_light_radius(scene) > 0.0).then(|| flatland_near_light_paths(b)),
    }
}

/// One record of the distribution figure.
pub type RecordInfo = crate::pipeline::record::RecordInfo<D2>;
/// Light fields per pixel, shared by placements of the same scene, method and probe
/// settings.
pub type RecordMemo = crate::pipeline::placement::RecordMemo<D2>;

/// A field reconstructed from caches, with its records and costs.
#[derive(Clone, Debug)]
pub struct CachedField {
    pub field: Field,
    /// Records per cache (one, or single and multiple with `per_part`).
    pub records: Vec<Vec<RecordInfo>>,
    pub eps: f64,
    pub placement_seconds: f64,
    pub reconstruction_seconds: f64,
    /// Rays of the records' light fields (memoised ones included) and the checks.
    pub placement_rays: u64,
    /// Shadow rays of the per-pixel direct part and the records' visibility.
    pub reconstruction_rays: u64,
    /// Valid pixels no record covered (placement guarantees zero).
    pub uncovered_pixels: usize,
    /// Samples per pixel of the straight light, where the records left it out.
    pub direct_samples: Option<u32>,
    /// The pixels near point lights that were path traced whole, where any were.
    pub near_light: Option<NearLight>,
    /// Directions per pixel of the point lights' once-scattered light, where the
    /// records left it out.
    pub point_scatter: Option<u32>,
    /// The records' own noise relative to their values
    /// (`pipeline::placement::ValueNoise::relative`).
    pub records_relative_noise: Option<f64>,
}

/// The pixels path traced whole around point lights
/// (`CacheSettings::near_light_paths`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct NearLight {
    /// Paths per pixel.
    pub paths: u32,
    /// Distance from a point light within which pixels are path traced.
    pub radius: f64,
    /// Pixels inside the medium within it.
    pub pixels: usize,
}

impl CachedField {
    pub fn record_count(&self) -> usize {
        self.records.iter().map(Vec::len).sum()
    }
}

/// The field's pixel centres inside the medium, coarse to fine.
struct FieldPixels<'a> {
    scene: &'a Scene,
    field: &'a Field,
    order: Vec<usize>,
    omega_o: DVec2,
}

impl QuerySource<D2> for FieldPixels<'_> {
    fn units(&self) -> usize {
        self.order.len()
    }

    fn points(&self, k: usize, out: &mut Vec<QueryPoint<D2>>) {
        let pixel = self.order[k];
        let y = self
            .field
            .pixel_center(pixel % self.field.width, pixel / self.field.width);
        if self.scene.medium_at(y).is_some() {
            out.push(QueryPoint {
                key: pixel as u128,
                id: pixel as u64,
                y,
            });
        }
    }

    fn outgoing(&self, _: DVec2) -> Outgoing<DVec2> {
        Outgoing::Direction(self.omega_o)
    }
}

/// The cached quantities a field of `part` needs.
fn cached_parts(cs: &CacheSettings, part: Part) -> &'static [Cached] {
    if cs.per_part || matches!(part, Part::Single | Part::Multiple) {
        &[Cached::Single, Cached::Multiple]
    } else {
        &[Cached::Scattered]
    }
}

/// Place records at `cs.eps` (or at the ε giving `target` records) and reconstruct
/// the field of `fp.part` (direct evaluated per pixel). An error when cancelled, or
/// when no ε gives about `target` records.
pub fn render_cached(
    scene: &Scene,
    fp: &FieldParams,
    cs: &CacheSettings,
    target: Option<usize>,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<CachedField, CountError> {
    let field = Field::new(fp.width, fp.height, scene.domain_min, scene.domain_max);
    // The point lights' once-scattered light, and all light near them, are taken
    // per pixel only where one cache holds all scattered light (the records leave
    // the former out of that cache).
    let all_in_one = fp.part == Part::All && !cs.per_part;
    let cs = &CacheSettings {
        point_scatter: cs.point_scatter.filter(|_| all_in_one),
        ..cs.clone()
    };
    // (paths, radius) of the pixels path traced whole near point lights.
    let near_light = cs
        .near_light_paths
        .filter(|&n| all_in_one && n > 0)
        .map(|n| (n, near_light_radius(scene)))
        .filter(|&(_, r)| r > 0.0);
    let source = FieldPixels {
        scene,
        field: &field,
        order: placement_order(fp.width, fp.height),
        omega_o: DVec2::from_angle(fp.omega_o_deg.to_radians()),
    };
    let cached = cached_parts(cs, fp.part);
    let mut placement = match target {
        Some(n) => place_with_count(scene, &source, cs, cached, n, memo, progress)?,
        None => place(scene, &source, cs, cached, memo, progress)?,
    };
    // The straight light's samples as a share of what the records cost per pixel
    // (the placement's query points are the pixels inside the medium).
    if let (Some(min), Some(share)) = (placement.direct_samples, cs.direct_share) {
        let points = placement.query_points as usize;
        placement.direct_samples = Some(shared_direct_samples(min, share, placement.rays, points));
    }
    Ok(reconstruct(scene, fp, (cs, near_light), field, placement, progress)?)
}

/// Every pixel from the caches (plus the parts taken per pixel, and the pixels
/// near point lights path traced whole with `near_light`'s (paths, radius)); an
/// error when cancelled.
fn reconstruct(
    scene: &Scene,
    fp: &FieldParams,
    (cs, near_light): (&CacheSettings, Option<(u32, f64)>),
    mut field: Field,
    p: Placement<D2>,
    progress: &Progress,
) -> Result<CachedField, Cancelled> {
    let t1 = std::time::Instant::now();
    let (w, h) = (fp.width, fp.height);
    let omega_o = DVec2::from_angle(fp.omega_o_deg.to_radians());
    let second_order = cs.second_order && cs.method == CacheMethod::Ours;
    let per_part = p.caches.len() == 2;
    // Per pixel (value, inside the medium, covered by a record); per row its rays
    // and its pixels path traced near a point light.
    type Row = (Vec<(Rgb, bool, bool)>, u64, usize);
    let near: Vec<Vec<Near>> = p.caches.iter().map(|c| near_table(scene, c)).collect();
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        .map(|j| {
            let (mut rays, mut near_pixels) = (0, 0);
            let mut scratch = Vec::new();
            let row = (0..w)
                .map(|i| {
                    // Pixels near a lamp may take thousands of paths each.
                    progress.check()?;
                    let x = field.pixel_center(i, j);
                    let Some(m) = scene.medium_at(x) else {
                        return Ok((Rgb::ZERO, false, true));
                    };
                    let item = (j * w + i) as u64;
                    if let Some((n, _)) = near_light.filter(|&(_, r)| near_a_point_light(scene, x, r)) {
                        let v = path_traced(
                            scene,
                            (x, omega_o),
                            &cs.probe.settings,
                            n,
                            (cs.seed, item),
                            progress,
                            &mut rays,
                        )?;
                        near_pixels += 1;
                        return Ok((v, true, true));
                    }
                    let lobe = Lobe::Phase {
                        phase: m.phase,
                        travel: -omega_o,
                    };
                    let mut s = Sampler::new(cs.seed, item);
                    let direct = match (fp.part, p.direct_samples) {
                        (Part::All, Some(n)) => direct_mean(scene, x, (&lobe, m.sigma_s), n, &mut s, &mut rays),
                        (Part::All | Part::Direct, _) => scene.direct_part(x, &lobe, &mut s, &mut rays) * m.sigma_s,
                        _ => Rgb::ZERO,
                    };
                    // `render_cached` kept it only for a field of all light in one cache.
                    let once = cs.point_scatter.map_or(Rgb::ZERO, |n| {
                        once_scattered_point_lights(scene, x, &lobe, n, (cs.seed, item), &mut rays) * m.sigma_s
                    });
                    let cached: Vec<Option<Rgb>> = p
                        .caches
                        .iter()
                        .zip(&near)
                        .map(|(c, n)| interpolate(scene, (c, n, None), x, second_order, &mut scratch, &mut rays))
                        .collect();
                    let covered = cached.iter().all(Option::is_some);
                    let cached: Vec<Rgb> = cached.into_iter().map(|c| c.unwrap_or(Rgb::ZERO)).collect();
                    let v = match (fp.part, per_part) {
                        (Part::Direct, _) => direct,
                        (Part::All, false) => direct + once + cached[0],
                        (Part::All, true) => direct + cached[0] + cached[1],
                        (Part::Single, _) => cached[0],
                        (Part::Multiple, _) => cached[1],
                    };
                    Ok((v, true, covered))
                })
                .collect::<Result<_, Cancelled>>()?;
            Ok((row, rays, near_pixels))
        })
        .collect::<Result<_, Cancelled>>()?;
    let (mut reconstruction_rays, mut uncovered_pixels, mut near_pixels) = (0, 0, 0);
    for (j, (row, rays, row_near_pixels)) in rows.into_iter().enumerate() {
        reconstruction_rays += rays;
        near_pixels += row_near_pixels;
        for (i, (v, valid, covered)) in row.into_iter().enumerate() {
            field.values[j * w + i] = v;
            field.valid[j * w + i] = valid;
            uncovered_pixels += !covered as usize;
        }
    }
    Ok(CachedField {
        field,
        records: p.records(),
        eps: p.eps,
        placement_seconds: p.seconds,
        reconstruction_seconds: t1.elapsed().as_secs_f64(),
        placement_rays: p.rays,
        reconstruction_rays,
        uncovered_pixels,
        direct_samples: p.direct_samples,
        point_scatter: cs.point_scatter,
        records_relative_noise: p.value_noise.relative(),
        near_light: near_light.map(|(paths, radius)| NearLight {
            paths,
            radius,
            pixels: near_pixels,
        }),
    })
}

/// L_s(x, ω_o) path traced with `n` samples, as the path tracer's pixels are
/// (streams (seed ^ salt, item, k)), cancellable: a pixel near a lamp may take a
/// million paths.
fn path_traced(
    scene: &Scene,
    (x, omega_o): (DVec2, DVec2),
    settings: &Settings,
    n: u32,
    (seed, item): (u64, u64),
    progress: &Progress,
    rays: &mut u64,
) -> Result<Rgb, Cancelled> {
    let q = Query::InScattered { omega_o };
    let e = estimate_cancellable(scene, x, &q, settings, n, (seed ^ NEAR_LIGHT_STREAM, item), progress)?;
    *rays += e.rays;
    Ok(e.mean.total())
}

/// Salt of the near-light pixels' paths: apart from the pixel's other samples.
const NEAR_LIGHT_STREAM: u64 = 0x4EA2_0117_0000_0001;
