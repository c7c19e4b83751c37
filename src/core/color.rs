//! RGB radiometric values. Linear (not sRGB), one f64 per channel.

use glam::DVec3;

/// A linear RGB radiometric quantity (radiance, intensity, reflectance, coefficients).
pub type Rgb = DVec3;

/// Rec. 709 luminance of a linear RGB value (the cache's error metric uses it).
pub fn luminance(c: Rgb) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// True when every channel is finite.
pub fn is_finite(c: Rgb) -> bool {
    c.x.is_finite() && c.y.is_finite() && c.z.is_finite()
}

/// Mean of the three channels.
pub fn average(c: Rgb) -> f64 {
    (c.x + c.y + c.z) / 3.0
}
