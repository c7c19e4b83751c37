//! The seeds of an experiment's parts, derived from the one seed the user gives, so
//! that the command line and the app draw the same streams and no two parts of an
//! experiment share one by accident.

use crate::core::rng::mix64;

/// The converged reference's seed: its own streams, independent of the method it
/// judges (a reference sharing the method's streams would share its noise).
pub fn reference_seed(seed: u64) -> u64 {
    seed ^ 0x5EED
}

/// Path tracing's seed when it is compared with the caches in 3D (not the streams
/// of the caches' camera rays).
pub fn pt_seed(seed: u64) -> u64 {
    seed ^ 0xB7
}

/// The seed of point `k` of the gradient study: grid points 0.., line points
/// 2³² + 0.., so the grid's size does not change the line's numbers.
pub fn point_seed(seed: u64, k: usize, on_line: bool) -> u64 {
    let index = k as u64 + if on_line { 1 << 32 } else { 0 };
    mix64(seed ^ mix64(index))
}

/// The seed of batch `b` (1, 2, …) of a finite-difference reference split into
/// independent batches (their spread estimates its noise).
pub fn reference_batch_seed(point_seed: u64, b: u64) -> u64 {
    mix64(point_seed ^ b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The values written into committed results and reproduced by `compare_command`.
    #[test]
    fn seeds_are_the_published_ones() {
        assert_eq!(reference_seed(7), 7 ^ 0x5EED);
        assert_eq!(pt_seed(1), 1 ^ 0xB7);
        assert_eq!(point_seed(3, 5, false), mix64(3 ^ mix64(5)));
        assert_eq!(point_seed(3, 5, true), mix64(3 ^ mix64(5 + (1 << 32))));
        assert_eq!(reference_batch_seed(9, 2), mix64(9 ^ 2));
    }
}
