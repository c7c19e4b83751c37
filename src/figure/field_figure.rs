//! A radiance field as a figure: the field's pixels (tone-mapped or false colour),
//! the scene drawn over them, an optional title, and for false colour a colour bar.
//!
//! Layout: the field is shown one figure pixel per field pixel, enlarged by an
//! integer factor (nearest neighbour, so pixels stay visible as pixels) when its
//! longest side is well under 512 px ([`upscale_factor`]). A tone-mapped figure
//! without a title is exactly the (enlarged) field. Otherwise a white margin
//! surrounds it, the title sits centred above, and the colour bar to the right has
//! the field's height. Text and line sizes grow with the figure.
//!
//! Pixel colours: where the field is undefined (`valid == false`) a neutral dark
//! grey ([`INVALID_RGB`]); NaN in a defined pixel magenta ([`NAN_RGB`]) so that
//! numerical bugs are seen; false colour maps the Rec. 709 luminance of each value.

use super::colorbar::{ColorScale, colorbar_width, draw_colorbar};
use super::colormap::tonemap;
use super::overlay::{OverlayStyle, draw_scene};
use super::panel::View;
use super::text::{HAlign, VAlign, draw_text_aligned, text_width};
use crate::core::color::luminance;
use crate::flatland::field::Field;
use crate::flatland::scene::Scene;
use tiny_skia::{Color, Pixmap};

/// How field values become colours.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldStyle {
    /// RGB × 2^exposure, clamped, sRGB-encoded.
    Tonemapped { exposure: f64 },
    /// Luminance through viridis, linear or logarithmic, over `range` (automatic and
    /// robust when None, see [`ColorScale::auto`]; an unusable range is repaired, see
    /// [`ColorScale::new`]).
    FalseColor { log: bool, range: Option<(f64, f64)> },
}

/// Pixels where the field is undefined.
pub const INVALID_RGB: [u8; 3] = [64, 64, 64];
/// Defined pixels holding NaN.
pub const NAN_RGB: [u8; 3] = [255, 0, 255];

const BACKGROUND: [u8; 4] = [255, 255, 255, 255];
const TEXT: [u8; 4] = [20, 20, 20, 255];

/// A field mapped to opaque 8-bit sRGB colours (row 0 = top), with the colour scale
/// used for false colour: what a GUI needs to show a field and its legend.
#[derive(Clone, Debug, PartialEq)]
pub struct MappedField {
    pub width: usize,
    pub height: usize,
    /// Row-major RGBA, alpha 255 everywhere (so straight = premultiplied).
    pub rgba: Vec<u8>,
    pub scale: Option<ColorScale>,
}

impl MappedField {
    /// Copy into `pixmap` with the top-left corner at (x0, y0), each field pixel
    /// becoming a `k`×`k` block; parts outside the pixmap are skipped.
    pub fn blit(&self, pixmap: &mut Pixmap, x0: i32, y0: i32, k: u32) {
        let (pw, ph) = (pixmap.width() as i32, pixmap.height() as i32);
        let k = k.max(1) as i32;
        let data = pixmap.data_mut();
        for y in 0..self.height as i32 * k {
            let py = y0 + y;
            if py < 0 || py >= ph {
                continue;
            }
            let src_row = (y / k) as usize * self.width;
            for x in 0..self.width as i32 * k {
                let px = x0 + x;
                if px < 0 || px >= pw {
                    continue;
                }
                let s = (src_row + (x / k) as usize) * 4;
                let d = ((py * pw + px) * 4) as usize;
                data[d..d + 4].copy_from_slice(&self.rgba[s..s + 4]);
            }
        }
    }

    /// A pixmap of the field alone, enlarged `k` times.
    pub fn to_pixmap(&self, k: u32) -> Pixmap {
        let k = k.max(1);
        let mut p = Pixmap::new(self.width as u32 * k, self.height as u32 * k).expect("non-empty field");
        self.blit(&mut p, 0, 0, k);
        p
    }
}

/// The colour scale of a false-colour style for this field: `range` if given (made
/// valid), else the robust automatic range of the luminance of valid pixels.
pub fn field_color_scale(field: &Field, log: bool, range: Option<(f64, f64)>) -> ColorScale {
    match range {
        Some((lo, hi)) => ColorScale::new(log, lo, hi),
        None => ColorScale::auto(
            field
                .values
                .iter()
                .zip(&field.valid)
                .filter(|(_, ok)| **ok)
                .map(|(v, _)| luminance(*v)),
            log,
        ),
    }
}

