//! The 3D probe inspector: the probe's depth along its camera ray, the incoming
//! light field on the sphere (an equal-area cylindrical map: longitude across,
//! sine of the latitude down, so every ray covers the same area), and per method
//! the luminance L_s with its gradient, the Hessian's eigenvalues and the cache
//! extent the metric gives it (ours: the ellipsoid's radii; Jarosz 2008: one
//! radius), with "copy as command".

use super::probe3d::{Probe3dResult, metric, ray_length};
use super::workbench3d::Workbench3d;
use crate::core::metric::{CacheMethod, first_order_extent, second_order_extent};
use crate::core::space::{D3, Space};
use crate::core::taylor_rgb::PartDerivs;
use crate::figure::ColorScale;
use eframe::egui::{self, vec2};
use glam::DVec3;
use std::sync::Arc;
use tiny_skia::{Paint, PathBuilder, Pixmap, Transform};

/// One method's row of the readout (luminance of the total L_s).
#[derive(Clone, Debug, PartialEq)]
pub struct Readout3 {
    pub name: &'static str,
    pub value: f64,
    pub gradient: DVec3,
    /// Ascending eigenvalues of the luminance Hessian (None: the method has none).
    pub eigenvalues: Option<DVec3>,
    /// The extent's radii (ours: per Hessian axis; Jarosz 2008: one ball).
    pub radii: DVec3,
}

pub fn readout(
    name: &'static str,
    parts: &PartDerivs<D3>,
    method: CacheMethod,
    has_hessian: bool,
    m: &crate::core::metric::MetricParams,
) -> Readout3 {
    let lum = parts.total().luminance();
    let extent = match method {
        CacheMethod::Ours => second_order_extent::<D3>(lum.value, lum.hess, lum.grad, m),
        CacheMethod::Jarosz08 => first_order_extent::<D3>(lum.value, lum.grad, m),
    };
    Readout3 {
        name,
        value: lum.value,
        gradient: lum.grad,
        eigenvalues: has_hessian.then(|| D3::sym_eigen(lum.hess).0),
        radii: extent.radii,
    }
}

/// The readout rows of a probe result: ours, Jarosz 2008 and the reference.
pub fn readouts(w: &Workbench3d, r: &Probe3dResult) -> Vec<Readout3> {
    let scene = w.doc.scene();
    let ours = metric(scene, CacheMethod::Ours, &w.params);
    let j08 = metric(scene, CacheMethod::Jarosz08, &w.params);
    let mut v = vec![
        readout("ours (aware)", &r.shared.aware, CacheMethod::Ours, true, &ours),
        readout("Jarosz 2008", &r.shared.unaware, CacheMethod::Jarosz08, false, &j08),
    ];
    if let Some(d) = &r.reference {
        v.push(readout("reference (FD)", &d.parts, CacheMethod::Ours, true, &ours));
    }
    v
}

fn vec3(v: DVec3) -> String {
    format!("({:.3e}, {:.3e}, {:.3e})", v.x, v.y, v.z)
}

impl Workbench3d {
    /// `volcache probe …` giving the same numbers for `method` (aware, unaware).
    pub fn probe_command(&self, r: &Probe3dResult, method: &str) -> String {
        let scene = self.doc.path().map_or_else(
            || format!("scenes3d/{}.json", self.doc.stem()),
            |p| p.display().to_string(),
        );
        format!(
            "volcache probe {scene} --at {},{},{} --method {method} --rays {} --steps {} --seed {} --json",
            r.at.x, r.at.y, r.at.z, self.params.rays, self.params.steps, r.seed
        )
    }

    pub(super) fn inspector(&mut self, ui: &mut egui::Ui) {
        ui.heading("3D probe");
        let Some(mut probe) = self.probe.clone() else {
            ui.label("click the view to place a probe on a pixel's camera ray");
            return;
        };
        let far = ray_length(self.doc.scene(), probe.pixel);
        super::panel3d::labelled(
            ui,
            "depth along the ray",
            egui::Slider::new(&mut probe.depth, 0.0..=far),
        );
        ui.horizontal(|ui| {
            let c = ui.checkbox(&mut probe.reference, "reference (finite differences), spp");
            ui.add(egui::DragValue::new(&mut probe.reference_spp).range(16..=1 << 20))
                .labelled_by(c.id);
        });
        if ui.button("Remove probe").clicked() {
            self.probe = None;
            return;
        }
        if Some(&probe) != self.probe.as_ref() {
            self.probe = Some(probe);
        }
        if let Some(j) = self.probe_job.running() {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(j.stage());
            });
        }
        let Some(r) = self.probe_job.current().cloned() else {
            return;
        };
        ui.label(format!(
            "at {} · L_s towards the camera · {} rays · {:.2} s{}",
            vec3(r.at),
            r.rays,
            r.seconds,
            if r.inside_medium { "" } else { " · outside the medium" }
        ));
        for row in readouts(self, &r) {
            ui.separator();
            ui.strong(row.name);
            ui.monospace(format!("L   {:.4e}", row.value));
            ui.monospace(format!("∇L  {}", vec3(row.gradient)));
            if let Some(e) = row.eigenvalues {
                ui.monospace(format!("λ(H) {}", vec3(e)));
            }
            ui.monospace(format!("radii {}", vec3(row.radii)));
        }
        ui.horizontal(|ui| {
            for m in ["aware", "unaware"] {
                let c = self.probe_command(&r, m);
                if ui
                    .button(format!("Copy {m} command"))
                    .on_hover_text(c.clone())
                    .clicked()
                {
                    ui.ctx().copy_text(c);
                }
            }
        });
        ui.separator();
        ui.label("incoming light (equal-area map, log luminance; up at the top)");
        ui.checkbox(&mut self.show_proxy, "proxy triangles (bridging ones in magenta)");
        let w = ui.available_width().clamp(120.0, 360.0);
        let size = vec2(w, w / std::f32::consts::PI);
        let ppp = ui.ctx().pixels_per_point();
        let (pw, ph) = ((size.x * ppp).round() as u32, (size.y * ppp).round() as u32);
        let fresh = self
            .light_field_tex
            .as_ref()
            .is_some_and(|(k, proxy, pw0, _)| Arc::ptr_eq(k, &r) && *proxy == self.show_proxy && *pw0 == pw);
        if !fresh {
            let pm = light_field_pixmap(&r, self.show_proxy, pw, ph);
            let image =
                egui::ColorImage::from_rgba_premultiplied([pm.width() as usize, pm.height() as usize], pm.data());
            let tex = ui
                .ctx()
                .load_texture("light_field3d", image, egui::TextureOptions::LINEAR);
            self.light_field_tex = Some((r.clone(), self.show_proxy, pw, tex));
        }
        if let Some((_, _, _, tex)) = &self.light_field_tex {
            ui.image((tex.id(), size));
        }
    }
}

