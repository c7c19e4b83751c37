//! Error maps: where and how much a field differs from a reference, per pixel, in
//! false colour with a colour bar (a [`field_figure_with`] of the error field).
//!
//! The error is of luminance (Rec. 709), as in [`field_errors`]:
//! - absolute: |L_test − L_ref|;
//! - relative: |L_test − L_ref| / √(L_ref² + 0.01·mean(L_ref)²), the mean of whose
//!   square is the relMSE of [`field_errors`] (robust where L_ref → 0).
//!
//! The scale is logarithmic (caching errors span decades, from smooth regions to
//! shadow edges); zero error takes the bottom colour. Pixels undefined in either
//! field are grey ([`INVALID_RGB`]), NaN errors magenta. Maps of several methods
//! are comparable only on one range: compute it with [`shared_error_range`] and pass
//! it to each [`error_map_figure`].
//!
//! [`field_errors`]: crate::flatland::field::field_errors
//! [`INVALID_RGB`]: super::field_figure::INVALID_RGB

use super::colorbar::ColorScale;
use super::field_figure::{FieldStyle, FigureOptions, field_figure_with};
use crate::core::color::{Rgb, luminance};
use crate::flatland::field::Field;
use crate::flatland::scene::Scene;
use tiny_skia::Pixmap;

/// The per-pixel luminance error of `test` against `reference` as a grey field
/// (every channel = the error), defined where both are. Panics if the grids differ.
pub fn error_field(test: &Field, reference: &Field, relative: bool) -> Field {
    assert_eq!(
        (test.width, test.height),
        (reference.width, reference.height),
        "error map: fields must share a grid"
    );
    let mut e = Field::new(test.width, test.height, reference.world_min, reference.world_max);
    let both = |k: usize| test.valid[k] && reference.valid[k];
    // The relMSE floor of field_errors: 0.01·mean(L_ref)² over pixels valid in both.
    let (sum, n) = (0..reference.values.len())
        .filter(|&k| both(k))
        .fold((0.0, 0usize), |(s, n), k| (s + luminance(reference.values[k]), n + 1));
    let mean = if n > 0 { sum / n as f64 } else { 0.0 };
    let floor = 0.01 * mean * mean;
    for k in 0..e.values.len() {
        e.valid[k] = both(k);
        if !e.valid[k] {
            continue;
        }
        let (a, b) = (luminance(test.values[k]), luminance(reference.values[k]));
        let d = (a - b).abs();
        let v = if relative {
            let den = (b * b + floor).sqrt();
            if den > 0.0 { d / den } else { d }
        } else {
            d
        };
        e.values[k] = Rgb::splat(v);
    }
    e
}

/// One (log) range for the error maps of several fields against their references:
/// the robust automatic range over the errors of all of them together.
pub fn shared_error_range(pairs: &[(&Field, &Field)], relative: bool) -> (f64, f64) {
    let errors: Vec<f64> = pairs
        .iter()
        .flat_map(|(t, r)| {
            let e = error_field(t, r, relative);
            e.values
                .iter()
                .zip(&e.valid)
                .filter(|(_, ok)| **ok)
                .map(|(v, _)| v.x)
                .collect::<Vec<_>>()
        })
        .collect();
    let s = ColorScale::auto(errors, true);
    (s.min, s.max)
}

/// The error map of `test` against `reference` (see the module documentation), the
/// scene drawn over it if given, on `range` (automatic if None), under `title`.
pub fn error_map_figure(
    test: &Field,
    reference: &Field,
    scene: Option<&Scene>,
    range: Option<(f64, f64)>,
    relative: bool,
    title: Option<&str>,
) -> Pixmap {
    let e = error_field(test, reference, relative);
    let style = FieldStyle::FalseColor { log: true, range };
    let opts = FigureOptions {
        title,
        colorbar_label: if relative {
            "relative error |L − L_ref| / L_ref"
        } else {
            "absolute error |L − L_ref|"
        },
        ..Default::default()
    };
    field_figure_with(&e, scene, &style, &opts)
}

