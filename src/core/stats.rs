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
    pub pixels: usize,
}

impl ImageErrors {
    /// From (test, reference) luminance pairs; all zero for none.
    pub fn of_luminance_pairs(pairs: &[(f64, f64)]) -> Self {
        if pairs.is_empty() {
            return ImageErrors::default();
        }
        let n = pairs.len() as f64;
        let mean_ref = pairs.iter().map(|p| p.1).sum::<f64>() / n;
        let floor = 0.01 * mean_ref * mean_ref;
        ImageErrors {
            rmse: (pairs.iter().map(|(a, b)| (a - b).powi(2)).sum::<f64>() / n).sqrt(),
            relmse: pairs
                .iter()
                .map(|(a, b)| (a - b).powi(2) / (b * b + floor).max(f64::MIN_POSITIVE))
                .sum::<f64>()
                / n,
            max_abs: pairs.iter().map(|(a, b)| (a - b).abs()).fold(0.0, f64::max),
            mean_reference: mean_ref,
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
