//! Cache records drawn as their extents: the paper's point-distribution insets.
//!
//! Each record is drawn as its ellipse (centre `position`, unit `axes` scaled by
//! `radii`, so a circle when the radii are equal): a thin anti-aliased outline and,
//! optionally, a small dot at its centre. Outlines are translucent, so where records
//! pile up (shadow edges for `ours`) their ink adds up and the region reads as
//! density. The scene's geometry is drawn under the records (see [`super::overlay`]).
//!
//! Colours ([`RecordColor`]): one colour for all, or an attribute through viridis on
//! a logarithmic scale — the record's radius (geometric mean √(r₁r₂), the radius of
//! the circle of equal area), its luminance, or its cost (rays of its light field).
//! The automatic range is robust ([`ColorScale::auto`]); pass a shared `range` to
//! compare figures. Records are drawn on a dark background, where the darkest
//! viridis colours would vanish: the scale is extended downwards by a third of its
//! span ([`LIFT`] of the bar), so the lowest attribute value is a visible purple and
//! the colour bar shows the mapping exactly as drawn.
//!
//! Geometry: outlines follow the ellipse within 0.2 px wherever it may show, however
//! large it is (only the visible arcs are refined), and are clipped to the view
//! (see [`Canvas`]); an extent under the line width is drawn as a blob. Records are
//! drawn in the order given. A record with a non-finite position or an infinite
//! radius is skipped; a negative or NaN radius counts as 0.

use super::colorbar::{ColorScale, colorbar_width, draw_colorbar};
use super::field_figure::{field_color_scale, upscale_factor};
use super::gradient_color::PANEL_BACKGROUND;
use super::overlay::{OverlayStyle, draw_scene};
use super::panel::{Canvas, View};
use super::text::{HAlign, VAlign, draw_text_aligned, text_width};
use crate::core::color::luminance;
use crate::flatland::cached_field::RecordInfo;
use crate::flatland::field::Field;
use crate::flatland::scene::Scene;
use glam::DVec2;
use tiny_skia::{Color, Pixmap};

/// What colours a record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RecordColor {
    /// One sRGB colour for every record.
    Uniform([u8; 3]),
    /// √(r₁r₂), world units (log scale).
    ByRadius,
    /// Luminance of the record's value (log scale).
    ByLuminance,
    /// Rays traced for the record's light field (log scale).
    ByCost,
}

impl RecordColor {
    /// The attribute coloured by (None for [`RecordColor::Uniform`]).
    pub fn attribute(&self, r: &RecordInfo) -> Option<f64> {
        match self {
            RecordColor::Uniform(_) => None,
            RecordColor::ByRadius => Some((radius(r.radii[0]) * radius(r.radii[1])).sqrt()),
            RecordColor::ByLuminance => Some(r.luminance),
            RecordColor::ByCost => Some(r.rays as f64),
        }
    }

    /// The quantity written along the colour bar.
    pub fn label(&self) -> &'static str {
        match self {
            RecordColor::Uniform(_) => "",
            RecordColor::ByRadius => "record radius √(r₁r₂)",
            RecordColor::ByLuminance => "record luminance",
            RecordColor::ByCost => "rays per record",
        }
    }
}

/// How records are drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordStyle {
    pub color: RecordColor,
    /// Outline width, pixels.
    pub line_width: f32,
    /// Opacity of outlines in (0, 1]; automatic from the record count when None
    /// ([`RecordStyle::alpha_for`]).
    pub alpha: Option<f32>,
    /// Radius of the dot at each record's position, pixels (0: no dot).
    pub dot_radius: f32,
    /// Draw the extents (false: dots only).
    pub outlines: bool,
    /// Attribute range shared between figures (log scale); from the records if None.
    pub range: Option<(f64, f64)>,
}

impl Default for RecordStyle {
    /// Light-blue outlines 1 px wide, no dots, automatic alpha.
    fn default() -> Self {
        RecordStyle {
            color: RecordColor::Uniform(RECORD_BLUE),
            line_width: 1.0,
            alpha: None,
            dot_radius: 0.0,
            outlines: true,
            range: None,
        }
    }
}

