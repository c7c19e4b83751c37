//! The 3D mode's side panel (scene, method, display, medium and light edits,
//! camera) and status bar. Edits go through [`super::document3d::Document3d`],
//! whose validation is the scene loader's; a refused edit shows its error.

use super::document3d::SHIPPED_SCENES_3D;
use super::render3d_job::{DEFAULT_MOMENT_BANDS, Method3d};
use super::workbench3d::{RecordShade, Workbench3d};
use crate::core::harmonics::MAX_BANDS;
use crate::volume::scene_desc::{Color, LightDesc, SceneDesc};
use eframe::egui;

/// A value edited after its label (the label names it for screen readers).
pub(super) fn labelled(ui: &mut egui::Ui, label: &str, widget: impl egui::Widget) -> egui::Response {
    ui.horizontal(|ui| {
        let l = ui.label(label);
        ui.add(widget).labelled_by(l.id)
    })
    .inner
}

/// A colour field edited as one grey value (its mean) or per channel.
fn color_edit(ui: &mut egui::Ui, label: &str, c: &Color, speed: f64) -> Option<Color> {
    let mut v = c.0;
    let grey = v[0] == v[1] && v[1] == v[2];
    let mut changed = false;
    ui.horizontal(|ui| {
        let l = ui.label(label);
        let drag = |ui: &mut egui::Ui, x: &mut f64| {
            let d = egui::DragValue::new(x).speed(speed).range(0.0..=f64::MAX);
            ui.add(d).labelled_by(l.id).changed()
        };
        if grey {
            let mut x = v[0];
            changed |= drag(ui, &mut x);
            v = [x; 3];
        } else {
            for x in &mut v {
                changed |= drag(ui, x);
            }
        }
    });
    changed.then_some(Color(v))
}

impl Workbench3d {
    /// Apply an edit, showing the loader's error when it is refused.
    fn apply(&mut self, key: &str, f: impl FnOnce(&mut SceneDesc)) {
        if let Err(e) = self.doc.edit(key, f) {
            self.error(e.to_string());
        }
    }

