//! The paper's self-contained 2D ("flatland") model: what is particular to 2D — the
//! scene file format and its validation, segments, point and collimated lights and
//! emitting segments, polygonal media, and radiance fields over the domain. The
//! method itself (path tracing, probes, proxies, derivatives, cache placement) is
//! `crate::pipeline`'s, for `D2`.

pub mod cached_field;
pub mod field;
pub mod geometry;
pub mod lights;
pub mod medium;
pub mod scene;
pub mod scene_desc;
mod scene_world;
pub mod shipped;
pub mod validate;
