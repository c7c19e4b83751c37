//! The canvas: the field (as `figure::field_to_rgba` maps it for the command line)
//! under the overlays, with pan (drag empty space, or any drag with the secondary
//! button), zoom (wheel or pinch, about the pointer), dragging of scene handles and
//! of the probe, and clicks (select a segment or light; elsewhere, place the probe).

use super::edit::{Handle, pick, selection_of};
use super::overlay::{self, Overlay};
use super::readout::MethodReadout;
use super::result_id::ResultId;
use super::scene_draw::draw_scene;
use super::view::{Xform, zoom_about};
use super::workbench::{DragKind, DragState, Workbench};
use crate::core::metric::MetricParams;
use crate::figure::{ColorScale, FieldStyle, field_to_rgba, tonemap_grey, tonemap_scale, viridis};
use crate::pipeline::world::World;
use eframe::egui::{self, Align2, Color32, FontId, Mesh, Pos2, Rect, Sense, Shape, Stroke, pos2, vec2};

/// Pick radius of handles, screen points.
const PICK_RADIUS: f32 = 8.0;
const BACKGROUND: Color32 = Color32::from_rgb(30, 30, 34);
/// Width of the colour bar's strip at the canvas' right edge.
const COLORBAR_STRIP: f32 = 100.0;

impl Workbench {
    /// How the canvas maps the field to colours (exports use the same).
    pub fn field_style(&self) -> FieldStyle {
        if self.display.false_color {
            FieldStyle::FalseColor { log: true, range: None }
        } else {
            FieldStyle::Tonemapped {
                exposure: self.exposure(),
            }
        }
    }

    /// Re-map the field into the texture when a new level landed or the display changed.
    fn update_texture(&mut self, ctx: &egui::Context) {
        let Some(level) = self.field.latest() else { return };
        let key = (ResultId::of(level), self.display);
        if self.texture.as_ref().is_some_and(|(_, k)| *k == key) {
            return;
        }
        let f = &level.rendered.field;
        let mapped = field_to_rgba(f, &self.field_style());
        let image = egui::ColorImage::from_rgba_unmultiplied([f.width, f.height], &mapped.rgba);
        self.color_scale = mapped.scale;
        match &mut self.texture {
            Some((t, k)) => {
                t.set(image, egui::TextureOptions::NEAREST);
                *k = key;
            }
            None => self.texture = Some((ctx.load_texture("field", image, egui::TextureOptions::NEAREST), key)),
        }
    }

    /// Re-make the gradient overlay's image when the grid, method or part changed.
    fn update_gradient_texture(&mut self, ctx: &egui::Context) {
        let Some(grid) = self.gradients.current() else {
            self.gradient_tex = None;
            return;
        };
        let key = (ResultId::of(grid), self.gradient_aware, self.field_params.part);
        if self.gradient_tex.as_ref().is_some_and(|(_, k, _)| *k == key) {
            return;
        }
        let view = overlay::gradient_view(grid, self.gradient_aware, self.field_params.part);
        let tex = ctx.load_texture("gradients", view.image.clone(), egui::TextureOptions::NEAREST);
        self.gradient_tex = Some((tex, key, view));
    }

    pub(super) fn metric(&self) -> MetricParams {
        MetricParams::scene_relative(self.doc.scene().scale(), self.method.eps)
    }

    /// The methods' readouts at the probe for the field's part.
    pub fn readouts(&self) -> Vec<MethodReadout> {
        let (part, metric) = (self.field_params.part, self.metric());
        let mut out = Vec::new();
        if let Some(p) = self.probe_result() {
            out.push(MethodReadout::new("aware", &p.aware, true, part, &metric));
            out.push(MethodReadout::new("unaware", &p.unaware, false, part, &metric));
        }
        if let Some(r) = self.reference_result() {
            out.push(MethodReadout::reference(r, part, &metric));
        }
        out
    }

