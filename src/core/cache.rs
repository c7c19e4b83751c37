//! The radiance cache (theory.md §8), generic over dimension and payload.
//!
//! A [`Record`] holds a position x_i, a payload with derivatives (an
//! [`Interpolant`]: e.g. `TaylorRgb<S>` for one RGB quantity, `[TaylorRgb<S>; 2]`
//! for single and multiple scattering kept apart), its [`Extent`] and its cost.
//! [`Cache`] indexes the extents (a hierarchical hash grid, `cache_index.rs`) and
//! answers coverage queries and the reconstruction
//!
//!   L(y) ≈ Σ_i w_i (L_i + ∇L_i·(y − x_i) [+ ½ (y − x_i)ᵀ H_i (y − x_i)]) / Σ_i w_i,
//!   w_i = 1 − d_i(y) over the records with d_i(y) < 1 (tent, Schwarzhaupt et al.).
//!
//! Covering records are always visited in insertion order, so every result is the
//! same bit for bit as a linear scan's, whatever the index does.
//!
//! # Deterministic placement (implemented by the callers, e.g. `flatland::field`)
//!
//! `Cache` is `Sync` (parallel reads) and [`Cache::insert`] takes `&mut self`, so a
//! placement that is the same for any thread count is:
//!
//! ```text
//! for batch in query_points.chunks(BATCH)            // fixed order, BATCH a constant
//!     uncovered = batch.par_iter().filter(|y| !cache.is_covered(y))   // parallel reads
//!     records   = uncovered.par_iter().map(|y| compute_record(y, rng(seed, index of y)))
//!     for (y, r) in zip(uncovered, records)          // sequential, in the fixed order
//!         if !cache.is_covered(y) { cache.insert(r) }  // re-check: an earlier record
//!                                                       // of this batch may cover y
//! ```
//!
//! BATCH must not depend on the thread count. Records computed and then skipped by
//! the re-check are wasted work (small for BATCH ≪ the number of records); count
//! their rays in the cost. Afterwards every query point is covered (no holes).

use super::cache_index::{GridIndex, IndexError};
use super::color::Rgb;
use super::metric::Extent;
use super::space::Space;
use super::taylor::Taylor2;
use super::taylor_rgb::TaylorRgb;

/// A value that can be averaged with weights (the reconstruction's output).
pub trait Blend: Sized {
    fn zero() -> Self;
    /// self += w · v.
    fn add_scaled(&mut self, v: &Self, w: f64);
}

impl Blend for f64 {
    fn zero() -> Self {
        0.0
    }
    fn add_scaled(&mut self, v: &Self, w: f64) {
        *self += w * v;
    }
}

impl Blend for Rgb {
    fn zero() -> Self {
        Rgb::ZERO
    }
    fn add_scaled(&mut self, v: &Self, w: f64) {
        *self += *v * w;
    }
}

impl<T: Blend, const N: usize> Blend for [T; N] {
    fn zero() -> Self {
        std::array::from_fn(|_| T::zero())
    }
    fn add_scaled(&mut self, v: &Self, w: f64) {
        self.iter_mut().zip(v).for_each(|(a, b)| a.add_scaled(b, w));
    }
}

/// A cached value with derivatives that extrapolates to a nearby point.
pub trait Interpolant<S: Space> {
    type Out: Blend;
    /// Value at x + dx: first order, plus ½ dxᵀ H dx when `second_order`. (Named
    /// apart from `Taylor2::extrapolate`, which is always second order.)
    fn extrapolated(&self, dx: S::Vec, second_order: bool) -> Self::Out;
    fn is_finite(&self) -> bool;
}

impl<S: Space> Interpolant<S> for Taylor2<S> {
    type Out = f64;
    fn extrapolated(&self, dx: S::Vec, second_order: bool) -> f64 {
        let first = self.value + S::dot(self.grad, dx);
        if second_order {
            first + 0.5 * S::dot(dx, self.hess * dx)
        } else {
            first
        }
    }
    fn is_finite(&self) -> bool {
        Taylor2::is_finite(self)
    }
}

