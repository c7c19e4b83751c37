//! Line plots: series of (x, y) points on linear or logarithmic axes, for the paper's
//! gradient profiles and for error-vs-time and error-vs-cache-count curves.
//!
//! A [`Plot`] is drawn on white into a pixel rectangle ([`draw_plot_into`], for
//! multi-panel figures) or into its own pixmap ([`draw_plot`]). Layout: the title
//! centred on top, the y label written vertically on the left, tick labels outside a
//! framed plot area, light grid lines at the ticks (lighter at minor ticks), a grey
//! zero line on a linear axis whose range spans 0, and the legend in the corner of
//! the plot area that hides the least of the curves. Text and line sizes follow the
//! rectangle's area (12 px labels for 640 × 400, at least 11 px).
//!
//! Series are anti-aliased and clipped to the plot area. A point that cannot be shown
//! (NaN or ±∞, or ≤ 0 on a log axis) breaks the line there. Ranges and ticks: see
//! [`super::axis`]; an automatic y range only considers points within the x range.
//! [`draw_plots_stacked`] stacks plots with aligned plot areas (a shared x axis).

pub use super::axis::{Axis, AxisMap, AxisTick, Scale};
use super::panel::{Canvas, View};
use super::plot_layout::{FRAME, GRID_MAJOR, GRID_MINOR, TEXT, WHITE, ZERO_LINE, fill_rect, sizes};
pub use super::plot_layout::{LineStyle, Plot, PlotLayout, Series};
use super::plot_series::{draw_legend, draw_series};
use super::text::{HAlign, VAlign, draw_text_aligned, draw_text_vertical, text_width};
use glam::DVec2;
use tiny_skia::Pixmap;

/// Draw `p` in its own `width` × `height` pixmap.
pub fn draw_plot(p: &Plot) -> Pixmap {
    let mut pixmap = Pixmap::new(p.width.max(1), p.height.max(1)).expect("non-zero size");
    draw_plot_into(&mut pixmap, (0.0, 0.0, p.width as f32, p.height as f32), p);
    pixmap
}

/// Draw `p` into the rectangle (x, y, width, height) of `pixmap`, on white.
pub fn draw_plot_into(pixmap: &mut Pixmap, rect: (f32, f32, f32, f32), p: &Plot) {
    let layout = PlotLayout::new(rect, p);
    draw_plot_with_layout(pixmap, &layout, p);
}

/// Draw plots one above the other in `rect`, equal heights, plot areas aligned.
pub fn draw_plots_stacked(pixmap: &mut Pixmap, rect: (f32, f32, f32, f32), plots: &[&Plot]) {
    let n = plots.len().max(1) as f32;
    let sub = |k: usize| {
        let (y0, y1) = (rect.1 + rect.3 * k as f32 / n, rect.1 + rect.3 * (k + 1) as f32 / n);
        (rect.0, y0.round(), rect.2, y1.round() - y0.round())
    };
    let left = plots
        .iter()
        .enumerate()
        .map(|(k, p)| PlotLayout::natural_left(sub(k), p))
        .fold(0.0, f32::max);
    for (k, p) in plots.iter().enumerate() {
        draw_plot_with_layout(pixmap, &PlotLayout::with_left(sub(k), p, left), p);
    }
}

