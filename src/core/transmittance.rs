//! Homogeneous transmittance T(d) = exp(-σ_t d) (theory.md §1), per RGB channel.

use super::color::Rgb;

/// Transmittance over a length `d` of a homogeneous medium with extinction `sigma_t`.
#[inline]
pub fn transmittance(sigma_t: Rgb, d: f64) -> Rgb {
    let tau = sigma_t * d.max(0.0);
    Rgb::new((-tau.x).exp(), (-tau.y).exp(), (-tau.z).exp())
}
