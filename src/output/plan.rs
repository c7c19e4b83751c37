//! The files one run reads and writes, checked before any work is done: no output
//! may be one of the run's inputs (`field s.json --out s.json` would destroy the
//! scene), and no two outputs may be the same file (only the last would survive).
//!
//! Two paths name the same file when they resolve to the same place (symbolic links
//! and `..` followed, as far as the path exists) or, for existing files, share a
//! device and inode (hard links).

use std::path::{Component, Path, PathBuf};

/// Why a run's outputs are refused. Each names the options (or roles) and the path.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PlanError {
    #[error("{output} would overwrite {input} ({path}): give an output path that is not an input of the run")]
    OverwritesInput {
        output: String,
        input: String,
        path: String,
    },
    #[error("{first} and {second} name the same file ({path}): each output needs its own path")]
    SameOutput {
        first: String,
        second: String,
        path: String,
    },
}

/// Inputs and outputs of a run, each with the option (or role) that names it.
#[derive(Debug, Default, Clone)]
pub struct OutputPlan {
    inputs: Vec<(String, PathBuf)>,
    outputs: Vec<(String, PathBuf)>,
}

impl OutputPlan {
    pub fn new() -> Self {
        Self::default()
    }

    /// A file the run reads (`label` says which: "the scene", "--records-in"…).
    pub fn input(&mut self, label: impl Into<String>, path: &Path) -> &mut Self {
        self.inputs.push((label.into(), path.to_path_buf()));
        self
    }

    /// A file the run writes.
    pub fn output(&mut self, label: impl Into<String>, path: &Path) -> &mut Self {
        self.outputs.push((label.into(), path.to_path_buf()));
        self
    }

    /// The first conflict, if any.
    pub fn check(&self) -> Result<(), PlanError> {
        let key = |p: &PathBuf| FileKey::of(p);
        let inputs: Vec<FileKey> = self.inputs.iter().map(|(_, p)| key(p)).collect();
        let outputs: Vec<FileKey> = self.outputs.iter().map(|(_, p)| key(p)).collect();
        for (k, (label, path)) in self.outputs.iter().enumerate() {
            if let Some(i) = inputs.iter().position(|x| x.same(&outputs[k])) {
                return Err(PlanError::OverwritesInput {
                    output: label.clone(),
                    input: self.inputs[i].0.clone(),
                    path: path.display().to_string(),
                });
            }
            if let Some(j) = outputs[..k].iter().position(|x| x.same(&outputs[k])) {
                return Err(PlanError::SameOutput {
                    first: self.outputs[j].0.clone(),
                    second: label.clone(),
                    path: path.display().to_string(),
                });
            }
        }
        Ok(())
    }
}

/// Where a path leads: its resolved absolute form and, if it exists, its inode.
struct FileKey {
    resolved: PathBuf,
    inode: Option<(u64, u64)>,
}

impl FileKey {
    fn of(path: &Path) -> FileKey {
        use std::os::unix::fs::MetadataExt;
        FileKey {
            resolved: resolve(path),
            inode: std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino())),
        }
    }

    fn same(&self, other: &FileKey) -> bool {
        self.resolved == other.resolved || (self.inode.is_some() && self.inode == other.inode)
    }
}

/// The absolute path with its longest existing prefix canonicalised (links
/// followed) and the rest normalised lexically.
fn resolve(path: &Path) -> PathBuf {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut prefix = abs.clone();
    let mut rest: Vec<PathBuf> = Vec::new();
    loop {
        if let Ok(c) = prefix.canonicalize() {
            let mut out = c;
            for part in rest.iter().rev() {
                push_normal(&mut out, part);
            }
            return out;
        }
        match (prefix.file_name().map(|n| n.to_os_string()), prefix.parent()) {
            (Some(name), Some(parent)) => {
                rest.push(PathBuf::from(name));
                prefix = parent.to_path_buf();
            }
            _ => return lexical(&abs),
        }
    }
}

fn push_normal(out: &mut PathBuf, part: &Path) {
    for c in part.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
}

fn lexical(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    push_normal(&mut out, p);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_output_on_an_input_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("s.json");
        std::fs::write(&scene, "{}").unwrap();
        let mut plan = OutputPlan::new();
        plan.input("the scene", &scene);
        // Spelled differently: through `.` and `..`, and through a hard link.
        let other = dir.path().join("sub/../s.json");
        plan.output("--out", &dir.path().join("./x.png"))
            .output("--json", &other);
        let err = plan.check().unwrap_err().to_string();
        assert!(err.contains("--json would overwrite the scene"), "{err}");
        let link = dir.path().join("hard.json");
        std::fs::hard_link(&scene, &link).unwrap();
        let mut plan = OutputPlan::new();
        plan.input("the scene", &scene).output("--exr", &link);
        assert!(matches!(plan.check(), Err(PlanError::OverwritesInput { .. })));
    }

    #[test]
    fn two_outputs_on_one_file_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let mut plan = OutputPlan::new();
        plan.output("--out", &dir.path().join("new/f.png"))
            .output("--exr", &dir.path().join("new/g.exr"));
        assert_eq!(plan.check(), Ok(()));
        plan.output("--json", &dir.path().join("new/./f.png"));
        let err = plan.check().unwrap_err().to_string();
        assert!(err.contains("--out and --json name the same file"), "{err}");
        // Through a symbolic link to the folder.
        std::fs::create_dir(dir.path().join("real")).unwrap();
        std::os::unix::fs::symlink(dir.path().join("real"), dir.path().join("link")).unwrap();
        let mut plan = OutputPlan::new();
        plan.output("--out", &dir.path().join("real/a.png"))
            .output("--exr", &dir.path().join("link/a.png"));
        assert!(matches!(plan.check(), Err(PlanError::SameOutput { .. })));
    }
}
