//! The speed-up of ours over Jarosz 2008 at equal error, from their (time, error)
//! curves: at each error Jarosz 2008 reached on its Pareto front (no faster run of
//! its beats it), the time ours needs for it, interpolated on ours' front
//! ([`time_to_error`]). Where ours' fastest run is already below that error, that
//! run's time bounds the speed-up from below; errors ours never reaches give none.

use super::runs3d::{Run3d, curve};
use crate::core::stats::time_to_error;
use serde::Serialize;

/// Both methods' times at one error, and their ratio.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Speedup {
    /// Which error: "image" or "medium".
    pub of: &'static str,
    pub error: f64,
    pub seconds_ours: f64,
    pub seconds_jarosz08: f64,
    /// seconds_jarosz08 / seconds_ours.
    pub speedup: f64,
    /// True when ours' fastest run is already below `error`: then `seconds_ours` is
    /// that run's time and `speedup` a lower bound.
    pub lower_bound: bool,
}

/// The speed-ups at Jarosz 2008's errors, from (seconds, error) runs sorted by time.
pub fn speedups_of(of: &'static str, ours: &[(f64, f64)], jarosz: &[(f64, f64)]) -> Vec<Speedup> {
    let mut out = Vec::new();
    for (i, &(tj, e)) in jarosz.iter().enumerate() {
        // A slower run with a larger error says nothing about the time that error needs.
        if jarosz[..i].iter().any(|p| p.1 <= e) {
            continue;
        }
        let (to, lower_bound) = match (time_to_error(ours, e), ours.first()) {
            (Some(to), _) => (to, false),
            (None, Some(&(t0, e0))) if e0 <= e => (t0, true),
            _ => continue,
        };
        out.push(Speedup {
            of,
            error: e,
            seconds_ours: to,
            seconds_jarosz08: tj,
            speedup: tj / to,
            lower_bound,
        });
    }
    out
}

/// The speed-ups of a 3D sweep, for the image's error and then its medium part's.
pub fn speedups(runs: &[Run3d]) -> Vec<Speedup> {
    [("image", false), ("medium", true)]
        .into_iter()
        .flat_map(|(of, medium)| {
            let ours = curve(runs, "ours", |r| r.seconds, medium);
            let jarosz = curve(runs, "jarosz08", |r| r.seconds, medium);
            speedups_of(of, &ours, &jarosz)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speedups_at_jarosz_pareto_runs_with_lower_bounds() {
        // The staircase's medium errors (results/tradeoff3d_staircase.json), rounded.
        let ours = [(6.4, 0.0185), (7.8, 0.0176), (12.9, 0.0154), (20.7, 0.0109)];
        let jarosz = [
            (7.2, 0.0268),
            (8.9, 0.0180),
            (13.0, 0.0228),
            (21.4, 0.0174),
            (67.7, 0.0182),
        ];
        let s = speedups_of("medium", &ours, &jarosz);
        let errors: Vec<f64> = s.iter().map(|s| s.error).collect();
        assert_eq!(errors, [0.0268, 0.0180, 0.0174], "dominated runs skipped");
        // 0.0268: ours' fastest run is already below it, so only a lower bound.
        assert!(s[0].lower_bound && s[0].seconds_ours == 6.4);
        assert!((s[0].speedup - 7.2 / 6.4).abs() < 1e-12);
        // 0.0180: interpolated log-log between ours' first two runs.
        assert!(!s[1].lower_bound && s[1].seconds_ours > 6.4 && s[1].seconds_ours < 7.8);
        assert!(s[1].speedup > 1.1 && s[1].speedup < 1.4, "{}", s[1].speedup);
        assert!(s[2].speedup > 2.4 && s[2].speedup < 2.9, "{}", s[2].speedup);
        // Errors ours never reaches give nothing.
        assert!(speedups_of("medium", &[(10.0, 0.05)], &jarosz).is_empty());
    }

    /// On power laws error = c/√t the rule is exact: ours at half the constant is 4×
    /// faster at every error.
    #[test]
    fn a_known_fourfold_speedup() {
        let runs: Vec<(f64, f64)> = [1.0, 4.0, 16.0, 64.0]
            .iter()
            .map(|&t| (t, 0.5 / f64::sqrt(t)))
            .collect();
        let jarosz: Vec<(f64, f64)> = [16.0, 64.0, 256.0].iter().map(|&t| (t, 1.0 / f64::sqrt(t))).collect();
        let s = speedups_of("image", &runs, &jarosz);
        assert_eq!(s.len(), 3);
        for x in &s {
            assert!(!x.lower_bound && (x.speedup - 4.0).abs() < 1e-9, "{x:?}");
        }
        // Where Jarosz 2008 is no better than ours' fastest run, only a lower bound.
        let s = speedups_of("image", &runs, &[(4.0, 0.5)]);
        assert!(s[0].lower_bound && s[0].seconds_ours == 1.0 && s[0].speedup == 4.0);
    }
}
