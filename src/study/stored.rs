//! Files of the reference store: converged references are expensive, so they are
//! kept on disk, named by a hash of the scene and the parameters that made them, and
//! read back by any later run with the same key.
//!
//! Per key: `<key>.json` (how converged the reference is), `<key>.rgb64` (the values
//! at full precision, read back) and `<key>.exr` (for viewers; f32). A reference
//! read back in f32 would judge a re-run against slightly different numbers than the
//! run that rendered it, so only the `.rgb64` file is read: an entry without one
//! (from before it existed) is rendered anew.
//!
//! `.rgb64` layout: the 8 bytes `VCRGB64\n`, width and height as little-endian u64,
//! then width × height × 3 little-endian f64, row-major, row 0 on top (as the EXR).

use crate::core::color::Rgb;
use crate::core::rng::fnv1a;
use crate::output::{encode_exr, image_field, write_atomic, write_json};
use anyhow::Context;
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"VCRGB64\n";
const HEADER: usize = MAGIC.len() + 16;

/// The store's key for a scene description and the parameters of its reference:
/// a stable hash (FNV-1a) of both as JSON.
pub fn store_key(desc: &impl Serialize, params: &impl Serialize) -> String {
    let text = format!(
        "{}|{}",
        serde_json::to_string(desc).unwrap_or_default(),
        serde_json::to_string(params).unwrap_or_default()
    );
    format!("{:016x}", fnv1a(text.as_bytes()))
}

/// `<dir>/<name>.<ext>`.
pub fn entry_path(dir: &Path, name: &str, ext: &str) -> PathBuf {
    dir.join(format!("{name}.{ext}"))
}

/// What `<dir>/<name>.json` says about the entry, if it is there and reads as a `T`.
pub fn read_info<T: DeserializeOwned>(dir: &Path, name: &str) -> Option<T> {
    let text = std::fs::read_to_string(entry_path(dir, name, "json")).ok()?;
    serde_json::from_str(&text).ok()
}

/// Write `<dir>/<name>.json`, atomically.
pub fn write_info(dir: &Path, name: &str, info: &impl Serialize) -> anyhow::Result<()> {
    write_json(&entry_path(dir, name, "json"), info)
}

/// The `.rgb64` bytes of a `width` × `height` image.
pub fn encode_rgb64(width: usize, height: usize, values: &[Rgb]) -> Vec<u8> {
    assert_eq!(values.len(), width * height, "an image of {width}×{height} values");
    let mut out = Vec::with_capacity(HEADER + 24 * values.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(width as u64).to_le_bytes());
    out.extend_from_slice(&(height as u64).to_le_bytes());
    for v in values {
        for c in v.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    out
}

/// An image from `.rgb64` bytes: (width, height, values); None when the bytes are
/// not one (wrong magic, or a length that does not match the size).
pub fn decode_rgb64(bytes: &[u8]) -> Option<(usize, usize, Vec<Rgb>)> {
    let rest = bytes.strip_prefix(MAGIC)?;
    let word = |k: usize| -> Option<u64> { Some(u64::from_le_bytes(rest.get(8 * k..8 * k + 8)?.try_into().ok()?)) };
    let (w, h) = (usize::try_from(word(0)?).ok()?, usize::try_from(word(1)?).ok()?);
    let data = &rest[16..];
    if w.checked_mul(h)?.checked_mul(24)? != data.len() {
        return None;
    }
    let f = |k: usize| f64::from_le_bytes(data[8 * k..8 * k + 8].try_into().expect("8 bytes"));
    Some((
        w,
        h,
        (0..w * h)
            .map(|p| Rgb::new(f(3 * p), f(3 * p + 1), f(3 * p + 2)))
            .collect(),
    ))
}

/// The values of `<dir>/<name>.rgb64`, if it is a `width` × `height` image.
pub fn read_image(dir: &Path, name: &str, width: usize, height: usize) -> Option<Vec<Rgb>> {
    let bytes = std::fs::read(entry_path(dir, name, "rgb64")).ok()?;
    let (w, h, values) = decode_rgb64(&bytes)?;
    ((w, h) == (width, height)).then_some(values)
}

/// Write `<dir>/<name>.rgb64` and, for viewers, `<dir>/<name>.exr` (pixels where
/// `valid` is false as 0, as every EXR of ours), each atomically.
pub fn write_image(
    dir: &Path,
    name: &str,
    width: usize,
    height: usize,
    values: &[Rgb],
    valid: Option<&[bool]>,
) -> anyhow::Result<()> {
    let context = || format!("storing the reference in {}", dir.display());
    write_atomic(&entry_path(dir, name, "rgb64"), &encode_rgb64(width, height, values)).with_context(context)?;
    let mut field = image_field(width, height, values);
    if let Some(valid) = valid {
        field.valid.copy_from_slice(valid);
    }
    write_atomic(&entry_path(dir, name, "exr"), &encode_exr(&field)?).with_context(context)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb64_round_trip_is_exact() {
        let values: Vec<Rgb> = (0..6)
            .map(|k| Rgb::new(0.1 * k as f64, 1.0 / 3.0 + k as f64, -1e-300 * k as f64))
            .collect();
        let bytes = encode_rgb64(3, 2, &values);
        assert_eq!(decode_rgb64(&bytes), Some((3, 2, values.clone())));
        // Truncated, wrong magic or wrong size: not an image.
        assert_eq!(decode_rgb64(&bytes[..bytes.len() - 1]), None);
        assert_eq!(decode_rgb64(b"VCRGB64\n"), None);
        let mut other = bytes.clone();
        other[0] = b'X';
        assert_eq!(decode_rgb64(&other), None);
        let dir = tempfile::tempdir().unwrap();
        write_image(dir.path(), "k", 3, 2, &values, None).unwrap();
        assert_eq!(read_image(dir.path(), "k", 3, 2), Some(values));
        assert_eq!(read_image(dir.path(), "k", 2, 3), None, "size checked");
        assert!(entry_path(dir.path(), "k", "exr").is_file());
    }

    #[test]
    fn keys_are_stable_and_distinguish_parameters() {
        let a = store_key(&"scene", &[1, 2]);
        assert_eq!(a, store_key(&"scene", &[1, 2]));
        assert_eq!(a.len(), 16);
        assert_ne!(a, store_key(&"scene", &[1, 3]));
        assert_eq!(a, format!("{:016x}", fnv1a(b"\"scene\"|[1,2]")));
    }
}
