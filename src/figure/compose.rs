//! Several finished figures composed into one: rows of panels, each with an
//! optional caption above and below (e.g. `volcache figure compare`: reference |
//! ours | jarosz08 fields on the first row, their cache distributions and error
//! maps below, the numbers in the captions).
//!
//! Layout, on white (field figures and plots already sit on white margins, so
//! neither looks boxed in):
//! - column k is as wide as the widest panel or caption line in column k of any
//!   row; columns are separated by an even gap, rows likewise;
//! - a row is a band for captions above, one for panels and one for captions
//!   below, each as tall as the row's tallest; a panel smaller than its cell is
//!   centred in it, its captions just above and below it, centred on the column
//!   and split into lines at '\n';
//! - the title is centred on top; text sizes follow the largest panel (14 px
//!   captions for panels up to ~560 px).
//!
//! Panels are copied pixel for pixel (whole-pixel positions, source-over onto the
//! white background), so the result is deterministic to the byte.

use super::text::{HAlign, VAlign, draw_text_aligned, text_metrics, text_width};
use tiny_skia::{Color, Pixmap, PixmapPaint, Transform};

/// One cell of a grid: caption above, panel, caption below.
pub type Cell = (Option<String>, Pixmap, Option<String>);

const TEXT: [u8; 4] = [20, 20, 20, 255];
const CAPTION: [u8; 4] = [20, 20, 20, 255];
const DETAIL: [u8; 4] = [80, 80, 80, 255];

fn lines(caption: &Option<String>) -> Vec<&str> {
    match caption {
        Some(c) if !c.trim().is_empty() => c.split('\n').collect(),
        _ => Vec::new(),
    }
}

/// Sizes derived from the largest panel.
struct Sizes {
    caption: f32,
    title: f32,
    line_h: f32,
    gap: f32,
    margin: f32,
    pad: f32,
}

fn sizes(largest: f32) -> Sizes {
    let s = (largest / 560.0).clamp(1.0, 2.5);
    let caption = (14.0 * s).round();
    let m = text_metrics(caption);
    Sizes {
        caption,
        title: (18.0 * s).round(),
        line_h: (1.15 * (m.ascent + m.descent)).ceil(),
        gap: (16.0 * s).round(),
        margin: (16.0 * s).round(),
        pad: (0.35 * caption).round(),
    }
}

