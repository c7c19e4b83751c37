//! Helpers shared by the subcommands: scene loading, argument parsers, progress.

use anyhow::Context;
use glam::DVec2;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Mutex, Once};
use std::time::Duration;
use volcache::flatland::scene::Scene;
use volcache::limits;
use volcache::output::{OutputPlan, SetError, write_set};
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

/// Parse `WxH` (within `limits::MAX_SIDE` per side and `limits::MAX_PIXELS`).
pub fn parse_res(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got `{s}`"))?;
    let p = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("`{v}` in `{s}`: {e}"));
    let (w, h) = (p(w)?, p(h)?);
    match limits::resolution_problem(w, h) {
        Some(why) => Err(format!("resolution {why}")),
        None => Ok([w, h]),
    }
}

/// One coordinate of `s`: finite and within ±`limits::MAX_COORD`.
fn coordinate(v: &str, s: &str) -> Result<f64, String> {
    let c = v
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("`{v}` in `{s}` is not a finite number"))?;
    if c.abs() > limits::MAX_COORD {
        return Err(format!("`{v}` in `{s}` lies beyond ±{:e}", limits::MAX_COORD));
    }
    Ok(c)
}

/// Parse `X,Y` as a point within ±`limits::MAX_COORD`.
pub fn parse_point(s: &str) -> Result<DVec2, String> {
    let (x, y) = s.split_once(',').ok_or_else(|| format!("expected X,Y, got `{s}`"))?;
    Ok(DVec2::new(coordinate(x, s)?, coordinate(y, s)?))
}

/// Comma-separated numbers, each within ±`limits::MAX_COORD` (points and sensors
/// whose count depends on the scene's dimension, checked by the caller).
#[derive(Clone, Debug, PartialEq)]
pub struct Coords {
    /// As given, for messages.
    pub text: String,
    pub values: Vec<f64>,
}

pub fn parse_coords(s: &str) -> Result<Coords, String> {
    let values = s.split(',').map(|v| coordinate(v, s)).collect::<Result<_, _>>()?;
    Ok(Coords {
        text: s.to_string(),
        values,
    })
}

/// A scene of either dimension: a 3D scene file has a `camera`, a 2D one a `domain`.
pub enum AnyScene {
    Flat(Box<Scene>),
    Volume(Box<volcache::volume::scene::Scene>),
}

/// Load a 2D or 3D scene file (the embedded 2D default when none is given). A
/// file that is not JSON, or has no `camera`, is read as 2D, whose errors name it.
pub fn load_any_scene(path: Option<&Path>) -> anyhow::Result<AnyScene> {
    let Some(p) = path else {
        return Ok(AnyScene::Flat(Box::new(Scene::default_scene())));
    };
    let text = volcache::scene_check::read(p)?;
    Ok(match volcache::scene_check::is_3d_json(&text) {
        true => AnyScene::Volume(Box::new(volcache::volume::scene::Scene::load(p)?)),
        false => AnyScene::Flat(Box::new(Scene::load(p)?)),
    })
}

/// A count option within `1..=max`.
pub fn check_count(flag: &str, v: u64, max: u64) -> anyhow::Result<()> {
    anyhow::ensure!(v >= 1, "{flag} must be at least 1");
    anyhow::ensure!(v <= max, "{flag} must be at most {max}, got {v}");
    Ok(())
}

/// Samples per pixel (or per point) within `1..=max`.
pub fn check_spp(flag: &str, v: u32, max: u32) -> anyhow::Result<()> {
    check_count(flag, v as u64, max as u64)
}

/// A real option within `[lo, hi]` (and finite).
pub fn check_range(flag: &str, v: f64, (lo, hi): (f64, f64)) -> anyhow::Result<()> {
    anyhow::ensure!(
        v.is_finite() && (lo..=hi).contains(&v),
        "{flag} must lie between {lo:e} and {hi:e}, got {v}"
    );
    Ok(())
}

/// An angle in degrees within ±`limits::MAX_ANGLE_DEG`.
pub fn check_angle(flag: &str, v: f64) -> anyhow::Result<()> {
    check_range(flag, v, (-limits::MAX_ANGLE_DEG, limits::MAX_ANGLE_DEG))
}

/// An exposure in stops within ±`limits::MAX_EXPOSURE`.
pub fn check_exposure(v: f64) -> anyhow::Result<()> {
    check_range("--exposure", v, (-limits::MAX_EXPOSURE, limits::MAX_EXPOSURE))
}

