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

/// A box in f32 lanes (x, y, z, w), rounded outwards from f64: the build works on
/// these (four lanes at a time, half the bytes of f64), and the wide nodes store
/// their x, y and z as they are. Lane w means nothing in a node's box: a primitive's
/// box carries its index there (see [`Ref`]). Aligned, so that a box is two
/// aligned 16-byte loads.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Box4 {
    pub lo: [f32; 4],
    pub hi: [f32; 4],
}

/// The smallest f32 ≥ x. Branching on the rounding direction suits the traversal,
/// where x is mostly ∞ (nothing hit yet): the branch predicts well there.
pub fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

/// The largest f32 ≤ x, for the primitives' boxes: selected rather than branched
/// on which way the conversion rounded, which is as good as random there (the
/// mispredicted branches took most of the time of making the boxes).
#[inline]
fn down(x: f64) -> f32 {
    let f = x as f32;
    let d = f.next_down();
    if f as f64 > x { d } else { f }
}

/// The smallest f32 ≥ x, for the primitives' boxes (as [`down`]).
#[inline]
fn up(x: f64) -> f32 {
    let f = x as f32;
    let u = f.next_up();
    if (f as f64) < x { u } else { f }
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
            (r.lo[a], r.hi[a]) = (down(b.min[a]), up(b.max[a]));
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
    assert!(n < 1 << 29, "primitive indices below 2^29 (see Ref)");
    // The build partitions these in place: each carries its box and index, so every
    // pass reads memory in order (an index array into the boxes read it at random
    // and took a third longer on the benchmark sphere).
    let mut refs: Vec<Ref> = (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| Ref::new(Box4::outward(&bounds(i)), i as u32))
        .collect();
    // Binary trees of the benchmark sphere have 0.6 nodes per primitive (2·n over
    // the smallest split node was too few: the vector grew and was copied).
    let mut nodes = Vec::with_capacity(n);
    if !refs.is_empty() {
        let (root, centres) = chunked(
            &refs,
            |c| {
                c.iter().fold((Box4::EMPTY, Box4::EMPTY), |(b, mut cb), r| {
                    cb.grow(&r.centre2());
                    (b.union(&r.b), cb)
                })
            },
            |a, c| (a.0.union(&c.0), a.1.union(&c.1)),
        );
        if rayon::current_num_threads() == 1 {
            // The tasks' nodes flattened are those of a sequential build: on one
            // thread, build straight into `nodes` (no copies, no vectors per task).
            split_range::<S>(&mut nodes, &mut refs, 0, root, centres);
        } else {
            subtree::<S>(&mut refs, 0, root, centres).flatten(&mut nodes);
        }
    }
    let order = refs.par_iter().with_min_len(CHUNK).map(Ref::index).collect();
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

/// A primitive during the build: its outward f32 box with its index in lane w. 32
/// bytes, aligned (a separate index made it 36), and every pass reads and moves
/// these. The index is kept as a normal float and its negation, so that lane w of
/// the centre is exactly 0 and no arithmetic meets a subnormal (slow on x86): its
/// bits flip bit 30, which makes the exponent 128 to 191 for indices below 2²⁹.
#[derive(Clone, Copy, Debug)]
struct Ref {
    b: Box4,
}

/// Bit 30 of an f32: see [`Ref`].
const INDEX_FLIP: u32 = 1 << 30;

impl Ref {
    fn new(mut b: Box4, index: u32) -> Ref {
        let w = f32::from_bits(index ^ INDEX_FLIP);
        (b.lo[3], b.hi[3]) = (w, -w);
        Ref { b }
    }

    fn index(&self) -> u32 {
        self.b.lo[3].to_bits() ^ INDEX_FLIP
    }

    /// Twice the box's centre (the bins need only an affine image of the centre).
    #[inline]
    fn centre2(&self) -> [f32; 4] {
        std::array::from_fn(|a| self.b.lo[a] + self.b.hi[a])
    }
}

/// Bins of the three axes: bounds and count per bin.
#[derive(Clone, Copy)]
struct Bins {
    boxes: [[Box4; BINS]; 3],
    counts: [[u32; BINS]; 3],
}

impl Bins {
    const EMPTY: Bins = Bins {
        boxes: [[Box4::EMPTY; BINS]; 3],
        counts: [[0; BINS]; 3],
    };

    fn merge(mut self, o: Bins) -> Bins {
        for (x, y) in self.boxes.iter_mut().flatten().zip(o.boxes.iter().flatten()) {
            *x = x.union(y);
        }
        for (x, y) in self.counts.iter_mut().flatten().zip(o.counts.iter().flatten()) {
            *x += y;
        }
        self
    }
}

/// Where centres fall in the bins: bin k = (c − lo)·scale per axis, the scale
/// precomputed (no division per primitive); a flat axis gets scale 0 (everything
/// in bin 0, never split).
struct Grid {
    lo: [f32; 4],
    scale: [f32; 4],
}

impl Grid {
    fn new<S: Dim>(centres: &Box4) -> Grid {
        let scale = std::array::from_fn(|a| {
            let extent = centres.hi[a] - centres.lo[a];
            if a < S::DIM && extent > 0.0 {
                BINS as f32 * 0.999_99 / extent
            } else {
                0.0
            }
        });
        Grid { lo: centres.lo, scale }
    }

    /// The bins of centre `c` on every axis.
    #[inline]
    fn bins(&self, c: &[f32; 4]) -> [usize; 4] {
        let x: [f32; 4] = std::array::from_fn(|a| (c[a] - self.lo[a]) * self.scale[a]);
        std::array::from_fn(|a| Self::clamp(x[a]))
    }

    /// Bin ⌊x⌋ clamped to the bins: clamped as a float, then converted (the same bin
    /// as converting then clamping, for the x ≥ 0 met here), which spares the checks
    /// of a saturating conversion (a third of the binning's instructions).
    #[inline]
    fn clamp(x: f32) -> usize {
        let x = if x > 0.0 { x } else { 0.0 }; // NaN becomes 0 too
        let x = if x < (BINS - 1) as f32 { x } else { (BINS - 1) as f32 };
        // SAFETY: x is in [0, BINS − 1], not NaN, so it converts exactly to i32.
        unsafe { x.to_int_unchecked::<i32>() as usize & (BINS - 1) }
    }
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

/// The subtree of `refs` (whose boxes' union is `bounds`, whose centres' is
/// `centres`, and which start at `offset` in leaf order): large ones split here and
/// build their children with `rayon::join`, the rest sequentially.
fn subtree<S: Dim>(refs: &mut [Ref], offset: usize, bounds: Box4, centres: Box4) -> Built {
    if refs.len() < TASK {
        let mut nodes = Vec::with_capacity(refs.len());
        split_range::<S>(&mut nodes, refs, offset, bounds, centres);
        return Built::Nodes(nodes);
    }
    let Some(s) = split::<S>(refs, bounds, centres) else {
        let leaf = BinNode::Leaf {
            start: offset as u32,
            count: refs.len() as u32,
        };
        return Built::Nodes(vec![(bounds, leaf)]);
    };
    let (lo, hi) = refs.split_at_mut(s.mid);
    let (left, right) = rayon::join(
        || subtree::<S>(lo, offset, s.bounds[0], s.centres[0]),
        || subtree::<S>(hi, offset + s.mid, s.bounds[1], s.centres[1]),
    );
    Built::Join(bounds, Box::new(left), Box::new(right))
}

/// Build the subtree of `refs` sequentially into `nodes` (as [`subtree`]);
/// returns its node index.
fn split_range<S: Dim>(
    nodes: &mut Vec<(Box4, BinNode)>,
    refs: &mut [Ref],
    offset: usize,
    bounds: Box4,
    centres: Box4,
) -> u32 {
    let node = nodes.len() as u32;
    let leaf = BinNode::Leaf {
        start: offset as u32,
        count: refs.len() as u32,
    };
    nodes.push((bounds, leaf));
    let Some(s) = split::<S>(refs, bounds, centres) else {
        return node;
    };
    let (lo, hi) = refs.split_at_mut(s.mid);
    let left = split_range::<S>(nodes, lo, offset, s.bounds[0], s.centres[0]);
    let right = split_range::<S>(nodes, hi, offset + s.mid, s.bounds[1], s.centres[1]);
    nodes[node as usize].1 = BinNode::Inner { left, right };
    node
}

/// A split: primitives on the left, and the boxes' and centres' unions of each side.
struct Split {
    mid: usize,
    bounds: [Box4; 2],
    centres: [Box4; 2],
}

/// The binned SAH split of `refs` (boxes' union `bounds`, centres' `centres`):
/// partitions them in place, or returns None when a leaf is cheaper or no split
/// exists (all centres coincide).
fn split<S: Dim>(refs: &mut [Ref], bounds: Box4, centres: Box4) -> Option<Split> {
    let n = refs.len();
    if n <= S::BVH_LEAF.0 {
        return None;
    }
    let grid = Grid::new::<S>(&centres);
    let bin_into = |bins: &mut Bins, r: &Ref| {
        let k = grid.bins(&r.centre2());
        for (a, &k) in k.iter().enumerate().take(S::DIM) {
            bins.boxes[a][k] = bins.boxes[a][k].union(&r.b);
            bins.counts[a][k] += 1;
        }
    };
    let bins = chunked(
        refs,
        |c| {
            let mut bins = Bins::EMPTY;
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
            bins.merge(odd)
        },
        Bins::merge,
    );
    // Best split over the axes: (cost, axis, last bin on the left, left and right bounds).
    let mut best: Option<(f64, usize, usize, Box4, Box4)> = None;
    for a in 0..S::DIM {
        if grid.scale[a] == 0.0 {
            continue;
        }
        best_on_axis::<S>(&bins.boxes[a], &bins.counts[a], a, &mut best);
    }
    let (cost, axis, k, left_bounds, right_bounds) = best?;
    if cost >= bounds.half_boundary::<S>() * n as f64 && n <= S::BVH_LEAF.1 {
        return None; // a leaf is cheaper
    }
    // The partition also gathers each side's centres, which the children's bins
    // need: no separate pass over the primitives for them. Bin ≤ k is tested as
    // x < k + 1 on the unclamped x (the same answer, NaN included, as k < BINS − 1),
    // without the conversion.
    let mut sides = [Box4::EMPTY; 2];
    let mut mid = 0;
    let past_k = (k + 1) as f32;
    for j in 0..n {
        let c = refs[j].centre2();
        let right = (c[axis] - grid.lo[axis]) * grid.scale[axis] >= past_k;
        if !right {
            sides[0].grow(&c);
            refs.swap(j, mid);
            mid += 1;
        } else {
            sides[1].grow(&c);
        }
    }
    Some(Split {
        mid,
        bounds: [left_bounds, right_bounds],
        centres: sides,
    })
}

/// The SAH sweep over one axis's bins: improves `best` (cost, axis, last bin on
/// the left, left and right bounds) with the candidates "bins ≤ k on the left" for
/// each occupied bin k. An empty bin would repeat its predecessor's candidate at
/// the same cost (the earlier one wins ties), so only the occupied bins are swept,
/// listed first: small nodes, most of them, occupy a few of the bins.
fn best_on_axis<S: Dim>(
    boxes: &[Box4; BINS],
    counts: &[u32; BINS],
    axis: usize,
    best: &mut Option<(f64, usize, usize, Box4, Box4)>,
) {
    let mut occupied = [0usize; BINS + 1];
    let mut m = 0;
    for (k, &count) in counts.iter().enumerate() {
        occupied[m] = k;
        m += (count > 0) as usize;
    }
    // Right sides: the bins from the i-th occupied one on.
    let mut right = [(Box4::EMPTY, 0u32); BINS];
    let mut acc = (Box4::EMPTY, 0u32);
    for i in (1..m).rev() {
        let k = occupied[i];
        acc = (acc.0.union(&boxes[k]), acc.1 + counts[k]);
        right[i] = acc;
    }
    let mut left = (Box4::EMPTY, 0u32);
    for i in 0..m.saturating_sub(1) {
        let k = occupied[i];
        left = (left.0.union(&boxes[k]), left.1 + counts[k]);
        let r = right[i + 1];
        let cost = left.0.half_boundary::<S>() * left.1 as f64 + r.0.half_boundary::<S>() * r.1 as f64;
        if best.as_ref().is_none_or(|b| cost < b.0) {
            *best = Some((cost, axis, k, left.0, r.0));
        }
    }
}
