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
use super::eye_cone::{EyeCone, served};
use super::moments::{MomentQuery, RecordMoments};
use super::probe::Outgoing;
use super::record::{CacheSettings, Cached, RecordData, RecordInfo, compute_record};
use super::sight::{Near, near_record, near_table, sees_near};
use super::world::{PointLight, World};
use crate::core::cache::{Cache, Record};
use crate::core::color::Rgb;
use crate::core::metric::gradient_noise_radius;
use crate::core::space::Space;
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

/// A cache as interpolation reads it: the records, the occluders near each
/// ([`near_table`]) and the eye cone they serve within, if any.
pub type Served<'a, S> = (&'a RadianceCache<S>, &'a [Near], Option<&'a EyeCone<S>>);

/// Light fields per query point, shared by placements of the same scene, method,
/// probe settings and source (and edge reach asked for or not: only then do they
/// hold [`RecordData::nearest_edge`]).
pub type RecordMemo<S> = HashMap<u128, RecordData<S>>;

/// Placed caches and what placing them cost.
#[derive(Clone, Debug)]
pub struct Placement<S: Dim> {
    /// One cache per cached quantity.
    pub caches: Vec<RadianceCache<S>>,
    pub cached: Vec<Cached>,
    pub eps: f64,
    /// Per cache, per record (in the cache's order): its moments over ω_o
    /// (`super::moments`), empty without [`CacheSettings::moment_bands`].
    pub moments: Vec<Vec<RecordMoments<S>>>,
    /// Query points visited.
    pub query_points: u64,
    /// Rays of the records' light fields plus the visibility tests of the checks.
    pub rays: u64,
    /// Coverage checks plus the capture time of every record used.
    pub seconds: f64,
    /// The records leave out the light arriving straight from the lights, which
    /// is sampled this many times at every point served
    /// ([`CacheSettings::direct_samples`]).
    pub direct_samples: Option<u32>,
    /// How noisy the records placed here are (not those read from a file).
    pub value_noise: ValueNoise,
    /// The records serve only the points their eye sees near them
    /// ([`CacheSettings::eye_cone_deg`]).
    pub eye_cone: Option<EyeCone<S>>,
}

/// The records' own noise, summed over the records a placement made: the
/// variance each estimated for its value (`RecordData::value_var`) and its
/// value's square (luminances of the scattered light).
///
/// Why: an image's reported standard error covers its camera samples, and a
/// record's error is shared by every point it serves, so it is not in it. Where
/// records are noisy (thick fog, a lamp in it: README, "Where the 3D cache
/// fails") their relative noise tells how far the image may be off.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ValueNoise {
    pub variance_sum: f64,
    pub square_sum: f64,
}

impl ValueNoise {
    /// √(Σ variance / Σ value²): the records' noise relative to their values
    /// (RMS over RMS, so that dark records weigh little); None without records
    /// or light.
    pub fn relative(&self) -> Option<f64> {
        let r = (self.variance_sum / self.square_sum).sqrt();
        (self.square_sum > 0.0 && r.is_finite()).then_some(r)
    }

    fn add(&mut self, variance: f64, value: f64) {
        if variance.is_finite() && value.is_finite() {
            self.variance_sum += variance.max(0.0);
            self.square_sum += value * value;
        }
    }
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
    place_onto(world, source, cs, cached, None, memo, progress)
}

