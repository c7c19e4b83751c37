//! The 3D renderer (issue 6, first half): scenes of quads, boxes and OBJ meshes with
//! diffuse materials, point / sun / sky / area lights and a homogeneous medium;
//! an f64 binned-SAH BVH; the reference volumetric path tracer and image rendering.
//!
//! scene_desc (JSON) → validate → scene (triangles, BVH, lights, medium) →
//! transport (path tracer) → render (progressive image).

pub mod bvh;
pub mod camera;
pub mod derivatives;
pub mod lights;
pub mod medium;
pub mod mesh;
pub mod probe;
pub mod proxy;
pub mod render;
pub mod scene;
pub mod scene_desc;
pub mod sphere;
pub mod transport;
pub mod validate;
