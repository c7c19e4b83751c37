//! The workbench's state and its per-frame scheduling. [`Workbench::tick`] (no UI)
//! takes in results and makes sure the right jobs run for the current scene
//! revision and parameters, cancelling the stale ones; [`Workbench::ui`] lays out
//! the panels (controls, canvas, inspector, status bar) around it.

use super::compare::{CompareKey, CompareParams, CompareResult, spawn_compare};
use super::compute::{
    FieldLevel, GradientGrid, MethodParams, ProbeResult, ReferenceResult, spawn_field, spawn_gradients, spawn_probe,
    spawn_reference,
};
use super::document::Document;
use super::edit::{Handle, Selection};
use super::field_method::{CacheFieldParams, FieldMethod, spawn_cached_field};
use super::jobs::{Notify, Slot, no_notify};
use super::layout::{CONTROLS_WIDTH, INSPECTOR_WIDTH, panel_max_widths};
use super::overlay::{Overlay, Overlays};
use super::result_id::ResultId;
use super::view::{ViewState, Xform};
use crate::figure::{ColorScale, RecordColor};
use crate::flatland::cached_field::CacheMethod;
use crate::flatland::field::FieldParams;
use crate::flatland::scene_desc::Part;
use crate::pipeline::path::Settings;
use crate::pipeline::probe::ProbeSettings;
use eframe::egui;
use glam::DVec2;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How the field is shown (changing it re-maps colours, never recomputes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Display {
    /// Log luminance through viridis with a colour bar, else tone-mapped RGB.
    pub false_color: bool,
    /// Tone mapping takes its exposure from the field (`figure::auto_exposure`),
    /// else from `exposure`.
    pub auto_exposure: bool,
    /// Stops, tone-mapped display without automatic exposure.
    pub exposure: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub text: String,
    pub error: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum DragKind {
    Handle(Handle),
    Pan,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct DragState {
    pub kind: DragKind,
    pub last_world: DVec2,
}

#[derive(PartialEq)]
pub(super) struct ProbeKey {
    revision: u64,
    at: DVec2,
    ps: ProbeSettings,
    seed: u64,
    omega_o_deg: f64,
}

#[derive(PartialEq)]
pub(super) struct ReferenceKey {
    revision: u64,
    at: DVec2,
    spp: u32,
    fd_step: f64,
    settings: Settings,
    seed: u64,
    omega_o_deg: f64,
}

#[derive(PartialEq)]
pub(super) struct GradientKey {
    revision: u64,
    n: (usize, usize),
    ps: ProbeSettings,
    seed: u64,
    omega_o_deg: f64,
}

/// What the gradient overlay's texture was made from: the grid, aware or not, the part.
pub(super) type GradientTexKey = (ResultId<GradientGrid>, bool, Part);

pub struct Workbench {
    pub doc: Document,
    pub field_params: FieldParams,
    pub display: Display,
    pub method: MethodParams,
    pub overlays: Overlays,
    /// The gradient overlay shows the aware method (else unaware).
    pub gradient_aware: bool,
    /// The gradient overlay draws an arrow per cell (at most 24 per side) over
    /// its angle-coded image.
    pub gradient_arrows: bool,
    pub probe: Option<DVec2>,
    pub selection: Option<Selection>,
    /// The side panels are shown (the toolbar's toggles; small windows hide them).
    pub show_controls: bool,
    pub show_inspector: bool,
    /// "Open…": shipped scenes and a file browser.
    pub open_dialog: super::open_dialog::OpenDialog,
    /// A 3D scene file chosen here, for the window to open in 3D mode.
    pub open_3d: Option<std::path::PathBuf>,
    pub view: ViewState,
    /// Compute the reference at the probe (on demand), and keep doing so as it moves.
    pub want_reference: bool,
    pub auto_reference: bool,
    pub(super) field: Slot<(u64, FieldParams, FieldMethod, CacheFieldParams), Arc<FieldLevel>>,
    /// How the canvas' field is computed: path traced, or from a radiance cache.
    pub field_method: FieldMethod,
    pub cache_field: CacheFieldParams,
    pub(super) probe_job: Slot<ProbeKey, Arc<ProbeResult>>,
    pub(super) reference: Slot<ReferenceKey, Arc<ReferenceResult>>,
    pub(super) gradients: Slot<GradientKey, Arc<GradientGrid>>,
    /// The compare view's parameters, whether it is open, and its job.
    pub compare_params: CompareParams,
    pub show_compare: bool,
    /// The method whose records and error the overlays show.
    pub overlay_method: CacheMethod,
    /// What colours the records (overlay and compare view).
    pub record_color: RecordColor,
    pub(super) compare: Slot<CompareKey, Arc<CompareResult>>,
    /// Textures of the compare view and the error overlay, for one result.
    pub(super) compare_tex: Option<super::compare_textures::CompareTextures>,
    pub(super) compare_out: String,
    pub(super) texture: Option<(egui::TextureHandle, (ResultId<FieldLevel>, Display))>,
    pub(super) color_scale: Option<ColorScale>,
    /// The automatic exposure of the field level it was computed for.
    auto_stops: std::cell::RefCell<Option<(ResultId<FieldLevel>, f64)>>,
    /// The gradient overlay's texture, its key (grid, aware?, part) and arrows.
    pub(super) gradient_tex: Option<(egui::TextureHandle, GradientTexKey, super::overlay::GradientView)>,
    pub message: Option<Message>,
    pub(super) drag: Option<DragState>,
    pub(super) hovered: Option<Handle>,
    pub(super) last_xf: Option<Xform>,
    /// The canvas' rectangle last frame (the colour bar's strip included).
    pub(super) canvas_rect: Option<egui::Rect>,
    pub(super) scene_path: String,
    pub(super) export_path: String,
    /// Shapes the canvas drew last frame (tests check overlays through it).
    pub shapes_drawn: usize,
    /// Written once everything asked for is computed (`StartOptions::ready_file`).
    ready_file: Option<std::path::PathBuf>,
    notify: Notify,
    has_ctx: bool,
    generation: u64,
    stats: super::frame_stats::FrameStats,
}

impl Workbench {
    pub fn new(doc: Document) -> Self {
        let scene = doc.scene().clone();
        let field_params = FieldParams::from_scene(&scene);
        let scene_path = doc.path().map_or(String::new(), |p| p.display().to_string());
        let export_path = format!("out/{}_app.png", doc.stem());
        Workbench {
            display: Display {
                false_color: false,
                auto_exposure: true,
                exposure: scene.desc.render.exposure,
            },
            field_params,
            method: MethodParams::default(),
            overlays: Overlays::default(),
            gradient_aware: true,
            gradient_arrows: true,
            probe: None,
            selection: None,
            show_controls: true,
            show_inspector: true,
            open_dialog: Default::default(),
            open_3d: None,
            view: ViewState::default(),
            want_reference: false,
            auto_reference: false,
            field: Slot::default(),
            field_method: FieldMethod::PathTracing,
            cache_field: CacheFieldParams::default(),
            probe_job: Slot::default(),
            reference: Slot::default(),
            gradients: Slot::default(),
            compare_params: CompareParams::default(),
            show_compare: false,
            overlay_method: CacheMethod::Ours,
            record_color: RecordColor::Uniform(crate::figure::RECORD_BLUE),
            compare: Slot::default(),
            compare_tex: None,
            compare_out: "out/compare".into(),
            texture: None,
            color_scale: None,
            auto_stops: std::cell::RefCell::new(None),
            gradient_tex: None,
            message: None,
            drag: None,
            hovered: None,
            last_xf: None,
            canvas_rect: None,
            scene_path,
            export_path,
            shapes_drawn: 0,
            ready_file: None,
            notify: no_notify(),
            has_ctx: false,
            generation: doc.generation(),
            stats: super::frame_stats::FrameStats::from_env(),
            doc,
        }
    }

    /// Apply the start-up options of `volcache app`.
    pub fn with_start(mut self, s: super::StartOptions) -> Self {
        self.probe = s.probe;
        self.overlays.set(Overlay::Gradients, s.gradients);
        (self.want_reference, self.auto_reference) = (s.reference, s.reference);
        self.display.false_color = s.false_color;
        self.ready_file = s.ready_file;
        self
    }

    /// Everything asked for is computed: the field converged, and the probe, the
    /// reference and the gradient overlay if they are on.
    pub fn settled(&self) -> bool {
        self.field_converged()
            && (self.probe.is_none() || self.probe_done())
            && (!self.want_reference || self.reference_done())
            && (!self.overlays.is_on(Overlay::Gradients) || self.gradients.is_done())
            && (!self.compare_needed() || self.compare_done())
    }

    /// The compare view is open or an overlay shows its results (the records
    /// overlay shows the field's own records when the field comes from a cache).
    pub fn compare_needed(&self) -> bool {
        self.show_compare
            || self.overlays.is_on(Overlay::ErrorMap)
            || (self.overlays.is_on(Overlay::Records) && self.field_method == FieldMethod::PathTracing)
    }

    /// What the comparison is computed for now.
    pub fn compare_key(&self) -> CompareKey {
        let scene = self.doc.scene();
        CompareKey {
            revision: self.doc.revision(),
            fp: self.compare_params.field_params(scene, &self.field_params),
            params: self.compare_params.clone(),
        }
    }

    /// The latest comparison of the current key (possibly partial: reference first,
    /// then each method); None while a changed scene or parameter recomputes it.
    pub fn compare_result(&self) -> Option<&Arc<CompareResult>> {
        self.compare.current()
    }

    /// The comparison of the current key has every method.
    pub fn compare_done(&self) -> bool {
        self.compare.is_done() && self.compare_result().is_some_and(|r| r.is_complete())
    }

    /// A look at the current comparison job.
    pub fn compare_watch(&self) -> Option<super::jobs::JobWatch> {
        self.compare.job().map(|j| j.watch())
    }

    /// Comparison jobs started so far.
    pub fn compare_starts(&self) -> u64 {
        self.compare.starts
    }

    pub fn info(&mut self, text: impl Into<String>) {
        self.message = Some(Message {
            text: text.into(),
            error: false,
        });
    }

    pub fn error(&mut self, text: impl Into<String>) {
        self.message = Some(Message {
            text: text.into(),
            error: true,
        });
    }

    pub fn omega_o(&self) -> DVec2 {
        DVec2::from_angle(self.field_params.omega_o_deg.to_radians())
    }

    /// The latest field level, if any.
    pub fn field_level(&self) -> Option<&Arc<FieldLevel>> {
        self.field.latest()
    }

    /// The exposure the field is tone-mapped with (stops): the shown level's
    /// automatic exposure, or the slider's. Exports and the copied command use it.
    pub fn exposure(&self) -> f64 {
        let level = self.field.latest().filter(|_| self.display.auto_exposure);
        let Some(level) = level else {
            return self.display.exposure;
        };
        if let Some((id, e)) = &*self.auto_stops.borrow()
            && id.is(level)
        {
            return *e;
        }
        let e = crate::figure::auto_exposure(&level.rendered.field);
        *self.auto_stops.borrow_mut() = Some((ResultId::of(level), e));
        e
    }

    /// The field job of the current parameters has delivered every level.
    pub fn field_converged(&self) -> bool {
        self.field.is_done()
    }

    /// Field jobs started so far (each edit of the scene or a parameter starts one).
    pub fn field_starts(&self) -> u64 {
        self.field.starts
    }

    /// The current field job's status.
    pub fn field_status(&self) -> Option<super::jobs::Status> {
        self.field.job().map(|j| j.status())
    }

    /// A look at the current field job.
    pub fn field_watch(&self) -> Option<super::jobs::JobWatch> {
        self.field.job().map(|j| j.watch())
    }

    pub fn probe_result(&self) -> Option<&Arc<ProbeResult>> {
        self.probe_job.current().filter(|r| Some(r.at) == self.probe)
    }

    pub fn probe_done(&self) -> bool {
        self.probe.is_some() && self.probe_job.is_done() && self.probe_result().is_some()
    }

    pub fn reference_result(&self) -> Option<&Arc<ReferenceResult>> {
        self.reference.current()
    }

    pub fn reference_done(&self) -> bool {
        self.reference.is_done()
    }

    pub fn gradient_grid(&self) -> Option<&Arc<GradientGrid>> {
        self.gradients.current()
    }

    /// The scene file field of the side panel.
    pub fn scene_path_mut(&mut self) -> &mut String {
        &mut self.scene_path
    }

    /// The PNG path of "Export PNG".
    pub fn export_path_mut(&mut self) -> &mut String {
        &mut self.export_path
    }

    /// The canvas' rectangle in the last frame (tests check the layout with it).
    pub fn canvas_rect(&self) -> Option<egui::Rect> {
        self.canvas_rect
    }

    /// The screen position of a world point in the last frame's canvas.
    pub fn screen_pos(&self, world: DVec2) -> Option<egui::Pos2> {
        self.last_xf.map(|xf| xf.to_screen(world))
    }

    fn probe_settings(&self, rays: usize) -> ProbeSettings {
        self.method.probe_settings(rays, self.field_params.settings)
    }

    /// Take in results and (re)start the jobs the current state needs; never blocks.
    pub fn tick(&mut self) {
        self.field.update();
        self.probe_job.update();
        self.reference.update();
        self.gradients.update();
        self.compare.update();
        if self.doc.generation() != self.generation {
            // A different scene: its own render defaults, a fresh view, no probe.
            self.generation = self.doc.generation();
            let scene = self.doc.scene();
            self.field_params = FieldParams::from_scene(scene);
            self.display.exposure = scene.desc.render.exposure;
            self.view = ViewState::default();
            (self.probe, self.selection, self.want_reference) = (None, None, false);
            self.field.reset(true);
            self.gradients.reset(true);
            self.compare.reset(true);
            self.export_path = format!("out/{}_app.png", self.doc.stem());
            // The file field shows the scene's own file (undo past a load brings
            // back the previous one), so Save writes where the scene came from.
            self.scene_path = self.doc.path().map_or(String::new(), |p| p.display().to_string());
        }
        let scene = self.doc.scene().clone();
        let rev = self.doc.revision();
        let (seed, omega) = (self.field_params.seed, self.field_params.omega_o_deg);
        let notify = self.notify.clone();
        let fp = self.field_params.clone();
        let (fm, cf) = (self.field_method, self.cache_field);
        self.field.ensure((rev, fp.clone(), fm, cf), || match fm {
            FieldMethod::PathTracing => spawn_field(scene.clone(), fp, notify.clone()),
            FieldMethod::Cache(m) => spawn_cached_field(scene.clone(), fp, m, cf, notify.clone()),
        });

        match self.probe {
            Some(at) => {
                let ps = self.probe_settings(self.method.rays);
                let key = ProbeKey {
                    revision: rev,
                    at,
                    ps,
                    seed,
                    omega_o_deg: omega,
                };
                let omega_o = self.omega_o();
                self.probe_job.ensure(key, || {
                    spawn_probe(scene.clone(), at, omega_o, ps, seed, notify.clone())
                });
                let key = ReferenceKey {
                    revision: rev,
                    at,
                    spp: self.method.ref_spp,
                    fd_step: self.method.fd_step,
                    settings: self.field_params.settings,
                    seed,
                    omega_o_deg: omega,
                };
                if self.reference.key().is_some_and(|k| *k != key) {
                    self.reference.reset(true);
                    self.want_reference = self.auto_reference;
                }
                if self.want_reference {
                    let (spp, step, settings) = (key.spp, key.fd_step, key.settings);
                    self.reference.ensure(key, || {
                        spawn_reference(scene.clone(), at, omega_o, spp, step, settings, seed, notify.clone())
                    });
                }
            }
            None => {
                self.probe_job.reset(true);
                self.reference.reset(true);
            }
        }

        if self.overlays.is_on(Overlay::Gradients) {
            let ps = self.probe_settings(self.method.grid_rays);
            let n0 = self.method.grid.clamp(1, 128);
            let n_max = match self.method.grid_refine {
                true => self.field_params.width.max(self.field_params.height).clamp(n0, 1024),
                false => n0,
            };
            let n = (n0, n_max);
            let key = GradientKey {
                revision: rev,
                n,
                ps,
                seed,
                omega_o_deg: omega,
            };
            let omega_o = self.omega_o();
            self.gradients.ensure(key, || {
                spawn_gradients(scene.clone(), n, omega_o, ps, seed, notify.clone())
            });
        } else {
            self.gradients.reset(true);
        }

        if self.compare_needed() {
            let key = self.compare_key();
            let spawn = || spawn_compare(scene.clone(), &key, notify.clone());
            self.compare.ensure(key.clone(), spawn);
        } else if self.compare.running().is_some() {
            // Closed while computing: stop (the next opening starts anew).
            self.compare.reset(false);
        }
    }

    /// Some job is computing.
    pub fn busy(&self) -> bool {
        self.field.running().is_some()
            || self.probe_job.running().is_some()
            || self.reference.running().is_some()
            || self.gradients.running().is_some()
            || self.compare.running().is_some()
    }

    /// One frame of the whole window.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let start = Instant::now();
        if !self.has_ctx {
            let ctx = ui.ctx().clone();
            self.notify = Arc::new(move || ctx.request_repaint());
            self.has_ctx = true;
        }
        self.tick();
        self.shortcuts(ui);
        egui::Panel::top("toolbar").show(ui, |ui| self.toolbar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        // The side panels give way to the canvas, scroll what does not fit, and stay
        // in place whether or not there is a probe: placing one never moves the
        // canvas under the pointer.
        let width = ui.available_rect_before_wrap().width();
        let (controls_max, inspector_max) = panel_max_widths(width, self.show_controls, self.show_inspector);
        let scroll = || egui::ScrollArea::both().auto_shrink(false);
        if self.show_controls {
            egui::Panel::left("controls")
                .default_size(CONTROLS_WIDTH)
                .max_size(controls_max)
                .show(ui, |ui| scroll().show(ui, |ui| self.controls(ui)));
        }
        if self.show_inspector {
            egui::Panel::right("inspector")
                .default_size(INSPECTOR_WIDTH)
                .max_size(inspector_max)
                .show(ui, |ui| scroll().show(ui, |ui| self.inspector(ui)));
        }
        egui::CentralPanel::no_frame().show(ui, |ui| self.canvas(ui));
        self.compare_window(ui.ctx());
        self.open_window(ui.ctx());
        // Restart what this frame's edits made stale now, not a frame later.
        self.tick();

        // A gesture (drag, slider, typing a value) ends when the pointer is up and
        // no text field has focus.
        let idle = ui.input(|i| !i.pointer.any_down()) && !ui.ctx().text_edit_focused();
        if idle {
            self.doc.end_gesture();
        }
        if self.busy() {
            ui.ctx().request_repaint_after(Duration::from_millis(100));
        }
        if self.ready_file.is_some() && self.settled() {
            let path = self.ready_file.take().unwrap();
            if let Err(e) = std::fs::write(&path, "ready\n") {
                self.error(format!("writing {}: {e}", path.display()));
            }
        }
        let dt = ui.input(|i| i.unstable_dt);
        if self.stats.record(dt, start.elapsed(), self.busy()) {
            ui.ctx().request_repaint();
        }
    }
}

impl eframe::App for Workbench {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        Workbench::ui(self, ui);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> Workbench {
        let mut wb = Workbench::new(Document::default_scene());
        (wb.field_params.width, wb.field_params.height, wb.field_params.spp) = (8, 8, 1);
        (wb.method.rays, wb.method.steps, wb.method.grid, wb.method.grid_rays) = (16, 2, 2, 8);
        wb
    }

    #[test]
    fn tick_starts_what_is_needed_and_restarts_only_on_change() {
        let mut wb = small();
        wb.tick();
        assert_eq!(wb.field_starts(), 1);
        assert!(wb.probe_job.job().is_none() && wb.gradients.job().is_none());
        wb.tick();
        assert_eq!(wb.field_starts(), 1, "nothing changed");
        // A display change re-maps colours only.
        wb.display.exposure += 1.0;
        wb.tick();
        assert_eq!(wb.field_starts(), 1);
        // A scene edit restarts the field; the old job is told to stop.
        let old = wb.field_watch().unwrap();
        wb.doc.edit("g", |d| d.medium.as_mut().unwrap().g = 0.5).unwrap();
        wb.tick();
        assert!(old.is_cancel_requested());
        assert_eq!(wb.field_starts(), 2);
        // The probe, then the reference on demand; moving the probe drops the
        // reference unless it follows.
        wb.probe = Some(DVec2::new(0.0, -0.5));
        wb.tick();
        assert_eq!(wb.probe_job.starts, 1);
        assert!(wb.reference.job().is_none());
        wb.want_reference = true;
        wb.tick();
        assert_eq!(wb.reference.starts, 1);
        wb.probe = Some(DVec2::new(0.1, -0.5));
        wb.tick();
        assert_eq!((wb.probe_job.starts, wb.reference.starts), (2, 1));
        assert!(!wb.want_reference && wb.reference.job().is_none());
        wb.auto_reference = true;
        wb.want_reference = true;
        wb.tick();
        wb.probe = Some(DVec2::new(0.2, -0.5));
        wb.tick();
        assert_eq!(wb.reference.starts, 3, "following the probe");
        // Overlays: the gradient grid runs only while shown.
        wb.overlays.set(Overlay::Gradients, true);
        wb.tick();
        assert!(wb.gradients.job().is_some());
        wb.overlays.set(Overlay::Gradients, false);
        wb.tick();
        assert!(wb.gradients.job().is_none());
    }

    #[test]
    fn loading_another_scene_resets_its_render_settings() {
        let mut wb = small();
        wb.probe = Some(DVec2::ZERO);
        wb.tick();
        let json = crate::flatland::scene::DEFAULT_SCENE_JSON.replace("\"spp\": 128", "\"spp\": 3");
        wb.doc.load_json(&json, "other.json", None).unwrap();
        wb.tick();
        assert_eq!((wb.field_params.spp, wb.field_params.width), (3, 256));
        assert_eq!(wb.probe, None);
        wb.field.reset(true); // stop the 256² job
    }
}