/// Map every pixel of `field` to a colour with `style`.
pub fn field_to_rgba(field: &Field, style: &FieldStyle) -> MappedField {
    let scale = match style {
        FieldStyle::Tonemapped { .. } => None,
        FieldStyle::FalseColor { log, range } => Some(field_color_scale(field, *log, *range)),
    };
    let mut rgba = Vec::with_capacity(field.values.len() * 4);
    for (v, &ok) in field.values.iter().zip(&field.valid) {
        let c = if !ok {
            INVALID_RGB
        } else if v.is_nan() {
            NAN_RGB
        } else {
            match (style, &scale) {
                (FieldStyle::FalseColor { .. }, Some(s)) => s.color(luminance(*v)),
                (FieldStyle::Tonemapped { exposure }, _) => tonemap(*v, *exposure),
                _ => unreachable!("false colour has a scale"),
            }
        };
        rgba.extend_from_slice(&[c[0], c[1], c[2], 255]);
    }
    MappedField {
        width: field.width,
        height: field.height,
        rgba,
        scale,
    }
}

/// Integer enlargement bringing a field's longest side closest to 512 px (1 for
/// fields of about 340 px or more).
pub fn upscale_factor(width: usize, height: usize) -> u32 {
    let longest = width.max(height).max(1) as f64;
    (512.0 / longest).round().max(1.0) as u32
}

/// Options of [`field_figure_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct FigureOptions<'a> {
    pub title: Option<&'a str>,
    /// Quantity and unit written along the colour bar (false colour only).
    pub colorbar_label: &'a str,
    /// Enlargement factor; [`upscale_factor`] when None.
    pub upscale: Option<u32>,
    pub overlay: Option<OverlayStyle>,
}

impl Default for FigureOptions<'_> {
    fn default() -> Self {
        FigureOptions {
            title: None,
            colorbar_label: "luminance",
            upscale: None,
            overlay: None,
        }
    }
}

/// The figure of a field: see the module documentation for the layout. Panics if
/// the field has no pixels.
pub fn field_figure(field: &Field, scene: Option<&Scene>, style: &FieldStyle, title: Option<&str>) -> Pixmap {
    field_figure_with(
        field,
        scene,
        style,
        &FigureOptions {
            title,
            ..Default::default()
        },
    )
}

