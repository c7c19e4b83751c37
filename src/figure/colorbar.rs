//! False-colour scales: the value → colour mapping (linear or logarithmic, viridis),
//! its robust automatic range, tick positions and labels, and the vertical colour
//! bar drawn beside a figure.
//!
//! Automatic range (over finite values): linear scales run from 0 (or the 1st
//! percentile when there are negative values) to the 99.5th percentile; logarithmic
//! scales run over the 1st to 99.5th percentiles of the positive values, at most
//! 10 decades. Values beyond the range take the end colours, so a few fireflies or
//! a singular light source do not wash out the whole figure.
//!
//! Labels: linear ticks at 1–2–5 steps (a common ×10ⁿ factor for very small or large
//! values), logarithmic ticks at powers of ten written 10ⁿ (1–2–5 multiples, as plain
//! decimals when short, when the range is under two decades; unlabelled minor ticks
//! at 2…9 × 10ⁿ).

use super::colormap::viridis;
use super::text::{HAlign, VAlign, draw_text_aligned, draw_text_vertical, text_metrics, text_width};
use tiny_skia::{Color, Paint, PathBuilder, Pixmap, Rect, Transform};

/// A value range shown with the viridis map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorScale {
    pub log: bool,
    /// Value at the bottom colour (> 0 when `log`).
    pub min: f64,
    /// Value at the top colour (> min).
    pub max: f64,
}

/// One tick of a colour bar.
#[derive(Clone, Debug, PartialEq)]
pub struct Tick {
    pub value: f64,
    /// Position along the bar, 0 = bottom, 1 = top.
    pub t: f64,
    /// None for minor (unlabelled) ticks.
    pub label: Option<String>,
}

/// Value at quantile `q` of sorted data (nearest rank).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let k = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[k.min(sorted.len() - 1)]
}

impl ColorScale {
    /// A scale from an explicit range, repaired if unusable: a log scale needs
    /// 0 < min < max, a linear one min < max.
    pub fn new(log: bool, min: f64, max: f64) -> Self {
        let (mut lo, mut hi) = (min, max);
        if !hi.is_finite() || (log && hi <= 0.0) {
            hi = 1.0;
        }
        if log {
            if !(lo.is_finite() && lo > 0.0 && lo < hi) {
                lo = hi * 1e-3;
            }
            // Subnormal ends would give log10 → −inf (a tick count of 2³¹): keep the
            // range within normal floats.
            lo = lo.max(f64::MIN_POSITIVE);
            if hi <= lo {
                hi = 10.0 * lo;
            }
        } else if !(lo.is_finite() && lo < hi) {
            lo = if hi > 0.0 { 0.0 } else { hi - 1.0 };
        }
        if !log && !(hi - lo).is_normal() {
            // A width that overflows or is subnormal: a unit range around the top.
            (lo, hi) = if hi.abs() > 1.0 {
                (hi - hi.abs() * 0.5, hi)
            } else {
                (hi - 1.0, hi)
            };
        }
        ColorScale { log, min: lo, max: hi }
    }

    /// The robust automatic range of `values` (non-finite values ignored).
    pub fn auto(values: impl IntoIterator<Item = f64>, log: bool) -> Self {
        let mut v: Vec<f64> = values
            .into_iter()
            .filter(|x| x.is_finite() && (!log || *x > 0.0))
            .collect();
        if v.is_empty() {
            return ColorScale::new(log, if log { 1e-3 } else { 0.0 }, 1.0);
        }
        v.sort_by(f64::total_cmp);
        let hi = quantile(&v, 0.995);
        if log {
            let lo = quantile(&v, 0.01).max(hi * 1e-10);
            let lo = if lo < hi { lo } else { hi / 10.0 };
            ColorScale::new(true, lo, hi)
        } else {
            let lo = if v[0] >= 0.0 { 0.0 } else { quantile(&v, 0.01) };
            let hi = if hi > lo { hi } else { v[v.len() - 1].max(lo + 1.0) };
            ColorScale::new(false, lo, hi)
        }
    }

