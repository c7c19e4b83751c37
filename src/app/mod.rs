//! The interactive workbench (`volcache app`, or `volcache` alone): an egui/eframe
//! window over the flatland model and, as its second mode, the 3D renderer
//! ([`mode`]: the switch; opening a 3D scene file switches to 3D). UI only: every number comes from the library
//! functions the command line calls, on background threads ([`jobs`]), and the
//! state logic (scene edits, undo, scheduling) lives apart from the widgets.
//!
//! - [`document`]: the edited scene, validation, undo/redo ([`history`]), load/save;
//!   [`open_dialog`], [`open_window`]: "Open…" (shipped scenes, a file browser);
//!   [`edit`]: picking and dragging handles, adding and deleting items;
//! - [`jobs`]: background jobs and the cancel-and-restart policy ([`jobs::Slot`]);
//!   [`compute`]: what the jobs compute (field levels, probe, reference, gradients);
//!   [`field_method`]: the field from a radiance cache instead of path tracing;
//!   [`compare`]: the compare view's computation (reference and caches at equal
//!   count), [`compare_view`]: its window and the record / error overlays' data;
//! - [`workbench`]: state and per-frame scheduling; [`canvas`], [`overlay`],
//!   [`scene_draw`], [`view`]: the canvas; [`inspector`], [`readout`]: the probe
//!   inspector; [`panels`], [`scene_panel`], [`toolbar`]: side panel, status bar,
//!   toolbar and shortcuts; [`layout`]: how the panels give way to the canvas;
//!   [`command`]: "copy as command".
//! - 3D mode: [`workbench3d`] (state, scheduling), [`document3d`] (the scene,
//!   its camera, undo, save), [`render3d_job`] (the view's progressive render by
//!   path tracing, ours or Jarosz 2008), [`orbit`] (camera motion), [`view3d`]
//!   (the image, mouse, record overlay), [`panel3d`] (side panel, status bar),
//!   [`probe3d`] and [`inspector3d`] (the probe on a pixel's camera ray),
//!   [`compare3d`] and [`compare3d_view`] (the paper's comparison, as `figure
//!   compare3d` runs it).

pub mod canvas;
pub mod command;
pub mod compare;
pub mod compare3d;
pub mod compare3d_view;
pub mod compare_textures;
pub mod compare_view;
pub mod compute;
pub mod document;
pub mod document3d;
pub mod edit;
pub mod error_map3d;
pub mod field_method;
pub mod frame_stats;
pub mod history;
pub mod inspector;
pub mod inspector3d;
pub mod jobs;
pub mod layout;
pub mod mode;
pub mod open_dialog;
pub mod open_window;
pub mod overlay;
pub mod panel3d;
pub mod panels;
pub mod probe3d;
pub mod readout;
pub mod render3d_job;
pub mod result_id;
pub mod scene_draw;
pub mod scene_panel;
pub mod toolbar;
pub mod view;
pub mod view3d;
pub mod workbench;
pub mod workbench3d;

pub use document::Document;
pub use mode::{App, Mode};
pub use workbench::Workbench;
pub use workbench3d::Workbench3d;

use eframe::egui;
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

