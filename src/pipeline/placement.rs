//! Radiance-cache placement over a source of query points, in any dimension
//! (theory.md §8): a 2D field's pixel centres coarse to fine, or every march point of
//! a 3D image's camera samples.
//!
//! Placement walks the source's units (pixels) in its order and creates a record
//! wherever no record that sees the point covers it, so a reconstruction from the
//! same points has no holes, and no record is used across a surface. Batches of
//! units are checked in parallel against the caches as they were at the batch's
//! start; their uncovered points are then re-checked and filled in order. Covered
//! points stay covered as records are added, so the result is that of a sequential
//! walk and does not depend on the thread count. Each record's light field is
//! captured in parallel over its rays.
//!
//! Light fields are memoised per query point ([`RecordMemo`]) with the seconds they
//! took, so an equal-count search pays for each point once, and a placement's time
//! is what a fresh placement would take (its checks plus its records' capture).

use super::dim::Dim;
use super::probe::Outgoing;
use super::record::{CacheSettings, Cached, RecordData, RecordInfo, compute_record, sees};
use super::world::World;
use crate::core::cache::{Cache, Record};
use crate::core::color::Rgb;
use crate::core::taylor_rgb::TaylorRgb;
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::time::Instant;

/// Units checked in parallel before their uncovered points are filled in order.
/// A constant, so that placement does not depend on the thread count.
const BATCH: usize = 64;

/// A point where the cache is queried.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryPoint<S: Dim> {
    /// Identifies the point among the source's (the memo's key).
    pub key: u128,
    /// The stream of its record's light field.
    pub id: u64,
    pub y: S::Vec,
}

/// Where a cache is queried: units in placement order, each with its points.
pub trait QuerySource<S: Dim>: Sync {
    /// The number of units (pixels), in placement order.
    fn units(&self) -> usize;
    /// The query points of the k-th unit in placement order.
    fn points(&self, k: usize, out: &mut Vec<QueryPoint<S>>);
    /// Where L_s leaves a query point towards.
    fn outgoing(&self, y: S::Vec) -> Outgoing<S::Vec>;
}

pub type RadianceCache<S> = Cache<S, TaylorRgb<S>>;

/// Light fields per query point, shared by placements of the same scene, method,
/// probe settings and source.
pub type RecordMemo<S> = HashMap<u128, RecordData<S>>;

/// Placed caches and what placing them cost.
#[derive(Clone, Debug)]
pub struct Placement<S: Dim> {
    /// One cache per cached quantity.
    pub caches: Vec<RadianceCache<S>>,
    pub cached: Vec<Cached>,
    pub eps: f64,
    /// Query points visited.
    pub query_points: u64,
    /// Rays of the records' light fields plus the visibility tests of the checks.
    pub rays: u64,
    /// Coverage checks plus the capture time of every record used.
    pub seconds: f64,
}

impl<S: Dim> Placement<S> {
    pub fn record_count(&self) -> usize {
        self.caches.iter().map(|c| c.len()).sum()
    }

    /// The records of each cache, for figures and JSON.
    pub fn records(&self) -> Vec<Vec<RecordInfo<S>>> {
        self.caches
            .iter()
            .map(|c| c.records().iter().map(RecordInfo::of).collect())
            .collect()
    }
}

