//! Panels of rendered 3D images (handed in as linear RGB pixels, row 0 on top):
//! tone-mapped and enlarged by whole pixels, a zoomed inset with its window outlined
//! on the full image, cache records projected into the image as dots over a dimmed
//! copy, and per-pixel error maps (as `figure::error_map`'s, on a shared range).

use super::colorbar::{ColorScale, colorbar_width, draw_colorbar};
use super::colormap::tonemap;
use super::error_map::error_field;
use super::field_figure::{FieldStyle, FigureOptions, field_figure_with};
use crate::core::color::Rgb;
use crate::flatland::field::Field;
use glam::DVec2;
use tiny_skia::{Color, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

/// A linear RGB image.
#[derive(Clone, Copy, Debug)]
pub struct Image<'a> {
    pub width: usize,
    pub height: usize,
    pub values: &'a [Rgb],
}

impl Image<'_> {
    /// As a field (the error maps' type); its world rectangle is unused.
    pub fn to_field(&self) -> Field {
        let mut f = Field::new(self.width, self.height, DVec2::ZERO, DVec2::ONE);
        f.values.copy_from_slice(self.values);
        f
    }
}

/// Pixels [x0, x1) × [y0, y1) of an image.
pub type Window = [usize; 4];

/// The window of `img` tone-mapped (`exposure` stops), each pixel a `scale`² block,
/// multiplied by `dim` (1 = as is).
fn tonemapped(img: &Image, win: Window, exposure: f64, scale: u32, dim: f64) -> Pixmap {
    let [x0, y0, x1, y1] = win;
    let s = scale.max(1) as usize;
    let (w, h) = ((x1 - x0) * s, (y1 - y0) * s);
    let mut pm = Pixmap::new(w as u32, h as u32).expect("image size");
    let data = pm.data_mut();
    for y in 0..h {
        for x in 0..w {
            let v = img.values[(y0 + y / s) * img.width + x0 + x / s];
            let [r, g, b] = tonemap(v * dim, exposure);
            let k = 4 * (y * w + x);
            data[k..k + 4].copy_from_slice(&[r, g, b, 255]);
        }
    }
    pm
}

/// The whole image, tone-mapped and enlarged `scale` times.
pub fn image_panel(img: &Image, exposure: f64, scale: u32) -> Pixmap {
    tonemapped(img, [0, 0, img.width, img.height], exposure, scale, 1.0)
}

/// The window enlarged `scale` times (a zoomed inset).
pub fn inset_panel(img: &Image, win: Window, exposure: f64, scale: u32) -> Pixmap {
    tonemapped(img, win, exposure, scale, 1.0)
}

/// Outline `win` (image pixels) on a panel drawn at `scale`.
pub fn outline_window(pm: &mut Pixmap, win: Window, scale: u32, color: [u8; 4]) {
    let s = scale as f32;
    let [x0, y0, x1, y1] = win.map(|v| v as f32 * s);
    if let Some(r) = Rect::from_ltrb(x0 + 1.0, y0 + 1.0, x1 - 1.0, y1 - 1.0) {
        let mut paint = Paint::default();
        paint.set_color_rgba8(color[0], color[1], color[2], color[3]);
        paint.anti_alias = true;
        let stroke = Stroke {
            width: 2.0,
            ..Default::default()
        };
        pm.stroke_path(&PathBuilder::from_rect(r), &paint, &stroke, Transform::identity(), None);
    }
}

/// A shared colour scale (log) for record sizes.
pub fn record_size_scale(sizes: impl IntoIterator<Item = f64>) -> ColorScale {
    ColorScale::auto(sizes, true)
}

/// Records as dots at their image positions (pixel units, None: not in view),
/// coloured by size on `scale`, over the image dimmed to a third; a colour bar for
/// the sizes on the right.
pub fn records_panel(
    img: &Image,
    exposure: f64,
    scale: u32,
    dots: &[(Option<DVec2>, f64)],
    sizes: &ColorScale,
    label: &str,
) -> Pixmap {
    let base = tonemapped(img, [0, 0, img.width, img.height], exposure, scale, 0.3);
    let (w, h) = (base.width() as f32, base.height() as f32);
    let font = (h / 28.0).clamp(10.0, 14.0);
    let bar_h = 0.8 * h;
    let extra = 12.0 + colorbar_width(sizes, bar_h, font, label);
    let mut pm = Pixmap::new((w + extra).ceil() as u32, h as u32).expect("panel size");
    pm.fill(Color::WHITE);
    pm.draw_pixmap(
        0,
        0,
        base.as_ref(),
        &tiny_skia::PixmapPaint::default(),
        Transform::identity(),
        None,
    );
    let r = (1.2 + 0.6 * scale as f32).min(4.0);
    for &(pos, size) in dots {
        let Some(p) = pos else { continue };
        let (x, y) = (p.x as f32 * scale as f32, p.y as f32 * scale as f32);
        if !(0.0..w).contains(&x) || !(0.0..h).contains(&y) {
            continue;
        }
        let [cr, cg, cb] = sizes.color(size);
        let mut paint = Paint::default();
        paint.set_color_rgba8(cr, cg, cb, 255);
        paint.anti_alias = true;
        if let Some(c) = PathBuilder::from_circle(x, y, r) {
            pm.fill_path(&c, &paint, tiny_skia::FillRule::Winding, Transform::identity(), None);
        }
    }
    draw_colorbar(&mut pm, sizes, w + 8.0, 0.1 * h, bar_h, font, label);
    pm
}

