//! The numbers the probe inspector shows, from the methods' results (no UI here):
//! per method the luminance of the chosen part with its gradient and Hessian, the
//! Hessian's eigen-decomposition and the cache extent the metric gives it
//! (`core::metric`: the paper's ellipse for methods with a Hessian, the Jarosz 2008
//! circle for the unaware method), and the incoming radiance binned over angle.

use super::compute::{Incoming, ReferenceResult};
use crate::core::metric::{Extent, MetricParams, first_order_extent, second_order_extent};
use crate::core::space::{D2, Space};
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
type PartDerivs = crate::pipeline::derivatives::PartDerivs<crate::core::space::D2>;
use crate::flatland::scene_desc::Part;
use glam::{DMat2, DVec2};
use std::f64::consts::{PI, TAU};

pub fn part_of(p: &PartDerivs, part: Part) -> TaylorRgb<D2> {
    match part {
        Part::All => p.total(),
        Part::Direct => p.direct,
        Part::Single => p.single,
        Part::Multiple => p.multiple,
    }
}

/// One method's column of the inspector table.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodReadout {
    pub name: &'static str,
    /// Luminance of the part with its derivatives (Hessian zero without one).
    pub lum: Taylor2<D2>,
    pub has_hessian: bool,
    /// Ascending eigenvalues and their unit eigenvectors (columns).
    pub eigenvalues: DVec2,
    pub eigenvectors: DMat2,
    pub extent: Extent<D2>,
    /// Per radius: held at the metric's "r_min" or "r_max" (theory.md §7), if so.
    pub clamped: [Option<&'static str>; 2],
    /// Standard errors (the reference's batches), if known.
    pub stderr: Option<StdErrors>,
}

/// Standard errors of the mean over independent batches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StdErrors {
    pub value: f64,
    pub grad: DVec2,
    /// H_xx, H_xy, H_yy.
    pub hess: [f64; 3],
    /// Of the sorted eigenvalues (from their spread over batches).
    pub eigenvalues: DVec2,
}

impl MethodReadout {
    pub fn new(name: &'static str, parts: &PartDerivs, has_hessian: bool, part: Part, metric: &MetricParams) -> Self {
        let lum = part_of(parts, part).luminance();
        let (eigenvalues, eigenvectors) = D2::sym_eigen(lum.hess);
        let extent = if has_hessian {
            second_order_extent::<D2>(lum.value, lum.hess, lum.grad, metric)
        } else {
            first_order_extent::<D2>(lum.value, lum.grad, metric)
        };
        let at = |r: f64, bound: f64| (r - bound).abs() <= 1e-9 * bound;
        let clamped = [extent.radii.x, extent.radii.y].map(|r| {
            if at(r, metric.r_max) {
                Some("r_max")
            } else if at(r, metric.r_min) {
                Some("r_min")
            } else {
                None
            }
        });
        MethodReadout {
            name,
            lum,
            has_hessian,
            eigenvalues,
            eigenvectors,
            extent,
            clamped,
            stderr: None,
        }
    }

    /// The reference: the batches' mean, with standard errors from their spread.
    pub fn reference(r: &ReferenceResult, part: Part, metric: &MetricParams) -> Self {
        let mut out = Self::new("reference", &r.mean(), true, part, metric);
        let n = r.batches.len();
        if n >= 2 {
            let l: Vec<Taylor2<D2>> = r.batches.iter().map(|b| part_of(b, part).luminance()).collect();
            let eig: Vec<DVec2> = l.iter().map(|t| D2::sym_eigen(t.hess).0).collect();
            let se = |f: &dyn Fn(usize) -> f64| {
                let m = (0..n).map(f).sum::<f64>() / n as f64;
                ((0..n).map(|k| (f(k) - m).powi(2)).sum::<f64>() / ((n - 1) * n) as f64).sqrt()
            };
            out.stderr = Some(StdErrors {
                value: se(&|k| l[k].value),
                grad: DVec2::new(se(&|k| l[k].grad.x), se(&|k| l[k].grad.y)),
                hess: [
                    se(&|k| l[k].hess.x_axis.x),
                    se(&|k| l[k].hess.y_axis.x),
                    se(&|k| l[k].hess.y_axis.y),
                ],
                eigenvalues: DVec2::new(se(&|k| eig[k].x), se(&|k| eig[k].y)),
            });
        }
        out
    }

    /// The Hessian is not known from its estimate: some eigenvalue's standard error
    /// is as large as the eigenvalue (the reference's batches disagree on its sign
    /// or size), so its ellipse says little about the true extent.
    pub fn hessian_is_noise(&self) -> bool {
        self.stderr
            .is_some_and(|e| (0..2).any(|k| e.eigenvalues[k] >= self.eigenvalues[k].abs() || e.eigenvalues[k].is_nan()))
    }

    pub fn is_finite(&self) -> bool {
        self.lum.is_finite() && self.eigenvalues.is_finite() && self.extent.radii.is_finite()
    }
}