/// [`place`] starting from the records of an earlier placement of the same
/// quantities (another camera's, whose records carry moments over ω_o): only the
/// points they leave uncovered get new records, and the placement's rays and
/// seconds are those of this walk alone.
pub fn place_onto<W: World, Q: QuerySource<W::S>>(
    world: &W,
    source: &Q,
    cs: &CacheSettings,
    cached: &[Cached],
    earlier: Option<Placement<W::S>>,
    memo: &mut RecordMemo<W::S>,
    progress: &Progress,
) -> Result<Placement<W::S>, Cancelled> {
    let start = Instant::now();
    let metric = cs.metric(world.scale());
    let units = source.units();
    progress.start(units as u64);
    let (caches, mut moments, mut value_noise) = match earlier {
        Some(p) if p.cached == cached => (p.caches, p.moments, p.value_noise),
        _ => (
            cached.iter().map(|_| Cache::new()).collect(),
            vec![Vec::new(); cached.len()],
            ValueNoise::default(),
        ),
    };
    // Records without moments (read from a file) keep an empty entry, so that entry
    // i stays record i's.
    for (table, cache) in moments.iter_mut().zip(&caches) {
        table.resize(cache.len(), RecordMoments::default());
    }
    let (mut records_seconds, mut capture_wall) = (0.0, 0.0);
    // Per cache, per record: the occluders near it (`super::sight`).
    let near: Vec<Vec<Near>> = caches.iter().map(|c| near_table(world, c)).collect();
    // A source's points all leave towards one eye (a camera) or along a direction.
    let g = world.medium().map_or(0.0, |m| <W::S as Dim>::phase_g(&m.phase));
    let eye_cone = EyeCone::towards(source.outgoing(<W::S as Space>::zero()), cs.eye_cone_deg, g);
    type State<S> = (Vec<RadianceCache<S>>, Vec<Vec<Near>>);
    let uncovered = |(caches, near): &State<W::S>, y, rays: &mut u64| -> Vec<usize> {
        (0..caches.len())
            .filter(|&c| {
                !caches[c].is_covered_where(y, |i, x| {
                    served(eye_cone.as_ref(), x, y) && sees_near(world, &near[c][i], x, y, rays)
                })
            })
            .collect()
    };
    let mut state = (caches, near);
    let holds_light = cs.records_hold_light(world.has_extended_lights());
    let (query_points, rays) = walk(
        units,
        progress,
        &mut state,
        |k, out| source.points(k, out),
        |st, p: &QueryPoint<W::S>, rays| holds_light && !uncovered(st, p.y, rays).is_empty(),
        |st, p, rays| {
            let missing = uncovered(st, p.y, rays);
            let (caches, near) = st;
            if missing.is_empty() {
                return Ok(());
            }
            let d = memoised(memo, p.key, &mut capture_wall, || {
                compute_record(world, p.y, source.outgoing(p.y), cs, p.id, progress)
            })?;
            *rays += d.rays;
            records_seconds += d.seconds;
            value_noise.add(d.value_var, d.scattered_luminance());
            // One distance per record, whichever caches it serves.
            let lamp = cs.lamp_reach.map(|k| (k, nearest_lamp(world.point_lights(), p.y)));
            for c in missing {
                let value = d.payload(cached[c]);
                let luminance = d.metric_luminance(cached[c], value.luminance());
                let mut extent = cs.method.extent(&luminance, d.metric_hessian(cached[c]), &metric);
                if let Some(k) = cs.edge_reach {
                    extent = extent.within((k * d.nearest_edge).max(metric.r_min));
                }
                if let Some((k, d_lamp)) = lamp.filter(|&(_, d)| d.is_finite()) {
                    extent = extent.within((k * d_lamp).max(metric.r_min));
                }
                if cs.gradient_noise_reach {
                    let reach = gradient_noise_radius::<W::S>(luminance.value, d.multiple_grad_var, &metric);
                    extent = extent.within(reach);
                }
                // The extent follows the measured gradient; the extrapolation uses
                // it less where it is mostly noise (`RecordData::payload_to_extrapolate`).
                let value = if cs.shrink_noisy_gradients {
                    d.payload_to_extrapolate(cached[c])
                } else {
                    value
                };
                let record = Record {
                    position: p.y,
                    value,
                    extent,
                    cost_rays: d.rays,
                };
                // A non-finite light field is refused by the cache: the point stays
                // uncovered (reported by the reconstruction) rather than failing.
                let near_it = near_record(world, record.position, &record.extent);
                if caches[c].insert(record).is_ok() {
                    moments[c].push(d.moment_payload(cached[c]));
                    near[c].push(near_it);
                }
            }
            Ok(())
        },
    )?;
    let (caches, _) = state;
    Ok(Placement {
        caches,
        cached: cached.to_vec(),
        moments,
        eps: cs.eps,
        query_points,
        rays,
        seconds: start.elapsed().as_secs_f64() - capture_wall + records_seconds,
        direct_samples: cs.direct_samples,
        value_noise,
        eye_cone,
    })
}

/// Distance from `x` to the nearest point light that emits, +∞ without one.
fn nearest_lamp<S: Dim>(lights: &[PointLight<S>], x: S::Vec) -> f64 {
    lights
        .iter()
        .filter(|l| l.intensity.max_element() > 0.0)
        .map(|l| <S as crate::core::space::Space>::length(l.position - x))
        .fold(f64::INFINITY, f64::min)
}

