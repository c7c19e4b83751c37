//! Radiance caching over a 2D field (theory.md §6–8).
//!
//! Placement walks the field's pixel centres (inside the medium) in a fixed
//! coarse-to-fine order and creates a record wherever no record covers the point;
//! every pixel is then reconstructed from its covering records. Methods:
//! - `ours`: occlusion-aware value, gradient and Hessian (`derivatives::aware`),
//!   extent = the seed's Hessian ellipse (`core::metric::second_order_extent`);
//! - `jarosz08`: occlusion-unaware value and gradient, extent = the gradient circle
//!   (`core::metric::first_order_extent`).
//!
//! The direct part (delta lights) is singular at shadow and beam edges and cheap:
//! it is evaluated per pixel, never cached (theory.md §2). The cached quantity is
//! single + multiple scattering, in one cache, or one cache per part
//! (`per_part`). Records are computed sequentially in placement order, each light
//! field in parallel over its rays, so results do not depend on the thread count.
//! Light fields are memoised per pixel ([`RecordMemo`]), so the ε bisection of the
//! equal-count mode only pays for points it has not seen.

use super::derivatives::{self, AwareSettings, PartDerivs};
use super::field::{Field, FieldParams};
use super::lights::{Lobe, direct_lights};
use super::probe::{ProbeSettings, capture};
use super::proxy;
use super::scene::Scene;
use super::scene_desc::Part;
use crate::core::cache::{Cache, Record};
use crate::core::color::{Rgb, luminance};
use crate::core::metric::{MetricParams, with_radiance_floor};
use crate::core::rng::mix64;
use crate::core::space::D2;
use crate::core::taylor_rgb::TaylorRgb;
use crate::progress::{Cancelled, Progress};
use glam::{DMat2, DVec2};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;

pub use crate::core::metric::CacheMethod;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CacheSettings {
    pub method: CacheMethod,
    /// Error threshold ε (theory.md §6).
    pub eps: f64,
    pub probe: ProbeSettings,
    pub aware: AwareSettings,
    /// Separate caches for single and multiple scattering.
    pub per_part: bool,
    /// Second-order interpolation (ours only; the baseline has no Hessian).
    pub second_order: bool,
    /// Fraction of the mean element radiance added to every element before the
    /// metric's Hessian (Schwarzhaupt et al. 2012, for black occluders).
    pub hessian_floor: f64,
    pub seed: u64,
}

impl CacheSettings {
    pub fn new(method: CacheMethod, eps: f64) -> Self {
        CacheSettings {
            method,
            eps,
            probe: ProbeSettings::default(),
            aware: AwareSettings::default(),
            per_part: false,
            second_order: false,
            hessian_floor: 0.01,
            seed: 1,
        }
    }

    pub fn metric(&self, scene: &Scene) -> MetricParams {
        MetricParams::scene_relative(scene.scale(), self.eps)
    }
}

/// What one light field gives a record, kept to re-derive extents for another ε.
#[derive(Clone, Debug)]
pub struct RecordData {
    pub parts: PartDerivs,
    /// Luminance Hessians used by the metric (with the radiance floor), per cached
    /// quantity: [single + multiple, single, multiple].
    pub metric_hessians: [DMat2; 3],
    pub rays: u64,
}

/// Light-field results per pixel index, shared by placements of the same scene,
/// method and probe settings.
pub type RecordMemo = HashMap<usize, RecordData>;

/// One record of the distribution figure.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RecordInfo {
    pub position: DVec2,
    /// Unit axes (columns) and radii of the extent.
    pub axes: [DVec2; 2],
    pub radii: [f64; 2],
    pub luminance: f64,
    pub rays: u64,
}

/// A field reconstructed from caches, with its records and costs.
#[derive(Clone, Debug)]
pub struct CachedField {
    pub field: Field,
    /// Records per cache (one, or single and multiple with `per_part`).
    pub records: Vec<Vec<RecordInfo>>,
    pub placement_seconds: f64,
    pub reconstruction_seconds: f64,
    /// Rays of the light fields of the records (memoised ones included).
    pub placement_rays: u64,
    /// Shadow rays of the per-pixel direct part.
    pub reconstruction_rays: u64,
    /// Valid pixels no record covered (placement guarantees zero).
    pub uncovered_pixels: usize,
}

