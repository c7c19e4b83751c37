//! Time to a target error: how long each method's (time, RMSE) curve needs to reach
//! 3%, 1% and 0.3% relative RMSE (RMSE over the reference's mean), and the ratios
//! path tracing / ours and Jarosz 2008 / ours at each target — the table users read
//! to decide whether a cache pays for itself.
//!
//! The reference has noise of its own. A measured RMSE m of an image whose own error
//! is e against a reference with RMS noise r (independent of it) is √(e² + r²) in
//! expectation, so every curve is judged by √(m² − r²), and a target below r is
//! reported as not measurable: no run could be shown to reach it or to miss it.

use super::reference3d::ReferenceInfo3d;
use super::runs3d::{Run3d, curve};
use crate::core::stats::time_to_error;
use serde::Serialize;

/// The relative RMSE targets of the table.
pub const RELATIVE_TARGETS: [f64; 3] = [0.03, 0.01, 0.003];

/// The time one method needs for a target error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum TimeTo {
    /// Interpolated (log-log) between its runs on either side of the error.
    Reached { seconds: f64 },
    /// Its fastest run is already below the error: it needs at most this.
    AtMost { seconds: f64 },
    /// None of its runs reached it; the longest took this.
    NotReached { longest: f64 },
}

/// How a ratio of two [`TimeTo`]s is known.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    Exact,
    AtLeast,
    AtMost,
}

/// other's time / ours' time at one target.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Ratio {
    pub value: f64,
    pub bound: Bound,
}

/// One method's time to a target.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodTime {
    pub method: String,
    #[serde(flatten)]
    pub time: TimeTo,
}

/// One target of one error (image, medium part or field).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TargetRow {
    pub of: &'static str,
    /// The target as a fraction of the reference's mean.
    pub relative: f64,
    /// The target as an RMSE.
    pub error: f64,
    /// The reference's own RMS noise the curves were corrected by.
    pub reference_noise: f64,
    /// False when the target is below the reference's noise; then no times are given.
    pub measurable: bool,
    /// Per method (in the order given), its time to the target.
    pub times: Vec<MethodTime>,
    pub pt_over_ours: Option<Ratio>,
    pub jarosz08_over_ours: Option<Ratio>,
}

/// `runs` (seconds, measured RMSE) with the reference's noise `noise` removed:
/// √(m² − r²), a run within the noise counting as error zero (it reaches every
/// measurable target).
pub fn corrected(runs: &[(f64, f64)], noise: f64) -> Vec<(f64, f64)> {
    runs.iter()
        .map(|&(t, m)| (t, (m * m - noise * noise).max(0.0).sqrt().max(f64::MIN_POSITIVE)))
        .collect()
}

/// The time a method with (seconds, error) `runs` needs for `error`; None without runs.
pub fn time_to(runs: &[(f64, f64)], error: f64) -> Option<TimeTo> {
    let usable: Vec<(f64, f64)> = runs
        .iter()
        .copied()
        .filter(|(t, e)| t.is_finite() && *t > 0.0 && e.is_finite())
        .collect();
    let fastest = usable.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0))?;
    if fastest.1 <= error {
        return Some(TimeTo::AtMost { seconds: fastest.0 });
    }
    Some(match time_to_error(&usable, error) {
        Some(seconds) => TimeTo::Reached { seconds },
        None => TimeTo::NotReached {
            longest: usable.iter().map(|r| r.0).fold(0.0, f64::max),
        },
    })
}

/// other / ours, with what is known of it when either time is only bounded.
pub fn ratio(other: TimeTo, ours: TimeTo) -> Option<Ratio> {
    use TimeTo::*;
    let (value, bound) = match (other, ours) {
        (Reached { seconds: o }, Reached { seconds: u }) => (o / u, Bound::Exact),
        (Reached { seconds: o } | NotReached { longest: o }, AtMost { seconds: u }) => (o / u, Bound::AtLeast),
        (NotReached { longest: o }, Reached { seconds: u }) => (o / u, Bound::AtLeast),
        (Reached { seconds: o } | AtMost { seconds: o }, NotReached { longest: u }) => (o / u, Bound::AtMost),
        (AtMost { seconds: o }, Reached { seconds: u }) => (o / u, Bound::AtMost),
        (AtMost { .. }, AtMost { .. }) | (NotReached { .. }, NotReached { .. }) => return None,
    };
    Some(Ratio { value, bound })
}

