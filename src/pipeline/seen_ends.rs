//! The nearest end of a surface that a point sees as a silhouette, found from the
//! geometry ([`World::primitive_ends`]) rather than between a probe's rays.
//!
//! Why: a probe finds where surfaces end between its rays, and a surface seen
//! nearly edge-on subtends less than one ray spacing. A record 0.004 beside the
//! occluder's line, 0.15 from its end (`occluder.json` at 256², budget 4: ~400
//! directions, 0.016 rad apart; the occluder subtends 0.023 rad there) saw no end,
//! took the metric's radius (0.5) and reached across the end: errors above 0.1 on
//! both sides of it, 3× the image's error at 128², where the records happened to
//! sit farther from that line. In 3D a thin quad (a lamp, a shelf) seen from
//! beside its plane is missed the same way.

use super::dim::Dim;
use super::silhouette::sees_other;
use super::world::World;
use crate::core::space::Space;

type VecOf<W> = <<W as World>::S as Space>::Vec;

/// Most primitives listed around a point before the box is shrunk.
const MAX_LISTED: usize = 256;
/// Most candidate ends tested with rays (nearest first): beyond them the point
/// sees so many ends so near that the probe's rays find one.
const MAX_TESTED: usize = 16;
/// Sideways offset of the ray that looks past an end, relative to its distance.
const PAST_END: f64 = 1e-4;

/// Distance from `x` to the nearest end of a primitive within `within` that `x`
/// sees, with nothing at its depth just past it — a silhouette, as the probe's
/// [`sees_other`] tells one between neighbouring rays (a corner or an edge where
/// two primitives meet and x sees both is none) — and the rays cast; +∞ when
/// none. The look past an end turns the sight line away from the primitive, at
/// right angles to it, in the plane the sight line and the leaving direction span.
pub fn nearest_seen_end<W: World>(world: &W, x: VecOf<W>, within: f64) -> (f64, u64) {
    let tiny = 1e-9 * world.scale();
    let mut r = within.min(world.scale());
    if r.is_nan() || r <= tiny || !W::S::vec_is_finite(x) {
        return (f64::INFINITY, 0);
    }
    let mut ids = Vec::new();
    // A crowded neighbourhood: the nearest ends lie in a smaller box.
    while !world.occluders_in_box(
        x - <W::S as Dim>::splat(r),
        x + <W::S as Dim>::splat(r),
        MAX_LISTED,
        &mut ids,
    ) {
        r *= 0.5;
        if r <= tiny {
            return (f64::INFINITY, 0);
        }
    }
    let mut ends = Vec::with_capacity(3 * ids.len());
    let mut found = Vec::new();
    for &id in &ids {
        found.clear();
        world.primitive_ends(id, x, &mut found);
        for &(end, leaving) in &found {
            let d = W::S::length(end - x);
            if d > tiny && d < r {
                ends.push((d, id, end, leaving));
            }
        }
    }
    ends.sort_by(|p, q| p.0.total_cmp(&q.0));
    let mut rays = 0;
    for &(d, id, end, leaving) in ends.iter().take(MAX_TESTED) {
        let u = (end - x) / d;
        rays += 1;
        // Seen: nothing before it (the primitive itself meets the line only there).
        if world.occluded(x, u, d * (1.0 - 1e-6), None) {
            continue;
        }
        let side = leaving - u * W::S::dot(u, leaving);
        let len = W::S::length(side);
        if len.is_nan() || len <= 1e-9 {
            // Seen exactly end-on: the primitive is a point (2D) or a line (3D) there.
            return (d, rays);
        }
        let past = end + side * (PAST_END * d / len) - x;
        let t = W::S::length(past);
        rays += 1;
        let hit = world.closest_hit(x, past / t, 4.0 * t, Some(id));
        let (prim_j, len_j) = hit.map_or((None, f64::INFINITY), |h| (Some(h.prim), h.t));
        if sees_other(id, d, prim_j, len_j) {
            return (d, rays);
        }
    }
    (f64::INFINITY, rays)
}