    /// Position of `v` in the range, clamped to [0, 1]; NaN stays NaN, and values
    /// ≤ 0 on a log scale map to 0.
    pub fn normalize(&self, v: f64) -> f64 {
        if v.is_nan() {
            return f64::NAN;
        }
        let t = if self.log {
            if v <= 0.0 {
                0.0
            } else if (self.max / self.min).is_finite() && (v / self.min).is_finite() {
                (v / self.min).ln() / (self.max / self.min).ln()
            } else {
                // Ranges wider than f64 (10⁻³⁰⁰…10³⁰⁰): the same in logarithms.
                (v.ln() - self.min.ln()) / (self.max.ln() - self.min.ln())
            }
        } else {
            (v - self.min) / (self.max - self.min)
        };
        t.clamp(0.0, 1.0)
    }

    /// Value at position t ∈ [0, 1] of the range.
    pub fn value_at(&self, t: f64) -> f64 {
        if self.log {
            let ratio = self.max / self.min;
            if ratio.is_finite() {
                self.min * ratio.powf(t)
            } else {
                (self.min.ln() + t * (self.max.ln() - self.min.ln())).exp()
            }
        } else {
            self.min + t * (self.max - self.min)
        }
    }

    /// The colour of `v` (NaN → the bottom colour; callers flag NaN themselves).
    pub fn color(&self, v: f64) -> [u8; 3] {
        viridis(self.normalize(v))
    }

    /// Ticks for a bar with room for about `max_labels` labels, bottom to top.
    pub fn ticks(&self, max_labels: usize) -> Vec<Tick> {
        let max_labels = max_labels.max(2);
        if self.log {
            self.log_ticks(max_labels)
        } else {
            self.linear_ticks(max_labels)
        }
    }

    fn tick(&self, value: f64, label: Option<String>) -> Tick {
        Tick {
            value,
            t: self.normalize(value),
            label,
        }
    }

    fn linear_ticks(&self, max_labels: usize) -> Vec<Tick> {
        let step = nice_step((self.max - self.min) / (max_labels - 1) as f64);
        let first = (self.min / step - 1e-9).ceil() as i64;
        let last = (self.max / step + 1e-9).floor() as i64;
        // A step lost in rounding (a range near the limits of f64) would ask for
        // billions of ticks: label the ends instead.
        if !(step > 0.0 && step.is_finite()) || last.saturating_sub(first) > 4 * max_labels as i64 {
            return [self.min, self.max]
                .map(|v| self.tick(v, Some(format!("{v:.3e}"))))
                .into();
        }
        let magnitude = self.min.abs().max(self.max.abs());
        // Plain decimals for moderate magnitudes, a common power of ten otherwise.
        let exponent = if (1e-2..1e5).contains(&magnitude) {
            0
        } else {
            magnitude.log10().floor() as i32
        };
        let unit = 10f64.powi(exponent);
        let decimals = decimals_for(step / unit);
        (first..=last)
            .map(|k| {
                let v = k as f64 * step;
                // (k == 0 avoids "-0.0" from rounding.)
                let m = format!("{:.*}", decimals, if k == 0 { 0.0 } else { v / unit });
                let label = match (exponent, k) {
                    (0, _) => m,
                    (_, 0) => "0".to_string(),
                    _ => format!("{m}×10{}", superscript(exponent)),
                };
                self.tick(v, Some(label))
            })
            .collect()
    }

    fn log_ticks(&self, max_labels: usize) -> Vec<Tick> {
        let (lo, hi) = (self.min.log10(), self.max.log10());
        let (k0, k1) = ((lo - 1e-9).ceil() as i32, (hi + 1e-9).floor() as i32);
        let in_range = |v: f64| v >= self.min * (1.0 - 1e-9) && v <= self.max * (1.0 + 1e-9);
        let powers = (k1 - k0 + 1).max(0) as usize;
        let mut ticks = Vec::new();
        if powers >= 2 {
            let stride = powers.div_ceil(max_labels) as i32;
            for k in k0..=k1 {
                let labelled = (k - k0) % stride == 0;
                ticks.push(self.tick(10f64.powi(k), labelled.then(|| format!("10{}", superscript(k)))));
            }
            if hi - lo <= 6.0 {
                for k in (k0 - 1)..=k1 {
                    for m in 2..=9 {
                        let v = m as f64 * 10f64.powi(k);
                        if in_range(v) {
                            ticks.push(self.tick(v, None));
                        }
                    }
                }
            }
        } else {
            // Under two decades: label 1, 2, 5 (or every digit) × 10ⁿ, in plain
            // decimals when they are short.
            let plain = self.min >= 0.01 && self.max < 1e4;
            for mantissas in [&[1, 2, 5][..], &[1, 2, 3, 4, 5, 6, 7, 8, 9][..]] {
                ticks.clear();
                for k in (k0 - 1)..=k1.max(k0) {
                    for &m in mantissas {
                        let v = m as f64 * 10f64.powi(k);
                        if in_range(v) {
                            let label = if plain {
                                format!("{:.*}", (-k).max(0) as usize, v)
                            } else if m == 1 {
                                format!("10{}", superscript(k))
                            } else {
                                format!("{m}×10{}", superscript(k))
                            };
                            ticks.push(self.tick(v, Some(label)));
                        }
                    }
                }
                if ticks.len() >= 2 {
                    break;
                }
            }
            if ticks.len() < 2 {
                // A range inside one digit step: label the ends.
                ticks = [self.min, self.max]
                    .iter()
                    .map(|&v| self.tick(v, Some(short_sci(v))))
                    .collect();
            }
        }
        ticks.sort_by(|a, b| a.value.total_cmp(&b.value));
        ticks
    }
}

