//! The figures `volcache caches` writes beside the field: the record distribution
//! and the error map against the reference.

use super::common::png_bytes;
use std::path::{Path, PathBuf};
use volcache::figure::{RecordColor, RecordStyle, error_map_figure, records_figure};
use volcache::flatland::field::Field;
use volcache::flatland::scene::Scene;
use volcache::study::field_runs::MethodRun;

/// The error map and (when there are records) the record distribution, as PNG
/// files of `dir`.
pub fn cache_figures(
    dir: &Path,
    scene: &Scene,
    run: &MethodRun,
    reference: &Field,
) -> anyhow::Result<Vec<(PathBuf, Vec<u8>)>> {
    let rmse = run.errors.map_or(f64::NAN, |e| e.rmse);
    let png = dir.join("error.png");
    let title = format!("{:?}: |error|, RMSE {rmse:.3e}", run.method);
    let figure = error_map_figure(&run.field, reference, Some(scene), None, false, Some(&title));
    let mut files = vec![(png.clone(), png_bytes(&png, &figure)?)];
    if run.records > 0 {
        let png = dir.join("records.png");
        let style = RecordStyle::colored(RecordColor::ByRadius);
        let title = format!("{:?}", run.method);
        let figure = records_figure(Some(&run.field), scene, &run.all_records(), &style, Some(&title));
        files.push((png.clone(), png_bytes(&png, &figure)?));
    }
    Ok(files)
}