impl<S: Space> Interpolant<S> for TaylorRgb<S> {
    type Out = Rgb;
    fn extrapolated(&self, dx: S::Vec, second_order: bool) -> Rgb {
        let [r, g, b] = self.channels.map(|c| c.extrapolated(dx, second_order));
        Rgb::new(r, g, b)
    }
    fn is_finite(&self) -> bool {
        TaylorRgb::is_finite(self)
    }
}

impl<S: Space, T: Interpolant<S>, const N: usize> Interpolant<S> for [T; N] {
    type Out = [T::Out; N];
    fn extrapolated(&self, dx: S::Vec, second_order: bool) -> Self::Out {
        std::array::from_fn(|i| self[i].extrapolated(dx, second_order))
    }
    fn is_finite(&self) -> bool {
        self.iter().all(T::is_finite)
    }
}

/// One cache point.
#[derive(Clone, Debug, PartialEq)]
pub struct Record<S: Space, V> {
    pub position: S::Vec,
    pub value: V,
    pub extent: Extent<S>,
    /// Rays traced to compute it (for cost accounting).
    pub cost_rays: u64,
}

impl<S: Space, V> Record<S, V> {
    /// Tent weight at y: 1 − d(y) inside the extent, 0 outside.
    pub fn weight(&self, y: S::Vec) -> f64 {
        self.extent.tent_weight(self.position, y)
    }
}

/// Why a record was refused.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum CacheError {
    #[error("record position is not finite")]
    NonFinitePosition,
    #[error("record value or derivatives are not finite")]
    NonFiniteValue,
    #[error("record extent needs finite positive radii and orthonormal axes")]
    InvalidExtent,
    #[error("record extent is too large to index")]
    TooLarge,
}

/// Records and the spatial index over their extents.
#[derive(Clone, Debug)]
pub struct Cache<S: Space, V> {
    records: Vec<Record<S, V>>,
    /// (position, extent) of each record, packed apart from the payloads so that
    /// the coverage test's scattered reads touch less memory.
    shapes: Vec<(S::Vec, Extent<S>)>,
    index: GridIndex,
}

impl<S: Space, V> Default for Cache<S, V> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Space, V> Cache<S, V> {
    pub fn new() -> Self {
        Cache {
            records: Vec::new(),
            shapes: Vec::new(),
            index: GridIndex::default(),
        }
    }

    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The records, in insertion order (index = position in this slice).
    pub fn records(&self) -> &[Record<S, V>] {
        &self.records
    }

    /// Total rays traced by all records.
    pub fn cost_rays(&self) -> u64 {
        self.records.iter().map(|r| r.cost_rays).sum()
    }

    /// (record index, tent weight in (0, 1]) of every record covering y, by index.
    pub fn covering(&self, y: S::Vec) -> Vec<(usize, f64)> {
        let mut out = Vec::new();
        self.covering_into(y, &mut out);
        out
    }

    /// [`Cache::covering`] into a reused buffer (cleared first).
    pub fn covering_into(&self, y: S::Vec, out: &mut Vec<(usize, f64)>) {
        out.clear();
        self.index.for_candidates(to_array::<S>(y), S::DIM, |id| {
            let (x, e) = &self.shapes[id as usize];
            let w = e.tent_weight(*x, y);
            if w > 0.0 {
                out.push((id as usize, w));
            }
        });
        out.sort_unstable_by_key(|&(i, _)| i);
    }

    /// [`Cache::covering_into`] keeping only the records that pass `keep(index,
    /// position)` (e.g. a record must see y: it never extrapolates across a surface).
    pub fn covering_where(&self, y: S::Vec, out: &mut Vec<(usize, f64)>, mut keep: impl FnMut(usize, S::Vec) -> bool) {
        self.covering_into(y, out);
        out.retain(|&(i, _)| keep(i, self.shapes[i].0));
    }

    /// Some record covers y.
    pub fn is_covered(&self, y: S::Vec) -> bool {
        self.is_covered_where(y, |_, _| true)
    }

    /// Some record whose position passes `keep` covers y (`keep` is called only
    /// until one is found).
    pub fn is_covered_where(&self, y: S::Vec, mut keep: impl FnMut(usize, S::Vec) -> bool) -> bool {
        let mut covered = false;
        self.index.for_candidates(to_array::<S>(y), S::DIM, |id| {
            if !covered {
                let (x, e) = &self.shapes[id as usize];
                covered = e.contains(*x, y) && keep(id as usize, *x);
            }
        });
        covered
    }

