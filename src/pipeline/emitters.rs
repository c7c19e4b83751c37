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

    /// [`Emitters::pick`], and `u` rescaled to [0, 1) within the picked emitter's
    /// share: a uniform number independent of the pick, so one draw picks and
    /// places (a stratified set's draws then spread over each emitter).
    pub fn pick_remapped(&self, u: f64) -> (usize, u32, f64) {
        let (k, prim) = self.pick(u);
        let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let p = self.cdf[k] - lo;
        let rest = if p > 0.0 {
            ((u - lo) / p).clamp(0.0, 1.0 - f64::EPSILON / 2.0)
        } else {
            0.0
        };
        (k, prim, rest)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Four emitters: white, a faint blue one, one of zero measure (never picked),
    /// and a bright short one.
    fn table() -> (Emitters, Vec<f64>) {
        let e = [
            (2, Rgb::splat(1.0), 2.0),
            (5, Rgb::new(0.0, 0.0, 1e-6), 1.0),
            (6, Rgb::splat(3.0), 0.0),
            (9, Rgb::new(4.0, 2.0, 1.0), 0.5),
        ];
        // luminance × measure (the floor at 10⁻³ of the brightest channel does not
        // bind for non-negative colours: luminance ≥ 0.0722 × the brightest).
        let w: Vec<f64> = e.iter().map(|&(_, c, m)| luminance(c) * m).collect();
        let total: f64 = w.iter().sum();
        (Emitters::new(e.into_iter()), w.iter().map(|x| x / total).collect())
    }

    #[test]
    fn probabilities_follow_luminance_times_measure() {
        let (em, want) = table();
        assert_eq!(em.prims, vec![2, 5, 6, 9]);
        for (k, p) in want.iter().enumerate() {
            assert!(
                (em.probability(k) - p).abs() < 1e-15,
                "emitter {k}: {} vs {p}",
                em.probability(k)
            );
        }
        assert!(em.probability(1) > 0.0);
        assert_eq!(em.probability(2), 0.0);
        assert!(((0..4).map(|k| em.probability(k)).sum::<f64>() - 1.0).abs() < 1e-15);
        for (k, &prim) in em.prims.iter().enumerate() {
            assert_eq!(em.find(prim), Some(k));
        }
        assert_eq!(em.find(3), None);
        assert!(!em.is_empty() && Emitters::new(std::iter::empty()).is_empty());
    }

    /// Stratified numbers pick each emitter as often as its probability says (to one
    /// stratum), an emitter of probability zero never, and u at the ends of [0, 1)
    /// the first and the last.
    #[test]
    fn pick_inverts_the_table() {
        let (em, want) = table();
        let n = 1_000_000;
        let mut counts = [0usize; 4];
        for i in 0..n {
            let (k, prim) = em.pick((i as f64 + 0.5) / n as f64);
            assert_eq!(prim, em.prims[k]);
            counts[k] += 1;
        }
        for k in 0..4 {
            let expected = want[k] * n as f64;
            assert!(
                (counts[k] as f64 - expected).abs() <= 1.0,
                "emitter {k}: {} vs {expected}",
                counts[k]
            );
        }
        assert_eq!(counts[2], 0);
        assert_eq!(em.pick(0.0).0, 0);
        assert_eq!(em.pick(1.0 - f64::EPSILON).0, 3);
    }

    /// The remapped number is uniform within each emitter: stratified u give, per
    /// emitter, its own evenly spread numbers in [0, 1) (mean 1/2, none outside),
    /// and the pick is `pick`'s.
    #[test]
    fn the_remapped_number_is_uniform_within_each_emitter() {
        let (em, _) = table();
        let n = 200_000;
        let (mut sum, mut count) = ([0.0; 4], [0usize; 4]);
        for i in 0..n {
            let u = (i as f64 + 0.5) / n as f64;
            let (k, prim, rest) = em.pick_remapped(u);
            assert_eq!((k, prim), em.pick(u));
            assert!((0.0..1.0).contains(&rest), "u {u}: {rest}");
            sum[k] += rest;
            count[k] += 1;
        }
        for k in [0, 3] {
            let mean = sum[k] / count[k] as f64;
            assert!(
                (mean - 0.5).abs() < 1.0 / count[k] as f64 + 1e-9,
                "emitter {k}: mean {mean}"
            );
        }
        assert!(em.pick_remapped(1.0 - f64::EPSILON / 2.0).2 < 1.0);
    }
}
