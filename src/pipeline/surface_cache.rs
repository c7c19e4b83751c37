//! An irradiance cache on surfaces, in any dimension (issue 16 item 3): records of
//! the indirect irradiance of diffuse surfaces ([`super::surface_record`]) placed
//! over a source of surface points (the first hits of a 3D image's camera rays),
//! and interpolated there. Direct light is left to each pixel
//! ([`super::path::direct_at`]): its shadows are sharp.
//!
//! The walk is the medium cache's ([`super::placement::walk`]): no holes over the
//! source's points, results independent of the thread count. A record serves a
//! point when the point lies in its extent (the metric's ellipse in the tangent
//! plane, from the record's tangential Hessian), their normals agree (a crease or
//! a curved surface is not extrapolated across: [`NORMAL_AGREEMENT`]), and each
//! sees the other from just above its surface.

use super::dim::Dim;
use super::placement::{RadianceCache, interpolate_kept, memoised, walk};
use super::probe::SurfaceReceiver;
use super::record::CacheSettings;
use super::sight::{Near, near_record, sees_near};
use super::surface_record::{SurfaceRecordData, compute_surface_record};
use super::world::World;
use crate::core::cache::{Cache, Record};
use crate::core::color::Rgb;
use crate::core::space::Space;
use crate::progress::{Cancelled, Progress};
use std::collections::HashMap;
use std::time::Instant;

/// The least cosine between a record's normal and a point's for the record to
/// serve it (≈ 18°): irradiance caching's usual normal test (Ward et al. 1988
/// weigh by √(1 − n·n')), here a cut, since the extent already weighs distance.
pub const NORMAL_AGREEMENT: f64 = 0.95;

/// A surface point where the cache is queried.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceQuery<S: Dim> {
    /// Identifies the point among the source's (the memo's key).
    pub key: u128,
    /// The stream of its record's light field.
    pub id: u64,
    pub y: S::Vec,
    /// Unit normal of the side the point is seen from.
    pub normal: S::Vec,
    /// The primitive it lies on.
    pub prim: u32,
}

/// Where a surface cache is queried: units in placement order, each with its points.
pub trait SurfaceSource<S: Dim>: Sync {
    fn units(&self) -> usize;
    fn points(&self, k: usize, out: &mut Vec<SurfaceQuery<S>>);
}

/// Surface records' light fields per query point, shared by placements of the same
/// scene, settings and source.
pub type SurfaceMemo<S> = HashMap<u128, SurfaceRecordData<S>>;

/// A placed surface cache and what placing it cost.
#[derive(Clone, Debug)]
pub struct SurfaceCache<S: Dim> {
    /// Records of the indirect irradiance (all parts together).
    pub cache: RadianceCache<S>,
    /// Per record, its unit normal.
    pub normals: Vec<S::Vec>,
    /// Per record, the occluders near it (`super::sight`).
    pub near: Vec<Near>,
    pub eps: f64,
    pub query_points: u64,
    pub rays: u64,
    /// Checks plus the capture time of every record used.
    pub seconds: f64,
}

impl<S: Dim> SurfaceCache<S> {
    pub fn record_count(&self) -> usize {
        self.cache.len()
    }
}

/// Whether record i (at x) of `sc` may serve the surface point `y` with normal `n`
/// (see the module docs), as the cache's filter.
fn serving<W: World>(
    world: &W,
    (normals, near): (&[<W::S as Space>::Vec], &[Near]),
    (y, n): (<W::S as Space>::Vec, <W::S as Space>::Vec),
    rays: &mut u64,
) -> impl FnMut(usize, <W::S as Space>::Vec) -> bool {
    let lift = 1e-6 * world.scale();
    move |i, x| {
        let m = normals[i];
        W::S::dot(m, n) >= NORMAL_AGREEMENT && sees_near(world, &near[i], x + m * lift, y + n * lift, rays)
    }
}

/// Place indirect-irradiance records (`cs`: method, ε, probe, seed) over every
/// point of `source`.
pub fn place_surfaces<W: World, Q: SurfaceSource<W::S>>(
    world: &W,
    source: &Q,
    cs: &CacheSettings,
    memo: &mut SurfaceMemo<W::S>,
    progress: &Progress,
) -> Result<SurfaceCache<W::S>, Cancelled> {
    let start = Instant::now();
    let metric = cs.metric(world.scale());
    let units = source.units();
    progress.start(units as u64);
    type State<S> = (RadianceCache<S>, Vec<<S as Space>::Vec>, Vec<Near>);
    let mut state: State<W::S> = (Cache::new(), Vec::new(), Vec::new());
    let (mut records_seconds, mut capture_wall) = (0.0, 0.0);
    let covered = |(cache, normals, near): &State<W::S>, p: &SurfaceQuery<W::S>, rays: &mut u64| {
        cache.is_covered_where(p.y, serving(world, (normals, near), (p.y, p.normal), rays))
    };
    let (query_points, rays) = walk(
        units,
        progress,
        &mut state,
        |k, out| source.points(k, out),
        |st, p, rays| !covered(st, p, rays),
        |st, p, rays| {
            if covered(st, &p, rays) {
                return Ok(());
            }
            let receiver = SurfaceReceiver {
                normal: p.normal,
                prim: p.prim,
                emitted: false,
            };
            let d = memoised(memo, p.key, &mut capture_wall, || {
                compute_surface_record(world, p.y, receiver, cs, p.id, progress)
            })?;
            *rays += d.rays;
            records_seconds += d.seconds;
            let value = d.irradiance();
            let mut luminance = value.luminance();
            luminance.value = d.metric_luminance(luminance.value);
            let record = Record {
                position: p.y,
                value,
                extent: cs.method.extent(&luminance, d.metric_hessian, &metric),
                cost_rays: d.rays,
            };
            // A non-finite light field is refused: the point stays uncovered and is
            // path traced by the reconstruction.
            let near_it = near_record(world, record.position, &record.extent);
            if st.0.insert(record).is_ok() {
                st.1.push(d.normal);
                st.2.push(near_it);
            }
            Ok(())
        },
    )?;
    let (cache, normals, near) = state;
    Ok(SurfaceCache {
        cache,
        normals,
        near,
        eps: cs.eps,
        query_points,
        rays,
        seconds: start.elapsed().as_secs_f64() - capture_wall + records_seconds,
    })
}

/// The indirect irradiance at the surface point `y` (normal `n`) from the records
/// that serve it, each extrapolated without going negative (as the medium cache's);
/// None when none does.
pub fn interpolate_surface<W: World>(
    world: &W,
    sc: &SurfaceCache<W::S>,
    (y, n): (<W::S as Space>::Vec, <W::S as Space>::Vec),
    second_order: bool,
    scratch: &mut Vec<(usize, f64)>,
    rays: &mut u64,
) -> Option<Rgb> {
    let keep = serving(world, (&sc.normals, &sc.near), (y, n), rays);
    interpolate_kept(&sc.cache, y, second_order, scratch, keep, |i| {
        sc.cache.records()[i].value
    })
}