    /// Number of (cell, record) entries in the index, for diagnostics.
    pub fn index_entries(&self) -> usize {
        self.index.entries()
    }
}

impl<S: Space, V: Interpolant<S>> Cache<S, V> {
    /// Adds a record and returns its index. Refuses non-finite positions or values
    /// and extents without finite positive radii and orthonormal axes (the index's
    /// bounding boxes assume them).
    pub fn insert(&mut self, record: Record<S, V>) -> Result<usize, CacheError> {
        if !S::vec_is_finite(record.position) {
            return Err(CacheError::NonFinitePosition);
        }
        if !record.value.is_finite() {
            return Err(CacheError::NonFiniteValue);
        }
        let e = &record.extent;
        let radii_ok = (0..S::DIM).all(|k| e.radii[k] > 0.0 && e.radii[k].is_finite());
        let ortho = S::frobenius(S::transpose(e.axes) * e.axes - S::identity());
        if !(radii_ok && S::mat_is_finite(e.axes) && ortho <= 1e-9) {
            return Err(CacheError::InvalidExtent);
        }
        let id = u32::try_from(self.records.len()).map_err(|_| CacheError::TooLarge)?;
        let (c, h) = (to_array::<S>(record.position), to_array::<S>(e.half_widths()));
        self.index.insert(id, c, h, S::DIM).map_err(|err| match err {
            IndexError::NonFinite | IndexError::TooLarge => CacheError::TooLarge,
        })?;
        self.shapes.push((record.position, record.extent));
        self.records.push(record);
        Ok(id as usize)
    }

    /// Weighted extrapolation from the covering records (theory.md §8), or None
    /// where no record covers y.
    pub fn interpolate(&self, y: S::Vec, second_order: bool) -> Option<V::Out> {
        self.interpolate_with(y, second_order, &mut Vec::new())
    }

    /// [`Cache::interpolate`] with a reused scratch buffer (no allocation per query).
    pub fn interpolate_with(&self, y: S::Vec, second_order: bool, scratch: &mut Vec<(usize, f64)>) -> Option<V::Out> {
        self.interpolate_where(y, second_order, scratch, |_, _| true)
    }

    /// [`Cache::interpolate`] from the covering records whose position passes `keep`
    /// ([`Cache::covering_where`]): Σ w_i v_i / Σ w_i, or None if none is kept.
    pub fn interpolate_where(
        &self,
        y: S::Vec,
        second_order: bool,
        scratch: &mut Vec<(usize, f64)>,
        keep: impl FnMut(usize, S::Vec) -> bool,
    ) -> Option<V::Out> {
        self.covering_where(y, scratch, keep);
        let total: f64 = scratch.iter().map(|&(_, w)| w).sum();
        if total <= 0.0 {
            return None;
        }
        let mut out = V::Out::zero();
        for &(i, w) in scratch.iter() {
            let r = &self.records[i];
            out.add_scaled(&r.value.extrapolated(y - r.position, second_order), w / total);
        }
        Some(out)
    }
}

/// The order placement visits the pixels of a width × height grid (row-major
/// indices): coarse to fine (strides 16, 8, 4, 2, 1), so early records are spread
/// over the image rather than piled up along its top rows.
pub fn placement_order(width: usize, height: usize) -> Vec<usize> {
    let mut seen = vec![false; width * height];
    let mut order = Vec::with_capacity(width * height);
    for stride in [16, 8, 4, 2, 1] {
        for j in (0..height).step_by(stride) {
            for i in (0..width).step_by(stride) {
                let k = j * width + i;
                if !seen[k] {
                    seen[k] = true;
                    order.push(k);
                }
            }
        }
    }
    order
}

fn to_array<S: Space>(v: S::Vec) -> [f64; 3] {
    let mut a = [0.0; 3];
    for (i, x) in a.iter_mut().enumerate().take(S::DIM) {
        *x = v[i];
    }
    a
}

#[cfg(test)]
#[path = "cache_tests.rs"]
mod tests;
