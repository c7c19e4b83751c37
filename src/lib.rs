//! volcache: a research workbench for light transport in participating media,
//! reproducing "Second-Order Occlusion-Aware Volumetric Radiance Caching"
//! (Marco, Jarabo, Jarosz, Gutierrez; ACM TOG 2018).
//!
//! Layers (see README, "Architecture"):
//! - [`core`]: dimension-generic numerics (phase function, transmittance, RNG streams,
//!   statistics). Knows nothing of scenes, files, threads or UI.
//! - [`pipeline`]: the method once, generic over the dimension: path tracing, BVH,
//!   probe → proxy → derivatives → record → placement.
//! - [`flatland`]: the paper's 2D model: scenes, ray casting, reference estimators,
//!   radiance fields.
//! - [`figure`]: drawing of data it is handed (tiny-skia), PNG/EXR/JSON writers.
//! - [`progress`]: the progress/cancel handle every long-running entry point takes.
//! - [`volume`]: the 3D renderer: scenes, f64 BVH, reference volumetric path tracer.
//! - [`study`]: experiment protocols (equal record count, references on disk,
//!   speed-ups, the gradient study), used by the command line and the app alike.
//! - [`app`]: the interactive workbench (egui/eframe); UI only, it calls the same
//!   functions as the command line.

pub mod app;
pub mod core;
pub mod figure;
pub mod flatland;
pub mod limits;
pub mod output;
pub mod pipeline;
pub mod progress;
pub mod scene_check;
pub mod study;
pub mod volume;