    pub(super) fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("3D scene");
        ui.label(format!(
            "{}{}",
            self.doc.stem(),
            if self.doc.is_dirty() { " (modified)" } else { "" }
        ));
        ui.horizontal_wrapped(|ui| {
            for (name, _) in SHIPPED_SCENES_3D {
                if ui.button(name).clicked() {
                    self.load_shipped(name);
                }
            }
        });
        ui.horizontal(|ui| {
            let l = ui.label("file");
            ui.add(egui::TextEdit::singleline(&mut self.scene_path).desired_width(150.0))
                .labelled_by(l.id);
        });
        ui.horizontal(|ui| {
            if ui.button("Open").clicked() {
                let p = std::path::PathBuf::from(self.scene_path.trim());
                self.load_file(&p);
            }
            if ui
                .button("Save")
                .on_hover_text("the scene with the current camera")
                .clicked()
            {
                self.save();
            }
            if ui.add_enabled(self.doc.can_undo(), egui::Button::new("Undo")).clicked() {
                self.undo();
            }
            if ui.add_enabled(self.doc.can_redo(), egui::Button::new("Redo")).clicked() {
                self.redo();
            }
        });
        ui.separator();
        self.method_controls(ui);
        ui.separator();
        self.display_controls(ui);
        ui.separator();
        self.medium_controls(ui);
        self.light_controls(ui);
        ui.separator();
        ui.strong("Camera");
        ui.label("drag: orbit · right/middle or Shift+drag: pan · wheel: dolly · click: probe");
        if ui.button("Reset camera").clicked() {
            self.doc.reset_camera();
        }
        ui.separator();
        if ui
            .button("Compare view…")
            .on_hover_text("reference, ours and Jarosz 2008 at equal count, path tracing at equal time")
            .clicked()
        {
            self.show_compare = true;
        }
    }

    fn method_controls(&mut self, ui: &mut egui::Ui) {
        ui.strong("Method");
        ui.horizontal_wrapped(|ui| {
            for m in Method3d::ALL {
                if ui.selectable_label(self.params.method == m, m.label()).clicked() {
                    self.set_method(m);
                }
            }
        });
        let p = &mut self.params;
        let mut width = p.width;
        labelled(
            ui,
            &format!("width (height {})", p.height),
            egui::DragValue::new(&mut width).range(16..=1280),
        );
        if width != p.width {
            let [w, h] = self.doc.desc().render.resolution;
            p.height = ((width as f64 * h as f64 / w as f64).round() as usize).max(4);
            p.width = width;
        }
        match p.method {
            Method3d::PathTracing => {
                labelled(
                    ui,
                    "samples per pixel",
                    egui::DragValue::new(&mut p.spp).range(1..=65536),
                );
            }
            _ => {
                labelled(
                    ui,
                    "rays per record",
                    egui::DragValue::new(&mut p.rays).range(16..=65536),
                );
                labelled(
                    ui,
                    "camera samples",
                    egui::DragValue::new(&mut p.cache_spp).range(1..=64),
                );
                let mut custom = p.eps.is_some();
                ui.horizontal(|ui| {
                    let c = ui.checkbox(&mut custom, "ε");
                    if let Some(e) = &mut p.eps {
                        ui.add(egui::DragValue::new(e).speed(1e-4).range(1e-9..=10.0))
                            .labelled_by(c.id);
                    } else {
                        ui.label("scene default");
                    }
                });
                if custom != p.eps.is_some() {
                    p.eps = custom.then(|| self.render.current().map_or(1e-3, |f| f.eps.max(1e-9)));
                }
                // Records with moments over ω_o serve any camera: a camera move then
                // places only where the earlier records leave points uncovered.
                let mut keep = p.moment_bands.is_some();
                ui.horizontal(|ui| {
                    ui.checkbox(&mut keep, "keep records when the camera moves")
                        .on_hover_text(
                            "Records store their moments over the outgoing direction (spherical harmonics \
                             to band L, (L+1)² derivative passes each) so that another camera reads them \
                             for its own directions; truncation error ~ g^(L+1).",
                        );
                    if let Some(b) = &mut p.moment_bands {
                        ui.add(egui::DragValue::new(b).range(0..=MAX_BANDS).prefix("L = "));
                    }
                });
                if keep != p.moment_bands.is_some() {
                    p.moment_bands = keep.then_some(DEFAULT_MOMENT_BANDS);
                }
                ui.checkbox(&mut p.surface_cache, "surface cache (indirect light on surfaces)")
                    .on_hover_text(
                        "The first surfaces' indirect irradiance from occlusion-aware second-order \
                         records on the surfaces, direct light sampled per camera sample \
                         (render3d --surface-cache ours); off: reflected light path traced.",
                    );
                let mut limited = p.edge_reach.is_some();
                ui.horizontal(|ui| {
                    ui.checkbox(&mut limited, "reach ≤ edge distance ×").on_hover_text(
                        "Records reach no farther than this multiple of their distance to the nearest \
                         silhouette edge they see (render3d --edge-reach)",
                    );
                    let mut k = p.edge_reach.unwrap_or(1.0);
                    ui.add_enabled(limited, egui::DragValue::new(&mut k).range(0.01..=100.0).speed(0.05))
                        .accessible_name("edge reach");
                    p.edge_reach = limited.then_some(k);
                });
                let mut limited = p.lamp_reach.is_some();
                ui.horizontal(|ui| {
                    ui.checkbox(&mut limited, "reach ≤ lamp distance ×").on_hover_text(
                        "Records reach no farther than this multiple of their distance to the nearest \
                         point light: the scattered light grows as 1/distance around a lamp, beyond any \
                         record's Taylor expansion (render3d --lamp-reach; off: --no-lamp-reach)",
                    );
                    let mut k = p.lamp_reach.unwrap_or(crate::pipeline::budget::VOLUME_LAMP_REACH);
                    ui.add_enabled(limited, egui::DragValue::new(&mut k).range(0.01..=100.0).speed(0.05))
                        .accessible_name("lamp reach");
                    p.lamp_reach = limited.then_some(k);
                });
                let mut coned = p.eye_cone_deg.is_some();
                ui.horizontal(|ui| {
                    ui.checkbox(&mut coned, "serve within ° of the camera").on_hover_text(
                        "A record serves only the points the camera sees within this angle of it: the light it \
                         holds leaves towards the camera, a direction that turns fast near the camera \
                         (render3d --eye-cone; anisotropic fog only)",
                    );
                    let mut a = p
                        .eye_cone_deg
                        .unwrap_or(crate::pipeline::eye_cone::SUGGESTED_EYE_CONE_DEG);
                    ui.add_enabled(coned, egui::DragValue::new(&mut a).range(0.01..=90.0).speed(0.1))
                        .accessible_name("eye cone");
                    p.eye_cone_deg = coned.then_some(a);
                });
                if p.method == Method3d::Ours {
                    ui.checkbox(&mut p.gradient_noise_reach, "reach ≤ gradient noise")
                        .on_hover_text(
                            "Records reach no farther than where their multiple-scattering gradient's noise \
                         adds the error ε allows (render3d --gradient-noise-reach): pays where the \
                         records' gradients are noise and their light varies, as around a lamp in \
                         forward-scattering fog",
                        );
                }
            }
        }
    }

    fn display_controls(&mut self, ui: &mut egui::Ui) {
        let d = &mut self.display;
        ui.strong("Display");
        ui.checkbox(&mut d.medium_only, "medium part alone (∫ T L_s dt)");
        ui.horizontal(|ui| {
            let c = ui.checkbox(&mut d.auto_exposure, "auto exposure");
            ui.add_enabled(
                !d.auto_exposure,
                egui::DragValue::new(&mut d.exposure).speed(0.05).range(-40.0..=40.0),
            )
            .labelled_by(c.id);
        });
        ui.checkbox(&mut d.error_map, "error map against a path-traced reference");
        if d.error_map {
            ui.horizontal(|ui| {
                let l = ui.label("reference spp");
                ui.add(egui::DragValue::new(&mut self.reference_spp).range(1..=1 << 16))
                    .labelled_by(l.id);
            });
            match (self.reference.running(), self.reference.current()) {
                (Some(j), _) => {
                    ui.label(format!("{} — {:.0}%", j.stage(), 100.0 * j.fraction()));
                }
                (None, Some(r)) => {
                    ui.label(format!(
                        "reference: {} spp, {:.1} s, relative standard error {:.2}%",
                        r.spp,
                        r.seconds,
                        100.0 * r.relative_std_error()
                    ));
                }
                (None, None) => {}
            }
        }
        let d = &mut self.display;
        ui.checkbox(&mut d.show_records, "draw the cache's records");
        ui.horizontal(|ui| {
            ui.label("coloured by");
            for (s, name) in [
                (RecordShade::Radius, "radius"),
                (RecordShade::Luminance, "value"),
                (RecordShade::Cost, "cost"),
            ] {
                ui.radio_value(&mut d.record_shade, s, name);
            }
        });
    }

    fn medium_controls(&mut self, ui: &mut egui::Ui) {
        let Some(m) = self.doc.desc().medium.clone() else {
            ui.label("no medium (vacuum)");
            return;
        };
        ui.strong("Medium");
        if let Some(c) = color_edit(ui, "σ_a", &m.sigma_a, 0.005) {
            self.apply("medium.sigma_a", |d| d.medium.as_mut().unwrap().sigma_a = c);
        }
        if let Some(c) = color_edit(ui, "σ_s", &m.sigma_s, 0.005) {
            self.apply("medium.sigma_s", |d| d.medium.as_mut().unwrap().sigma_s = c);
        }
        let mut g = m.g;
        labelled(ui, "g", egui::Slider::new(&mut g, -0.99..=0.99));
        if g != m.g {
            self.apply("medium.g", |d| d.medium.as_mut().unwrap().g = g);
        }
    }

    fn light_controls(&mut self, ui: &mut egui::Ui) {
        let lights = self.doc.desc().lights.clone();
        if lights.is_empty() {
            return;
        }
        ui.strong("Lights");
        for (i, l) in lights.iter().enumerate() {
            match l {
                LightDesc::Point(p) => {
                    if let Some(c) = color_edit(ui, &format!("point {i}: I"), &p.intensity, 0.02) {
                        self.apply(&format!("lights[{i}]"), |d| {
                            if let LightDesc::Point(p) = &mut d.lights[i] {
                                p.intensity = c;
                            }
                        });
                    }
                }
                LightDesc::Sun(s) => {
                    if let Some(c) = color_edit(ui, &format!("sun {i}: E"), &s.irradiance, 0.05) {
                        self.apply(&format!("lights[{i}]"), |d| {
                            if let LightDesc::Sun(s) = &mut d.lights[i] {
                                s.irradiance = c;
                            }
                        });
                    }
                    let mut dir = s.direction;
                    let changed = ui
                        .horizontal(|ui| {
                            let l = ui.label("  direction");
                            dir.iter_mut()
                                .map(|x| {
                                    let d = egui::DragValue::new(x).speed(0.01).range(-1.0..=1.0);
                                    ui.add(d).labelled_by(l.id).changed()
                                })
                                .fold(false, |a, b| a | b)
                        })
                        .inner;
                    if changed {
                        self.apply(&format!("lights[{i}].direction"), |d| {
                            if let LightDesc::Sun(s) = &mut d.lights[i] {
                                s.direction = dir;
                            }
                        });
                    }
                }
                LightDesc::Sky(s) => {
                    if let Some(c) = color_edit(ui, &format!("sky {i}: L"), &s.radiance, 0.01) {
                        self.apply(&format!("lights[{i}]"), |d| {
                            if let LightDesc::Sky(s) = &mut d.lights[i] {
                                s.radiance = c;
                            }
                        });
                    }
                }
            }
        }
    }

    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            if let Some(j) = self.render.running() {
                ui.spinner();
                ui.label(format!("{} — {:.0}%", j.stage(), 100.0 * j.fraction()));
                if ui.button("Cancel").clicked() {
                    self.render.cancel();
                }
            } else if let Some(f) = self.render.current() {
                ui.label(format!("{} done", f.method.label()));
            }
            if let Some(f) = self.frame().cloned() {
                let img = &f.image;
                ui.separator();
                ui.label(format!(
                    "level {}/{}: {}×{} @ {} spp · {:.2} s · {:.2} M rays{}",
                    f.level,
                    f.levels,
                    img.width,
                    img.height,
                    img.spp,
                    img.seconds,
                    img.rays as f64 * 1e-6,
                    match (f.records.len(), f.carried) {
                        (0, _) => String::new(),
                        (n, 0) => format!(" · {n} records (ε = {:.3e})", f.eps),
                        (n, c) => format!(" · {n} records, {c} from earlier cameras (ε = {:.3e})", f.eps),
                    }
                ));
                if let Some(c) = self.command()
                    && ui.button("Copy as command").on_hover_text(c.clone()).clicked()
                {
                    ui.ctx().copy_text(c);
                }
            }
            if let Some((m, err)) = &self.message {
                ui.separator();
                let color = if *err {
                    egui::Color32::from_rgb(255, 110, 100)
                } else {
                    ui.visuals().text_color()
                };
                ui.colored_label(color, m);
            }
        });
    }
}
