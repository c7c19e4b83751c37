//! Radiance fields over a grid of the scene's domain.

use crate::core::color::Rgb;
use glam::DVec2;

/// A W×H grid of RGB values over a world rectangle. Row 0 is the *top* row
/// (largest y); pixel (i, j) is centred at
/// x = min.x + (i + ½)·(max.x − min.x)/W,  y = max.y − (j + ½)·(max.y − min.y)/H.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub width: usize,
    pub height: usize,
    pub world_min: DVec2,
    pub world_max: DVec2,
    /// Row-major, `width * height` values.
    pub values: Vec<Rgb>,
    /// False where the quantity is not defined (L_s outside the medium): figures
    /// show the background and the scene there.
    pub valid: Vec<bool>,
}

impl Field {
    pub fn new(width: usize, height: usize, world_min: DVec2, world_max: DVec2) -> Self {
        let n = width * height;
        Field {
            width,
            height,
            world_min,
            world_max,
            values: vec![Rgb::ZERO; n],
            valid: vec![true; n],
        }
    }

    /// World position of the centre of pixel (i, j).
    pub fn pixel_center(&self, i: usize, j: usize) -> DVec2 {
        let size = self.world_max - self.world_min;
        DVec2::new(
            self.world_min.x + (i as f64 + 0.5) * size.x / self.width as f64,
            self.world_max.y - (j as f64 + 0.5) * size.y / self.height as f64,
        )
    }

    /// Continuous pixel coordinates (x right, y down) of a world point.
    pub fn world_to_pixel(&self, p: DVec2) -> DVec2 {
        let size = self.world_max - self.world_min;
        DVec2::new(
            (p.x - self.world_min.x) / size.x * self.width as f64,
            (self.world_max.y - p.y) / size.y * self.height as f64,
        )
    }

    pub fn get(&self, i: usize, j: usize) -> Rgb {
        self.values[j * self.width + i]
    }
}

use super::scene::Scene;
use super::scene_desc::{Part, Quantity};
use crate::core::color::luminance;
use crate::core::space::D2;
use crate::pipeline::path::{Query, Settings, estimate};
use crate::progress::{Cancelled, Progress};
use rayon::prelude::*;
use serde::Serialize;

/// Per pixel: value of the selected part, std error of its luminance, defined?, rays.
type PixelResult = (Rgb, f64, bool, u64);

/// What to render.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FieldParams {
    pub width: usize,
    pub height: usize,
    pub spp: u32,
    pub seed: u64,
    pub quantity: Quantity,
    pub part: Part,
    /// ω_o for L_s, as an angle in degrees.
    pub omega_o_deg: f64,
    pub settings: Settings,
}

impl FieldParams {
    /// The scene's own defaults (its `render` block).
    pub fn from_scene(scene: &Scene) -> Self {
        let r = &scene.desc.render;
        FieldParams {
            width: r.resolution[0] as usize,
            height: r.resolution[1] as usize,
            spp: r.spp,
            seed: r.seed,
            quantity: r.quantity,
            part: r.part,
            omega_o_deg: r.omega_o_deg,
            settings: Settings {
                max_depth: r.max_depth,
                ..Settings::default()
            },
        }
    }

    pub fn query(&self) -> Query<D2> {
        Query::from_quantity(self.quantity, DVec2::from_angle(self.omega_o_deg.to_radians()))
    }
}

/// A rendered field with what it cost and how noisy it is.
#[derive(Clone, Debug)]
pub struct RenderedField {
    pub field: Field,
    /// Per pixel standard error of the luminance of the selected part.
    pub std_error: Vec<f64>,
    pub rays: u64,
    pub seconds: f64,
}

impl RenderedField {
    /// RMS over pixels of the per-pixel standard error (luminance).
    pub fn rms_std_error(&self) -> f64 {
        let n = self.std_error.len().max(1) as f64;
        (self.std_error.iter().map(|e| e * e).sum::<f64>() / n).sqrt()
    }

    /// Mean over valid pixels of (standard error / max(value, small)) of luminance:
    /// how converged the field is.
    pub fn mean_relative_error(&self) -> f64 {
        let lum: Vec<f64> = self.field.values.iter().map(|v| luminance(*v)).collect();
        let floor = 1e-3 * lum.iter().cloned().fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let (sum, n) = lum
            .iter()
            .zip(&self.std_error)
            .zip(&self.field.valid)
            .filter(|(_, v)| **v)
            .fold((0.0, 0usize), |(s, n), ((l, e), _)| (s + e / l.max(floor), n + 1));
        if n == 0 { 0.0 } else { sum / n as f64 }
    }
}

/// Render the field of `params.quantity` over the scene's domain, one estimate per
/// pixel centre. Deterministic for a seed, whatever the thread count. Rows are the
/// unit of progress; cancellation is checked per pixel.
pub fn render_field(scene: &Scene, params: &FieldParams, progress: &Progress) -> Result<RenderedField, Cancelled> {
    let start = std::time::Instant::now();
    let (w, h) = (params.width, params.height);
    let mut field = Field::new(w, h, scene.domain_min, scene.domain_max);
    let q = params.query();
    progress.start(h as u64);
    let rows: Vec<Result<Vec<PixelResult>, Cancelled>> = (0..h)
        .into_par_iter()
        .map(|j| {
            let mut row = Vec::with_capacity(w);
            for i in 0..w {
                progress.check()?;
                let x = field.pixel_center(i, j);
                let valid = q.defined_at(scene, x);
                let e = estimate(
                    scene,
                    x,
                    &q,
                    &params.settings,
                    params.spp,
                    params.seed,
                    (j * w + i) as u64,
                );
                row.push((
                    e.mean.get(params.part),
                    luminance(e.std_error.get(params.part)),
                    valid,
                    e.rays,
                ));
            }
            progress.advance(1);
            Ok(row)
        })
        .collect();
    let mut std_error = Vec::with_capacity(w * h);
    let mut rays = 0;
    for (j, row) in rows.into_iter().enumerate() {
        for (i, (v, se, valid, r)) in row?.into_iter().enumerate() {
            field.values[j * w + i] = v;
            field.valid[j * w + i] = valid;
            std_error.push(se);
            rays += r;
        }
    }
    Ok(RenderedField {
        field,
        std_error,
        rays,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Errors of a field against a reference, over pixels valid in both (luminance).
pub use crate::core::stats::ImageErrors as FieldErrors;

/// RMSE, relMSE and max error of `test` against `reference` (same grid).
pub fn field_errors(test: &Field, reference: &Field) -> FieldErrors {
    assert_eq!(
        (test.width, test.height),
        (reference.width, reference.height),
        "fields must share a grid"
    );
    let pairs: Vec<(f64, f64)> = test
        .values
        .iter()
        .zip(&reference.values)
        .zip(test.valid.iter().zip(&reference.valid))
        .filter(|(_, (a, b))| **a && **b)
        .map(|((a, b), _)| (luminance(*a), luminance(*b)))
        .collect();
    FieldErrors::of_luminance_pairs(&pairs)
}
