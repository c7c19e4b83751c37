//! Helpers shared by the subcommands: scene loading, argument parsers, progress.

use anyhow::Context;
use glam::DVec2;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Once};
use std::time::Duration;
use volcache::flatland::scene::Scene;
use volcache::progress::Progress;

/// Load a scene file, or the embedded default scene when none is given.
pub fn load_scene(path: Option<&Path>) -> anyhow::Result<Scene> {
    Ok(match path {
        Some(p) => Scene::load(p)?,
        None => Scene::default_scene(),
    })
}

/// File stem used to name default outputs.
pub fn scene_stem(path: Option<&Path>) -> String {
    path.and_then(|p| p.file_stem()).map_or_else(
        || {
            volcache::flatland::scene::DEFAULT_SCENE_NAME
                .trim_end_matches(".json")
                .to_string()
        },
        |s| s.to_string_lossy().into_owned(),
    )
}

/// Parse `WxH`.
pub fn parse_res(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got `{s}`"))?;
    let p = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("`{v}` in `{s}`: {e}"));
    let (w, h) = (p(w)?, p(h)?);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!("resolution must be between 1 and 16384 per side, got {w}x{h}"));
    }
    Ok([w, h])
}

/// Parse `X,Y` as a finite point.
pub fn parse_point(s: &str) -> Result<DVec2, String> {
    let (x, y) = s.split_once(',').ok_or_else(|| format!("expected X,Y, got `{s}`"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("`{v}` in `{s}` is not a finite number"))
    };
    Ok(DVec2::new(p(x)?, p(y)?))
}

/// A progress handle cancelled by Ctrl-C, and a bar that follows it until dropped.
pub struct ProgressUi {
    pub progress: Arc<Progress>,
    bar: ProgressBar,
    stop: Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl ProgressUi {
    /// A Ctrl-C-cancellable progress handle; the bar is drawn only when `show_bar`.
    pub fn new(label: &str, show_bar: bool) -> ProgressUi {
        let progress = Arc::new(Progress::new());
        watch_ctrl_c(&progress);
        let bar = if show_bar {
            ProgressBar::new(1)
        } else {
            ProgressBar::hidden()
        };
        bar.set_style(
            ProgressStyle::with_template("{msg} [{bar:40.cyan/blue}] {percent:>3}% {elapsed_precise} (eta {eta})")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_message(label.to_string());
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (p, b, s) = (progress.clone(), bar.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            while !s.load(std::sync::atomic::Ordering::Relaxed) {
                b.set_length(p.total().max(1));
                b.set_position(p.done());
                std::thread::sleep(Duration::from_millis(100));
            }
        });
        ProgressUi {
            progress,
            bar,
            stop,
            thread: Some(thread),
        }
    }

    pub fn finish(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        self.bar.set_position(self.progress.done());
        self.bar.finish_and_clear();
    }
}

/// What the library's long computations report to (they make it only when there
/// is work, and drop it when done).
impl AsRef<Progress> for ProgressUi {
    fn as_ref(&self) -> &Progress {
        &self.progress
    }
}

impl Drop for ProgressUi {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// The computation Ctrl-C cancels (the handler can be installed once per process).
static CTRL_C_TARGET: Mutex<Option<Arc<Progress>>> = Mutex::new(None);

fn watch_ctrl_c(progress: &Arc<Progress>) {
    static INSTALL: Once = Once::new();
    INSTALL.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            eprintln!("\ninterrupted: stopping…");
            if let Some(p) = CTRL_C_TARGET.lock().ok().and_then(|g| g.clone()) {
                p.cancel();
            }
        });
    });
    if let Ok(mut g) = CTRL_C_TARGET.lock() {
        *g = Some(progress.clone());
    }
}

/// Default output path `out/<stem><suffix>` unless one was given.
pub fn out_path(given: Option<PathBuf>, stem: &str, suffix: &str) -> PathBuf {
    given.unwrap_or_else(|| PathBuf::from("out").join(format!("{stem}{suffix}")))
}

/// Context for writing a file.
pub fn wrote(path: &Path, r: anyhow::Result<()>) -> anyhow::Result<()> {
    r.with_context(|| format!("writing {}", path.display()))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