impl RecordStyle {
    /// The default style coloured by `color`.
    pub fn colored(color: RecordColor) -> Self {
        RecordStyle {
            color,
            ..Default::default()
        }
    }

    /// Outline opacity for `count` records: [`RecordStyle::alpha`] if set, else
    /// 0.85 up to 300 records, falling as count^(−1/4) to 0.3 (≈ 19 000 records),
    /// so a dense cache still shows its density rather than a solid blot.
    pub fn alpha_for(&self, count: usize) -> f32 {
        match self.alpha {
            Some(a) => a.clamp(0.0, 1.0),
            None => (0.85 * (300.0 / count.max(1) as f32).powf(0.25)).clamp(0.3, 0.85),
        }
    }
}

/// The default uniform record colour (reads well over the dark panel and the
/// light-grey scene geometry).
pub const RECORD_BLUE: [u8; 3] = [96, 200, 255];
/// Fraction of the colour bar below the attribute range (see the module docs).
pub const LIFT: f64 = 0.25;
/// Panel background behind records without a field.
const DARK: [u8; 3] = PANEL_BACKGROUND;
/// Undefined pixels of a dimmed field: darker than any defined one.
const DIM_INVALID: [u8; 3] = [6, 6, 8];
const TEXT: [u8; 4] = [20, 20, 20, 255];

fn radius(r: f64) -> f64 {
    if r > 0.0 { r } else { 0.0 }
}

/// The colour scale of attribute colouring for `records` (None for uniform
/// colours), extended below the data range by [`LIFT`]: the scale both drawing and
/// colour bar use.
pub fn record_color_scale(records: &[RecordInfo], style: &RecordStyle) -> Option<ColorScale> {
    if matches!(style.color, RecordColor::Uniform(_)) {
        return None;
    }
    let data = match style.range {
        Some((lo, hi)) => ColorScale::new(true, lo, hi),
        None => ColorScale::auto(records.iter().filter_map(|r| style.color.attribute(r)), true),
    };
    // min' such that the data minimum sits at LIFT: ln min = ln min' + LIFT·(ln max − ln min').
    let span = (data.max / data.min).ln();
    let lowered = data.min * (-span * LIFT / (1.0 - LIFT)).exp();
    Some(ColorScale::new(true, lowered, data.max))
}

/// The two semi-axes of a record's extent in pixel space (view's y flip and
/// possibly unequal x and y scales applied), or None if the record is unusable.
fn pixel_semi_axes(view: &View, r: &RecordInfo) -> Option<(DVec2, DVec2, DVec2)> {
    let [r0, r1] = r.radii.map(radius);
    if !(r.position.is_finite() && r0.is_finite() && r1.is_finite()) {
        return None;
    }
    let size = view.world_max - view.world_min;
    let to_px = DVec2::new(view.width as f64 / size.x, -(view.height as f64) / size.y);
    // Radii are capped at 10¹² views (so that pixel coordinates stay finite and
    // exact enough); an extent that large shows as straight edges anyway.
    let cap = 1e12 * size.max_element();
    let a0 = r.axes[0].try_normalize().unwrap_or(DVec2::X);
    let a1 = r.axes[1].try_normalize().unwrap_or(a0.perp());
    let c = view.to_pixel_f64(r.position);
    Some((c, a0 * r0.min(cap) * to_px, a1 * r1.min(cap) * to_px))
}

/// Most arcs one ellipse is split into (a few thousand suffice for any ellipse
/// that fits in 10⁴ views; far beyond, its visible part is a straight edge anyway).
const MAX_ELLIPSE_SPLITS: usize = 1 << 16;

