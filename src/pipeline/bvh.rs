//! Ray casting over primitives (segments in 2D, triangles in 3D) in f64: a bounding
//! volume hierarchy built with a binned surface-area heuristic (16 bins per axis,
//! leaves of at most 4 primitives; in 2D the "area" is the half perimeter), or a
//! flat list for scenes too small to pay for a tree.
//!
//! Why our own: the well-kept Rust BVH crates (obvhs, bvh) work in f32, while the
//! renderer, the derivative core and the proxy geometry are f64; converting every ray
//! and hit would lose the precision the derivative code relies on. Answers equal a
//! brute-force scan on random rays (tests here and in `tests/`).

use super::dim::Dim;
use smallvec::SmallVec;

/// Something a ray can hit.
pub trait Primitive<S: Dim>: Send + Sync {
    /// Corners of the primitive's bounding box.
    fn bounds(&self) -> (S::Vec, S::Vec);
    /// Ray o + t·d against the primitive: (t, u, v) with t in (t_min, t_max).
    fn intersect(&self, o: S::Vec, d: S::Vec, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)>;
}

#[derive(Clone, Copy, Debug)]
pub struct Aabb<S: Dim> {
    pub min: S::Vec,
    pub max: S::Vec,
}

impl<S: Dim> Aabb<S> {
    pub fn empty() -> Self {
        Aabb {
            min: S::splat(f64::INFINITY),
            max: S::splat(f64::NEG_INFINITY),
        }
    }

    pub fn grow(&mut self, p: S::Vec) {
        self.min = S::min(self.min, p);
        self.max = S::max(self.max, p);
    }

    pub fn union(self, o: &Self) -> Self {
        Aabb {
            min: S::min(self.min, o.min),
            max: S::max(self.max, o.max),
        }
    }

    fn half_boundary(&self) -> f64 {
        S::half_boundary(S::max(self.max - self.min, S::zero()))
    }

    /// Slab test: the entry distance when the ray overlaps the box within [0, t_max].
    #[inline]
    fn hit(&self, o: S::Vec, inv_d: S::Vec, t_max: f64) -> Option<f64> {
        let t0 = S::mul(self.min - o, inv_d);
        let t1 = S::mul(self.max - o, inv_d);
        let (lo, hi) = (S::min(t0, t1), S::max(t0, t1));
        let enter = S::max_element(lo).max(0.0);
        // NaN (0·∞) arises only when the ray lies in a slab plane: count as overlap.
        if S::any_nan(lo) || S::any_nan(hi) || enter <= S::min_element(hi).min(t_max) * (1.0 + 1e-12) {
            Some(enter)
        } else {
            None
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Node<S: Dim> {
    bounds: Aabb<S>,
    /// Leaf: first index into `order`; inner: index of the right child (left is next).
    start_or_right: u32,
    /// Leaf: number of primitives (> 0); inner: 0.
    count: u32,
}

#[derive(Clone, Debug)]
struct Bvh<S: Dim> {
    nodes: Vec<Node<S>>,
    order: Vec<u32>,
}

const MAX_LEAF: usize = 4;
const BINS: usize = 16;

/// Below this many primitives the flat list is faster than the tree
/// (`volcache bench flatland` measures the crossover on random segment soups).
pub const BVH_THRESHOLD: usize = 6;

/// How ray queries are answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accel {
    /// Test every primitive (fine for a few).
    Linear,
    Bvh,
}

impl<S: Dim> Bvh<S> {
    fn build(boxes: &[Aabb<S>]) -> Self {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * boxes.len()),
            order: (0..boxes.len() as u32).collect(),
        };
        if !boxes.is_empty() {
            let centres: Vec<S::Vec> = boxes.iter().map(|b| (b.min + b.max) * 0.5).collect();
            bvh.split(boxes, &centres, 0, boxes.len());
        }
        bvh
    }