/// The memo's light field of `key`, computed (and its wall time added to
/// `capture_wall`) when the memo does not have it: a placement is charged its
/// records' own seconds, memoised or not, not the capture's wall time.
pub(super) fn memoised<'m, D>(
    memo: &'m mut HashMap<u128, D>,
    key: u128,
    capture_wall: &mut f64,
    compute: impl FnOnce() -> Result<D, Cancelled>,
) -> Result<&'m mut D, Cancelled> {
    Ok(match memo.entry(key) {
        Entry::Occupied(e) => e.into_mut(),
        Entry::Vacant(e) => {
            let t = Instant::now();
            let d = compute()?;
            *capture_wall += t.elapsed().as_secs_f64();
            e.insert(d)
        }
    })
}

/// The walk every placement shares: units in batches of [`BATCH`], each unit's
/// points kept in parallel where `open` says a record is missing against the state
/// at the batch's start, then `fill`ed in order (which re-checks: a point filled
/// earlier in the batch may cover it now). Covered points stay covered as records
/// are added, so the result is that of a sequential walk whatever the thread
/// count. Returns the points visited and the checks' rays (`fill` adds its own).
pub(super) fn walk<P: Send, St: Sync>(
    units: usize,
    progress: &Progress,
    state: &mut St,
    points: impl Fn(usize, &mut Vec<P>) + Sync,
    open: impl Fn(&St, &P, &mut u64) -> bool + Sync,
    mut fill: impl FnMut(&mut St, P, &mut u64) -> Result<(), Cancelled>,
) -> Result<(u64, u64), Cancelled> {
    let (mut query_points, mut rays) = (0u64, 0u64);
    for batch in (0..units).collect::<Vec<_>>().chunks(BATCH) {
        progress.check()?;
        // Per unit: its points still open, its point count, the checks' rays.
        let pending: Vec<(Vec<P>, u64, u64)> = batch
            .par_iter()
            .map(|&k| {
                let (mut out, mut r) = (Vec::new(), 0u64);
                points(k, &mut out);
                let n = out.len() as u64;
                out.retain(|p| open(state, p, &mut r));
                (out, n, r)
            })
            .collect();
        for (open_points, n, r) in pending {
            query_points += n;
            rays += r;
            for p in open_points {
                fill(state, p, &mut rays)?;
            }
        }
        progress.advance(batch.len() as u64);
    }
    Ok((query_points, rays))
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

/// L_s at `y` from the covering records that see it (and serve it, within `cone`:
/// [`Placement::eye_cone`]), clamped at zero (radiance is non-negative; an
/// extrapolated gradient can overshoot). None when no visible record covers `y`.
/// `near`: the records' occluders, [`near_table`] of `cache`.
pub fn interpolate<W: World>(
    world: &W,
    (cache, near, cone): Served<'_, W::S>,
    y: <W::S as crate::core::space::Space>::Vec,
    second_order: bool,
    scratch: &mut Vec<(usize, f64)>,
    rays: &mut u64,
) -> Option<Rgb> {
    interpolate_by(world, (cache, near, cone), y, second_order, scratch, rays, |i| {
        cache.records()[i].value
    })
}

/// [`interpolate`] from the records' moments over ω_o (`table`, as
/// [`Placement::moments`]) for the ω_o of `query` ([`RecordMoments::towards`]).
#[allow(clippy::too_many_arguments)] // interpolate's inputs and the moments'
pub fn interpolate_moments<W: World>(
    world: &W,
    (cache, near): (&RadianceCache<W::S>, &[Near]),
    table: &[RecordMoments<W::S>],
    query: &MomentQuery<W::S>,
    y: <W::S as crate::core::space::Space>::Vec,
    second_order: bool,
    scratch: &mut Vec<(usize, f64)>,
    rays: &mut u64,
) -> Option<Rgb> {
    // Moments serve every ω_o: no cone.
    interpolate_by(world, (cache, near, None), y, second_order, scratch, rays, |i| {
        table[i].towards(&cache.records()[i].value, query)
    })
}

fn interpolate_by<W: World>(
    world: &W,
    (cache, near, cone): Served<'_, W::S>,
    y: <W::S as crate::core::space::Space>::Vec,
    second_order: bool,
    scratch: &mut Vec<(usize, f64)>,
    rays: &mut u64,
    payload: impl Fn(usize) -> TaylorRgb<W::S>,
) -> Option<Rgb> {
    let keep = |i: usize, x| served(cone, x, y) && sees_near(world, &near[i], x, y, rays);
    interpolate_kept(cache, y, second_order, scratch, keep, payload)
}

/// Σ w_i v_i(y) / Σ w_i over the records covering `y` that pass `keep(index,
/// position)`, each extrapolated without going negative; None when none is kept.
pub(super) fn interpolate_kept<S: Dim>(
    cache: &RadianceCache<S>,
    y: S::Vec,
    second_order: bool,
    scratch: &mut Vec<(usize, f64)>,
    keep: impl FnMut(usize, S::Vec) -> bool,
    payload: impl Fn(usize) -> TaylorRgb<S>,
) -> Option<Rgb> {
    cache.covering_where(y, scratch, keep);
    let total: f64 = scratch.iter().map(|&(_, w)| w).sum();
    if total <= 0.0 {
        return None;
    }
    let records = cache.records();
    let mut out = Rgb::ZERO;
    for &(i, w) in scratch.iter() {
        out += nonnegative_extrapolation(&payload(i), y - records[i].position, second_order) * (w / total);
    }
    Some(out.max(Rgb::ZERO))
}

/// A record's payload extrapolated by `d`, per channel: where its Taylor expansion
/// goes negative it has left the region it describes (it extrapolates across a
/// peak or an edge it was not fitted to), and the next lower order stands in —
/// first order for second, the record's value for first. Radiance is never
/// negative, and a negative term clamped to zero afterwards left isolated black
/// pixels next to lights (issue 16: up to 47 in a shaded-light scene).
fn nonnegative_extrapolation<S: crate::pipeline::dim::Dim>(value: &TaylorRgb<S>, d: S::Vec, second_order: bool) -> Rgb {
    use crate::core::cache::Interpolant;
    let mut v = value.extrapolated(d, second_order);
    if v.min_element() >= 0.0 {
        return v;
    }
    let first = if second_order { value.extrapolated(d, false) } else { v };
    let value = value.value();
    for c in 0..3 {
        if v[c] < 0.0 {
            v[c] = if first[c] >= 0.0 { first[c] } else { value[c].max(0.0) };
        }
    }
    v
}

#[cfg(test)]
mod extrapolation_tests {
    use super::nonnegative_extrapolation;
    use crate::core::cache::Record;
    use crate::core::color::Rgb;
    use crate::core::metric::Extent;
    use crate::core::space::D2;
    use crate::core::taylor::Taylor2;
    use crate::core::taylor_rgb::TaylorRgb;
    use glam::{DMat2, DVec2};

    /// Per channel: a positive expansion is kept as is; a negative second-order
    /// term falls back to first order, a negative first order to the value.
    #[test]
    fn a_negative_expansion_falls_back_order_by_order() {
        let red = Taylor2::new(1.0, DVec2::new(-0.5, 0.0), DMat2::ZERO);
        let green = Taylor2::new(1.0, DVec2::new(-3.0, 0.0), DMat2::ZERO);
        let blue = Taylor2::new(1.0, DVec2::ZERO, DMat2::from_diagonal(DVec2::splat(-10.0)));
        let r: Record<D2, TaylorRgb<D2>> = Record {
            position: DVec2::ZERO,
            value: TaylorRgb::<D2> {
                channels: [red, green, blue],
            },
            extent: Extent::isotropic(1.0),
            cost_rays: 0,
        };
        let y = DVec2::new(0.5, 0.0);
        // Second order: red 0.75 kept; green 1 − 1.5 < 0 → value 1; blue 1 − 1.25 < 0 → first order 1.
        let at = |y: DVec2, second: bool| nonnegative_extrapolation::<D2>(&r.value, y - r.position, second);
        assert_eq!(at(y, true), Rgb::new(0.75, 1.0, 1.0));
        assert_eq!(at(y, false), Rgb::new(0.75, 1.0, 1.0));
        assert_eq!(at(DVec2::new(0.1, 0.0), true).x, 0.95);
    }
}
