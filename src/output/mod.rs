//! Output files: PNG figures, EXR radiance fields, JSON records.
//!
//! Every writer goes through [`write_atomic`]: the bytes are written to a temporary
//! file beside the destination and renamed over it, so an interrupted run (Ctrl-C,
//! a crash, a full disk) never leaves a truncated file in place of a good one.
//! Errors name the path. The outputs of one run are checked against its inputs and
//! each other first ([`OutputPlan`]) and written as a set whose JSON summary, written
//! last, names every file with its hash ([`write_set`]).
//!
//! EXR files hold linear RGB as 32-bit floats (ZIP-compressed scanlines, lossless);
//! row 0 of a [`Field`] (its top row) is the EXR's first scanline, as image viewers
//! expect. Pixels where the field is undefined (`valid == false`) are written as 0.

mod plan;
mod set;
pub use plan::{OutputPlan, PlanError};
pub use set::{SetError, WrittenFile, clean_stale_temps, write_set};

use crate::flatland::field::Field;
use anyhow::{Context, anyhow};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Temporary files of concurrent writers in one process must not collide.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary file used while writing `path`: hidden, in the same directory
/// (so the final `rename` stays on one file system), unique per process and call.
/// The `.tmp` suffix keeps strays out of git (`.gitignore`).
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}-{n}.tmp", std::process::id()))
}

/// Write `bytes` to a new temporary file beside `path` (creating the parent
/// directories, and removing stale temporary files of dead writers there first);
/// returns its path. On failure nothing is left behind.
pub(crate) fn write_temp(path: &Path, bytes: &[u8]) -> std::io::Result<PathBuf> {
    if path.file_name().is_none() {
        return Err(std::io::Error::other("not a file path"));
    }
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)
        .map_err(|e| std::io::Error::other(format!("cannot create the directory {}: {e}", dir.display())))?;
    set::clean_stale_temps(dir);
    let tmp = temp_path(path);
    let written = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.flush()
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(std::io::Error::other(format!("cannot write: {e}")));
    }
    Ok(tmp)
}

/// Write `bytes` to `path` atomically: create the parent directories, write a
/// temporary file in the same directory, then rename it over `path`. On failure the
/// temporary file is removed and any previous `path` is left untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = write_temp(path, bytes).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    if let Err(e) = std::fs::rename(&tmp, path) {
        let _ = std::fs::remove_file(&tmp);
        return Err(anyhow!("{}: cannot replace the file: {e}", path.display()));
    }
    Ok(())
}

/// Encode a pixmap as PNG (8-bit sRGB RGBA) and write it atomically.
pub fn write_png(path: &Path, pixmap: &tiny_skia::Pixmap) -> anyhow::Result<()> {
    let bytes = pixmap
        .encode_png()
        .map_err(|e| anyhow!("{}: cannot encode the PNG: {e}", path.display()))?;
    write_atomic(path, &bytes)
}

/// A rendered image (row 0 on top) as the writers' [`Field`]; its world rectangle
/// is unused.
pub fn image_field(width: usize, height: usize, values: &[crate::core::color::Rgb]) -> Field {
    let mut f = Field::new(width, height, glam::DVec2::ZERO, glam::DVec2::ONE);
    f.values.copy_from_slice(values);
    f
}

/// Encode a field as a linear RGB float32 EXR in memory.
pub fn encode_exr(field: &Field) -> anyhow::Result<Vec<u8>> {
    use exr::prelude::*;
    let (w, h) = (field.width, field.height);
    if w == 0 || h == 0 || field.values.len() != w * h || field.valid.len() != w * h {
        return Err(anyhow!(
            "field of {w}×{h} pixels has {} values and {} validity flags",
            field.values.len(),
            field.valid.len()
        ));
    }
    // An EXR holds f32: a value outside its range would be written as inf (the
    // validated scene ranges keep radiance far below; this guards against a bug).
    if let Some(k) = (0..w * h).find(|&k| field.valid[k] && !fits_f32(field.values[k])) {
        return Err(anyhow!(
            "pixel ({}, {}) holds {:?}, outside the f32 range of an EXR",
            k % w,
            k / w,
            field.values[k].to_array()
        ));
    }
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let k = y * w + x;
        if field.valid[k] {
            let v = field.values[k];
            (v.x as f32, v.y as f32, v.z as f32)
        } else {
            (0.0f32, 0.0f32, 0.0f32)
        }
    });
    let attributes = LayerAttributes {
        software_name: Some(Text::from("volcache")),
        ..LayerAttributes::default()
    };
    let layer = Layer::new((w, h), attributes, Encoding::SMALL_LOSSLESS, channels);
    let image = Image::from_layer(layer);
    let mut cursor = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut cursor)
        .map_err(|e| anyhow!("cannot encode the EXR: {e}"))?;
    Ok(cursor.into_inner())
}