impl CachedField {
    pub fn record_count(&self) -> usize {
        self.records.iter().map(Vec::len).sum()
    }
}

type Payload = TaylorRgb<D2>;

pub use crate::core::cache::placement_order;

fn compute_record(
    scene: &Scene,
    x: DVec2,
    omega_o: DVec2,
    cs: &CacheSettings,
    pixel: usize,
    progress: &Progress,
) -> Result<RecordData, Cancelled> {
    let seed = mix64(cs.seed ^ mix64(pixel as u64));
    // The caller's progress: a cancel stops a capture between its rays (one record
    // can take minutes with deep paths in a dense, forward-scattering medium).
    let lf = capture(scene, x, omega_o, &cs.probe, seed, 0, progress)?;
    let (parts, metric_hessians) = match cs.method {
        CacheMethod::Ours => {
            let elements = proxy::build(&lf, cs.aware.rule);
            let parts = derivatives::aware(&lf, &elements, &cs.aware);
            let floored = with_radiance_floor(&elements, cs.hessian_floor);
            let h = derivatives::aware(&lf, &floored, &cs.aware);
            let lum = |t: &TaylorRgb<D2>| t.luminance().hess;
            (parts, [lum(&(h.single + h.multiple)), lum(&h.single), lum(&h.multiple)])
        }
        CacheMethod::Jarosz08 => (derivatives::unaware(&lf), [DMat2::ZERO; 3]),
    };
    Ok(RecordData {
        parts,
        metric_hessians,
        rays: lf.cost_rays,
    })
}

fn info(r: &Record<D2, Payload>) -> RecordInfo {
    RecordInfo {
        position: r.position,
        axes: [r.extent.axes.x_axis, r.extent.axes.y_axis],
        radii: r.extent.radii.to_array(),
        luminance: luminance(r.value.value()),
        rays: r.cost_rays,
    }
}

/// A record at x may be used at y: it sees y (a record never extrapolates across a
/// surface, the field jumps there).
fn sees(scene: &Scene, x: DVec2, y: DVec2) -> bool {
    let d = y - x;
    let len = d.length();
    len == 0.0 || !scene.geometry.occluded(x, d / len, len, None)
}

/// Covering records of `y` that can see it, as (index, tent weight) in `out`.
fn visible_covering(scene: &Scene, cache: &Cache<D2, Payload>, y: DVec2, out: &mut Vec<(usize, f64)>) {
    cache.covering_where(y, out, |x| sees(scene, x, y));
}

/// Weighted first- (or second-) order extrapolation from the visible covering
/// records, clamped at zero (radiance is non-negative; an extrapolated gradient can
/// overshoot). None when no visible record covers `y`.
fn reconstruct(
    scene: &Scene,
    cache: &Cache<D2, Payload>,
    y: DVec2,
    second_order: bool,
    scratch: &mut Vec<(usize, f64)>,
) -> Option<Rgb> {
    cache
        .interpolate_where(y, second_order, scratch, |x| sees(scene, x, y))
        .map(|v| v.max(Rgb::ZERO))
}

