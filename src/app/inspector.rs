//! The probe inspector: the incoming light field as a polar plot, the proxy's
//! statistics, and per method (aware / unaware / reference) the table of L_s,
//! gradient, Hessian, eigenvalues and the cache extent, with the reference computed
//! on demand (progress bar, Cancel) and the commands reproducing the numbers.

use super::command::probe_command;
use super::compute::ProbeResult;
use super::overlay::method_color;
use super::readout::{MethodReadout, StdErrors, bin_angle, polar_bins};
use super::workbench::Workbench;
use crate::pipeline::world::DirectLight;
use eframe::egui::{self, Align2, Color32, FontId, Pos2, RichText, Sense, Shape, Stroke, Vec2, pos2, vec2};
use glam::DVec2;

/// What the inspector says before there is a probe.
pub const PROBE_HINT: &str = "Click in the fog to place the probe: its incoming light field, proxy \
     elements, and L_s with gradient and Hessian by each method appear here. Drag it to move it.";

const SURFACE: Color32 = Color32::from_rgb(255, 196, 46);
const MEDIUM: Color32 = Color32::from_rgb(140, 205, 255);

fn num(v: f64) -> String {
    if v == 0.0 { "0".into() } else { format!("{v:.2e}") }
}

impl Workbench {
    pub(super) fn inspector(&mut self, ui: &mut egui::Ui) {
        let Some(at) = self.probe else {
            ui.heading("Probe");
            ui.label(PROBE_HINT);
            return;
        };
        ui.horizontal(|ui| {
            ui.heading("Probe");
            ui.label(format!("at ({:.4}, {:.4})", at.x, at.y));
            if ui.small_button("Remove").clicked() {
                self.probe = None;
            }
        });
        match self.probe_result().cloned() {
            None => {
                // An older result is never shown for the current scene (Slot::current).
                let what = if self.probe_job.latest().is_some() {
                    "recomputing for the changed scene or settings"
                } else {
                    "capturing the light field"
                };
                ui.horizontal(|ui| {
                    ui.spinner();
                    ui.label(format!("{what} ({} rays)…", self.method.rays));
                });
            }
            Some(p) => {
                if !p.inside_medium {
                    ui.colored_label(Color32::from_rgb(255, 170, 80), "outside the medium: L_s = 0 here");
                }
                polar_plot(ui, &p);
                let bridging = p.elements.iter().filter(|e| e.bridging).count();
                ui.weak(format!(
                    "{} rays, {} proxy elements ({bridging} bridging), {:.2} M rays, {:.2} s",
                    p.light_field.rays.len(),
                    p.elements.len(),
                    p.rays as f64 / 1e6,
                    p.seconds
                ));
            }
        }
        ui.separator();
        self.reference_controls(ui);
        self.table(ui);
        ui.separator();
        self.probe_commands(ui, at);
    }

