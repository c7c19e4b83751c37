//! Reference fields (2D) for error measurements: converged path-traced fields, kept
//! in the reference store ([`super::stored`]) so sweeps and comparisons do not
//! recompute them.

use super::stored::{entry_path, read_image, read_info, store_key, write_image, write_info};
use crate::flatland::field::{Field, FieldParams, render_field};
use crate::flatland::scene::Scene;
use crate::progress::Progress;
use serde::{Deserialize, Serialize};
use std::path::Path;

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

/// The files the store in `dir` holds for the reference of `fp` (full-precision
/// values, the EXR to look at, the JSON description): outputs of a run that may
/// render it, so they are checked against its inputs and other outputs.
pub fn reference_files(scene: &Scene, fp: &FieldParams, dir: &Path) -> Vec<std::path::PathBuf> {
    let key = store_key(&scene.desc, fp);
    ["rgb64", "exr", "json"].map(|ext| entry_path(dir, &key, ext)).to_vec()
}

/// The reference field for `fp` (its spp and seed are the reference's) from the
/// store in `dir`, or rendered and stored. `progress` makes the handle the render
/// reports to, given a label, only when there is a render (so the command line
/// shows a bar only then); it is dropped when the render ends.
pub fn reference_field<P: AsRef<Progress>>(
    scene: &Scene,
    fp: &FieldParams,
    dir: &Path,
    progress: impl FnOnce(&str) -> P,
) -> anyhow::Result<(Field, ReferenceInfo)> {
    let key = store_key(&scene.desc, fp);
    if let Some(found) = stored_field(scene, fp, dir, &key) {
        return Ok(found);
    }
    let handle = progress(&format!("reference {}x{} @ {} spp", fp.width, fp.height, fp.spp));
    let r = render_field(scene, fp, handle.as_ref());
    drop(handle);
    let r = r?;
    let n = r.std_error.len().max(1) as f64;
    let info = ReferenceInfo {
        key: key.clone(),
        spp: fp.spp,
        mean_relative_std_error: r.mean_relative_error(),
        rms_std_error: (r.std_error.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
        seconds: r.seconds,
        from_disk: false,
    };
    let f = &r.field;
    write_image(dir, &key, f.width, f.height, &f.values, Some(&f.valid))?;
    write_info(dir, &key, &info)?;
    Ok((r.field, info))
}

/// The stored field of `key`, exactly as rendered: its values at full precision,
/// and where it is defined recomputed as the render decides it.
fn stored_field(scene: &Scene, fp: &FieldParams, dir: &Path, key: &str) -> Option<(Field, ReferenceInfo)> {
    let mut info: ReferenceInfo = read_info(dir, key)?;
    let values = read_image(dir, key, fp.width, fp.height)?;
    let mut field = Field::new(fp.width, fp.height, scene.domain_min, scene.domain_max);
    let q = fp.query();
    for (k, v) in values.into_iter().enumerate() {
        field.values[k] = v;
        field.valid[k] = q.defined_at(scene, field.pixel_center(k % fp.width, k / fp.width));
    }
    info.from_disk = true;
    Some((field, info))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// A reference read back is the one rendered, bit for bit (values and where it
    /// is defined), and says it came from disk; other parameters miss the store.
    #[test]
    fn a_stored_reference_comes_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        // A medium over part of the domain: the field is undefined elsewhere.
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/flatland_scenes/windows.json");
        let scene = Scene::load(std::path::Path::new(path)).unwrap();
        let fp = FieldParams {
            width: 9,
            height: 7,
            spp: 2,
            ..FieldParams::from_scene(&scene)
        };
        let renders = std::cell::Cell::new(0);
        let get = |fp: &FieldParams| {
            reference_field(&scene, fp, dir.path(), |_| {
                renders.set(renders.get() + 1);
                Arc::new(Progress::new())
            })
            .unwrap()
        };
        let (fresh, info) = get(&fp);
        let (back, info_back) = get(&fp);
        assert!(!info.from_disk && info_back.from_disk);
        assert_eq!(back, fresh);
        assert!(fresh.valid.iter().any(|v| !v), "pixels outside the medium");
        assert_eq!((info_back.key, info_back.spp), (info.key, 2));
        let (_, other) = get(&FieldParams { seed: 2, ..fp.clone() });
        assert!(!other.from_disk);
        assert_eq!(renders.get(), 2, "a progress handle only for a render");
    }
}
