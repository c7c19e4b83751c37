//! The method, once, generic over the dimension (`S: Dim`, on the core's `Space`):
//! the scene as the method sees it ([`world::World`]), ray casting over primitives
//! ([`bvh`]), path tracing ([`path`]), and the radiance-cache pipeline — a point's
//! light field ([`probe`]) → occlusion-free proxy ([`proxy`]) → aware / unaware /
//! reference derivatives ([`derivatives`]) → a record ([`record`]) → placement over
//! a source of query points ([`placement`]). `flatland` (2D) and `volume` (3D)
//! implement [`world::World`] and supply their query points; nothing here knows
//! files, cameras or images.

pub mod budget;
pub mod bvh;
mod bvh_build;
mod bvh_wide;
pub mod derivatives;
pub mod dim;
pub mod directions;
pub mod emitters;
pub mod eye_cone;
pub mod lamp_aim;
pub mod lobe;
pub mod medium;
pub mod moments;
pub mod moments_sum;
pub mod nee;
pub mod path;
pub mod placement;
pub mod point_leg;
pub mod point_scatter;
pub mod probe;
pub mod proxy;
mod proxy_cut;
pub mod record;
pub mod seen_ends;
pub mod sensor;
pub mod sight;
pub mod silhouette;
pub mod slide;
pub mod surface_cache;
pub mod surface_record;
#[cfg(test)]
mod testing;
pub mod world;