    /// Build the subtree of `order[start..end]`; returns its node index.
    fn split(&mut self, boxes: &[Aabb<S>], centres: &[S::Vec], start: usize, end: usize) -> usize {
        let items = &self.order[start..end];
        let bounds = items.iter().fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
        let node = self.nodes.len();
        self.nodes.push(Node {
            bounds,
            start_or_right: start as u32,
            count: (end - start) as u32,
        });
        if end - start <= MAX_LEAF {
            return node;
        }
        let mut cb = Aabb::<S>::empty();
        items.iter().for_each(|&i| cb.grow(centres[i as usize]));
        let bin = |axis: usize, i: u32| {
            let (lo, hi) = (cb.min[axis], cb.max[axis]);
            (((centres[i as usize][axis] - lo) / (hi - lo) * BINS as f64) as usize).min(BINS - 1)
        };
        // Best binned SAH split over the axes: (cost, axis, last bin on the left).
        let mut best = (f64::INFINITY, 0, 0);
        for axis in 0..S::DIM {
            if cb.max[axis] <= cb.min[axis] {
                continue;
            }
            let mut bins = [(Aabb::<S>::empty(), 0usize); BINS];
            for &i in items {
                let k = bin(axis, i);
                bins[k].0 = bins[k].0.union(&boxes[i as usize]);
                bins[k].1 += 1;
            }
            let mut right = [(0.0, 0usize); BINS];
            let (mut acc, mut n) = (Aabb::<S>::empty(), 0);
            for k in (1..BINS).rev() {
                acc = acc.union(&bins[k].0);
                n += bins[k].1;
                right[k] = (acc.half_boundary(), n);
            }
            let (mut acc, mut n) = (Aabb::<S>::empty(), 0);
            for k in 0..BINS - 1 {
                acc = acc.union(&bins[k].0);
                n += bins[k].1;
                let (ra, rn) = right[k + 1];
                if n > 0 && rn > 0 {
                    let cost = acc.half_boundary() * n as f64 + ra * rn as f64;
                    if cost < best.0 {
                        best = (cost, axis, k);
                    }
                }
            }
        }
        let leaf_cost = bounds.half_boundary() * (end - start) as f64;
        if best.0.is_infinite() || (best.0 >= leaf_cost && end - start <= 4 * MAX_LEAF) {
            return node; // all centres coincide, or a split costs more than a leaf
        }
        let (axis, k) = (best.1, best.2);
        let slice = &mut self.order[start..end];
        let mut mid = 0;
        for j in 0..slice.len() {
            if bin(axis, slice[j]) <= k {
                slice.swap(j, mid);
                mid += 1;
            }
        }
        let mid = start + mid;
        self.split(boxes, centres, start, mid);
        let right = self.split(boxes, centres, mid, end);
        self.nodes[node].start_or_right = right as u32;
        self.nodes[node].count = 0;
        node
    }

    /// Visit the primitives of the leaves the ray overlaps, nearer boxes first;
    /// `visit` may shrink `t_far` and returns true to stop.
    #[inline]
    fn traverse(&self, o: S::Vec, d: S::Vec, t_far: &mut f64, mut visit: impl FnMut(u32, &mut f64) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        let inv_d = S::recip(d);
        let Some(t_root) = self.nodes[0].bounds.hit(o, inv_d, *t_far) else {
            return;
        };
        // Nodes to visit with the distance at which the ray enters them (tested when
        // pushed; skipped if a hit found since is nearer). Depth is logarithmic for
        // sane inputs; the stack spills to the heap otherwise.
        let mut stack: SmallVec<[(u32, f64); 64]> = SmallVec::new();
        stack.push((0, t_root));
        while let Some((idx, t_enter)) = stack.pop() {
            if t_enter > *t_far * (1.0 + 1e-12) {
                continue;
            }
            let n = &self.nodes[idx as usize];
            if n.count > 0 {
                let s = n.start_or_right as usize;
                for &i in &self.order[s..s + n.count as usize] {
                    if visit(i, t_far) {
                        return;
                    }
                }
            } else {
                let (left, right) = (idx + 1, n.start_or_right);
                let tl = self.nodes[left as usize].bounds.hit(o, inv_d, *t_far);
                let tr = self.nodes[right as usize].bounds.hit(o, inv_d, *t_far);
                // Push the farther child first so that the nearer one is visited first.
                match (tl, tr) {
                    (Some(a), Some(b)) => {
                        let (near, far) = if a <= b {
                            ((left, a), (right, b))
                        } else {
                            ((right, b), (left, a))
                        };
                        stack.push(far);
                        stack.push(near);
                    }
                    (Some(a), None) => stack.push((left, a)),
                    (None, Some(b)) => stack.push((right, b)),
                    (None, None) => {}
                }
            }
        }
    }
}

