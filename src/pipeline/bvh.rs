//! Ray casting over primitives (segments in 2D, triangles in 3D) in f64: a bounding
//! volume hierarchy — a binned-SAH binary tree (`bvh_build`) collapsed into 4-wide
//! nodes with conservative f32 boxes (`bvh_wide`), primitives stored in leaf order
//! — or a flat list for scenes too small to pay for a tree.
//!
//! Why our own: the well-kept Rust BVH crates (obvhs, bvh) work in f32, while the
//! renderer, the derivative core and the proxy geometry are f64; converting every ray
//! and hit would lose the precision the derivative code relies on. Here only the
//! boxes are f32 (rounded outwards, so they never cull a hit); the primitives are
//! tested in f64, and answers equal a brute-force scan on random rays, the same
//! primitive on ties (tests here and in `tests/`).

use super::bvh_build;
pub use super::bvh_build::Aabb;
use super::bvh_wide::WideBvh;
use super::dim::Dim;
use rayon::prelude::*;
use std::hash::Hasher;

/// Something a ray can hit.
pub trait Primitive<S: Dim>: Send + Sync {
    /// What the BVH's leaves store of a primitive: only the fields its intersection
    /// reads (a triangle's 72 bytes of its 112), so a leaf spans fewer cache lines.
    /// Leaf loads were the largest cost of a traversal on the benchmark sphere.
    type Leaf: Send + Sync;
    /// Corners of the primitive's bounding box.
    fn bounds(&self) -> (S::Vec, S::Vec);
    fn leaf(&self) -> Self::Leaf;
    /// Ray o + t·d against the primitive: (t, u, v) with t in (t_min, t_max). The
    /// distance t must not depend on t_max (hits are compared across queries).
    fn intersect_leaf(leaf: &Self::Leaf, o: S::Vec, d: S::Vec, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)>;
    /// The same test on the primitive itself (the flat list and brute force).
    #[inline]
    fn intersect(&self, o: S::Vec, d: S::Vec, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
        Self::intersect_leaf(&self.leaf(), o, d, t_min, t_max)
    }
}

/// How ray queries are answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accel {
    /// Test every primitive (fine for a few).
    Linear,
    Bvh,
}

/// Primitives with their acceleration structure.
#[derive(Clone, Debug)]
pub struct Geometry<S: Dim, P: Primitive<S>> {
    /// The primitives in the caller's order: hits name them by this index.
    pub prims: Vec<P>,
    /// With the BVH: the primitives in leaf order, each with its index in `prims`
    /// (the leaves read them contiguously, without an index array).
    leaf_prims: Vec<(P::Leaf, u32)>,
    bvh: WideBvh,
    accel: Accel,
    dim: std::marker::PhantomData<S>,
}

impl<S: Dim, P: Primitive<S>> Geometry<S, P> {
    /// A BVH above [`Dim::FLAT_LIST_MAX`] primitives, a flat list up to it.
    pub fn new(prims: Vec<P>) -> Self {
        let accel = if prims.len() > S::FLAT_LIST_MAX {
            Accel::Bvh
        } else {
            Accel::Linear
        };
        Self::with_accel(prims, accel)
    }

    pub fn with_accel(prims: Vec<P>, accel: Accel) -> Self {
        let (leaf_prims, bvh) = match accel {
            Accel::Bvh => {
                let tree = bvh_build::build::<S>(prims.len(), |i| {
                    let (min, max) = prims[i].bounds();
                    Aabb { min, max }
                });
                let leaf_prims = tree
                    .order
                    .par_iter()
                    .with_min_len(4096)
                    .map(|&i| (prims[i as usize].leaf(), i))
                    .collect();
                (leaf_prims, WideBvh::collapse::<S>(&tree))
            }
            Accel::Linear => (Vec::new(), WideBvh::default()),
        };
        Geometry {
            prims,
            leaf_prims,
            bvh,
            accel,
            dim: std::marker::PhantomData,
        }
    }

    /// A hash of the acceleration structure's layout (every node's boxes, children
    /// and counts bit for bit, and the primitives' leaf order): equal whatever the
    /// thread count that built it.
    pub fn layout_hash(&self) -> u64 {
        let mut h = std::hash::DefaultHasher::new();
        self.bvh.hash_into(&mut h);
        self.leaf_prims.iter().for_each(|(_, i)| h.write_u32(*i));
        h.finish()
    }

