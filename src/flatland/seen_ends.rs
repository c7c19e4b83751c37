//! The nearest segment end a point sees as a silhouette, found from the geometry
//! ([`crate::pipeline::world::World::nearest_seen_end`] in 2D).
//!
//! Why: a probe finds the ends of surfaces between its rays, and a segment seen
//! nearly edge-on subtends less than one ray spacing. A record 0.004 beside the
//! occluder's line, 0.15 from its end (`occluder.json` at 256², budget 4: ~400
//! directions, 0.016 rad apart; the occluder subtends 0.023 rad there) saw no end,
//! took the metric's radius (0.5) and reached across the end: errors above 0.1 on
//! both sides of it, 3× the image's error at 128², where the records happened to
//! sit farther from that line.

use super::scene::Scene;
use crate::pipeline::silhouette::sees_other;
use crate::pipeline::world::World;
use glam::DVec2;

/// Most segments listed around a point before the box is shrunk.
const MAX_LISTED: usize = 256;
/// Most candidate ends tested with rays (nearest first): beyond them the point
/// sees so many ends so near that the probe's rays find one.
const MAX_TESTED: usize = 16;
/// Sideways offset of the ray that looks past an end, relative to its distance.
const PAST_END: f64 = 1e-4;

/// Distance from `x` to the nearest segment end within `within` that `x` sees,
/// with nothing of the same depth just past it (a silhouette, as the probe's
/// [`sees_other`] tells one between neighbouring rays: a corner where two
/// segments meet and both are seen is not one), and the rays cast; +∞ when none.
pub fn nearest_seen_end(scene: &Scene, x: DVec2, within: f64) -> (f64, u64) {
    let mut r = within.min(scene.scale());
    if r.is_nan() || r <= 0.0 || !x.is_finite() {
        return (f64::INFINITY, 0);
    }
    let mut ids = Vec::new();
    // A crowded neighbourhood: the nearest ends lie in a smaller box.
    while !scene.geometry.prims_in_box(x - r, x + r, MAX_LISTED, &mut ids) {
        r *= 0.5;
        if r <= scene.t_min {
            return (f64::INFINITY, 0);
        }
    }
    let mut ends: Vec<(f64, u32, DVec2, DVec2)> = Vec::with_capacity(2 * ids.len());
    for &id in &ids {
        let seg = &scene.geometry.prims[id as usize];
        for (end, other) in [(seg.a, seg.b), (seg.b, seg.a)] {
            let d = (end - x).length();
            if d > scene.t_min && d < r {
                ends.push((d, id, end, other));
            }
        }
    }
    ends.sort_by(|p, q| p.0.total_cmp(&q.0));
    let mut rays = 0;
    for &(d, id, end, other) in ends.iter().take(MAX_TESTED) {
        let u = (end - x) / d;
        rays += 1;
        // Seen: nothing before it (the segment itself meets the line only there).
        if scene.occluded(x, u, d * (1.0 - 1e-6), None) {
            continue;
        }
        // Past it, away from its own segment: nothing else at its depth.
        let mut side = u.perp();
        if side.dot(other - end) > 0.0 {
            side = -side;
        }
        let past = end + side * (PAST_END * d) - x;
        let t = past.length();
        rays += 1;
        let hit = scene.closest_hit(x, past / t, 4.0 * t, Some(id));
        let (prim_j, len_j) = hit.map_or((None, f64::INFINITY), |h| (Some(h.prim), h.t));
        if sees_other(id, d, prim_j, len_j) {
            return (d, rays);
        }
    }
    (f64::INFINITY, rays)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(segments: &str) -> Scene {
        let json = format!(
            r#"{{"domain": {{"min": [-1, -1], "max": [1, 1]}}, "segments": [{segments}],
            "medium": {{"sigma_a": 0.1, "sigma_s": 0.9, "g": 0.0, "region": "everywhere"}},
            "render": {{"resolution": [8, 8], "spp": 1, "seed": 1}}}}"#
        );
        Scene::from_json(&json, "<seen_ends>").unwrap_or_else(|e| panic!("{e}"))
    }

    const BAR: &str = r#"{"name": "bar", "a": [-0.35, 0.25], "b": [0.35, 0.25], "reflectance": 0.5}"#;

    /// Beside the bar's line, however near (down to 1e-9), the nearer end is found
    /// exactly: seen edge-on it is still a silhouette.
    #[test]
    fn an_end_seen_edge_on_is_found_exactly() {
        let s = scene(BAR);
        for h in [1e-9, 1e-6, 1e-3, 0.004, 0.05] {
            for (x0, end) in [(-0.5, -0.35), (0.9, 0.35), (-0.36, -0.35)] {
                for side in [-1.0, 1.0] {
                    let x = DVec2::new(x0, 0.25 + side * h);
                    let exact = x.distance(DVec2::new(end, 0.25));
                    let (d, rays) = nearest_seen_end(&s, x, 10.0);
                    assert_eq!(d, exact, "{x:?}");
                    assert!(rays <= 2, "{rays}");
                }
            }
        }
    }

    /// Nothing nearer than `within` is reported, and an end hidden behind another
    /// segment is passed over for the next one seen.
    #[test]
    fn only_ends_within_reach_and_in_sight_count() {
        let s = scene(BAR);
        let x = DVec2::new(-0.5, 0.3);
        let exact = x.distance(DVec2::new(-0.35, 0.25));
        assert_eq!(nearest_seen_end(&s, x, exact * 0.99).0, f64::INFINITY);
        assert_eq!(nearest_seen_end(&s, x, exact * 1.01).0, exact);
        // A wall between x and the bar's left end; its own ends are farther.
        let wall = r#"{"name": "wall", "a": [-0.42, 0.0], "b": [-0.42, 0.5], "reflectance": 0.5}"#;
        let s = scene(&format!("{BAR}, {wall}"));
        let (d, _) = nearest_seen_end(&s, x, 10.0);
        let wall_end = x
            .distance(DVec2::new(-0.42, 0.5))
            .min(x.distance(DVec2::new(-0.42, 0.0)));
        assert_eq!(d, wall_end);
        assert!(d > exact);
    }

    /// Where two segments meet and x sees both, the corner is no silhouette (the
    /// probe's rays see the same depth on both sides of it); seen with one face
    /// only, it is.
    #[test]
    fn a_corner_seen_from_both_faces_is_no_silhouette() {
        let l = r#"{"name": "top", "a": [-0.3, 0.2], "b": [0.2, 0.2], "reflectance": 0.5},
                   {"name": "side", "a": [0.2, 0.2], "b": [0.2, -0.3], "reflectance": 0.5}"#;
        let s = scene(l);
        let corner = DVec2::new(0.2, 0.2);
        // Outside the corner, seeing the top and the side.
        let x = DVec2::new(0.3, 0.3);
        let (d, _) = nearest_seen_end(&s, x, 10.0);
        assert!(d > x.distance(corner) * 1.5, "{d}");
        assert_eq!(
            d,
            x.distance(DVec2::new(0.2, -0.3)).min(x.distance(DVec2::new(-0.3, 0.2)))
        );
        // Above the top, short of the side's line: the side is hidden, the corner ends the top.
        let x = DVec2::new(0.1, 0.5);
        assert_eq!(nearest_seen_end(&s, x, 10.0).0, x.distance(corner));
    }
}
