//! The 3D mode's state and scheduling: the scene ([`Document3d`]), what the view
//! renders ([`View3dParams`]) and how it is shown. [`Workbench3d::tick`] (no UI)
//! takes in results and restarts the render job (and the error map's reference,
//! [`super::error_map3d`]) when the scene, the camera or the parameters change,
//! cancelling the stale one; the widgets are in
//! [`super::panel3d`] (side panel, status bar) and [`super::view3d`] (the image,
//! camera motion, overlays).

use super::document3d::Document3d;
use super::error_map3d::{
    DEFAULT_REFERENCE_SPP, ErrorMap, ReferenceKey, error_map, reference_params, spawn_reference3d,
};
use super::jobs::{Notify, Slot, no_notify};
use super::probe3d::{Probe3d, Probe3dKey, Probe3dResult, spawn_probe3d};
use super::render3d_job::{Frame3d, Method3d, View3dParams, spawn_render3d};
use crate::core::stats::ImageErrors;
use crate::figure::{auto_exposure, colormap::tonemap};
use crate::output::image_field;
use crate::volume::cached::Placement;
use crate::volume::render::Rendered;
use eframe::egui;
use std::sync::Arc;

/// The scene description with a fixed camera: what a cache with moments over ω_o
/// must share with the state it is reused in.
fn without_camera(desc: &crate::volume::scene_desc::SceneDesc) -> crate::volume::scene_desc::SceneDesc {
    let mut d = desc.clone();
    d.camera = crate::volume::scene_desc::CameraDesc {
        position: [0.0; 3],
        look_at: [0.0; 3],
        up: [0.0; 3],
        fov_deg: 0.0,
    };
    d
}

/// The default width of the view's image, pixels (the aspect is the scene's).
pub const DEFAULT_VIEW_WIDTH: usize = 200;

/// What the records' overlay texture was drawn for: frame, shading, size in
/// pixels, scene revision.
pub type RecordsTexKey = (usize, RecordShade, u32, u32, u64);

#[derive(Clone, Debug, PartialEq)]
pub struct RenderKey {
    revision: u64,
    params: View3dParams,
}

/// What colours the records drawn over the image (as `figure compare3d`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecordShade {
    /// Geometric mean of the ellipsoid's radii.
    Radius,
    Luminance,
    /// Rays traced for its light field.
    Cost,
}

/// How the image is shown (changing it never recomputes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Display3d {
    /// The medium's in-scattered part alone (∫ T L_s dt), not the whole image.
    pub medium_only: bool,
    pub auto_exposure: bool,
    pub exposure: f64,
    pub show_records: bool,
    pub record_shade: RecordShade,
    /// Show the error against a reference of the same camera instead of the image.
    pub error_map: bool,
}

pub struct Workbench3d {
    pub doc: Document3d,
    pub params: View3dParams,
    pub display: Display3d,
    pub render: Slot<RenderKey, Arc<Frame3d>>,
    pub probe: Option<Probe3d>,
    pub probe_job: Slot<Probe3dKey, Arc<Probe3dResult>>,
    /// The file field of the side panel (Open / Save).
    pub scene_path: String,
    pub message: Option<(String, bool)>,
    pub(super) notify: Notify,
    pub(super) has_ctx: bool,
    /// The image's texture and the frame, display and error map it shows.
    pub(super) texture: Option<(egui::TextureHandle, usize, Display3d, bool)>,
    /// Counts frames and references taken in, so the texture knows when to update.
    pub(super) frames: usize,
    /// The reference of the error map, for the current state (rendered while the
    /// error map is asked for) and its samples per pixel.
    pub reference: Slot<ReferenceKey, Arc<Rendered>>,
    pub reference_spp: u32,
    /// The errors of the error map on view (None when it is not shown) and its
    /// colour range.
    pub error_shown: Option<(ImageErrors, (f64, f64))>,
    /// Written once the view (and the probe) finished refining.
    pub ready_file: Option<std::path::PathBuf>,
    pub show_inspector: bool,
    /// The probe inspector draws the proxy's triangles on its light-field map.
    pub show_proxy: bool,
    /// The compare window: its parameters, whether it is open, its job and the
    /// textures of the result they show.
    pub compare_params: super::compare3d::Compare3dParams,
    pub show_compare: bool,
    pub compare: Slot<(u64, super::compare3d::Compare3dParams), Arc<super::compare3d::Compare3dOutcome>>,
    pub(super) compare_tex: Option<(Arc<super::compare3d::Compare3dOutcome>, Vec<egui::TextureHandle>)>,
    /// Where the image was drawn last frame (tests click and drag in it).
    pub view_rect: Option<egui::Rect>,
    /// The records' overlay texture, its key (frame, shading, size, revision) and
    /// how many discs it holds.
    pub(super) records_tex: Option<(RecordsTexKey, egui::TextureHandle, usize)>,
    /// The probe inspector's light-field map: its result, proxy shown, width, texture.
    pub(super) light_field_tex: Option<(Arc<Probe3dResult>, bool, u32, egui::TextureHandle)>,
    /// Record discs the view drew last frame (tests check the overlay through it).
    pub records_drawn: usize,
    /// The last full-size cache with moments over ω_o, and the scene (camera
    /// aside) and view parameters it was placed for: a camera move starts from it.
    kept: Option<(crate::volume::scene_desc::SceneDesc, View3dParams, Arc<Placement>)>,
    stats: super::frame_stats::FrameStats,
}