/// The table rows of one error: `curves` are (method, runs of (seconds, measured
/// RMSE)), `mean` the reference's mean, `noise` its RMS noise. Methods are named
/// "ours", "jarosz08" and "pt" for the ratios.
pub fn target_rows(of: &'static str, curves: &[(&str, Vec<(f64, f64)>)], mean: f64, noise: f64) -> Vec<TargetRow> {
    let corrected: Vec<(&str, Vec<(f64, f64)>)> = curves.iter().map(|(m, r)| (*m, corrected(r, noise))).collect();
    RELATIVE_TARGETS
        .iter()
        .map(|&relative| {
            let error = relative * mean;
            let measurable = error > noise && error > 0.0;
            let times: Vec<MethodTime> = if measurable {
                corrected
                    .iter()
                    .filter_map(|(m, r)| {
                        Some(MethodTime {
                            method: m.to_string(),
                            time: time_to(r, error)?,
                        })
                    })
                    .collect()
            } else {
                Vec::new()
            };
            let of_method = |name: &str| times.iter().find(|t| t.method == name).map(|t| t.time);
            let over_ours = |name: &str| ratio(of_method(name)?, of_method("ours")?);
            TargetRow {
                of,
                relative,
                error,
                reference_noise: noise,
                measurable,
                pt_over_ours: over_ours("pt"),
                jarosz08_over_ours: over_ours("jarosz08"),
                times,
            }
        })
        .collect()
}

/// The RMS noise of a reference of `ref_spp` samples per pixel, from path-traced
/// runs of the same estimator: a run of s samples measures m² = a/s + a/S in
/// expectation (its noise and the reference's, per-sample variance a), so
/// r² = a/S; the median over the runs. None without runs.
pub fn noise_from_pt(runs: &[(u32, f64)], ref_spp: u32) -> Option<f64> {
    let big_s = ref_spp.max(1) as f64;
    let mut a: Vec<f64> = runs
        .iter()
        .filter(|(s, m)| *s > 0 && m.is_finite())
        .map(|&(s, m)| m * m / (1.0 / s as f64 + 1.0 / big_s))
        .collect();
    if a.is_empty() {
        return None;
    }
    a.sort_by(f64::total_cmp);
    let med = if a.len() % 2 == 1 {
        a[a.len() / 2]
    } else {
        0.5 * (a[a.len() / 2 - 1] + a[a.len() / 2])
    };
    Some((med / big_s).sqrt())
}

/// The rows of a 3D sweep: the image's error (its reference's noise from the
/// reference's own per-pixel standard errors) and the medium part's (its noise from
/// the path-traced runs, [`noise_from_pt`]; zero without any).
pub fn rows_3d(runs: &[Run3d], reference: &ReferenceInfo3d) -> Vec<TargetRow> {
    let Some(first) = runs.first() else {
        return Vec::new();
    };
    let methods = ["ours", "jarosz08", "pt"];
    let curves = |medium: bool| -> Vec<(&str, Vec<(f64, f64)>)> {
        methods
            .iter()
            .map(|&m| (m, curve(runs, m, |r| r.seconds, medium)))
            .filter(|c| !c.1.is_empty())
            .collect()
    };
    let image_mean = first.errors.mean_reference;
    let image_noise = reference.relative_std_error * image_mean;
    let pt: Vec<(u32, f64)> = runs
        .iter()
        .filter(|r| r.method == "pt")
        .map(|r| (r.spp, r.medium_errors.rmse))
        .collect();
    let medium_noise = noise_from_pt(&pt, reference.spp).unwrap_or(0.0);
    let mut rows = target_rows("image", &curves(false), image_mean, image_noise);
    rows.extend(target_rows(
        "medium",
        &curves(true),
        first.medium_errors.mean_reference,
        medium_noise,
    ));
    rows
}

