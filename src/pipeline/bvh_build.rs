//! The BVH's build: a binary tree over primitive boxes by the binned surface-area
//! heuristic (16 bins per axis, every axis binned in one pass over the primitives;
//! in 2D the "area" is the half perimeter), which `bvh_wide` then collapses into
//! 4-wide nodes. Parallel over rayon (large nodes bin in chunks, large subtrees are
//! tasks) and deterministic: the same boxes give the same tree whatever the thread
//! count.

use super::dim::Dim;
use rayon::prelude::*;

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
/// Nodes of at least `2·CHUNK` primitives bin (and find their centre bounds) in
/// chunks of `CHUNK` on rayon, merged in chunk order.
const CHUNK: usize = 1 << 13;
/// Subtrees of at least this many primitives are built as rayon tasks.
const TASK: usize = 1 << 12;

/// The binary tree of primitives `0..n`, `bounds(i)` the box of primitive i.
/// The same boxes give the same tree, bit for bit, whatever the thread count: how
/// the work splits into chunks and tasks depends on sizes only, and what crosses
/// them (box min and max, integer sums) is merged in a fixed order (chunk order,
/// then left before right), so even 0.0 and −0.0 cannot trade places.
pub fn build<S: Dim>(n: usize, bounds: impl Fn(usize) -> Aabb<S> + Sync) -> BinaryTree {
    // The build partitions these in place: each carries its box and index, so every
    // pass reads memory in order (an index array into the boxes read it at random
    // and took a third longer on the benchmark sphere).
    let mut refs: Vec<Ref> = (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| Ref {
            b: Box4::outward(&bounds(i)),
            index: i as u32,
        })
        .collect();
    let mut nodes = Vec::with_capacity(2 * n / MAX_LEAF + 1);
    if !refs.is_empty() {
        let root = chunked(
            &refs,
            |c| c.iter().fold(Box4::EMPTY, |a, r| a.union(&r.b)),
            |a, c| a.union(&c),
        );
        subtree::<S>(&mut refs, 0, root).flatten(&mut nodes);
    }
    let order = refs.par_iter().with_min_len(CHUNK).map(|r| r.index).collect();
    BinaryTree { nodes, order }
}