impl Workbench3d {
    pub fn new(doc: Document3d) -> Self {
        let params = View3dParams::for_scene(doc.scene(), DEFAULT_VIEW_WIDTH);
        Workbench3d {
            scene_path: doc.path().map_or(String::new(), |p| p.display().to_string()),
            params,
            display: Display3d {
                medium_only: false,
                auto_exposure: true,
                exposure: doc.desc().render.exposure,
                show_records: true,
                record_shade: RecordShade::Radius,
                error_map: false,
            },
            doc,
            render: Slot::default(),
            probe: None,
            probe_job: Slot::default(),
            message: None,
            notify: no_notify(),
            has_ctx: false,
            texture: None,
            frames: 0,
            reference: Slot::default(),
            reference_spp: DEFAULT_REFERENCE_SPP,
            error_shown: None,
            ready_file: None,
            show_inspector: true,
            show_proxy: true,
            records_drawn: 0,
            kept: None,
            records_tex: None,
            light_field_tex: None,
            view_rect: None,
            compare_params: Default::default(),
            show_compare: false,
            compare: Slot::default(),
            compare_tex: None,
            stats: super::frame_stats::FrameStats::from_env(),
        }
    }

    /// Apply the command line's start options (`volcache app SCENE3D …`).
    pub fn start(&mut self, s: &super::StartOptions) {
        if let Some(m) = s.method3d {
            self.params.method = m;
        }
        if let Some(w) = s.view_width {
            let width = self.params.width;
            self.params = View3dParams {
                method: self.params.method,
                ..View3dParams::for_scene(self.doc.scene(), if w > 0 { w } else { width })
            };
        }
        if let Some(p) = s.pixel {
            let pixel = p.clamp(glam::DVec2::ZERO, glam::DVec2::ONE);
            let mut probe = super::probe3d::Probe3d::at_pixel(self.doc.scene(), pixel);
            probe.reference = s.reference;
            self.probe = Some(probe);
        }
        self.ready_file = s.ready_file.clone();
    }

    pub fn info(&mut self, s: impl Into<String>) {
        self.message = Some((s.into(), false));
    }

    pub fn error(&mut self, s: impl Into<String>) {
        self.message = Some((s.into(), true));
    }

    /// Take in results; start (and cancel) jobs for the current state.
    pub fn tick(&mut self) {
        if self.render.update() {
            self.frames += 1;
        }
        self.probe_job.update();
        self.compare.update();
        if self.reference.update() {
            self.frames += 1;
        }
        let key = RenderKey {
            revision: self.doc.revision(),
            params: self.params.clone(),
        };
        self.keep_moments(&key);
        let (scene, params, notify) = (self.doc.scene().clone(), self.params.clone(), self.notify.clone());
        let earlier = self.earlier_records();
        self.render
            .ensure(key, || spawn_render3d(scene, params, earlier, notify));
        if let Some(p) = &self.probe {
            let key = p.key(self.doc.revision(), &self.params);
            let (scene, probe, notify) = (self.doc.scene().clone(), p.clone(), self.notify.clone());
            let params = self.params.clone();
            self.probe_job
                .ensure(key, || spawn_probe3d(scene, probe, params, notify));
        } else {
            self.probe_job.reset(true);
        }
        let rp = reference_params(self.doc.scene(), &self.params, self.reference_spp);
        let key = ReferenceKey {
            revision: self.doc.revision(),
            params: rp.clone(),
        };
        if self.display.error_map {
            let (scene, notify) = (self.doc.scene().clone(), self.notify.clone());
            self.reference.ensure(key, || spawn_reference3d(scene, rp, notify));
        } else if self.reference.key() != Some(&key) && self.reference.running().is_some() {
            // Nobody looks at it, and it is for another state: stop it.
            self.reference.reset(false);
        }
    }