    pub(super) fn canvas(&mut self, ui: &mut egui::Ui) {
        self.update_texture(ui.ctx());
        self.update_gradient_texture(ui.ctx());
        self.update_compare_textures(ui.ctx());
        let rect = ui.available_rect_before_wrap();
        let resp = ui.allocate_rect(rect, Sense::click_and_drag());
        let scene = self.doc.scene().clone();
        self.canvas_rect = Some(rect);
        // The colour bar gets its own strip, so that it never hides the field; the
        // strip is there in every display mode, so switching never moves the field.
        let view_rect = rect.with_max_x(rect.max.x - COLORBAR_STRIP);
        let mut xf = Xform::new(view_rect, scene.domain_min, scene.domain_max, &self.view);

        if resp.hovered() {
            let (scroll, pinch) = ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta()));
            let factor = pinch as f64 * (scroll as f64 * 0.002).exp();
            if factor != 1.0
                && let Some(p) = resp.hover_pos()
            {
                zoom_about(&mut self.view, &xf, p, factor);
                xf = Xform::new(view_rect, scene.domain_min, scene.domain_max, &self.view);
            }
        }
        self.last_xf = Some(xf);
        self.interact(ui, &resp, &xf);

        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, BACKGROUND);
        if let Some((tex, _)) = &self.texture {
            let r = xf.rect_of(scene.domain_min, scene.domain_max);
            let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0));
            painter.image(tex.id(), r, uv, Color32::WHITE);
        }
        self.shapes_drawn = self.draw_overlays(&painter, &xf);
        if self.probe.is_none() {
            hint(&painter, &xf, "click in the fog to place the probe");
        } else if self.overlays.is_on(Overlay::Gradients) && self.gradient_tex.is_none() {
            // The old scene's arrows are gone (Slot::current); say why none show.
            hint(&painter, &xf, "gradient overlay: computing for the current scene…");
        }
        // Both displays explain their colours: viridis over log luminance, or the
        // tone-mapped grey ramp from black to the value shown white.
        let short = self.quantity_label().split(" (").next().unwrap_or_default();
        if let Some(scale) = self.colorbar_scale() {
            if self.display.false_color {
                draw_colorbar(&painter, rect, &scale, short, &viridis);
            } else {
                let e = self.exposure();
                let grey = |t: f64| tonemap_grey(scale.value_at(t), e);
                // Per channel, not luminance: the quantity's symbol alone.
                let symbol = short.split(' ').next().unwrap_or_default();
                draw_colorbar(&painter, rect, &scale, &format!("{symbol}, linear"), &grey);
            }
        }
    }

    /// The scale the colour bar shows: false colour's, or for tone mapping the
    /// values from black to white at the exposure in use (None before a field).
    pub fn colorbar_scale(&self) -> Option<ColorScale> {
        match self.display.false_color {
            true => self.color_scale,
            false => self.texture.as_ref().map(|_| tonemap_scale(self.exposure())),
        }
    }

    pub(super) fn quantity_label(&self) -> &'static str {
        match self.field_params.quantity {
            crate::flatland::scene_desc::Quantity::Ls => "L_s luminance (W m^-1 rad^-1)",
            crate::flatland::scene_desc::Quantity::Fluence => "fluence luminance (W m^-1)",
        }
    }

    fn draw_overlays(&self, painter: &egui::Painter, xf: &Xform) -> usize {
        let rect = xf.rect;
        let mut n = 0;
        if self.overlays.is_on(Overlay::ErrorMap)
            && let Some((tex, (lo, hi))) = self.error_overlay()
        {
            let r = xf.rect_of(self.doc.scene().domain_min, self.doc.scene().domain_max);
            let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0));
            painter.image(tex.id(), r, uv, Color32::WHITE);
            n += 1;
            let method = super::compare::method_label(self.overlay_method);
            let text = format!("|error| of {method} vs reference: log viridis, {lo:.1e} … {hi:.1e}");
            painter.text(
                pos2(rect.left() + 8.0, rect.top() + 10.0),
                Align2::LEFT_CENTER,
                text,
                FontId::proportional(11.0),
                Color32::WHITE,
            );
        }
        if self.overlays.is_on(Overlay::Gradients)
            && let Some((tex, _, view)) = &self.gradient_tex
        {
            let r = xf.rect_of(self.doc.scene().domain_min, self.doc.scene().domain_max);
            let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0));
            painter.image(tex.id(), r, uv, Color32::WHITE);
            n += 1;
            if self.gradient_arrows {
                n += overlay::paint(painter, rect, overlay::arrow_shapes(view, xf));
            }
            let c = pos2(rect.left() + 34.0, rect.bottom() - 34.0);
            n += overlay::paint(painter, rect, overlay::wheel_shapes(c, 22.0));
            let method = if self.gradient_aware { "aware" } else { "unaware" };
            let text = format!("∇L_s ({method}): hue = direction, brightness = log |∇L|");
            let font = FontId::proportional(11.0);
            painter.text(
                pos2(c.x + 30.0, c.y + 14.0),
                Align2::LEFT_CENTER,
                text,
                font,
                Color32::WHITE,
            );
        }
        if self.overlays.is_on(Overlay::Records) {
            // Clipped to the domain, as `figure::draw_records` clips to its view.
            let scene = self.doc.scene();
            let domain = xf.rect_of(scene.domain_min, scene.domain_max).intersect(rect);
            n += overlay::paint(painter, domain, self.record_overlay_shapes(xf));
        }
        if self.overlays.is_on(Overlay::Scene) {
            n += draw_scene(painter, xf, self.doc.desc(), self.hovered, self.selection);
        }
        if let Some(p) = self.probe_result() {
            if self.overlays.is_on(Overlay::ProbeRays) {
                n += overlay::paint(painter, rect, overlay::ray_shapes(p, xf, 64));
            }
            if self.overlays.is_on(Overlay::ProbeElements) {
                n += overlay::paint(painter, rect, overlay::element_shapes(p, xf, 512));
            }
        }
        if let Some(at) = self.probe {
            if self.overlays.is_on(Overlay::Extents) {
                n += overlay::paint(painter, rect, overlay::extent_shapes(at, &self.readouts(), xf));
            }
            n += overlay::paint(
                painter,
                rect,
                overlay::probe_marker(at, xf, self.hovered == Some(Handle::Probe)),
            );
        }
        n
    }

    fn interact(&mut self, ui: &egui::Ui, resp: &egui::Response, xf: &Xform) {
        let tol = xf.to_world_len(PICK_RADIUS);
        let at = |p: Pos2| xf.to_world(p);
        self.hovered = match (&self.drag, resp.hover_pos()) {
            (
                Some(DragState {
                    kind: DragKind::Handle(h),
                    ..
                }),
                _,
            ) => Some(*h),
            (_, Some(p)) => pick(self.doc.desc(), self.probe, at(p), tol),
            _ => None,
        };
        if resp.drag_started() {
            let origin = ui.input(|i| i.pointer.press_origin()).or(resp.interact_pointer_pos());
            if let Some(o) = origin {
                let primary = resp.dragged_by(egui::PointerButton::Primary);
                let h = pick(self.doc.desc(), self.probe, at(o), tol).filter(|_| primary);
                self.drag = Some(DragState {
                    kind: h.map_or(DragKind::Pan, DragKind::Handle),
                    last_world: at(o),
                });
            }
        }
        if resp.dragged()
            && let (Some(d), Some(p)) = (self.drag, resp.interact_pointer_pos())
        {
            let now = at(p);
            match d.kind {
                DragKind::Pan => {
                    let delta = resp.drag_delta();
                    self.view.pan -= glam::DVec2::new(delta.x as f64, -delta.y as f64) / xf.scale;
                }
                DragKind::Handle(Handle::Probe) => self.probe = Some(now),
                DragKind::Handle(h) => {
                    if let Err(e) = self.doc.edit("drag", |s| super::edit::drag(s, h, d.last_world, now)) {
                        self.error(e.to_string());
                    }
                    if let Some(sel) = selection_of(h) {
                        self.selection = Some(sel);
                    }
                }
            }
            self.drag = Some(DragState { last_world: now, ..d });
        }
        if resp.drag_stopped() {
            self.drag = None;
            self.doc.end_gesture();
        }
        if resp.clicked()
            && let Some(p) = resp.interact_pointer_pos()
        {
            match pick(self.doc.desc(), self.probe, at(p), tol).and_then(selection_of) {
                Some(sel) => self.selection = Some(sel),
                None => {
                    self.selection = None;
                    self.probe = Some(at(p));
                }
            }
        }
        let cursor = match self.hovered {
            _ if matches!(
                self.drag,
                Some(DragState {
                    kind: DragKind::Pan,
                    ..
                })
            ) =>
            {
                egui::CursorIcon::Grabbing
            }
            Some(_) => egui::CursorIcon::PointingHand,
            None => egui::CursorIcon::Crosshair,
        };
        if resp.hovered() {
            ui.ctx().set_cursor_icon(cursor);
        }
    }
}

