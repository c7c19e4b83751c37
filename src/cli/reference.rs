//! Reference fields for error measurements: converged path-traced fields, cached on
//! disk keyed by a hash of the scene and the parameters, so sweeps and comparisons
//! do not recompute them.

use super::common::ProgressUi;
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use volcache::flatland::field::{Field, FieldParams, render_field};
use volcache::flatland::scene::Scene;
use volcache::output::{encode_exr, read_exr, write_atomic, write_json};

/// How converged a reference is (written beside it and into result JSON).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceInfo {
    pub key: String,
    pub spp: u32,
    /// Mean over pixels of standard error / value (luminance): the reference's own
    /// relative noise.
    pub mean_relative_std_error: f64,
    /// Its RMS standard error (luminance), to compare with the errors it judges.
    pub rms_std_error: f64,
    pub seconds: f64,
    pub from_disk: bool,
}

use volcache::core::rng::fnv1a;

pub fn reference_key(scene: &Scene, fp: &FieldParams) -> String {
    let text = format!(
        "{}|{}",
        serde_json::to_string(&scene.desc).unwrap_or_default(),
        serde_json::to_string(fp).unwrap_or_default()
    );
    format!("{:016x}", fnv1a(text.as_bytes()))
}

/// The files (EXR, JSON) holding the reference for `fp` in `dir`.
pub fn reference_files(scene: &Scene, fp: &FieldParams, dir: &Path) -> (PathBuf, PathBuf) {
    let key = reference_key(scene, fp);
    (dir.join(format!("{key}.exr")), dir.join(format!("{key}.json")))
}

/// The reference field for `fp` (its spp is the reference's), from `dir` when it
/// is there, otherwise rendered (with a progress bar) and stored. Its values are
/// f32-rounded either way (the precision of the stored EXR).
pub fn reference_field(
    scene: &Scene,
    fp: &FieldParams,
    dir: &Path,
    quiet: bool,
) -> anyhow::Result<(Field, ReferenceInfo)> {
    let (exr, json) = reference_files(scene, fp, dir);
    let key = reference_key(scene, fp);
    if let (Ok((w, h, px)), Ok(text)) = (read_exr(&exr), std::fs::read_to_string(&json))
        && (w, h) == (fp.width, fp.height)
        && let Ok(mut info) = serde_json::from_str::<ReferenceInfo>(&text)
    {
        let mut field = Field::new(w, h, scene.domain_min, scene.domain_max);
        let q = fp.query();
        for (k, p) in px.iter().enumerate() {
            field.values[k] = glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            field.valid[k] = q.defined_at(scene, field.pixel_center(k % w, k / w));
        }
        info.from_disk = true;
        return Ok((field, info));
    }
    let ui = ProgressUi::new(
        &format!("reference {}x{} @ {} spp", fp.width, fp.height, fp.spp),
        !quiet,
    );
    let r = render_field(scene, fp, &ui.progress);
    ui.finish();
    let mut r = r.map_err(|_| anyhow::Error::from(volcache::progress::Cancelled))?;
    // The EXR stores f32: measure errors against exactly what a later run reads
    // back, so that RMSEs do not change once the reference comes from disk.
    volcache::output::round_to_f32(&mut r.field);
    let n = r.std_error.len().max(1) as f64;
    let info = ReferenceInfo {
        key: key.clone(),
        spp: fp.spp,
        mean_relative_std_error: r.mean_relative_error(),
        rms_std_error: (r.std_error.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
        seconds: r.seconds,
        from_disk: false,
    };
    write_atomic(&exr, &encode_exr(&r.field)?)
        .with_context(|| format!("caching the reference in {}", dir.display()))?;
    write_json(&json, &info)?;
    Ok((r.field, info))
}
