//! The BVH's f32 node boxes never cull a hit that the exact f64 test finds. The
//! primitives here are closed axis-aligned boxes tested exactly in f64, so a
//! primitive's bounds are the primitive itself: a ray that grazes a face, runs
//! along an edge or lies in a face's plane hits it, and only an outward-rounded,
//! conservatively traversed f32 box keeps that hit. Coordinates go from 1e-30 to
//! 1e12, where an f32 ulp (65,536 at 1e12) is far larger than the boxes, and the
//! BVH must answer as a brute-force scan, bit for bit, in 2D and 3D.

use volcache::core::rng::Sampler;
use volcache::core::space::{D2, D3};
use volcache::pipeline::bvh::{Accel, Geometry, Primitive};
use volcache::pipeline::dim::Dim;

/// A closed axis-aligned box, hit where the ray first touches it (t = 0 when the
/// origin is inside).
#[derive(Clone, Copy, Debug)]
struct AxisBox<S: Dim> {
    lo: S::Vec,
    hi: S::Vec,
}

impl<S: Dim> Primitive<S> for AxisBox<S> {
    type Leaf = Self;

    fn bounds(&self) -> (S::Vec, S::Vec) {
        (self.lo, self.hi)
    }

    fn leaf(&self) -> Self {
        *self
    }

    /// The exact slab test: a zero direction component keeps the ray inside the
    /// slab iff the origin is (faces included); otherwise f64 divisions.
    fn intersect_leaf(b: &Self, o: S::Vec, d: S::Vec, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
        let (mut enter, mut exit) = (0.0f64, f64::INFINITY);
        for a in 0..S::DIM {
            if d[a] == 0.0 {
                if o[a] < b.lo[a] || o[a] > b.hi[a] {
                    return None;
                }
                continue;
            }
            let (t0, t1) = ((b.lo[a] - o[a]) / d[a], (b.hi[a] - o[a]) / d[a]);
            enter = enter.max(t0.min(t1));
            exit = exit.min(t0.max(t1));
        }
        (enter <= exit && enter > t_min && enter < t_max).then_some((enter, 0.0, 0.0))
    }
}

fn vec<S: Dim>(mut f: impl FnMut(usize) -> f64) -> S::Vec {
    (0..S::DIM).fold(S::zero(), |v, a| v + S::axis(a) * f(a))
}

/// The closest hit by testing every box: (t, index), the lowest index on ties.
fn brute_force<S: Dim>(boxes: &[AxisBox<S>], o: S::Vec, d: S::Vec, t_min: f64) -> Option<(f64, u32)> {
    let mut best: Option<(f64, u32)> = None;
    for (i, b) in boxes.iter().enumerate() {
        if let Some((t, _, _)) = b.intersect(o, d, t_min, f64::INFINITY)
            && best.is_none_or(|(bt, _)| t < bt)
        {
            best = Some((t, i as u32));
        }
    }
    best
}

/// At each scale, 300 small boxes with coordinates that f32 cannot represent, and
/// rays that touch them exactly: along an edge or in a face's plane (direction
/// components 0), or aimed at a corner from afar (so the f64 test sits on the
/// boundary between hit and miss). Returns how many rays touched their target box.
fn grazing_rays_keep_their_hits<S: Dim>() -> usize {
    let mut touched = 0;
    for (k, scale) in [1e-30, 1e-6, 1.0, 1e6, 1e12].into_iter().enumerate() {
        let mut s = Sampler::new(21, (S::DIM * 10 + k) as u64);
        let boxes: Vec<AxisBox<S>> = (0..300)
            .map(|_| {
                let lo = vec::<S>(|_| scale * (1.0 + 0.3 * s.next_f64()) * if s.next_f64() < 0.5 { -1.0 } else { 1.0 });
                // Sizes from 1e-9 to 1e-3 of the scale: at 1e12 many lie within one f32 ulp.
                let size = vec::<S>(|_| scale * 10f64.powf(-9.0 + 6.0 * s.next_f64()));
                AxisBox { lo, hi: lo + size }
            })
            .collect();
        let bvh = Geometry::<S, AxisBox<S>>::with_accel(boxes.clone(), Accel::Bvh);
        let t_min = -1.0; // origins on a face still count (t = 0)
        for r in 0..3000 {
            let b = boxes[r % boxes.len()];
            // A point on the box's boundary: each coordinate a bound, or inside.
            let corner = vec::<S>(|a| match (r / 7 + a) % 3 {
                0 => b.lo[a],
                1 => b.hi[a],
                _ => b.lo[a] + 0.5 * (b.hi[a] - b.lo[a]),
            });
            let (o, d) = if r % 2 == 0 {
                // Along one axis from far away, in the planes of the other bounds.
                let axis = r / 2 % S::DIM;
                let sign = if r % 4 == 0 { 1.0 } else { -1.0 };
                let o = vec::<S>(|a| {
                    if a == axis {
                        corner[a] - sign * 2.0 * scale
                    } else {
                        corner[a]
                    }
                });
                (o, S::axis(axis) * sign)
            } else {
                // Towards the corner from a random point, 1e-10 to 1 of the scale
                // away: near ones meet the box before f32 resolves it.
                let far = scale * 10f64.powf(-10.0 + 10.0 * s.next_f64());
                let o = vec::<S>(|a| corner[a] + far * (s.next_f64() - 0.5) * 4.0);
                let d = corner - o;
                (o, d / S::length(d))
            };
            let want = brute_force(&boxes, o, d, t_min);
            touched += b.intersect(o, d, t_min, f64::INFINITY).is_some() as usize;
            let got = bvh.closest_hit(o, d, t_min, f64::INFINITY, None).map(|h| (h.0, h.1));
            assert_eq!(got, want, "scale {scale}, ray {r}: o {o:?} d {d:?}");
            assert_eq!(
                bvh.occluded(o, d, t_min, f64::INFINITY, None),
                want.is_some(),
                "scale {scale}, ray {r}"
            );
        }
    }
    touched
}

#[test]
fn grazing_rays_keep_their_hits_2d() {
    let touched = grazing_rays_keep_their_hits::<D2>();
    assert!(
        touched > 5000,
        "only {touched} rays touched their box: the test would be toothless"
    );
}

#[test]
fn grazing_rays_keep_their_hits_3d() {
    let touched = grazing_rays_keep_their_hits::<D3>();
    assert!(
        touched > 5000,
        "only {touched} rays touched their box: the test would be toothless"
    );
}