/// The smallest of 1, 2, 2.5, 5 × 10ⁿ at least `raw`.
fn nice_step(raw: f64) -> f64 {
    let raw = if raw.is_finite() && raw > 0.0 { raw } else { 1.0 };
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    let nice = [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .find(|&c| c >= m * (1.0 - 1e-9))
        .unwrap_or(10.0);
    nice * p
}

/// Decimals needed to print multiples of `step` exactly.
fn decimals_for(step: f64) -> usize {
    (0..8)
        .find(|&d| ((step * 10f64.powi(d as i32)).round() - step * 10f64.powi(d as i32)).abs() < 1e-6)
        .unwrap_or(8)
}

/// An integer in superscript digits (e.g. −3 → "⁻³").
pub fn superscript(n: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if n < 0 {
        s.push('⁻');
    }
    for c in n.unsigned_abs().to_string().chars() {
        s.push(DIGITS[c.to_digit(10).unwrap() as usize]);
    }
    s
}

/// A value to three significant digits, in short scientific notation (e.g. 3.2×10⁻⁴)
/// unless 0.01 ≤ |v| < 1000.
pub fn short_sci(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor() as i32;
    if (-2..3).contains(&e) {
        return format!("{:.*}", (2 - e).max(0) as usize, v);
    }
    let m = v / 10f64.powi(e);
    format!("{m:.2}×10{}", superscript(e))
}

const TEXT: [u8; 4] = [25, 25, 25, 255];
const FRAME: [u8; 4] = [70, 70, 70, 255];

/// Layout of a colour bar at a given font size.
struct BarLayout {
    bar_w: f32,
    tick_len: f32,
    gap: f32,
    labels_w: f32,
    label_h: f32,
}

fn layout(ticks: &[Tick], font_px: f32, label: &str) -> BarLayout {
    let labels_w = ticks
        .iter()
        .filter_map(|t| t.label.as_deref())
        .map(|l| text_width(l, font_px))
        .fold(0.0, f32::max);
    let m = text_metrics(font_px);
    BarLayout {
        bar_w: (1.1 * font_px).round(),
        tick_len: (0.35 * font_px).round().max(2.0),
        gap: (0.3 * font_px).round().max(2.0),
        labels_w: labels_w.ceil(),
        label_h: if label.is_empty() {
            0.0
        } else {
            (m.ascent + m.descent).ceil()
        },
    }
}

fn max_labels(height: f32, font_px: f32) -> usize {
    ((height / (2.6 * font_px)) as usize).clamp(2, 9)
}

/// Width a colour bar of `height` pixels with its labels needs.
pub fn colorbar_width(scale: &ColorScale, height: f32, font_px: f32, label: &str) -> f32 {
    let ticks = scale.ticks(max_labels(height, font_px));
    let l = layout(&ticks, font_px, label);
    let label_part = if label.is_empty() { 0.0 } else { 2.0 * l.gap + l.label_h };
    l.bar_w + l.tick_len + l.gap + l.labels_w + label_part
}

fn fill_rect(pixmap: &mut Pixmap, x: f32, y: f32, w: f32, h: f32, c: [u8; 4]) {
    if let Some(r) = Rect::from_xywh(x, y, w, h) {
        let mut p = Paint::default();
        p.set_color(Color::from_rgba8(c[0], c[1], c[2], c[3]));
        p.anti_alias = false;
        pixmap.fill_rect(r, &p, Transform::identity(), None);
    }
}

/// Draw a vertical colour bar with its top-left corner at (x, y): the gradient
/// (`height` pixels tall), ticks and labels on its right, and `label` (the quantity
/// and unit) written vertically beyond them. Uses [`colorbar_width`] pixels.
pub fn draw_colorbar(pixmap: &mut Pixmap, scale: &ColorScale, x: f32, y: f32, height: f32, font_px: f32, label: &str) {
    let (x, y, height) = (x.round(), y.round(), height.round());
    let ticks = scale.ticks(max_labels(height, font_px));
    let l = layout(&ticks, font_px, label);
    // The gradient: one colour per pixel row, top = max.
    let rows = height as i32;
    for r in 0..rows {
        let t = 1.0 - (r as f64 + 0.5) / rows as f64;
        let [cr, cg, cb] = viridis(t);
        fill_rect(pixmap, x, y + r as f32, l.bar_w, 1.0, [cr, cg, cb, 255]);
    }
    // Frame (1 px, outside the gradient).
    let frame = PathBuilder::from_rect(Rect::from_xywh(x - 0.5, y - 0.5, l.bar_w + 1.0, height + 1.0).unwrap());
    let mut p = Paint::default();
    p.set_color_rgba8(FRAME[0], FRAME[1], FRAME[2], FRAME[3]);
    let stroke = tiny_skia::Stroke {
        width: 1.0,
        ..Default::default()
    };
    pixmap.stroke_path(&frame, &p, &stroke, Transform::identity(), None);

    let right = x + l.bar_w;
    for t in &ticks {
        // Centre of the pixel row holding this value.
        let ty = (y + ((1.0 - t.t) * height as f64) as f32).clamp(y, y + height - 1.0);
        let len = if t.label.is_some() {
            l.tick_len
        } else {
            0.55 * l.tick_len
        };
        fill_rect(pixmap, right, ty.floor(), len.max(1.0), 1.0, FRAME);
        if let Some(text) = &t.label {
            let cy = ty.floor() + 0.5;
            draw_text_aligned(
                pixmap,
                text,
                right + l.tick_len + l.gap,
                cy,
                font_px,
                TEXT,
                HAlign::Left,
                VAlign::Middle,
            );
        }
    }
    if !label.is_empty() {
        let lx = right + l.tick_len + l.gap + l.labels_w + 2.0 * l.gap;
        draw_text_vertical(
            pixmap,
            label,
            lx,
            y + 0.5 * height,
            font_px,
            TEXT,
            HAlign::Center,
            VAlign::Top,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ranges at the ends of f64 (a field of 5·10⁻³²⁴ from σ_s = 5e-324, adjacent
    /// subnormals, a width that overflows) give a handful of finite ticks: they
    /// asked for 2³¹ (5.4 GB) before.
    #[test]
    fn extreme_ranges_give_few_ticks() {
        let cases = [
            ColorScale::auto([5e-324, 1e-323, 0.0], true),
            ColorScale::auto([5e-324, 1e-323], false),
            ColorScale::new(true, 0.0, 5e-324),
            ColorScale::new(false, 5e-324, 1e-323),
            ColorScale::new(false, -1e308, 1e308),
            ColorScale::new(true, 1e-300, 1e300),
            ColorScale::new(false, 1e300, 1.0000000000000002e300),
        ];
        for scale in cases {
            for n in [2, 8, 40] {
                let ticks = scale.ticks(n);
                assert!(ticks.len() <= 700, "{scale:?}: {} ticks", ticks.len());
                assert!(
                    ticks.iter().all(|t| t.value.is_finite() && t.t.is_finite()),
                    "{scale:?}"
                );
            }
            assert!(
                scale.min.is_finite() && scale.max.is_finite() && scale.min < scale.max,
                "{scale:?}"
            );
        }
    }

    fn labels(ticks: &[Tick]) -> Vec<String> {
        ticks.iter().filter_map(|t| t.label.clone()).collect()
    }

    #[test]
    fn auto_range_is_robust() {
        let mut v: Vec<f64> = (0..1000).map(|i| i as f64 / 1000.0).collect();
        v.push(1e9); // a firefly
        v.push(f64::NAN);
        let s = ColorScale::auto(v.iter().copied(), false);
        assert_eq!(s.min, 0.0);
        assert!((s.max - 0.995).abs() < 0.01, "{s:?}");
        let s = ColorScale::auto(v.iter().copied().map(|x| x + 1e-3), true);
        assert!(s.min > 0.0 && s.min < 0.02 && s.max < 1.1, "{s:?}");
        // Degenerate data still gives a usable range.
        for d in [vec![], vec![0.0; 5], vec![2.0; 5], vec![-1.0; 3]] {
            for log in [false, true] {
                let s = ColorScale::auto(d.iter().copied(), log);
                assert!(s.min < s.max && (!log || s.min > 0.0), "{d:?} {log}: {s:?}");
            }
        }
        assert_eq!(ColorScale::new(true, 0.0, 10.0).min, 1e-2);
    }

    #[test]
    fn normalize_and_invert() {
        let s = ColorScale::new(true, 1e-3, 10.0);
        assert!((s.normalize(1e-1) - 0.5).abs() < 1e-12);
        assert_eq!(s.normalize(-1.0), 0.0);
        assert_eq!(s.normalize(1e9), 1.0);
        assert!(s.normalize(f64::NAN).is_nan());
        assert!((s.value_at(0.5) - 0.1).abs() < 1e-12);
        let l = ColorScale::new(false, -2.0, 2.0);
        assert_eq!(l.normalize(0.0), 0.5);
    }

    #[test]
    fn tick_labels_read_well() {
        assert_eq!(
            labels(&ColorScale::new(false, 0.0, 1.0).ticks(6)),
            ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]
        );
        assert_eq!(
            labels(&ColorScale::new(false, 0.0, 37.0).ticks(5)),
            ["0", "10", "20", "30"]
        );
        assert_eq!(
            labels(&ColorScale::new(false, 0.0, 0.0042).ticks(5)),
            ["0", "2×10⁻³", "4×10⁻³"]
        );
        assert_eq!(
            labels(&ColorScale::new(true, 2e-4, 30.0).ticks(8)),
            ["10⁻³", "10⁻²", "10⁻¹", "10⁰", "10¹"]
        );
        assert_eq!(
            labels(&ColorScale::new(true, 1e-12, 1.0).ticks(5)),
            ["10⁻¹²", "10⁻⁹", "10⁻⁶", "10⁻³", "10⁰"]
        );
        assert_eq!(labels(&ColorScale::new(true, 0.15, 0.9).ticks(6)), ["0.2", "0.5"]);
        assert_eq!(
            labels(&ColorScale::new(true, 0.03, 0.7).ticks(6)),
            ["0.05", "0.1", "0.2", "0.5"]
        );
        assert_eq!(
            labels(&ColorScale::new(true, 1.5e-4, 9e-4).ticks(6)),
            ["2×10⁻⁴", "5×10⁻⁴"]
        );
        assert_eq!(labels(&ColorScale::new(true, 0.31, 0.39).ticks(6)), ["0.310", "0.390"]);
        let t = ColorScale::new(true, 1e-3, 1.0).ticks(8);
        assert!(t.iter().any(|t| t.label.is_none()), "minor ticks");
        assert!(t.windows(2).all(|w| w[0].t <= w[1].t));
        assert_eq!(short_sci(0.5), "0.500");
        assert_eq!(short_sci(12345.0), "1.23×10⁴");
    }

    #[test]
    fn colorbar_draws_within_its_width() {
        let s = ColorScale::new(true, 1e-3, 10.0);
        let w = colorbar_width(&s, 200.0, 12.0, "luminance");
        let mut p = Pixmap::new(200, 240).unwrap();
        draw_colorbar(&mut p, &s, 20.0, 20.0, 200.0, 12.0, "luminance");
        let mut xmax = 0;
        for y in 0..240 {
            for x in 0..200 {
                if p.pixel(x, y).unwrap().alpha() > 0 {
                    xmax = xmax.max(x);
                }
            }
        }
        assert!(
            (xmax as f32) < 20.0 + w + 1.0 && (xmax as f32) > 20.0 + 0.8 * w,
            "{xmax} vs {w}"
        );
        // Top of the bar is the top colour, bottom the bottom colour.
        let top = p.pixel(25, 20).unwrap();
        assert_eq!([top.red(), top.green(), top.blue()], viridis(1.0 - 0.5 / 200.0));
        let bottom = p.pixel(25, 219).unwrap();
        assert_eq!([bottom.red(), bottom.green(), bottom.blue()], viridis(0.5 / 200.0));
    }
}