    pub fn accel(&self) -> Accel {
        self.accel
    }

    pub fn len(&self) -> usize {
        self.prims.len()
    }

    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// Closest intersection with t in (t_min, t_max), ignoring primitive `skip`:
    /// (t, primitive, u, v). Of primitives hit at the same distance, the lowest
    /// index wins, so the answer is a brute-force scan's whatever the traversal
    /// order.
    pub fn closest_hit(
        &self,
        o: S::Vec,
        d: S::Vec,
        t_min: f64,
        t_max: f64,
        skip: Option<u32>,
    ) -> Option<(f64, u32, f64, f64)> {
        let mut best: Option<(f64, u32, f64, f64)> = None;
        let mut test = |p: &P::Leaf, i: u32, t_far: &mut f64| {
            if Some(i) == skip {
                return;
            }
            // A hit at the best distance itself may still win the tie.
            let limit = if best.is_some() { t_far.next_up() } else { *t_far };
            if let Some((t, u, v)) = P::intersect_leaf(p, o, d, t_min, limit)
                && best.is_none_or(|b| t < b.0 || i < b.1)
            {
                *t_far = t;
                best = Some((t, i, u, v));
            }
        };
        let mut t_far = t_max;
        match self.accel {
            Accel::Linear => {
                for (i, p) in self.prims.iter().enumerate() {
                    test(&p.leaf(), i as u32, &mut t_far);
                }
            }
            Accel::Bvh => self.bvh.traverse::<S, true>(o, d, &mut t_far, |first, count, t_far| {
                for (p, i) in &self.leaf_prims[first..first + count] {
                    test(p, *i, t_far);
                }
                false
            }),
        }
        best
    }

    /// Is there an intersection with t in (t_min, t_max) other than `skip`? Stops
    /// at the first found, in whatever order the tree meets them.
    pub fn occluded(&self, o: S::Vec, d: S::Vec, t_min: f64, t_max: f64, skip: Option<u32>) -> bool {
        let hits = |p: &P::Leaf, i: u32| Some(i) != skip && P::intersect_leaf(p, o, d, t_min, t_max).is_some();
        match self.accel {
            Accel::Linear => self.prims.iter().enumerate().any(|(i, p)| hits(&p.leaf(), i as u32)),
            Accel::Bvh => {
                let mut found = false;
                let mut t_far = t_max;
                self.bvh.traverse::<S, false>(o, d, &mut t_far, |first, count, _| {
                    found = self.leaf_prims[first..first + count].iter().any(|(p, i)| hits(p, *i));
                    found
                });
                found
            }
        }
    }
}

impl<S: Dim, P: Primitive<S>> Geometry<S, P> {
    /// The primitives whose bounding boxes overlap the box [`lo`, `hi`], into
    /// `out` (cleared first) in increasing index; false, with `out` incomplete,
    /// once there are more than `limit`. Every primitive that meets the box is
    /// listed (a superset: their boxes, not the primitives, are tested).
    pub fn prims_in_box(&self, lo: S::Vec, hi: S::Vec, limit: usize, out: &mut Vec<u32>) -> bool {
        out.clear();
        let overlaps = |p: &P| {
            let (a, b) = p.bounds();
            (0..S::DIM).all(|k| a[k] <= hi[k] && b[k] >= lo[k])
        };
        let complete = match self.accel {
            Accel::Linear => {
                for (i, p) in self.prims.iter().enumerate() {
                    if overlaps(p) {
                        out.push(i as u32);
                        if out.len() > limit {
                            return false;
                        }
                    }
                }
                true
            }
            Accel::Bvh => {
                let (mut lo32, mut hi32) = ([0.0f32; 3], [0.0f32; 3]);
                for k in 0..S::DIM {
                    lo32[k] = -bvh_build::round_up(-lo[k]);
                    hi32[k] = bvh_build::round_up(hi[k]);
                }
                let mut complete = true;
                self.bvh.overlapping::<S>(lo32, hi32, |first, count| {
                    for &(_, i) in &self.leaf_prims[first..first + count] {
                        if overlaps(&self.prims[i as usize]) {
                            out.push(i);
                        }
                    }
                    complete = out.len() <= limit;
                    !complete
                });
                complete
            }
        };
        out.sort_unstable();
        complete
    }

