//! Canvas overlays, each toggled on its own. To add one: add a variant to [`Overlay`] with its label, hold its data in the
//! workbench (usually a [`super::jobs::Slot`]), and draw it in
//! `Workbench::draw_overlays` (canvas.rs) — the toggles list [`Overlay::ALL`].

use super::compute::{GradientGrid, ProbeResult};
use super::readout::{MethodReadout, extent_outline, part_of};
use super::view::Xform;
use crate::figure::{
    ColorScale, FieldStyle, GradientSample, RECORD_BLUE, RecordColor, RecordStyle, angle_color, error_field,
    field_to_rgba, gradient_color, magnitude_range, record_color_scale, viridis,
};
use crate::flatland::cached_field::RecordInfo;
use crate::flatland::field::Field;
use crate::flatland::scene_desc::Part;
use crate::pipeline::proxy::ElementKind;
use eframe::egui::{Color32, ColorImage, Painter, Pos2, Rect, Shape, Stroke, Vec2, vec2};
use glam::DVec2;

#[cfg(test)]
mod tests {
    use super::*;
    use eframe::egui::pos2;

    /// A reference whose Hessian eigenvalues are within their standard errors is
    /// drawn dashed (many short segments), a converged one as one solid outline.
    #[test]
    fn a_noisy_reference_ellipse_is_dashed_and_a_converged_one_solid() {
        use crate::app::readout::{MethodReadout, StdErrors};
        use crate::core::metric::MetricParams;
        use crate::core::taylor::Taylor2;
        use crate::core::taylor_rgb::TaylorRgb;
        let m = MetricParams::scene_relative(2.0, 0.05);
        let h = glam::DMat2::from_cols(DVec2::new(-8.0, 0.0), DVec2::new(0.0, -2.0));
        let parts = crate::core::taylor_rgb::PartDerivs {
            single: TaylorRgb::tint(Taylor2::new(1.0, DVec2::ZERO, h), crate::core::color::Rgb::ONE),
            ..Default::default()
        };
        let se = |l0: f64, l1: f64| StdErrors {
            value: 0.01,
            grad: DVec2::splat(0.01),
            hess: [0.1; 3],
            eigenvalues: DVec2::new(l0, l1),
        };
        let mut r = MethodReadout::new("reference", &parts, true, crate::flatland::scene_desc::Part::All, &m);
        let xf = Xform::new(
            Rect::from_min_max(pos2(0.0, 0.0), pos2(400.0, 400.0)),
            DVec2::splat(-1.0),
            DVec2::splat(1.0),
            &Default::default(),
        );
        r.stderr = Some(se(0.4, 0.1));
        assert!(!r.hessian_is_noise());
        assert_eq!(extent_shapes(DVec2::ZERO, &[r.clone()], &xf).len(), 1);
        r.stderr = Some(se(0.4, 2.5));
        assert!(r.hessian_is_noise());
        assert!(extent_shapes(DVec2::ZERO, &[r.clone()], &xf).len() > 10);
        // Without batches (no standard errors) nothing is flagged.
        r.stderr = None;
        assert!(!r.hessian_is_noise());
    }

