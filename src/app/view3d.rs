//! The 3D view: the latest image, scaled to fit with its aspect ratio; camera
//! motion with the mouse (drag: orbit; right or middle drag, or Shift+drag: pan;
//! wheel: dolly), a click places the probe on that pixel's ray; the cache's
//! records drawn over the image as discs of their ellipsoids' mean radius,
//! coloured as `figure compare3d` colours them.

use super::probe3d::Probe3d;
use super::workbench3d::{RecordShade, Workbench3d};
use crate::figure::ColorScale;
use crate::volume::cached::RecordInfo;
use crate::volume::camera::Camera;
use crate::volume::orbit::{dolly, orbit, pan};
use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke, vec2};
use glam::{DVec2, DVec3};
use tiny_skia::{Paint, PathBuilder, Pixmap, Transform};

/// Radians of orbit per view width dragged.
const ORBIT_PER_WIDTH: f64 = std::f64::consts::PI;
/// Dolly factor per scroll point (egui's scroll delta).
const DOLLY_PER_POINT: f64 = 0.002;

/// A record's disc in image fractions: centre and radius (of the height).
pub fn record_disc(cam: &Camera, r: &RecordInfo) -> Option<(DVec2, f64)> {
    let d = r.position - cam.position;
    let p = cam.project(d)?;
    let z = d.dot(cam.forward);
    let mean = (r.radii[0] * r.radii[1] * r.radii[2]).cbrt();
    if !mean.is_finite() || z <= 0.0 {
        return None;
    }
    // |down| is tan(fov/2): half the image height at distance 1.
    let radius = 0.5 * mean / (z * cam.down.length());
    Some((DVec2::new(p.x / cam.width as f64, p.y / cam.height as f64), radius))
}

/// The records' outlines on a transparent `w` × `h` pixmap covering the image:
/// discs of their mean radius, translucent so that where records pile up their
/// ink reads as density. Returns the pixmap and how many discs reach into it.
pub fn records_pixmap(cam: &Camera, records: &[RecordInfo], shade: RecordShade, w: u32, h: u32) -> (Pixmap, usize) {
    let mut pm = Pixmap::new(w, h).expect("a positive size");
    let scale = ColorScale::auto(records.iter().map(|r| shade_of(shade, r)), true);
    let (fw, fh) = (w as f32, h as f32);
    let stroke = tiny_skia::Stroke {
        width: 1.0,
        ..Default::default()
    };
    let mut drawn = 0;
    for r in records {
        let Some((c, radius)) = record_disc(cam, r) else {
            continue;
        };
        let (x, y) = (c.x as f32 * fw, c.y as f32 * fh);
        let px = (radius as f32 * fh).max(1.5);
        let reaches = x + px >= 0.0 && x - px <= fw && y + px >= 0.0 && y - px <= fh;
        let Some(circle) = PathBuilder::from_circle(x, y, px.min(8.0 * fh)).filter(|_| reaches) else {
            continue;
        };
        let [cr, cg, cb] = scale.color(shade_of(shade, r));
        let mut paint = Paint::default();
        paint.set_color_rgba8(cr, cg, cb, 120);
        paint.anti_alias = true;
        pm.stroke_path(&circle, &paint, &stroke, Transform::identity(), None);
        drawn += 1;
    }
    (pm, drawn)
}

/// The attribute a record is coloured by.
pub fn shade_of(shade: RecordShade, r: &RecordInfo) -> f64 {
    match shade {
        RecordShade::Radius => (r.radii[0] * r.radii[1] * r.radii[2]).cbrt(),
        RecordShade::Luminance => r.luminance,
        RecordShade::Cost => r.rays as f64,
    }
}

/// The largest rectangle of aspect `w`:`h` centred in `avail`.
fn fit(avail: Rect, w: usize, h: usize) -> Rect {
    let aspect = w as f32 / h.max(1) as f32;
    let size = if avail.width() / avail.height().max(1.0) > aspect {
        vec2(avail.height() * aspect, avail.height())
    } else {
        vec2(avail.width(), avail.width() / aspect)
    };
    Rect::from_center_size(avail.center(), size)
}

