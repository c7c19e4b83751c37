//! Russian roulette on a path's throughput, shared by the 2D and 3D path tracers.

use super::color::Rgb;
use super::rng::Sampler;

/// Continue with probability min(1, max channel of `beta`), reweighting survivors.
/// Returns false when the path ends.
#[inline]
pub fn survives(beta: &mut Rgb, s: &mut Sampler) -> bool {
    let q = beta.max_element();
    if q < 1.0 {
        if s.next_f64() >= q {
            return false;
        }
        *beta /= q;
    }
    true
}