/// Peak bytes per pixel of a command, with a margin of about 2.5× over what was
/// measured (`/usr/bin/time -f %M`, peak resident set at 1024² and 2048²): values,
/// validity, standard errors and per-row results, the figure, the encoded PNG/EXR.
/// `field`: 77 bytes per pixel measured.
pub const FIELD_BYTES_PER_PIXEL: usize = 200;
/// `caches`: the reference and the reconstruction, record lists, error map,
/// figures: 141 measured (2D records are at most one per pixel).
pub const CACHES_BYTES_PER_PIXEL: usize = 400;
/// `render3d`: image and medium part, per-pixel statistics: 146 measured (records,
/// which grow with ε → 0 rather than with pixels, are watched while running), plus
/// the adaptive split's statistics over the placed samples (`volume::image_split::
/// PixelSpread`, 104 bytes, counted not measured).
pub const RENDER3D_BYTES_PER_PIXEL: usize = 500;

/// Refuse an image whose memory (at `bytes_per_pixel`) exceeds what the machine
/// has available, before any work is done (rather than aborting half-way).
pub fn ensure_memory(pixels: usize, bytes_per_pixel: usize, what: &str) -> anyhow::Result<()> {
    let need = (pixels as u64).saturating_mul(bytes_per_pixel as u64);
    if let Some(avail) = available_memory() {
        anyhow::ensure!(
            need <= avail,
            "{what} of {pixels} pixels needs about {:.1} GB of memory; {:.1} GB are available",
            need as f64 / 1e9,
            avail as f64 / 1e9
        );
    }
    Ok(())
}

