//! What a plot is ([`Plot`]: axes and [`Series`] in a [`LineStyle`]) and where its
//! parts go in a pixel rectangle ([`PlotLayout`]): the plot area, the axis maps and
//! ticks, and the sizes of text and lines, which follow the rectangle's area. The
//! drawing is [`super::plot`]'s (frame, grid, labels) and [`super::plot_series`]'s
//! (curves, legend); both read this and neither reads the other's.

use super::axis::{Axis, AxisMap, AxisTick};
use super::text::{text_metrics, text_width};
use glam::DVec2;
use tiny_skia::{Color, Paint, Pixmap, Rect, Transform};

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineStyle {
    Solid,
    Dashed,
    Dotted,
    Markers,
    LineAndMarkers,
}

/// One curve of a plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry ("" for none).
    pub label: String,
    /// sRGB colour.
    pub color: [u8; 3],
    pub points: Vec<(f64, f64)>,
    pub style: LineStyle,
}

impl Series {
    /// A solid line.
    pub fn new(label: &str, color: [u8; 3], points: Vec<(f64, f64)>) -> Self {
        Series {
            label: label.to_string(),
            color,
            points,
            style: LineStyle::Solid,
        }
    }

    pub fn with_style(mut self, style: LineStyle) -> Self {
        self.style = style;
        self
    }
}

/// A plot; `width` × `height` is the size [`draw_plot`] gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Plot {
    pub title: Option<String>,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Series>,
    pub width: u32,
    pub height: u32,
    pub legend: bool,
}

impl Plot {
    /// A 640 × 400 plot with a legend and no title or series.
    pub fn new(x: Axis, y: Axis) -> Self {
        Plot {
            title: None,
            x,
            y,
            series: Vec::new(),
            width: 640,
            height: 400,
            legend: true,
        }
    }
}

pub(crate) const WHITE: [u8; 4] = [255, 255, 255, 255];
pub(crate) const TEXT: [u8; 4] = [25, 25, 25, 255];
pub(crate) const FRAME: [u8; 4] = [70, 70, 70, 255];
pub(crate) const GRID_MAJOR: [u8; 4] = [222, 222, 222, 255];
pub(crate) const GRID_MINOR: [u8; 4] = [240, 240, 240, 255];
pub(crate) const ZERO_LINE: [u8; 4] = [150, 150, 150, 255];

/// Where a plot's parts go in its rectangle.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotLayout {
    /// The whole rectangle (x, y, width, height).
    pub rect: (f32, f32, f32, f32),
    /// The plot area (x, y, width, height), whole pixels: where the data are drawn.
    pub area: (f32, f32, f32, f32),
    pub x: AxisMap,
    pub y: AxisMap,
    pub x_ticks: Vec<AxisTick>,
    pub y_ticks: Vec<AxisTick>,
    /// Size of tick labels, axis labels and legend text.
    pub font_px: f32,
}

pub(crate) struct Sizes {
    pub font: f32,
    pub title: f32,
    pub tick: f32,
    pub gap: f32,
    pub line_h: f32,
}

pub(crate) fn sizes(rect: (f32, f32, f32, f32)) -> Sizes {
    let font = (12.0 * (rect.2 * rect.3).max(1.0).sqrt() / 506.0)
        .round()
        .clamp(11.0, 28.0);
    let m = text_metrics(font);
    Sizes {
        font,
        title: (1.2 * font).round(),
        tick: (0.4 * font).round().max(3.0),
        gap: (0.35 * font).round().max(2.0),
        line_h: (m.ascent + m.descent).ceil(),
    }
}

fn label_width(ticks: &[AxisTick], font: f32) -> f32 {
    ticks
        .iter()
        .filter_map(|t| t.label.as_deref())
        .map(|l| text_width(l, font))
        .fold(0.0, f32::max)
        .ceil()
}

impl PlotLayout {
    /// The layout of `p` in `rect` = (x, y, width, height).
    pub fn new(rect: (f32, f32, f32, f32), p: &Plot) -> Self {
        Self::with_left(rect, p, 0.0)
    }

