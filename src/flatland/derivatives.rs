//! Derivative methods for L_s at a medium point (theory.md §4–5), per part:
//! - `aware`: value, gradient and Hessian from the occlusion-free proxy elements
//!   (the paper's method, [`super::proxy`]);
//! - `unaware`: value and gradient as Jarosz et al. 2008 (directions and the
//!   along-ray parametrisation fixed, visibility and measure ignored);
//! - `reference`: central finite differences of the path-traced L_s with common
//!   random numbers (the same streams at every stencil point).

use super::scene::Scene;
use super::transport::{Estimate, Query, Settings, estimate};
use crate::core::color::Rgb;
use crate::core::space::D2;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use glam::{DMat2, DVec2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// L_s with its derivatives, per part (theory.md §2).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PartDerivs {
    pub direct: TaylorRgb<D2>,
    pub single: TaylorRgb<D2>,
    pub multiple: TaylorRgb<D2>,
}

impl PartDerivs {
    pub fn total(&self) -> TaylorRgb<D2> {
        self.direct + self.single + self.multiple
    }

    pub fn is_finite(&self) -> bool {
        self.direct.is_finite() && self.single.is_finite() && self.multiple.is_finite()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Occlusion-aware value, gradient and Hessian from proxy elements (ours).
    Aware,
    /// Occlusion-unaware value and gradient (Jarosz et al. 2008).
    Unaware,
    /// Central finite differences of path-traced L_s with common random numbers.
    Reference,
}

/// A method's answer at one point and what it cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Derivatives {
    pub method: Method,
    pub at: DVec2,
    pub parts: PartDerivs,
    /// False for first-order methods (the Hessian fields are zero).
    pub has_hessian: bool,
    pub rays: u64,
    pub seconds: f64,
}

/// Finite-difference reference settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReferenceSettings {
    /// Samples per stencil point.
    pub spp: u32,
    /// Step h as a fraction of the scene size (domain diagonal).
    pub relative_step: f64,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            spp: 20_000,
            relative_step: 4e-3,
        }
    }
}

/// Central differences of the estimated L_s at x: 9-point stencil (±h on each axis
/// for gradient and diagonal, the 4 diagonal points for the mixed term), every
/// point with the same random streams.
pub fn reference(
    scene: &Scene,
    x: DVec2,
    omega_o: DVec2,
    rs: &ReferenceSettings,
    settings: &Settings,
    seed: u64,
) -> Derivatives {
    let start = std::time::Instant::now();
    let h = rs.relative_step * scene.scale();
    let offsets = [
        (0, 0),
        (1, 0),
        (-1, 0),
        (0, 1),
        (0, -1),
        (1, 1),
        (1, -1),
        (-1, 1),
        (-1, -1),
    ];
    let q = Query::InScattered { omega_o };
    let est: Vec<Estimate> = offsets
        .par_iter()
        .map(|&(i, j)| {
            let p = x + DVec2::new(i as f64, j as f64) * h;
            estimate(scene, p, &q, settings, rs.spp, seed, 0)
        })
        .collect();
    let rays = est.iter().map(|e| e.rays).sum();
    let part = |get: &dyn Fn(&Estimate) -> Rgb| -> TaylorRgb<D2> {
        let v: Vec<Rgb> = est.iter().map(get).collect();
        let channel = |c: usize| {
            let f = |k: usize| v[k][c];
            let grad = DVec2::new(f(1) - f(2), f(3) - f(4)) / (2.0 * h);
            let hxx = (f(1) - 2.0 * f(0) + f(2)) / (h * h);
            let hyy = (f(3) - 2.0 * f(0) + f(4)) / (h * h);
            let hxy = (f(5) - f(6) - f(7) + f(8)) / (4.0 * h * h);
            Taylor2::new(f(0), grad, DMat2::from_cols_array(&[hxx, hxy, hxy, hyy]))
        };
        TaylorRgb {
            channels: [channel(0), channel(1), channel(2)],
        }
    };
    let parts = PartDerivs {
        direct: part(&|e| e.mean.direct),
        single: part(&|e| e.mean.single),
        multiple: part(&|e| e.mean.multiple),
    };
    Derivatives {
        method: Method::Reference,
        at: x,
        parts,
        has_hessian: true,
        rays,
        seconds: start.elapsed().as_secs_f64(),
    }
}
