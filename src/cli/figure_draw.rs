//! Drawing for `volcache figure gradients`: the gradient panels (through
//! [`volcache::figure::gradient_figure`]) and the profiles along the line, each with a
//! word-wrapped footer saying how the numbers were made.

use glam::DVec2;
use tiny_skia::{Color, Pixmap, PixmapPaint, Transform};
use volcache::figure::{
    AWARE_PURPLE, Axis, Canvas, GradientSample, GradientStyle, HAlign, LineStyle, Plot, REFERENCE_BLUE, Series,
    UNAWARE_ORANGE, VAlign, View, draw_plots_stacked, draw_text_aligned, gradient_figure, text_width,
};
use volcache::flatland::scene::Scene;
use volcache::study::gradients::{METHODS, PointOut};

/// A figure's title and footer lines (each wrapped to the figure's width).
pub struct FigureText {
    pub title: String,
    pub footer: Vec<String>,
}

const TEXT: [u8; 4] = [20, 20, 20, 255];
const FOOTER: [u8; 4] = [70, 70, 70, 255];
const FOOTER_PX: f32 = 12.0;
const MARGIN: f32 = 16.0;

/// The luminance gradients of `method` for `part` at the points inside the medium.
pub fn samples(points: &[PointOut], method: &str, part: &str) -> Vec<GradientSample> {
    points
        .iter()
        .filter_map(|p| {
            let m = p.method(method)?;
            Some(GradientSample {
                at: DVec2::from_array(p.at),
                grad: m.part(part).grad(),
            })
        })
        .collect()
}

