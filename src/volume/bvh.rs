//! A bounding volume hierarchy over triangles in f64, built with a binned
//! surface-area heuristic (16 bins per axis, leaves of at most 4 triangles).
//!
//! Why our own: the well-kept Rust BVH crates we found (obvhs, bvh) work in f32
//! (obvhs with glam `Vec3A`), while the whole renderer, the derivative core and the
//! proxy geometry are f64 (`DVec3`); converting every ray and hit would lose the
//! precision the derivative code relies on and cost a copy per query. The scenes are
//! small (boxes, quads, a low-poly mesh), so a compact binned-SAH BVH is enough; it
//! is checked against brute force in `tests/volume_bvh.rs`.

use super::mesh::{Hit, Triangle};
use glam::DVec3;
use smallvec::SmallVec;

#[derive(Clone, Copy, Debug)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn grow(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    fn of(t: &Triangle) -> Aabb {
        let mut b = Aabb::EMPTY;
        t.vertices().iter().for_each(|&p| b.grow(p));
        b
    }

    fn half_area(&self) -> f64 {
        let e = (self.max - self.min).max(DVec3::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// Slab test: does the ray overlap the box within [0, t_max]?
    #[inline]
    fn hit(&self, o: DVec3, inv_d: DVec3, t_max: f64) -> bool {
        let t0 = (self.min - o) * inv_d;
        let t1 = (self.max - o) * inv_d;
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        // NaN (0·∞) only when the ray lies in a slab plane: count as overlap.
        if lo.is_nan_mask().any() || hi.is_nan_mask().any() {
            return true;
        }
        let enter = lo.max_element().max(0.0);
        let exit = hi.min_element().min(t_max);
        enter <= exit * (1.0 + 1e-12)
    }
}

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first index into `order`; inner: index of the right child (left is next).
    start_or_right: u32,
    /// Leaf: number of triangles (> 0); inner: 0.
    count: u32,
}

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const MAX_LEAF: usize = 4;
const BINS: usize = 16;

impl Bvh {
    pub fn build(tris: &[Triangle]) -> Bvh {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * tris.len()),
            order: (0..tris.len() as u32).collect(),
        };
        if !tris.is_empty() {
            let boxes: Vec<Aabb> = tris.iter().map(Aabb::of).collect();
            let centres: Vec<DVec3> = boxes.iter().map(|b| 0.5 * (b.min + b.max)).collect();
            bvh.split(&boxes, &centres, 0, tris.len());
        }
        bvh
    }

    /// Build the subtree of `order[start..end]`; returns its node index.
    fn split(&mut self, boxes: &[Aabb], centres: &[DVec3], start: usize, end: usize) -> usize {
        let items = &self.order[start..end];
        let bounds = items.iter().fold(Aabb::EMPTY, |b, &i| b.union(&boxes[i as usize]));
        let node = self.nodes.len();
        self.nodes.push(Node {
            bounds,
            start_or_right: start as u32,
            count: (end - start) as u32,
        });
        if end - start <= MAX_LEAF {
            return node;
        }
        let mut cb = Aabb::EMPTY;
        items.iter().for_each(|&i| cb.grow(centres[i as usize]));
        // Best binned SAH split over the three axes: (cost, axis, bin).
        let mut best = (f64::INFINITY, 0, 0);
        for axis in [0usize, 1, 2] {
            let (lo, hi) = (cb.min[axis], cb.max[axis]);
            if hi <= lo {
                continue;
            }
            let mut bins = [(Aabb::EMPTY, 0usize); BINS];
            for &i in items {
                let k = (((centres[i as usize][axis] - lo) / (hi - lo) * BINS as f64) as usize).min(BINS - 1);
                bins[k].0 = bins[k].0.union(&boxes[i as usize]);
                bins[k].1 += 1;
            }
            let mut right = [(0.0, 0usize); BINS];
            let (mut acc, mut n) = (Aabb::EMPTY, 0);
            for k in (1..BINS).rev() {
                acc = acc.union(&bins[k].0);
                n += bins[k].1;
                right[k] = (acc.half_area(), n);
            }
            let (mut acc, mut n) = (Aabb::EMPTY, 0);
            for k in 0..BINS - 1 {
                acc = acc.union(&bins[k].0);
                n += bins[k].1;
                let (ra, rn) = right[k + 1];
                if n > 0 && rn > 0 {
                    let cost = acc.half_area() * n as f64 + ra * rn as f64;
                    if cost < best.0 {
                        best = (cost, axis, k);
                    }
                }
            }
        }
        let leaf_cost = bounds.half_area() * (end - start) as f64;
        if best.0.is_infinite() || (best.0 >= leaf_cost && end - start <= 4 * MAX_LEAF) {
            return node;
        }
        let (axis, k) = (best.1, best.2);
        let (lo, hi) = (cb.min[axis], cb.max[axis]);
        let in_left =
            |i: u32| (((centres[i as usize][axis] - lo) / (hi - lo) * BINS as f64) as usize).min(BINS - 1) <= k;
        let slice = &mut self.order[start..end];
        let mut mid = 0;
        for j in 0..slice.len() {
            if in_left(slice[j]) {
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

    /// Closest intersection with t in (t_min, t_max), ignoring triangle `skip`.
    pub fn closest_hit(
        &self,
        tris: &[Triangle],
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        skip: Option<u32>,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_far = t_max;
        self.traverse(o, d, &mut t_far, |i, t_far| {
            if Some(i) == skip {
                return false;
            }
            if let Some((t, u, v)) = tris[i as usize].intersect(o, d, t_min, *t_far) {
                *t_far = t;
                best = Some(Hit { t, tri: i, u, v });
            }
            false
        });
        best
    }

    /// Is there any intersection with t in (t_min, t_max) other than `skip`?
    pub fn occluded(&self, tris: &[Triangle], o: DVec3, d: DVec3, t_min: f64, t_max: f64, skip: Option<u32>) -> bool {
        let mut found = false;
        let mut t_far = t_max;
        self.traverse(o, d, &mut t_far, |i, t_far| {
            found = Some(i) != skip && tris[i as usize].intersect(o, d, t_min, *t_far).is_some();
            found
        });
        found
    }

    /// Visit the triangles of leaves the ray overlaps; `visit` may shrink `t_far` and
    /// returns true to stop.
    #[inline]
    fn traverse(&self, o: DVec3, d: DVec3, t_far: &mut f64, mut visit: impl FnMut(u32, &mut f64) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        let inv_d = d.recip();
        // A degenerate split sequence can be deep: the stack grows on the heap if needed.
        let mut stack: SmallVec<[u32; 64]> = SmallVec::new();
        stack.push(0);
        while let Some(idx) = stack.pop() {
            let n = &self.nodes[idx as usize];
            if !n.bounds.hit(o, inv_d, *t_far) {
                continue;
            }
            if n.count > 0 {
                let s = n.start_or_right as usize;
                for &i in &self.order[s..s + n.count as usize] {
                    if visit(i, t_far) {
                        return;
                    }
                }
            } else {
                stack.push(n.start_or_right);
                stack.push(idx + 1);
            }
        }
    }
}