/// Rows of panels with captions under an optional title; see the module
/// documentation. An empty grid gives a figure with only the title (or a small
/// white square).
pub fn compose_grid(cells: &[Vec<Cell>], title: Option<&str>) -> Pixmap {
    let largest = cells
        .iter()
        .flatten()
        .map(|(_, p, _)| p.width().max(p.height()) as f32)
        .fold(0.0, f32::max);
    let sz = sizes(largest);
    let title = title.filter(|t| !t.trim().is_empty());

    let columns = cells.iter().map(Vec::len).max().unwrap_or(0);
    let mut col_w = vec![0.0f32; columns];
    for row in cells {
        for (k, (above, p, below)) in row.iter().enumerate() {
            let text_w = lines(above)
                .iter()
                .chain(lines(below).iter())
                .map(|l| text_width(l, sz.caption).ceil())
                .fold(0.0, f32::max);
            col_w[k] = col_w[k].max(p.width() as f32).max(text_w);
        }
    }
    // Per row: lines above, panel band height, lines below.
    let bands: Vec<(usize, f32, usize)> = cells
        .iter()
        .map(|row| {
            let above = row.iter().map(|c| lines(&c.0).len()).max().unwrap_or(0);
            let panel = row.iter().map(|c| c.1.height() as f32).fold(0.0, f32::max);
            let below = row.iter().map(|c| lines(&c.2).len()).max().unwrap_or(0);
            (above, panel, below)
        })
        .collect();
    let text_band = |n: usize| {
        if n == 0 { 0.0 } else { n as f32 * sz.line_h + sz.pad }
    };
    let row_h = |b: &(usize, f32, usize)| text_band(b.0) + b.1 + text_band(b.2);

    let top = if title.is_some() {
        (2.4 * sz.title).round()
    } else {
        sz.margin
    };
    let grid_w = col_w.iter().sum::<f32>() + sz.gap * columns.saturating_sub(1) as f32;
    let grid_h = bands.iter().map(row_h).sum::<f32>() + sz.gap * bands.len().saturating_sub(1) as f32;
    let title_w = title.map_or(0.0, |t| text_width(t, sz.title).ceil());
    let width = (2.0 * sz.margin + grid_w.max(title_w)).max(2.0 * sz.margin).ceil();
    let height = (top + grid_h + sz.margin).ceil();
    let mut pixmap = Pixmap::new(width as u32, height as u32).expect("figure size");
    pixmap.fill(Color::WHITE);

    if let Some(t) = title {
        draw_text_aligned(
            &mut pixmap,
            t,
            0.5 * width,
            0.55 * top,
            sz.title,
            TEXT,
            HAlign::Center,
            VAlign::Middle,
        );
    }
    // Centre the grid when the title is wider.
    let x_start = ((width - grid_w) / 2.0).floor();
    let mut y = top;
    for (row, band) in cells.iter().zip(&bands) {
        let panel_y = y + text_band(band.0);
        let mut x = x_start;
        for (k, (above, p, below)) in row.iter().enumerate() {
            let cx = x + 0.5 * col_w[k];
            let px = (cx - 0.5 * p.width() as f32).round() as i32;
            let py = (panel_y + 0.5 * (band.1 - p.height() as f32)).round() as i32;
            pixmap.draw_pixmap(px, py, p.as_ref(), &PixmapPaint::default(), Transform::identity(), None);
            // Captions hug their panel: lines above end just over it, lines below
            // start just under it.
            let above = lines(above);
            let first = py as f32 - sz.pad - above.len() as f32 * sz.line_h;
            for (i, l) in above.iter().enumerate() {
                caption_line(&mut pixmap, l, cx, first + i as f32 * sz.line_h, i == 0, &sz);
            }
            let below_y = (py + p.height() as i32) as f32 + sz.pad;
            for (i, l) in lines(below).iter().enumerate() {
                caption_line(&mut pixmap, l, cx, below_y + i as f32 * sz.line_h, i == 0, &sz);
            }
            x += col_w[k] + sz.gap;
        }
        y += row_h(band) + sz.gap;
    }
    pixmap
}

