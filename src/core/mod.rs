//! The numeric core shared by 2D and 3D: pure math, no scenes, files, threads or UI.

pub mod color;
pub mod phase;
pub mod rng;
pub mod stats;
pub mod transmittance;