/// Place records for the quantities `cached` over every query point of `source`.
pub fn place<W: World, Q: QuerySource<W::S>>(
    world: &W,
    source: &Q,
    cs: &CacheSettings,
    cached: &[Cached],
    memo: &mut RecordMemo<W::S>,
    progress: &Progress,
) -> Result<Placement<W::S>, Cancelled> {
    let start = Instant::now();
    let metric = cs.metric(world.scale());
    let units = source.units();
    progress.start(units as u64);
    let mut caches: Vec<RadianceCache<W::S>> = cached.iter().map(|_| Cache::new()).collect();
    let (mut query_points, mut rays, mut records_seconds, mut capture_wall) = (0u64, 0u64, 0.0, 0.0);
    let uncovered = |caches: &[RadianceCache<W::S>], y, rays: &mut u64| -> Vec<usize> {
        (0..caches.len())
            .filter(|&c| !caches[c].is_covered_where(y, |x| sees(world, x, y, rays)))
            .collect()
    };
    for batch in (0..units).collect::<Vec<_>>().chunks(BATCH) {
        progress.check()?;
        // Per unit: its points with uncovered caches, its point count, the checks' rays.
        type Pending<S> = (Vec<QueryPoint<S>>, u64, u64);
        let pending: Vec<Pending<W::S>> = batch
            .par_iter()
            .map(|&k| {
                let (mut points, mut r) = (Vec::new(), 0u64);
                source.points(k, &mut points);
                let n = points.len() as u64;
                points.retain(|p| !uncovered(&caches, p.y, &mut r).is_empty());
                (points, n, r)
            })
            .collect();
        for (points, n, r) in pending {
            query_points += n;
            rays += r;
            for p in points {
                let missing = uncovered(&caches, p.y, &mut rays);
                if missing.is_empty() {
                    continue;
                }
                let d = match memo.entry(p.key) {
                    Entry::Occupied(e) => e.into_mut(),
                    Entry::Vacant(e) => {
                        let t = Instant::now();
                        let d = compute_record(world, p.y, source.outgoing(p.y), cs, p.id, progress)?;
                        capture_wall += t.elapsed().as_secs_f64();
                        e.insert(d)
                    }
                };
                rays += d.rays;
                records_seconds += d.seconds;
                for c in missing {
                    let value = d.payload(cached[c]);
                    let record = Record {
                        position: p.y,
                        value,
                        extent: cs
                            .method
                            .extent(&value.luminance(), d.metric_hessian(cached[c]), &metric),
                        cost_rays: d.rays,
                    };
                    // A non-finite light field is refused by the cache: the point stays
                    // uncovered (reported by the reconstruction) rather than failing.
                    let _ = caches[c].insert(record);
                }
            }
        }
        progress.advance(batch.len() as u64);
    }
    Ok(Placement {
        caches,
        cached: cached.to_vec(),
        eps: cs.eps,
        query_points,
        rays,
        seconds: start.elapsed().as_secs_f64() - capture_wall + records_seconds,
    })
}

/// Why an equal-count placement has no result.
#[derive(Debug, thiserror::Error)]
pub enum CountError {
    #[error("cancelled")]
    Cancelled(#[from] Cancelled),
    /// Placement counts jump with ε (a record placed earlier changes what later
    /// points see), and some counts are out of reach.
    #[error(
        "no error threshold places {target} records (±{ACCEPT_PERCENT}%): the nearest is {best} records \
         at ε = {eps:.4e}; try another count or record seed"
    )]
    Unreachable { target: usize, best: usize, eps: f64 },
}

/// How far from the target an equal-count placement may end, in percent.
pub const ACCEPT_PERCENT: f64 = 5.0;

/// Equal-count mode: search ε (`core::equal_count`) until placement makes `target`
/// records (±1%, or the nearest within ±[`ACCEPT_PERCENT`]), reusing memoised
/// light fields; an error when no ε comes that close.
pub fn place_with_count<W: World, Q: QuerySource<W::S>>(
    world: &W,
    source: &Q,
    cs: &CacheSettings,
    cached: &[Cached],
    target: usize,
    memo: &mut RecordMemo<W::S>,
    progress: &Progress,
) -> Result<Placement<W::S>, CountError> {
    let tol = (target as f64 * 0.01).max(1.0);
    let (placement, eps) = crate::core::equal_count::search_eps(target, tol, cs.eps, |eps| {
        let c = CacheSettings { eps, ..cs.clone() };
        place(world, source, &c, cached, memo, progress).map(|p| (p.record_count(), p))
    })?;
    let best = placement.record_count();
    if (best as f64 - target as f64).abs() > tol.max(target as f64 * ACCEPT_PERCENT / 100.0) {
        return Err(CountError::Unreachable { target, best, eps });
    }
    Ok(placement)
}

/// L_s at `y` from the covering records that see it, clamped at zero (radiance is
/// non-negative; an extrapolated gradient can overshoot). None when no visible
/// record covers `y`.
pub fn interpolate<W: World>(
    world: &W,
    cache: &RadianceCache<W::S>,
    y: <W::S as crate::core::space::Space>::Vec,
    second_order: bool,
    scratch: &mut Vec<(usize, f64)>,
    rays: &mut u64,
) -> Option<Rgb> {
    cache
        .interpolate_where(y, second_order, scratch, |x| sees(world, x, y, rays))
        .map(|v| v.max(Rgb::ZERO))
}
