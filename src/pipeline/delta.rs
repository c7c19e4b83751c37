//! Point lights in any dimension: an isotropic point of intensity I (W per unit
//! angle or solid angle) lights a point at distance r with I·T/r^{d−1} (theory.md §1).
//! Evaluated analytically with visibility, never sampled.

use super::dim::Dim;
use super::lobe::Lobe;
use super::world::{DirectLight, World};
use crate::core::color::Rgb;
use crate::core::space::Space;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight<S: Dim> {
    pub position: S::Vec,
    pub intensity: Rgb,
}

/// Unit direction and distance from `p` to a light at `q` (None on top of it).
fn towards<S: Dim>(p: S::Vec, q: S::Vec) -> Option<(S::Vec, f64)> {
    let r = S::length(q - p);
    (r > 0.0).then(|| ((q - p) / r, r))
}

/// Light from `lights` arriving at `p`, weighted by `lobe` (`skip`: the primitive
/// `p` lies on). The distance is clamped at 1e-9 of the scene size, so a point on
/// top of a light (users probe there) stays finite.
pub fn point_lights<W: World>(
    world: &W,
    lights: &[PointLight<W::S>],
    p: super::world::VecOf<W>,
    lobe: &Lobe<W::S>,
    skip: Option<u32>,
    rays: &mut u64,
) -> Rgb {
    let r_min = 1e-9 * world.scale();
    let mut sum = Rgb::ZERO;
    for l in lights {
        let Some((w, r)) = towards::<W::S>(p, l.position) else {
            continue;
        };
        let (value, _) = lobe.eval(w);
        if value == Rgb::ZERO {
            continue;
        }
        *rays += 1;
        if !world.occluded(p, w, r, skip) {
            let falloff = r.max(r_min).powi(W::S::DIM as i32 - 1);
            sum += value * l.intensity * world.transmittance(p, w, r) / falloff;
        }
    }
    sum
}

/// The lights of `lights` visible from `x`, for the closed-form derivatives.
pub fn gather<W: World>(
    world: &W,
    lights: &[PointLight<W::S>],
    x: super::world::VecOf<W>,
    out: &mut Vec<DirectLight<W::S>>,
    rays: &mut u64,
) {
    for l in lights {
        let Some((w, r)) = towards::<W::S>(x, l.position) else {
            continue;
        };
        *rays += 1;
        if !world.occluded(x, w, r, None) {
            out.push(DirectLight::Point {
                position: l.position,
                intensity: l.intensity,
                transmittance: world.transmittance(x, w, r),
            });
        }
    }
}
