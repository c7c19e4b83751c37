//! Whether a record sees a point it covers, answered cheaply and exactly.
//!
//! A record is never used across a surface: every interpolation and every
//! coverage check casts a visibility ray from the record to the point, once per
//! covering record. In 3D that is one ray per covering record per march point, and
//! it made a cached camera sample cost ~28 path-traced ones on the staircase (stop
//! 26). But the segment from a record at x to a point y inside its extent lies in
//! the extent (an ellipsoid is convex and holds x), so only the occluders that
//! meet the extent's bounding box can block it. Listed once per record, they
//! answer every later test: none (the record's extent is clear, no test at all),
//! a few (tested directly, without the tree), or many (the ray is cast as
//! before). The answers are those of the full ray cast, bit for bit: the same
//! primitives' intersection with the same bounds decides.

use super::dim::Dim;
use super::world::World;
use crate::core::cache::Cache;
use crate::core::metric::Extent;
use crate::core::space::Space;
use rayon::prelude::*;

/// Above this many occluders near a record, its tests cast rays through the tree.
/// Measured on the staircase's reconstruction (86 triangles, one pinned core,
/// median of 3 pairs): 64 takes 0.89× the time of 16; 256 no less than 64.
pub const FEW_OCCLUDERS: usize = 64;

/// The occluders that could come between a record and the points it covers.
#[derive(Clone, Debug, PartialEq)]
pub enum Near {
    /// None: the record sees every point of its extent.
    Clear,
    /// These (primitive indices, increasing).
    Few(Box<[u32]>),
    /// More than [`FEW_OCCLUDERS`], or a world that cannot list them.
    Many,
}

/// The occluders near the record at `x` with `extent`. The box is the extent's,
/// widened by 1e-5 scene sizes: the surface cache tests from points lifted off
/// their surfaces by 1e-6 scene sizes, and rounding must not drop an occluder
/// grazing the box.
pub fn near_record<W: World>(world: &W, x: <W::S as Space>::Vec, extent: &Extent<W::S>) -> Near {
    let pad = <W::S as Dim>::splat(1e-5 * world.scale());
    let h = extent.half_widths() * (1.0 + 1e-9) + pad;
    let mut ids = Vec::new();
    if !world.occluders_in_box(x - h, x + h, FEW_OCCLUDERS, &mut ids) {
        Near::Many
    } else if ids.is_empty() {
        Near::Clear
    } else {
        Near::Few(ids.into_boxed_slice())
    }
}

/// [`near_record`] of every record of `cache`, in its order.
pub fn near_table<W: World, V: Sync>(world: &W, cache: &Cache<W::S, V>) -> Vec<Near> {
    cache
        .records()
        .par_iter()
        .map(|r| near_record(world, r.position, &r.extent))
        .collect()
}

/// Does the record at `x`, with occluders `near`, see `y` (a point of its extent)?
/// A test that casts or checks anything counts one ray in `rays`.
pub fn sees_near<W: World>(
    world: &W,
    near: &Near,
    x: <W::S as Space>::Vec,
    y: <W::S as Space>::Vec,
    rays: &mut u64,
) -> bool {
    let d = y - x;
    let len = W::S::length(d);
    if len == 0.0 {
        return true;
    }
    match near {
        Near::Clear => true,
        Near::Few(ids) => {
            *rays += 1;
            !world.occluded_among(ids, x, d / len, len)
        }
        Near::Many => {
            *rays += 1;
            !world.occluded(x, d / len, len, None)
        }
    }
}
