//! Segments and ray casting in flatland.
//!
//! Robustness: a ray spawned on a segment skips that segment (a straight segment
//! cannot be hit again by a ray leaving it), and endpoints are inclusive with a tiny
//! parametric tolerance so that rays through a vertex shared by two segments never
//! slip between them. Rays parallel to a segment (grazing) do not hit it.

use crate::core::color::Rgb;
use crate::core::space::D2;
use crate::pipeline::bvh::{Geometry, Primitive};
use glam::DVec2;

/// 2D cross product (z component of the 3D cross product).
#[inline]
pub fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// A diffuse segment. Its front side is to the left of a→b (`normal`).
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    pub a: DVec2,
    pub b: DVec2,
    /// Unit normal on the front (left) side.
    pub normal: DVec2,
    pub reflectance: Rgb,
    pub emission: Rgb,
    pub two_sided: bool,
}

impl Segment {
    pub fn new(a: DVec2, b: DVec2, reflectance: Rgb, emission: Rgb, two_sided: bool) -> Self {
        let normal = (b - a).perp().normalize_or_zero();
        Segment {
            a,
            b,
            normal,
            reflectance,
            emission,
            two_sided,
        }
    }

    pub fn length(&self) -> f64 {
        (self.b - self.a).length()
    }

    pub fn point_at(&self, u: f64) -> DVec2 {
        self.a + (self.b - self.a) * u
    }

    /// The normal on the side a point `p` (or a ray coming from `p`) sees, and
    /// whether that side is active (reflects and emits).
    #[inline]
    pub fn facing(&self, p: DVec2) -> (DVec2, bool) {
        if (p - self.a).dot(self.normal) >= 0.0 {
            (self.normal, true)
        } else {
            (-self.normal, self.two_sided)
        }
    }

    /// The normal seen by a ray travelling along `dir` that hits the segment,
    /// and whether that side is active.
    #[inline]
    pub fn facing_dir(&self, dir: DVec2) -> (DVec2, bool) {
        if dir.dot(self.normal) <= 0.0 {
            (self.normal, true)
        } else {
            (-self.normal, self.two_sided)
        }
    }

    pub fn is_emitter(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// Parametric tolerance making shared endpoints watertight.
const U_EPS: f64 = 1e-12;

/// Ray o + t·d against segment [a, b]: `Some((t, u))` with t in (t_min, t_max).
#[inline]
pub fn intersect_segment(o: DVec2, d: DVec2, a: DVec2, b: DVec2, t_min: f64, t_max: f64) -> Option<(f64, f64)> {
    let e = b - a;
    let denom = cross(d, e);
    // Parallel (grazing) rays: no hit. Scale-aware threshold, |denom| ≤ 1e-14·|d||e|,
    // squared: two square roots per test were a noticeable share of a 2D query.
    if denom * denom <= 1e-28 * d.length_squared() * e.length_squared() {
        return None;
    }
    let ao = a - o;
    // The end-point test first, without a division: most segments a query meets
    // are missed beside an end (u outside [0, 1]).
    let u_num = cross(ao, d);
    let (lo, hi) = (-U_EPS * denom, (1.0 + U_EPS) * denom);
    let inside = if denom > 0.0 {
        u_num >= lo && u_num <= hi
    } else {
        u_num <= lo && u_num >= hi
    };
    if !inside {
        return None;
    }
    let t = cross(ao, e) / denom;
    if !(t > t_min && t < t_max) {
        return None;
    }
    Some((t, (u_num / denom).clamp(0.0, 1.0)))
}

impl Primitive<D2> for Segment {
    /// The end points (the intersection reads nothing else).
    type Leaf = [DVec2; 2];

    fn bounds(&self) -> (DVec2, DVec2) {
        (self.a.min(self.b), self.a.max(self.b))
    }

    fn leaf(&self) -> [DVec2; 2] {
        [self.a, self.b]
    }

    #[inline]
    fn intersect_leaf(&[a, b]: &[DVec2; 2], o: DVec2, d: DVec2, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
        intersect_segment(o, d, a, b, t_min, t_max).map(|(t, u)| (t, u, 0.0))
    }
}

/// Segments with their acceleration structure (`pipeline::bvh`).
pub type SegmentSet = Geometry<D2, Segment>;

/// The end of segment `seg` that x sees strictly between the directions `d_in`
/// (which meets the segment) and `d_out` (a neighbouring ray that does not): where
/// the segment stops being visible. Used to put a proxy's silhouette vertex at the
/// segment's true end instead of at the last ray's hit (issue 12: a ray grazing a
/// surface hits it at r ≈ d/Δθ, and the gradient grew as 1/d).
pub fn segment_silhouette(seg: &Segment, x: DVec2, d_in: DVec2, d_out: DVec2) -> Option<DVec2> {
    let turn = cross(d_in, d_out);
    [seg.a, seg.b].into_iter().find(|&e| {
        let w = e - x;
        cross(d_in, w) * turn > 0.0 && cross(w, d_out) * turn > 0.0 && w.dot(d_in + d_out) > 0.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(a: (f64, f64), b: (f64, f64)) -> Segment {
        Segment::new(DVec2::new(a.0, a.1), DVec2::new(b.0, b.1), Rgb::ZERO, Rgb::ZERO, true)
    }

    #[test]
    fn hits_interior_and_misses_parallel() {
        let s = seg((0.0, -1.0), (0.0, 1.0));
        let (t, u) = intersect_segment(DVec2::new(-2.0, 0.0), DVec2::X, s.a, s.b, 0.0, f64::INFINITY).unwrap();
        assert!((t - 2.0).abs() < 1e-15 && (u - 0.5).abs() < 1e-15);
        assert!(intersect_segment(DVec2::new(-2.0, 0.0), DVec2::Y, s.a, s.b, 0.0, f64::INFINITY).is_none());
        // Grazing along the segment itself: no hit, no NaN.
        assert!(intersect_segment(DVec2::new(0.0, -3.0), DVec2::Y, s.a, s.b, 0.0, f64::INFINITY).is_none());
    }

    /// A ray through the shared vertex of a closed polygon never escapes.
    #[test]
    fn shared_vertices_are_watertight() {
        let pts = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        let segs: Vec<Segment> = (0..4).map(|i| seg(pts[i], pts[(i + 1) % 4])).collect();
        let set = SegmentSet::new(segs);
        for &(x, y) in &pts {
            let d = DVec2::new(x, y).normalize();
            assert!(set.closest_hit(DVec2::ZERO, d, 2e-10, f64::INFINITY, None).is_some());
        }
    }
}