    /// Keep the current state's finished full-size cache when its records carry
    /// moments over ω_o.
    /// (`key` is the current state's: the slot's frame may still be an older
    /// state's until the next job starts.)
    fn keep_moments(&mut self, key: &RenderKey) {
        if self.params.moment_bands.is_none() || self.render.key() != Some(key) {
            return;
        }
        let Some(f) = self.render.current() else { return };
        let already = |p: &Arc<Placement>| self.kept.as_ref().is_some_and(|k| Arc::ptr_eq(&k.2, p));
        // Once per finished frame, not per UI frame (the description is cloned).
        if let (true, Some(p)) = (f.level == f.levels, &f.placement)
            && !already(p)
        {
            self.kept = Some((without_camera(self.doc.desc()), self.params.clone(), p.clone()));
        }
    }

    /// The kept cache, if it was placed for this scene and these parameters from
    /// another camera (a camera move keeps the records; any other change drops them).
    pub fn earlier_records(&self) -> Option<Arc<Placement>> {
        let (desc, params, p) = self.kept.as_ref()?;
        let same =
            self.params.moment_bands.is_some() && *params == self.params && *desc == without_camera(self.doc.desc());
        same.then(|| p.clone())
    }

    /// The error map of `frame` the view shows: asked for, the frame and the
    /// reference both of the current state, and of one size (not a coarse level).
    pub fn current_error_map(&self, frame: &Frame3d) -> Option<ErrorMap> {
        if !self.error_map_shown(frame) {
            return None;
        }
        error_map(&frame.image, self.reference.current()?, self.display.medium_only)
    }

    /// Whether the view shows `frame`'s error map (a cheap test: no map is made).
    pub fn error_map_shown(&self, frame: &Frame3d) -> bool {
        let (w, h) = (frame.image.width, frame.image.height);
        self.display.error_map
            && self.frame_is_current()
            && self.reference.current().is_some_and(|r| (r.width, r.height) == (w, h))
    }

    /// The latest frame, whichever state it was computed for.
    pub fn frame(&self) -> Option<&Arc<Frame3d>> {
        self.render.latest()
    }

    /// The latest frame belongs to the current scene, camera and parameters.
    pub fn frame_is_current(&self) -> bool {
        self.render.current().is_some()
    }

    /// The refinement finished for the current state.
    pub fn settled(&self) -> bool {
        self.render.is_done()
            && (self.probe.is_none() || self.probe_job.is_done())
            && (!self.display.error_map || self.reference.is_done())
    }

    pub fn set_method(&mut self, m: Method3d) {
        self.params.method = m;
    }

    /// The image as shown: the frame's values (or medium part) tone-mapped, RGBA.
    pub fn display_rgba(&self, frame: &Frame3d) -> Vec<u8> {
        let img = &frame.image;
        let values = if self.display.medium_only {
            &img.medium
        } else {
            &img.values
        };
        let exposure = if self.display.auto_exposure {
            auto_exposure(&image_field(img.width, img.height, values))
        } else {
            self.display.exposure
        };
        values
            .iter()
            .flat_map(|v| {
                let [r, g, b] = tonemap(*v, exposure);
                [r, g, b, 255]
            })
            .collect()
    }

    /// `volcache render3d …` reproducing the latest frame (the scene as saved:
    /// with unsaved edits or camera moves the command names a file that differs).
    pub fn command(&self) -> Option<String> {
        let f = self.frame()?;
        let scene = self.doc.path().map_or_else(
            || format!("scenes3d/{}.json", self.doc.stem()),
            |p| p.display().to_string(),
        );
        let ip = &f.image_params;
        let mut c = format!(
            "volcache render3d {scene} --method {} --res {}x{} --spp {} --seed {}",
            f.method.cli_name(),
            ip.width,
            ip.height,
            ip.spp,
            ip.seed
        );
        if f.method != Method3d::PathTracing {
            c += &format!(
                " --eps {:e} --rays {} --steps {}",
                f.eps, self.params.rays, self.params.steps
            );
            if self.params.surface_cache {
                c += " --surface-cache ours";
            }
            if let Some(k) = self.params.edge_reach {
                c += &format!(" --edge-reach {k}");
            }
            match self.params.lamp_reach {
                None => c += " --no-lamp-reach",
                Some(k) if k != crate::pipeline::budget::VOLUME_LAMP_REACH => c += &format!(" --lamp-reach {k}"),
                Some(_) => {}
            }
            if let Some(a) = self.params.eye_cone_deg {
                c += &format!(" --eye-cone {a}");
            }
            if self.params.gradient_noise_reach && f.method == Method3d::Ours {
                c += " --gradient-noise-reach";
            }
        }
        if f.carried > 0 {
            c += &format!(
                "  # the view reused {} records from earlier cameras; this command places afresh",
                f.carried
            );
        }
        Some(c)
    }