/// Greedy word wrap of `text` to `width` pixels at `size` px.
fn wrap(text: &str, width: f32, size: f32) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    for word in text.split(' ').filter(|w| !w.is_empty()) {
        let candidate = if cur.is_empty() {
            word.to_string()
        } else {
            format!("{cur} {word}")
        };
        if !cur.is_empty() && text_width(&candidate, size) > width {
            lines.push(std::mem::replace(&mut cur, word.to_string()));
        } else {
            cur = candidate;
        }
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

/// `img` with the footer lines wrapped below it, on white.
fn with_footer(img: &Pixmap, footer: &[String]) -> Pixmap {
    let width = img.width() as f32;
    let lines: Vec<String> = footer
        .iter()
        .flat_map(|l| wrap(l, width - 2.0 * MARGIN, FOOTER_PX))
        .collect();
    let line_h = (1.4 * FOOTER_PX).round();
    let extra = if lines.is_empty() {
        0.0
    } else {
        line_h * lines.len() as f32 + MARGIN
    };
    let mut out = Pixmap::new(img.width(), img.height() + extra as u32).expect("figure size");
    out.fill(Color::WHITE);
    out.draw_pixmap(0, 0, img.as_ref(), &PixmapPaint::default(), Transform::identity(), None);
    for (i, l) in lines.iter().enumerate() {
        draw_text_aligned(
            &mut out,
            l,
            MARGIN,
            img.height() as f32 + i as f32 * line_h,
            FOOTER_PX,
            FOOTER,
            HAlign::Left,
            VAlign::Top,
        );
    }
    out
}

/// The three methods' panels side by side (shared magnitude range, colour wheel),
/// the scene and the sampling line on each, title on top and footer below.
pub fn gradient_grid_figure(
    panels: &[(String, Vec<GradientSample>)],
    scene: &Scene,
    line: (DVec2, DVec2),
    style: GradientStyle,
    text: &FigureText,
) -> Pixmap {
    let img = gradient_figure(panels, scene, Some(line), style, Some(&text.title));
    with_footer(&img, &text.footer)
}

/// The gradient of `part` along the line: |∇L|, ∂L/∂x and ∂L/∂y stacked over s, per
/// method in the paper's colours (reference blue, unaware orange, aware purple),
/// with the reference's ±1σ noise estimate dotted; the legend is a row under the
/// title (so that it hides no data).
pub fn profile_figure(points: &[PointOut], part: &str, x_label: &str, text: &FigureText) -> Pixmap {
    let (width, plot_h, title_px) = (900.0f32, 250.0f32, 17.0f32);
    let colors = [AWARE_PURPLE, UNAWARE_ORANGE, REFERENCE_BLUE];
    let light_blue = [140, 185, 225];
    let get = |p: &PointOut, key: &str| p.method(key).map_or(DVec2::NAN, |m| m.part(part).grad());
    // Per-component 1σ of the reference: the vector RMS over √2.
    let sigma = |p: &PointOut| {
        p.reference_gradient_noise
            .map_or(f64::NAN, |n| n.part(part) / std::f64::consts::SQRT_2)
    };
    let s_of = |p: &PointOut| p.s.unwrap_or(f64::NAN);
    let plot = |y: &str, x: &str, f: fn(DVec2) -> f64| {
        let mut series = Vec::new();
        // The noise band first (under the curves), then reference, unaware, aware.
        for sign in [1.0, -1.0] {
            let pts = points
                .iter()
                .map(|p| (s_of(p), f(get(p, "reference")) + sign * sigma(p)))
                .collect();
            let label = if sign > 0.0 {
                "reference ± 1σ (noise estimate)"
            } else {
                ""
            };
            series.push(Series::new(label, light_blue, pts).with_style(LineStyle::Dotted));
        }
        for m in (0..3).rev() {
            let (key, caption) = METHODS[m];
            let pts = points.iter().map(|p| (s_of(p), f(get(p, key)))).collect();
            series.push(Series::new(caption, colors[m], pts).with_style(LineStyle::LineAndMarkers));
        }
        Plot {
            title: None,
            x: Axis::linear(x).with_range(0.0, 1.0),
            y: Axis::linear(y),
            series,
            width: width as u32,
            height: plot_h as u32,
            legend: false,
        }
    };
    let mut plots = [
        plot("|∇L|", "", |g| g.length()),
        plot("∂L/∂x", "", |g| g.x),
        plot("∂L/∂y", x_label, |g| g.y),
    ];
    // Magnitudes from 0, so that their ratios read off the plot.
    let top = plots[0]
        .series
        .iter()
        .flat_map(|s| &s.points)
        .map(|p| p.1)
        .filter(|m| m.is_finite())
        .fold(0.0, f64::max);
    if top > 0.0 {
        plots[0].y.range = Some((0.0, 1.05 * top));
    }
    let (title_h, legend_h) = ((2.2 * title_px).round(), 26.0f32);
    let mut img = Pixmap::new(width as u32, (title_h + legend_h + 3.0 * plot_h) as u32).expect("plot size");
    img.fill(Color::WHITE);
    let size = (title_px * ((width - 24.0) / text_width(&text.title, title_px)).min(1.0)).max(6.0);
    draw_text_aligned(
        &mut img,
        &text.title,
        0.5 * width,
        0.55 * title_h,
        size,
        TEXT,
        HAlign::Center,
        VAlign::Middle,
    );
    let entries: Vec<&Series> = plots[0].series.iter().filter(|s| !s.label.is_empty()).collect();
    draw_legend_row(&mut img, &entries, 0.5 * width, title_h + 0.5 * legend_h);
    draw_plots_stacked(
        &mut img,
        (0.0, title_h + legend_h, width, 3.0 * plot_h),
        &plots.iter().collect::<Vec<_>>(),
    );
    with_footer(&img, &text.footer)
}

/// A one-row legend centred at (cx, cy): per series a line sample (with a marker if
/// the series has them) and its label, in the plots' line widths.
fn draw_legend_row(img: &mut Pixmap, entries: &[&Series], cx: f32, cy: f32) {
    const FONT: f32 = 12.0;
    let (sample, gap_in, gap_between, width) = (30.0f32, 6.0f32, 22.0f32, 1.8f32);
    let widths: Vec<f32> = entries
        .iter()
        .map(|s| sample + gap_in + text_width(&s.label, FONT))
        .collect();
    let total = widths.iter().sum::<f32>() + gap_between * (entries.len().saturating_sub(1)) as f32;
    let mut x = (cx - 0.5 * total).round();
    for (s, w) in entries.iter().zip(&widths) {
        let color = [s.color[0], s.color[1], s.color[2], 255];
        let (a, b) = (
            DVec2::new(x as f64, cy as f64),
            DVec2::new((x + sample) as f64, cy as f64),
        );
        {
            let (iw, ih) = (img.width() as f32, img.height() as f32);
            let view = View::new(DVec2::ZERO, DVec2::ONE, 0.0, 0.0, iw, ih);
            let mut canvas = Canvas::new(img, &view, 0.0);
            let dash = (s.style == LineStyle::Dotted).then_some((width, 1.6 * width));
            canvas.polyline(&[a, b], false, width, color, dash);
            if s.style == LineStyle::LineAndMarkers {
                let c = 0.5 * (a + b);
                canvas.disc(c, 3.6, [255, 255, 255, 255]);
                canvas.disc(c, 2.7, color);
            }
        }
        draw_text_aligned(
            img,
            &s.label,
            x + sample + gap_in,
            cy,
            FONT,
            TEXT,
            HAlign::Left,
            VAlign::Middle,
        );
        x += w + gap_between;
    }
}
