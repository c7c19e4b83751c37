//! The compare view (a window): the reference and each cache method side by side on
//! the same scene at equal cache count, their records drawn over their fields (the
//! colours of `figure::draw_records`, one colour range for all), their error maps on
//! one shared range (`figure::shared_error_range`) and their numbers (records, ε,
//! rays, time, RMSE, relMSE), as `volcache figure compare` shows them (textures from
//! [`super::compare_textures`]). Also the data of the canvas's record and error
//! overlays, and the compare part of the side panel's "Methods".

use super::compare::{CompareResult, METHODS, compare_command, method_label};
use super::compare_textures::CompareTextures;
use super::overlay::{record_shapes, records_scale};
use super::view::{ViewState, Xform};
use super::workbench::Workbench;
use crate::figure::{RECORD_BLUE, RecordColor};
use crate::flatland::cached_field::{CacheMethod, RecordInfo};
use eframe::egui::{self, Color32, DragValue, Rect, RichText, Sense, pos2, vec2};

/// The record colourings offered.
pub const RECORD_COLORS: [(RecordColor, &str); 4] = [
    (RecordColor::Uniform(RECORD_BLUE), "uniform"),
    (RecordColor::ByRadius, "radius"),
    (RecordColor::ByLuminance, "value (luminance)"),
    (RecordColor::ByCost, "cost (rays)"),
];

fn color_name(c: RecordColor) -> &'static str {
    RECORD_COLORS
        .iter()
        .find(|(x, _)| *x == c)
        .map_or("uniform", |(_, n)| n)
}

/// The numbers of a run as shown under its images.
pub fn run_caption(r: &super::compare::MethodRun) -> String {
    // The records' own noise: an error shared by the pixels each serves.
    let noise = r
        .records_noise
        .map_or_else(String::new, |n| format!("\nrecords' noise {:.1}%", 100.0 * n));
    format!(
        "{} records, ε = {:.3e}\n{:.2e} rays, {:.2} s\nRMSE {:.3e}\nrelMSE {:.3e}{noise}",
        r.records.len(),
        r.eps,
        r.rays as f64,
        r.seconds,
        r.errors.rmse,
        r.errors.relmse
    )
}

impl Workbench {
    /// Re-make the comparison's textures when a new result landed or the exposure changed.
    pub(super) fn update_compare_textures(&mut self, ctx: &egui::Context) {
        let Some(res) = self.compare.current().cloned() else {
            self.compare_tex = None;
            return;
        };
        let exposure = self.exposure();
        if self.compare_tex.as_ref().is_some_and(|t| t.is_for(&res, exposure)) {
            return;
        }
        self.compare_tex = Some(CompareTextures::new(ctx, &res, exposure));
    }

    /// The records of every run of the latest comparison (for the shared colour range).
    fn record_lists(res: &CompareResult) -> Vec<&[RecordInfo]> {
        res.runs.iter().map(|r| r.records.as_slice()).collect()
    }

    /// The record overlay's shapes on the canvas (the overlay method's records).
    pub(super) fn record_overlay_shapes(&self, xf: &Xform) -> Vec<egui::Shape> {
        if self.field_method != super::field_method::FieldMethod::PathTracing {
            // The records the shown field was reconstructed from.
            let Some(f) = self.field.current() else { return vec![] };
            let scale = records_scale(&[&f.records], self.record_color);
            return record_shapes(&f.records, self.record_color, scale.as_ref(), xf);
        }
        let Some(res) = self.compare.current() else {
            return vec![];
        };
        let Some(run) = res.run(self.overlay_method) else {
            return vec![];
        };
        let scale = records_scale(&Self::record_lists(res), self.record_color);
        record_shapes(&run.records, self.record_color, scale.as_ref(), xf)
    }

    /// The error overlay's texture and range (the overlay method's error map).
    pub(super) fn error_overlay(&self) -> Option<(&egui::TextureHandle, (f64, f64))> {
        let res = self.compare.current()?;
        let k = res.runs.iter().position(|r| r.method == self.overlay_method)?;
        let t = self.compare_tex.as_ref()?;
        Some((t.errors.get(k)?, t.error_range))
    }

    /// The `volcache figure compare` line of the comparison.
    pub fn compare_command(&mut self) -> anyhow::Result<String> {
        let scene = self.scene_arg()?;
        let key = self.compare_key();
        Ok(compare_command(
            scene.as_deref(),
            &key.fp,
            &self.compare_params,
            &self.compare_out,
        ))
    }