    #[test]
    fn segments_are_clipped_to_the_view() {
        let r = Rect::from_min_max(pos2(0.0, 0.0), pos2(10.0, 10.0));
        assert_eq!(
            clip_segment(pos2(-10.0, 5.0), pos2(20.0, 5.0), r),
            Some([pos2(0.0, 5.0), pos2(10.0, 5.0)])
        );
        assert_eq!(clip_segment(pos2(-10.0, -5.0), pos2(20.0, -5.0), r), None);
        assert_eq!(
            clip_segment(pos2(2.0, 2.0), pos2(3.0, 4.0), r),
            Some([pos2(2.0, 2.0), pos2(3.0, 4.0)])
        );
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Overlay {
    /// Segments, lights, medium outline (with their drag handles).
    Scene,
    /// ∇L_s on a coarse grid, colour-coded by direction and log magnitude.
    Gradients,
    /// The probe's rays to their hit points.
    ProbeRays,
    /// The probe's proxy elements (those bridging occlusion boundaries highlighted).
    ProbeElements,
    /// The cache extents of the methods at the probe.
    Extents,
    /// The records of the compare view's method: ellipses (ours) or circles
    /// (Jarosz 2008), coloured by a record attribute.
    Records,
    /// |error| of the compare view's method against its reference (log viridis).
    ErrorMap,
}

impl Overlay {
    pub const ALL: [Overlay; 7] = [
        Overlay::Scene,
        Overlay::Gradients,
        Overlay::ProbeRays,
        Overlay::ProbeElements,
        Overlay::Extents,
        Overlay::Records,
        Overlay::ErrorMap,
    ];

    pub fn label(self) -> &'static str {
        match self {
            Overlay::Scene => "Scene",
            Overlay::Gradients => "Gradient field",
            Overlay::ProbeRays => "Probe rays",
            Overlay::ProbeElements => "Proxy elements",
            Overlay::Extents => "Cache extents",
            Overlay::Records => "Cache records",
            Overlay::ErrorMap => "Error map",
        }
    }

    pub fn on_by_default(self) -> bool {
        !matches!(self, Overlay::Gradients | Overlay::Records | Overlay::ErrorMap)
    }

    /// The overlay shows the compare view's results (which it needs computed).
    pub fn needs_compare(self) -> bool {
        matches!(self, Overlay::Records | Overlay::ErrorMap)
    }
}

/// Which overlays are on.
#[derive(Clone, Debug, PartialEq)]
pub struct Overlays(Vec<Overlay>);

impl Default for Overlays {
    fn default() -> Self {
        Overlays(Overlay::ALL.into_iter().filter(|o| o.on_by_default()).collect())
    }
}

impl Overlays {
    pub fn is_on(&self, o: Overlay) -> bool {
        self.0.contains(&o)
    }

    /// Some overlay on needs the compare view's results.
    pub fn need_compare(&self) -> bool {
        self.0.iter().any(|o| o.needs_compare())
    }

