//! The colour code of gradient figures: each gradient ∇L gets the hue of its
//! direction and a brightness growing with log |∇L|, and a colour wheel explains it.
//!
//! - Direction: the angle of ∇L counter-clockwise from +x with world y up (a
//!   gradient pointing up the figure is π/2), coloured by [`angle_color`] (Oklab hue
//!   circle at constant lightness, so no direction stands out).
//! - Brightness: log |∇L| mapped linearly from a magnitude range onto [0.15, 1]
//!   (clamped), so weak gradients stay dimly visible; figures share one range
//!   between panels so that methods are comparable ([`magnitude_range`]: the 2nd
//!   and 98th percentiles of the nonzero magnitudes, robust to fireflies).
//!   |∇L| = 0 shows the dark [`PANEL_BACKGROUND`]; non-finite gradients are magenta
//!   ([`NAN_RGB`]) so that numerical bugs are seen.
//! - Samples lie on a regular grid whose spacing is inferred from their positions
//!   ([`grid_spacing`]).

use super::colormap::angle_color;
use super::field_figure::NAN_RGB;
use super::text::{HAlign, VAlign, blend_pixel, draw_text_aligned};
use glam::DVec2;
use tiny_skia::Pixmap;

/// The gradient ∇L of a quantity at a world position (world units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GradientSample {
    pub at: DVec2,
    pub grad: DVec2,
}

/// Background of the panels (and of cells with a zero gradient).
pub const PANEL_BACKGROUND: [u8; 3] = [14, 14, 18];
const TEXT: [u8; 4] = [20, 20, 20, 255];
pub(crate) const MIN_BRIGHTNESS: f64 = 0.15;

/// Spacing of the regular grid the samples lie on: per axis, the smallest gap
/// between distinct coordinates. An axis with a single coordinate takes the other
/// axis's spacing; None for fewer than two distinct positions.
pub fn grid_spacing(samples: &[GradientSample]) -> Option<DVec2> {
    let gap = |coord: fn(&GradientSample) -> f64| {
        let mut v: Vec<f64> = samples.iter().map(coord).filter(|c| c.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        let extent = v.last().zip(v.first()).map_or(0.0, |(hi, lo)| hi - lo);
        let tol = 1e-6 * extent;
        v.windows(2).map(|w| w[1] - w[0]).filter(|&d| d > tol).reduce(f64::min)
    };
    match (gap(|s| s.at.x), gap(|s| s.at.y)) {
        (Some(x), Some(y)) => Some(DVec2::new(x, y)),
        (Some(d), None) | (None, Some(d)) => Some(DVec2::splat(d)),
        (None, None) => None,
    }
}

/// The shared brightness range: 2nd and 98th percentiles of the finite nonzero
/// magnitudes; (10⁻³, 1) without any, a decade below a single value.
pub fn magnitude_range<'a>(samples: impl IntoIterator<Item = &'a GradientSample>) -> (f64, f64) {
    let mut m: Vec<f64> = samples
        .into_iter()
        .map(|s| s.grad.length())
        .filter(|&m| m.is_finite() && m > 0.0)
        .collect();
    if m.is_empty() {
        return (1e-3, 1.0);
    }
    m.sort_by(f64::total_cmp);
    let q = |p: f64| m[(((m.len() - 1) as f64) * p).round() as usize];
    let (lo, hi) = (q(0.02), q(0.98));
    if lo < hi { (lo, hi) } else { (hi / 10.0, hi) }
}

/// Brightness of a gradient magnitude: log-linear over `range` onto [0.15, 1]; 0 for
/// a zero or non-finite magnitude.
pub fn gradient_brightness(magnitude: f64, range: (f64, f64)) -> f64 {
    if !(magnitude.is_finite() && magnitude > 0.0) {
        return 0.0;
    }
    let (lo, hi) = (range.0.max(f64::MIN_POSITIVE), range.1);
    let t = if hi > lo {
        (magnitude / lo).ln() / (hi / lo).ln()
    } else {
        1.0
    };
    MIN_BRIGHTNESS + (1.0 - MIN_BRIGHTNESS) * t.clamp(0.0, 1.0)
}

/// The colour of a gradient (see the module documentation).
pub fn gradient_color(grad: DVec2, range: (f64, f64)) -> [u8; 3] {
    if !grad.is_finite() {
        return NAN_RGB;
    }
    let b = gradient_brightness(grad.length(), range);
    if b == 0.0 {
        PANEL_BACKGROUND
    } else {
        angle_color(grad.y.atan2(grad.x), b)
    }
}

