//! The gradient study (the paper's gradient figure, `volcache figure gradients`):
//! at the centres of an N × N grid over the scene's domain and at M points along a
//! line, the luminance of L_s with its gradient (and Hessian) by ours (aware),
//! Jarosz 2008 (unaware) and the finite-difference reference, per scattering part.
//!
//! - aware and unaware share one light field per point ([`aware_and_unaware`]);
//! - the reference is the mean of two independent batches at half the samples each
//!   (the cost of one run), and half their difference, |∇₁ − ∇₂| / 2, estimates its
//!   own RMS error, so a method's error can be told from the reference's noise;
//! - every point's streams derive from the seed and the point's index
//!   ([`point_seed`]), so results do not depend on the thread count.
//!
//! [`super::gradient_summary`] summarises the errors against the reference.

use super::light_field_derivs::{aware_and_unaware, mean_parts, reference_batch};
use super::seeds::point_seed;
use crate::core::space::D2;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use crate::flatland::scene::Scene;
use crate::pipeline::derivatives::{AwareSettings, ReferenceSettings};
use crate::pipeline::probe::{Outgoing, ProbeSettings};
use crate::pipeline::world::World;
use crate::progress::{Cancelled, Progress};
use glam::{DMat2, DVec2};
use rayon::prelude::*;
use serde::Serialize;

type PartDerivs = crate::pipeline::derivatives::PartDerivs<D2>;

/// The methods in panel order: (key, caption).
pub const METHODS: [(&str, &str); 3] = [
    ("aware", "ours (aware)"),
    ("unaware", "Jarosz 2008 (unaware)"),
    ("reference", "reference (finite differences)"),
];

/// A segment in world units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    pub from: DVec2,
    pub to: DVec2,
}

fn part_of(p: &PartDerivs, key: &str) -> TaylorRgb<D2> {
    match key {
        "direct" => p.direct,
        "single" => p.single,
        "multiple" => p.multiple,
        _ => p.total(),
    }
}

/// Luminance value, gradient and (if the method has one) Hessian of one part.
#[derive(Serialize, Clone, Copy, Debug)]
pub struct TaylorOut {
    pub value: f64,
    pub gradient: [f64; 2],
    /// Row-major; None for first-order methods.
    pub hessian: Option<[[f64; 2]; 2]>,
}

impl TaylorOut {
    fn new(t: &Taylor2<D2>, hessian: bool) -> Self {
        let h: DMat2 = t.hess;
        TaylorOut {
            value: t.value,
            gradient: t.grad.to_array(),
            // Symmetric, so columns and rows agree; written row-major anyway.
            hessian: hessian.then_some([[h.x_axis.x, h.y_axis.x], [h.x_axis.y, h.y_axis.y]]),
        }
    }

    pub fn grad(&self) -> DVec2 {
        DVec2::from_array(self.gradient)
    }
}

/// One method's answer at a point, per part (luminance).
#[derive(Serialize, Clone, Copy, Debug)]
pub struct MethodOut {
    pub direct: TaylorOut,
    pub single: TaylorOut,
    pub multiple: TaylorOut,
    pub total: TaylorOut,
}

impl MethodOut {
    fn new(p: &PartDerivs, hessian: bool) -> Self {
        let f = |k| TaylorOut::new(&part_of(p, k).luminance(), hessian);
        MethodOut {
            direct: f("direct"),
            single: f("single"),
            multiple: f("multiple"),
            total: f("total"),
        }
    }

    pub fn part(&self, key: &str) -> &TaylorOut {
        match key {
            "direct" => &self.direct,
            "single" => &self.single,
            "multiple" => &self.multiple,
            _ => &self.total,
        }
    }
}

/// |∇₁ − ∇₂| / 2 of the reference's two half-sample runs, per part: an estimate of
/// the RMS error of the reference gradient (a one-sample estimate: noisy itself).
#[derive(Serialize, Clone, Copy, Debug)]
pub struct NoiseOut {
    pub single: f64,
    pub multiple: f64,
    pub total: f64,
}

impl NoiseOut {
    pub fn part(&self, key: &str) -> f64 {
        match key {
            "single" => self.single,
            "multiple" => self.multiple,
            _ => self.total,
        }
    }
}

/// What a point cost (or, summed, the whole study).
#[derive(Serialize, Clone, Copy, Debug, Default)]
pub struct CostOut {
    /// Light field capture (shared by aware and unaware).
    pub capture_rays: u64,
    pub capture_seconds: f64,
    /// Proxy construction and evaluation of the aware derivatives.
    pub aware_seconds: f64,
    pub unaware_seconds: f64,
    pub reference_rays: u64,
    pub reference_seconds: f64,
}

