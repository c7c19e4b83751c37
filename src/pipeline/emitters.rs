//! The emitting primitives of a scene and how next-event estimation picks one: in
//! proportion to (luminance of the emission) × (length or area), with a floor so
//! that a coloured emitter of zero luminance is still found.

use crate::core::color::{Rgb, luminance};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Emitters {
    /// Indices of the emitting primitives, increasing.
    pub prims: Vec<u32>,
    /// Cumulative probabilities of picking each.
    cdf: Vec<f64>,
}

impl Emitters {
    /// From (primitive, emission, measure) of every emitting primitive, in order.
    pub fn new(emitting: impl Iterator<Item = (u32, Rgb, f64)>) -> Self {
        let (prims, weights): (Vec<u32>, Vec<f64>) = emitting
            .map(|(i, e, measure)| (i, luminance(e).max(1e-3 * e.max_element()) * measure))
            .unzip();
        let total: f64 = weights.iter().sum();
        let cdf = weights
            .iter()
            .scan(0.0, |acc, w| {
                *acc += w / total;
                Some(*acc)
            })
            .collect();
        Emitters { prims, cdf }
    }

    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// The emitter picked by a uniform number `u`: (its number k, its primitive).
    pub fn pick(&self, u: f64) -> (usize, u32) {
        let k = self.cdf.partition_point(|&c| c <= u).min(self.prims.len() - 1);
        (k, self.prims[k])
    }

    /// Probability of picking emitter number `k`.
    pub fn probability(&self, k: usize) -> f64 {
        self.cdf[k] - if k == 0 { 0.0 } else { self.cdf[k - 1] }
    }

    /// The number of primitive `prim` among the emitters, if it emits.
    pub fn find(&self, prim: u32) -> Option<usize> {
        self.prims.binary_search(&prim).ok()
    }
}