/// Place records and reconstruct the field of `fp.part` (direct evaluated per pixel).
pub fn render_cached(
    scene: &Scene,
    fp: &FieldParams,
    cs: &CacheSettings,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<CachedField, Cancelled> {
    let start = std::time::Instant::now();
    let (w, h) = (fp.width, fp.height);
    let mut field = Field::new(w, h, scene.domain_min, scene.domain_max);
    let omega_o = DVec2::from_angle(fp.omega_o_deg.to_radians());
    let metric = cs.metric(scene);
    let per_part = cs.per_part || matches!(fp.part, Part::Single | Part::Multiple);
    // Which cached quantities: index into RecordData::metric_hessians.
    let quantities: &[usize] = if per_part { &[1, 2] } else { &[0] };
    let payload = |d: &RecordData, q: usize| -> Payload {
        match q {
            0 => d.parts.single + d.parts.multiple,
            1 => d.parts.single,
            _ => d.parts.multiple,
        }
    };
    let mut caches: Vec<Cache<D2, Payload>> = quantities.iter().map(|_| Cache::new()).collect();
    let order = placement_order(w, h);
    progress.start(order.len() as u64);
    let mut placement_rays = 0;
    for &k in &order {
        progress.check()?;
        progress.advance(1);
        let x = field.pixel_center(k % w, k / w);
        if scene.medium_at(x).is_none() {
            continue;
        }
        let mut scratch = Vec::new();
        let uncovered: Vec<usize> = (0..caches.len())
            .filter(|&c| {
                visible_covering(scene, &caches[c], x, &mut scratch);
                scratch.is_empty()
            })
            .collect();
        if uncovered.is_empty() {
            continue;
        }
        let d = match memo.entry(k) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => {
                e.insert(compute_record(scene, x, omega_o, cs, k, progress)?)
            }
        };
        placement_rays += d.rays;
        for c in uncovered {
            let q = quantities[c];
            let value = payload(d, q);
            let extent = cs.method.extent(&value.luminance(), d.metric_hessians[q], &metric);
            let record = Record {
                position: x,
                value,
                extent,
                cost_rays: d.rays,
            };
            // Non-finite payloads are rejected by the cache; skip them rather than fail.
            let _ = caches[c].insert(record);
        }
    }
    let placement_seconds = start.elapsed().as_secs_f64();

    let t1 = std::time::Instant::now();
    let second_order = cs.second_order && cs.method == CacheMethod::Ours;
    // Per pixel (value, inside the medium, covered by a record), and rays per row.
    type Row = (Vec<(Rgb, bool, bool)>, u64);
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        .map(|j| {
            let mut rays = 0;
            let mut scratch = Vec::new();
            let row = (0..w)
                .map(|i| {
                    let x = field.pixel_center(i, j);
                    let Some(m) = scene.medium_at(x) else {
                        return (Rgb::ZERO, false, true);
                    };
                    let direct = if matches!(fp.part, Part::All | Part::Direct) {
                        let lobe = Lobe::Phase {
                            hg: m.phase,
                            travel: -omega_o,
                        };
                        direct_lights(scene, x, &lobe, None, &mut rays) * m.sigma_s
                    } else {
                        Rgb::ZERO
                    };
                    let cached: Vec<Option<Rgb>> = caches
                        .iter()
                        .map(|c| reconstruct(scene, c, x, second_order, &mut scratch))
                        .collect();
                    let covered = cached.iter().all(Option::is_some);
                    let cached: Vec<Rgb> = cached.into_iter().map(|c| c.unwrap_or(Rgb::ZERO)).collect();
                    let v = match (fp.part, per_part) {
                        (Part::Direct, _) => direct,
                        (Part::All, false) => direct + cached[0],
                        (Part::All, true) => direct + cached[0] + cached[1],
                        (Part::Single, _) => cached[0],
                        (Part::Multiple, _) => cached[1],
                    };
                    (v, true, covered)
                })
                .collect();
            (row, rays)
        })
        .collect();
    let (mut reconstruction_rays, mut uncovered_pixels) = (0, 0);
    for (j, (row, rays)) in rows.into_iter().enumerate() {
        reconstruction_rays += rays;
        for (i, (v, valid, covered)) in row.into_iter().enumerate() {
            field.values[j * w + i] = v;
            field.valid[j * w + i] = valid;
            uncovered_pixels += !covered as usize;
        }
    }
    Ok(CachedField {
        field,
        records: caches.iter().map(|c| c.records().iter().map(info).collect()).collect(),
        placement_seconds,
        reconstruction_seconds: t1.elapsed().as_secs_f64(),
        placement_rays,
        reconstruction_rays,
        uncovered_pixels,
    })
}

/// Equal-count mode: search ε (`core::equal_count`) until placement makes `target`
/// records (±1%), reusing memoised light fields. Returns the final field and ε.
pub fn render_with_count(
    scene: &Scene,
    fp: &FieldParams,
    cs: &CacheSettings,
    target: usize,
    memo: &mut RecordMemo,
    progress: &Progress,
) -> Result<(CachedField, f64), Cancelled> {
    let tol = (target as f64 * 0.01).max(1.0);
    crate::core::equal_count::search_eps(target, tol, cs.eps, |eps| {
        let c = CacheSettings { eps, ..cs.clone() };
        render_cached(scene, fp, &c, memo, progress).map(|f| (f.record_count(), f))
    })
}