    /// [`Geometry::occluded`] testing only the primitives `ids` (e.g. those
    /// [`Geometry::prims_in_box`] lists around a segment): the same answer as
    /// the whole scene's whenever `ids` holds every primitive near the ray's span.
    pub fn occluded_among(&self, ids: &[u32], o: S::Vec, d: S::Vec, t_min: f64, t_max: f64) -> bool {
        ids.iter()
            .any(|&i| self.prims[i as usize].intersect(o, d, t_min, t_max).is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Sampler;
    use crate::core::space::{D2, D3};

    /// A test primitive in any dimension: a ball (disc in 2D), hit from outside or
    /// from inside.
    #[derive(Clone, Copy, Debug)]
    struct Ball<S: Dim> {
        centre: S::Vec,
        radius: f64,
    }

    impl<S: Dim> Primitive<S> for Ball<S> {
        type Leaf = Self;

        fn bounds(&self) -> (S::Vec, S::Vec) {
            let r = S::splat(self.radius);
            (self.centre - r, self.centre + r)
        }

        fn leaf(&self) -> Self {
            *self
        }

        fn intersect_leaf(ball: &Self, o: S::Vec, d: S::Vec, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
            let oc = o - ball.centre;
            let b = S::dot(oc, d);
            let disc = b * b - (S::dot(oc, oc) - ball.radius * ball.radius);
            if disc < 0.0 {
                return None;
            }
            let q = disc.sqrt();
            [-b - q, -b + q]
                .into_iter()
                .find(|&t| t > t_min && t < t_max)
                .map(|t| (t, 0.0, 0.0))
        }
    }

    fn random_in<S: Dim>(s: &mut Sampler, lo: f64, hi: f64) -> S::Vec {
        (0..S::DIM).fold(S::zero(), |v, i| v + S::axis(i) * (lo + (hi - lo) * s.next_f64()))
    }

    /// The closest of all primitives but `skip`, testing every one.
    fn brute_force<S: Dim>(
        balls: &[Ball<S>],
        o: S::Vec,
        d: S::Vec,
        t_max: f64,
        skip: Option<u32>,
    ) -> Option<(f64, u32)> {
        let mut best: Option<(f64, u32)> = None;
        for (i, b) in balls.iter().enumerate().filter(|(i, _)| Some(*i as u32) != skip) {
            if let Some((t, _, _)) = b.intersect(o, d, T_MIN, t_max)
                && best.is_none_or(|(bt, _)| t < bt)
            {
                best = Some((t, i as u32));
            }
        }
        best
    }

    const T_MIN: f64 = 1e-9;

    /// BVH and flat list answer as a brute-force scan (the same distance bit for bit,
    /// the same primitive unless two tie) for closest hits, occlusion and a skipped
    /// primitive, on random rays through a random soup of balls, on rays along the
    /// axes (zero direction components: the slab test's 0·∞), and on a soup whose
    /// centres all coincide (no split possible).
    fn bvh_matches_brute_force<S: Dim>() {
        let mut s = Sampler::new(5, S::DIM as u64);
        let soup: Vec<Ball<S>> = (0..1500)
            .map(|_| Ball {
                centre: random_in::<S>(&mut s, 0.0, 10.0),
                radius: 0.02 + 0.3 * s.next_f64(),
            })
            .collect();
        let stack: Vec<Ball<S>> = (0..40)
            .map(|k| Ball {
                centre: S::splat(5.0),
                radius: 0.1 + 0.05 * k as f64,
            })
            .collect();
        for (name, balls) in [("soup", soup), ("concentric", stack)] {
            let bvh = Geometry::<S, Ball<S>>::with_accel(balls.clone(), Accel::Bvh);
            let flat = Geometry::<S, Ball<S>>::with_accel(balls.clone(), Accel::Linear);
            let mut hits = 0;
            for k in 0..6000 {
                let mut o = random_in::<S>(&mut s, -1.0, 11.0);
                let d = if k % 5 == 0 {
                    // Along an axis, in the planes of a ball's bounding box: the slab
                    // test meets 0·∞ and the ray grazes the ball.
                    let (axis, b) = (k / 5 % S::DIM, balls[k % balls.len()]);
                    o = (0..S::DIM).fold(S::zero(), |v, i| {
                        v + S::axis(i) * if i == axis { o[i] } else { b.centre[i] + b.radius }
                    });
                    S::axis(axis) * if k % 2 == 0 { 1.0 } else { -1.0 }
                } else {
                    let v = random_in::<S>(&mut s, -1.0, 1.0);
                    v / S::length(v)
                };
                let t_max = if k % 3 == 0 { 8.0 * s.next_f64() } else { f64::INFINITY };
                let want = brute_force(&balls, o, d, t_max, None);
                for g in [&bvh, &flat] {
                    let got = g.closest_hit(o, d, T_MIN, t_max, None).map(|h| (h.0, h.1));
                    assert_eq!(got, want, "{name}, ray {k}");
                    assert_eq!(g.occluded(o, d, T_MIN, t_max, None), want.is_some(), "{name}, ray {k}");
                }
                let Some((_, first)) = want else { continue };
                hits += 1;
                let next = brute_force(&balls, o, d, t_max, Some(first));
                for g in [&bvh, &flat] {
                    let got = g.closest_hit(o, d, T_MIN, t_max, Some(first)).map(|h| (h.0, h.1));
                    assert_eq!(got, next, "{name}, ray {k} skipping {first}");
                    assert_eq!(g.occluded(o, d, T_MIN, t_max, Some(first)), next.is_some());
                }
            }
            assert!(hits > 500, "{name}: only {hits} rays hit: the test would be toothless");
        }
    }

    /// The tree and the flat list list the primitives whose boxes overlap a query
    /// box exactly as a scan of every box does (boxes from a point to a third of
    /// the soup, touching ones included), and report an overflow of the limit
    /// exactly when the scan finds more.
    fn boxes_match_brute_force<S: Dim>() {
        let mut s = Sampler::new(6, S::DIM as u64);
        let soup: Vec<Ball<S>> = (0..1500)
            .map(|_| Ball {
                centre: random_in::<S>(&mut s, 0.0, 10.0),
                radius: 0.02 + 0.3 * s.next_f64(),
            })
            .collect();
        let tree = Geometry::with_accel(soup.clone(), Accel::Bvh);
        let flat = Geometry::with_accel(soup.clone(), Accel::Linear);
        let (mut out, mut sizes) = (Vec::new(), Vec::new());
        for q in 0..600 {
            let c = random_in::<S>(&mut s, -1.0, 11.0);
            let h = random_in::<S>(&mut s, 0.0, if q % 3 == 0 { 0.0 } else { 3.0 });
            let (lo, hi) = (c - h, c + h);
            let scan: Vec<u32> = (0..soup.len() as u32)
                .filter(|&i| {
                    let (a, b) = soup[i as usize].bounds();
                    (0..S::DIM).all(|k| a[k] <= hi[k] && b[k] >= lo[k])
                })
                .collect();
            sizes.push(scan.len());
            for g in [&tree, &flat] {
                assert!(g.prims_in_box(lo, hi, usize::MAX, &mut out));
                assert_eq!(out, scan);
                let limit = 8;
                assert_eq!(g.prims_in_box(lo, hi, limit, &mut out), scan.len() <= limit);
            }
        }
        // Discriminating: empty, few and many answers all occur.
        assert!(sizes.iter().filter(|&&n| n == 0).count() > 50, "{sizes:?}");
        assert!(
            sizes.iter().filter(|&&n| (1..=8).contains(&n)).count() > 50,
            "{sizes:?}"
        );
        assert!(sizes.iter().filter(|&&n| n > 8).count() > 50, "{sizes:?}");
    }

    #[test]
    fn boxes_match_brute_force_2d() {
        boxes_match_brute_force::<D2>();
    }

    #[test]
    fn boxes_match_brute_force_3d() {
        boxes_match_brute_force::<D3>();
    }

    #[test]
    fn bvh_matches_brute_force_2d() {
        bvh_matches_brute_force::<D2>();
    }

    #[test]
    fn bvh_matches_brute_force_3d() {
        bvh_matches_brute_force::<D3>();
    }
}
