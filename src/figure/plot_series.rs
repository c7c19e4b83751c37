//! How the series of a [`Plot`] look: lines (solid, dashed, dotted) and markers
//! drawn in the plot area, and the legend showing a sample of each.
//!
//! Line width 1.8 px and markers of radius 2.7 px (with a white ring, so that
//! overlapping markers stay distinct) at the 12 px font size, scaled with it by
//! `u` = font / 12. Dashes are 4 × 2.5 widths, dots 1 × 1.6 widths. The legend sits
//! inside the plot area, in the corner that hides the least of the curves (top
//! right, top left, bottom right, bottom left on ties), on a translucent white box.

use super::panel::{Canvas, View};
use super::plot_layout::{LineStyle, Plot, PlotLayout, Series, TEXT, WHITE, fill_rect};
use super::text::{HAlign, VAlign, draw_text_aligned, text_width};
use glam::DVec2;
use tiny_skia::Pixmap;

fn dash(style: LineStyle, width: f32) -> Option<(f32, f32)> {
    match style {
        LineStyle::Dashed => Some((4.0 * width, 2.5 * width)),
        LineStyle::Dotted => Some((1.0 * width, 1.6 * width)),
        _ => None,
    }
}

fn has_line(style: LineStyle) -> bool {
    !matches!(style, LineStyle::Markers)
}

fn has_markers(style: LineStyle) -> bool {
    matches!(style, LineStyle::Markers | LineStyle::LineAndMarkers)
}

fn marker(canvas: &mut Canvas, c: DVec2, color: [u8; 3], u: f32) {
    canvas.disc(c, 3.6 * u, WHITE);
    canvas.disc(c, 2.7 * u, [color[0], color[1], color[2], 255]);
}

pub(crate) fn draw_series(canvas: &mut Canvas, l: &PlotLayout, s: &Series, u: f32) {
    let width = 1.8 * u;
    let color = [s.color[0], s.color[1], s.color[2], 255];
    let pts: Vec<Option<DVec2>> = s.points.iter().map(|&(x, y)| l.to_pixel(x, y)).collect();
    if has_line(s.style) {
        for run in pts.split(Option::is_none) {
            let run: Vec<DVec2> = run.iter().flatten().copied().collect();
            if run.len() >= 2 {
                canvas.polyline(&run, false, width, color, dash(s.style, width));
            }
        }
    }
    if has_markers(s.style) {
        for q in pts.iter().flatten() {
            marker(canvas, *q, s.color, u);
        }
    }
}