/// One caption line centred on cx with its ascent line at y; the first line of a
/// caption in the caption colour, the others (numbers) a lighter grey.
fn caption_line(pixmap: &mut Pixmap, text: &str, cx: f32, y: f32, first: bool, sz: &Sizes) {
    draw_text_aligned(
        pixmap,
        text,
        cx,
        y,
        sz.caption,
        if first { CAPTION } else { DETAIL },
        HAlign::Center,
        VAlign::Top,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solid(w: u32, h: u32, c: [u8; 3]) -> Pixmap {
        let mut p = Pixmap::new(w, h).unwrap();
        p.fill(Color::from_rgba8(c[0], c[1], c[2], 255));
        p
    }

    fn rgb(p: &Pixmap, x: u32, y: u32) -> [u8; 3] {
        let c = p.pixel(x, y).unwrap();
        [c.red(), c.green(), c.blue()]
    }

    /// Bounding box of the pixels of colour c.
    fn bbox(p: &Pixmap, c: [u8; 3]) -> (u32, u32, u32, u32) {
        let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
        for y in 0..p.height() {
            for x in 0..p.width() {
                if rgb(p, x, y) == c {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
            }
        }
        (x0, y0, x1 + 1 - x0, y1 + 1 - y0)
    }

    #[test]
    fn grid_has_the_expected_size_and_places_panels() {
        let (red, green, blue) = ([200, 0, 0], [0, 160, 0], [0, 0, 200]);
        let cells = vec![
            vec![(None, solid(100, 80, red), None), (None, solid(60, 40, green), None)],
            vec![(None, solid(50, 50, blue), None)],
        ];
        let p = compose_grid(&cells, None);
        // Margins 16, gaps 16: columns 100 and 60, rows 80 and 50.
        assert_eq!(
            (p.width(), p.height()),
            (16 + 100 + 16 + 60 + 16, 16 + 80 + 16 + 50 + 16)
        );
        assert_eq!(bbox(&p, red), (16, 16, 100, 80));
        // The small green panel is centred in its 60 × 80 cell.
        assert_eq!(bbox(&p, green), (132, 36, 60, 40));
        // The blue one is centred in the first column (100 wide).
        assert_eq!(bbox(&p, blue), (41, 112, 50, 50));
        assert_eq!(rgb(&p, 0, 0), [255; 3]);
    }

    #[test]
    fn captions_and_title_add_bands_and_ink() {
        let cells = vec![vec![
            (Some("reference".to_string()), solid(120, 100, [0, 0, 0]), None),
            (
                Some("ours".to_string()),
                solid(120, 100, [0, 0, 0]),
                Some("1200 records\nRMSE 3.1×10⁻³".to_string()),
            ),
        ]];
        let p = compose_grid(&cells, Some("windows.json at 1200 records"));
        let q = compose_grid(&cells, Some("windows.json at 1200 records"));
        assert_eq!(p.data(), q.data(), "deterministic");
        let plain = compose_grid(&[vec![(None, solid(120, 100, [0, 0, 0]), None)]], None);
        assert!(
            p.height() > plain.height() + 3 * 18,
            "{} vs {}",
            p.height(),
            plain.height()
        );
        // Both panels start on the same row, below the title and the captions.
        let (_, y0, _, h) = bbox(&p, [0, 0, 0]);
        assert_eq!(h, 100);
        let dark = |y: std::ops::Range<u32>, x: std::ops::Range<u32>| {
            y.flat_map(|y| x.clone().map(move |x| (x, y)))
                .filter(|&(x, y)| rgb(&p, x, y)[0] < 128)
                .count()
        };
        assert!(dark(0..y0, 0..p.width()) > 100, "title and captions above");
        assert!(dark(y0 + 100..p.height(), 0..p.width()) > 100, "captions below");
        // A caption line wider than its panel widens the column.
        let wide = compose_grid(
            &[vec![(
                None,
                solid(20, 20, [0, 0, 0]),
                Some("a caption far wider than twenty pixels".into()),
            )]],
            None,
        );
        assert!(wide.width() > 200);
    }

    #[test]
    fn empty_grids_and_translucent_panels() {
        let p = compose_grid(&[], None);
        assert!(p.width() > 0 && p.height() > 0);
        let t = compose_grid(&[vec![]], Some("title only"));
        assert!(t.width() > text_width("title only", 18.0) as u32);
        // A transparent panel shows the white background.
        let c = compose_grid(&[vec![(None, Pixmap::new(10, 10).unwrap(), None)]], None);
        assert!(c.pixels().iter().all(|px| px.red() == 255 && px.alpha() == 255));
    }

    /// With `VOLCACHE_FIGURE_OUT=dir`, writes `compose_example.png` there: the
    /// layout of `volcache figure compare` on synthetic data (fields, cache
    /// distributions, error maps on a shared range, and a plot).
    #[test]
    fn example_compose() {
        use super::super::error_map::{error_map_figure, shared_error_range};
        use super::super::field_figure::{FieldStyle, field_figure};
        use super::super::gradient_figure::{AWARE_PURPLE, REFERENCE_BLUE, UNAWARE_ORANGE};
        use super::super::plot::{Axis, LineStyle, Plot, Series, draw_plot};
        use super::super::records::{RecordColor, RecordStyle, records_figure};
        use super::super::synthetic::{example_scene, shadow_field, synthetic_records};
        use crate::flatland::field::field_errors;

        let scene = example_scene();
        let reference = shadow_field(128, 128, 0.4, 0.01);
        let ours = shadow_field(128, 128, 0.4, 0.03);
        let jarosz = shadow_field(128, 128, 0.37, 0.12);
        let style = FieldStyle::FalseColor { log: true, range: None };
        let range = shared_error_range(&[(&ours, &reference), (&jarosz, &reference)], false);
        let rec_style = RecordStyle::colored(RecordColor::ByRadius);
        let (rec_ours, rec_jarosz) = (synthetic_records(&scene, true), synthetic_records(&scene, false));
        let rec_range = {
            let all: Vec<_> = rec_ours.iter().chain(&rec_jarosz).cloned().collect();
            let s =
                super::super::colorbar::ColorScale::auto(all.iter().filter_map(|r| rec_style.color.attribute(r)), true);
            Some((s.min, s.max))
        };
        let rec_style = RecordStyle {
            range: rec_range,
            ..rec_style
        };
        let numbers = |f: &crate::flatland::field::Field, n: usize, secs: f64| {
            let e = field_errors(f, &reference);
            format!(
                "{n} records · 2.4×10⁶ rays · {secs:.1} s\nRMSE {}",
                super::super::colorbar::short_sci(e.rmse)
            )
        };
        let times: Vec<f64> = (0..10).map(|k| 0.5 * 1.7f64.powi(k)).collect();
        let curve = |c: f64, slope: f64| times.iter().map(|&t| (t, c * t.powf(-slope))).collect();
        let mut plot = Plot::new(Axis::log10("time (s)"), Axis::log10("RMSE"));
        plot.series = vec![
            Series::new("pt", REFERENCE_BLUE, curve(0.3, 0.5)).with_style(LineStyle::Dashed),
            Series::new("jarosz08", UNAWARE_ORANGE, curve(0.05, 0.3)),
            Series::new("ours", AWARE_PURPLE, curve(0.02, 0.4)),
        ];
        (plot.width, plot.height) = (560, 420);
        let cells = vec![
            vec![
                (
                    Some("reference".to_string()),
                    field_figure(&reference, Some(&scene), &style, None),
                    Some("path traced, 4096 spp".to_string()),
                ),
                (
                    Some("ours".to_string()),
                    field_figure(&ours, Some(&scene), &style, None),
                    Some(numbers(&ours, rec_ours.len(), 1.2)),
                ),
                (
                    Some("jarosz08".to_string()),
                    field_figure(&jarosz, Some(&scene), &style, None),
                    Some(numbers(&jarosz, rec_jarosz.len(), 0.9)),
                ),
            ],
            vec![
                (Some("error vs time".to_string()), draw_plot(&plot), None),
                (
                    None,
                    records_figure(None, &scene, &rec_ours, &rec_style, Some("ours")),
                    None,
                ),
                (
                    None,
                    records_figure(None, &scene, &rec_jarosz, &rec_style, Some("jarosz08")),
                    None,
                ),
            ],
            vec![
                (None, Pixmap::new(1, 1).unwrap(), None),
                (
                    None,
                    error_map_figure(
                        &ours,
                        &reference,
                        Some(&scene),
                        Some(range),
                        false,
                        Some("ours: |error|"),
                    ),
                    None,
                ),
                (
                    None,
                    error_map_figure(
                        &jarosz,
                        &reference,
                        Some(&scene),
                        Some(range),
                        false,
                        Some("jarosz08: |error|"),
                    ),
                    None,
                ),
            ],
        ];
        let p = compose_grid(
            &cells,
            Some("occluder: reference, ours and jarosz08 at equal cache count"),
        );
        assert_eq!(
            p.data(),
            compose_grid(
                &cells,
                Some("occluder: reference, ours and jarosz08 at equal cache count")
            )
            .data()
        );
        if let Some(dir) = std::env::var_os("VOLCACHE_FIGURE_OUT") {
            let path = std::path::Path::new(&dir).join("compose_example.png");
            crate::output::write_png(&path, &p).unwrap();
        }
    }
}