/// [`field_figure`] with every option.
pub fn field_figure_with(field: &Field, scene: Option<&Scene>, style: &FieldStyle, opts: &FigureOptions) -> Pixmap {
    let mapped = field_to_rgba(field, style);
    let k = opts
        .upscale
        .unwrap_or_else(|| upscale_factor(field.width, field.height))
        .max(1);
    let (pw, ph) = (field.width as f32 * k as f32, field.height as f32 * k as f32);
    // Sizes of text and marks follow the panel (1 at 512 px).
    let s = (pw.max(ph) / 512.0).clamp(0.75, 3.0);
    let label_px = (13.0 * s).round();
    let title_px = (16.0 * s).round();

    let title = opts.title.filter(|t| !t.trim().is_empty());
    let decorated = title.is_some() || mapped.scale.is_some();
    let margin = if decorated { (12.0 * s).round() } else { 0.0 };
    let top = if title.is_some() {
        (2.2 * title_px).round()
    } else {
        margin
    };
    let bar_gap = (14.0 * s).round();
    let bar_w = mapped.scale.map_or(0.0, |sc| {
        bar_gap + colorbar_width(&sc, ph, label_px, opts.colorbar_label).ceil()
    });
    let width = (margin + pw + bar_w + margin).ceil();
    let height = (top + ph + margin).ceil();

    let mut pixmap = Pixmap::new(width as u32, height as u32).expect("field is not empty");
    pixmap.fill(Color::from_rgba8(
        BACKGROUND[0],
        BACKGROUND[1],
        BACKGROUND[2],
        BACKGROUND[3],
    ));
    mapped.blit(&mut pixmap, margin as i32, top as i32, k);

    if let Some(scene) = scene {
        let view = View::of_field(field, margin, top, k as f32);
        let style = opts.overlay.unwrap_or_else(|| OverlayStyle::for_panel(pw.max(ph)));
        draw_scene(&mut pixmap, scene, &view, &style);
    }
    if let Some(t) = title {
        // Shrink a long title to fit the figure; centre it on the field if possible.
        let room = width - 2.0 * margin.max(4.0);
        let size = (title_px * (room / text_width(t, title_px)).min(1.0)).max(6.0);
        let w = text_width(t, size);
        let cx = (margin + 0.5 * pw).clamp(margin + 0.5 * w, (width - margin - 0.5 * w).max(margin + 0.5 * w));
        draw_text_aligned(
            &mut pixmap,
            t,
            cx,
            0.5 * top + 0.15 * title_px,
            size,
            TEXT,
            HAlign::Center,
            VAlign::Middle,
        );
    }
    if let Some(sc) = &mapped.scale {
        draw_colorbar(
            &mut pixmap,
            sc,
            margin + pw + bar_gap,
            top,
            ph,
            label_px,
            opts.colorbar_label,
        );
    }
    pixmap
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::color::Rgb;
    use glam::DVec2;

    const SCENE: &str = r#"{
        "domain": { "min": [-1, -1], "max": [1, 1] },
        "segments": [
            { "a": [-0.5, 0.0], "b": [0.5, 0.0], "reflectance": 0.8 },
            { "a": [0.4, 0.7], "b": [-0.4, 0.7], "emission": 2.0, "two_sided": false },
            { "points": [[-0.9, -0.9], [-0.6, -0.9], [-0.6, -0.6]], "closed": true, "reflectance": 0.3 }
        ],
        "lights": [
            { "type": "point", "position": [0.6, -0.5], "intensity": 1.0 },
            { "type": "collimated", "direction": [1, -1], "aperture": [[-1.0, 0.2], [-0.6, 0.6]], "irradiance": 1.0 }
        ],
        "medium": { "sigma_a": 0.1, "sigma_s": 1.0, "region": { "polygon": [[-0.8, -0.3], [0.8, -0.3], [0.8, 0.9], [-0.8, 0.9]] } }
    }"#;

    /// A smooth positive gradient over [-1, 1]², invalid in the left-most columns.
    fn gradient_field(w: usize, h: usize) -> Field {
        let mut f = Field::new(w, h, DVec2::new(-1.0, -1.0), DVec2::new(1.0, 1.0));
        for j in 0..h {
            for i in 0..w {
                let p = f.pixel_center(i, j);
                let k = j * w + i;
                f.values[k] = Rgb::new(1.0, 0.8, 0.6) * (0.02 + 0.5 * (p.x + 1.0) * (0.3 + 0.35 * (p.y + 1.0)));
                f.valid[k] = i >= 3;
            }
        }
        f
    }

    fn rgb_at(p: &Pixmap, x: u32, y: u32) -> [u8; 3] {
        let c = p.pixel(x, y).unwrap();
        [c.red(), c.green(), c.blue()]
    }

    #[test]
    fn tonemapped_figure_is_the_enlarged_field() {
        let f = gradient_field(48, 32);
        let scene = Scene::from_json(SCENE, "test").unwrap();
        let k = upscale_factor(48, 32);
        assert_eq!(k, 11);
        let style = FieldStyle::Tonemapped { exposure: 0.0 };
        let p = field_figure(&f, Some(&scene), &style, None);
        assert_eq!((p.width(), p.height()), (48 * k, 32 * k));
        // Deterministic to the byte.
        assert_eq!(p.data(), field_figure(&f, Some(&scene), &style, None).data());
        // Invalid pixels are grey (away from the overlay), valid ones tone-mapped.
        assert_eq!(rgb_at(&p, k, 30 * k), INVALID_RGB);
        let (i, j) = (40, 28);
        assert_eq!(
            rgb_at(&p, i * k + k / 2, j * k + k / 2),
            tonemap(f.get(i as usize, j as usize), 0.0)
        );
        // Without the scene the segment's pixels show the field.
        let bare = field_figure(&f, None, &style, None);
        let (sx, sy) = (24 * k, 16 * k); // world (0, 0): the middle of the reflector
        assert_eq!(rgb_at(&bare, sx, sy), tonemap(f.get(24, 16), 0.0));
        // With it, light grey ink on the segment and a dark outline just beside it.
        let c = rgb_at(&p, sx, sy);
        assert!(c.iter().all(|&v| v > 180) && c[0].abs_diff(c[2]) < 4, "{c:?}");
        let edge = rgb_at(&p, sx, sy - 2);
        assert!(edge.iter().all(|&v| v < 60), "{edge:?}");
    }

    #[test]
    fn false_color_figure_has_bar_title_and_grey_invalid_pixels() {
        let f = gradient_field(40, 40);
        let scene = Scene::from_json(SCENE, "test").unwrap();
        let style = FieldStyle::FalseColor { log: true, range: None };
        let p = field_figure(&f, Some(&scene), &style, Some("L_s, occluder scene"));
        let k = upscale_factor(40, 40);
        assert_eq!(k, 13);
        let panel = 40 * k;
        assert!(
            p.width() > panel + 60 && p.height() > panel + 20,
            "{}×{}",
            p.width(),
            p.height()
        );
        assert_eq!(
            p.data(),
            field_figure(&f, Some(&scene), &style, Some("L_s, occluder scene")).data()
        );
        // The panel's origin: the margin on the left, the title band above.
        let (x0, y0) = (p.width() - panel, p.height() - panel);
        let x0 = (0..x0)
            .find(|&x| rgb_at(&p, x, p.height() / 2 + 50) != [255; 3])
            .unwrap();
        let y0 = (0..y0)
            .rev()
            .find(|&y| rgb_at(&p, x0 + panel - 3, y) == [255; 3])
            .unwrap()
            + 1;
        assert_eq!(rgb_at(&p, x0 + 1, y0 + panel - 2), INVALID_RGB);
        // Title ink above the panel, colour bar ink to the right of it.
        let ink = |x: std::ops::Range<u32>, y: std::ops::Range<u32>| {
            y.flat_map(|y| x.clone().map(move |x| (x, y)))
                .filter(|&(x, y)| rgb_at(&p, x, y)[0] < 128)
                .count()
        };
        assert!(ink(0..p.width(), 0..y0) > 50, "title");
        assert!(ink(x0 + panel + 2..p.width(), y0..y0 + panel) > 500, "colour bar");
        // Valid pixels follow viridis: the brightest corner is near the top colour.
        let sc = field_color_scale(&f, true, None);
        let top_right = rgb_at(&p, x0 + panel - 2, y0 + 1);
        assert_eq!(top_right, sc.color(luminance(f.get(39, 0))));
    }

    #[test]
    fn nan_is_flagged_and_ranges_are_honoured() {
        let mut f = gradient_field(8, 8);
        f.values[9 * 4] = Rgb::splat(f64::NAN);
        let m = field_to_rgba(
            &f,
            &FieldStyle::FalseColor {
                log: false,
                range: Some((0.0, 1e-9)),
            },
        );
        assert_eq!(&m.rgba[36 * 4..36 * 4 + 3], &NAN_RGB);
        assert_eq!(m.scale.unwrap().max, 1e-9);
        // Everything valid is above the range: the top colour.
        assert_eq!(&m.rgba[7 * 4..7 * 4 + 3], &super::super::colormap::viridis(1.0));
        let pm = m.to_pixmap(3);
        assert_eq!((pm.width(), pm.height()), (24, 24));
    }

    /// Larger figures of each style render; with `VOLCACHE_FIGURE_OUT=dir` they are
    /// written there to be looked at (`figure_example*.png`).
    #[test]
    fn example_figures() {
        let scene = Scene::from_json(SCENE, "test").unwrap();
        let square = gradient_field(128, 128);
        let wide = gradient_field(600, 300);
        let figures = [
            (
                "",
                field_figure(
                    &square,
                    Some(&scene),
                    &FieldStyle::FalseColor { log: true, range: None },
                    Some("Synthetic gradient, log luminance"),
                ),
            ),
            (
                "_linear",
                field_figure(
                    &wide,
                    Some(&scene),
                    &FieldStyle::FalseColor {
                        log: false,
                        range: None,
                    },
                    Some("Linear scale, 600×300"),
                ),
            ),
            (
                "_tonemapped",
                field_figure(&square, Some(&scene), &FieldStyle::Tonemapped { exposure: 0.0 }, None),
            ),
        ];
        assert_eq!((figures[2].1.width(), figures[2].1.height()), (512, 512));
        assert!(figures[1].1.width() > 600 && figures[1].1.height() > 300);
        if let Some(dir) = std::env::var_os("VOLCACHE_FIGURE_OUT") {
            for (suffix, p) in &figures {
                let path = std::path::Path::new(&dir).join(format!("figure_example{suffix}.png"));
                crate::output::write_png(&path, p).unwrap();
            }
        }
    }
}