/// Incoming radiance averaged over `bins` equal angular bins starting at angle 0:
/// (surface, medium) per bin; empty bins are zero.
pub fn polar_bins(incoming: &[Incoming], bins: usize) -> Vec<(f64, f64)> {
    let bins = bins.max(1);
    let mut sum = vec![(0.0, 0.0, 0usize); bins];
    for r in incoming {
        let a = r.angle.rem_euclid(TAU);
        let k = ((a / TAU * bins as f64) as usize).min(bins - 1);
        sum[k].0 += r.surface;
        sum[k].1 += r.medium;
        sum[k].2 += 1;
    }
    sum.into_iter()
        .map(|(s, m, c)| {
            if c == 0 {
                (0.0, 0.0)
            } else {
                (s / c as f64, m / c as f64)
            }
        })
        .collect()
}

/// Centre angle of bin k of `bins`.
pub fn bin_angle(k: usize, bins: usize) -> f64 {
    (k as f64 + 0.5) / bins as f64 * TAU
}

/// Points of an extent's outline around `center` (world units).
pub fn extent_outline(center: DVec2, e: &Extent<D2>, n: usize) -> Vec<DVec2> {
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64 * 2.0 * PI;
            center + e.axes.x_axis * (e.radii.x * t.cos()) + e.axes.y_axis * (e.radii.y * t.sin())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::color::Rgb;

    fn parts(value: f64, grad: DVec2, hess: DMat2) -> PartDerivs {
        PartDerivs {
            single: TaylorRgb::tint(Taylor2::new(value, grad, hess), Rgb::ONE),
            ..Default::default()
        }
    }

    #[test]
    fn readout_has_eigenvalues_and_an_ellipse_along_them() {
        let m = MetricParams::scene_relative(2.0, 0.05);
        let h = DMat2::from_cols(DVec2::new(-8.0, 0.0), DVec2::new(0.0, -0.5));
        let r = MethodReadout::new("aware", &parts(1.0, DVec2::ZERO, h), true, Part::All, &m);
        assert!((r.eigenvalues - DVec2::new(-8.0, -0.5)).length() < 1e-9);
        // The strongly curved axis (x, λ = −8) gets the shorter radius.
        let rx = r.extent.radii.x;
        assert!(
            r.extent.axes.x_axis.x.abs() > 0.99 && rx < r.extent.radii.y,
            "{:?}",
            r.extent
        );
        assert!(r.is_finite());
        // Unaware: a circle from the gradient.
        let u = MethodReadout::new("unaware", &parts(1.0, DVec2::new(3.0, 4.0), h), false, Part::Single, &m);
        assert!(u.extent.is_isotropic());
        assert_eq!((r.clamped, u.clamped), ([None, Some("r_max")], [None, None]));
        assert!((u.extent.radii.x - 0.05 / 5.0).abs() < 1e-12);
        // The part that is zero reads zero.
        let d = MethodReadout::new("aware", &parts(1.0, DVec2::X, h), true, Part::Direct, &m);
        assert_eq!(d.lum.value, 0.0);
    }

    #[test]
    fn reference_standard_errors_come_from_the_batches() {
        let m = MetricParams::scene_relative(2.0, 0.05);
        let r = ReferenceResult {
            batches: vec![
                parts(1.0, DVec2::new(1.0, 0.0), DMat2::ZERO),
                parts(3.0, DVec2::new(3.0, 0.0), DMat2::ZERO),
            ],
            planned: 2,
            spp_per_batch: 1,
            rays: 0,
            seconds: 0.0,
        };
        let o = MethodReadout::reference(&r, Part::All, &m);
        assert!((o.lum.value - 2.0).abs() < 1e-12);
        // Sample sd √2 over √2 batches: 1.
        let se = o.stderr.unwrap();
        assert!((se.value - 1.0).abs() < 1e-12);
        assert!((se.grad - DVec2::new(1.0, 0.0)).length() < 1e-12);
        assert_eq!(se.hess, [0.0; 3]);
    }

    #[test]
    fn polar_bins_average_per_angle() {
        let inc = [
            Incoming {
                angle: 0.1,
                surface: 1.0,
                medium: 0.5,
            },
            Incoming {
                angle: 0.2,
                surface: 3.0,
                medium: 0.5,
            },
            Incoming {
                angle: -0.1,
                surface: 7.0,
                medium: 0.0,
            },
        ];
        let b = polar_bins(&inc, 4);
        assert_eq!(b, vec![(2.0, 0.5), (0.0, 0.0), (0.0, 0.0), (7.0, 0.0)]);
        assert!((bin_angle(0, 4) - PI / 4.0).abs() < 1e-12);
        let e = Extent::<D2>::isotropic(2.0);
        let o = extent_outline(DVec2::ONE, &e, 8);
        assert!(o.iter().all(|p| ((*p - DVec2::ONE).length() - 2.0).abs() < 1e-12));
    }
}
