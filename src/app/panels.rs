//! The side panel (scene file, field, scene editors, method, export) and the status
//! bar (what is computing, its progress with Cancel, and the cost so far).

use super::command::field_command;
use super::jobs::{Job, Status};
use super::workbench::Workbench;
use crate::figure::field_figure;
use crate::flatland::scene_desc::{Part, Quantity};
use crate::output::write_png;
use eframe::egui::{self, Color32, DragValue, RichText};
use std::path::{Path, PathBuf};

impl Workbench {
    pub(super) fn controls(&mut self, ui: &mut egui::Ui) {
        ui.add_space(4.0);
        egui::CollapsingHeader::new("Scene file")
            .default_open(true)
            .show(ui, |ui| self.file_section(ui));
        egui::CollapsingHeader::new("Field")
            .default_open(true)
            .show(ui, |ui| self.field_section(ui));
        egui::CollapsingHeader::new("Edit")
            .default_open(true)
            .show(ui, |ui| self.selection_editor(ui));
        egui::CollapsingHeader::new("Medium")
            .default_open(true)
            .show(ui, |ui| self.medium_editor(ui));
        egui::CollapsingHeader::new("Methods")
            .default_open(false)
            .show(ui, |ui| self.method_section(ui));
        egui::CollapsingHeader::new("Export")
            .default_open(true)
            .show(ui, |ui| self.export_section(ui));
    }

    /// Load a scene file; on error keep the scene and show why.
    pub fn load_scene(&mut self, path: &Path) {
        // A 3D scene opens in the window's 3D mode (see `super::mode`).
        if std::fs::read_to_string(path).is_ok_and(|t| crate::scene_check::is_3d_json(&t)) {
            self.open_3d = Some(path.to_path_buf());
            self.open_dialog.open = false;
            return;
        }
        match self.doc.load_file(path) {
            Ok(()) => {
                self.scene_path = path.display().to_string();
                self.info(format!("loaded {}", path.display()));
            }
            Err(e) => self.error(e.to_string()),
        }
    }

    /// Save to the file named in the file field (never to a name the app made up:
    /// an embedded scene has none until the user types one).
    pub fn save_scene(&mut self) {
        let p = PathBuf::from(self.scene_path.trim());
        if p.as_os_str().is_empty() {
            self.error("type a file name to save the scene to");
            return;
        }
        match self.doc.save(&p) {
            Ok(()) => self.info(format!("saved {}", p.display())),
            Err(e) => self.error(format!("saving {}: {e:#}", p.display())),
        }
    }

    fn file_section(&mut self, ui: &mut egui::Ui) {
        ui.label(RichText::new(&self.doc.desc().description).weak());
        ui.horizontal(|ui| {
            let l = ui.label("file");
            let hint = format!("<embedded {}>", crate::flatland::scene::DEFAULT_SCENE_NAME);
            let edit = egui::TextEdit::singleline(&mut self.scene_path).hint_text(hint);
            ui.add(edit.desired_width(f32::INFINITY)).labelled_by(l.id);
        });
        ui.horizontal(|ui| {
            if ui.button("Load").clicked() {
                let p = PathBuf::from(self.scene_path.trim());
                self.load_scene(&p);
            }
            if ui.button("Save").clicked() {
                self.save_scene();
            }
            ui.toggle_value(&mut self.open_dialog.open, "Open…")
                .on_hover_text("the shipped scenes, or a scene file from any folder");
        });
    }

    fn field_section(&mut self, ui: &mut egui::Ui) {
        let p = &mut self.field_params;
        ui.horizontal(|ui| {
            ui.selectable_value(&mut p.quantity, Quantity::Ls, "L_s");
            ui.selectable_value(&mut p.quantity, Quantity::Fluence, "fluence");
            ui.separator();
            let l = ui.label("part");
            egui::ComboBox::from_id_salt("part")
                .selected_text(super::command::part_arg(p.part))
                .show_ui(ui, |ui| {
                    for part in [Part::All, Part::Direct, Part::Single, Part::Multiple] {
                        ui.selectable_value(&mut p.part, part, super::command::part_arg(part));
                    }
                })
                .response
                .labelled_by(l.id);
        });
        ui.horizontal(|ui| {
            ui.label("resolution");
            ui.add(DragValue::new(&mut p.width).range(1..=4096))
                .accessible_name("field width (pixels)");
            ui.label("×");
            ui.add(DragValue::new(&mut p.height).range(1..=4096))
                .accessible_name("field height (pixels)");
        });
        ui.horizontal(|ui| {
            let l = ui.label("spp");
            ui.add(DragValue::new(&mut p.spp).range(1..=1_000_000).speed(1.0))
                .labelled_by(l.id);
            let l = ui.label("seed");
            ui.add(DragValue::new(&mut p.seed)).labelled_by(l.id);
        });
        ui.add(egui::Slider::new(&mut p.omega_o_deg, -180.0..=180.0).text("ω_o (deg)"));
        ui.checkbox(&mut self.display.false_color, "false colour (log)");
        ui.add_enabled_ui(!self.display.false_color, |ui| {
            ui.horizontal(|ui| {
                let mut auto = self.display.auto_exposure;
                let r = ui.checkbox(&mut auto, "auto exposure").on_hover_text(format!(
                    "the brightest {:.0}% of the field's pixels just reach white",
                    100.0 * (1.0 - crate::figure::AUTO_EXPOSURE_PERCENTILE)
                ));
                if r.changed() {
                    // Manual from where auto was: the image does not jump.
                    self.display.exposure = self.exposure();
                    self.display.auto_exposure = auto;
                }
                // While automatic, the slider shows the exposure in use.
                let mut shown = self.exposure();
                let value = if auto { &mut shown } else { &mut self.display.exposure };
                ui.add_enabled(!auto, egui::Slider::new(value, -40.0..=40.0).text("stops"));
            });
        });
    }

