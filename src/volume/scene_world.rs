//! The 3D scene as the method sees it ([`World`]): ray casting over its triangles,
//! its medium, the surface at a hit, the sky, and next-event estimation through
//! [`super::lights`]. Apart from [`super::scene`] so that the lights, which read the
//! scene, and the scene's description do not import each other.

use super::lights::{self, Lobe};
use super::medium::{Medium, Region};
use super::mesh::Hit;
use super::scene::Scene;
use crate::core::color::Rgb;
use crate::core::rng::Sampler;
use crate::core::space::D3;
use crate::pipeline::world::{DirectLight, SurfacePoint, World};
use glam::DVec3;

impl World for Scene {
    type S = D3;
    type Region = Region;

    fn scale(&self) -> f64 {
        self.scale
    }

    #[inline]
    fn closest_hit(&self, o: DVec3, d: DVec3, t_max: f64, skip: Option<u32>) -> Option<Hit> {
        let (t, prim, u, v) = self.geometry.closest_hit(o, d, self.t_min(), t_max, skip)?;
        Some(Hit { t, prim, u, v })
    }

    #[inline]
    fn occluded(&self, o: DVec3, d: DVec3, t_max: f64, skip: Option<u32>) -> bool {
        self.geometry.occluded(o, d, self.t_min(), t_max, skip)
    }

    fn occluders_in_box(&self, lo: DVec3, hi: DVec3, limit: usize, out: &mut Vec<u32>) -> bool {
        self.geometry.prims_in_box(lo, hi, limit, out)
    }

    fn occluded_among(&self, ids: &[u32], o: DVec3, d: DVec3, t_max: f64) -> bool {
        // The bounds of `occluded`, so that the answers agree.
        self.geometry.occluded_among(ids, o, d, self.t_min(), t_max)
    }

    fn centre(&self) -> DVec3 {
        0.5 * (self.bounds.min + self.bounds.max)
    }

    fn medium(&self) -> Option<&Medium> {
        self.medium.as_ref()
    }

    fn silhouette(&self, prim: u32, x: DVec3, d_in: DVec3, d_out: DVec3) -> Option<DVec3> {
        super::mesh::triangle_silhouette(&self.geometry.prims[prim as usize], x, d_in, d_out)
    }

    fn edge_direction(&self, prim: u32, p: DVec3) -> Option<DVec3> {
        super::mesh::triangle_edge_through(&self.geometry.prims[prim as usize], p)
    }

    fn primitive_ends(&self, prim: u32, x: DVec3, out: &mut Vec<(DVec3, DVec3)>) {
        super::mesh::triangle_edge_points(&self.geometry.prims[prim as usize], x, out)
    }

    fn surface(&self, hit: &Hit, dir: DVec3) -> SurfacePoint<D3> {
        let tri = &self.geometry.prims[hit.prim as usize];
        let surf = &self.surfaces[tri.shape as usize];
        let facing = tri.normal.dot(dir) < 0.0;
        SurfacePoint {
            point: tri.point_at(hit.u, hit.v),
            normal: if facing { tri.normal } else { -tri.normal },
            active: facing || surf.two_sided,
            emission: surf.emission,
            reflectance: surf.reflectance,
        }
    }

    fn point_lights(&self) -> &[crate::pipeline::world::PointLight<D3>] {
        &self.point_lights
    }

    fn directional_lights_each(
        &self,
        p: DVec3,
        lobe: &Lobe,
        skip: Option<u32>,
        rays: &mut u64,
        each: &mut impl FnMut(DVec3, Rgb),
    ) -> Rgb {
        lights::delta_suns(self, p, lobe, skip, rays, each)
    }

    fn delta_lights_each(
        &self,
        p: DVec3,
        lobe: &Lobe,
        skip: Option<u32>,
        rays: &mut u64,
        each: &mut impl FnMut(DVec3, Rgb),
    ) -> Rgb {
        lights::delta_lights(self, p, lobe, skip, rays, each)
    }

    fn sampled_nee_each(
        &self,
        p: DVec3,
        lobe: &Lobe,
        skip: Option<u32>,
        mis: bool,
        s: &mut Sampler,
        rays: &mut u64,
        each: &mut impl FnMut(DVec3, Rgb),
    ) -> Rgb {
        lights::distant_nee(self, p, lobe, skip, mis, s, rays, each)
            + lights::emitter_nee(self, p, lobe, skip, mis, s, rays, each)
    }

    fn has_extended_lights(&self) -> bool {
        !self.emitters.is_empty() || self.sky != Rgb::ZERO
    }

    fn emitter_pdf(&self, from: DVec3, prim: u32, y: DVec3) -> f64 {
        lights::emitter_pdf(self, from, prim, y)
    }

    fn escaped(&self, w: DVec3, lobe_pdf: Option<f64>) -> Rgb {
        lights::escaped_radiance(self, w, lobe_pdf)
    }

    /// The sky: sun cones are far narrower than a probe ray's solid angle, so they
    /// are evaluated with the direct part instead.
    fn escaped_probe(&self, _w: DVec3) -> Rgb {
        self.sky
    }

    fn direct_part(&self, p: DVec3, lobe: &Lobe, s: &mut Sampler, rays: &mut u64) -> Rgb {
        lights::direct_part(self, p, lobe, s, rays)
    }

    fn direct_lights(&self, x: DVec3) -> (Vec<DirectLight<D3>>, u64) {
        lights::gather_direct(self, x)
    }
}
