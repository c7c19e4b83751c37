//! Error measures and running statistics.

/// Welford running mean and variance.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunningStats {
    pub n: u64,
    mean: f64,
    m2: f64,
}

impl RunningStats {
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Unbiased sample variance.
    pub fn variance(&self) -> f64 {
        if self.n < 2 { 0.0 } else { self.m2 / (self.n - 1) as f64 }
    }

    /// Standard error of the mean.
    pub fn std_error(&self) -> f64 {
        (self.variance() / self.n.max(1) as f64).sqrt()
    }
}

/// Root mean square error between two equally sized slices.
pub fn rmse(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    if a.is_empty() {
        return 0.0;
    }
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

/// Errors of an image (or field) against a reference, over the pixels compared
/// (luminance).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ImageErrors {
    pub rmse: f64,
    /// Mean of (a − b)² / (b² + 0.01·mean(b)²): relative, robust where b → 0.
    pub relmse: f64,
    pub max_abs: f64,
    pub mean_reference: f64,
    /// Mean of a − b: the part of the error that no averaging over pixels removes
    /// (a method's bias shows here; noise and extrapolation errors of either
    /// sign mostly cancel). Its share of the RMSE says whether more samples or
    /// records can help.
    #[serde(default)]
    pub bias: f64,
    pub pixels: usize,
}

impl ImageErrors {
    /// From (test, reference) luminance pairs; all zero for none.
    ///
    /// Computed on values divided by the largest |value| (every measure is
    /// homogeneous, so this changes nothing but keeps squares of 10³⁰⁰ or 10⁻³⁰⁰ in
    /// range). Where the reference is zero everywhere its mean gives no floor for
    /// relMSE: the test's mean does instead, and an all-zero pair of images has
    /// relMSE 0 (not (a − b)²/f64::MIN_POSITIVE, ~10³⁰³).
    pub fn of_luminance_pairs(pairs: &[(f64, f64)]) -> Self {
        if pairs.is_empty() {
            return ImageErrors::default();
        }
        let n = pairs.len() as f64;
        let scale = pairs.iter().fold(0.0f64, |m, (a, b)| m.max(a.abs()).max(b.abs()));
        let s = if scale > 0.0 && scale.is_finite() { scale } else { 1.0 };
        let mean = |f: fn(&(f64, f64)) -> f64| pairs.iter().map(|p| f(p) / s).sum::<f64>() / n;
        let mean_ref = mean(|p| p.1);
        let floor_mean = if mean_ref != 0.0 { mean_ref } else { mean(|p| p.0.abs()) };
        let floor = 0.01 * floor_mean * floor_mean;
        let relmse = pairs
            .iter()
            .map(|(a, b)| {
                let (a, b) = (a / s, b / s);
                let den = b * b + floor;
                if den > 0.0 { (a - b).powi(2) / den } else { 0.0 }
            })
            .sum::<f64>()
            / n;
        ImageErrors {
            rmse: s * (pairs.iter().map(|(a, b)| ((a - b) / s).powi(2)).sum::<f64>() / n).sqrt(),
            relmse,
            max_abs: pairs.iter().map(|(a, b)| (a - b).abs()).fold(0.0, f64::max),
            mean_reference: mean_ref * s,
            bias: s * mean(|p| p.0 - p.1),
            pixels: pairs.len(),
        }
    }
}

/// Luminance errors of an image against a reference of the same size.
pub fn luminance_errors(values: &[crate::core::color::Rgb], reference: &[crate::core::color::Rgb]) -> ImageErrors {
    use crate::core::color::luminance;
    let pairs: Vec<(f64, f64)> = values
        .iter()
        .zip(reference)
        .map(|(a, b)| (luminance(*a), luminance(*b)))
        .collect();
    ImageErrors::of_luminance_pairs(&pairs)
}