impl Workbench3d {
    /// The central view.
    pub(super) fn view(&mut self, ui: &mut egui::Ui) {
        let avail = ui.available_rect_before_wrap();
        let (w, h) = (self.params.width, self.params.height);
        let rect = fit(avail, w, h);
        self.view_rect = Some(rect);
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let painter = ui.painter_at(avail);
        painter.rect_filled(avail, 0.0, Color32::from_gray(20));
        self.update_texture(ui.ctx());
        match &self.texture {
            Some((tex, _, _, _)) => {
                let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
                painter.image(tex.id(), rect, uv, Color32::WHITE);
            }
            None => {
                painter.text(
                    rect.center(),
                    egui::Align2::CENTER_CENTER,
                    "rendering…",
                    egui::FontId::proportional(16.0),
                    Color32::GRAY,
                );
            }
        }
        if !self.frame_is_current() && self.frame().is_some() {
            painter.text(
                rect.left_top() + vec2(6.0, 6.0),
                egui::Align2::LEFT_TOP,
                "refining…",
                egui::FontId::proportional(13.0),
                Color32::from_rgb(255, 210, 120),
            );
        }
        self.draw_error_caption(&painter, rect);
        self.records_drawn = if self.display.show_records {
            self.draw_records(&ui.painter_at(rect), rect)
        } else {
            0
        };
        self.draw_probe(&painter, rect);
        self.camera_input(ui, &response, rect);
    }

    fn update_texture(&mut self, ctx: &egui::Context) {
        let Some(frame) = self.frame().cloned() else { return };
        // Whether the map is shown is checked every UI frame; the map itself is
        // made only when the texture changes.
        let shown = self.error_map_shown(&frame);
        let stale = match &self.texture {
            Some((_, n, d, e)) => *n != self.frames || *d != self.display || *e != shown,
            None => true,
        };
        if !stale {
            return;
        }
        let map = self.current_error_map(&frame);
        let key = (self.frames, self.display, map.is_some());
        self.error_shown = map.as_ref().map(|m| (m.errors, m.range));
        let rgba = match map {
            Some(m) => m.rgba,
            None => self.display_rgba(&frame),
        };
        let image = egui::ColorImage::from_rgba_unmultiplied([frame.image.width, frame.image.height], &rgba);
        match &mut self.texture {
            Some((t, n, d, e)) => {
                t.set(image, egui::TextureOptions::LINEAR);
                (*n, *d, *e) = key;
            }
            None => {
                let t = ctx.load_texture("view3d", image, egui::TextureOptions::LINEAR);
                self.texture = Some((t, key.0, key.1, key.2));
            }
        }
    }

    /// What the error map shows (its range and RMSE), or why it is not shown yet.
    fn draw_error_caption(&self, painter: &egui::Painter, rect: Rect) {
        if !self.display.error_map {
            return;
        }
        let shown = self.texture.as_ref().is_some_and(|t| t.3);
        let text = match (&self.error_shown, shown) {
            (Some((e, (lo, hi))), true) => format!(
                "|L − L_ref| {}, log colour {lo:.1e}…{hi:.1e}: RMSE {:.3e} (mean L_ref {:.3e})",
                if self.display.medium_only {
                    "of the medium part"
                } else {
                    "of the image"
                },
                e.rmse,
                e.mean_reference
            ),
            _ if self.reference.running().is_some() => "error map: rendering the reference…".to_string(),
            _ => "error map: at the view's full size, once the reference and the image are of this state".to_string(),
        };
        painter.text(
            rect.left_bottom() + vec2(6.0, -6.0),
            egui::Align2::LEFT_BOTTOM,
            text,
            egui::FontId::proportional(13.0),
            Color32::from_rgb(255, 230, 160),
        );
    }