/// A one-line note at the bottom of the field's view, on a dark backdrop.
fn hint(painter: &egui::Painter, xf: &Xform, text: &str) {
    let at = pos2(xf.rect.center().x, xf.rect.bottom() - 16.0);
    let galley = painter.layout_no_wrap(text.into(), FontId::proportional(13.0), Color32::WHITE);
    let r = Rect::from_center_size(at, galley.size() + vec2(14.0, 6.0));
    painter.rect_filled(r, 4.0, Color32::from_black_alpha(170));
    painter.galley(r.min + vec2(7.0, 3.0), galley, Color32::WHITE);
}

/// A vertical colour bar at the canvas' right edge with labelled ticks; `color`
/// gives the colour at a position t ∈ [0, 1] up the bar.
fn draw_colorbar(
    painter: &egui::Painter,
    canvas: Rect,
    scale: &ColorScale,
    label: &str,
    color: &dyn Fn(f64) -> [u8; 3],
) {
    let h = (canvas.height() * 0.6).clamp(120.0, 420.0);
    let bar = Rect::from_min_size(pos2(canvas.right() - 86.0, canvas.center().y - 0.5 * h), vec2(14.0, h));
    let back = Rect::from_min_max(
        bar.min - vec2(8.0, 26.0),
        pos2(canvas.right() - 4.0, bar.bottom() + 10.0),
    );
    painter.rect_filled(back, 4.0, Color32::from_black_alpha(170));
    let mut mesh = Mesh::default();
    let n = 64;
    for k in 0..n {
        let (t0, t1) = (k as f32 / n as f32, (k + 1) as f32 / n as f32);
        let c = color(0.5 * (t0 + t1) as f64);
        let r = Rect::from_x_y_ranges(bar.x_range(), bar.bottom() - t1 * h..=bar.bottom() - t0 * h);
        mesh.add_colored_rect(r, Color32::from_rgb(c[0], c[1], c[2]));
    }
    painter.add(Shape::mesh(mesh));
    painter.rect_stroke(bar, 0.0, Stroke::new(1.0, Color32::GRAY), egui::StrokeKind::Outside);
    let font = FontId::proportional(11.0);
    for t in scale.ticks(7) {
        let y = bar.bottom() - t.t as f32 * h;
        let len = if t.label.is_some() { 5.0 } else { 3.0 };
        painter.line_segment(
            [pos2(bar.right(), y), pos2(bar.right() + len, y)],
            Stroke::new(1.0, Color32::WHITE),
        );
        if let Some(l) = &t.label {
            painter.text(
                pos2(bar.right() + 7.0, y),
                Align2::LEFT_CENTER,
                l,
                font.clone(),
                Color32::WHITE,
            );
        }
    }
    painter.text(
        pos2(bar.left() - 4.0, bar.top() - 14.0),
        Align2::LEFT_CENTER,
        label,
        font,
        Color32::WHITE,
    );
}
