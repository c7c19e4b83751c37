//! Colour: the sRGB transfer function, exposure tone mapping, the viridis false-colour
//! map and a perceptual hue wheel for directions.
//!
//! All outputs are 8-bit sRGB-encoded (display) colours.
//!
//! - [`viridis`] is evaluated from a degree-14 Chebyshev least-squares fit per channel
//!   to the 256-entry viridis table (van der Walt & Smith, matplotlib, CC0); the fit
//!   differs from the table by at most 0.28/255, so at most one 8-bit level after
//!   rounding. It is perceptually uniform and monotone in lightness, and readable by
//!   colour-blind viewers and in greyscale print.
//! - [`angle_color`] walks the hue circle of Oklab (Ottosson 2020) at constant
//!   lightness and chroma, so no direction looks brighter than another (unlike HSV,
//!   whose yellow and cyan stand out).

use crate::core::color::Rgb;

/// The sRGB opto-electronic transfer function (IEC 61966-2-1) of a linear value,
/// clamped to [0, 1] (NaN → 0).
pub fn srgb_encode(linear: f64) -> f64 {
    if linear.is_nan() || linear <= 0.0 {
        0.0
    } else if linear <= 0.003_130_8 {
        12.92 * linear
    } else if linear >= 1.0 {
        1.0
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`srgb_encode`]: linear value of an encoded one in [0, 1].
pub fn srgb_decode(encoded: f64) -> f64 {
    let e = encoded.clamp(0.0, 1.0);
    if e <= 0.040_45 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

/// An encoded value in [0, 1] as an 8-bit level (rounded).
#[inline]
pub fn to_u8(encoded: f64) -> u8 {
    (encoded.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Tone map linear RGB for display: multiply by 2^exposure_stops, clamp each channel
/// to [0, 1], sRGB-encode. NaN channels become 0.
pub fn tonemap(rgb: Rgb, exposure_stops: f64) -> [u8; 3] {
    let k = exposure_stops.exp2();
    [
        to_u8(srgb_encode(rgb.x * k)),
        to_u8(srgb_encode(rgb.y * k)),
        to_u8(srgb_encode(rgb.z * k)),
    ]
}

/// Chebyshev coefficients (on t ∈ [0, 1] mapped to x = 2t − 1) of the viridis
/// red, green and blue channels (sRGB-encoded).
const VIRIDIS_CHEBYSHEV: [[f64; 15]; 3] = [
    [
        0.408685303,
        0.29831589,
        0.254973645,
        0.0802211112,
        -0.0331615251,
        -0.0196831763,
        -0.00178314534,
        0.0065440167,
        0.00208256026,
        -0.003684529,
        -0.00144519426,
        0.00173786127,
        0.000889558609,
        -0.000761377733,
        -0.000743431746,
    ],
    [
        0.518721142,
        0.454668502,
        -0.0573709758,
        -0.0048518759,
        -0.00846997684,
        0.000751235251,
        0.00214133304,
        0.000842709253,
        -0.000325864931,
        0.00011329123,
        0.000181636653,
        -0.000294459358,
        0.000249351145,
        -0.000196634733,
        0.000166170398,
    ],
    [
        0.375889699,
        -0.146720652,
        -0.170658126,
        0.0211424205,
        0.0148292236,
        0.0288197857,
        0.0146767892,
        0.00487351003,
        0.00413135579,
        0.00119996665,
        -0.000715381655,
        -0.000934545222,
        -0.00107654441,
        -0.000755849306,
        -0.000524751284,
    ],
];

/// Clenshaw evaluation of a Chebyshev series at x ∈ [−1, 1].
fn chebyshev(c: &[f64], x: f64) -> f64 {
    let (mut b1, mut b2) = (0.0, 0.0);
    for &ck in c[1..].iter().rev() {
        let b0 = 2.0 * x * b1 - b2 + ck;
        b2 = b1;
        b1 = b0;
    }
    x * b1 - b2 + c[0]
}

/// The viridis colour map as sRGB-encoded floats in [0, 1]; `t` is clamped to
/// [0, 1] and NaN maps to 0.
pub fn viridis_f64(t: f64) -> [f64; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = 2.0 * t - 1.0;
    VIRIDIS_CHEBYSHEV.map(|c| chebyshev(&c, x).clamp(0.0, 1.0))
}

/// The viridis colour map (dark blue-violet at 0, yellow at 1); `t` is clamped to
/// [0, 1] and NaN maps to 0.
pub fn viridis(t: f64) -> [u8; 3] {
    viridis_f64(t).map(to_u8)
}

/// Oklab (L, a, b) to linear sRGB (Ottosson's matrices).
pub fn oklab_to_linear_srgb(l: f64, a: f64, b: f64) -> [f64; 3] {
    let l_ = l + 0.396_337_777_4 * a + 0.215_803_757_3 * b;
    let m_ = l - 0.105_561_345_8 * a - 0.063_854_172_8 * b;
    let s_ = l - 0.089_484_177_5 * a - 1.291_485_548_0 * b;
    let (l3, m3, s3) = (l_ * l_ * l_, m_ * m_ * m_, s_ * s_ * s_);
    [
        4.076_741_662_1 * l3 - 3.307_711_591_3 * m3 + 0.230_969_929_2 * s3,
        -1.268_438_004_6 * l3 + 2.609_757_401_1 * m3 - 0.341_319_396_5 * s3,
        -0.004_196_086_3 * l3 - 0.703_418_614_7 * m3 + 1.707_614_701_0 * s3,
    ]
}

/// Oklab lightness and chroma of the hue wheel at full brightness: the largest
/// chroma at L = 0.75 that keeps every hue inside the sRGB gamut (≈ 0.1275).
const WHEEL_L: f64 = 0.75;
const WHEEL_C: f64 = 0.125;

/// A colour for a direction: hue = `angle_rad` (counter-clockwise from +x; 0 is
/// pink-red, π/2 ochre, π teal, 3π/2 blue), brightness in [0, 1] scales the Oklab
/// lightness and chroma together (0 = black), so hue stays constant as magnitude
/// fades. Constant perceived lightness across hues at a given brightness.
pub fn angle_color(angle_rad: f64, brightness: f64) -> [u8; 3] {
    let k = if brightness.is_nan() {
        0.0
    } else {
        brightness.clamp(0.0, 1.0)
    };
    let h = if angle_rad.is_finite() { angle_rad } else { 0.0 };
    let (s, c) = h.sin_cos();
    // Scaling L, a, b by k scales linear RGB by k³: every brightness stays in gamut.
    let rgb = oklab_to_linear_srgb(WHEEL_L * k, WHEEL_C * k * c, WHEEL_C * k * s);
    rgb.map(|v| to_u8(srgb_encode(v)))
}

/// Relative luminance (Rec. 709) of an 8-bit sRGB colour.
pub fn srgb8_luminance(c: [u8; 3]) -> f64 {
    let l = c.map(|v| srgb_decode(v as f64 / 255.0));
    0.2126 * l[0] + 0.7152 * l[1] + 0.0722 * l[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_known_values() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert_eq!(srgb_encode(1.0), 1.0);
        assert_eq!(srgb_encode(-1.0), 0.0);
        assert_eq!(srgb_encode(7.0), 1.0);
        assert_eq!(srgb_encode(f64::NAN), 0.0);
        // The two branches meet (to 1e-7) at the breakpoint 0.0031308 → 0.04045.
        let below = srgb_encode(0.003_130_8);
        let above = 1.055 * 0.003_130_8f64.powf(1.0 / 2.4) - 0.055;
        assert!(
            (below - 0.040_45).abs() < 1e-5 && (below - above).abs() < 1e-7,
            "{below} {above}"
        );
        assert!((srgb_encode(0.5) - 0.735_356_6).abs() < 1e-6);
        assert!((srgb_encode(0.18) - 0.461_356).abs() < 1e-5);
        for k in 0..=100 {
            let v = k as f64 / 100.0;
            assert!((srgb_decode(srgb_encode(v)) - v).abs() < 1e-12);
        }
    }

    #[test]
    fn tonemap_exposure_and_clamp() {
        assert_eq!(tonemap(Rgb::new(0.0, 0.5, 4.0), 0.0), [0, 188, 255]);
        assert_eq!(tonemap(Rgb::splat(0.25), 1.0), tonemap(Rgb::splat(0.5), 0.0));
        assert_eq!(tonemap(Rgb::new(f64::NAN, f64::INFINITY, -1.0), 0.0), [0, 255, 0]);
    }

    #[test]
    fn viridis_endpoints_and_reference_points() {
        // Entries 0, 64, 128, 192 and 255 of the published 256-entry table.
        let table = [
            (0, [0.267004, 0.004874, 0.329415]),
            (64, [0.229739, 0.322361, 0.545706]),
            (128, [0.127568, 0.566949, 0.550556]),
            (192, [0.369214, 0.788888, 0.382914]),
            (255, [0.993248, 0.906157, 0.143936]),
        ];
        for (i, want) in table {
            let got = viridis_f64(i as f64 / 255.0);
            for c in 0..3 {
                assert!((got[c] - want[c]).abs() < 1.5e-3, "entry {i}: {got:?} vs {want:?}");
            }
        }
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(viridis(-3.0), viridis(0.0));
        assert_eq!(viridis(9.0), viridis(1.0));
        assert_eq!(viridis(f64::NAN), viridis(0.0));
    }

    #[test]
    fn viridis_luminance_is_monotone() {
        let lum = |c: [f64; 3]| {
            let l = c.map(srgb_decode);
            0.2126 * l[0] + 0.7152 * l[1] + 0.0722 * l[2]
        };
        let (mut prev, mut prev8) = (-1.0, -1.0);
        for k in 0..=2048 {
            let t = k as f64 / 2048.0;
            let y = lum(viridis_f64(t));
            assert!(y > prev, "luminance drops at t = {t}");
            // 8-bit rounding alone may dip by a few 1e-4 (as the published table does).
            let y8 = srgb8_luminance(viridis(t));
            assert!(y8 > prev8 - 5e-4, "8-bit luminance drops at t = {t}");
            (prev, prev8) = (y, y8.max(prev8));
        }
        let span = srgb8_luminance(viridis(1.0)) / srgb8_luminance(viridis(0.0));
        assert!(span > 30.0, "{span}");
    }

    #[test]
    fn hue_wheel_is_even_and_in_gamut() {
        let lum: Vec<f64> = (0..360)
            .map(|d| srgb8_luminance(angle_color((d as f64).to_radians(), 1.0)))
            .collect();
        let (lo, hi) = lum.iter().fold((f64::MAX, 0.0f64), |(a, b), &y| (a.min(y), b.max(y)));
        // Constant Oklab L: luminance nearly constant (HSV would span 0.07–0.93).
        assert!(hi / lo < 1.15, "{lo} {hi}");
        // In gamut: the unclamped linear values stay within [0, 1].
        for d in 0..360 {
            let h = (d as f64).to_radians();
            let rgb = oklab_to_linear_srgb(WHEEL_L, WHEEL_C * h.cos(), WHEEL_C * h.sin());
            assert!(rgb.iter().all(|&v| (-1e-9..=1.0 + 1e-9).contains(&v)), "{d}°: {rgb:?}");
        }
        assert_eq!(angle_color(1.0, 0.0), [0, 0, 0]);
        // Opposite directions are clearly different colours.
        let (a, b) = (angle_color(0.0, 1.0), angle_color(std::f64::consts::PI, 1.0));
        assert!(a.iter().zip(b).map(|(&x, y)| (x as i32 - y as i32).abs()).sum::<i32>() > 150);
        // Dimmer is darker.
        assert!(srgb8_luminance(angle_color(2.0, 0.5)) < 0.5 * srgb8_luminance(angle_color(2.0, 1.0)));
    }
}
