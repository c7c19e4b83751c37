//! Text for figures: DejaVu Sans (embedded, loaded once) rasterised with ab_glyph and
//! blended over a premultiplied-alpha pixmap.
//!
//! Conventions: `size_px` is the em size in pixels (as CSS `font-size`); positions
//! are pixmap pixels (x right, y down). [`draw_text`] takes the left end of the
//! baseline; [`draw_text_aligned`] anchors any side. Text is a single line (control
//! characters are skipped); the origin is snapped to whole pixels so that glyph stems
//! stay crisp and identical text renders identically wherever it is placed. Colours
//! are straight (non-premultiplied) sRGB RGBA; blending is source-over in the
//! pixmap's sRGB space, as tiny-skia does.

use ab_glyph::{Font, FontRef, Glyph, GlyphId, PxScale, ScaleFont, point};
use std::sync::OnceLock;
use tiny_skia::Pixmap;

const FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_BYTES).expect("assets/DejaVuSans.ttf is a valid font"))
}

/// ab_glyph's scale is the height ascent − descent; convert from the em size.
fn px_scale(size_px: f32) -> PxScale {
    let f = font();
    let upem = f.units_per_em().unwrap_or(2048.0);
    PxScale::from(size_px.max(0.0) * f.height_unscaled() / upem)
}

/// Vertical metrics of the font at `size_px`, in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextMetrics {
    /// Distance from the baseline up to the top of the tallest glyphs (> 0).
    pub ascent: f32,
    /// Distance from the baseline down to the lowest descender (> 0).
    pub descent: f32,
    /// Height of capitals and digits above the baseline.
    pub cap_height: f32,
}

pub fn text_metrics(size_px: f32) -> TextMetrics {
    let f = font();
    let scaled = f.as_scaled(px_scale(size_px));
    let upem = f.units_per_em().unwrap_or(2048.0);
    // ab_glyph stores the top (y_max, font units, y up) of the outline in `bounds.min.y`.
    let cap = f.outline(f.glyph_id('H')).map_or(0.73 * upem, |o| o.bounds.min.y);
    TextMetrics {
        ascent: scaled.ascent(),
        descent: -scaled.descent(),
        cap_height: cap / upem * size_px,
    }
}

/// Lay out `text` on a baseline starting at `origin`; returns the glyphs and the
/// advance width.
fn layout(text: &str, size_px: f32, origin: (f32, f32)) -> (Vec<Glyph>, f32) {
    let f = font();
    let scale = px_scale(size_px);
    let scaled = f.as_scaled(scale);
    let mut caret = 0.0f32;
    let mut prev: Option<GlyphId> = None;
    let mut glyphs = Vec::with_capacity(text.len());
    for c in text.chars().filter(|c| !c.is_control()) {
        let id = f.glyph_id(c);
        if let Some(p) = prev {
            caret += scaled.kern(p, id);
        }
        glyphs.push(id.with_scale_and_position(scale, point(origin.0 + caret, origin.1)));
        caret += scaled.h_advance(id);
        prev = Some(id);
    }
    (glyphs, caret)
}

/// Advance width of `text` at `size_px`, in pixels.
pub fn text_width(text: &str, size_px: f32) -> f32 {
    layout(text, size_px, (0.0, 0.0)).1
}

/// Coverage of `text` laid out from the baseline origin (0, 0): calls
/// `plot(x, y, coverage)` with pixel coordinates relative to the origin.
fn rasterize(text: &str, size_px: f32, mut plot: impl FnMut(i32, i32, f32)) {
    let f = font();
    let (glyphs, _) = layout(text, size_px, (0.0, 0.0));
    for g in glyphs {
        if let Some(outlined) = f.outline_glyph(g) {
            let b = outlined.px_bounds();
            let (bx, by) = (b.min.x as i32, b.min.y as i32);
            outlined.draw(|x, y, c| plot(bx + x as i32, by + y as i32, c));
        }
    }
}

/// Source-over blend of a straight-alpha colour with `coverage` onto one pixel.
#[inline]
pub(crate) fn blend_pixel(pixmap: &mut Pixmap, x: i32, y: i32, color: [u8; 4], coverage: f32) {
    let (w, h) = (pixmap.width() as i32, pixmap.height() as i32);
    if x < 0 || y < 0 || x >= w || y >= h {
        return;
    }
    let sa = color[3] as f32 / 255.0 * coverage.clamp(0.0, 1.0);
    if sa <= 0.0 {
        return;
    }
    let k = ((y * w + x) * 4) as usize;
    let px = &mut pixmap.data_mut()[k..k + 4];
    for (d, &c) in px.iter_mut().zip(&color[..3]) {
        *d = (c as f32 * sa + *d as f32 * (1.0 - sa) + 0.5).min(255.0) as u8;
    }
    px[3] = (255.0 * sa + px[3] as f32 * (1.0 - sa) + 0.5).min(255.0) as u8;
    // Keep the premultiplied invariant (colour ≤ alpha) despite rounding.
    let a = px[3];
    for d in &mut px[..3] {
        *d = (*d).min(a);
    }
}

/// Draw `text` with the left end of its baseline at (x, y).
pub fn draw_text(pixmap: &mut Pixmap, text: &str, x: f32, y: f32, size_px: f32, color: [u8; 4]) {
    let (ox, oy) = (x.round() as i32, y.round() as i32);
    rasterize(text, size_px, |px, py, c| {
        blend_pixel(pixmap, ox + px, oy + py, color, c)
    });
}

/// Horizontal anchor of a text position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HAlign {
    Left,
    Center,
    Right,
}

