//! Delta lights (point and collimated) seen from a point, kept with what their
//! closed-form derivatives need. Visibility is fixed at the point (derivatives are
//! closed form away from shadow boundaries, theory.md §2).

use super::geometry::intersect_segment;
use super::scene::Scene;
use crate::core::color::Rgb;
use glam::DVec2;
use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum DirectLight {
    /// A visible point light: irradiance-like term I·T/r at x.
    Point {
        position: DVec2,
        intensity: Rgb,
        /// Transmittance from x to the light (medium region honoured).
        transmittance: Rgb,
    },
    /// A collimated beam reaching x through its aperture.
    Collimated {
        /// Direction of travel (unit).
        direction: DVec2,
        irradiance: Rgb,
        /// Distance from x to the aperture, against the beam.
        distance: f64,
        /// Unit normal of the aperture line (for how `distance` changes with x).
        aperture_normal: DVec2,
        transmittance: Rgb,
    },
}

impl DirectLight {
    /// The delta lights visible from `x`, and the shadow rays this cost.
    pub fn gather(scene: &Scene, x: DVec2) -> (Vec<DirectLight>, u64) {
        let mut out = Vec::new();
        let mut rays = 0;
        let tr = |w: DVec2, d: f64| scene.medium.as_ref().map_or(Rgb::ONE, |m| m.transmittance(x, w, d));
        for l in &scene.point_lights {
            let d = l.position - x;
            let r = d.length();
            if r == 0.0 {
                continue;
            }
            rays += 1;
            if !scene.geometry.occluded(x, d / r, r, None) {
                out.push(DirectLight::Point {
                    position: l.position,
                    intensity: l.intensity,
                    transmittance: tr(d / r, r),
                });
            }
        }
        for l in &scene.collimated_lights {
            let w = -l.direction;
            let Some((t, _)) = intersect_segment(x, w, l.aperture[0], l.aperture[1], 0.0, f64::INFINITY) else {
                continue;
            };
            rays += 1;
            if !scene.geometry.occluded(x, w, t, None) {
                out.push(DirectLight::Collimated {
                    direction: l.direction,
                    irradiance: l.irradiance,
                    distance: t,
                    aperture_normal: (l.aperture[1] - l.aperture[0]).perp().normalize(),
                    transmittance: tr(w, t),
                });
            }
        }
        (out, rays)
    }
}
