//! The state of "Open…" (its window is [`super::open_window`]): the folder its
//! file browser lists, and the listing. A browser of our own because the crates
//! that would do it do not fit: egui-file-dialog 0.15 is built on egui 0.36 (the
//! app is on 0.37), and rfd's default backend needs an XDG desktop portal, which a
//! bare X server (Xvfb, a remote X session) does not have.

use std::path::{Path, PathBuf};

/// The browser's state: shown or not, and the folder it lists.
pub struct OpenDialog {
    pub open: bool,
    pub dir: PathBuf,
    /// The folder field's text (applied on Enter or "Go").
    pub dir_text: String,
}

impl Default for OpenDialog {
    fn default() -> Self {
        let cwd = std::env::current_dir().unwrap_or_else(|_| PathBuf::from("."));
        // Where the shipped scenes live in a checkout, else where the app started.
        let scenes = cwd.join("flatland_scenes");
        let dir = if scenes.is_dir() { scenes } else { cwd };
        OpenDialog {
            open: false,
            dir_text: dir.display().to_string(),
            dir,
        }
    }
}

impl OpenDialog {
    /// List `dir` from now on.
    pub fn go(&mut self, dir: PathBuf) {
        self.dir_text = dir.display().to_string();
        self.dir = dir;
    }
}

/// The sub-folders and `.json` files of `dir`, each sorted by name (hidden entries
/// skipped).
pub fn listing(dir: &Path) -> std::io::Result<(Vec<PathBuf>, Vec<PathBuf>)> {
    let (mut dirs, mut files) = (Vec::new(), Vec::new());
    for e in std::fs::read_dir(dir)? {
        let p = e?.path();
        let hidden = p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'));
        if hidden {
            continue;
        }
        if p.is_dir() {
            dirs.push(p);
        } else if p.extension().is_some_and(|x| x == "json") {
            files.push(p);
        }
    }
    dirs.sort();
    files.sort();
    Ok((dirs, files))
}
