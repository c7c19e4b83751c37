//! What a path vertex does with light arriving from a direction ω (theory.md §1:
//! ω points *towards* where light comes from; it travels along −ω): value(ω) is the
//! factor multiplying L_i(ω) dω — the phase function, the BRDF times the cosine, or
//! one (plain integration, for fluence).

use super::dim::Dim;
use crate::core::color::Rgb;
use crate::core::phase::hg_of_mu;
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

/// ∇_travel ln f(travel, ω) of the HG phase (μ = travel·ω): (d ln f/dμ)(ω − μ·travel),
/// tangent to the unit sphere (circle) at `travel`. Zero for g = 0; finite for any
/// |g| < 1 (at most (d+1)|g|/(1 − |g|)² in length).
pub fn phase_log_slope<S: Dim>(phase: &S::Phase, travel: S::Vec, w: S::Vec) -> S::Vec {
    let g = S::phase_g(phase);
    if g == 0.0 {
        return S::zero();
    }
    let mu = S::dot(travel, w);
    let (f, df, _) = hg_of_mu::<S>(g, mu);
    if f > 0.0 {
        (w - travel * mu) * (df / f)
    } else {
        S::zero()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Sampler;
    use crate::core::space::{D2, D3};
    use crate::pipeline::path::estimate_with;
    use crate::pipeline::testing::{chi_square, chi_square_quantile};
    use std::f64::consts::PI;

    const SAMPLES: usize = 100_000;
    const RINGS: usize = 48;

    /// The lobes about `axis(0)` with the mean of ω·axis under their sampling pdf:
    /// HG's mean cosine is g (theory.md §1, both dimensions); the cosine lobe's is
    /// ∫cos² dθ/2 = π/4 on the circle and ∫cos² dω/π = 2/3 on the sphere.
    fn lobes<S: Dim>(axis: S::Vec) -> Vec<(String, Lobe<S>, f64)> {
        let mut v: Vec<(String, Lobe<S>, f64)> = [0.0, 0.5, -0.5, 0.99, -0.99]
            .into_iter()
            .map(|g| {
                let lobe = Lobe::Phase {
                    phase: S::phase(g),
                    travel: axis,
                };
                (format!("HG g = {g}"), lobe, g)
            })
            .collect();
        let cosine_mean = if S::DIM == 2 { PI / 4.0 } else { 2.0 / 3.0 };
        let lambert = Lobe::Lambert {
            normal: axis,
            reflectance: Rgb::new(0.2, 0.5, 0.9),
        };
        v.push(("cosine".into(), lambert, cosine_mean));
        v.push(("uniform".into(), Lobe::Uniform, 0.0));
        v
    }

    /// Every sample's pdf and value/pdf agree with `eval`, the sampled directions
    /// follow the pdf (χ² at the 10⁻⁴ level), the pdf integrates to one, and the mean
    /// cosine about the lobe's axis is the closed form for axes in any orientation.
    fn sampling_matches_the_pdf<S: Dim>() {
        for (k, (name, lobe, _)) in lobes::<S>(S::axis(0)).into_iter().enumerate() {
            let mut s = Sampler::new(17, k as u64);
            let dirs: Vec<S::Vec> = (0..SAMPLES)
                .map(|_| {
                    let (w, weight, pdf) = lobe.sample(&mut s);
                    let (value, pdf_eval) = lobe.eval(w);
                    assert!((S::length(w) - 1.0).abs() < 1e-12, "{name}: |ω| = {}", S::length(w));
                    assert!(
                        pdf > 0.0 && (pdf - pdf_eval).abs() <= 1e-9 * pdf_eval,
                        "{name}: pdf {pdf} vs {pdf_eval}"
                    );
                    let err = (weight * pdf - value).abs().max_element();
                    assert!(err <= 1e-9 * value.max_element(), "{name}: {weight}·{pdf} vs {value}");
                    w
                })
                .collect();
            let (chi2, dof, total) = chi_square::<S>(&dirs, |w| lobe.eval(w).1, RINGS);
            let limit = chi_square_quantile(dof, 3.72);
            eprintln!(
                "d = {}, {name}: χ² {chi2:.1} over {dof} dof (limit {limit:.1}), ∫pdf {total:.8}",
                S::DIM
            );
            assert!((total - 1.0).abs() < 1e-6, "{name}: ∫pdf = {total}");
            assert!(dof >= 10, "{name}: only {dof} degrees of freedom");
            assert!(chi2 < limit, "{name}: χ² = {chi2} over {dof} dof");
        }
        // Moments about random axes (the samplers build their own frames).
        for k in 0..7 {
            let (mean, se) = estimate_with(SAMPLES as u64, 23, k, |s| {
                let axis = S::sample_uniform(s);
                let (name, lobe, _) = lobes::<S>(axis).swap_remove(k as usize);
                let (w, _, _) = lobe.sample(s);
                assert!((S::length(w) - 1.0).abs() < 1e-12, "{name}");
                Rgb::splat(S::dot(w, axis))
            });
            let (name, _, want) = lobes::<S>(S::axis(0)).swap_remove(k as usize);
            eprintln!(
                "d = {}, {name}: mean cosine {:.5} ± {:.5} (want {want:.5})",
                S::DIM,
                mean.x,
                se.x
            );
            assert!(
                (mean.x - want).abs() < 4.0 * se.x && se.x < 0.01,
                "{name}: {} ± {} vs {want}",
                mean.x,
                se.x
            );
        }
    }

    /// f·`phase_log_slope` is the derivative of the phase with respect to the
    /// travel direction (central differences on the unit sphere, circle), for g up
    /// to ±0.99 and directions from forward to backward.
    fn phase_slope_is_the_phase_derivative<S: Dim>() {
        let mut s = Sampler::new(3, 1);
        for g in [0.0, 0.3, -0.5, 0.9, -0.99, 0.99] {
            let phase = S::phase(g);
            for _ in 0..200 {
                let (travel, w, axis) = (
                    S::sample_uniform(&mut s),
                    S::sample_uniform(&mut s),
                    S::sample_uniform(&mut s),
                );
                let h = 1e-6;
                let turned = |e: f64| {
                    let t = travel + axis * e;
                    S::phase_eval(&phase, t / S::length(t), w)
                };
                // The derivative along `axis` of f at travel normalised: the tangent part.
                let want = (turned(h) - turned(-h)) / (2.0 * h);
                let f = S::phase_eval(&phase, travel, w);
                let value = f * S::dot(phase_log_slope::<S>(&phase, travel, w), axis);
                let tol = 1e-5 * (f + want.abs()) / (1.0 - g.abs()).powi(2);
                assert!(
                    (value - want).abs() <= tol,
                    "d = {}, g = {g}: {value} vs {want}",
                    S::DIM
                );
            }
        }
    }

    #[test]
    fn phase_slope_is_the_phase_derivative_on_the_circle() {
        phase_slope_is_the_phase_derivative::<D2>();
    }

    #[test]
    fn phase_slope_is_the_phase_derivative_on_the_sphere() {
        phase_slope_is_the_phase_derivative::<D3>();
    }

    #[test]
    fn sampling_matches_the_pdf_on_the_circle() {
        sampling_matches_the_pdf::<D2>();
    }

    #[test]
    fn sampling_matches_the_pdf_on_the_sphere() {
        sampling_matches_the_pdf::<D3>();
    }
}
