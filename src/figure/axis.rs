//! Plot axes: the shown range of an axis (explicit, or automatic from the data), the
//! data → pixel mapping, and tick positions and labels. Used by [`super::plot`].
//!
//! - Automatic range: the data's extent (finite values; positive ones on a log axis)
//!   grown by 5 % of the span on each side (of the span in decades on a log axis). A
//!   single value gets ±10 % (±1 around 0; ±½ decade on a log axis); no data gives
//!   [0, 1] (linear) or [1, 10] (log). An explicit range that is unusable (not
//!   finite, empty, or not positive on a log axis) is replaced by the automatic one.
//! - Linear ticks: multiples of a 1–2–5 × 10ⁿ step, written as plain decimals for
//!   moderate magnitudes (10⁻² ≤ |v| < 10⁵) and as m×10ⁿ otherwise.
//! - Log ticks: decades labelled 10ⁿ with unlabelled minor ticks at 2…9 × 10ⁿ (the
//!   rules of [`ColorScale::ticks`]: fewer labels for many decades, 1–2–5 labels
//!   when the range spans less than two decades).

use super::colorbar::{ColorScale, superscript};

/// How data values are placed along an axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    Linear,
    /// Logarithmic (base 10); values ≤ 0 are not shown.
    Log10,
}

/// One axis of a plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Quantity and unit ("" for none: no room is reserved for it).
    pub label: String,
    pub scale: Scale,
    /// Shown range (lo < hi); automatic from the data when None.
    pub range: Option<(f64, f64)>,
}

impl Axis {
    pub fn linear(label: &str) -> Self {
        Axis {
            label: label.to_string(),
            scale: Scale::Linear,
            range: None,
        }
    }

    pub fn log10(label: &str) -> Self {
        Axis {
            label: label.to_string(),
            scale: Scale::Log10,
            range: None,
        }
    }

    pub fn with_range(mut self, lo: f64, hi: f64) -> Self {
        self.range = Some((lo, hi));
        self
    }

    /// The range shown for data `values`: see the module documentation.
    pub fn resolve(&self, values: impl IntoIterator<Item = f64>) -> (f64, f64) {
        let log = self.scale == Scale::Log10;
        if let Some((lo, hi)) = self.range
            && lo.is_finite()
            && hi.is_finite()
            && lo < hi
            && (!log || lo > 0.0)
        {
            return (lo, hi);
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values {
            if v.is_finite() && (!log || v > 0.0) {
                let v = if log { v.log10() } else { v };
                (lo, hi) = (lo.min(v), hi.max(v));
            }
        }
        // (In decades on a log axis: no data shows [1, 10].)
        let (lo, hi) = if lo > hi {
            (0.0, 1.0)
        } else if lo == hi {
            let d = if log {
                0.5
            } else if lo == 0.0 {
                1.0
            } else {
                0.1 * lo.abs()
            };
            (lo - d, hi + d)
        } else {
            let m = 0.05 * (hi - lo);
            (lo - m, hi + m)
        };
        if log {
            (10f64.powf(lo), 10f64.powf(hi))
        } else {
            (lo, hi)
        }
    }
}

/// Data → pixel mapping of one axis: `lo` maps to pixel `p0`, `hi` to `p1` (for a
/// vertical axis p0 is the bottom, so p1 < p0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisMap {
    pub lo: f64,
    pub hi: f64,
    pub scale: Scale,
    pub p0: f64,
    pub p1: f64,
}

impl AxisMap {
    /// Position of `v` along the axis, 0 at lo and 1 at hi (not clamped); None for
    /// values that cannot be shown (non-finite, or ≤ 0 on a log axis).
    pub fn fraction(&self, v: f64) -> Option<f64> {
        let t = match self.scale {
            Scale::Linear => (v - self.lo) / (self.hi - self.lo),
            Scale::Log10 if v > 0.0 => (v / self.lo).log10() / (self.hi / self.lo).log10(),
            Scale::Log10 => return None,
        };
        t.is_finite().then_some(t)
    }