/// `MemAvailable` of /proc/meminfo, in bytes (None where there is none).
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
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
        let limit = memory_limit();
        let thread = std::thread::spawn(move || {
            while !s.load(std::sync::atomic::Ordering::Relaxed) {
                b.set_length(p.total().max(1));
                b.set_position(p.done());
                // What grows with the input beyond the image (records as ε → 0,
                // query points) stops the run cleanly instead of an abort.
                if let (Some(rss), Some(limit)) = (resident_memory(), limit)
                    && rss > limit
                {
                    MEMORY_STOP.store(true, std::sync::atomic::Ordering::Relaxed);
                    p.cancel();
                }
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

/// Set when a computation was stopped because the process outgrew its memory.
static MEMORY_STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether the last cancel came from the memory watch rather than Ctrl-C.
pub fn stopped_for_memory() -> bool {
    MEMORY_STOP.load(std::sync::atomic::Ordering::Relaxed)
}

/// How a cancelled computation ends: exit 130 after Ctrl-C, an error when the
/// memory watch stopped it.
pub fn cancelled() -> anyhow::Result<ExitCode> {
    anyhow::ensure!(
        !stopped_for_memory(),
        "stopped: the run outgrew the memory available (fewer pixels, samples or march points, or a larger --eps)"
    );
    eprintln!("cancelled: no output written (existing files left untouched)");
    Ok(ExitCode::from(INTERRUPTED))
}

/// The resident set size this process may reach: `VOLCACHE_MEMORY_LIMIT_MB`, or
/// what it holds now plus 80% of what the machine has available.
fn memory_limit() -> Option<u64> {
    if let Some(mb) = std::env::var("VOLCACHE_MEMORY_LIMIT_MB")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        return Some(mb << 20);
    }
    Some(resident_memory()? + available_memory()? / 5 * 4)
}

/// This process's resident set size in bytes (`/proc/self/statm`).
fn resident_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = text.split_whitespace().nth(1)?.parse().ok()?;
    // SAFETY: sysconf has no preconditions.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    Some(pages * page.max(4096) as u64)
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

/// Exit code of a run stopped by Ctrl-C (128 + SIGINT), as shells report it.
pub const INTERRUPTED: u8 = 130;

/// Refuse, before any work is done, outputs that would overwrite an input of the
/// run or each other.
pub fn check_plan(plan: &OutputPlan) -> anyhow::Result<()> {
    plan.check().map_err(anyhow::Error::from)
}

/// Write the outputs of a run as a set (`output::write_set`: every file renamed
/// into place after all are written, the JSON summary last, naming the files and
/// their hashes), print them, and give the exit code: 130 when Ctrl-C came (before
/// the renames nothing is replaced; after, the outputs are complete and kept).
pub fn write_outputs(
    files: Vec<(PathBuf, Vec<u8>)>,
    summary: Option<(&Path, serde_json::Value)>,
    progress: &Progress,
) -> anyhow::Result<ExitCode> {
    let summary_path = summary.as_ref().map(|(p, _)| p.to_path_buf());
    match write_set(&files, summary, &|| progress.is_cancelled()) {
        Ok(_) => {}
        Err(SetError::Interrupted) => {
            eprintln!("cancelled: no output written (existing files left untouched)");
            return Ok(ExitCode::from(INTERRUPTED));
        }
        Err(e) => return Err(anyhow::Error::from(e).context("writing the outputs")),
    }
    for p in files.iter().map(|(p, _)| p).chain(summary_path.as_ref()) {
        eprintln!("wrote {}", p.display());
    }
    if progress.is_cancelled() {
        eprintln!("interrupted while the outputs were being renamed into place: they are complete");
        return Ok(ExitCode::from(INTERRUPTED));
    }
    Ok(ExitCode::SUCCESS)
}

/// PNG bytes of a pixmap.
pub fn png_bytes(path: &Path, pixmap: &tiny_skia::Pixmap) -> anyhow::Result<Vec<u8>> {
    pixmap
        .encode_png()
        .map_err(|e| anyhow::anyhow!("{}: cannot encode the PNG: {e}", path.display()))
}

/// EXR bytes of a field.
pub fn exr_bytes(path: &Path, field: &volcache::flatland::field::Field) -> anyhow::Result<Vec<u8>> {
    volcache::output::encode_exr(field).with_context(|| format!("{}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ctrl-C during the write phase (issue 14: it was ignored and the run exited
    /// 0): before the renames nothing is replaced and the exit code is 130.
    #[test]
    fn ctrl_c_while_writing_exits_130_and_replaces_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("f.png");
        std::fs::write(&png, b"old").unwrap();
        let progress = Progress::new();
        progress.cancel();
        let json = dir.path().join("f.json");
        let code = write_outputs(
            vec![(png.clone(), b"new".to_vec())],
            Some((&json, serde_json::json!({}))),
            &progress,
        )
        .unwrap();
        assert_eq!(code, ExitCode::from(INTERRUPTED));
        assert_eq!(std::fs::read(&png).unwrap(), b"old");
        assert!(!json.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // Not cancelled: written, summary last, exit 0.
        let code = write_outputs(
            vec![(png.clone(), b"new".to_vec())],
            Some((&json, serde_json::json!({}))),
            &Progress::new(),
        )
        .unwrap();
        assert_eq!(code, ExitCode::SUCCESS);
        assert_eq!(std::fs::read(&png).unwrap(), b"new");
    }

    #[test]
    fn option_ranges() {
        assert!(parse_res("4096x4096").is_ok());
        assert!(parse_res("16384x16384").unwrap_err().contains("pixels"));
        assert!(parse_point("1e12,-1e12").is_ok());
        assert!(parse_point("1e308,0").is_err() && parse_point("nan,0").is_err());
        assert!(check_range("--x", f64::NAN, (0.0, 1.0)).is_err());
        assert!(check_exposure(100.0).is_ok() && check_exposure(100.5).is_err());
        assert!(ensure_memory(1, 1, "x").is_ok());
        assert!(ensure_memory(usize::MAX / 1024, 1024, "x").is_err());
    }
}

/// Adaptive records (`CacheSettings::record_noise`), for `caches` and `render3d`.
#[derive(clap::Args, Debug, Clone)]
pub struct RecordNoiseArgs {
    /// Adaptive records: each takes further light fields of `--rays` directions
    /// (their derivatives averaged) until the estimated relative standard error of
    /// its value is at most this, or it has `--max-light-fields`. Default: one light
    /// field per record.
    #[arg(long)]
    pub record_noise: Option<f64>,
    /// The most light fields a record takes under `--record-noise`.
    #[arg(long, default_value_t = 8)]
    pub max_light_fields: u32,
}

impl RecordNoiseArgs {
    pub fn check(&self) -> anyhow::Result<()> {
        if let Some(t) = self.record_noise {
            check_range("--record-noise", t, volcache::limits::RECORD_NOISE)?;
        }
        check_count("--max-light-fields", self.max_light_fields as u64, 64)
    }

    pub fn target(&self) -> Option<volcache::pipeline::record::NoiseTarget> {
        self.record_noise
            .map(|relative| volcache::pipeline::record::NoiseTarget {
                relative,
                max_light_fields: self.max_light_fields,
            })
    }
}
