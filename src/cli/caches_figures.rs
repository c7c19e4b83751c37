//! The figures `volcache caches` writes beside the field: the record distribution
//! and the error map against the reference.

use super::caches::MethodRun;
use super::common::wrote;
use std::path::Path;
use volcache::core::color::luminance;
use volcache::figure::{FieldStyle, field_figure};
use volcache::flatland::field::Field;
use volcache::flatland::scene::Scene;
use volcache::output::write_png;

/// |L_test − L_ref| (luminance) as a field, for error maps.
pub fn error_field(test: &Field, reference: &Field) -> Field {
    let mut e = test.clone();
    for (k, v) in e.values.iter_mut().enumerate() {
        *v = glam::DVec3::splat((luminance(test.values[k]) - luminance(reference.values[k])).abs());
        e.valid[k] = test.valid[k] && reference.valid[k];
    }
    e
}

pub fn write_cache_figures(dir: &Path, scene: &Scene, run: &MethodRun, reference: &Field) -> anyhow::Result<()> {
    let err = error_field(&run.field, reference);
    let style = FieldStyle::FalseColor { log: true, range: None };
    let rmse = run.errors.map_or(f64::NAN, |e| e.rmse);
    let png = dir.join("error.png");
    let title = format!("{:?}: |error|, RMSE {rmse:.3e}", run.method);
    wrote(&png, write_png(&png, &field_figure(&err, Some(scene), &style, Some(&title))))
}
