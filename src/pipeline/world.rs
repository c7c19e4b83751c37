//! The scene as the method sees it, in any dimension: ray casting, the medium,
//! surfaces met by rays, and light — next-event estimation from a point with a lobe,
//! the pdf that weights emission found by lobe sampling (MIS), the radiance of rays
//! that leave the scene, and the delta lights seen from a point with what their
//! closed-form derivatives need. The 2D scene (`flatland`) and the 3D scene
//! (`volume`) implement it; path tracing, probes, proxies, derivatives and cache
//! placement are written once against it.

use super::dim::Dim;
use super::lobe::Lobe;
use super::medium::{Medium, Region};
use crate::core::color::Rgb;
use crate::core::rng::Sampler;
use serde::Serialize;

/// The closest intersection along a ray: distance, primitive and its surface
/// parameters (`v` is zero for a segment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub prim: u32,
    pub u: f64,
    pub v: f64,
}

/// A surface point found by a ray, seen from the ray's side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint<S: Dim> {
    pub point: S::Vec,
    /// Unit normal on the side the ray came from.
    pub normal: S::Vec,
    /// That side reflects and emits (the back of a one-sided surface absorbs).
    pub active: bool,
    pub emission: Rgb,
    pub reflectance: Rgb,
}

/// A delta light seen from a point x (visibility and transmittance included), with
/// what its closed-form derivatives in x need (theory.md §2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum DirectLight<S: Dim> {
    /// A point light: I·T/r^{d−1} at x.
    Point {
        position: S::Vec,
        intensity: Rgb,
        /// Transmittance from x to the light.
        transmittance: Rgb,
    },
    /// A directional light (a collimated beam in 2D, a sun in 3D — its cone, if any,
    /// taken at its centre): E·T, with the medium depth along `to_light` and its
    /// gradient in x (the depth is piecewise linear in x).
    Directional {
        to_light: S::Vec,
        irradiance: Rgb,
        depth: f64,
        depth_grad: S::Vec,
        transmittance: Rgb,
    },
}

/// An isotropic point light of intensity I (W per unit angle or solid angle): it
/// lights a point at distance r with I·T/r^{d−1} (theory.md §1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight<S: Dim> {
    pub position: S::Vec,
    pub intensity: Rgb,
}

/// Radius of the sphere (circle) where unbounded media end, in scene sizes.
pub const WORLD_RADIUS: f64 = 1e3;

/// The scene as the method sees it.
pub trait World: Sync {
    type S: Dim;
    type Region: Region<Self::S>;

    /// The scene's length scale (its diagonal).
    fn scale(&self) -> f64;
    /// Closest hit along o + t·d with t < t_max, ignoring primitive `skip`.
    fn closest_hit(&self, o: VecOf<Self>, d: VecOf<Self>, t_max: f64, skip: Option<u32>) -> Option<Hit>;
    /// Is o + t·d blocked for some t < t_max (other than by `skip`)?
    fn occluded(&self, o: VecOf<Self>, d: VecOf<Self>, t_max: f64, skip: Option<u32>) -> bool;
    /// The occluders whose bounding boxes overlap the box [`lo`, `hi`], into
    /// `out` in increasing index; false when there are more than `limit` or the
    /// world cannot list them (then only [`World::occluded`] answers).
    fn occluders_in_box(&self, _lo: VecOf<Self>, _hi: VecOf<Self>, _limit: usize, _out: &mut Vec<u32>) -> bool {
        false
    }
    /// [`World::occluded`] (nothing skipped) testing only the occluders `ids`: the
    /// same answer whenever `ids` lists every occluder near the ray's span (as
    /// [`World::occluders_in_box`] of a box holding it does).
    fn occluded_among(&self, _ids: &[u32], o: VecOf<Self>, d: VecOf<Self>, t_max: f64) -> bool {
        self.occluded(o, d, t_max, None)
    }
    /// The centre of the scene's bounds.
    fn centre(&self) -> VecOf<Self>;
    /// Distance along p + t·d to the sphere of [`WORLD_RADIUS`] scene sizes around
    /// the centre, where unbounded media end (0 outside it): paths leaving it escape,
    /// so a thin non-absorbing fog cannot keep a path scattering far away forever.
    fn world_exit(&self, p: VecOf<Self>, d: VecOf<Self>) -> f64 {
        let r = WORLD_RADIUS * self.scale();
        let o = p - self.centre();
        let b = <Self::S as crate::core::space::Space>::dot(o, d);
        let disc = b * b - (<Self::S as crate::core::space::Space>::length_squared(o) - r * r);
        if disc <= 0.0 { 0.0 } else { (-b + disc.sqrt()).max(0.0) }
    }
    fn medium(&self) -> Option<&Medium<Self::S, Self::Region>>;
    /// The medium at `p`, if any.
    fn medium_at(&self, p: VecOf<Self>) -> Option<&Medium<Self::S, Self::Region>> {
        self.medium().filter(|m| m.contains(p))
    }
    /// Transmittance along p + t·w for t in [0, dist] (one in vacuum).
    fn transmittance(&self, p: VecOf<Self>, w: VecOf<Self>, dist: f64) -> Rgb {
        self.medium().map_or(Rgb::ONE, |m| m.transmittance(p, w, dist))
    }

    /// The point of primitive `prim`'s boundary that `x` sees strictly between the
    /// directions `d_in` (which meets it) and `d_out`, in the plane through x they
    /// span (in 2D, the segment's end between them), if there is one.
    fn silhouette(&self, prim: u32, x: VecOf<Self>, d_in: VecOf<Self>, d_out: VecOf<Self>) -> Option<VecOf<Self>>;