type PanicHook = Box<dyn Fn(&std::panic::PanicHookInfo<'_>) + Send + Sync + 'static>;

/// Exit code when no window can be opened.
pub const NO_DISPLAY_EXIT: u8 = 3;

/// What to say when no window can be opened.
pub const HEADLESS_HELP: &str = "\
The workbench needs a display (X11 or Wayland); none is available here.
Everything it shows can be computed headless:
  volcache field [SCENE] --res WxH --spp N --out out/field.png   the radiance field (PNG, EXR, JSON)
  volcache probe [SCENE] --at X,Y --method aware|unaware|reference --json   L_s, gradient, Hessian at a point
  volcache figure gradients [SCENE] --line X0,Y0,X1,Y1 --out DIR   the paper's gradient figure
  volcache caches [SCENE] ...   radiance caches, their records and errors
Run `volcache --help` for all commands. Under Xvfb, see scripts/screenshot.sh.";

/// DejaVu Sans (the figures' font) as a fallback for symbols egui's fonts lack.
const DEJAVU: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

pub fn install_fonts(ctx: &egui::Context) {
    use egui::epaint::text::{FontInsert, FontPriority, InsertFontFamily};
    let families = [egui::FontFamily::Proportional, egui::FontFamily::Monospace]
        .map(|family| InsertFontFamily {
            family,
            priority: FontPriority::Lowest,
        })
        .to_vec();
    ctx.add_font(FontInsert::new(
        "DejaVuSans",
        egui::FontData::from_static(DEJAVU),
        families,
    ));
}

/// A display server is named in the environment.
pub fn has_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// Give the calling thread the nice value `nice`: computation threads yield to the
/// UI thread (on Linux the nice value is per thread), so frames stay smooth while
/// every core computes.
pub fn lower_priority(nice: i32) {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority only changes the calling thread's nice value.
    unsafe {
        libc::setpriority(libc::PRIO_PROCESS, 0, nice);
    }
    #[cfg(not(target_os = "linux"))]
    let _ = nice;
}

fn no_window(why: &str) -> ExitCode {
    eprintln!("volcache: cannot open the workbench window: {why}\n\n{HEADLESS_HELP}");
    ExitCode::from(NO_DISPLAY_EXIT)
}

/// How the workbench starts (the `app` subcommand's flags).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StartOptions {
    /// Place the probe here.
    pub probe: Option<glam::DVec2>,
    /// Show the gradient overlay.
    pub gradients: bool,
    /// Compute the reference at the probe (and follow it).
    pub reference: bool,
    /// False colour instead of tone mapping.
    pub false_color: bool,
    /// Write this file once everything asked for has been computed (scripts wait
    /// on it, e.g. scripts/screenshot.sh).
    pub ready_file: Option<std::path::PathBuf>,
    /// 3D: the view's method, width (pixels) and a probe at image point U,V.
    pub method3d: Option<render3d_job::Method3d>,
    pub view_width: Option<usize>,
    pub pixel: Option<glam::DVec2>,
}

/// Open the workbench on `scene` (the embedded default when None). Without a
/// display, explain the headless commands and return a non-zero code.
pub fn run(scene: Option<&Path>, start: StartOptions) -> anyhow::Result<ExitCode> {
    // A bad scene file is an error whether or not there is a display.
    let is_3d = match scene {
        Some(p) => crate::scene_check::is_3d_json(&crate::scene_check::read(p)?),
        None => false,
    };
    let app = match scene {
        Some(p) if is_3d => {
            let mut app = App::volume(document3d::Document3d::open(p)?);
            app.volume_mut().start(&start);
            app
        }
        _ => App::flat(Workbench::new(Document::open(scene)?).with_start(start)),
    };
    if !has_display() {
        return Ok(no_window("neither DISPLAY nor WAYLAND_DISPLAY is set"));
    }
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([1280.0, 800.0])
            .with_title("volcache workbench"),
        ..Default::default()
    };
    // Window-system failures can panic deep inside winit before the app starts:
    // report those like errors; a panic once the app runs is a bug and propagates.
    let started = Arc::new(AtomicBool::new(false));
    let message = Arc::new(Mutex::new(String::new()));
    let previous: Arc<PanicHook> = Arc::new(std::panic::take_hook());
    {
        let (started, message, previous) = (started.clone(), message.clone(), previous.clone());
        std::panic::set_hook(Box::new(move |info| {
            if started.load(Ordering::Relaxed) {
                previous(info);
            } else {
                *message.lock().unwrap() = info.to_string();
            }
        }));
    }
    let s = started.clone();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        eframe::run_native(
            "volcache",
            options,
            Box::new(move |cc| {
                s.store(true, Ordering::Relaxed);
                install_fonts(&cc.egui_ctx);
                Ok(Box::new(app))
            }),
        )
    }));
    let prev = previous.clone();
    std::panic::set_hook(Box::new(move |info| prev(info)));
    if result.is_err() && started.load(Ordering::Relaxed) {
        std::process::exit(101); // the previous hook has reported the panic
    }
    Ok(match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => no_window(&e.to_string()),
        Err(_) => no_window(&message.lock().unwrap()),
    })
}