    /// Pixel coordinate of `v` (None as for [`AxisMap::fraction`]).
    pub fn to_pixel(&self, v: f64) -> Option<f64> {
        self.fraction(v).map(|t| self.p0 + t * (self.p1 - self.p0))
    }

    /// Does the axis show `v` (within the range, ends included)?
    pub fn contains(&self, v: f64) -> bool {
        self.fraction(v).is_some_and(|t| (-1e-9..=1.0 + 1e-9).contains(&t))
    }

    /// Ticks with room for about `max_labels` labels.
    pub fn ticks(&self, max_labels: usize) -> Vec<AxisTick> {
        axis_ticks(self.lo, self.hi, self.scale, max_labels)
    }
}

/// A tick of an axis; minor ticks have no label.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisTick {
    pub value: f64,
    pub label: Option<String>,
}

/// Ticks of the range [lo, hi] with room for about `max_labels` labels, ascending.
pub fn axis_ticks(lo: f64, hi: f64, scale: Scale, max_labels: usize) -> Vec<AxisTick> {
    match scale {
        Scale::Linear => linear_ticks(lo, hi, max_labels),
        Scale::Log10 => log_ticks(lo, hi, max_labels),
    }
}

/// The smallest of 1, 2, 5 × 10ⁿ at least `raw`.
pub fn nice_step(raw: f64) -> f64 {
    let raw = if raw.is_finite() && raw > 0.0 { raw } else { 1.0 };
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .find(|&c| c >= m * (1.0 - 1e-9))
        .unwrap_or(10.0)
        * p
}

/// Decimals needed to print multiples of `step` exactly.
fn decimals_for(step: f64) -> usize {
    (0..10)
        .find(|&d| {
            let s = step * 10f64.powi(d as i32);
            (s.round() - s).abs() < 1e-6 * s.abs().max(1.0)
        })
        .unwrap_or(10)
}

/// Labelled ticks at multiples of a 1–2–5 step.
pub fn linear_ticks(lo: f64, hi: f64, max_labels: usize) -> Vec<AxisTick> {
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Vec::new();
    }
    let step = nice_step((hi - lo) / (max_labels.max(2) - 1) as f64);
    let (first, last) = ((lo / step - 1e-9).ceil() as i64, (hi / step + 1e-9).floor() as i64);
    let magnitude = lo.abs().max(hi.abs());
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
            let m = format!("{:.*}", decimals, v / unit);
            let label = if k == 0 {
                "0".to_string()
            } else if exponent == 0 {
                m
            } else {
                format!("{m}×10{}", superscript(exponent))
            };
            AxisTick {
                value: v,
                label: Some(label),
            }
        })
        .collect()
}