/// Primitives with their acceleration structure.
#[derive(Clone, Debug)]
pub struct Geometry<S: Dim, P> {
    pub prims: Vec<P>,
    bvh: Bvh<S>,
    accel: Accel,
}

impl<S: Dim, P: Primitive<S>> Geometry<S, P> {
    /// A BVH above [`BVH_THRESHOLD`] primitives, a flat list below.
    pub fn new(prims: Vec<P>) -> Self {
        let accel = if prims.len() > BVH_THRESHOLD {
            Accel::Bvh
        } else {
            Accel::Linear
        };
        Self::with_accel(prims, accel)
    }

    pub fn with_accel(prims: Vec<P>, accel: Accel) -> Self {
        let boxes: Vec<Aabb<S>> = prims
            .iter()
            .map(|p| {
                let (min, max) = p.bounds();
                Aabb { min, max }
            })
            .collect();
        let bvh = match accel {
            Accel::Bvh => Bvh::build(&boxes),
            Accel::Linear => Bvh {
                nodes: Vec::new(),
                order: Vec::new(),
            },
        };
        Geometry { prims, bvh, accel }
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

    /// Visit candidates along the ray: every primitive (flat list) or the BVH's.
    #[inline]
    fn visit(&self, o: S::Vec, d: S::Vec, t_far: &mut f64, mut f: impl FnMut(u32, &mut f64) -> bool) {
        match self.accel {
            Accel::Linear => {
                for i in 0..self.prims.len() as u32 {
                    if f(i, t_far) {
                        return;
                    }
                }
            }
            Accel::Bvh => self.bvh.traverse(o, d, t_far, f),
        }
    }

    /// Closest intersection with t in (t_min, t_max), ignoring primitive `skip`:
    /// (t, primitive, u, v).
    pub fn closest_hit(
        &self,
        o: S::Vec,
        d: S::Vec,
        t_min: f64,
        t_max: f64,
        skip: Option<u32>,
    ) -> Option<(f64, u32, f64, f64)> {
        let mut best = None;
        let mut t_far = t_max;
        self.visit(o, d, &mut t_far, |i, t_far| {
            if Some(i) != skip
                && let Some((t, u, v)) = self.prims[i as usize].intersect(o, d, t_min, *t_far)
            {
                *t_far = t;
                best = Some((t, i, u, v));
            }
            false
        });
        best
    }

    /// Is there an intersection with t in (t_min, t_max) other than `skip`?
    pub fn occluded(&self, o: S::Vec, d: S::Vec, t_min: f64, t_max: f64, skip: Option<u32>) -> bool {
        let mut found = false;
        let mut t_far = t_max;
        self.visit(o, d, &mut t_far, |i, t_far| {
            found = Some(i) != skip && self.prims[i as usize].intersect(o, d, t_min, *t_far).is_some();
            found
        });
        found
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
        fn bounds(&self) -> (S::Vec, S::Vec) {
            let r = S::splat(self.radius);
            (self.centre - r, self.centre + r)
        }

        fn intersect(&self, o: S::Vec, d: S::Vec, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
            let oc = o - self.centre;
            let b = S::dot(oc, d);
            let disc = b * b - (S::dot(oc, oc) - self.radius * self.radius);
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

    #[test]
    fn bvh_matches_brute_force_2d() {
        bvh_matches_brute_force::<D2>();
    }

    #[test]
    fn bvh_matches_brute_force_3d() {
        bvh_matches_brute_force::<D3>();
    }
}