fn fits_f32(v: crate::core::color::Rgb) -> bool {
    v.to_array().iter().all(|c| c.is_finite() && c.abs() <= f32::MAX as f64)
}

/// Write a field as a linear RGB float32 EXR (row 0 = top scanline; invalid
/// pixels as 0), atomically.
pub fn write_exr(path: &Path, field: &Field) -> anyhow::Result<()> {
    let bytes = encode_exr(field).with_context(|| format!("{}", path.display()))?;
    write_atomic(path, &bytes)
}

/// Read the first RGB layer of an EXR: (width, height, row-major pixels, first row
/// = top scanline). Any sample type is converted to f32.
pub fn read_exr(path: &Path) -> anyhow::Result<(usize, usize, Vec<[f32; 3]>)> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| (size.width(), vec![[0.0f32; 3]; size.width() * size.height()]),
            |(w, pixels): &mut (usize, Vec<[f32; 3]>), Vec2(x, y), (r, g, b): (f32, f32, f32)| {
                pixels[y * *w + x] = [r, g, b]
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| anyhow!("{}: cannot read the EXR: {e}", path.display()))?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((size.width(), size.height(), pixels))
}

/// Write `value` as pretty-printed JSON (with a final newline), atomically.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    let mut bytes =
        serde_json::to_vec_pretty(value).with_context(|| format!("{}: cannot serialise the JSON", path.display()))?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::color::Rgb;
    use glam::DVec2;

    /// The names in a folder, sorted (the submodules' tests use it too).
    pub(super) fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn exr_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let mut f = Field::new(5, 3, DVec2::new(-1.0, -1.0), DVec2::new(1.0, 1.0));
        for j in 0..3 {
            for i in 0..5 {
                f.values[j * 5 + i] = Rgb::new(i as f64 + 0.25, j as f64 * 1e3, -0.5 + 1e-6 * (i + j) as f64);
            }
        }
        f.valid[7] = false;
        let path = dir.path().join("sub/field.exr");
        write_exr(&path, &f).unwrap();
        let (w, h, px) = read_exr(&path).unwrap();
        assert_eq!((w, h, px.len()), (5, 3, 15));
        for (k, p) in px.iter().enumerate() {
            let expect = if k == 7 { Rgb::ZERO } else { f.values[k] };
            let e = [expect.x as f32, expect.y as f32, expect.z as f32];
            assert_eq!(*p, e, "pixel {k}");
        }
        assert_eq!(entries(&dir.path().join("sub")), vec!["field.exr".to_string()]);
    }

    #[test]
    fn write_atomic_replaces_and_cleans_up() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a/b/out.json");
        write_atomic(&path, b"first version, longer").unwrap();
        write_json(&path, &serde_json::json!({"x": 1})).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "{\n  \"x\": 1\n}\n");
        assert_eq!(entries(path.parent().unwrap()), vec!["out.json".to_string()]);
    }

    #[test]
    fn failed_write_names_the_path_and_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        // The destination is a non-empty directory: rename must fail.
        let path = dir.path().join("taken");
        std::fs::create_dir(&path).unwrap();
        std::fs::write(path.join("keep"), b"x").unwrap();
        let err = write_atomic(&path, b"data").unwrap_err().to_string();
        assert!(err.contains("taken"), "{err}");
        assert_eq!(entries(dir.path()), vec!["taken".to_string()]);
        assert_eq!(std::fs::read(path.join("keep")).unwrap(), b"x");
    }

    #[test]
    fn png_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let mut pm = tiny_skia::Pixmap::new(4, 2).unwrap();
        pm.fill(tiny_skia::Color::from_rgba8(10, 20, 30, 255));
        let path = dir.path().join("x.png");
        write_png(&path, &pm).unwrap();
        let back = tiny_skia::Pixmap::load_png(&path).unwrap();
        assert_eq!(back.data(), pm.data());
    }
}