#[cfg(test)]
mod tests {
    use super::super::colormap::viridis;
    use super::super::field_figure::{INVALID_RGB, field_to_rgba};
    use super::*;
    use glam::DVec2;

    fn field(w: usize, h: usize, f: impl Fn(DVec2) -> f64) -> Field {
        let mut out = Field::new(w, h, DVec2::splat(-1.0), DVec2::splat(1.0));
        for j in 0..h {
            for i in 0..w {
                out.values[j * w + i] = Rgb::splat(f(out.pixel_center(i, j)));
            }
        }
        out
    }

    #[test]
    fn identical_fields_have_zero_error() {
        let mut a = field(16, 12, |p| 0.5 + 0.3 * p.x);
        a.valid[5] = false;
        for relative in [false, true] {
            let e = error_field(&a, &a, relative);
            assert!(e.values.iter().all(|v| *v == Rgb::ZERO));
            assert!(!e.valid[5] && e.valid[6]);
            // Drawn: the bottom colour everywhere but grey where undefined.
            let m = field_to_rgba(&e, &FieldStyle::FalseColor { log: true, range: None });
            assert_eq!(&m.rgba[5 * 4..5 * 4 + 3], &INVALID_RGB);
            assert_eq!(&m.rgba[6 * 4..6 * 4 + 3], &viridis(0.0));
            let p = error_map_figure(&a, &a, None, None, relative, Some("zero"));
            assert!(p.width() > 16 && p.height() > 12);
        }
    }

    #[test]
    fn absolute_and_relative_errors() {
        let r = field(8, 8, |p| 1.0 + 0.5 * p.y);
        let mut t = r.clone();
        t.values[10] += Rgb::splat(0.2);
        t.valid[20] = false;
        let e = error_field(&t, &r, false);
        assert!((e.values[10].x - 0.2).abs() < 1e-12 && e.values[11].x == 0.0);
        assert!(!e.valid[20]);
        let rel = error_field(&t, &r, true);
        let b = luminance(r.values[10]);
        let n = 63.0;
        let mean = (r.values.iter().map(|v| luminance(*v)).sum::<f64>() - luminance(r.values[20])) / n;
        let want = 0.2 / (b * b + 0.01 * mean * mean).sqrt();
        assert!(
            (rel.values[10].x - want).abs() < 1e-12,
            "{} vs {want}",
            rel.values[10].x
        );
        // relMSE agrees with field_errors.
        let fe = crate::flatland::field::field_errors(&t, &r);
        let relmse = rel
            .values
            .iter()
            .zip(&rel.valid)
            .filter(|(_, ok)| **ok)
            .map(|(v, _)| v.x * v.x)
            .sum::<f64>()
            / n;
        assert!(
            (relmse - fe.relmse).abs() < 1e-12 * fe.relmse.max(1.0),
            "{relmse} vs {}",
            fe.relmse
        );
    }

    #[test]
    fn shared_range_makes_maps_comparable() {
        let r = field(32, 32, |p| 1.0 + 0.2 * p.x);
        let small = field(32, 32, |p| 1.0 + 0.2 * p.x + 1e-3 * (1.0 + p.y));
        let big = field(32, 32, |p| 1.0 + 0.2 * p.x + 1e-1 * (1.0 + p.y));
        let (lo, hi) = shared_error_range(&[(&small, &r), (&big, &r)], false);
        assert!(lo < 3e-3 && hi > 0.1, "{lo} {hi}");
        // On the shared range the small error map is darker than the big one.
        let mean_g = |t: &Field| {
            let e = error_field(t, &r, false);
            let m = field_to_rgba(
                &e,
                &FieldStyle::FalseColor {
                    log: true,
                    range: Some((lo, hi)),
                },
            );
            m.rgba.chunks(4).map(|c| c[1] as f64).sum::<f64>()
        };
        assert!(mean_g(&small) < 0.7 * mean_g(&big));
        let a = error_map_figure(&small, &r, None, Some((lo, hi)), false, None);
        assert_eq!(
            a.data(),
            error_map_figure(&small, &r, None, Some((lo, hi)), false, None).data()
        );
    }
}