pub(crate) fn draw_legend(pixmap: &mut Pixmap, l: &PlotLayout, p: &Plot, u: f32) {
    let entries: Vec<&Series> = p.series.iter().filter(|s| !s.label.is_empty()).collect();
    if entries.is_empty() {
        return;
    }
    let font = l.font_px;
    let (pad, sample, row) = ((0.6 * font).round(), (2.4 * font).round(), (1.5 * font).round());
    let text_w = entries.iter().map(|s| text_width(&s.label, font)).fold(0.0, f32::max);
    let (w, h) = (
        (pad + sample + 0.6 * font + text_w + pad).ceil(),
        2.0 * pad + row * entries.len() as f32,
    );
    let (ax, ay, aw, ah) = l.area;
    let inset = (0.6 * font).round();
    // Corners in order of preference; keep the one hiding the least of the curves,
    // sampled every few pixels (so that long segments count too).
    let corners = [
        (ax + aw - inset - w, ay + inset),
        (ax + inset, ay + inset),
        (ax + aw - inset - w, ay + ah - inset - h),
        (ax + inset, ay + ah - inset - h),
    ];
    let mut ink: Vec<DVec2> = Vec::new();
    for s in &p.series {
        let pts: Vec<Option<DVec2>> = s.points.iter().map(|&(x, y)| l.to_pixel(x, y)).collect();
        if has_line(s.style) {
            for w in pts.windows(2) {
                if let [Some(a), Some(b)] = *w {
                    let n = ((b - a).length() / 4.0).ceil().clamp(1.0, 256.0) as usize;
                    ink.extend((0..n).map(|k| a.lerp(b, k as f64 / n as f64)));
                }
            }
        }
        ink.extend(pts.iter().flatten());
    }
    let hidden = |(x, y): (f32, f32)| {
        let (lo, hi) = (
            DVec2::new(x as f64, y as f64),
            DVec2::new((x + w) as f64, (y + h) as f64),
        );
        ink.iter().filter(|q| q.cmpge(lo).all() && q.cmple(hi).all()).count()
    };
    let (x, y) = corners.into_iter().min_by_key(|&c| hidden(c)).unwrap();
    let (x, y) = (x.round(), y.round());
    fill_rect(pixmap, x, y, w, h, [255, 255, 255, 235]);
    for (fx, fy, fw, fh) in [
        (x, y, w, 1.0),
        (x, y + h - 1.0, w, 1.0),
        (x, y, 1.0, h),
        (x + w - 1.0, y, 1.0, h),
    ] {
        fill_rect(pixmap, fx, fy, fw, fh, [185, 185, 185, 255]);
    }
    let view = View::new(DVec2::ZERO, DVec2::ONE, x, y, w, h);
    for (k, s) in entries.iter().enumerate() {
        let cy = y + pad + row * (k as f32 + 0.5);
        let (a, b) = (
            DVec2::new((x + pad) as f64, cy as f64),
            DVec2::new((x + pad + sample) as f64, cy as f64),
        );
        let mut canvas = Canvas::new(pixmap, &view, 0.0);
        let width = 1.8 * u;
        if has_line(s.style) {
            let color = [s.color[0], s.color[1], s.color[2], 255];
            canvas.polyline(&[a, b], false, width, color, dash(s.style, width));
        }
        if has_markers(s.style) {
            marker(&mut canvas, 0.5 * (a + b), s.color, u);
        }
        let tx = x + pad + sample + 0.6 * font;
        draw_text_aligned(pixmap, &s.label, tx, cy, font, TEXT, HAlign::Left, VAlign::Middle);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figure::plot::{Axis, draw_plot};

    #[test]
    fn legend_avoids_the_curves_and_shows_each_style() {
        // A curve through the top right only: the legend moves to the top left.
        let mut p = Plot::new(Axis::linear("x"), Axis::linear("y"));
        let styles = [
            LineStyle::Solid,
            LineStyle::Dashed,
            LineStyle::Dotted,
            LineStyle::Markers,
        ];
        for (k, style) in styles.into_iter().enumerate() {
            let pts = (0..=20)
                .map(|i| (i as f64 / 20.0, (i as f64 / 20.0).powi(4) + 0.01 * k as f64))
                .collect();
            p.series
                .push(Series::new(&format!("{style:?}"), [200, 30 + 40 * k as u8, 30], pts).with_style(style));
        }
        let img = draw_plot(&p);
        let l = PlotLayout::new((0.0, 0.0, 640.0, 400.0), &p);
        let is_frame = |x: u32, y: u32| {
            let c = img.pixel(x, y).unwrap();
            [c.red(), c.green(), c.blue()] == [185, 185, 185]
        };
        let (ax, ay, aw) = (l.area.0 as u32, l.area.1 as u32, l.area.2 as u32);
        let frame_in = |x0: u32, x1: u32| {
            (ay..ay + 15)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| is_frame(x, y))
                .count()
        };
        let (left, right) = (frame_in(ax, ax + aw / 2), frame_in(ax + aw / 2, ax + aw));
        assert!(left > 50 && right == 0, "{left} {right}");
        // Each entry shows its colour in the legend box.
        for k in 0..4u8 {
            let c = [200, 30 + 40 * k, 30];
            let n = (ay..ay + 120)
                .flat_map(|y| (ax..ax + aw / 2).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    let q = img.pixel(x, y).unwrap();
                    [q.red(), q.green(), q.blue()] == c
                })
                .count();
            assert!(n > 3, "entry {k}: {n}");
        }
    }
}