    fn table(&self, ui: &mut egui::Ui) {
        let rows = self.readouts();
        let part = super::command::part_arg(self.field_params.part);
        ui.label(format!(
            "L_s (luminance, part: {part}) and its derivatives; ε = {}",
            self.method.eps
        ));
        let get = |name: &str| rows.iter().find(|r| r.name == name);
        let cols = [get("aware"), get("unaware"), get("reference")];
        type Cell = fn(&MethodReadout) -> String;
        type Se = Option<fn(&StdErrors) -> f64>;
        let table: [(&str, Cell, Se); 12] = [
            ("L_s", |r| num(r.lum.value), Some(|e| e.value)),
            ("∂L/∂x", |r| num(r.lum.grad.x), Some(|e| e.grad.x)),
            ("∂L/∂y", |r| num(r.lum.grad.y), Some(|e| e.grad.y)),
            ("|∇L|", |r| num(r.lum.grad.length()), None),
            ("H_xx", |r| hess(r, r.lum.hess.x_axis.x), Some(|e| e.hess[0])),
            ("H_xy", |r| hess(r, r.lum.hess.y_axis.x), Some(|e| e.hess[1])),
            ("H_yy", |r| hess(r, r.lum.hess.y_axis.y), Some(|e| e.hess[2])),
            ("λ_1", |r| hess(r, r.eigenvalues.x), Some(|e| e.eigenvalues.x)),
            ("λ_2", |r| hess(r, r.eigenvalues.y), Some(|e| e.eigenvalues.y)),
            ("extent R_1", |r| radius(r, 0), None),
            ("extent R_2", |r| radius(r, 1), None),
            (
                "axis e_1 (deg)",
                |r| {
                    let e = r.extent.axes.x_axis;
                    if r.extent.is_isotropic() {
                        "circle".into()
                    } else {
                        format!("{:.1}", e.y.atan2(e.x).to_degrees())
                    }
                },
                None,
            ),
        ];
        let reference_se = cols[2].and_then(|r| r.stderr);
        egui::Grid::new("derivs")
            .striped(true)
            .num_columns(5)
            .min_col_width(58.0)
            .show(ui, |ui| {
                ui.label("");
                for name in ["aware", "unaware", "reference"] {
                    ui.label(RichText::new(name).color(method_color(name)).strong());
                }
                ui.label("ref. ± s.e.")
                    .on_hover_text("standard error of the reference, from its batches");
                ui.end_row();
                for (label, cell, se) in table {
                    ui.label(label);
                    for c in cols {
                        ui.monospace(c.map_or("—".to_string(), cell));
                    }
                    let e = reference_se
                        .zip(se)
                        .map_or(String::new(), |(e, f)| format!("±{:.1e}", f(&e)));
                    ui.monospace(e);
                    ui.end_row();
                }
            });
        if rows.iter().any(|r| r.hessian_is_noise()) {
            ui.colored_label(
                egui::Color32::from_rgb(255, 210, 120),
                "reference Hessian too noisy (an eigenvalue's s.e. ≥ its size): its ellipse is dashed; \
                 compute the reference with more samples",
            );
        }
        ui.weak(
            "unaware (Jarosz 2008) has no Hessian: its extent is the gradient circle R = εL/|∇L|. \
             A radius marked ↑ is held at the metric's r_max, ↓ at its r_min.",
        );
    }

    fn reference_controls(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let running = self.reference.running().is_some();
            let label = format!("Compute reference ({} spp)", self.method.ref_spp);
            if ui.add_enabled(!running, egui::Button::new(label)).clicked() {
                self.want_reference = true;
            }
            ui.checkbox(&mut self.auto_reference, "follow the probe");
        });
        if let Some(j) = self.reference.running() {
            let mut cancel = false;
            ui.horizontal(|ui| {
                ui.add(
                    egui::ProgressBar::new(j.fraction() as f32)
                        .desired_width(160.0)
                        .show_percentage(),
                );
                cancel = ui.small_button("Cancel").clicked();
            });
            if cancel {
                self.reference.cancel();
                self.want_reference = false;
            }
        }
        if let Some(r) = self.reference_result() {
            ui.weak(format!(
                "central differences: mean of {}/{} batches × {} spp per stencil point (± = standard error), \
                 {:.2} M rays, {:.2} s",
                r.batches.len(),
                r.planned,
                r.spp_per_batch,
                r.rays as f64 / 1e6,
                r.seconds
            ));
        }
    }

    fn probe_commands(&mut self, ui: &mut egui::Ui, at: DVec2) {
        ui.horizontal_wrapped(|ui| {
            ui.label("Copy command:");
            for method in ["aware", "unaware", "reference"] {
                if ui.small_button(method).clicked() {
                    match self.scene_arg() {
                        Ok(scene) => {
                            let (seed, omega) = (self.field_params.seed, self.field_params.omega_o_deg);
                            let c = probe_command(scene.as_deref(), at, method, &self.method, seed, omega);
                            ui.ctx().copy_text(c.clone());
                            self.info(format!("copied: {c}"));
                        }
                        Err(e) => self.error(format!("saving the edited scene: {e:#}")),
                    }
                }
            }
        });
    }
}

