//! Automatic exposure for tone-mapped fields, and the grey scale that explains a
//! tone-mapped image the way the viridis bar explains false colour.
//!
//! The exposure puts the 99th percentile of the pixels' brightest channel at white
//! (1% of the positive pixels clip), so a field is readable whatever its absolute
//! level: σ_s = 5 is not white nor σ_s = 10⁵ black (issue 15). Only defined, finite,
//! positive values count: undefined pixels (outside the medium) and a field that is
//! zero almost everywhere do not drag the exposure to infinity.

use super::colorbar::ColorScale;
use super::colormap::tonemap;
use crate::core::color::Rgb;
use crate::flatland::field::Field;
use crate::limits::MAX_EXPOSURE;

/// The fraction of positive pixels shown below white by [`auto_exposure`].
pub const AUTO_EXPOSURE_PERCENTILE: f64 = 0.99;

/// Stops that map the [`AUTO_EXPOSURE_PERCENTILE`] of the brightest channel of
/// `field`'s defined pixels to white, within ±[`MAX_EXPOSURE`] (the command line's
/// `--exposure` range); 0 for a field without a positive value.
pub fn auto_exposure(field: &Field) -> f64 {
    let mut v: Vec<f64> = field
        .values
        .iter()
        .zip(&field.valid)
        .filter(|(_, ok)| **ok)
        .map(|(c, _)| c.x.max(c.y).max(c.z))
        .filter(|x| x.is_finite() && *x > 0.0)
        .collect();
    if v.is_empty() {
        return 0.0;
    }
    let k = ((v.len() - 1) as f64 * AUTO_EXPOSURE_PERCENTILE).round() as usize;
    let (_, white, _) = v.select_nth_unstable_by(k, f64::total_cmp);
    (-white.log2()).clamp(-MAX_EXPOSURE, MAX_EXPOSURE)
}

/// The linear scale of a tone-mapped display: 0 (black) to the value that reaches
/// white at `exposure` stops, for the colour bar's ticks.
pub fn tonemap_scale(exposure: f64) -> ColorScale {
    ColorScale::new(false, 0.0, (-exposure).exp2())
}

/// The display colour of a grey of value `v` at `exposure` stops (the bar's ramp).
pub fn tonemap_grey(v: f64, exposure: f64) -> [u8; 3] {
    tonemap(Rgb::splat(v), exposure)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    fn field(values: &[f64]) -> Field {
        let mut f = Field::new(values.len(), 1, DVec2::ZERO, DVec2::ONE);
        for (p, v) in f.values.iter_mut().zip(values) {
            *p = Rgb::new(*v * 0.5, *v, *v * 0.25);
        }
        f
    }

    #[test]
    fn the_99th_percentile_reaches_white_at_any_level() {
        for level in [1e-12, 1.0, 5.0, 1e9] {
            let values: Vec<f64> = (1..=1000).map(|k| level * k as f64).collect();
            let e = auto_exposure(&field(&values));
            // Rank 0.99·999 = 989 of 1..=1000: the value 990·level.
            assert!((e + (990.0 * level).log2()).abs() < 1e-9, "{level}: {e}");
            assert_eq!(tonemap_grey(990.0 * level, e), [255; 3]);
            assert!(tonemap_grey(500.0 * level, e)[0] < 255);
        }
    }

    #[test]
    fn undefined_zero_and_non_finite_pixels_do_not_count() {
        let mut f = field(&[0.0, 0.0, 0.0, 2.0, f64::NAN, f64::INFINITY, 1e30]);
        f.valid[6] = false;
        assert_eq!(auto_exposure(&f), -1.0, "only the 2.0 counts");
        assert_eq!(auto_exposure(&field(&[0.0; 4])), 0.0);
        assert_eq!(auto_exposure(&field(&[1e-300])), MAX_EXPOSURE);
    }

    #[test]
    fn the_bar_runs_from_black_to_white() {
        let s = tonemap_scale(2.0);
        assert_eq!((s.min, s.max), (0.0, 0.25));
        assert_eq!(tonemap_grey(s.value_at(0.0), 2.0), [0; 3]);
        assert_eq!(tonemap_grey(s.value_at(1.0), 2.0), [255; 3]);
    }
}