/// |luminance error| of `test` against `reference` on a shared (log) range, with
/// its colour bar (the error maps of `figure::error_map`).
pub fn error_panel(test: &Image, reference: &Image, range: (f64, f64), scale: u32) -> Pixmap {
    let e = error_field(&test.to_field(), &reference.to_field(), false);
    let style = FieldStyle::FalseColor {
        log: true,
        range: Some(range),
    };
    let opts = FigureOptions {
        colorbar_label: "absolute error |L − L_ref|",
        upscale: Some(scale.max(1)),
        ..Default::default()
    };
    field_figure_with(&e, None, &style, &opts)
}

/// The window of `size` (w, h) whose summed |a − b| (luminance) is largest, on a
/// grid of steps of a quarter of its size: where two images disagree most.
pub fn largest_difference_window(a: &Image, b: &Image, size: (usize, usize)) -> Window {
    let (w, h) = (size.0.clamp(1, a.width), size.1.clamp(1, a.height));
    let (sx, sy) = ((w / 4).max(1), (h / 4).max(1));
    let d: Vec<f64> = a
        .values
        .iter()
        .zip(b.values)
        .map(|(p, q)| (crate::core::color::luminance(*p) - crate::core::color::luminance(*q)).abs())
        .collect();
    let mut best = (f64::NEG_INFINITY, [0, 0, w, h]);
    let mut y = 0;
    while y + h <= a.height {
        let mut x = 0;
        while x + w <= a.width {
            let s: f64 = (y..y + h)
                .map(|j| d[j * a.width + x..j * a.width + x + w].iter().sum::<f64>())
                .sum();
            if s > best.0 {
                best = (s, [x, y, x + w, y + h]);
            }
            x += sx;
        }
        y += sy;
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> f64) -> Vec<Rgb> {
        (0..w * h).map(|k| Rgb::splat(f(k % w, k / w))).collect()
    }

    #[test]
    fn panels_have_the_expected_sizes_and_pixels() {
        let v = image(8, 6, |x, _| x as f64 / 8.0);
        let img = Image {
            width: 8,
            height: 6,
            values: &v,
        };
        let p = image_panel(&img, 0.0, 3);
        assert_eq!((p.width(), p.height()), (24, 18));
        // Whole-pixel enlargement: a 3×3 block per pixel.
        let px = |pm: &Pixmap, x: u32, y: u32| pm.pixel(x, y).unwrap();
        assert_eq!(px(&p, 6, 0), px(&p, 8, 2));
        assert_ne!(px(&p, 6, 0), px(&p, 9, 0));
        let inset = inset_panel(&img, [2, 1, 6, 4], 0.0, 4);
        assert_eq!((inset.width(), inset.height()), (16, 12));
        assert_eq!(px(&inset, 0, 0), px(&p, 6, 3));
    }

    #[test]
    fn largest_difference_window_finds_the_change() {
        let a = image(32, 24, |_, _| 1.0);
        let b = image(32, 24, |x, y| {
            if (20..24).contains(&x) && (4..8).contains(&y) {
                3.0
            } else {
                1.0
            }
        });
        let ia = Image {
            width: 32,
            height: 24,
            values: &a,
        };
        let ib = Image {
            width: 32,
            height: 24,
            values: &b,
        };
        let [x0, y0, x1, y1] = largest_difference_window(&ia, &ib, (8, 6));
        assert!(x0 <= 20 && x1 >= 24 && y0 <= 4 && y1 >= 8, "{x0} {y0} {x1} {y1}");
    }

    #[test]
    fn record_dots_are_drawn_in_their_colour() {
        let v = image(10, 10, |_, _| 0.0);
        let img = Image {
            width: 10,
            height: 10,
            values: &v,
        };
        let sizes = record_size_scale([0.1, 1.0]);
        let p = records_panel(
            &img,
            0.0,
            4,
            &[(Some(DVec2::new(5.0, 5.0)), 1.0), (None, 0.5)],
            &sizes,
            "radius",
        );
        assert!(p.width() > 40);
        let c = p.pixel(20, 20).unwrap();
        let want = sizes.color(1.0);
        assert_eq!([c.red(), c.green(), c.blue()], want);
    }
}
