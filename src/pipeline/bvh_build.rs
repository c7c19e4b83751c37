//! The BVH's build: a binary tree over primitive boxes by the binned surface-area
//! heuristic (16 bins per axis, every axis binned in one pass over the primitives;
//! in 2D the "area" is the half perimeter), which `bvh_wide` then collapses into
//! 4-wide nodes. Deterministic: the same boxes give the same tree.

use super::dim::Dim;

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

    #[inline]
    pub fn grow(&mut self, p: S::Vec) {
        self.min = S::min(self.min, p);
        self.max = S::max(self.max, p);
    }

    #[inline]
    pub fn union(self, o: &Self) -> Self {
        Aabb {
            min: S::min(self.min, o.min),
            max: S::max(self.max, o.max),
        }
    }

    /// The surface-area heuristic's measure: half the boundary (0 when empty).
    pub fn half_boundary(&self) -> f64 {
        S::half_boundary(S::max(self.max - self.min, S::zero()))
    }
}

/// A box in f32 lanes (x, y, z, unused), rounded outwards from f64: the build works
/// on these (four lanes at a time, half the bytes of f64), and the wide nodes store
/// them as they are.
#[derive(Clone, Copy, Debug)]
pub struct Box4 {
    pub lo: [f32; 4],
    pub hi: [f32; 4],
}

pub fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x { f.next_down() } else { f }
}

pub fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

impl Box4 {
    const EMPTY: Box4 = Box4 {
        lo: [f32::INFINITY; 4],
        hi: [f32::NEG_INFINITY; 4],
    };

    /// The f32 box containing `b` (unused lanes 0).
    pub fn outward<S: Dim>(b: &Aabb<S>) -> Box4 {
        let mut r = Box4 {
            lo: [0.0; 4],
            hi: [0.0; 4],
        };
        for a in 0..S::DIM {
            (r.lo[a], r.hi[a]) = (round_down(b.min[a]), round_up(b.max[a]));
        }
        r
    }

    #[inline]
    fn union(&self, o: &Box4) -> Box4 {
        // Written as comparisons so that they compile to packed min and max.
        Box4 {
            lo: std::array::from_fn(|a| if o.lo[a] < self.lo[a] { o.lo[a] } else { self.lo[a] }),
            hi: std::array::from_fn(|a| if o.hi[a] > self.hi[a] { o.hi[a] } else { self.hi[a] }),
        }
    }

    #[inline]
    fn grow(&mut self, p: &[f32; 4]) {
        *self = self.union(&Box4 { lo: *p, hi: *p });
    }

    /// The surface-area heuristic's measure (as [`Dim::half_boundary`]): half the
    /// perimeter in 2D, half the area in 3D; 0 when empty.
    pub fn half_boundary<S: Dim>(&self) -> f64 {
        let e: [f64; 3] = std::array::from_fn(|a| (self.hi[a] as f64 - self.lo[a] as f64).max(0.0));
        if S::DIM == 2 {
            e[0] + e[1]
        } else {
            e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
        }
    }
}

/// A node of the binary tree: a leaf holds `order[start..start + count]`.
#[derive(Clone, Copy, Debug)]
pub enum BinNode {
    Leaf { start: u32, count: u32 },
    Inner { left: u32, right: u32 },
}

/// The binary tree: nodes with their bounds (root first) and the primitives in
/// leaf order.
pub struct BinaryTree {
    pub nodes: Vec<(Box4, BinNode)>,
    pub order: Vec<u32>,
}

/// Leaves hold at most this many primitives; a SAH split is forced above
/// `FORCE_SPLIT` primitives even when a leaf looks cheaper.
pub const MAX_LEAF: usize = 4;
const FORCE_SPLIT: usize = 4 * MAX_LEAF;
const BINS: usize = 16;

pub fn build<S: Dim>(boxes: &[Aabb<S>]) -> BinaryTree {
    let mut tree = BinaryTree {
        nodes: Vec::with_capacity(2 * boxes.len() / MAX_LEAF + 1),
        order: Vec::new(),
    };
    // The build partitions these in place: each carries its box and index, so every
    // pass reads memory in order (an index array into the boxes read it at random
    // and took a third longer on the benchmark sphere).
    let mut refs: Vec<Ref> = boxes
        .iter()
        .enumerate()
        .map(|(i, b)| Ref {
            b: Box4::outward(b),
            index: i as u32,
        })
        .collect();
    if !refs.is_empty() {
        let bounds = refs.iter().fold(Box4::EMPTY, |a, r| a.union(&r.b));
        split_range::<S>(&mut tree, &mut refs, 0, bounds);
    }
    tree.order = refs.iter().map(|r| r.index).collect();
    tree
}

