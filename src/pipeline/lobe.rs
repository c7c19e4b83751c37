//! What a path vertex does with light arriving from a direction ω (theory.md §1:
//! ω points *towards* where light comes from; it travels along −ω): value(ω) is the
//! factor multiplying L_i(ω) dω — the phase function, the BRDF times the cosine, or
//! one (plain integration, for fluence).

use super::dim::Dim;
use crate::core::color::Rgb;
use crate::core::rng::Sampler;

#[derive(Clone, Copy, Debug)]
pub enum Lobe<S: Dim> {
    /// Scattering in a medium; `travel` is the direction the path arrived along
    /// (value f(travel, ω); HG is symmetric).
    Phase { phase: S::Phase, travel: S::Vec },
    /// Lambertian reflection on the side with unit `normal`: ρ·max(0, n·ω)/(2 or π).
    Lambert { normal: S::Vec, reflectance: Rgb },
    /// Plain integration over all directions (fluence).
    Uniform,
}

impl<S: Dim> Lobe<S> {
    /// Value and sampling pdf (per unit angle or solid angle) of direction `w`.
    #[inline]
    pub fn eval(&self, w: S::Vec) -> (Rgb, f64) {
        match *self {
            Lobe::Phase { phase, travel } => {
                let f = S::phase_eval(&phase, travel, w);
                (Rgb::splat(f), f)
            }
            Lobe::Lambert { normal, reflectance } => {
                let c = S::lambert(S::dot(normal, w).max(0.0));
                (reflectance * c, c)
            }
            Lobe::Uniform => (Rgb::ONE, 1.0 / S::SPHERE_MEASURE),
        }
    }

    /// Sample a direction: (ω, value/pdf, pdf).
    #[inline]
    pub fn sample(&self, s: &mut Sampler) -> (S::Vec, Rgb, f64) {
        match *self {
            Lobe::Phase { phase, travel } => {
                let w = S::phase_sample(&phase, travel, s);
                (w, Rgb::ONE, S::phase_eval(&phase, travel, w))
            }
            Lobe::Lambert { normal, reflectance } => {
                let (w, pdf) = S::sample_cosine(normal, s);
                (w, reflectance, pdf)
            }
            Lobe::Uniform => (
                S::sample_uniform(s),
                Rgb::splat(S::SPHERE_MEASURE),
                1.0 / S::SPHERE_MEASURE,
            ),
        }
    }
}
