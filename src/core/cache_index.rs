//! Spatial index of the cache (theory.md §8 coverage queries): a hierarchical hash
//! grid over the records' axis-aligned bounding boxes.
//!
//! Radii span r_min..r_max (250× by default), so one cell size cannot suit every
//! record. Level ℓ has cells of side 2^ℓ; a record goes to the level of the
//! smallest power of two ≥ its box's width, into every cell its box overlaps there
//! (at most 2 per axis, so 4 in 2D, 8 in 3D). A query visits one cell per occupied
//! level. Insertion is O(1) and needs no rebuild, which suits placement (queries
//! and insertions interleave). The index only returns candidates: the exact test is
//! the caller's, so coarse cells, saturated coordinates or hash collisions can cost
//! time but never change a result.

use super::rng::mix64;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};

/// Levels beyond ±LEVEL_LIMIT would make 2^-ℓ overflow or underflow.
const LEVEL_LIMIT: i32 = 1000;

/// Cells are 2^SUBDIVISION times smaller than the widest box on their level:
/// more cells per record, fewer candidates per query (queries outnumber records).
const SUBDIVISION: i32 = 2;

/// Boxes are grown by this relative margin (plus an absolute one) so that a point
/// that the exact test finds inside, with rounding, is always inside its box.
const BOX_MARGIN: f64 = 1e-9;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct CellKey {
    level: i32,
    cell: [i64; 3],
}

impl Hash for CellKey {
    fn hash<H: Hasher>(&self, h: &mut H) {
        h.write_u64(self.level as u64);
        self.cell.iter().for_each(|&c| h.write_u64(c as u64));
    }
}

/// SplitMix-based hasher: fast, deterministic and good enough for integer keys.
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        bytes.iter().for_each(|&b| self.write_u64(b as u64));
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = mix64(self.0 ^ v);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

/// Why a box cannot be indexed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum IndexError {
    NonFinite,
    TooLarge,
}

/// Hierarchical hash grid of record ids (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct GridIndex {
    /// Occupied levels, ascending, each with its cells' inverse side 2^-ℓ.
    levels: Vec<(i32, f64)>,
    cells: HashMap<CellKey, Vec<u32>, BuildHasherDefault<KeyHasher>>,
}

impl GridIndex {
    /// Index record `id` with box centre `c` and half-widths `h` (first `dim` entries).
    pub(crate) fn insert(&mut self, id: u32, c: [f64; 3], h: [f64; 3], dim: usize) -> Result<(), IndexError> {
        let mut width = 0.0f64;
        let (mut lo, mut hi) = ([0.0; 3], [0.0; 3]);
        for i in 0..dim {
            let hi_ = h[i] * (1.0 + BOX_MARGIN) + f64::MIN_POSITIVE;
            lo[i] = c[i] - hi_;
            hi[i] = c[i] + hi_;
            if !(lo[i].is_finite() && hi[i].is_finite()) {
                return Err(IndexError::NonFinite);
            }
            width = width.max(2.0 * hi_);
        }
        // Smallest power of two ≥ width; tiny boxes use the lowest level (larger
        // cells than needed are still correct).
        let level = (width.log2().ceil() as i32)
            .saturating_sub(SUBDIVISION)
            .max(-LEVEL_LIMIT);
        if level > LEVEL_LIMIT {
            return Err(IndexError::TooLarge);
        }
        let inv = 2f64.powi(-level);
        let (a, b) = (cell_of(lo, inv, dim), cell_of(hi, inv, dim));
        let mut cell = a;
        // Odometer over the (≤ 2 or 3 per axis) cells between a and b.
        loop {
            self.cells.entry(CellKey { level, cell }).or_default().push(id);
            let mut i = 0;
            while i < dim {
                if cell[i] < b[i] {
                    cell[i] += 1;
                    break;
                }
                cell[i] = a[i];
                i += 1;
            }
            if i == dim {
                break;
            }
        }
        if let Err(pos) = self.levels.binary_search_by_key(&level, |&(l, _)| l) {
            self.levels.insert(pos, (level, inv));
        }
        Ok(())
    }

    /// Calls `f` with every id whose box may contain `y` (each id at most once:
    /// a record lives on one level, and one cell per level is visited).
    pub(crate) fn for_candidates(&self, y: [f64; 3], dim: usize, mut f: impl FnMut(u32)) {
        if !y[..dim].iter().all(|v| v.is_finite()) {
            return;
        }
        for &(level, inv) in &self.levels {
            let key = CellKey {
                level,
                cell: cell_of(y, inv, dim),
            };
            if let Some(ids) = self.cells.get(&key) {
                ids.iter().for_each(|&id| f(id));
            }
        }
    }

    /// Number of (cell, id) entries: the index's memory, for diagnostics.
    pub(crate) fn entries(&self) -> usize {
        self.cells.values().map(Vec::len).sum()
    }
}

/// Integer cell of point p at the level of inverse side `inv` = 2^-ℓ: floor(p · inv),
/// exact scaling by a power of two, saturating at the i64 range (monotone, so boxes
/// still contain their points).
fn cell_of(p: [f64; 3], inv: f64, dim: usize) -> [i64; 3] {
    let mut c = [0i64; 3];
    for i in 0..dim {
        c[i] = (p[i] * inv).floor() as i64;
    }
    c
}