/// The rows as a plain-text table, one line per target.
pub fn table_text(rows: &[TargetRow]) -> String {
    let time = |t: &TimeTo| match *t {
        TimeTo::Reached { seconds } => format!("{seconds:.1} s"),
        TimeTo::AtMost { seconds } => format!("≤ {seconds:.1} s"),
        TimeTo::NotReached { longest } => format!("not in {longest:.0} s"),
    };
    let ratio = |r: &Option<Ratio>| match r {
        None => "–".to_string(),
        Some(Ratio { value, bound }) => {
            let b = match bound {
                Bound::Exact => "",
                Bound::AtLeast => "≥ ",
                Bound::AtMost => "≤ ",
            };
            format!("{b}{value:.2}×")
        }
    };
    let mut out = String::new();
    for r in rows {
        let head = format!("{} {:>4.1}% (RMSE {:.2e})", r.of, 100.0 * r.relative, r.error);
        if !r.measurable {
            out += &format!(
                "{head}: below the reference's noise ({:.2e}): not measurable\n",
                r.reference_noise
            );
            continue;
        }
        let times: Vec<String> = r
            .times
            .iter()
            .map(|t| format!("{} {}", t.method, time(&t.time)))
            .collect();
        out += &format!(
            "{head}: {}; pt/ours {}, jarosz08/ours {}\n",
            times.join(", "),
            ratio(&r.pt_over_ours),
            ratio(&r.jarosz08_over_ours)
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn power_law(c: f64, times: &[f64]) -> Vec<(f64, f64)> {
        times.iter().map(|&t| (t, c / t.sqrt())).collect()
    }

    /// Error c/√t: the time to error e is (c/e)², so a method at half the constant
    /// is 4× faster at every target, and the rows say so exactly.
    #[test]
    fn a_known_fourfold_ratio_at_every_target() {
        let times = [1.0, 4.0, 16.0, 64.0, 256.0, 1024.0, 4096.0, 16384.0, 65536.0];
        let curves = [("ours", power_law(0.05, &times)), ("pt", power_law(0.1, &times))];
        let rows = target_rows("image", &curves, 1.0, 0.0);
        assert_eq!(rows.len(), 3);
        for r in &rows {
            assert!(r.measurable);
            let TimeTo::Reached { seconds } = r.times[0].time else {
                panic!("{r:?}")
            };
            assert!((seconds - (0.05 / r.error).powi(2)).abs() < 1e-9 * seconds, "{r:?}");
            let p = r.pt_over_ours.unwrap();
            assert!(p.bound == Bound::Exact && (p.value - 4.0).abs() < 1e-9, "{p:?}");
            assert!(r.jarosz08_over_ours.is_none());
        }
    }

    #[test]
    fn bounds_when_a_curve_starts_below_or_ends_above_the_target() {
        let ours = [(2.0, 0.005), (8.0, 0.0025)];
        let pt = [(1.0, 0.05), (4.0, 0.02)];
        // 1%: ours' fastest run is below it, pt never gets there.
        assert_eq!(time_to(&ours, 0.01), Some(TimeTo::AtMost { seconds: 2.0 }));
        assert_eq!(time_to(&pt, 0.01), Some(TimeTo::NotReached { longest: 4.0 }));
        let r = ratio(time_to(&pt, 0.01).unwrap(), time_to(&ours, 0.01).unwrap()).unwrap();
        assert_eq!((r.value, r.bound), (2.0, Bound::AtLeast));
        // 0.1%: neither reaches it: no ratio.
        assert_eq!(
            ratio(time_to(&pt, 0.001).unwrap(), time_to(&ours, 0.001).unwrap()),
            None
        );
        assert_eq!(time_to(&[], 0.01), None);
    }

    /// A target below the reference's noise is not measurable; above it, the
    /// corrected curve decides: m = √(e² + r²) with e = 0.5/√t reaches e exactly.
    #[test]
    fn the_reference_noise_is_removed_and_bounds_the_targets() {
        let r = 0.004;
        let times = [1.0, 10.0, 100.0, 1000.0, 10000.0];
        let measured: Vec<(f64, f64)> = times
            .iter()
            .map(|&t| {
                let e = 0.5 / f64::sqrt(t);
                (t, (e * e + r * r).sqrt())
            })
            .collect();
        let rows = target_rows("medium", &[("pt", measured)], 1.0, r);
        assert!(rows[0].measurable && rows[1].measurable && !rows[2].measurable);
        assert!(rows[2].times.is_empty());
        let TimeTo::Reached { seconds } = rows[1].times[0].time else {
            panic!("{rows:?}")
        };
        // e = 0.01 at t = 2500; log-log interpolation between 1000 and 10000 of an
        // exact power law is exact.
        assert!((seconds - 2500.0).abs() < 1e-6, "{seconds}");
        assert!(table_text(&rows).contains("not measurable"));
    }

    /// Path-traced runs of s samples against a reference of S measure
    /// m² = a(1/s + 1/S): the reference's noise √(a/S) comes back exactly.
    #[test]
    fn reference_noise_from_path_traced_runs() {
        let (a, big_s) = (0.09_f64, 8192);
        let runs: Vec<(u32, f64)> = [4u32, 64, 1024]
            .iter()
            .map(|&s| (s, (a * (1.0 / s as f64 + 1.0 / big_s as f64)).sqrt()))
            .collect();
        let r = noise_from_pt(&runs, big_s).unwrap();
        assert!((r - (a / big_s as f64).sqrt()).abs() < 1e-12, "{r}");
        assert_eq!(noise_from_pt(&[], big_s), None);
    }
}