/// The time a method needs to reach error `e`, from its (time, error) runs: on the
/// Pareto front (runs no faster run beats), interpolated log-log between the last
/// run above `e` and the first at or below it. None when no run reaches `e`, or
/// every run is already below it (the curve says nothing there).
pub fn time_to_error(runs: &[(f64, f64)], e: f64) -> Option<f64> {
    let mut sorted: Vec<(f64, f64)> = runs
        .iter()
        .copied()
        .filter(|(t, err)| *t > 0.0 && *err > 0.0 && t.is_finite() && err.is_finite())
        .collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for p in sorted {
        if front.last().is_none_or(|l| p.1 < l.1) {
            front.push(p);
        }
    }
    let k = front.iter().position(|p| p.1 <= e)?;
    if k == 0 {
        return None;
    }
    let ((t0, e0), (t1, e1)) = (front[k - 1], front[k]);
    let f = (e.ln() - e0.ln()) / (e1.ln() - e0.ln());
    Some((t0.ln() + f * (t1.ln() - t0.ln())).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass() {
        let xs = [1.0, 2.0, 4.0, 7.0, 11.0];
        let mut s = RunningStats::default();
        xs.iter().for_each(|&x| s.push(x));
        let mean = xs.iter().sum::<f64>() / 5.0;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 4.0;
        assert!((s.mean() - mean).abs() < 1e-12);
        assert!((s.variance() - var).abs() < 1e-12);
        assert_eq!(rmse(&[1.0, 2.0], &[1.0, 4.0]), 2f64.sqrt());
    }

    /// relMSE against an all-zero reference is finite (it was up to 6.5·10³⁰³ or
    /// inf), and the measures are unchanged by a common scale, even at 10±³⁰⁰.
    #[test]
    fn errors_stay_finite_at_extremes() {
        let zero = ImageErrors::of_luminance_pairs(&[(0.0, 0.0), (0.0, 0.0)]);
        assert_eq!((zero.rmse, zero.relmse), (0.0, 0.0));
        let e = ImageErrors::of_luminance_pairs(&[(1.0, 0.0), (3.0, 0.0)]);
        // Floor: 0.01 × mean(test)² = 0.04, so (1 + 9) / 0.04 / 2.
        assert!((e.relmse - 125.0).abs() < 1e-12, "{e:?}");
        let base = [(1.0, 2.0), (3.0, 2.5), (0.0, 0.5)];
        let want = ImageErrors::of_luminance_pairs(&base);
        for k in [1e-300, 1e300, 5e-324 / 0.5] {
            let scaled: Vec<(f64, f64)> = base.iter().map(|(a, b)| (a * k, b * k)).collect();
            let e = ImageErrors::of_luminance_pairs(&scaled);
            assert!(e.rmse.is_finite() && e.relmse.is_finite(), "{k}: {e:?}");
            if k > 1e-320 {
                assert!((e.rmse / k / want.rmse - 1.0).abs() < 1e-12, "{k}: {e:?}");
                assert!((e.relmse / want.relmse - 1.0).abs() < 1e-12, "{k}: {e:?}");
            }
        }
    }

    /// The bias is the signed mean difference: errors of both signs cancel in it,
    /// a constant offset is all of it; it keeps its sign and scale at 10^±300.
    #[test]
    fn bias_is_the_mean_difference() {
        let e = ImageErrors::of_luminance_pairs(&[(1.5, 1.0), (0.5, 1.0), (2.25, 2.0)]);
        assert!((e.bias - 0.25 / 3.0).abs() < 1e-15, "{e:?}");
        let shifted = ImageErrors::of_luminance_pairs(&[(1.1, 1.0), (2.1, 2.0)]);
        assert!((shifted.bias - shifted.rmse).abs() < 1e-12, "{shifted:?}");
        let tiny = ImageErrors::of_luminance_pairs(&[(0.9e-300, 1e-300)]);
        assert!((tiny.bias / -1e-301 - 1.0).abs() < 1e-9, "{tiny:?}");
    }

    #[test]
    fn time_to_error_on_the_pareto_front() {
        // error = 1/√t, with a dominated run (slower and worse) ignored.
        let runs = [(1.0, 1.0), (4.0, 0.5), (9.0, 0.8), (16.0, 0.25)];
        assert!((time_to_error(&runs, 0.5).unwrap() - 4.0).abs() < 1e-12);
        // Log-log interpolation is exact on a power law.
        assert!((time_to_error(&runs, 0.35355339059327373).unwrap() - 8.0).abs() < 1e-9);
        assert_eq!(time_to_error(&runs, 0.1), None);
        assert_eq!(time_to_error(&runs, 2.0), None);
    }
}