/// Vertical anchor of a text position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VAlign {
    /// y is the top of the tallest glyphs (the ascent line).
    Top,
    /// y is the middle of capitals and digits (for labels beside a tick).
    Middle,
    /// y is the baseline.
    Baseline,
    /// y is the bottom of the descenders.
    Bottom,
}

/// Draw `text` anchored at (x, y) as given by `h` and `v`.
#[allow(clippy::too_many_arguments)]
pub fn draw_text_aligned(
    pixmap: &mut Pixmap,
    text: &str,
    x: f32,
    y: f32,
    size_px: f32,
    color: [u8; 4],
    h: HAlign,
    v: VAlign,
) {
    let (bx, by) = baseline_origin(text, x, y, size_px, h, v);
    draw_text(pixmap, text, bx, by, size_px, color);
}

fn baseline_origin(text: &str, x: f32, y: f32, size_px: f32, h: HAlign, v: VAlign) -> (f32, f32) {
    let w = text_width(text, size_px);
    let m = text_metrics(size_px);
    let bx = match h {
        HAlign::Left => x,
        HAlign::Center => x - 0.5 * w,
        HAlign::Right => x - w,
    };
    let by = match v {
        VAlign::Top => y + m.ascent,
        VAlign::Middle => y + 0.5 * m.cap_height,
        VAlign::Baseline => y,
        VAlign::Bottom => y - m.descent,
    };
    (bx, by)
}

/// Draw `text` turned 90° counter-clockwise (reading bottom to top, as a vertical
/// axis label). The anchors refer to the text's own frame: `h` along the reading
/// direction (Center centres it vertically on y), `v` across it (Top puts the
/// ascent line at x, with the text to its right).
#[allow(clippy::too_many_arguments)]
pub fn draw_text_vertical(
    pixmap: &mut Pixmap,
    text: &str,
    x: f32,
    y: f32,
    size_px: f32,
    color: [u8; 4],
    h: HAlign,
    v: VAlign,
) {
    // In the text's frame (u along the baseline, v down) the anchor sits at (0, 0);
    // the frame maps to the screen as (u, v) → (x + v, y − u), exact on whole pixels.
    let (bu, bv) = baseline_origin(text, 0.0, 0.0, size_px, h, v);
    let (ox, oy) = ((x + bv).round() as i32, (y - bu).round() as i32);
    rasterize(text, size_px, |gu, gv, c| {
        blend_pixel(pixmap, ox + gv, oy - gu - 1, color, c)
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ink(p: &Pixmap) -> u32 {
        p.data().chunks(4).map(|px| px[3] as u32).sum()
    }

    #[test]
    fn text_puts_ink_where_expected() {
        let mut p = Pixmap::new(120, 40).unwrap();
        draw_text(&mut p, "Hello 10⁻³", 4.0, 28.0, 16.0, [0, 0, 0, 255]);
        assert!(ink(&p) > 255 * 40, "too little ink: {}", ink(&p));
        // Nothing below the descenders or left of the origin.
        for y in 0..40 {
            for x in 0..120 {
                let a = p.pixel(x, y).unwrap().alpha();
                if a > 0 {
                    assert!(y < 28 + 5 && x >= 4 && y > 28 - 18, "ink at ({x}, {y})");
                }
            }
        }
        // Opaque text is opaque somewhere, and premultiplied colour never exceeds alpha.
        assert!(p.pixels().iter().any(|c| c.alpha() == 255));
        let mut q = Pixmap::new(60, 30).unwrap();
        q.fill(tiny_skia::Color::from_rgba8(40, 80, 120, 128));
        draw_text(&mut q, "Wg", 2.0, 20.0, 18.0, [250, 200, 10, 200]);
        for c in q.pixels() {
            assert!(c.red() <= c.alpha() && c.green() <= c.alpha() && c.blue() <= c.alpha());
        }
    }

    #[test]
    fn width_grows_with_text_and_size() {
        let a = text_width("10", 14.0);
        let b = text_width("100", 14.0);
        assert!(a > 0.0 && b > a);
        assert!((text_width("100", 28.0) - 2.0 * b).abs() < 0.5);
        assert_eq!(text_width("", 14.0), 0.0);
        let m = text_metrics(20.0);
        assert!(m.ascent > m.cap_height && m.cap_height > 10.0 && m.descent > 2.0);
    }

    #[test]
    fn aligned_and_vertical_text_stay_in_place() {
        let mut p = Pixmap::new(100, 100).unwrap();
        draw_text_aligned(
            &mut p,
            "Right",
            90.0,
            10.0,
            12.0,
            [0, 0, 0, 255],
            HAlign::Right,
            VAlign::Top,
        );
        for y in 0..100 {
            for x in 0..100 {
                if p.pixel(x, y).unwrap().alpha() > 0 {
                    assert!(x <= 91 && (9..30).contains(&y), "ink at ({x}, {y})");
                }
            }
        }
        let mut v = Pixmap::new(100, 100).unwrap();
        draw_text_vertical(
            &mut v,
            "Vertical",
            10.0,
            50.0,
            12.0,
            [0, 0, 0, 255],
            HAlign::Center,
            VAlign::Top,
        );
        let (mut ymin, mut ymax, mut xmin, mut xmax) = (100, 0, 100, 0);
        for y in 0..100u32 {
            for x in 0..100u32 {
                if v.pixel(x, y).unwrap().alpha() > 0 {
                    (ymin, ymax, xmin, xmax) = (ymin.min(y), ymax.max(y), xmin.min(x), xmax.max(x));
                }
            }
        }
        // Taller than wide, centred on y = 50, starting right of x = 10.
        assert!(ymax - ymin > 3 * (xmax - xmin), "{xmin}..{xmax} × {ymin}..{ymax}");
        assert!(((ymin + ymax) as i32 / 2 - 50).abs() <= 2 && xmin >= 9);
    }
}