    /// Draw the current frame's records; returns how many were drawn. They are
    /// rasterised once per frame, shading and size into a texture (tiny-skia):
    /// hundreds of large translucent outlines tessellated anew every UI frame cost
    /// the UI thread ~40 ms a frame under llvmpipe.
    fn draw_records(&mut self, painter: &egui::Painter, rect: Rect) -> usize {
        let Some(frame) = self.render.current().cloned() else {
            return 0;
        };
        let ppp = painter.ctx().pixels_per_point();
        let (w, h) = (
            (rect.width() * ppp).round() as u32,
            (rect.height() * ppp).round() as u32,
        );
        let key = (self.frames, self.display.record_shade, w, h, self.doc.revision());
        if self.records_tex.as_ref().is_none_or(|(k, _, _)| *k != key) {
            let cam = &self.doc.scene().camera;
            let (pm, drawn) = records_pixmap(cam, &frame.records, self.display.record_shade, w.max(1), h.max(1));
            let image =
                egui::ColorImage::from_rgba_premultiplied([pm.width() as usize, pm.height() as usize], pm.data());
            let tex = painter
                .ctx()
                .load_texture("records3d", image, egui::TextureOptions::LINEAR);
            self.records_tex = Some((key, tex, drawn));
        }
        let (_, tex, drawn) = self.records_tex.as_ref().unwrap();
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        painter.image(tex.id(), rect, uv, Color32::WHITE);
        *drawn
    }

    fn draw_probe(&self, painter: &egui::Painter, rect: Rect) {
        let Some(p) = &self.probe else { return };
        let c = rect.min + vec2(p.pixel.x as f32 * rect.width(), p.pixel.y as f32 * rect.height());
        let s = Stroke::new(2.0, Color32::from_rgb(255, 80, 200));
        painter.line_segment([c - vec2(7.0, 0.0), c + vec2(7.0, 0.0)], s);
        painter.line_segment([c - vec2(0.0, 7.0), c + vec2(0.0, 7.0)], s);
        painter.circle_stroke(c, 4.0, s);
    }

    fn camera_input(&mut self, ui: &egui::Ui, response: &egui::Response, rect: Rect) {
        let cam = self.doc.desc().camera.clone();
        let mut moved = None;
        if response.dragged() {
            let d = response.drag_delta();
            let (dx, dy) = (d.x as f64, d.y as f64);
            let shift = ui.input(|i| i.modifiers.shift);
            let panning = shift
                || response.dragged_by(egui::PointerButton::Secondary)
                || response.dragged_by(egui::PointerButton::Middle);
            let hgt = rect.height().max(1.0) as f64;
            moved = Some(if panning {
                pan(&cam, dx / hgt, dy / hgt)
            } else {
                let per = ORBIT_PER_WIDTH / rect.width().max(1.0) as f64;
                orbit(&cam, -dx * per, dy * per)
            });
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y) as f64;
            if scroll != 0.0 {
                moved = Some(dolly(&cam, (-scroll * DOLLY_PER_POINT).exp(), self.doc.scene().scale));
            }
        }
        if let Some(c) = moved
            && let Err(e) = self.doc.set_camera(c)
        {
            self.error(e.to_string());
        }
        if response.clicked()
            && let Some(pos) = response.interact_pointer_pos()
        {
            let f = (pos - rect.min) / rect.size();
            let pixel = DVec2::new(f.x as f64, f.y as f64);
            self.probe = Some(Probe3d::at_pixel(self.doc.scene(), pixel));
        }
    }
}

/// The unit direction from the camera through image fractions `pixel`.
pub fn pixel_direction(cam: &Camera, pixel: DVec2) -> DVec3 {
    cam.direction(pixel * DVec2::new(cam.width as f64, cam.height as f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_record_projects_where_its_centre_is_seen_with_its_radius() {
        let cam = Camera::new(DVec3::ZERO, -DVec3::Z, DVec3::Y, 90.0, 200, 100);
        let r = RecordInfo {
            position: pixel_direction(&cam, DVec2::new(0.25, 0.75)) * 3.0,
            axes: [DVec3::X, DVec3::Y, DVec3::Z],
            radii: [0.5, 0.5, 0.5],
            luminance: 1.0,
            rays: 64,
        };
        let (c, radius) = record_disc(&cam, &r).unwrap();
        assert!((c - DVec2::new(0.25, 0.75)).length() < 1e-9);
        // At fov 90° the image's half height at depth z is z: radius 0.5 at depth
        // z is 0.25/z of the height.
        let z = r.position.dot(-DVec3::Z);
        assert!((radius - 0.25 / z).abs() < 1e-12);
        let behind = RecordInfo {
            position: DVec3::Z,
            ..r
        };
        assert!(record_disc(&cam, &behind).is_none());
    }
}