/// The ellipse c + u·cos t + v·sin t (pixels) as a closed polyline (first point not
/// repeated) within 0.2 px of the curve where it may cross the rectangle [lo, hi]:
/// arcs are split until their chord is that close or provably outside, so huge
/// extents cost only what shows.
fn ellipse_polyline(c: DVec2, u: DVec2, v: DVec2, lo: DVec2, hi: DVec2) -> Vec<DVec2> {
    use std::f64::consts::TAU;
    let at = |t: f64| {
        let (s, co) = t.sin_cos();
        c + u * co + v * s
    };
    // |e''(t)| ≤ |u| + |v|: a chord over Δt is within (|u| + |v|)·Δt²/8 of its arc.
    let bend = u.length() + v.length();
    let n0 = ((TAU * bend / 6.0).ceil() as usize).clamp(12, 256);
    let mut pts = Vec::with_capacity(n0);
    // Arcs split in all: where rounding keeps the bound from ever proving an arc
    // outside (extents ~10¹⁵ px), splitting would otherwise go on for 2⁶⁰ arcs.
    let mut splits = 0usize;
    // Depth-first over [t0, t1] (iterative, so no recursion limit to worry about).
    for k in 0..n0 {
        let mut stack = vec![(TAU * k as f64 / n0 as f64, TAU * (k + 1) as f64 / n0 as f64, 0u32)];
        while let Some((t0, t1, depth)) = stack.pop() {
            let (a, b) = (at(t0), at(t1));
            let sag = bend * (t1 - t0).powi(2) / 8.0;
            let outside = (a.max(b) + sag).cmplt(lo).any() || (a.min(b) - sag).cmpgt(hi).any();
            if sag < 0.2 || depth >= 60 || outside || splits >= MAX_ELLIPSE_SPLITS {
                pts.push(a);
            } else {
                let m = 0.5 * (t0 + t1);
                splits += 1;
                stack.push((m, t1, depth + 1));
                stack.push((t0, m, depth + 1));
            }
        }
    }
    pts
}

/// Draw `records` over the `view` rectangle of `pixmap` (clipped to it).
pub fn draw_records(pixmap: &mut Pixmap, view: &View, records: &[RecordInfo], style: &RecordStyle) {
    let scale = record_color_scale(records, style);
    let alpha = style.alpha_for(records.len());
    let lw = style.line_width.max(0.1);
    let margin = (lw + style.dot_radius.max(0.0) + 2.0) as f64;
    let mut canvas = Canvas::new(pixmap, view, margin);
    let (lo, hi) = (view.min() - margin, view.max() + margin);
    let to_u8 = |a: f32| (255.0 * a.clamp(0.0, 1.0)).round() as u8;
    for r in records {
        let Some((c, u, v)) = pixel_semi_axes(view, r) else {
            continue;
        };
        let rgb = match (style.color, &scale) {
            (RecordColor::Uniform(rgb), _) => rgb,
            (color, Some(s)) => s.color(color.attribute(r).unwrap_or(0.0)),
            _ => unreachable!("attribute colours have a scale"),
        };
        // Bounding box of the ellipse: half-extent √(u_i² + v_i²) per axis.
        let half = DVec2::new(u.x.hypot(v.x), u.y.hypot(v.y));
        if (c + half).cmplt(lo).any() || (c - half).cmpgt(hi).any() {
            continue;
        }
        if style.outlines {
            let color = [rgb[0], rgb[1], rgb[2], to_u8(alpha)];
            let rms = ((u.length_squared() + v.length_squared()) / 2.0).sqrt();
            if rms < 0.5 * lw as f64 {
                // Below the line width an outline is a blob: draw it as one.
                canvas.disc(c, (0.5 * lw as f64 + rms) as f32, color);
            } else {
                let pts = ellipse_polyline(c, u, v, lo, hi);
                canvas.polyline(&pts, true, lw, color, None);
            }
        }
        if style.dot_radius > 0.0 && canvas.inside(c) {
            let a = if style.outlines { (1.5 * alpha).min(1.0) } else { alpha };
            canvas.disc(c, style.dot_radius, [rgb[0], rgb[1], rgb[2], to_u8(a)]);
        }
    }
}

/// A field as a dim grey background: log luminance from dark to mid grey, so
/// coloured records stay the brightest marks; undefined pixels darker still.
fn dimmed_field(field: &Field) -> Vec<u8> {
    let s = field_color_scale(field, true, None);
    field
        .values
        .iter()
        .zip(&field.valid)
        .flat_map(|(v, &ok)| {
            let c = if ok {
                let g = (24.0 + 76.0 * s.normalize(luminance(*v)).max(0.0)).round() as u8;
                [g, g, g]
            } else {
                DIM_INVALID
            };
            [c[0], c[1], c[2], 255]
        })
        .collect()
}

