//! Next-event estimation shared by every light of every dimension: one light sample
//! seen from a path vertex ([`light_sample`]: lobe, visibility, transmittance and
//! the MIS weight against lobe sampling), and point lights — an isotropic point of
//! intensity I (W per unit angle or solid angle) lights a point at distance r with
//! I·T/r^{d−1} (theory.md §1), evaluated analytically, never sampled.

use super::dim::Dim;
use super::lobe::Lobe;
use super::medium::pass_probability;
pub use super::world::PointLight;
use super::world::VecOf;
use super::world::{DirectLight, World};
use crate::core::color::Rgb;
use crate::core::mis::power_heuristic;
use crate::core::space::Space;

/// A light seen from a vertex `p` along the unit direction `w`.
#[derive(Clone, Copy, Debug)]
pub struct LightSample<V> {
    pub w: V,
    /// Distance to the light (infinite for a distant one: the world's exit).
    pub dist: f64,
    /// Radiance (or intensity / r^{d−1}, irradiance for a delta light).
    pub radiance: Rgb,
    /// The pdf it was sampled with (per unit angle or solid angle); 1 for a delta light.
    pub pdf: f64,
}

/// value(w)·L·T/pdf of a light sample from `p` (zero if the lobe ignores `w` or the
/// light is occluded), with `mis` the power-heuristic weight against lobe sampling.
/// `each` sees every non-zero sample with its direction (the probes' direction
/// slopes reweight them; other callers pass [`super::world::ignore`]).
#[allow(clippy::too_many_arguments)] // the light sample's state is spelled out
pub fn light_sample<W: World>(
    world: &W,
    p: VecOf<W>,
    lobe: &Lobe<W::S>,
    skip: Option<u32>,
    l: &LightSample<VecOf<W>>,
    mis: bool,
    rays: &mut u64,
    each: &mut impl FnMut(VecOf<W>, Rgb),
) -> Rgb {
    let (value, lobe_pdf) = lobe.eval(l.w);
    if value == Rgb::ZERO {
        return Rgb::ZERO;
    }
    *rays += 1;
    if world.occluded(p, l.w, l.dist, skip) {
        return Rgb::ZERO;
    }
    let dist = if l.dist.is_finite() {
        l.dist
    } else {
        world.world_exit(p, l.w)
    };
    let tr = world.transmittance(p, l.w, dist);
    // MIS against lobe sampling (pbrt-v4's volumetric rule): the lobe strategy finds
    // this light only if its free flight also passes the medium in between, so its
    // density here is the lobe's times that probability. With direction densities
    // alone it claims a share it practically never delivers deep in fog (measured:
    // single scattering 20-74% low at 12 mean free paths).
    let weight = if mis {
        power_heuristic(l.pdf, lobe_pdf * pass_probability(tr))
    } else {
        1.0
    };
    let c = value * l.radiance * tr * (weight / l.pdf);
    each(l.w, c);
    c
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
    p: VecOf<W>,
    lobe: &Lobe<W::S>,
    skip: Option<u32>,
    rays: &mut u64,
    each: &mut impl FnMut(VecOf<W>, Rgb),
) -> Rgb {
    let r_min = 1e-9 * world.scale();
    let mut sum = Rgb::ZERO;
    for l in lights {
        if let Some((w, dist)) = towards::<W::S>(p, l.position) {
            let radiance = l.intensity / dist.max(r_min).powi(W::S::DIM as i32 - 1);
            let l = LightSample {
                w,
                dist,
                radiance,
                pdf: 1.0,
            };
            sum += light_sample(world, p, lobe, skip, &l, false, rays, each);
        }
    }
    sum
}

/// The lights of `lights` visible from `x`, for the closed-form derivatives.
pub fn gather<W: World>(
    world: &W,
    lights: &[PointLight<W::S>],
    x: VecOf<W>,
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
