//! The outputs of one run written as a set, so that a reader can tell whether they
//! belong together: every file is first written to a temporary file beside it, then
//! the files are renamed into place one by one and the JSON summary last, naming
//! each file of the set with its size and FNV-1a hash. A run killed while renaming
//! leaves the previous summary, whose hashes no longer match the new files; a run
//! interrupted (Ctrl-C) before renaming replaces nothing.
//!
//! Temporary files are named `.<name>.<pid>-<n>.tmp`; ones whose process is gone
//! (a run killed between writing and renaming) are removed by the next write into
//! the same folder.

use crate::core::rng::fnv1a;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A file of the set, as its summary lists it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct WrittenFile {
    /// Relative to the summary's folder when inside it, else as given.
    pub path: String,
    pub bytes: u64,
    /// FNV-1a (64-bit) of the file's bytes, hex.
    pub fnv1a64: String,
}

impl WrittenFile {
    fn of(path: &Path, bytes: &[u8], summary_dir: Option<&Path>) -> WrittenFile {
        let shown = summary_dir.and_then(|d| path.strip_prefix(d).ok()).unwrap_or(path);
        WrittenFile {
            path: shown.display().to_string(),
            bytes: bytes.len() as u64,
            fnv1a64: format!("{:016x}", fnv1a(bytes)),
        }
    }

    /// Whether `path` now holds exactly this file.
    pub fn matches(&self, path: &Path) -> bool {
        std::fs::read(path).is_ok_and(|b| b.len() as u64 == self.bytes && format!("{:016x}", fnv1a(&b)) == self.fnv1a64)
    }
}

/// Why a set was not (wholly) written.
#[derive(Debug, thiserror::Error)]
pub enum SetError {
    #[error("interrupted before the outputs were replaced: nothing was written")]
    Interrupted,
    #[error("{path}: {message}")]
    Io { path: String, message: String },
}

/// Write `files` and then the JSON `summary` (an object; its `outputs` field is set
/// to the list of `files` with their hashes). `interrupted` is asked once every
/// temporary file is written: when it says yes, they are removed and nothing is
/// replaced. Returns the list the summary holds.
pub fn write_set(
    files: &[(PathBuf, Vec<u8>)],
    summary: Option<(&Path, serde_json::Value)>,
    interrupted: &dyn Fn() -> bool,
) -> Result<Vec<WrittenFile>, SetError> {
    let summary_dir = summary.as_ref().and_then(|(p, _)| p.parent());
    let listed: Vec<WrittenFile> = files.iter().map(|(p, b)| WrittenFile::of(p, b, summary_dir)).collect();
    let mut all: Vec<(PathBuf, Vec<u8>)> = files.to_vec();
    if let Some((path, mut value)) = summary {
        if let Some(obj) = value.as_object_mut() {
            obj.insert("outputs".into(), serde_json::to_value(&listed).unwrap_or_default());
        }
        let mut bytes = serde_json::to_vec_pretty(&value).map_err(|e| io_error(path, e))?;
        bytes.push(b'\n');
        all.push((path.to_path_buf(), bytes));
    }
    let mut temps: Vec<PathBuf> = Vec::with_capacity(all.len());
    let remove = |temps: &[PathBuf]| temps.iter().for_each(|t| drop(std::fs::remove_file(t)));
    for (path, bytes) in &all {
        match super::write_temp(path, bytes) {
            Ok(t) => temps.push(t),
            Err(e) => {
                remove(&temps);
                return Err(io_error(path, e));
            }
        }
    }
    if interrupted() {
        remove(&temps);
        return Err(SetError::Interrupted);
    }
    for (k, ((path, _), tmp)) in all.iter().zip(&temps).enumerate() {
        if let Err(e) = std::fs::rename(tmp, path) {
            remove(&temps[k..]);
            return Err(io_error(path, format!("cannot replace the file: {e}")));
        }
    }
    Ok(listed)
}

fn io_error(path: &Path, e: impl std::fmt::Display) -> SetError {
    SetError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Remove the temporary files of our naming in `dir` whose writer is gone.
pub fn clean_stale_temps(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if let Some(pid) = temp_owner(&name)
            && !process_alive(pid)
        {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// The pid in a name `.<name>.<pid>-<n>.tmp` (see `output::temp_path`).
fn temp_owner(file_name: &str) -> Option<i32> {
    let inner = file_name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (_, tag) = inner.rsplit_once('.')?;
    let (pid, n) = tag.split_once('-')?;
    n.parse::<u64>().ok()?;
    pid.parse::<i32>().ok().filter(|&p| p > 0)
}

fn process_alive(pid: i32) -> bool {
    if pid as u32 == std::process::id() {
        return true;
    }
    // Signal 0 checks existence; EPERM means it exists under another user.
    // SAFETY: kill with signal 0 sends nothing.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::tests::entries as names;

    #[test]
    fn the_summary_names_every_file_with_its_hash() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b, s) = (
            dir.path().join("f.png"),
            dir.path().join("f.exr"),
            dir.path().join("f.json"),
        );
        let files = vec![(a.clone(), b"png bytes".to_vec()), (b.clone(), b"exr bytes".to_vec())];
        let listed = write_set(&files, Some((&s, serde_json::json!({"x": 1}))), &|| false).unwrap();
        let back: serde_json::Value = serde_json::from_slice(&std::fs::read(&s).unwrap()).unwrap();
        assert_eq!(back["x"], 1);
        let outputs: Vec<WrittenFile> = serde_json::from_value(back["outputs"].clone()).unwrap();
        assert_eq!(outputs, listed);
        assert_eq!(outputs[0].path, "f.png");
        assert!(outputs[0].matches(&a) && outputs[1].matches(&b) && !outputs[0].matches(&b));
        assert_eq!(names(dir.path()), ["f.exr", "f.json", "f.png"]);
    }

    #[test]
    fn an_interrupt_before_renaming_replaces_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("f.png");
        std::fs::write(&a, b"old").unwrap();
        let err = write_set(&[(a.clone(), b"new".to_vec())], None, &|| true).unwrap_err();
        assert!(matches!(err, SetError::Interrupted));
        assert_eq!(std::fs::read(&a).unwrap(), b"old");
        assert_eq!(names(dir.path()), ["f.png"]);
    }

    #[test]
    fn stale_temporary_files_of_dead_writers_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        // A process that has exited: its pid is free (until reused).
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let stale = format!(".f.png.{dead}-0.tmp");
        let live = format!(".f.png.{}-7.tmp", std::process::id());
        for n in [&stale, &live, &"f.png.1-2.tmp".to_string(), &".notes.tmp".to_string()] {
            std::fs::write(dir.path().join(n), b"x").unwrap();
        }
        clean_stale_temps(dir.path());
        let left = names(dir.path());
        assert!(!left.contains(&stale), "{left:?}");
        assert!(
            left.contains(&live) && left.contains(&".notes.tmp".to_string()),
            "{left:?}"
        );
        assert!(left.contains(&"f.png.1-2.tmp".to_string()), "not ours: {left:?}");
    }
}