/// The legend of the colour coding: a disc centred at (cx, cy) whose hue at each
/// point is the direction from the centre (counter-clockwise from +x, up is +y) and
/// whose brightness grows from the centre (|∇L| at or below the range) to the rim
/// (at or above it), with "+x", "+y" beside it and "direction / log |∇L|" below.
/// Text extends about 0.45 × radius + 15 px beyond the disc.
pub fn colour_wheel_legend(pixmap: &mut Pixmap, cx: f32, cy: f32, radius: f32) {
    let r = radius.max(2.0);
    let (x0, x1) = ((cx - r - 1.0).floor() as i32, (cx + r + 1.0).ceil() as i32);
    let (y0, y1) = ((cy - r - 1.0).floor() as i32, (cy + r + 1.0).ceil() as i32);
    for py in y0..y1 {
        for px in x0..x1 {
            // Pixel centre relative to the disc centre, world orientation (y up).
            let (dx, dy) = ((px as f32 + 0.5 - cx) as f64, (cy - py as f32 - 0.5) as f64);
            let rho = dx.hypot(dy);
            let coverage = (r as f64 + 0.5 - rho).clamp(0.0, 1.0) as f32;
            if coverage > 0.0 {
                let t = (rho / r as f64).min(1.0);
                let [red, g, b] = angle_color(dy.atan2(dx), MIN_BRIGHTNESS + (1.0 - MIN_BRIGHTNESS) * t);
                blend_pixel(pixmap, px, py, [red, g, b, 255], coverage);
            }
        }
    }
    let font = (0.2 * r).clamp(10.0, 16.0).round();
    let gap = (0.3 * font).round();
    let grey = [90, 90, 90, 255];
    draw_text_aligned(pixmap, "+x", cx + r + gap, cy, font, grey, HAlign::Left, VAlign::Middle);
    draw_text_aligned(
        pixmap,
        "+y",
        cx,
        cy - r - gap,
        font,
        grey,
        HAlign::Center,
        VAlign::Bottom,
    );
    let label = "direction / log |∇L|";
    draw_text_aligned(
        pixmap,
        label,
        cx,
        cy + r + 2.0 * gap,
        font,
        TEXT,
        HAlign::Center,
        VAlign::Top,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figure::colormap::srgb8_luminance;
    use std::f64::consts::FRAC_PI_2;

    fn rgb(p: &Pixmap, x: u32, y: u32) -> [u8; 3] {
        let c = p.pixel(x, y).unwrap();
        [c.red(), c.green(), c.blue()]
    }

    /// Samples at the centres of an n × n grid over [-1, 1]² with gradient f(p).
    fn grid(n: usize, f: impl Fn(DVec2) -> DVec2) -> Vec<GradientSample> {
        let h = 2.0 / n as f64;
        (0..n * n)
            .map(|k| {
                let at = DVec2::new(-1.0 + h * ((k % n) as f64 + 0.5), -1.0 + h * ((k / n) as f64 + 0.5));
                GradientSample { at, grad: f(at) }
            })
            .collect()
    }

    #[test]
    fn spacing_and_range_are_inferred() {
        let g = grid(8, |p| p);
        assert!((grid_spacing(&g).unwrap() - DVec2::splat(0.25)).length() < 1e-12);
        let row: Vec<_> = (0..4)
            .map(|i| GradientSample {
                at: DVec2::new(i as f64 * 0.1, 2.0),
                grad: DVec2::X,
            })
            .collect();
        assert!((grid_spacing(&row).unwrap() - DVec2::splat(0.1)).length() < 1e-12);
        assert_eq!(grid_spacing(&row[..1]), None);
        let (lo, hi) = magnitude_range(&g);
        assert!(lo > 0.0 && lo < hi && hi < 2f64.sqrt());
        assert_eq!(magnitude_range(&[]), (1e-3, 1.0));
        assert_eq!(magnitude_range(&row), (0.1, 1.0));
    }

    #[test]
    fn brightness_grows_with_magnitude() {
        let range = (1e-3, 1.0);
        let mags = [0.0, 1e-5, 1e-3, 1e-2, 0.1, 1.0, 10.0];
        let b: Vec<f64> = mags.iter().map(|&m| gradient_brightness(m, range)).collect();
        let want = [0.0, 0.15, 0.15, 0.15 + 0.85 / 3.0, 0.15 + 0.85 * 2.0 / 3.0, 1.0, 1.0];
        assert!(b.iter().zip(want).all(|(x, y)| (x - y).abs() < 1e-12), "{b:?}");
        let lum: Vec<f64> = [1e-3, 1e-2, 0.1, 1.0]
            .iter()
            .map(|&m| srgb8_luminance(gradient_color(DVec2::new(0.6, -0.8) * m, range)))
            .collect();
        assert!(lum.windows(2).all(|w| w[0] < w[1]), "{lum:?}");
        assert_eq!(gradient_color(DVec2::ZERO, range), PANEL_BACKGROUND);
        assert_eq!(gradient_color(DVec2::new(f64::NAN, 1.0), range), NAN_RGB);
    }

    #[test]
    fn colour_wheel_follows_world_orientation() {
        let mut p = Pixmap::new(200, 200).unwrap();
        colour_wheel_legend(&mut p, 100.0, 100.0, 60.0);
        // Pixel (x, y) has its centre at (x + ½, y + ½); y up in world terms.
        let expect = |x: u32, y: u32| {
            let (dx, dy) = (x as f64 + 0.5 - 100.0, 100.0 - y as f64 - 0.5);
            angle_color(dy.atan2(dx), 0.15 + 0.85 * dx.hypot(dy) / 60.0)
        };
        for (x, y) in [(150, 100), (100, 50), (50, 100), (100, 150), (101, 101)] {
            assert_eq!(rgb(&p, x, y), expect(x, y), "({x}, {y})");
        }
        // Up in the picture is +y: the colour of π/2.
        let up = rgb(&p, 100, 45);
        let d = |a: [u8; 3], b: [u8; 3]| a.iter().zip(b).map(|(&x, y)| x.abs_diff(y) as u32).sum::<u32>();
        assert!(d(up, angle_color(FRAC_PI_2, 0.92)) < 12 && d(up, angle_color(-FRAC_PI_2, 0.92)) > 60);
        // The centre is dim.
        assert!(srgb8_luminance(rgb(&p, 100, 100)) < 0.05);
        assert!(
            p.pixel(100, 100 + 60 + 20).unwrap().alpha() > 0 || (0..200).any(|x| p.pixel(x, 175).unwrap().alpha() > 0)
        );
    }
}