/// `f` over `refs`; from two chunks on, `f` of each chunk of [`CHUNK`] on rayon,
/// merged in chunk order by `merge` (the same values as `f(refs)` for the min,
/// max and sums merged here).
fn chunked<T: Send>(refs: &[Ref], f: impl Fn(&[Ref]) -> T + Sync, merge: impl Fn(T, T) -> T) -> T {
    if refs.len() < 2 * CHUNK {
        return f(refs);
    }
    let parts: Vec<T> = refs.par_chunks(CHUNK).map(&f).collect();
    parts.into_iter().reduce(merge).expect("at least two chunks")
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

fn merge_bins(mut a: [Bins; 3], b: [Bins; 3]) -> [Bins; 3] {
    for (x, y) in a.iter_mut().flatten().zip(b.iter().flatten()) {
        *x = (x.0.union(&y.0), x.1 + y.1);
    }
    a
}

/// A subtree as built: nodes of a sequential build (indices local to it), or a
/// node whose two children were built as parallel tasks.
enum Built {
    Nodes(Vec<(Box4, BinNode)>),
    Join(Box4, Box<Built>, Box<Built>),
}

impl Built {
    /// Append the subtree's nodes in preorder (node, left subtree, right subtree:
    /// the order of a sequential build) with global indices.
    fn flatten(self, out: &mut Vec<(Box4, BinNode)>) {
        match self {
            Built::Nodes(nodes) => {
                let base = out.len() as u32;
                out.extend(nodes.into_iter().map(|(b, node)| match node {
                    BinNode::Inner { left, right } => (
                        b,
                        BinNode::Inner {
                            left: left + base,
                            right: right + base,
                        },
                    ),
                    leaf => (b, leaf),
                }));
            }
            Built::Join(b, left, right) => {
                let node = out.len();
                out.push((b, BinNode::Leaf { start: 0, count: 0 }));
                let l = out.len() as u32;
                left.flatten(out);
                let r = out.len() as u32;
                right.flatten(out);
                out[node].1 = BinNode::Inner { left: l, right: r };
            }
        }
    }
}

/// The subtree of `refs` (whose boxes' union is `bounds`, and which start at
/// `offset` in leaf order): large ones split here and build their children with
/// `rayon::join`, the rest sequentially.
fn subtree<S: Dim>(refs: &mut [Ref], offset: usize, bounds: Box4) -> Built {
    if refs.len() < TASK {
        let mut nodes = Vec::with_capacity(2 * refs.len() / MAX_LEAF + 1);
        split_range::<S>(&mut nodes, refs, offset, bounds);
        return Built::Nodes(nodes);
    }
    let Some((mid, left_bounds, right_bounds)) = split::<S>(refs, bounds) else {
        let leaf = BinNode::Leaf {
            start: offset as u32,
            count: refs.len() as u32,
        };
        return Built::Nodes(vec![(bounds, leaf)]);
    };
    let (lo, hi) = refs.split_at_mut(mid);
    let (left, right) = rayon::join(
        || subtree::<S>(lo, offset, left_bounds),
        || subtree::<S>(hi, offset + mid, right_bounds),
    );
    Built::Join(bounds, Box::new(left), Box::new(right))
}

/// Build the subtree of `refs` sequentially into `nodes` (as [`subtree`]);
/// returns its node index.
fn split_range<S: Dim>(nodes: &mut Vec<(Box4, BinNode)>, refs: &mut [Ref], offset: usize, bounds: Box4) -> u32 {
    let node = nodes.len() as u32;
    let leaf = BinNode::Leaf {
        start: offset as u32,
        count: refs.len() as u32,
    };
    nodes.push((bounds, leaf));
    let Some((mid, left_bounds, right_bounds)) = split::<S>(refs, bounds) else {
        return node;
    };
    let (lo, hi) = refs.split_at_mut(mid);
    let left = split_range::<S>(nodes, lo, offset, left_bounds);
    let right = split_range::<S>(nodes, hi, offset + mid, right_bounds);
    nodes[node as usize].1 = BinNode::Inner { left, right };
    node
}

/// The binned SAH split of `refs` (boxes' union `bounds`): partitions them in
/// place and returns (primitives on the left, left bounds, right bounds), or None
/// when a leaf is cheaper or no split exists (all centres coincide).
fn split<S: Dim>(refs: &mut [Ref], bounds: Box4) -> Option<(usize, Box4, Box4)> {
    let n = refs.len();
    if n <= MAX_LEAF {
        return None;
    }
    let cb = chunked(
        refs,
        |c| {
            let mut cb = Box4::EMPTY;
            c.iter().for_each(|r| cb.grow(&r.centre2()));
            cb
        },
        |a, c| a.union(&c),
    );
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
    let bin_into = |bins: &mut [Bins; 3], r: &Ref| {
        let centre = r.centre2();
        for (a, axis_bins) in bins.iter_mut().enumerate().take(S::DIM) {
            let k = bin(a, &centre);
            axis_bins[k].0 = axis_bins[k].0.union(&r.b);
            axis_bins[k].1 += 1;
        }
    };
    let bins = chunked(
        refs,
        |c| {
            let mut bins: [Bins; 3] = [[(Box4::EMPTY, 0); BINS]; 3];
            if c.len() < 64 {
                c.iter().for_each(|r| bin_into(&mut bins, r));
                return bins;
            }
            // Neighbouring primitives tend to fall in the same bins: two sets of
            // bins (even and odd primitives) halve the chains of dependent updates.
            let mut odd = bins;
            for pair in c.chunks(2) {
                bin_into(&mut bins, &pair[0]);
                if let Some(r) = pair.get(1) {
                    bin_into(&mut odd, r);
                }
            }
            merge_bins(bins, odd)
        },
        merge_bins,
    );
    // Best split over the axes: (cost, axis, last bin on the left, left and right bounds).
    let mut best: Option<(f64, usize, usize, Box4, Box4)> = None;
    for (a, axis_bins) in bins.iter().enumerate().take(S::DIM) {
        if scale[a] == 0.0 {
            continue;
        }
        let mut right = [(Box4::EMPTY, 0u32); BINS];
        let mut acc = (Box4::EMPTY, 0u32);
        for k in (1..BINS).rev() {
            if axis_bins[k].1 > 0 {
                acc = (acc.0.union(&axis_bins[k].0), acc.1 + axis_bins[k].1);
            }
            right[k] = acc;
        }
        // An empty bin k leaves both sides of candidate k − 1 as they are: the
        // same cost, and the earlier candidate wins ties. Small nodes (most of
        // them) have mostly empty bins.
        let mut left = (Box4::EMPTY, 0u32);
        for k in 0..BINS - 1 {
            if axis_bins[k].1 == 0 {
                continue;
            }
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
    let (cost, axis, k, left_bounds, right_bounds) = best?;
    if cost >= bounds.half_boundary::<S>() * n as f64 && n <= FORCE_SPLIT {
        return None; // a leaf is cheaper
    }
    let mut mid = 0;
    for j in 0..n {
        if bin(axis, &refs[j].centre2()) <= k {
            refs.swap(j, mid);
            mid += 1;
        }
    }
    Some((mid, left_bounds, right_bounds))
}