/// Each ray's incoming luminance as a dot on the equal-area cylindrical map, and
/// the proxy's triangles over it (those crossing the map's seam are left out),
/// on a `w` × `h` pixmap. Rasterised once per result: thousands of dots and
/// triangles tessellated every UI frame would hold the UI thread.
pub fn light_field_pixmap(r: &Probe3dResult, proxy: bool, w: u32, h: u32) -> Pixmap {
    let mut pm = Pixmap::new(w.max(1), h.max(1)).expect("a positive size");
    pm.fill(tiny_skia::Color::from_rgba8(15, 15, 15, 255));
    let (fw, fh) = (pm.width() as f32, pm.height() as f32);
    let total = |i: &super::probe3d::Incoming3| i.surface + i.medium;
    let scale = ColorScale::auto(r.incoming.iter().map(total), true);
    let dot = (fw * fh / r.incoming.len().max(1) as f32).sqrt().clamp(1.0, 6.0);
    let mut paint = Paint::default();
    for i in &r.incoming {
        let (x, y) = equal_area(i.dir);
        let v = total(i);
        let [cr, cg, cb] = if v > 0.0 { scale.color(v) } else { [0, 0, 0] };
        paint.set_color_rgba8(cr, cg, cb, 255);
        let (cx, cy) = (x as f32 * fw, y as f32 * fh);
        if let Some(rect) = tiny_skia::Rect::from_xywh(cx - 0.5 * dot, cy - 0.5 * dot, dot, dot) {
            pm.fill_rect(rect, &paint, Transform::identity(), None);
        }
    }
    if !proxy {
        return pm;
    }
    let x = r.shared.light_field.x;
    let stroke = tiny_skia::Stroke {
        width: 0.6,
        ..Default::default()
    };
    paint.anti_alias = true;
    for e in &r.shared.elements {
        let p = e.v.map(|v| equal_area((v - x).normalize_or_zero()));
        if (0..3).any(|i| (p[i].0 - p[(i + 1) % 3].0).abs() > 0.5) {
            continue;
        }
        let mut pb = PathBuilder::new();
        pb.move_to(p[0].0 as f32 * fw, p[0].1 as f32 * fh);
        for q in &p[1..] {
            pb.line_to(q.0 as f32 * fw, q.1 as f32 * fh);
        }
        pb.close();
        let Some(path) = pb.finish() else { continue };
        if e.bridging {
            paint.set_color_rgba8(255, 60, 220, 255);
        } else {
            paint.set_color_rgba8(255, 255, 255, 40);
        }
        pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
    pm
}

/// Lambert's cylindrical equal-area projection of a direction (y up) to [0, 1]²:
/// longitude across, (1 − sin latitude)/2 down.
pub fn equal_area(d: DVec3) -> (f64, f64) {
    let lon = d.z.atan2(d.x);
    (0.5 + lon / std::f64::consts::TAU, 0.5 * (1.0 - d.y.clamp(-1.0, 1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_area_map_puts_up_on_top_and_splits_the_sphere_evenly() {
        assert_eq!(equal_area(DVec3::Y).1, 0.0);
        assert_eq!(equal_area(-DVec3::Y).1, 1.0);
        assert_eq!(equal_area(DVec3::X), (0.5, 0.5));
        // Equal area: the fraction of uniform directions above the map's middle row
        // is one half, above y = 0.25 one quarter.
        let n = 10_000;
        let above = (0..n)
            .filter(|k| {
                let z = 1.0 - 2.0 * (*k as f64 + 0.5) / n as f64;
                equal_area(DVec3::new(0.0, z, (1.0 - z * z).sqrt())).1 < 0.25
            })
            .count();
        assert_eq!(above, n / 4);
    }
}