    fn method_section(&mut self, ui: &mut egui::Ui) {
        let m = &mut self.method;
        egui::Grid::new("methods").num_columns(2).show(ui, |ui| {
            let l = ui.label("probe rays");
            ui.add(DragValue::new(&mut m.rays).range(3..=1 << 18)).labelled_by(l.id);
            ui.end_row();
            let l = ui.label("medium steps per ray");
            ui.add(DragValue::new(&mut m.steps).range(1..=1024)).labelled_by(l.id);
            ui.end_row();
            let l = ui.label("paths per sample");
            ui.add(DragValue::new(&mut m.paths).range(1..=256)).labelled_by(l.id);
            ui.end_row();
            let l = ui.label("reference spp");
            ui.add(DragValue::new(&mut m.ref_spp).range(8..=100_000_000).speed(100.0))
                .labelled_by(l.id);
            ui.end_row();
            let l = ui.label("FD step (× scene size)");
            ui.add(
                DragValue::new(&mut m.fd_step)
                    .range(1e-6..=0.2)
                    .speed(1e-4)
                    .max_decimals(6),
            )
            .labelled_by(l.id);
            ui.end_row();
            let l = ui.label("ε (cache metric)");
            ui.add(
                DragValue::new(&mut m.eps)
                    .range(0.0..=100.0)
                    .speed(1e-3)
                    .max_decimals(6),
            )
            .labelled_by(l.id);
            ui.end_row();
            let l = ui.label("gradient grid");
            ui.add(DragValue::new(&mut m.grid).range(1..=128)).labelled_by(l.id);
            ui.end_row();
            let l = ui.label("gradient rays");
            ui.add(DragValue::new(&mut m.grid_rays).range(3..=1 << 16))
                .labelled_by(l.id);
            ui.end_row();
        });
        ui.horizontal(|ui| {
            ui.label("gradient overlay:");
            ui.radio_value(&mut self.gradient_aware, true, "aware (ours)");
            ui.radio_value(&mut self.gradient_aware, false, "unaware (Jarosz 2008)");
        });
        ui.horizontal_wrapped(|ui| {
            ui.label("field:");
            for m in super::field_method::FieldMethod::ALL {
                ui.radio_value(&mut self.field_method, m, m.label());
            }
        });
        if self.field_method != super::field_method::FieldMethod::PathTracing {
            ui.horizontal(|ui| {
                let c = &mut self.cache_field;
                let l = ui.label("cache ε");
                ui.add(DragValue::new(&mut c.eps).range(1e-6..=10.0).speed(1e-3))
                    .labelled_by(l.id);
                let l = ui.label("rays");
                ui.add(DragValue::new(&mut c.rays).range(3..=1 << 16)).labelled_by(l.id);
            });
            ui.weak("the records overlay shows the field's records");
        }
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.gradient_arrows, "arrows");
            ui.checkbox(&mut self.method.grid_refine, "refine to one cell per pixel")
                .on_hover_text("after the gradient grid, double it up to the field's resolution");
        });
        self.compare_section(ui);
    }

    /// The scene argument of commands: the file if it holds what is shown, else a
    /// saved copy of the edited scene (`None`: the embedded default).
    pub(super) fn scene_arg(&mut self) -> anyhow::Result<Option<String>> {
        if !self.doc.is_dirty() {
            return Ok(self.doc.path().map(|p| p.display().to_string()));
        }
        let p = PathBuf::from(format!(
            "out/{}_edited.json",
            self.doc.stem().trim_end_matches("_edited")
        ));
        // A copy for the command only: the document keeps its own file for Save.
        self.doc.write_copy(&p)?;
        Ok(Some(p.display().to_string()))
    }

    /// The `volcache field` line for the full-resolution field.
    pub fn field_command(&mut self) -> anyhow::Result<String> {
        // A cached field is `volcache caches`' reconstruction, whose command also
        // renders a reference; it is not offered as this field's command.
        anyhow::ensure!(
            self.field_method == super::field_method::FieldMethod::PathTracing,
            "the field shown comes from a radiance cache: its command line is `volcache caches` \
             (with a reference); switch the field to path tracing to copy `volcache field`"
        );
        let scene = self.scene_arg()?;
        Ok(field_command(
            scene.as_deref(),
            &self.field_params,
            self.exposure(),
            self.display.false_color,
            &self.export_path,
        ))
    }

    /// Write the shown field as the command line's figure would.
    pub fn export_png(&mut self) -> anyhow::Result<PathBuf> {
        let level = self
            .field_level()
            .cloned()
            .ok_or_else(|| anyhow::anyhow!("no field yet"))?;
        let p = &level.params;
        let title = format!(
            "{}: {} ({:?}), {} spp",
            self.doc.stem(),
            if p.quantity == Quantity::Ls { "L_s" } else { "fluence" },
            p.part,
            p.spp
        );
        let pix = field_figure(
            &level.rendered.field,
            Some(self.doc.scene()),
            &self.field_style(),
            Some(&title),
        );
        let path = PathBuf::from(self.export_path.trim());
        write_png(&path, &pix)?;
        Ok(path)
    }

    fn export_section(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let l = ui.label("PNG");
            ui.add(egui::TextEdit::singleline(&mut self.export_path).desired_width(f32::INFINITY))
                .labelled_by(l.id);
        });
        ui.horizontal(|ui| {
            if ui.button("Export PNG").clicked() {
                match self.export_png() {
                    Ok(p) => {
                        let partial = !self.field_converged();
                        let note = if partial {
                            " (a coarse level: refinement not finished)"
                        } else {
                            ""
                        };
                        self.info(format!("wrote {}{note}", p.display()));
                    }
                    Err(e) => self.error(format!("export: {e:#}")),
                }
            }
            if ui.button("Copy as command").clicked() {
                match self.field_command() {
                    Ok(c) => {
                        ui.ctx().copy_text(c.clone());
                        self.info(format!("copied: {c}"));
                    }
                    Err(e) => self.error(format!("saving the edited scene: {e:#}")),
                }
            }
        });
        ui.weak("The command renders the full-resolution field headless, bit-identical to the last level.");
    }

    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
        let mut cancel = [false; 5];
        ui.horizontal_wrapped(|ui| {
            cancel[0] = job_status(ui, "field", self.field.job());
            cancel[1] = job_status(ui, "probe", self.probe_job.job());
            cancel[2] = job_status(ui, "reference", self.reference.job());
            cancel[3] = job_status(ui, "gradients", self.gradients.job());
            cancel[4] = job_status(ui, "compare", self.compare.job());
        });
        if cancel[0] {
            self.field.cancel();
        }
        if cancel[1] {
            self.probe_job.cancel();
        }
        if cancel[2] {
            self.reference.cancel();
        }
        if cancel[3] {
            self.gradients.cancel();
        }
        if cancel[4] {
            self.compare.cancel();
        }
        if let Some(m) = &self.message {
            let color = if m.error {
                Color32::from_rgb(255, 110, 100)
            } else {
                ui.visuals().weak_text_color()
            };
            ui.add(egui::Label::new(RichText::new(&m.text).color(color)).wrap());
        }
    }
}

/// One job in the status bar; returns true if its Cancel was clicked.
fn job_status<T>(ui: &mut egui::Ui, name: &str, job: Option<&Job<T>>) -> bool {
    let Some(j) = job else { return false };
    let cost = format!("{:.2} M rays, {:.1} s", j.rays() as f64 / 1e6, j.seconds());
    match j.status() {
        Status::Running => {
            ui.label(j.stage());
            ui.add(
                egui::ProgressBar::new(j.fraction() as f32)
                    .desired_width(110.0)
                    .show_percentage(),
            );
            ui.label(cost);
            let clicked = ui.small_button(format!("Cancel {name}")).clicked();
            ui.separator();
            clicked
        }
        Status::Finished => {
            ui.weak(format!("{name} done: {cost}"));
            ui.separator();
            false
        }
        Status::Cancelled => {
            ui.weak(format!("{name} cancelled"));
            ui.separator();
            false
        }
        Status::Failed(m) => {
            ui.colored_label(Color32::RED, format!("{name} failed: {m}"));
            false
        }
    }
}