    /// The unit direction of primitive `prim`'s boundary edge through `p` (a point
    /// [`Self::silhouette`] returned), where the boundary has one (3D); `None` in 2D,
    /// where a silhouette is a point.
    fn edge_direction(&self, _prim: u32, _p: VecOf<Self>) -> Option<VecOf<Self>> {
        None
    }

    /// Where primitive `prim` ends nearest `x`, into `out`: points of its boundary
    /// (2D: the segment's two ends; 3D: the point of each triangle edge nearest x),
    /// each with the unit direction, in the primitive's plane, that leaves it
    /// there; for [`super::seen_ends::nearest_seen_end`]. Default: none.
    fn primitive_ends(&self, _prim: u32, _x: VecOf<Self>, _out: &mut Vec<(VecOf<Self>, VecOf<Self>)>) {}

    /// The surface point of `hit`, found by a ray travelling along `dir`.
    fn surface(&self, hit: &Hit, dir: VecOf<Self>) -> SurfacePoint<Self::S>;

    /// Light from delta lights arriving at `p`, weighted by `lobe` (`skip`: the
    /// primitive `p` lies on); `each` sees every light's direction and share
    /// (through [`super::nee::light_sample`]).
    fn delta_lights_each(
        &self,
        p: VecOf<Self>,
        lobe: &Lobe<Self::S>,
        skip: Option<u32>,
        rays: &mut u64,
        each: &mut impl FnMut(VecOf<Self>, Rgb),
    ) -> Rgb;
    /// The scene's point lights (part of [`World::delta_lights_each`]'s light): the
    /// path tracer also samples them along its legs (`super::point_leg`).
    fn point_lights(&self) -> &[PointLight<Self::S>] {
        &[]
    }
    /// [`World::delta_lights_each`] without the point lights: the directional
    /// delta lights (collimated beams in 2D, suns without a cone in 3D).
    fn directional_lights_each(
        &self,
        p: VecOf<Self>,
        lobe: &Lobe<Self::S>,
        skip: Option<u32>,
        rays: &mut u64,
        each: &mut impl FnMut(VecOf<Self>, Rgb),
    ) -> Rgb;
    /// [`World::delta_lights_each`] without an observer.
    fn delta_lights(&self, p: VecOf<Self>, lobe: &Lobe<Self::S>, skip: Option<u32>, rays: &mut u64) -> Rgb {
        self.delta_lights_each(p, lobe, skip, rays, &mut ignore)
    }
    /// One sample of the light from lights with an extent (emitters, sky, sun
    /// cones) arriving at `p`, weighted by `lobe`; with `mis`, carrying the power
    /// heuristic's weight against lobe sampling; `each` sees every sample's
    /// direction and share.
    #[allow(clippy::too_many_arguments)] // the vertex state is spelled out
    fn sampled_nee_each(
        &self,
        p: VecOf<Self>,
        lobe: &Lobe<Self::S>,
        skip: Option<u32>,
        mis: bool,
        s: &mut Sampler,
        rays: &mut u64,
        each: &mut impl FnMut(VecOf<Self>, Rgb),
    ) -> Rgb;
    /// [`World::sampled_nee_each`] without an observer.
    #[allow(clippy::too_many_arguments)] // the vertex state is spelled out
    fn sampled_nee(
        &self,
        p: VecOf<Self>,
        lobe: &Lobe<Self::S>,
        skip: Option<u32>,
        mis: bool,
        s: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        self.sampled_nee_each(p, lobe, skip, mis, s, rays, &mut ignore)
    }
    /// All next-event estimation at a path vertex.
    #[allow(clippy::too_many_arguments)] // the vertex state is spelled out
    fn nee(
        &self,
        p: VecOf<Self>,
        lobe: &Lobe<Self::S>,
        skip: Option<u32>,
        mis: bool,
        s: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        self.delta_lights(p, lobe, skip, rays) + self.sampled_nee(p, lobe, skip, mis, s, rays)
    }
    /// Whether any light has an extent a ray can meet (an emitting primitive, a
    /// sky), as opposed to delta lights alone.
    fn has_extended_lights(&self) -> bool;
    /// The pdf with which [`World::sampled_nee`] at `from` picks point `y` of
    /// emitting primitive `prim` (per unit angle or solid angle).
    fn emitter_pdf(&self, from: VecOf<Self>, prim: u32, y: VecOf<Self>) -> f64;
    /// Radiance arriving along a ray that leaves the scene in direction `w`, MIS-
    /// weighted against NEE when `w` was lobe-sampled with pdf `lobe_pdf`.
    fn escaped(&self, _w: VecOf<Self>, _lobe_pdf: Option<f64>) -> Rgb {
        Rgb::ZERO
    }
    /// Radiance carried by a probe ray that leaves the scene (lights kept apart for
    /// the direct part, such as sun cones, excluded).
    fn escaped_probe(&self, _w: VecOf<Self>) -> Rgb {
        Rgb::ZERO
    }

    /// The direct part of L_s (theory.md §2) at a medium point, weighted by `lobe`:
    /// what a radiance cache evaluates per query point instead of caching.
    fn direct_part(&self, p: VecOf<Self>, lobe: &Lobe<Self::S>, _s: &mut Sampler, rays: &mut u64) -> Rgb {
        self.delta_lights(p, lobe, None, rays)
    }
    /// The delta lights visible from `x`, and the shadow rays this cost.
    fn direct_lights(&self, x: VecOf<Self>) -> (Vec<DirectLight<Self::S>>, u64);
}

/// A light-sample observer that ignores every sample (see
/// [`super::nee::light_sample`]).
#[inline]
pub fn ignore<V>(_: V, _: Rgb) {}

/// The vector type of a world's dimension.
pub type VecOf<W> = <<W as World>::S as crate::core::space::Space>::Vec;