/// Draw `p` with a given layout.
pub fn draw_plot_with_layout(pixmap: &mut Pixmap, l: &PlotLayout, p: &Plot) {
    let s = sizes(l.rect);
    let (ax, ay, aw, ah) = l.area;
    fill_rect(pixmap, l.rect.0, l.rect.1, l.rect.2, l.rect.3, WHITE);

    // Grid (minor first), then zero lines; one-pixel lines on whole pixels.
    let column = |v: f64| l.x.to_pixel(v).map(|x| (x as f32).floor().clamp(ax, ax + aw - 1.0));
    let row = |v: f64| l.y.to_pixel(v).map(|y| (y as f32).floor().clamp(ay, ay + ah - 1.0));
    for major in [false, true] {
        let c = if major { GRID_MAJOR } else { GRID_MINOR };
        for t in l.x_ticks.iter().filter(|t| t.label.is_some() == major) {
            if let Some(x) = column(t.value) {
                fill_rect(pixmap, x, ay, 1.0, ah, c);
            }
        }
        for t in l.y_ticks.iter().filter(|t| t.label.is_some() == major) {
            if let Some(y) = row(t.value) {
                fill_rect(pixmap, ax, y, aw, 1.0, c);
            }
        }
    }
    if p.x.scale == Scale::Linear
        && l.x.lo < 0.0
        && l.x.hi > 0.0
        && let Some(x) = column(0.0)
    {
        fill_rect(pixmap, x, ay, 1.0, ah, ZERO_LINE);
    }
    if p.y.scale == Scale::Linear
        && l.y.lo < 0.0
        && l.y.hi > 0.0
        && let Some(y) = row(0.0)
    {
        fill_rect(pixmap, ax, y, aw, 1.0, ZERO_LINE);
    }

    let u = s.font / 12.0;
    let area_view = View::new(DVec2::ZERO, DVec2::ONE, ax, ay, aw, ah);
    {
        let mut canvas = Canvas::new(pixmap, &area_view, 8.0 * u as f64);
        for series in &p.series {
            draw_series(&mut canvas, l, series, u);
        }
    }

    // Frame just outside the plot area, ticks outside the frame.
    fill_rect(pixmap, ax - 1.0, ay - 1.0, aw + 2.0, 1.0, FRAME);
    fill_rect(pixmap, ax - 1.0, ay + ah, aw + 2.0, 1.0, FRAME);
    fill_rect(pixmap, ax - 1.0, ay, 1.0, ah, FRAME);
    fill_rect(pixmap, ax + aw, ay, 1.0, ah, FRAME);
    let (rx0, rx1) = (l.rect.0, l.rect.0 + l.rect.2);
    for t in &l.x_ticks {
        let Some(x) = column(t.value) else { continue };
        let len = if t.label.is_some() { s.tick } else { 0.55 * s.tick };
        fill_rect(pixmap, x, ay + ah + 1.0, 1.0, len.round(), FRAME);
        if let Some(text) = &t.label {
            // Keep end labels inside the rectangle.
            let half = 0.5 * text_width(text, s.font);
            let cx = (x + 0.5).clamp(rx0 + half, (rx1 - half).max(rx0 + half));
            let y = ay + ah + 1.0 + s.tick + s.gap;
            draw_text_aligned(pixmap, text, cx, y, s.font, TEXT, HAlign::Center, VAlign::Top);
        }
    }
    for t in &l.y_ticks {
        let Some(y) = row(t.value) else { continue };
        let len = if t.label.is_some() { s.tick } else { 0.55 * s.tick };
        fill_rect(pixmap, ax - 1.0 - len.round(), y, len.round(), 1.0, FRAME);
        if let Some(text) = &t.label {
            let x = ax - 1.0 - s.tick - s.gap;
            draw_text_aligned(pixmap, text, x, y + 0.5, s.font, TEXT, HAlign::Right, VAlign::Middle);
        }
    }
    if !p.x.label.is_empty() {
        let y = ay + ah + 1.0 + s.tick + s.gap + s.line_h + s.gap;
        draw_text_aligned(
            pixmap,
            &p.x.label,
            ax + 0.5 * aw,
            y,
            s.font,
            TEXT,
            HAlign::Center,
            VAlign::Top,
        );
    }
    if !p.y.label.is_empty() {
        let x = l.rect.0 + s.gap;
        draw_text_vertical(
            pixmap,
            &p.y.label,
            x,
            ay + 0.5 * ah,
            s.font,
            TEXT,
            HAlign::Center,
            VAlign::Top,
        );
    }
    if let Some(t) = p.title.as_deref().filter(|t| !t.trim().is_empty()) {
        let size = (s.title * ((l.rect.2 - 2.0 * s.gap) / text_width(t, s.title)).min(1.0)).max(6.0);
        let y = l.rect.1 + s.title;
        draw_text_aligned(pixmap, t, ax + 0.5 * aw, y, size, TEXT, HAlign::Center, VAlign::Middle);
    }
    if p.legend {
        draw_legend(pixmap, l, p, u);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rgb(p: &Pixmap, x: u32, y: u32) -> [u8; 3] {
        let c = p.pixel(x, y).unwrap();
        [c.red(), c.green(), c.blue()]
    }

    /// Pixels within `tol` (per channel) of `color`.
    fn count(p: &Pixmap, color: [u8; 3], tol: u8) -> usize {
        (0..p.height())
            .flat_map(|y| (0..p.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| rgb(p, x, y).iter().zip(color).all(|(&a, b)| a.abs_diff(b) <= tol))
            .count()
    }

    const BLUE: [u8; 3] = [31, 119, 180];
    const ORANGE: [u8; 3] = [255, 127, 14];
    const PURPLE: [u8; 3] = [148, 103, 189];

    fn example() -> Plot {
        let xs: Vec<f64> = (0..=40).map(|i| i as f64 / 40.0).collect();
        let mut p = Plot::new(Axis::linear("s"), Axis::linear("∂L/∂x"));
        p.title = Some("A test plot".into());
        p.series = vec![
            Series::new("reference", BLUE, xs.iter().map(|&x| (x, (6.0 * x).sin())).collect()),
            Series::new(
                "unaware",
                ORANGE,
                xs.iter().map(|&x| (x, 0.8 * (6.0 * x).sin())).collect(),
            )
            .with_style(LineStyle::Dashed),
            Series::new(
                "aware",
                PURPLE,
                xs.iter().map(|&x| (x, (6.0 * x).cos() - 0.5)).collect(),
            )
            .with_style(LineStyle::LineAndMarkers),
        ];
        p
    }

    #[test]
    fn mapping_is_monotone_and_inside_the_area() {
        let mut p = example();
        p.y = Axis::log10("error");
        p.series[0].points = (1..50).map(|i| (i as f64, 1.0 / i as f64)).collect();
        let l = PlotLayout::new((10.0, 20.0, 600.0, 380.0), &p);
        let (ax, ay, aw, ah) = l.area;
        assert!(
            ax > 10.0 && ay > 20.0 && ax + aw < 610.0 && ay + ah < 400.0,
            "{:?}",
            l.area
        );
        let mut prev = DVec2::NEG_INFINITY;
        for &(x, y) in &p.series[0].points {
            let q = l.to_pixel(x, y).unwrap();
            // x grows to the right, y decreases (1/i), so the pixel row grows.
            assert!(q.x > prev.x && q.y > prev.y, "{q} after {prev}");
            assert!(q.x >= ax as f64 && q.x <= (ax + aw) as f64 && q.y >= ay as f64 && q.y <= (ay + ah) as f64);
            prev = q;
        }
        assert_eq!(l.to_pixel(1.0, 0.0), None);
        assert_eq!(l.to_pixel(f64::NAN, 1.0), None);
    }

    #[test]
    fn every_series_leaves_ink_and_output_is_deterministic() {
        let p = example();
        let a = draw_plot(&p);
        assert_eq!((a.width(), a.height()), (640, 400));
        assert_eq!(a.data(), draw_plot(&p).data());
        for c in [BLUE, ORANGE, PURPLE] {
            assert!(count(&a, c, 2) > 40, "{c:?}: {}", count(&a, c, 2));
        }
        // Nothing drawn outside the rectangle when placed in a larger pixmap.
        let mut big = Pixmap::new(900, 500).unwrap();
        draw_plot_into(&mut big, (100.0, 50.0, 640.0, 400.0), &p);
        for y in 0..500 {
            for x in 0..900 {
                if !(100..740).contains(&x) || !(50..450).contains(&y) {
                    assert_eq!(big.pixel(x, y).unwrap().alpha(), 0, "ink at ({x}, {y})");
                }
            }
        }
        assert_eq!(rgb(&big, 100 + 320, 50 + 200), rgb(&a, 320, 200));
    }

    #[test]
    fn non_finite_points_break_lines_without_panicking() {
        let mut p = example();
        p.series[0].points[10].1 = f64::NAN;
        p.series[1].points[5] = (f64::INFINITY, 1.0);
        p.series[2].points[7].1 = f64::NEG_INFINITY;
        p.series.push(Series::new("empty", [0, 0, 0], vec![]));
        p.series
            .push(Series::new("all NaN", [0, 200, 0], vec![(f64::NAN, f64::NAN); 3]));
        p.legend = false;
        let a = draw_plot(&p);
        assert!(count(&a, BLUE, 2) > 40);
        // Log axes with non-positive values, and explicit ranges far from the data.
        p.y = Axis::log10("y");
        draw_plot(&p);
        p.x = Axis::linear("x").with_range(1e6, 2e6);
        p.y = Axis::linear("y").with_range(-1e-300, 1e-300);
        let b = draw_plot(&p);
        assert_eq!(count(&b, BLUE, 2), 0);
    }

    #[test]
    fn zero_line_and_stacked_alignment() {
        let p = example();
        let l = PlotLayout::new((0.0, 0.0, 640.0, 400.0), &p);
        let img = draw_plot(&p);
        let y0 = l.y.to_pixel(0.0).unwrap().floor() as u32;
        // The zero line runs across the area where no series passes (near the right edge).
        assert_eq!(rgb(&img, (l.area.0 + l.area.2) as u32 - 2, y0), ZERO_LINE[..3]);
        let mut q = example();
        q.y = Axis::linear("much longer tick labels").with_range(0.0, 123456.0);
        let mut pix = Pixmap::new(640, 600).unwrap();
        draw_plots_stacked(&mut pix, (0.0, 0.0, 640.0, 600.0), &[&p, &q]);
        let left = PlotLayout::natural_left((0.0, 0.0, 640.0, 300.0), &q);
        assert!(left > PlotLayout::natural_left((0.0, 0.0, 640.0, 300.0), &p));
        // Both frames' left edges are on the same column, just left of the areas.
        let x = left as u32 - 1;
        for y in [100, 150, 200, 400, 450, 500] {
            assert_eq!(rgb(&pix, x, y), FRAME[..3], "row {y}");
            assert_ne!(rgb(&pix, x + 1, y), FRAME[..3], "row {y}");
        }
    }

    /// With `VOLCACHE_FIGURE_OUT=dir`, writes `plot_example.png` there: a log–log
    /// error-vs-time plot beside a linear one, in one pixmap.
    #[test]
    fn example_plot() {
        let times: Vec<f64> = (0..12).map(|k| 0.5 * 1.6f64.powi(k)).collect();
        let curve = |c: f64, slope: f64| times.iter().map(|&t| (t, c * t.powf(-slope))).collect();
        let mut log = Plot::new(Axis::log10("render time (s)"), Axis::log10("relative MSE"));
        log.title = Some("Error vs time".into());
        log.series = vec![
            Series::new("path tracing", BLUE, curve(0.3, 1.0)).with_style(LineStyle::Dashed),
            Series::new("unaware (Jarosz 2008)", ORANGE, curve(0.02, 0.45)).with_style(LineStyle::LineAndMarkers),
            Series::new("aware (ours)", PURPLE, curve(0.006, 0.55)).with_style(LineStyle::LineAndMarkers),
        ];
        let lin = example();
        let mut pix = Pixmap::new(1280, 420).unwrap();
        draw_plot_into(&mut pix, (0.0, 0.0, 640.0, 420.0), &log);
        draw_plot_into(&mut pix, (640.0, 0.0, 640.0, 420.0), &lin);
        for c in [BLUE, ORANGE, PURPLE] {
            assert!(count(&pix, c, 2) > 80, "{c:?}");
        }
        if let Some(dir) = std::env::var_os("VOLCACHE_FIGURE_OUT") {
            crate::output::write_png(&std::path::Path::new(&dir).join("plot_example.png"), &pix).unwrap();
        }
    }
}