    pub fn busy(&self) -> bool {
        self.render.running().is_some()
            || self.probe_job.running().is_some()
            || self.compare.running().is_some()
            || self.reference.running().is_some()
    }

    /// One frame of the 3D mode: side panel, status bar, inspector, view.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let start = std::time::Instant::now();
        if !self.has_ctx {
            let ctx = ui.ctx().clone();
            self.notify = Arc::new(move || ctx.request_repaint());
            self.has_ctx = true;
        }
        self.tick();
        if ui.input_mut(|i| i.consume_key(egui::Modifiers::COMMAND, egui::Key::Z)) {
            self.undo();
        }
        if ui.input_mut(|i| i.consume_key(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z)) {
            self.redo();
        }
        egui::Panel::bottom("status3d").show(ui, |ui| self.status_bar(ui));
        let width = ui.available_rect_before_wrap().width();
        let (controls_max, inspector_max) = super::layout::panel_max_widths(width, true, self.show_inspector);
        let scroll = || egui::ScrollArea::both().auto_shrink(false);
        egui::Panel::left("controls3d")
            .default_size(super::layout::CONTROLS_WIDTH)
            .max_size(controls_max)
            .show(ui, |ui| scroll().show(ui, |ui| self.controls(ui)));
        if self.show_inspector {
            egui::Panel::right("inspector3d")
                .default_size(super::layout::INSPECTOR_WIDTH)
                .max_size(inspector_max)
                .show(ui, |ui| scroll().show(ui, |ui| self.inspector(ui)));
        }
        egui::CentralPanel::no_frame().show(ui, |ui| self.view(ui));
        self.compare_window(ui.ctx());
        // Restart what this frame's edits made stale now, not a frame later.
        self.tick();
        let idle = ui.input(|i| !i.pointer.any_down()) && !ui.ctx().text_edit_focused();
        if idle {
            self.doc.end_gesture();
        }
        if self.busy() {
            ui.ctx().request_repaint_after(std::time::Duration::from_millis(100));
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

    /// Undo / redo with a message.
    pub fn undo(&mut self) {
        if self.doc.undo() {
            self.info("undone");
        }
    }

    pub fn redo(&mut self) {
        if self.doc.redo() {
            self.info("redone");
        }
    }

    /// Load a 3D scene file; on error keep the scene and show why.
    pub fn load_file(&mut self, path: &std::path::Path) {
        match Document3d::open(path) {
            Ok(doc) => self.replace(doc, format!("loaded {}", path.display())),
            Err(e) => self.error(e.to_string()),
        }
    }

    pub fn load_shipped(&mut self, name: &str) {
        match Document3d::shipped(name) {
            Ok(doc) => self.replace(doc, format!("loaded the shipped {name} (Save asks for a file name)")),
            Err(e) => self.error(e.to_string()),
        }
    }

    fn replace(&mut self, doc: Document3d, msg: String) {
        let width = self.params.width;
        self.scene_path = doc.path().map_or(String::new(), |p| p.display().to_string());
        self.params = View3dParams {
            method: self.params.method,
            ..View3dParams::for_scene(doc.scene(), width)
        };
        self.display.exposure = doc.desc().render.exposure;
        self.doc = doc;
        self.probe = None;
        self.info(msg);
    }

    /// Save the scene (with the current camera) to the file named in the file
    /// field: never to a name the app made up.
    pub fn save(&mut self) {
        let p = std::path::PathBuf::from(self.scene_path.trim());
        if p.as_os_str().is_empty() {
            return self.error("type a file name to save the scene to");
        }
        match self.doc.save(&p) {
            Ok(()) => self.info(format!("saved {} (with the current camera)", p.display())),
            Err(e) => self.error(format!("saving {}: {e:#}", p.display())),
        }
    }
}