    pub fn set(&mut self, o: Overlay, on: bool) {
        self.0.retain(|&x| x != o);
        if on {
            self.0.push(o);
        }
    }
}

/// Colours of the methods (those of the gradient figures).
pub fn method_color(name: &str) -> Color32 {
    let c = match name {
        "aware" => crate::figure::AWARE_PURPLE,
        "unaware" => crate::figure::UNAWARE_ORANGE,
        _ => crate::figure::REFERENCE_BLUE,
    };
    Color32::from_rgb(c[0], c[1], c[2])
}

fn rgb(c: [u8; 3], alpha: u8) -> Color32 {
    Color32::from_rgba_unmultiplied(c[0], c[1], c[2], alpha)
}

/// The gradient overlay of one method and part: an n × n image (row 0 at the top,
/// transparent outside the medium) of translucent cells in the direction's hue with
/// brightness from the log magnitude (one range shared by the grid), and the unit
/// direction per cell for its arrow. One textured quad draws every cell.
pub struct GradientView {
    pub image: ColorImage,
    pub arrows: Vec<(DVec2, DVec2)>,
    pub cell: DVec2,
    /// Arrows are drawn on every `stride`-th cell.
    pub stride: usize,
}

pub fn gradient_view(grid: &GradientGrid, aware: bool, part: Part) -> GradientView {
    let samples: Vec<(usize, GradientSample)> = grid
        .points
        .iter()
        .enumerate()
        .filter_map(|(k, p)| {
            let d = if aware { p.aware } else { p.unaware }?;
            let grad = part_of(&d, part).luminance().grad;
            Some((k, GradientSample { at: p.at, grad }))
        })
        .collect();
    let range = magnitude_range(samples.iter().map(|(_, s)| s));
    let n = grid.n;
    let mut image = ColorImage::filled([n, n], Color32::TRANSPARENT);
    let mut arrows = Vec::with_capacity(samples.len());
    let stride = arrow_stride(n);
    for (k, s) in &samples {
        // Grid points run row by row from the bottom.
        let (i, j) = (k % n, n - 1 - k / n);
        image.pixels[j * n + i] = rgb(gradient_color(s.grad, range), 170);
        let (gi, gj) = (k % n, k / n);
        let marked = gi % stride == stride / 2 && gj % stride == stride / 2;
        if (stride == 1 || marked) && s.grad.length() > 0.0 && s.grad.is_finite() {
            arrows.push((s.at, s.grad.normalize()));
        }
    }
    GradientView {
        image,
        arrows,
        cell: grid.cell,
        stride,
    }
}

/// The most arrows drawn per side: a finer grid (up to one cell per pixel of the
/// field) shows every [`arrow_stride`]-th cell's arrow, so they stay readable.
pub const MAX_ARROWS_PER_SIDE: usize = 24;

/// Which cells carry an arrow on an `n` × `n` grid: every k-th in each direction.
pub fn arrow_stride(n: usize) -> usize {
    n.div_ceil(MAX_ARROWS_PER_SIDE).max(1)
}

/// An arrow per cell (per [`arrow_stride`]-th cell on fine grids): a dark line
/// through the cell centre with a triangular head.
pub fn arrow_shapes(view: &GradientView, xf: &Xform) -> Vec<Shape> {
    let half = 0.38 * view.cell.min_element() * view.stride as f64;
    let ink = Color32::from_black_alpha(200);
    let mut shapes = Vec::with_capacity(2 * view.arrows.len());
    for &(at, d) in &view.arrows {
        let (tail, tip) = (xf.to_screen(at - d * half), xf.to_screen(at + d * half));
        let v = tip - tail;
        let (u, side) = (v.normalized() * 5.0, vec2(-v.y, v.x).normalized() * 2.5);
        shapes.push(Shape::line_segment([tail, tip - u * 0.5], Stroke::new(1.5, ink)));
        shapes.push(Shape::convex_polygon(
            vec![tip, tip - u + side, tip - u - side],
            ink,
            Stroke::NONE,
        ));
    }
    shapes
}

/// A small colour wheel explaining the gradient colours, at `center`.
pub fn wheel_shapes(center: eframe::egui::Pos2, radius: f32) -> Vec<Shape> {
    let n = 36;
    (0..n)
        .map(|k| {
            let (a0, a1) = (
                k as f32 / n as f32 * std::f32::consts::TAU,
                (k + 1) as f32 / n as f32 * std::f32::consts::TAU,
            );
            // Screen y is down: world angle a is drawn at −a.
            let p = |a: f32| center + radius * Vec2::new(a.cos(), -a.sin());
            let c = angle_color(0.5 * (a0 + a1) as f64, 1.0);
            Shape::convex_polygon(vec![center, p(a0), p(a1)], rgb(c, 255), Stroke::NONE)
        })
        .collect()
}

/// The part of the segment [a, b] inside `rect` (Liang–Barsky): rays and bridging
/// elements reach far outside the view, and tessellating them whole costs frames.
pub fn clip_segment(a: Pos2, b: Pos2, rect: Rect) -> Option<[Pos2; 2]> {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [
        (-d.x, a.x - rect.left()),
        (d.x, rect.right() - a.x),
        (-d.y, a.y - rect.top()),
        (d.y, rect.bottom() - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then(|| [a + d * t0, a + d * t1])
}

/// Up to `max` of the probe's rays (evenly spread), to their hit point or cut,
/// with hit points coloured by their radiance (viridis over the brightest hit).
pub fn ray_shapes(p: &ProbeResult, xf: &Xform, max: usize) -> Vec<Shape> {
    let lf = &p.light_field;
    let stride = lf.rays.len().div_ceil(max.max(1)).max(1);
    let top = p.incoming.iter().map(|i| i.surface).fold(0.0, f64::max).max(1e-300);
    let x = xf.to_screen(lf.x);
    let mut shapes = Vec::new();
    for (r, inc) in lf.rays.iter().zip(&p.incoming).step_by(stride) {
        let end = xf.to_screen(lf.x + r.dir * r.length);
        if let Some(seg) = clip_segment(x, end, xf.rect) {
            shapes.push(Shape::line_segment(
                seg,
                Stroke::new(1.0, Color32::from_white_alpha(60)),
            ));
        }
        if r.hit.is_some() {
            shapes.push(Shape::circle_filled(end, 2.5, rgb(viridis(inc.surface / top), 255)));
        }
    }
    shapes
}

/// Surface elements as cyan polylines (at most ~`max_points` vertices: neighbours
/// are sub-pixel apart), broken at the elements bridging occlusion boundaries,
/// which are drawn red (surface pieces bold, medium shell pieces faint). Ordinary
/// medium shells are not drawn: thousands of arcs would hide the rest.
pub fn element_shapes(p: &ProbeResult, xf: &Xform, max_points: usize) -> Vec<Shape> {
    let surface: Vec<&crate::pipeline::proxy::Element<crate::core::space::D2>> =
        p.elements.iter().filter(|e| e.kind == ElementKind::Surface).collect();
    let stride = surface.len().div_ceil(max_points.max(1)).max(1);
    let (cyan, red) = (Color32::from_rgb(0, 200, 220), Color32::from_rgb(255, 60, 60));
    let mut shapes = Vec::new();
    let mut run: Vec<Pos2> = Vec::new();
    let flush = |run: &mut Vec<Pos2>, shapes: &mut Vec<Shape>| {
        if run.len() >= 2 {
            shapes.push(Shape::line(std::mem::take(run), Stroke::new(1.5, cyan)));
        }
        run.clear();
    };
    for (k, e) in surface.iter().enumerate() {
        let (a, b) = (xf.to_screen(e.v[0]), xf.to_screen(e.v[1]));
        let visible = clip_segment(a, b, xf.rect.expand(50.0)).is_some();
        if e.bridging || !visible {
            flush(&mut run, &mut shapes);
            continue;
        }
        if run.is_empty() {
            run.push(a);
        }
        if k % stride == 0 || k + 1 == surface.len() {
            run.push(b);
        }
    }
    flush(&mut run, &mut shapes);
    // Surface pieces bold; the (many more) medium shell pieces that bridge, fainter.
    let faint = Color32::from_rgba_unmultiplied(255, 60, 60, 110);
    for e in p.elements.iter().filter(|e| e.bridging) {
        if let Some(seg) = clip_segment(xf.to_screen(e.v[0]), xf.to_screen(e.v[1]), xf.rect) {
            let stroke = match e.kind {
                ElementKind::Surface => Stroke::new(2.5, red),
                ElementKind::Medium => Stroke::new(1.0, faint),
            };
            shapes.push(Shape::line_segment(seg, stroke));
        }
    }
    shapes
}

/// Each method's extent around the probe, in its colour; an extent whose Hessian
/// is not known from its estimate ([`MethodReadout::hessian_is_noise`]: the
/// reference with too few samples) is drawn dashed and faded, not as if exact.
pub fn extent_shapes(at: DVec2, readouts: &[MethodReadout], xf: &Xform) -> Vec<Shape> {
    let mut shapes = Vec::new();
    for r in readouts.iter().filter(|r| r.is_finite()) {
        let mut pts: Vec<_> = extent_outline(at, &r.extent, 48)
            .into_iter()
            .map(|p| xf.to_screen(p))
            .collect();
        let color = method_color(r.name);
        if r.hessian_is_noise() {
            pts.push(pts[0]);
            let faded = Stroke::new(1.5, color.gamma_multiply(0.6));
            shapes.extend(Shape::dashed_line(&pts, faded, 6.0, 5.0));
        } else {
            shapes.push(Shape::line(pts, Stroke::new(2.0, color)));
        }
    }
    shapes
}

/// The shared colour scale of records coloured by `color` over every record list
/// (the range of `figure compare`, so that radii compare across methods); None for
/// uniform colours.
pub fn records_scale(lists: &[&[RecordInfo]], color: RecordColor) -> Option<ColorScale> {
    let all: Vec<RecordInfo> = lists.iter().flat_map(|l| l.iter().cloned()).collect();
    let mut style = RecordStyle::colored(color);
    style.range = record_color_scale(&all, &style).map(|s| (s.min, s.max));
    record_color_scale(&all, &style)
}

/// Points of a record's extent on screen (c + u cos t + v sin t), or None if the
/// record is unusable or lies wholly outside `clip`. Radii are capped at 10⁶ views.
pub fn record_outline(r: &RecordInfo, xf: &Xform, clip: Rect, segments: usize) -> Option<Vec<Pos2>> {
    let [r0, r1] = r.radii.map(|x| x.max(0.0));
    if !(r.position.is_finite() && r0.is_finite() && r1.is_finite()) {
        return None;
    }
    let cap = 1e6 * xf.to_world_len(xf.rect.width().max(xf.rect.height()));
    let a0 = r.axes[0].try_normalize().unwrap_or(DVec2::X);
    let a1 = r.axes[1].try_normalize().unwrap_or(a0.perp());
    let (u, v) = (a0 * r0.min(cap), a1 * r1.min(cap));
    let c = xf.to_screen(r.position);
    let half = (u.length().max(v.length()) * xf.scale) as f32;
    let bbox = Rect::from_center_size(c, Vec2::splat(2.0 * half));
    if !bbox.intersects(clip) {
        return None;
    }
    let n = segments.max(8);
    Some(
        (0..n)
            .map(|k| {
                let (s, co) = (std::f64::consts::TAU * k as f64 / n as f64).sin_cos();
                xf.to_screen(r.position + u * co + v * s)
            })
            .collect(),
    )
}

/// Records as outlines in the colours of `figure::draw_records` (uniform light
/// blue, or the attribute through `scale`), with its automatic opacity; extents
/// smaller than a pixel as dots.
pub fn record_shapes(records: &[RecordInfo], color: RecordColor, scale: Option<&ColorScale>, xf: &Xform) -> Vec<Shape> {
    let style = RecordStyle::colored(color);
    let alpha = (255.0 * style.alpha_for(records.len())).round() as u8;
    let mut shapes = Vec::with_capacity(records.len());
    for r in records {
        let c = match (color, scale) {
            (RecordColor::Uniform(c), _) => c,
            (_, Some(s)) => s.color(color.attribute(r).unwrap_or(0.0)),
            (_, None) => RECORD_BLUE,
        };
        let ink = rgb(c, alpha);
        let screen_r = (r.radii[0].max(0.0) * r.radii[1].max(0.0)).sqrt() * xf.scale;
        if screen_r.is_finite() && screen_r < 1.0 {
            if r.position.is_finite() && xf.rect.contains(xf.to_screen(r.position)) {
                shapes.push(Shape::circle_filled(xf.to_screen(r.position), 1.0, ink));
            }
            continue;
        }
        let n = (screen_r * 0.5).clamp(16.0, 96.0) as usize;
        if let Some(pts) = record_outline(r, xf, xf.rect.expand(2.0), n) {
            shapes.push(Shape::closed_line(pts, Stroke::new(1.0, ink)));
        }
    }
    shapes
}

/// The error field of `test` against `reference` (absolute luminance error, as
/// `figure::error_field`) as an image on the log `range`: viridis where defined,
/// transparent elsewhere (row 0 at the top).
pub fn error_image(test: &Field, reference: &Field, range: (f64, f64)) -> ColorImage {
    let e = error_field(test, reference, false);
    let style = FieldStyle::FalseColor {
        log: true,
        range: Some(range),
    };
    let mut mapped = field_to_rgba(&e, &style);
    // Same pixel order as the field's texture: clear the undefined pixels.
    for (k, ok) in e.valid.iter().enumerate() {
        if !ok {
            mapped.rgba[4 * k + 3] = 0;
        }
    }
    ColorImage::from_rgba_unmultiplied([e.width, e.height], &mapped.rgba)
}

/// The probe's marker: a ring with a cross.
pub fn probe_marker(at: DVec2, xf: &Xform, hot: bool) -> Vec<Shape> {
    let c = xf.to_screen(at);
    let r = if hot { 9.0 } else { 7.0 };
    let white = Stroke::new(2.0, Color32::WHITE);
    vec![
        Shape::circle_stroke(c, r + 1.5, Stroke::new(4.0, Color32::BLACK)),
        Shape::circle_stroke(c, r, white),
        Shape::line_segment([c - vec2(r + 5.0, 0.0), c - vec2(r - 3.0, 0.0)], white),
        Shape::line_segment([c + vec2(r - 3.0, 0.0), c + vec2(r + 5.0, 0.0)], white),
        Shape::line_segment([c - vec2(0.0, r + 5.0), c - vec2(0.0, r - 3.0)], white),
        Shape::line_segment([c + vec2(0.0, r - 3.0), c + vec2(0.0, r + 5.0)], white),
    ]
}

/// Clip shapes to `rect` by painting through a clipped painter.
pub fn paint(painter: &Painter, rect: Rect, shapes: Vec<Shape>) -> usize {
    let n = shapes.len();
    painter.with_clip_rect(rect).extend(shapes);
    n
}
