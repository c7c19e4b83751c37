//! Padded, Owen-scrambled Sobol' points (Burley 2020, "Practical Hash-based Owen
//! Scrambling"; pbrt-v4's `PaddedSobolSampler`): the first dimensions of a set of
//! samples of one integral, spread so that every pair of dimensions is a (0,2)-
//! sequence, hence every single dimension stratified, for any sample count (a
//! net at powers of two). Each point is uniform on the unit square (the
//! scrambling is random), so an estimator stays unbiased; what it gains is that
//! the samples of one item no longer clump: an integrand with a few jumps (the
//! visible part of an emitter) has its error fall as ~n^-1 instead of n^-1/2.

/// Reverse the 32 bits of `x`.
#[inline]
fn reverse(x: u32) -> u32 {
    x.reverse_bits()
}

/// A random permutation of `x`'s bits in which each bit is flipped according to
/// the bits below it only (multiplying by an even number and xor, adding, and
/// multiplying by an odd number all keep that): on reversed bits it is a nested
/// uniform (Owen) scramble. Laine and Karras's construction with Vegdahl's
/// constants, as in Burley's paper.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Owen-scramble the base-2 digits of a number in [0, 2^32) read as a fraction.
#[inline]
fn owen_scramble(x: u32, seed: u32) -> u32 {
    reverse(laine_karras(reverse(x), seed))
}

/// The first two dimensions of the Sobol' sequence at `index` (32-bit fractions):
/// van der Corput, and the sequence of the primitive polynomial x + 1.
#[inline]
fn sobol_pair(index: u32) -> (u32, u32) {
    let (mut y, mut v, mut i) = (0u32, 1u32 << 31, index);
    while i != 0 {
        if i & 1 != 0 {
            y ^= v;
        }
        v ^= v >> 1;
        i >>= 1;
    }
    (reverse(index), y)
}

/// Dimensions `2·pair` and `2·pair + 1` of sample `index` of one set, as 32-bit
/// fractions, from the pair's three random seeds: the index shuffle (each pair
/// its own, so pairs are independent of one another: padding) and the scramble of
/// each dimension.
pub fn padded_pair(seeds: [u32; 3], index: u32) -> (u32, u32) {
    let (a, b) = sobol_pair(owen_scramble(index, seeds[0]));
    (owen_scramble(a, seeds[1]), owen_scramble(b, seeds[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scrambling seeds for set `seed`, pair `pair` (any well-mixed bits do).
    fn seeds(seed: u64, pair: u64) -> [u32; 3] {
        let h = |salt: u64| {
            let z = (seed + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ (3 * pair + salt + 1).wrapping_mul(0xD1B5_4A32_D192_ED03);
            (z.wrapping_mul(0xBF58_476D_1CE4_E5B9) >> 32) as u32
        };
        [h(0), h(1), h(2)]
    }

    fn unit(x: u32) -> f64 {
        (x as f64 + 0.5) / 4_294_967_296.0
    }

    #[test]
    fn every_power_of_two_prefix_is_a_net() {
        // The first 2^m points of a pair fill each of the 2^m elementary boxes of
        // every shape 2^a × 2^(m−a) exactly once.
        for seed in 0..6u64 {
            for pair in 0..3 {
                let m = 6;
                let n = 1u32 << m;
                let pts: Vec<(u32, u32)> = (0..n).map(|k| padded_pair(seeds(seed, pair), k)).collect();
                for a in 0..=m {
                    let mut seen = vec![false; n as usize];
                    for &(x, y) in &pts {
                        let cell = (((x as u64) >> (32 - a)) << (m - a)) | ((y as u64) >> (32 - (m - a)));
                        let cell = cell as usize;
                        assert!(!seen[cell], "seed {seed} pair {pair} shape {a}: box {cell} twice");
                        seen[cell] = true;
                    }
                }
            }
        }
    }

    #[test]
    fn points_are_uniform_over_seeds() {
        // Over random scrambles each point is uniform: the mean of point k over
        // 4,000 seeds is 1/2 and its second moment 1/3 within a few standard errors.
        let sets = 4000;
        for k in [0u32, 1, 5, 37] {
            let (mut m1, mut m2, mut mxy) = (0.0, 0.0, 0.0);
            for seed in 0..sets {
                let (a, b) = padded_pair(seeds(seed, 1), k);
                let (x, y) = (unit(a), unit(b));
                m1 += x + y;
                m2 += x * x + y * y;
                mxy += x * y;
            }
            let n = sets as f64;
            assert!(
                (m1 / (2.0 * n) - 0.5).abs() < 4.0 * (1.0 / 12.0 / (2.0 * n)).sqrt(),
                "k {k}"
            );
            assert!((m2 / (2.0 * n) - 1.0 / 3.0).abs() < 0.015, "k {k}");
            assert!((mxy / n - 0.25).abs() < 0.015, "k {k}");
        }
    }

    #[test]
    fn pairs_are_decorrelated() {
        // Padding: dimension 0 of pair 0 and of pair 1 are not the same stratum
        // order (their product's mean over a 64-point set is that of independent
        // uniforms, not of equal ones, 1/3).
        let mut sum = 0.0;
        let (sets, n) = (200u64, 64u32);
        for seed in 0..sets {
            for k in 0..n {
                sum += unit(padded_pair(seeds(seed, 0), k).0) * unit(padded_pair(seeds(seed, 1), k).0);
            }
        }
        let mean = sum / (sets * n as u64) as f64;
        assert!((mean - 0.25).abs() < 0.01, "mean {mean}");
    }
}