    /// The compare part of the side panel's "Methods".
    pub(super) fn compare_section(&mut self, ui: &mut egui::Ui) {
        ui.separator();
        ui.strong("Compare (equal cache count)");
        let p = &mut self.compare_params;
        egui::Grid::new("compare_params").num_columns(2).show(ui, |ui| {
            let l = ui.label("target records");
            ui.add(DragValue::new(&mut p.caches).range(1..=100_000))
                .labelled_by(l.id);
            ui.end_row();
            let l = ui.label("rays per record");
            ui.add(DragValue::new(&mut p.rays).range(3..=1 << 16)).labelled_by(l.id);
            ui.end_row();
            let l = ui.label("steps per ray");
            ui.add(DragValue::new(&mut p.steps).range(1..=1024)).labelled_by(l.id);
            ui.end_row();
            per_pixel_count(
                ui,
                &mut p.direct_samples,
                ("straight light per pixel", "straight-light samples per pixel"),
                (64, 4096),
                "Sample the light arriving straight from the lights at every pixel and cache only the rest (--direct-samples)",
            );
            ui.end_row();
            per_pixel_count(
                ui,
                &mut p.point_scatter,
                ("lamps' scattered light per pixel", "point-light scattering directions per pixel"),
                (64, 4096),
                "Sample the point lights' light scattered once in the fog at every pixel, with this many directions, and cache only the rest (--point-scatter): its peak around a lamp is not extrapolated",
            );
            ui.end_row();
            per_pixel_count(
                ui,
                &mut p.near_light_paths,
                ("path trace near lamps", "paths per pixel near a lamp"),
                (1024, 16384),
                "Path trace the pixels within a mean free path of a point light with this many paths each, instead of reading them from records (--near-light-paths): the light scattered twice and more still peaks there",
            );
            ui.end_row();
            let mut limited = p.edge_reach.is_some();
            ui.checkbox(&mut limited, "reach ≤ edge distance ×")
                .on_hover_text("Records reach no farther than this multiple of their distance to the nearest surface edge or point light they see (--edge-reach)");
            let mut k = p.edge_reach.unwrap_or(1.0);
            ui.add_enabled(limited, DragValue::new(&mut k).range(0.01..=100.0).speed(0.05))
                .accessible_name("edge reach");
            p.edge_reach = limited.then_some(k);
            ui.end_row();
            let mut limited = p.lamp_reach.is_some();
            ui.checkbox(&mut limited, "reach ≤ lamp distance ×").on_hover_text(
                "Records reach no farther than this multiple of their distance to the nearest point light (--lamp-reach): \
                 the light's log(1/r) peak lies outside a record's Taylor expansion beyond that distance",
            );
            let mut k = p.lamp_reach.unwrap_or(crate::pipeline::budget::VOLUME_LAMP_REACH);
            ui.add_enabled(limited, DragValue::new(&mut k).range(0.01..=100.0).speed(0.05))
                .accessible_name("lamp reach");
            p.lamp_reach = limited.then_some(k);
            ui.end_row();
            ui.checkbox(&mut p.gradient_noise_reach, "reach ≤ gradient noise")
                .on_hover_text("Ours' records reach no farther than where their multiple-scattering gradient's noise adds the error ε allows (--gradient-noise-reach): pays where the records' gradients are noise and their light varies, as around a lamp in forward-scattering fog");
            ui.end_row();
            let l = ui.label("compare reference spp");
            ui.add(DragValue::new(&mut p.ref_spp).range(1..=1_000_000).speed(10.0))
                .labelled_by(l.id);
            ui.end_row();
            let mut auto = p.res.is_none();
            ui.checkbox(&mut auto, "half the field resolution");
            let [mut w, mut h] = p.res.unwrap_or([
                (self.field_params.width / 2).max(1),
                (self.field_params.height / 2).max(1),
            ]);
            ui.add_enabled_ui(!auto, |ui| {
                ui.horizontal(|ui| {
                    ui.add(DragValue::new(&mut w).range(1..=2048))
                        .accessible_name("compare width (pixels)");
                    ui.label("×");
                    ui.add(DragValue::new(&mut h).range(1..=2048))
                        .accessible_name("compare height (pixels)");
                });
            });
            p.res = (!auto).then_some([w, h]);
            ui.end_row();
        });
        ui.horizontal(|ui| {
            ui.label("overlays show");
            for m in METHODS {
                ui.radio_value(&mut self.overlay_method, m, method_label(m));
            }
        });
        ui.horizontal(|ui| {
            let l = ui.label("record colour");
            egui::ComboBox::from_id_salt("record_color")
                .selected_text(color_name(self.record_color))
                .show_ui(ui, |ui| {
                    for (c, name) in RECORD_COLORS {
                        ui.selectable_value(&mut self.record_color, c, name);
                    }
                })
                .response
                .labelled_by(l.id);
        });
        ui.horizontal(|ui| {
            let l = ui.label("figure dir");
            ui.add(egui::TextEdit::singleline(&mut self.compare_out).desired_width(f32::INFINITY))
                .labelled_by(l.id);
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.show_compare, "Open compare view");
            if ui.button("Copy compare command").clicked() {
                match self.compare_command() {
                    Ok(c) => {
                        ui.ctx().copy_text(c.clone());
                        self.info(format!("copied: {c}"));
                    }
                    Err(e) => self.error(format!("saving the edited scene: {e:#}")),
                }
            }
        });
        ui.weak(
            "The comparison uses the scene's render settings at the compare resolution; the command \
             reproduces its figure and numbers headless (times and the reference's cache aside).",
        );
    }

    /// The compare window (when open).
    pub(super) fn compare_window(&mut self, ctx: &egui::Context) {
        if !self.show_compare {
            return;
        }
        let mut open = true;
        egui::Window::new("Compare")
            .open(&mut open)
            .default_width(780.0)
            .default_pos(pos2(340.0, 80.0))
            .show(ctx, |ui| self.compare_contents(ui));
        self.show_compare &= open;
    }

    fn compare_contents(&mut self, ui: &mut egui::Ui) {
        let key = self.compare_key();
        let p = &self.compare_params;
        ui.label(format!(
            "{}×{}, equal cache count: {} records of {} rays ({} steps); reference {} spp",
            key.fp.width, key.fp.height, p.caches, p.rays, p.steps, p.ref_spp
        ));
        let Some(res) = self.compare.current().cloned() else {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("computing the reference…");
            });
            return;
        };
        if !self.compare.is_done() {
            ui.horizontal(|ui| {
                ui.spinner();
                let stage = self.compare.running().map_or(String::new(), |j| j.stage());
                ui.label(stage);
            });
        }
        let Some(tex) = &self.compare_tex else { return };
        let scene = self.doc.scene().clone();
        let side = ((ui.available_width() - 24.0) / 3.0).clamp(120.0, 320.0);
        let lists = Self::record_lists(&res);
        let scale = records_scale(&lists, self.record_color);
        let cell = |ui: &mut egui::Ui, t: Option<&egui::TextureHandle>, records: Option<&[RecordInfo]>| {
            let (rect, _) = ui.allocate_exact_size(vec2(side, side), Sense::hover());
            let painter = ui.painter_at(rect);
            painter.rect_filled(rect, 0.0, Color32::from_rgb(30, 30, 34));
            let xf = Xform::new(rect, scene.domain_min, scene.domain_max, &ViewState::default());
            let domain = xf.rect_of(scene.domain_min, scene.domain_max);
            if let Some(t) = t {
                let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0));
                painter.image(t.id(), domain, uv, Color32::WHITE);
            }
            if let Some(r) = records {
                // Clipped to the domain, as `figure::draw_records` clips to its view.
                let shapes = record_shapes(r, self.record_color, scale.as_ref(), &xf);
                painter.with_clip_rect(domain).extend(shapes);
            }
        };
        egui::Grid::new("compare_grid")
            .num_columns(3)
            .spacing([8.0, 6.0])
            .show(ui, |ui| {
                ui.strong("reference");
                for m in METHODS {
                    ui.strong(match m {
                        CacheMethod::Ours => "ours (aware, Hessian ellipses)",
                        CacheMethod::Jarosz08 => "Jarosz 2008 (unaware, circles)",
                    });
                }
                ui.end_row();
                cell(ui, tex.fields.first(), None);
                for m in METHODS {
                    let k = res.runs.iter().position(|r| r.method == m);
                    cell(
                        ui,
                        k.and_then(|k| tex.fields.get(k + 1)),
                        k.map(|k| res.runs[k].records.as_slice()),
                    );
                }
                ui.end_row();
                ui.label(format!(
                    "{} spp path tracing\n{:.2e} rays, {:.2} s",
                    res.ref_spp, res.ref_rays as f64, res.ref_seconds
                ));
                for m in METHODS {
                    match res.run(m) {
                        Some(r) => ui.label(RichText::new(run_caption(r)).monospace()),
                        None => ui.weak("computing…"),
                    };
                }
                ui.end_row();
                ui.vertical(|ui| {
                    ui.weak("|error| vs the reference (log scale, shared):");
                    if !res.runs.is_empty() {
                        ui.weak(format!("{:.1e} … {:.1e}", tex.error_range.0, tex.error_range.1));
                    }
                });
                for m in METHODS {
                    let k = res.runs.iter().position(|r| r.method == m);
                    cell(ui, k.and_then(|k| tex.errors.get(k)), None);
                }
                ui.end_row();
            });
    }
}

/// A light part sampled per pixel instead of cached: a checkbox (`label`) and its
/// count per pixel (`name`): `default` when first checked, at most `most`.
fn per_pixel_count(
    ui: &mut egui::Ui,
    count: &mut Option<u32>,
    (label, name): (&str, &str),
    (default, most): (u32, u32),
    hover: &str,
) {
    let mut per_pixel = count.is_some();
    ui.checkbox(&mut per_pixel, label).on_hover_text(hover);
    let mut n = count.unwrap_or(default);
    ui.add_enabled(per_pixel, DragValue::new(&mut n).range(1..=most))
        .accessible_name(name);
    *count = per_pixel.then_some(n);
}
