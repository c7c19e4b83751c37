//! The figures `volcache caches` writes beside the field: the record distribution
//! and the error map against the reference.

use super::common::wrote;
use std::path::Path;
use volcache::figure::{RecordColor, RecordStyle, error_map_figure, records_figure};
use volcache::flatland::field::Field;
use volcache::flatland::scene::Scene;
use volcache::output::write_png;
use volcache::study::field_runs::MethodRun;

pub fn write_cache_figures(dir: &Path, scene: &Scene, run: &MethodRun, reference: &Field) -> anyhow::Result<()> {
    let rmse = run.errors.map_or(f64::NAN, |e| e.rmse);
    let png = dir.join("error.png");
    let title = format!("{:?}: |error|, RMSE {rmse:.3e}", run.method);
    wrote(
        &png,
        write_png(
            &png,
            &error_map_figure(&run.field, reference, Some(scene), None, false, Some(&title)),
        ),
    )?;
    if run.records > 0 {
        let png = dir.join("records.png");
        let style = RecordStyle::colored(RecordColor::ByRadius);
        let title = format!("{:?}", run.method);
        wrote(
            &png,
            write_png(
                &png,
                &records_figure(Some(&run.field), scene, &run.all_records(), &style, Some(&title)),
            ),
        )?;
    }
    Ok(())
}