impl CostOut {
    /// The costs of `points`, summed in order.
    pub fn total<'a>(points: impl Iterator<Item = &'a PointOut> + Clone) -> CostOut {
        let sum = |f: fn(&CostOut) -> f64| points.clone().map(|p| f(&p.cost)).sum::<f64>();
        CostOut {
            capture_rays: points.clone().map(|p| p.cost.capture_rays).sum(),
            capture_seconds: sum(|c| c.capture_seconds),
            aware_seconds: sum(|c| c.aware_seconds),
            unaware_seconds: sum(|c| c.unaware_seconds),
            reference_rays: points.clone().map(|p| p.cost.reference_rays).sum(),
            reference_seconds: sum(|c| c.reference_seconds),
        }
    }
}

/// Everything computed at one point.
#[derive(Serialize, Clone, Debug)]
pub struct PointOut {
    /// Position along the line in [0, 1] (line points only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub s: Option<f64>,
    pub at: [f64; 2],
    pub inside_medium: bool,
    /// The seed all of this point's streams derive from.
    pub seed: u64,
    pub aware: Option<MethodOut>,
    pub unaware: Option<MethodOut>,
    pub reference: Option<MethodOut>,
    pub reference_gradient_noise: Option<NoiseOut>,
    pub cost: CostOut,
}

impl PointOut {
    pub fn method(&self, key: &str) -> Option<&MethodOut> {
        match key {
            "aware" => self.aware.as_ref(),
            "unaware" => self.unaware.as_ref(),
            _ => self.reference.as_ref(),
        }
    }
}

/// Settings shared by all points of a study.
#[derive(Clone, Debug)]
pub struct GradientStudy<'a> {
    pub scene: &'a Scene,
    /// The direction L_s leaves towards.
    pub omega_o: DVec2,
    pub ps: ProbeSettings,
    pub aw: AwareSettings,
    /// Finite-difference step of the reference, a fraction of the scene size.
    pub relative_step: f64,
}

fn half_difference(a: &PartDerivs, b: &PartDerivs, key: &str) -> f64 {
    0.5 * (part_of(a, key).luminance().grad - part_of(b, key).luminance().grad).length()
}

impl GradientStudy<'_> {
    /// The three methods at `x` (the reference with `ref_spp` samples per stencil
    /// point in all); `seed` is the point's own. Outside the medium, where L_s is
    /// undefined, nothing is computed.
    pub fn point(
        &self,
        x: DVec2,
        s: Option<f64>,
        seed: u64,
        ref_spp: u32,
        progress: &Progress,
    ) -> Result<PointOut, Cancelled> {
        progress.check()?;
        let mut out = PointOut {
            s,
            at: x.to_array(),
            inside_medium: self.scene.medium_at(x).is_some(),
            seed,
            aware: None,
            unaware: None,
            reference: None,
            reference_gradient_noise: None,
            cost: CostOut::default(),
        };
        if !out.inside_medium {
            return Ok(out);
        }
        let dir = Outgoing::Direction(self.omega_o);
        let shared = aware_and_unaware(self.scene, x, dir, &self.ps, &self.aw, seed, progress)?;
        out.cost.capture_rays = shared.light_field.cost_rays;
        out.cost.capture_seconds = shared.light_field.seconds;
        out.cost.aware_seconds = shared.aware_seconds;
        out.cost.unaware_seconds = shared.unaware_seconds;
        let (aware, unaware) = (shared.aware, shared.unaware);
        drop(shared);
        progress.check()?;

        // Two independent halves: their mean is the reference, their spread its noise.
        let rs = ReferenceSettings {
            spp: ref_spp.div_ceil(2).max(1),
            relative_step: self.relative_step,
        };
        let r = [1u64, 2].map(|b| reference_batch(self.scene, x, dir, &rs, &self.ps.settings, seed, b));
        let reference = mean_parts(&[r[0].parts, r[1].parts]);
        out.cost.reference_rays = r.iter().map(|d| d.rays).sum();
        out.cost.reference_seconds = r.iter().map(|d| d.seconds).sum();

        out.aware = Some(MethodOut::new(&aware, true));
        out.unaware = Some(MethodOut::new(&unaware, false));
        out.reference = Some(MethodOut::new(&reference, true));
        let noise = |key| half_difference(&r[0].parts, &r[1].parts, key);
        out.reference_gradient_noise = Some(NoiseOut {
            single: noise("single"),
            multiple: noise("multiple"),
            total: noise("total"),
        });
        Ok(out)
    }

    /// Every point of the study, in parallel: the line's points (with `line_ref_spp`
    /// reference samples) and the grid's (`ref_spp`), each on the streams of
    /// [`point_seed`]. Progress counts points; a cancel returns `Cancelled`.
    pub fn run(
        &self,
        grid: &[DVec2],
        line: &[(f64, DVec2)],
        seed: u64,
        ref_spp: u32,
        line_ref_spp: u32,
        progress: &Progress,
    ) -> Result<(Vec<PointOut>, Vec<PointOut>), Cancelled> {
        progress.start((grid.len() + line.len()) as u64);
        // Line first: few points, shown closely; then the grid.
        let tasks: Vec<(bool, usize, Option<f64>, DVec2)> = line
            .iter()
            .enumerate()
            .map(|(k, &(s, x))| (true, k, Some(s), x))
            .chain(grid.iter().enumerate().map(|(k, &x)| (false, k, None, x)))
            .collect();
        let mut points = tasks
            .par_iter()
            .map(|&(on_line, k, s, x)| {
                let spp = if on_line { line_ref_spp } else { ref_spp };
                let r = self.point(x, s, point_seed(seed, k, on_line), spp, progress);
                progress.advance(1);
                r
            })
            .collect::<Result<Vec<PointOut>, Cancelled>>()?;
        progress.check()?;
        let grid_points = points.split_off(line.len());
        Ok((grid_points, points))
    }
}

