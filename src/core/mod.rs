//! The numeric core shared by 2D and 3D: pure math, no scenes, files, threads or UI.

pub mod cache;
mod cache_index;
pub mod color;
pub mod distance;
pub mod element;
pub mod equal_count;
pub mod equiangular;
pub mod free_flight;
pub mod graded_rule;
pub mod harmonics;
mod lobe_boundary;
pub mod metric;
pub mod mis;
pub mod phase;
pub mod phase_arc;
pub mod phase_patch;
pub mod rng;
pub mod roulette;
pub mod segment_boundary;
pub mod sobol;
pub mod space;
pub mod stats;
pub mod taylor;
pub mod taylor_rgb;
#[cfg(test)]
mod testing;
pub mod transmittance;
pub mod triangle;
pub mod unaware;
