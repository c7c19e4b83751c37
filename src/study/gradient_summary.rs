//! The gradient study's errors against its reference, summarised per scattering
//! part by medians over the points inside the medium where the reference gradient
//! is nonzero (medians: a few points near a shadow edge must not decide it), next
//! to the reference's own noise level.

use super::gradients::PointOut;
use glam::DVec2;
use serde::Serialize;

/// Error of a method's gradient against the reference's.
#[derive(Serialize, Default, Clone, Copy, Debug, PartialEq)]
pub struct ErrorSummary {
    pub points: usize,
    /// Angle between the method's and the reference's gradient, degrees.
    pub median_angle_error_deg: f64,
    /// ||∇| − |∇_ref|| / |∇_ref|.
    pub median_relative_magnitude_error: f64,
    /// |∇ − ∇_ref| / |∇_ref|.
    pub median_relative_vector_error: f64,
}

#[derive(Serialize, Default, Clone, Copy, Debug, PartialEq)]
pub struct PartSummary {
    pub aware: ErrorSummary,
    pub unaware: ErrorSummary,
    /// Median over points of (reference noise estimate) / |∇_ref|: relative errors
    /// of the methods near this level are indistinguishable from the reference's own.
    pub reference_median_relative_noise: f64,
}

/// Per part.
#[derive(Serialize, Default, Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    pub single: PartSummary,
    pub multiple: PartSummary,
    pub total: PartSummary,
}

impl Summary {
    pub fn of(points: &[PointOut]) -> Summary {
        Summary {
            single: summarize_part(points, "single"),
            multiple: summarize_part(points, "multiple"),
            total: summarize_part(points, "total"),
        }
    }

    pub fn part(&self, key: &str) -> PartSummary {
        match key {
            "single" => self.single,
            "multiple" => self.multiple,
            _ => self.total,
        }
    }
}

/// The median of the finite values (NaN for none).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The unsigned angle between two vectors, in degrees.
fn angle_deg(a: DVec2, b: DVec2) -> f64 {
    a.perp_dot(b).atan2(a.dot(b)).abs().to_degrees()
}

pub fn summarize_part(points: &[PointOut], part: &str) -> PartSummary {
    let valid: Vec<(&PointOut, DVec2)> = points
        .iter()
        .filter_map(|p| {
            let r = p.reference.as_ref()?.part(part).grad();
            (r.length() > 0.0 && r.is_finite()).then_some((p, r))
        })
        .collect();
    let errors = |key: &str| {
        let pairs: Vec<(DVec2, DVec2)> = valid
            .iter()
            .filter_map(|(p, r)| Some((p.method(key)?.part(part).grad(), *r)))
            .collect();
        ErrorSummary {
            points: pairs.len(),
            median_angle_error_deg: median(pairs.iter().map(|(g, r)| angle_deg(*g, *r)).collect()),
            median_relative_magnitude_error: median(
                pairs
                    .iter()
                    .map(|(g, r)| (g.length() - r.length()).abs() / r.length())
                    .collect(),
            ),
            median_relative_vector_error: median(pairs.iter().map(|(g, r)| (*g - *r).length() / r.length()).collect()),
        }
    };
    PartSummary {
        aware: errors("aware"),
        unaware: errors("unaware"),
        reference_median_relative_noise: median(
            valid
                .iter()
                .filter_map(|(p, r)| Some(p.reference_gradient_noise?.part(part) / r.length()))
                .collect(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::gradients::{CostOut, MethodOut, NoiseOut, TaylorOut};

    fn method(g: [f64; 2]) -> MethodOut {
        let t = TaylorOut {
            value: 1.0,
            gradient: g,
            hessian: None,
        };
        MethodOut {
            direct: t,
            single: t,
            multiple: t,
            total: t,
        }
    }

    fn point(aware: [f64; 2], unaware: [f64; 2], reference: [f64; 2]) -> PointOut {
        PointOut {
            s: None,
            at: [0.0; 2],
            inside_medium: true,
            seed: 0,
            aware: Some(method(aware)),
            unaware: Some(method(unaware)),
            reference: Some(method(reference)),
            reference_gradient_noise: Some(NoiseOut {
                single: 0.1,
                multiple: 0.1,
                total: 0.1,
            }),
            cost: CostOut::default(),
        }
    }

    #[test]
    fn medians_of_known_errors() {
        assert_eq!(median(vec![3.0, f64::NAN, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0]), 2.5);
        assert!(median(vec![]).is_nan());
        // Aware exact; unaware turned by 90° (relative vector error √2) or twice as
        // long (magnitude error 1); a zero reference gradient is left out.
        let pts = [
            point([1.0, 0.0], [0.0, 1.0], [1.0, 0.0]),
            point([0.0, 2.0], [0.0, 4.0], [0.0, 2.0]),
            point([0.0, 2.0], [0.0, 4.0], [0.0, 2.0]),
            point([5.0, 5.0], [5.0, 5.0], [0.0, 0.0]),
        ];
        let s = Summary::of(&pts).part("single");
        assert_eq!((s.aware.points, s.unaware.points), (3, 3));
        assert_eq!(s.aware.median_angle_error_deg, 0.0);
        assert_eq!(s.aware.median_relative_vector_error, 0.0);
        assert_eq!(s.unaware.median_angle_error_deg, 0.0);
        assert_eq!(s.unaware.median_relative_magnitude_error, 1.0);
        assert_eq!(s.unaware.median_relative_vector_error, 1.0);
        assert!((summarize_part(&pts[..1], "total").unaware.median_angle_error_deg - 90.0).abs() < 1e-12);
        assert_eq!(s.reference_median_relative_noise, 0.05);
    }
}
