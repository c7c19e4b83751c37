//! The 3D renderer: scenes of quads, boxes and OBJ meshes with diffuse materials,
//! point / sun / sky / area lights and a homogeneous medium; an f64 binned-SAH BVH;
//! the reference volumetric path tracer; and radiance caching on the shared core.
//!
//! scene_desc (JSON) → validate → scene (triangles, BVH, lights, medium) →
//! transport (path tracer) → render (progressive image), or
//! camera_march (query points) → cached (placement: probe → proxy → derivatives →
//! core::metric / core::cache; reconstruction) → records_file (shared by tiles).

pub mod bvh;
pub mod cached;
pub mod camera;
pub mod camera_march;
pub mod derivatives;
pub mod lights;
pub mod medium;
pub mod mesh;
pub mod probe;
pub mod proxy;
pub mod reconstruct;
pub mod records_file;
pub mod render;
pub mod scene;
pub mod scene_desc;
pub mod sphere;
pub mod transport;
pub mod validate;
