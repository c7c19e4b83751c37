//! Reference images (3D): converged path-traced images with their medium part, kept
//! in the reference store ([`super::stored`]) between runs.

use super::stored::{read_image, read_info, store_key, write_image, write_info};
use crate::progress::Progress;
use crate::volume::render::{RenderParams, Rendered, render};
use crate::volume::scene::Scene;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The reference of `image`: the same scene view and size with `spp` samples and
/// the reference seed of its seed (its own streams, never the judged image's).
pub fn reference_params(image: &RenderParams, spp: u32) -> RenderParams {
    RenderParams {
        spp: spp.max(1),
        seed: super::seeds::reference_seed(image.seed),
        ..image.clone()
    }
}

/// How converged the reference is.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceInfo3d {
    pub key: String,
    pub spp: u32,
    pub seconds: f64,
    /// RMS per-pixel standard error over the mean luminance.
    pub relative_std_error: f64,
    pub from_disk: bool,
}

/// The medium part's entry beside the image's.
fn medium_name(key: &str) -> String {
    format!("{key}_medium")
}

/// A converged path-traced image of `params` (its spp and seed are the
/// reference's) from the store in `dir`, or rendered and stored. `progress` makes
/// the render's handle, given a label, only when there is a render.
pub fn reference_image<P: AsRef<Progress>>(
    scene: &Scene,
    params: &RenderParams,
    dir: &Path,
    progress: impl FnOnce(&str) -> P,
) -> anyhow::Result<(Rendered, ReferenceInfo3d)> {
    let key = store_key(&scene.desc, params);
    let [x0, y0, x1, y1] = params.window();
    let (w, h) = (x1 - x0, y1 - y0);
    if let Some(found) = stored_image(dir, &key, w, h) {
        return Ok(found);
    }
    let handle = progress(&format!("reference {} spp", params.spp));
    let img = render(scene, params, handle.as_ref());
    drop(handle);
    let img = img?;
    let info = ReferenceInfo3d {
        key: key.clone(),
        spp: img.spp,
        seconds: img.seconds,
        relative_std_error: img.relative_std_error(),
        from_disk: false,
    };
    write_image(dir, &key, w, h, &img.values, None)?;
    write_image(dir, &medium_name(&key), w, h, &img.medium, None)?;
    write_info(dir, &key, &info)?;
    Ok((img, info))
}

/// The stored image of `key` with its medium part, at full precision (its noise
/// and rays are not kept: a reference is only compared against).
fn stored_image(dir: &Path, key: &str, w: usize, h: usize) -> Option<(Rendered, ReferenceInfo3d)> {
    let mut info: ReferenceInfo3d = read_info(dir, key)?;
    let values = read_image(dir, key, w, h)?;
    let medium = read_image(dir, &medium_name(key), w, h)?;
    info.from_disk = true;
    let img = Rendered {
        width: w,
        height: h,
        values,
        medium,
        std_error: vec![0.0; w * h],
        spp: info.spp,
        rays: 0,
        seconds: info.seconds,
    };
    Some((img, info))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn a_stored_reference_image_comes_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let scene = Scene::load(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes3d/fog_box.json"))).unwrap();
        let params = RenderParams {
            width: 6,
            height: 4,
            spp: 2,
            ..RenderParams::from_scene(&scene)
        };
        let get = || reference_image(&scene, &params, dir.path(), |_| Arc::new(Progress::new())).unwrap();
        let (fresh, info) = get();
        let (back, info_back) = get();
        assert!(!info.from_disk && info_back.from_disk);
        assert_eq!((back.values, back.medium), (fresh.values, fresh.medium));
        assert_eq!((back.spp, info_back.key), (fresh.spp, info.key));
    }
}