/// A primitive during the build: its outward f32 box and its index.
#[derive(Clone, Copy, Debug)]
struct Ref {
    b: Box4,
    index: u32,
}

impl Ref {
    /// Twice the box's centre (the bins need only an affine image of the centre).
    #[inline]
    fn centre2(&self) -> [f32; 4] {
        std::array::from_fn(|a| self.b.lo[a] + self.b.hi[a])
    }
}

/// Bins of one axis: bounds and count per bin.
type Bins = [(Box4, u32); BINS];

/// Build the subtree of `refs` (whose boxes' union is `bounds`, and which start at
/// `offset` in leaf order); returns its node index.
fn split_range<S: Dim>(tree: &mut BinaryTree, refs: &mut [Ref], offset: usize, bounds: Box4) -> u32 {
    let node = tree.nodes.len() as u32;
    let n = refs.len();
    let leaf = BinNode::Leaf {
        start: offset as u32,
        count: n as u32,
    };
    tree.nodes.push((bounds, leaf));
    if n <= MAX_LEAF {
        return node;
    }
    let mut cb = Box4::EMPTY;
    refs.iter().for_each(|r| cb.grow(&r.centre2()));
    // Bin index per axis: k = (c − lo)·scale, the scale precomputed (no division
    // per primitive); a flat axis gets scale 0 (everything in bin 0, never split).
    let scale: [f32; 4] = std::array::from_fn(|a| {
        let extent = cb.hi[a] - cb.lo[a];
        if a < S::DIM && extent > 0.0 {
            BINS as f32 * 0.999_99 / extent
        } else {
            0.0
        }
    });
    let bin = |a: usize, c: &[f32; 4]| (((c[a] - cb.lo[a]) * scale[a]) as usize).min(BINS - 1);
    let mut bins: [Bins; 3] = [[(Box4::EMPTY, 0); BINS]; 3];
    for r in refs.iter() {
        let c = r.centre2();
        for (a, axis_bins) in bins.iter_mut().enumerate().take(S::DIM) {
            let k = bin(a, &c);
            axis_bins[k].0 = axis_bins[k].0.union(&r.b);
            axis_bins[k].1 += 1;
        }
    }
    // Best split over the axes: (cost, axis, last bin on the left, left and right bounds).
    let mut best: Option<(f64, usize, usize, Box4, Box4)> = None;
    for (a, axis_bins) in bins.iter().enumerate().take(S::DIM) {
        if scale[a] == 0.0 {
            continue;
        }
        let mut right = [(Box4::EMPTY, 0u32); BINS];
        let mut acc = (Box4::EMPTY, 0u32);
        for k in (1..BINS).rev() {
            acc = (acc.0.union(&axis_bins[k].0), acc.1 + axis_bins[k].1);
            right[k] = acc;
        }
        let mut left = (Box4::EMPTY, 0u32);
        for k in 0..BINS - 1 {
            left = (left.0.union(&axis_bins[k].0), left.1 + axis_bins[k].1);
            let r = right[k + 1];
            if left.1 > 0 && r.1 > 0 {
                let cost = left.0.half_boundary::<S>() * left.1 as f64 + r.0.half_boundary::<S>() * r.1 as f64;
                if best.as_ref().is_none_or(|b| cost < b.0) {
                    best = Some((cost, a, k, left.0, r.0));
                }
            }
        }
    }
    let Some((cost, axis, k, left_bounds, right_bounds)) = best else {
        return node; // all centres coincide: no split possible
    };
    if cost >= bounds.half_boundary::<S>() * n as f64 && n <= FORCE_SPLIT {
        return node; // a leaf is cheaper
    }
    let mut mid = 0;
    for j in 0..n {
        if bin(axis, &refs[j].centre2()) <= k {
            refs.swap(j, mid);
            mid += 1;
        }
    }
    let (lo, hi) = refs.split_at_mut(mid);
    let left = split_range::<S>(tree, lo, offset, left_bounds);
    let right = split_range::<S>(tree, hi, offset + mid, right_bounds);
    tree.nodes[node as usize].1 = BinNode::Inner { left, right };
    node
}
