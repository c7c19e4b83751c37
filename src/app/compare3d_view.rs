//! The 3D compare window: parameters, Run / Cancel, then the four images with
//! their costs and errors, the error maps, and "copy as command". A result
//! computed for another scene or camera stays visible, marked stale.

use super::compare3d::{caption, compare_images, spawn_compare3d};
use super::panel3d::labelled;
use super::workbench3d::Workbench3d;
use eframe::egui;
use std::sync::Arc;

const NAMES: [&str; 4] = ["reference", "ours", "Jarosz 2008", "path tracing (equal time)"];

impl Workbench3d {
    /// Start the comparison for the current scene and parameters.
    pub fn run_compare(&mut self) {
        let key = (self.doc.revision(), self.compare_params.clone());
        let (scene, params, notify) = (
            self.doc.scene().clone(),
            self.compare_params.clone(),
            self.notify.clone(),
        );
        self.compare.ensure(key, || spawn_compare3d(scene, params, notify));
    }

    /// The comparison's result is for the scene and camera on screen.
    pub fn compare_is_current(&self) -> bool {
        self.compare.key().is_some_and(|k| k.0 == self.doc.revision()) && self.compare.current().is_some()
    }

    /// The copied command for the compare view's parameters.
    pub fn compare_command(&self) -> String {
        let file = self.doc.path().map_or_else(
            || format!("scenes3d/{}.json", self.doc.stem()),
            |p| p.display().to_string(),
        );
        self.compare_params.command(self.doc.scene(), &file)
    }

    pub(super) fn compare_window(&mut self, ctx: &egui::Context) {
        let mut open = self.show_compare;
        egui::Window::new("3D compare")
            .open(&mut open)
            .default_size([720.0, 520.0])
            .show(ctx, |ui| self.compare_contents(ui));
        self.show_compare = open;
    }

    fn compare_contents(&mut self, ui: &mut egui::Ui) {
        let p = &mut self.compare_params;
        ui.horizontal_wrapped(|ui| {
            labelled(ui, "records", egui::DragValue::new(&mut p.caches).range(1..=100_000));
            labelled(ui, "width", egui::DragValue::new(&mut p.width).range(8..=1280));
            labelled(ui, "camera spp", egui::DragValue::new(&mut p.spp).range(1..=64));
            labelled(
                ui,
                "reference spp",
                egui::DragValue::new(&mut p.ref_spp).range(16..=1 << 20),
            );
            labelled(ui, "rays", egui::DragValue::new(&mut p.rays).range(16..=65536));
        });
        ui.horizontal(|ui| {
            if ui.button("Run").clicked() {
                self.run_compare();
            }
            if let Some(j) = self.compare.running() {
                ui.spinner();
                ui.label(format!("{} — {:.0}%", j.stage(), 100.0 * j.fraction()));
                if ui.button("Cancel").clicked() {
                    self.compare.cancel();
                }
            }
            let c = self.compare_command();
            if ui.button("Copy as command").on_hover_text(c.clone()).clicked() {
                ui.ctx().copy_text(c);
            }
        });
        let Some(result) = self.compare.latest().cloned() else {
            return;
        };
        let res = match &*result {
            Ok(r) => r,
            Err(e) => {
                ui.colored_label(egui::Color32::from_rgb(255, 110, 100), e);
                return;
            }
        };
        if !self.compare_is_current() {
            ui.colored_label(
                egui::Color32::from_rgb(255, 210, 120),
                "stale: computed for another scene, camera or parameters — Run again",
            );
        }
        let stale_tex = self.compare_tex.as_ref().is_none_or(|(k, _)| !Arc::ptr_eq(k, &result));
        if stale_tex {
            let exposure = crate::figure::auto_exposure(&crate::output::image_field(
                res.reference.width,
                res.reference.height,
                &res.reference.values,
            ));
            let tex = compare_images(res, exposure)
                .into_iter()
                .enumerate()
                .map(|(i, img)| {
                    ui.ctx()
                        .load_texture(format!("compare3d{i}"), img, egui::TextureOptions::NEAREST)
                })
                .collect();
            self.compare_tex = Some((result.clone(), tex));
        }
        let Some((_, tex)) = &self.compare_tex else { return };
        let w = ((ui.available_width() - 24.0) / 4.0).max(40.0);
        let size = |t: &egui::TextureHandle| {
            let s = t.size_vec2();
            egui::vec2(w, w * s.y / s.x)
        };
        egui::Grid::new("compare3d_grid").show(ui, |ui| {
            for name in NAMES {
                ui.strong(name);
            }
            ui.end_row();
            for t in &tex[..4] {
                ui.image((t.id(), size(t)));
            }
            ui.end_row();
            ui.label(format!("{} spp", res.params.ref_spp));
            for r in &res.runs {
                ui.label(caption(r));
            }
            ui.end_row();
            ui.label("|error| (shared log range)");
            for t in &tex[4..] {
                ui.image((t.id(), size(t)));
            }
            ui.end_row();
        });
    }
}