/// Decades and minor ticks (see the module documentation).
pub fn log_ticks(lo: f64, hi: f64, max_labels: usize) -> Vec<AxisTick> {
    if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi) {
        return Vec::new();
    }
    ColorScale::new(true, lo, hi)
        .ticks(max_labels)
        .into_iter()
        .map(|t| AxisTick {
            value: t.value,
            label: t.label,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(ticks: &[AxisTick]) -> Vec<String> {
        ticks.iter().filter_map(|t| t.label.clone()).collect()
    }

    #[test]
    fn linear_ticks_use_1_2_5_steps() {
        assert_eq!(
            labels(&linear_ticks(0.0, 1.0, 6)),
            ["0", "0.2", "0.4", "0.6", "0.8", "1.0"]
        );
        assert_eq!(labels(&linear_ticks(-3.7, 12.0, 5)), ["0", "5", "10"]);
        assert_eq!(labels(&linear_ticks(-0.9, 0.9, 5)), ["-0.5", "0", "0.5"]);
        assert_eq!(labels(&linear_ticks(0.0, 0.0042, 5)), ["0", "2×10⁻³", "4×10⁻³"]);
        assert_eq!(labels(&linear_ticks(0.0, 2.4e5, 4)), ["0", "1×10⁵", "2×10⁵"]);
        for (lo, hi, n) in [(0.0, 1.0, 2), (-1e-7, 3e-7, 6), (1.0001, 1.0002, 5), (-5e3, 5e3, 9)] {
            let t = linear_ticks(lo, hi, n);
            assert!(t.len() >= 2 && t.len() <= 2 * n + 1, "{lo} {hi}: {t:?}");
            assert!(t.windows(2).all(|w| w[0].value < w[1].value));
            assert!(t.iter().all(|t| t.value >= lo - 1e-12 && t.value <= hi + 1e-12));
        }
        assert_eq!(nice_step(0.3), 0.5);
        assert_eq!(nice_step(7.0), 10.0);
        assert!(linear_ticks(1.0, 1.0, 5).is_empty());
    }

    #[test]
    fn log_ticks_are_decades_with_minor_ticks() {
        let t = log_ticks(2e-4, 30.0, 8);
        assert_eq!(labels(&t), ["10⁻³", "10⁻²", "10⁻¹", "10⁰", "10¹"]);
        assert!(t.iter().any(|t| t.label.is_none() && (t.value - 3e-3).abs() < 1e-12));
        assert!(t.windows(2).all(|w| w[0].value < w[1].value));
        // Many decades: fewer labels, still every decade ticked.
        let t = log_ticks(1e-12, 1.0, 5);
        assert_eq!(labels(&t), ["10⁻¹²", "10⁻⁹", "10⁻⁶", "10⁻³", "10⁰"]);
        assert_eq!(t.len(), 13);
        // Under a decade: 1–2–5 labels.
        assert_eq!(labels(&log_ticks(0.15, 0.9, 6)), ["0.2", "0.5"]);
        assert!(log_ticks(-1.0, 1.0, 5).is_empty());
    }

    #[test]
    fn ranges_are_resolved() {
        let lin = Axis::linear("x");
        assert_eq!(lin.resolve([0.0, 10.0, f64::NAN, f64::INFINITY]), (-0.5, 10.5));
        assert_eq!(lin.resolve([]), (0.0, 1.0));
        assert_eq!(lin.resolve([0.0]), (-1.0, 1.0));
        assert_eq!(lin.resolve([2.0, 2.0]), (1.8, 2.2));
        assert_eq!(lin.clone().with_range(-1.0, 3.0).resolve([100.0]), (-1.0, 3.0));
        assert_eq!(lin.with_range(3.0, 3.0).resolve([0.0, 10.0]), (-0.5, 10.5));
        let log = Axis::log10("y");
        let (lo, hi) = log.resolve([1e-3, 0.0, -5.0, 10.0]);
        assert!(
            (lo.log10() + 3.2).abs() < 1e-9 && (hi.log10() - 1.2).abs() < 1e-9,
            "{lo} {hi}"
        );
        assert_eq!(log.resolve([-1.0]), (1.0, 10.0));
        // An unusable log range (lo = 0) falls back to the data: 0.5..5 grown by 5 %.
        let (lo, hi) = log.clone().with_range(0.0, 1.0).resolve([0.5, 5.0]);
        assert!(
            (lo.log10() - (0.5f64.log10() - 0.05)).abs() < 1e-12 && (hi.log10() - (5f64.log10() + 0.05)).abs() < 1e-12
        );
        let m = AxisMap {
            lo: 1e-2,
            hi: 1e2,
            scale: Scale::Log10,
            p0: 100.0,
            p1: 0.0,
        };
        assert_eq!(m.to_pixel(1.0), Some(50.0));
        assert_eq!(m.to_pixel(0.0), None);
        assert_eq!(m.to_pixel(f64::NAN), None);
        assert!(m.contains(1e2) && !m.contains(1e3));
    }
}