/// Cell centres of an n × n grid over the domain, row by row from the bottom.
pub fn grid_points(scene: &Scene, n: usize) -> Vec<DVec2> {
    let (lo, size) = (scene.domain_min, scene.domain_max - scene.domain_min);
    (0..n * n)
        .map(|k| lo + size * DVec2::new((k % n) as f64 + 0.5, (k / n) as f64 + 0.5) / n as f64)
        .collect()
}

/// m points from `line.from` to `line.to`, end points included, with their s ∈ [0, 1].
pub fn line_points(line: Line, m: usize) -> Vec<(f64, DVec2)> {
    (0..m)
        .map(|i| {
            let s = if m > 1 { i as f64 / (m - 1) as f64 } else { 0.5 };
            (s, line.from.lerp(line.to, s))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn study(scene: &Scene) -> GradientStudy<'_> {
        GradientStudy {
            scene,
            omega_o: DVec2::X,
            ps: ProbeSettings {
                rays: 32,
                steps: 2,
                ..ProbeSettings::default_for::<D2>()
            },
            aw: AwareSettings::default(),
            relative_step: 1e-2,
        }
    }

    #[test]
    fn grid_and_line_points() {
        let scene = Scene::default_scene();
        let g = grid_points(&scene, 2);
        let (lo, hi) = (scene.domain_min, scene.domain_max);
        assert_eq!(g[0], lo + 0.25 * (hi - lo));
        assert_eq!(g[3], lo + 0.75 * (hi - lo));
        let l = line_points(
            Line {
                from: DVec2::ZERO,
                to: DVec2::X,
            },
            3,
        );
        assert_eq!(l, [(0.0, DVec2::ZERO), (0.5, DVec2::new(0.5, 0.0)), (1.0, DVec2::X)]);
        assert_eq!(
            line_points(
                Line {
                    from: DVec2::ZERO,
                    to: DVec2::X
                },
                1
            ),
            [(0.5, DVec2::new(0.5, 0.0))]
        );
    }

    /// Points keep their order and seeds whatever the schedule, the line's numbers
    /// do not depend on the grid, and points outside the medium carry nothing.
    #[test]
    fn a_tiny_study_is_deterministic_and_complete() {
        let scene = Scene::default_scene();
        let st = study(&scene);
        let line = line_points(
            Line {
                from: DVec2::new(-0.8, 0.1),
                to: DVec2::new(0.8, 0.1),
            },
            3,
        );
        let p = Progress::new();
        let (grid, on_line) = st.run(&grid_points(&scene, 2), &line, 1, 4, 8, &p).unwrap();
        assert_eq!((grid.len(), on_line.len(), p.done()), (4, 3, 7));
        let (_, alone) = st.run(&[], &line, 1, 4, 8, &p).unwrap();
        // Everything but the timings.
        let json = |v: &[PointOut]| {
            let untimed: Vec<PointOut> = v
                .iter()
                .map(|p| PointOut {
                    cost: CostOut::default(),
                    ..p.clone()
                })
                .collect();
            serde_json::to_string(&untimed).unwrap()
        };
        assert_eq!(json(&alone), json(&on_line));
        for (k, pt) in on_line.iter().enumerate() {
            assert_eq!(pt.seed, point_seed(1, k, true));
            assert_eq!(pt.s, Some(line[k].0));
        }
        for pt in grid.iter().chain(&on_line) {
            let computed = pt.aware.is_some() && pt.unaware.is_some() && pt.reference.is_some();
            assert_eq!(computed, pt.inside_medium, "{pt:?}");
            assert_eq!(pt.reference_gradient_noise.is_some(), pt.inside_medium);
        }
        assert!(on_line.iter().any(|p| p.inside_medium));
        let total = CostOut::total(grid.iter().chain(&on_line));
        assert_eq!(
            total.capture_rays,
            grid.iter().chain(&on_line).map(|p| p.cost.capture_rays).sum::<u64>()
        );
        p.cancel();
        assert_eq!(st.run(&[], &line, 1, 4, 8, &p).err(), Some(Cancelled));
    }
}