    /// The left margin (rectangle edge to plot area) that `p` needs in `rect`.
    pub fn natural_left(rect: (f32, f32, f32, f32), p: &Plot) -> f32 {
        let l = Self::new(rect, p);
        l.area.0 - rect.0
    }

    /// As [`PlotLayout::new`], with a left margin of at least `min_left` pixels (to
    /// align the plot areas of stacked plots).
    pub fn with_left(rect: (f32, f32, f32, f32), p: &Plot, min_left: f32) -> Self {
        let s = sizes(rect);
        let (rx, ry, rw, rh) = rect;
        let top = match &p.title {
            Some(t) if !t.trim().is_empty() => (2.0 * s.title).round(),
            _ => (0.8 * s.font).round(),
        };
        let x_label_h = if p.x.label.is_empty() { 0.0 } else { s.gap + s.line_h };
        let bottom = s.tick + s.gap + s.line_h + x_label_h + s.gap;
        let area_y = (ry + top).round();
        let area_h = (ry + rh - bottom).round() - area_y;

        let all = || p.series.iter().flat_map(|s| s.points.iter().copied());
        let (x_lo, x_hi) = p.x.resolve(all().map(|q| q.0));
        let x_probe = AxisMap {
            lo: x_lo,
            hi: x_hi,
            scale: p.x.scale,
            p0: 0.0,
            p1: 1.0,
        };
        let (y_lo, y_hi) = p.y.resolve(all().filter(|q| x_probe.contains(q.0)).map(|q| q.1));
        let y_ticks = super::axis::axis_ticks(y_lo, y_hi, p.y.scale, ((area_h / (2.8 * s.font)) as usize).clamp(2, 10));
        let y_label_w = if p.y.label.is_empty() { 0.0 } else { s.line_h + s.gap };
        let left = (s.gap + y_label_w + label_width(&y_ticks, s.font) + s.gap + s.tick).max(min_left);
        let right = (1.6 * s.font).round();
        let area_x = (rx + left).round();
        let area_w = ((rx + rw - right).round() - area_x).max(1.0);

        // As many x labels as fit with a gap of two ems between them.
        let mut n = ((area_w / (4.0 * s.font)) as usize).clamp(2, 12);
        let mut x_ticks = super::axis::axis_ticks(x_lo, x_hi, p.x.scale, n);
        while n > 2 {
            let labels = x_ticks.iter().filter(|t| t.label.is_some()).count() as f32;
            if labels * (label_width(&x_ticks, s.font) + 2.0 * s.font) <= area_w {
                break;
            }
            n -= 1;
            x_ticks = super::axis::axis_ticks(x_lo, x_hi, p.x.scale, n);
        }
        let area = (area_x, area_y, area_w, area_h.max(1.0));
        PlotLayout {
            rect,
            area,
            x: AxisMap {
                lo: x_lo,
                hi: x_hi,
                scale: p.x.scale,
                p0: area.0 as f64,
                p1: (area.0 + area.2) as f64,
            },
            y: AxisMap {
                lo: y_lo,
                hi: y_hi,
                scale: p.y.scale,
                p0: (area.1 + area.3) as f64,
                p1: area.1 as f64,
            },
            x_ticks,
            y_ticks,
            font_px: s.font,
        }
    }

    /// Pixel position of a data point; None if it cannot be shown.
    pub fn to_pixel(&self, x: f64, y: f64) -> Option<DVec2> {
        let q = DVec2::new(self.x.to_pixel(x)?, self.y.to_pixel(y)?);
        q.is_finite().then_some(q)
    }
}

pub(crate) fn fill_rect(pixmap: &mut Pixmap, x: f32, y: f32, w: f32, h: f32, c: [u8; 4]) {
    if let Some(r) = Rect::from_xywh(x, y, w, h) {
        let mut paint = Paint::default();
        paint.set_color(Color::from_rgba8(c[0], c[1], c[2], c[3]));
        paint.anti_alias = false;
        pixmap.fill_rect(r, &paint, Transform::identity(), None);
    }
}