/// The distribution figure: the records over the scene (over a dark background, or
/// over `field` dimmed to grey), the title with the record count above
/// ("{title} — N records", or "N records"), and a colour bar for attribute colours.
/// The panel is the field enlarged as in [`field_figure`](mod@super::field_figure),
/// or the scene's domain with its longest side 512 px.
pub fn records_figure(
    field: Option<&Field>,
    scene: &Scene,
    records: &[RecordInfo],
    style: &RecordStyle,
    title: Option<&str>,
) -> Pixmap {
    let (k, pw, ph) = match field {
        Some(f) => {
            let k = upscale_factor(f.width, f.height);
            (k, (f.width as u32 * k) as f32, (f.height as u32 * k) as f32)
        }
        None => {
            let size = scene.domain_max - scene.domain_min;
            let aspect = (size.x / size.y) as f32;
            let (w, h) = if aspect >= 1.0 {
                (512.0, (512.0 / aspect).round())
            } else {
                ((512.0 * aspect).round(), 512.0)
            };
            (1, w.max(1.0), h.max(1.0))
        }
    };
    let s = (pw.max(ph) / 512.0).clamp(0.75, 3.0);
    let (label_px, title_px) = ((13.0 * s).round(), (16.0 * s).round());
    let margin = (12.0 * s).round();
    let top = (2.2 * title_px).round();
    let scale = record_color_scale(records, style);
    let bar_gap = (14.0 * s).round();
    let bar_w = scale.map_or(0.0, |sc| {
        bar_gap + colorbar_width(&sc, ph, label_px, style.color.label()).ceil()
    });
    let width = (margin + pw + bar_w + margin).ceil();
    let height = (top + ph + margin).ceil();
    let mut pixmap = Pixmap::new(width as u32, height as u32).expect("figure size");
    pixmap.fill(Color::WHITE);

    let view = match field {
        Some(f) => {
            let mapped = super::field_figure::MappedField {
                width: f.width,
                height: f.height,
                rgba: dimmed_field(f),
                scale: None,
            };
            mapped.blit(&mut pixmap, margin as i32, top as i32, k);
            View::of_field(f, margin, top, k as f32)
        }
        None => {
            let bg = tiny_skia::Rect::from_xywh(margin, top, pw, ph).expect("panel size");
            let mut paint = tiny_skia::Paint::default();
            paint.set_color_rgba8(DARK[0], DARK[1], DARK[2], 255);
            pixmap.fill_rect(bg, &paint, tiny_skia::Transform::identity(), None);
            View::new(scene.domain_min, scene.domain_max, margin, top, pw, ph)
        }
    };
    draw_scene(&mut pixmap, scene, &view, &OverlayStyle::for_panel(pw.max(ph)));
    let mut style = style.clone();
    style.line_width *= s.max(1.0);
    style.dot_radius *= s.max(1.0);
    draw_records(&mut pixmap, &view, records, &style);

    let count = match records.len() {
        1 => "1 record".to_string(),
        n => format!("{n} records"),
    };
    let t = match title.filter(|t| !t.trim().is_empty()) {
        Some(t) => format!("{t} — {count}"),
        None => count,
    };
    let room = width - 2.0 * margin.max(4.0);
    let size = (title_px * (room / text_width(&t, title_px)).min(1.0)).max(6.0);
    let w = text_width(&t, size);
    let cx = (margin + 0.5 * pw).clamp(margin + 0.5 * w, (width - margin - 0.5 * w).max(margin + 0.5 * w));
    draw_text_aligned(
        &mut pixmap,
        &t,
        cx,
        0.5 * top + 0.15 * title_px,
        size,
        TEXT,
        HAlign::Center,
        VAlign::Middle,
    );
    if let Some(sc) = &scale {
        draw_colorbar(
            &mut pixmap,
            sc,
            margin + pw + bar_gap,
            top,
            ph,
            label_px,
            style.color.label(),
        );
    }
    pixmap
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ellipses far larger than the view (a record of a 10⁻³⁰⁷-wide domain, or any
    /// extent near the 10¹² views cap) are outlined in bounded time and points
    /// (they split 2⁶⁰ arcs before).
    #[test]
    fn huge_ellipses_end() {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let (lo, hi) = (DVec2::ZERO, DVec2::splat(100.0));
            let mut most = 0;
            for r in [1e6, 1e12, 1e15, 1e300] {
                for c in [DVec2::splat(50.0), DVec2::new(50.0 - r, 50.0), DVec2::new(3.0e7, -2.0)] {
                    let pts = ellipse_polyline(c, DVec2::new(r, 0.0), DVec2::new(0.0, r * 0.5), lo, hi);
                    assert!(pts.iter().all(|p| p.is_finite()));
                    most = most.max(pts.len());
                }
            }
            tx.send(most).unwrap();
        });
        let most = rx
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("outlining huge ellipses did not end within 20 s");
        assert!(most <= 2 * MAX_ELLIPSE_SPLITS + 256, "{most} points");
    }

    fn record(x: f64, y: f64, axis: DVec2, radii: [f64; 2], luminance: f64, rays: u64) -> RecordInfo {
        let a = axis.normalize();
        RecordInfo {
            position: DVec2::new(x, y),
            axes: [a, a.perp()],
            radii,
            luminance,
            rays,
        }
    }

    use super::super::synthetic::{example_scene as scene, synthetic_records};

    /// A 200 × 200 pixmap showing [-1, 1]² (100 px per world unit).
    fn canvas() -> (Pixmap, View) {
        let view = View::new(DVec2::splat(-1.0), DVec2::splat(1.0), 0.0, 0.0, 200.0, 200.0);
        (Pixmap::new(200, 200).unwrap(), view)
    }

    /// Pixel centres holding ink, in world coordinates.
    fn inked(p: &Pixmap, view: &View) -> Vec<DVec2> {
        let mut out = Vec::new();
        for y in 0..p.height() {
            for x in 0..p.width() {
                if p.pixel(x, y).unwrap().alpha() > 0 {
                    out.push(view.to_world(x as f32 + 0.5, y as f32 + 0.5));
                }
            }
        }
        out
    }

    #[test]
    fn ink_lies_on_the_ellipse() {
        // An ellipse of radii 0.6 and 0.2 along (1, 1), centred at (0.1, −0.1).
        let axis = DVec2::new(1.0, 1.0).normalize();
        let r = record(0.1, -0.1, axis, [0.6, 0.2], 1.0, 100);
        let (mut p, view) = canvas();
        draw_records(&mut p, &view, std::slice::from_ref(&r), &RecordStyle::default());
        let ink = inked(&p, &view);
        assert!(ink.len() > 200, "{}", ink.len());
        // Every inked pixel is within a pixel and a half of the ellipse: the
        // ellipse's implicit value (1 on the curve) is within its local width.
        let px = 0.01;
        for q in &ink {
            let d = *q - r.position;
            let (s, t) = (d.dot(axis) / 0.6, d.dot(axis.perp()) / 0.2);
            let rho = (s * s + t * t).sqrt();
            // |∇ρ| ≤ 1/0.2, so 1.5 px off the curve moves ρ by at most 1.5·px/0.2.
            assert!((rho - 1.0).abs() < 1.5 * px / 0.2, "ink at {q} (ρ = {rho})");
        }
        // The ends of both axes are inked; the centre is not.
        let at = |w: DVec2| {
            let (x, y) = view.to_pixel(w);
            p.pixel(x as u32, y as u32).unwrap().alpha()
        };
        for w in [axis * 0.6, -axis * 0.6, axis.perp() * 0.2, -axis.perp() * 0.2] {
            assert!(at(r.position + w) > 0, "no ink at {w}");
        }
        assert_eq!(at(r.position), 0);
        // With a dot, the centre is inked.
        let mut q = Pixmap::new(200, 200).unwrap();
        let dotted = RecordStyle {
            dot_radius: 2.0,
            ..Default::default()
        };
        draw_records(&mut q, &view, std::slice::from_ref(&r), &dotted);
        let (x, y) = view.to_pixel(r.position);
        assert!(q.pixel(x as u32, y as u32).unwrap().alpha() > 0);
    }

    #[test]
    fn circles_are_round_and_ellipses_are_not() {
        let spread = |radii: [f64; 2]| {
            let (mut p, view) = canvas();
            let r = record(0.0, 0.0, DVec2::new(0.3, 0.9), radii, 1.0, 1);
            draw_records(&mut p, &view, &[r], &RecordStyle::default());
            let d: Vec<f64> = inked(&p, &view).iter().map(|q| q.length()).collect();
            let max = d.iter().cloned().fold(0.0, f64::max);
            let min = d.iter().cloned().fold(f64::MAX, f64::min);
            (min, max)
        };
        let (min, max) = spread([0.5, 0.5]);
        assert!(min > 0.48 && max < 0.52, "circle spans {min}..{max}");
        let (min, max) = spread([0.7, 0.25]);
        assert!(min < 0.27 && max > 0.68, "ellipse spans {min}..{max}");
    }

    #[test]
    fn attribute_colours_differ() {
        let records = [
            record(-0.5, 0.0, DVec2::X, [0.05, 0.05], 1e-3, 10),
            record(0.5, 0.0, DVec2::X, [0.4, 0.4], 1.0, 10_000),
        ];
        let colour_of = |style: &RecordStyle, i: usize| {
            let (mut p, view) = canvas();
            draw_records(&mut p, &view, &records[i..i + 1], style);
            // Colour at the right end of the circle, un-premultiplied.
            let r = &records[i];
            let (x, y) = view.to_pixel(r.position + DVec2::X * r.radii[0]);
            let c = p.pixel(x.floor() as u32, y as u32).unwrap().demultiply();
            [c.red(), c.green(), c.blue()]
        };
        let close = |a: [u8; 3], b: [u8; 3]| a.iter().zip(b).all(|(&x, y)| x.abs_diff(y) <= 2);
        let uniform = RecordStyle {
            alpha: Some(1.0),
            ..Default::default()
        };
        assert!(close(colour_of(&uniform, 0), colour_of(&uniform, 1)));
        for color in [RecordColor::ByRadius, RecordColor::ByLuminance, RecordColor::ByCost] {
            let style = RecordStyle {
                color,
                alpha: Some(1.0),
                range: Some((1e-3, 1e4)),
                ..Default::default()
            };
            // Drawn alone, each record still takes its colour from the shared range.
            let (small, big) = (colour_of(&style, 0), colour_of(&style, 1));
            assert!(!close(small, big), "{color:?}: {small:?} vs {big:?}");
            // Higher attribute, brighter viridis (the lifted bottom is still purple).
            let lum = |c: [u8; 3]| super::super::colormap::srgb8_luminance(c);
            assert!(lum(big) > lum(small), "{color:?}");
            assert!(
                lum(small) > lum(PANEL_BACKGROUND) * 2.0,
                "{color:?}: bottom colour too dark"
            );
        }
        // The automatic scale puts the lowest record at LIFT.
        let s = record_color_scale(&records, &RecordStyle::colored(RecordColor::ByCost)).unwrap();
        assert!((s.normalize(10.0) - LIFT).abs() < 0.02, "{s:?}");
        assert!(record_color_scale(&records, &RecordStyle::default()).is_none());
    }

    #[test]
    fn unusable_and_huge_records_are_safe() {
        let (mut p, view) = canvas();
        let bad = [
            record(f64::NAN, 0.0, DVec2::X, [0.1, 0.1], 1.0, 1),
            record(0.0, 0.0, DVec2::X, [f64::INFINITY, 0.1], 1.0, 1),
            record(0.0, 0.0, DVec2::X, [-1.0, f64::NAN], 1.0, 1),
            RecordInfo {
                axes: [DVec2::ZERO; 2],
                ..record(0.5, 0.5, DVec2::X, [0.1, 0.1], 1.0, 1)
            },
            record(5.0, 5.0, DVec2::X, [0.1, 0.1], 1.0, 1),
        ];
        draw_records(&mut p, &view, &bad, &RecordStyle::colored(RecordColor::ByLuminance));
        let ink = inked(&p, &view);
        // Only the zero-radius record (a blob at the origin) and the record with
        // zero axes (drawn as a circle at (0.5, 0.5)) leave ink.
        assert!(
            ink.iter()
                .all(|q| q.length() < 0.03 || (q.distance(DVec2::splat(0.5)) - 0.1).abs() < 0.02)
        );
        // An ellipse a million times the view: a straight line across it, clipped.
        let mut q = Pixmap::new(200, 200).unwrap();
        let huge = record(0.0, -1e6, DVec2::X, [1e9, 1e6 + 0.2], 1.0, 1);
        draw_records(&mut q, &view, &[huge], &RecordStyle::default());
        for x in [5u32, 100, 195] {
            assert!(q.pixel(x, 80).unwrap().alpha() > 0, "x = {x}");
        }
        assert!(inked(&q, &view).iter().all(|w| (w.y - 0.2).abs() < 0.02));
        // A tilted one crossing the view away from its vertices: its tangent line.
        let (axis, radii, t) = (DVec2::from_angle(0.3), [2e6, 1e6], 2.0f64);
        let on = axis * radii[0] * t.cos() + axis.perp() * radii[1] * t.sin();
        let tangent = (-axis * radii[0] * t.sin() + axis.perp() * radii[1] * t.cos()).normalize();
        let mut q = Pixmap::new(200, 200).unwrap();
        draw_records(
            &mut q,
            &view,
            &[record(-on.x, -on.y, axis, radii, 1.0, 1)],
            &RecordStyle::default(),
        );
        let ink = inked(&q, &view);
        assert!(ink.len() > 150, "{}", ink.len());
        assert!(ink.iter().all(|w| w.perp_dot(tangent).abs() < 0.015), "off the tangent");
    }

    #[test]
    fn figure_shows_count_and_is_deterministic() {
        let scene = scene();
        let records: Vec<RecordInfo> = (0..40)
            .map(|i| {
                let t = i as f64 / 40.0;
                record(-0.8 + 1.6 * t, -0.5, DVec2::X, [0.05 + 0.1 * t, 0.05], t, 100 + i)
            })
            .collect();
        for color in [RecordColor::Uniform(RECORD_BLUE), RecordColor::ByRadius] {
            let style = RecordStyle::colored(color);
            let a = records_figure(None, &scene, &records, &style, Some("ours"));
            let b = records_figure(None, &scene, &records, &style, Some("ours"));
            assert_eq!(a.data(), b.data());
            // Panel 512², plus margins, title and (attribute colours only) a bar.
            let bar = matches!(color, RecordColor::ByRadius);
            assert!(a.width() >= 512 + 24 && (a.width() > 600) == bar, "{}", a.width());
            assert!(a.height() > 512 + 30);
        }
        // Over a field: the panel follows the field's enlargement.
        let f = Field::new(64, 32, scene.domain_min, scene.domain_max);
        let p = records_figure(Some(&f), &scene, &records, &RecordStyle::default(), None);
        assert_eq!(upscale_factor(64, 32), 8);
        assert!(
            p.width() >= 512 && p.width() < 560 && p.height() > 256,
            "{}×{}",
            p.width(),
            p.height()
        );
    }

    /// With `VOLCACHE_FIGURE_OUT=dir`, writes `records_example.png` there (a
    /// synthetic cache dense along shadow edges, coloured by radius, on the dark
    /// background) and `records_example_field.png` (uniform colour with centre
    /// dots, over the dimmed field).
    #[test]
    fn example_records_figure() {
        use super::super::synthetic::shadow_field;
        let scene = scene();
        let records = synthetic_records(&scene, true);
        let style = RecordStyle::colored(RecordColor::ByRadius);
        let p = records_figure(None, &scene, &records, &style, Some("Synthetic cache"));
        let dotted = RecordStyle {
            dot_radius: 1.2,
            ..Default::default()
        };
        let field = shadow_field(128, 128, 0.4, 0.01);
        let q = records_figure(Some(&field), &scene, &records, &dotted, Some("Over the field"));
        assert!(q.width() < p.width(), "uniform colours need no colour bar");
        if let Some(dir) = std::env::var_os("VOLCACHE_FIGURE_OUT") {
            let dir = std::path::Path::new(&dir);
            crate::output::write_png(&dir.join("records_example.png"), &p).unwrap();
            crate::output::write_png(&dir.join("records_example_field.png"), &q).unwrap();
        }
    }
}
