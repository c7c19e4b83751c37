//! RGB radiance with its derivatives: one [`Taylor2`] per channel.

use super::color::Rgb;
use super::space::Space;
use super::taylor::Taylor2;
use std::ops::{Add, AddAssign};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaylorRgb<S: Space> {
    pub channels: [Taylor2<S>; 3],
}

impl<S: Space> Default for TaylorRgb<S> {
    fn default() -> Self {
        TaylorRgb {
            channels: [Taylor2::zero(); 3],
        }
    }
}

impl<S: Space> TaylorRgb<S> {
    /// A scalar field times a constant colour.
    pub fn tint(t: Taylor2<S>, c: Rgb) -> Self {
        TaylorRgb {
            channels: [t * c.x, t * c.y, t * c.z],
        }
    }

    /// A colour without derivatives.
    pub fn constant(c: Rgb) -> Self {
        Self::tint(Taylor2::constant(1.0), c)
    }

    pub fn value(&self) -> Rgb {
        Rgb::new(self.channels[0].value, self.channels[1].value, self.channels[2].value)
    }

    /// Rec. 709 luminance with its derivatives (the error metric's quantity).
    pub fn luminance(&self) -> Taylor2<S> {
        let [r, g, b] = self.channels;
        r * 0.2126 + g * 0.7152 + b * 0.0722
    }

    /// Channel-wise product with per-channel scalar fields.
    pub fn mul_channels(self, t: [Taylor2<S>; 3]) -> Self {
        TaylorRgb {
            channels: [
                self.channels[0] * t[0],
                self.channels[1] * t[1],
                self.channels[2] * t[2],
            ],
        }
    }

    pub fn scale(self, k: f64) -> Self {
        TaylorRgb {
            channels: self.channels.map(|t| t * k),
        }
    }

    pub fn is_finite(&self) -> bool {
        self.channels.iter().all(|t| t.is_finite())
    }
}

impl<S: Space> Add for TaylorRgb<S> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        TaylorRgb {
            channels: [
                self.channels[0] + o.channels[0],
                self.channels[1] + o.channels[1],
                self.channels[2] + o.channels[2],
            ],
        }
    }
}

impl<S: Space> AddAssign for TaylorRgb<S> {
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

/// L_s with its derivatives, per part (theory.md §2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartDerivs<S: Space> {
    pub direct: TaylorRgb<S>,
    pub single: TaylorRgb<S>,
    pub multiple: TaylorRgb<S>,
}

impl<S: Space> Default for PartDerivs<S> {
    fn default() -> Self {
        PartDerivs {
            direct: TaylorRgb::default(),
            single: TaylorRgb::default(),
            multiple: TaylorRgb::default(),
        }
    }
}

impl<S: Space> PartDerivs<S> {
    pub fn total(&self) -> TaylorRgb<S> {
        self.direct + self.single + self.multiple
    }

    /// Every part's value is zero: the estimate saw no light at all (one part
    /// alone can be zero where the others are not, as single scattering in a
    /// lamp's shadow).
    pub fn sees_no_light(&self) -> bool {
        [self.direct, self.single, self.multiple]
            .iter()
            .all(|t| t.value() == Rgb::ZERO)
    }

    pub fn is_finite(&self) -> bool {
        self.direct.is_finite() && self.single.is_finite() && self.multiple.is_finite()
    }

    /// The mean of independent estimates (zero for none).
    pub fn mean(batches: &[Self]) -> Self {
        let Some((first, rest)) = batches.split_first() else {
            return PartDerivs::default();
        };
        let mut m = *first;
        for b in rest {
            m.direct += b.direct;
            m.single += b.single;
            m.multiple += b.multiple;
        }
        let k = 1.0 / batches.len() as f64;
        PartDerivs {
            direct: m.direct.scale(k),
            single: m.single.scale(k),
            multiple: m.multiple.scale(k),
        }
    }
}
