//! Side-panel editors of the scene: the selected segment or light, the medium.
//! Widgets edit a copy of the description; a change goes to the document, which
//! validates it (an invalid value is refused and its error shown). Ranges are wide
//! on purpose: extreme values are what users test.

use super::edit::{Selection, add_point_light, add_segment, segment_vertices, set_vertex};
use super::workbench::Workbench;
use crate::flatland::scene_desc::{Color, LightDesc, MediumDesc, RegionDesc, SceneDesc};
use crate::pipeline::world::World;
use eframe::egui::{self, DragValue};
use glam::DVec2;

/// An RGB value: one field while grey, three once "RGB" is ticked.
pub fn color_edit(ui: &mut egui::Ui, label: &str, c: &mut Color, max: f64) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        let l = ui.label(label).id;
        let grey = c.0[0] == c.0[1] && c.0[1] == c.0[2];
        let speed = |v: f64| (v.abs() * 0.01).max(1e-3);
        if grey {
            let mut v = c.0[0];
            let sp = speed(v);
            if ui
                .add(DragValue::new(&mut v).range(0.0..=max).speed(sp))
                .labelled_by(l)
                .changed()
            {
                *c = Color::grey(v);
                changed = true;
            }
        } else {
            for k in 0..3 {
                let sp = speed(c.0[k]);
                let r = ui.add(DragValue::new(&mut c.0[k]).range(0.0..=max).speed(sp));
                changed |= r.labelled_by(l).changed();
            }
        }
        let mut rgb = !grey;
        if ui.checkbox(&mut rgb, "RGB").changed() {
            if !rgb {
                *c = Color::grey((c.0[0] + c.0[1] + c.0[2]) / 3.0);
            } else {
                c.0[0] += 1e-9 * c.0[0].max(1e-9); // split the channels visibly
            }
            changed = true;
        }
    });
    changed
}

fn point_edit(ui: &mut egui::Ui, label: &str, p: &mut [f64; 2]) -> bool {
    ui.horizontal(|ui| {
        let l = ui.label(label).id;
        let a = ui
            .add(DragValue::new(&mut p[0]).speed(0.005).max_decimals(4))
            .labelled_by(l)
            .changed();
        let b = ui
            .add(DragValue::new(&mut p[1]).speed(0.005).max_decimals(4))
            .labelled_by(l)
            .changed();
        a || b
    })
    .inner
}

impl Workbench {
    /// Apply `edited` as one edit named `key`; show the error if it is refused.
    pub(super) fn commit(&mut self, key: &str, edited: SceneDesc) {
        match self.doc.edit(key, |d| *d = edited) {
            Ok(true) => {
                if self.message.as_ref().is_some_and(|m| m.error) {
                    self.message = None;
                }
            }
            Ok(false) => {}
            Err(e) => self.error(e.to_string()),
        }
    }

    pub(super) fn selection_editor(&mut self, ui: &mut egui::Ui) {
        let mut d = self.doc.desc().clone();
        let centre = self.last_xf.map_or(DVec2::ZERO, |xf| xf.center);
        ui.horizontal(|ui| {
            if ui.button("Add segment").clicked() {
                let i = add_segment(&mut d, centre, 0.2 * self.doc.scene().scale());
                self.selection = Some(Selection::Segment(i));
                self.commit("add", d.clone());
                self.doc.end_gesture();
            }
            if ui.button("Add point light").clicked() {
                let i = add_point_light(&mut d, centre);
                self.selection = Some(Selection::Light(i));
                self.commit("add", d.clone());
                self.doc.end_gesture();
            }
        });
        let mut key = String::new();
        let mut changed = false;
        match self.selection {
            Some(Selection::Segment(i)) if i < d.segments.len() => {
                let s = &mut d.segments[i];
                ui.strong(format!(
                    "Segment {i}{}",
                    s.name.as_ref().map_or(String::new(), |n| format!(": {n}"))
                ));
                let n = segment_vertices(s).len();
                for k in 0..n {
                    let mut p = segment_vertices(s)[k].to_array();
                    if point_edit(ui, &format!("vertex {k}"), &mut p) {
                        set_vertex(s, k, DVec2::from_array(p));
                        (key, changed) = (format!("seg{i}.v{k}"), true);
                    }
                }
                if color_edit(ui, "reflectance ρ", &mut s.reflectance, 1.0) {
                    (key, changed) = (format!("seg{i}.rho"), true);
                }
                if color_edit(ui, "emission", &mut s.emission, 1e6) {
                    (key, changed) = (format!("seg{i}.le"), true);
                }
                if ui.checkbox(&mut s.two_sided, "two-sided").changed() {
                    (key, changed) = (format!("seg{i}.sides"), true);
                }
            }
            Some(Selection::Light(i)) if i < d.lights.len() => {
                ui.strong(format!("Light {i}"));
                let (k, c) = match &mut d.lights[i] {
                    LightDesc::Point { position, intensity } => {
                        let a = point_edit(ui, "position", position);
                        let b = color_edit(ui, "intensity (W/rad)", intensity, 1e6);
                        ("pos", a || b)
                    }
                    LightDesc::Collimated {
                        direction,
                        aperture,
                        irradiance,
                    } => {
                        let a = point_edit(ui, "direction", direction);
                        let b = point_edit(ui, "aperture a", &mut aperture[0]);
                        let c = point_edit(ui, "aperture b", &mut aperture[1]);
                        let e = color_edit(ui, "irradiance (W/m)", irradiance, 1e6);
                        ("beam", a || b || c || e)
                    }
                };
                (key, changed) = (format!("light{i}.{k}"), c);
            }
            _ => {
                ui.weak(
                    "Click a segment or light to edit it; drag vertices, segments, lights and the medium's corners.",
                );
            }
        }
        if changed {
            self.commit(&key, d);
        }
        if self.selection.is_some() && ui.button("Delete selected (Del)").clicked() {
            self.delete_selection();
        }
    }

    pub(super) fn medium_editor(&mut self, ui: &mut egui::Ui) {
        let mut d = self.doc.desc().clone();
        let Some(m) = &mut d.medium else {
            if ui.button("Add a medium (fog everywhere)").clicked() {
                d.medium = Some(MediumDesc {
                    sigma_a: Color::grey(0.1),
                    sigma_s: Color::grey(0.9),
                    g: 0.0,
                    region: RegionDesc::Everywhere,
                });
                self.commit("medium.add", d);
                self.doc.end_gesture();
            }
            return;
        };
        let mut key = "";
        if color_edit(ui, "σ_a (1/m)", &mut m.sigma_a, 1e5) {
            key = "medium.sigma_a";
        }
        if color_edit(ui, "σ_s (1/m)", &mut m.sigma_s, 1e5) {
            key = "medium.sigma_s";
        }
        let g = ui.add(egui::Slider::new(&mut m.g, -0.999..=0.999).text("g (HG)"));
        if g.changed() {
            key = "medium.g";
        }
        let region = match &m.region {
            RegionDesc::Everywhere => "everywhere".to_string(),
            RegionDesc::Domain => "the domain".to_string(),
            RegionDesc::Rect(_) => "a rectangle (drag its corners)".to_string(),
            RegionDesc::Polygon(p) => format!("a polygon of {} vertices (drag them)", p.len()),
        };
        ui.weak(format!("region: {region}"));
        let remove = ui.button("Remove the medium (vacuum)").clicked();
        if remove {
            d.medium = None;
            key = "medium.remove";
        }
        if !key.is_empty() {
            self.commit(key, d);
        }
    }
}