/// A radius, marked when the metric's clamp holds it.
fn radius(r: &MethodReadout, k: usize) -> String {
    let v = if k == 0 { r.extent.radii.x } else { r.extent.radii.y };
    match r.clamped[k] {
        Some("r_max") => format!("{}↑", num(v)),
        Some(_) => format!("{}↓", num(v)),
        None => num(v),
    }
}

fn hess(r: &MethodReadout, v: f64) -> String {
    if r.has_hessian { num(v) } else { "—".into() }
}

/// Screen direction of a world angle (y up).
fn dir(a: f64) -> Vec2 {
    vec2(a.cos() as f32, -a.sin() as f32)
}

/// Incoming luminance over direction (from where it arrives), linear radius scaled
/// to the brightest bin: total white, from surfaces yellow, from the medium blue;
/// dashed rays point to the delta lights.
fn polar_plot(ui: &mut egui::Ui, p: &ProbeResult) {
    let side = ui.available_width().clamp(160.0, 250.0);
    let (rect, _) = ui.allocate_exact_size(vec2(side, side), Sense::hover());
    let painter = ui.painter_at(rect);
    let c = rect.center();
    let rmax = 0.5 * side - 16.0;
    painter.rect_filled(rect, 4.0, Color32::from_rgb(22, 22, 26));
    for k in 1..=4 {
        painter.circle_stroke(c, rmax * k as f32 / 4.0, Stroke::new(1.0, Color32::from_gray(60)));
    }
    let bins = polar_bins(&p.incoming, 72);
    let top = bins.iter().map(|b| b.0 + b.1).fold(0.0, f64::max);
    let curve = |f: &dyn Fn((f64, f64)) -> f64, color: Color32| {
        let pts: Vec<Pos2> = (0..=bins.len())
            .map(|k| {
                let k = k % bins.len();
                let r = if top > 0.0 { f(bins[k]) / top } else { 0.0 };
                c + dir(bin_angle(k, bins.len())) * (r as f32 * rmax)
            })
            .collect();
        Shape::line(pts, Stroke::new(1.5, color))
    };
    painter.add(curve(&|b| b.1, MEDIUM));
    painter.add(curve(&|b| b.0, SURFACE));
    painter.add(curve(&|b| b.0 + b.1, Color32::WHITE));
    for l in &p.light_field.direct_lights {
        let from = match l {
            DirectLight::Point { position, .. } => *position - p.light_field.x,
            DirectLight::Directional { to_light, .. } => *to_light,
        };
        let d = dir(from.y.atan2(from.x));
        painter.extend(Shape::dashed_line(
            &[c, c + d * rmax],
            Stroke::new(1.5, SURFACE),
            4.0,
            3.0,
        ));
    }
    let font = FontId::proportional(11.0);
    let text = format!("max {}", num(top));
    painter.text(
        pos2(rect.left() + 6.0, rect.top() + 10.0),
        Align2::LEFT_CENTER,
        text,
        font.clone(),
        Color32::GRAY,
    );
    let legend = [("total", Color32::WHITE), ("surfaces", SURFACE), ("medium", MEDIUM)];
    for (k, (name, color)) in legend.into_iter().enumerate() {
        let y = rect.bottom() - 10.0 - 13.0 * (2 - k) as f32;
        painter.text(
            pos2(rect.left() + 6.0, y),
            Align2::LEFT_CENTER,
            name,
            font.clone(),
            color,
        );
    }
    painter.text(
        pos2(rect.right() - 6.0, rect.bottom() - 10.0),
        Align2::RIGHT_CENTER,
        "incoming L_i (luminance)",
        font,
        Color32::GRAY,
    );
}
