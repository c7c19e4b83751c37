//! Deterministic random streams. Every estimator derives its stream from
//! (seed, item index), so results do not depend on thread count or scheduling
//! (pbrt-v4's rule: sampling depends only on the pixel and the sample index).

use rand::Rng;
use rand_pcg::Pcg64Mcg;

/// SplitMix64 finaliser: decorrelates nearby seeds and indices.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// FNV-1a: a stable hash of bytes (unlike std's, it does not change between Rust
/// versions), for keys of files that must match across runs.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A random stream for one work item (pixel, probe point, sample index...).
pub struct Sampler {
    rng: Pcg64Mcg,
    /// Draws handed out before the stream's own (a stratified sample's first
    /// dimensions, [`Sampler::stratified`]); `lead_next..lead_len` are left.
    lead: [f64; LEAD],
    lead_next: u8,
    lead_len: u8,
}

/// How many first draws of a stratified sample come from its Sobol' point: three
/// pairs, enough for one light sample and one lobe sample in 3D (pick, two
/// coordinates on a triangle; two angles).
pub const LEAD: usize = 6;

/// The largest f64 below 1.
const BELOW_ONE: f64 = 1.0 - f64::EPSILON / 2.0;

impl Sampler {
    /// The stream for item `index` of a computation seeded with `seed`.
    pub fn new(seed: u64, index: u64) -> Self {
        let hi = mix64(seed ^ mix64(index));
        let lo = mix64(hi ^ index.rotate_left(17) ^ 0xD1B5_4A32_D192_ED03);
        Sampler {
            rng: Pcg64Mcg::new(((hi as u128) << 64) | lo as u128),
            lead: [0.0; LEAD],
            lead_next: 0,
            lead_len: 0,
        }
    }

    /// Sample `k` of a stratified set for the item seeded with `seed` (for
    /// example a pixel's seed, drawn from its stream): its first [`LEAD`] draws
    /// are a padded, Owen-scrambled Sobol' point ([`super::sobol`]), so the set's
    /// samples spread over each pair of dimensions; later draws come from the
    /// sample's own stream. Each sample is still uniform: estimators stay
    /// unbiased and any sample count works.
    pub fn stratified(seed: u64, k: u32) -> Self {
        let mut s = Self::new(seed, k as u64);
        for pair in 0..LEAD / 2 {
            let h = |salt: u64| (mix64(seed ^ mix64(3 * pair as u64 + salt)) >> 32) as u32;
            let (a, b) = super::sobol::padded_pair([h(0), h(1), h(2)], k);
            // A random offset below 2^-32 keeps each draw uniform on [0, 1).
            // (Rounding may reach 1: clamp to the largest draw below it.)
            s.lead[2 * pair] = ((a as f64 + s.next_f64()) * (1.0 / 4_294_967_296.0)).min(BELOW_ONE);
            s.lead[2 * pair + 1] = ((b as f64 + s.next_f64()) * (1.0 / 4_294_967_296.0)).min(BELOW_ONE);
        }
        s.lead_len = LEAD as u8;
        s
    }

    /// 64 random bits (e.g. the seed of an item's stratified set).
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.rng.next_u64()
    }

    /// A stream for a sub-item (e.g. sample `k` of pixel `index`).
    pub fn new2(seed: u64, index: u64, sub: u64) -> Self {
        Self::new(mix64(seed ^ mix64(index)), sub)
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        if self.lead_next < self.lead_len {
            self.lead_next += 1;
            return self.lead[self.lead_next as usize - 1];
        }
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in [0, n), n > 0.
    #[inline]
    pub fn next_index(&mut self, n: usize) -> usize {
        ((self.next_f64() * n as f64) as usize).min(n.saturating_sub(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<f64> = (0..4).map(|_| Sampler::new(7, 3).next_f64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        let mut s1 = Sampler::new(7, 3);
        let mut s2 = Sampler::new(7, 4);
        assert_ne!(s1.next_f64(), s2.next_f64());
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut s = Sampler::new(1, 0);
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let u = s.next_f64();
            assert!((0.0..1.0).contains(&u));
            sum += u;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.003);
    }
}
