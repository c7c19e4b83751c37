//! The paper's self-contained 2D ("flatland") model of light transport in media.

pub mod bvh;
pub mod cached_field;
pub mod derivatives;
pub mod direct;
pub mod field;
pub mod geometry;
pub mod lights;
pub mod medium;
pub mod probe;
pub mod proxy;
pub mod scene;
pub mod scene_desc;
pub mod transport;
pub mod validate;
