//! The options of `volcache probe`, shared by its path-traced values
//! ([`super::probe`]) and its derivatives ([`super::probe_derivs`]).

use super::common::parse_point;
use super::field::QuantityArg;
use clap::{Args, ValueEnum};
use glam::DVec2;
use serde::Serialize;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Path-traced value (no derivatives).
    Pt,
    /// Occlusion-aware value, gradient and Hessian from proxy elements (ours).
    Aware,
    /// Occlusion-unaware value and gradient (Jarosz et al. 2008).
    Unaware,
    /// Central finite differences of path-traced L_s with common random numbers.
    Reference,
}

#[derive(Args, Debug)]
pub struct ProbeArgs {
    /// Scene JSON (default: the embedded occluder scene).
    pub scene: Option<PathBuf>,
    /// Point X,Y (repeat for several points).
    #[arg(long = "at", value_parser = parse_point, required = true, allow_hyphen_values = true)]
    pub at: Vec<DVec2>,
    #[arg(long, value_enum, default_value = "pt")]
    pub method: Method,
    /// Samples per point (default: 64 × the scene's spp).
    #[arg(long)]
    pub spp: Option<u32>,
    #[arg(long)]
    pub seed: Option<u64>,
    #[arg(long, value_enum)]
    pub quantity: Option<QuantityArg>,
    /// Outgoing direction ω_o of L_s in degrees.
    #[arg(long, allow_hyphen_values = true)]
    pub omega_o: Option<f64>,
    /// Directions per light field (aware, unaware).
    #[arg(long, default_value_t = 4096)]
    pub rays: usize,
    /// Recursive paths per hit and per medium sample (aware, unaware).
    #[arg(long, default_value_t = 1)]
    pub paths: u32,
    /// Ray-marched medium samples per ray (aware, unaware).
    #[arg(long, default_value_t = 24)]
    pub steps: usize,
    /// Finite-difference step as a fraction of the scene size (reference).
    #[arg(long, default_value_t = 1e-2)]
    pub fd_step: f64,
    /// Near-field clamp of medium elements, in march steps (aware).
    #[arg(long, default_value_t = 1.0)]
    pub medium_clamp: f64,
    /// Which radiance a proxy element carries (aware).
    #[arg(long, value_enum, default_value = "farther")]
    pub rule: volcache::pipeline::proxy::RadianceRule,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}
