//! The 3D renderer: what is particular to 3D — the scene file format and its
//! validation, triangles (quads, boxes, OBJ meshes), point / sun / sky / area lights,
//! box media, the pinhole camera, progressive images and the camera-march query
//! points of a cached render. The method itself (path tracing, BVH, probes,
//! proxies, derivatives, cache placement) is `crate::pipeline`'s, for `D3`.
//!
//! scene_desc (JSON) → validate → scene (triangles, BVH, lights, medium) →
//! render (progressive path-traced image), or camera_march (query points) →
//! cached (pipeline placement; reconstruction; surface_cache for the first
//! surfaces) → records_file (shared by tiles).

pub mod cached;
pub mod cached_params;
pub mod camera;
pub mod camera_march;
pub mod image_split;
pub mod lights;
mod march_image;
pub mod march_lights;
pub mod medium;
pub mod mesh;
pub mod orbit;
pub mod reconstruct;
pub mod records_file;
pub mod render;
pub mod scene;
pub mod scene_desc;
mod scene_world;
pub mod surface_cache;
pub mod validate;
