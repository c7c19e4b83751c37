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

/// The reference field for `fp` (its spp is the reference's), from `dir` when it
/// is there, otherwise rendered (with a progress bar) and stored.
pub fn reference_field(
    scene: &Scene,
    fp: &FieldParams,
    dir: &Path,
    quiet: bool,
) -> anyhow::Result<(Field, ReferenceInfo)> {
    let key = reference_key(scene, fp);
    let exr: PathBuf = dir.join(format!("{key}.exr"));
    let json = dir.join(format!("{key}.json"));
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
    let r = r.map_err(|_| anyhow::anyhow!("cancelled"))?;
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
