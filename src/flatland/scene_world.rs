//! The 2D scene as the method sees it ([`World`]): ray casting over its segments,
//! its medium, the surface at a hit, and next-event estimation through
//! [`super::lights`]. Apart from [`super::scene`] so that the lights, which read the
//! scene, and the scene's description do not import each other.

use super::lights::{self, Lobe};
use super::medium::{Medium, Region};
use super::scene::Scene;
use crate::core::color::Rgb;
use crate::core::rng::Sampler;
use crate::core::space::D2;
use crate::pipeline::world::{DirectLight, Hit, SurfacePoint, World};
use glam::DVec2;

impl World for Scene {
    type S = D2;
    type Region = Region;

    /// Diagonal of the domain.
    fn scale(&self) -> f64 {
        (self.domain_max - self.domain_min).length()
    }

    fn closest_hit(&self, o: DVec2, d: DVec2, t_max: f64, skip: Option<u32>) -> Option<Hit> {
        let (t, prim, u, v) = self.geometry.closest_hit(o, d, self.t_min, t_max, skip)?;
        Some(Hit { t, prim, u, v })
    }

    fn occluded(&self, o: DVec2, d: DVec2, t_max: f64, skip: Option<u32>) -> bool {
        self.geometry.occluded(o, d, self.t_min, t_max * (1.0 - 1e-10), skip)
    }

    fn occluders_in_box(&self, lo: DVec2, hi: DVec2, limit: usize, out: &mut Vec<u32>) -> bool {
        self.geometry.prims_in_box(lo, hi, limit, out)
    }

    fn occluded_among(&self, ids: &[u32], o: DVec2, d: DVec2, t_max: f64) -> bool {
        // The bounds of `occluded`, so that the answers agree.
        self.geometry
            .occluded_among(ids, o, d, self.t_min, t_max * (1.0 - 1e-10))
    }

    fn centre(&self) -> DVec2 {
        0.5 * (self.domain_min + self.domain_max)
    }

    fn medium(&self) -> Option<&Medium> {
        self.medium.as_ref()
    }

    fn silhouette(&self, prim: u32, x: DVec2, d_in: DVec2, d_out: DVec2) -> Option<DVec2> {
        super::geometry::segment_silhouette(&self.geometry.prims[prim as usize], x, d_in, d_out)
    }

    fn primitive_ends(&self, prim: u32, _x: DVec2, out: &mut Vec<(DVec2, DVec2)>) {
        let seg = &self.geometry.prims[prim as usize];
        let along = (seg.b - seg.a).normalize_or_zero();
        out.extend([(seg.a, -along), (seg.b, along)]);
    }

    fn surface(&self, hit: &Hit, dir: DVec2) -> SurfacePoint<D2> {
        let seg = &self.geometry.prims[hit.prim as usize];
        let (normal, active) = seg.facing_dir(dir);
        SurfacePoint {
            point: seg.point_at(hit.u),
            normal,
            active,
            emission: seg.emission,
            reflectance: seg.reflectance,
        }
    }

    fn point_lights(&self) -> &[crate::pipeline::world::PointLight<D2>] {
        &self.point_lights
    }

    fn directional_lights_each(
        &self,
        p: DVec2,
        lobe: &Lobe,
        skip: Option<u32>,
        rays: &mut u64,
        each: &mut impl FnMut(DVec2, Rgb),
    ) -> Rgb {
        lights::collimated_lights(self, p, lobe, skip, rays, each)
    }

    fn delta_lights_each(
        &self,
        p: DVec2,
        lobe: &Lobe,
        skip: Option<u32>,
        rays: &mut u64,
        each: &mut impl FnMut(DVec2, Rgb),
    ) -> Rgb {
        lights::direct_lights(self, p, lobe, skip, rays, each)
    }

    fn sampled_nee_each(
        &self,
        p: DVec2,
        lobe: &Lobe,
        skip: Option<u32>,
        mis: bool,
        s: &mut Sampler,
        rays: &mut u64,
        each: &mut impl FnMut(DVec2, Rgb),
    ) -> Rgb {
        lights::emitter_nee(self, p, lobe, skip, mis, s, rays, each)
    }

    fn has_extended_lights(&self) -> bool {
        !self.emitters.is_empty()
    }

    fn emitter_pdf(&self, from: DVec2, prim: u32, _y: DVec2) -> f64 {
        lights::emitter_pdf(self, from, prim)
    }

    fn direct_lights(&self, x: DVec2) -> (Vec<DirectLight<D2>>, u64) {
        lights::gather_direct(self, x)
    }
}
