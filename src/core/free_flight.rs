//! Free-flight sampling in a homogeneous medium, shared by the 2D and 3D path
//! tracers (pbrt-v4's rule: one routine walks every medium). The caller supplies
//! the pieces [t0, t1] of the ray inside the medium; chromatic media draw one
//! channel per flight and weight by the balance heuristic over the three channels'
//! pdfs, so every channel stays unbiased and weights stay bounded.

use super::color::Rgb;
use super::rng::Sampler;
use super::transmittance::transmittance;

/// Outcome of free-flight sampling along a ray up to the next surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Flight {
    /// A real scattering event at distance `t`; `weight` = T σ_s / pdf (per channel).
    Scatter { t: f64, weight: Rgb },
    /// The ray reaches the surface (or infinity); `weight` = T / P(pass).
    Pass { weight: Rgb },
}

/// Sample the next scattering event along a ray whose medium pieces are
/// `intervals` (increasing, within the distance to the next surface).
pub fn sample_flight(
    sigma_t: Rgb,
    sigma_s: Rgb,
    intervals: impl IntoIterator<Item = (f64, f64)>,
    s: &mut Sampler,
) -> Flight {
    let grey = sigma_t.x == sigma_t.y && sigma_t.y == sigma_t.z;
    let channel = if grey { 0 } else { s.next_index(3) };
    let sig_c = sigma_t[channel];
    let u = s.next_f64();
    // Medium length to travel; the drawn channel never scatters when σ_t = 0.
    let tau = if sig_c > 0.0 {
        -(1.0 - u).ln() / sig_c
    } else {
        f64::INFINITY
    };
    let mut walked = 0.0;
    for (a, b) in intervals {
        let len = b - a;
        if walked + len > tau {
            let weight = if grey {
                sigma_s / sigma_t
            } else {
                let tr = transmittance(sigma_t, tau);
                tr * sigma_s / ((sigma_t * tr).element_sum() / 3.0)
            };
            return Flight::Scatter {
                t: a + (tau - walked),
                weight,
            };
        }
        walked += len;
    }
    if grey {
        return Flight::Pass { weight: Rgb::ONE };
    }
    let tr = transmittance(sigma_t, walked);
    Flight::Pass {
        weight: tr / (tr.element_sum() / 3.0).max(f64::MIN_POSITIVE),
    }
}
