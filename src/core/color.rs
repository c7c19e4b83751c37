//! RGB radiometric values. Linear (not sRGB), one f64 per channel.

use glam::DVec3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

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

/// An RGB value written either as a scalar (grey) or as `[r, g, b]`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Color(pub [f64; 3]);

impl Color {
    pub fn grey(v: f64) -> Self {
        Color([v; 3])
    }
    pub fn is_zero(&self) -> bool {
        self.0 == [0.0; 3]
    }
}

impl Serialize for Color {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let [r, g, b] = self.0;
        if r == g && g == b {
            s.serialize_f64(r)
        } else {
            self.0.serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for Color {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Color;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an [r, g, b] array of three numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Color, E> {
                Ok(Color::grey(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Color, E> {
                Ok(Color::grey(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Color, E> {
                Ok(Color::grey(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<Color, A::Error> {
                let mut c = [0.0; 3];
                for (i, slot) in c.iter_mut().enumerate() {
                    *slot = a
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                if a.next_element::<f64>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(4, &self));
                }
                Ok(Color(c))
            }
        }
        d.deserialize_any(V)
    }
}
