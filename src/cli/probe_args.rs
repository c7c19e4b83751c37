//! The options of `volcache probe`, shared by its path-traced values
//! ([`super::probe`]), its irradiance meters ([`super::probe_sensor`]) and its
//! derivatives ([`super::probe_derivs`]).

use super::common::{Coords, parse_coords};
use clap::{Args, ValueEnum};
use glam::{DVec2, DVec3};
use serde::Serialize;
use std::path::PathBuf;
use volcache::flatland::scene_desc::Quantity;

/// What `probe` estimates.
#[derive(Clone, Copy, Debug, ValueEnum, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ProbeQuantity {
    /// In-scattered radiance L_s at points.
    Ls,
    /// Fluence at points.
    Fluence,
    /// Mean irradiance over the front of a `--sensor`.
    Irradiance,
}

impl From<Quantity> for ProbeQuantity {
    fn from(q: Quantity) -> Self {
        match q {
            Quantity::Ls => ProbeQuantity::Ls,
            Quantity::Fluence => ProbeQuantity::Fluence,
        }
    }
}

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
    /// Point X,Y (3D scenes: X,Y,Z); repeat for several points.
    #[arg(long = "at", value_parser = parse_coords, allow_hyphen_values = true)]
    pub at: Vec<Coords>,
    /// Irradiance meter (implies `--quantity irradiance`; repeat for several). 2D: the
    /// segment AX,AY,BX,BY, measuring light arriving at its left side (as scene
    /// segments' front). 3D: the parallelogram OX,OY,OZ,UX,UY,UZ,VX,VY,VZ (corner and
    /// two edges, front along u × v, as scene quads).
    #[arg(long, value_parser = parse_coords, allow_hyphen_values = true)]
    pub sensor: Vec<Coords>,
    #[arg(long, value_enum, default_value = "pt")]
    pub method: Method,
    /// Samples per point (default: 64 × the scene's spp).
    #[arg(long)]
    pub spp: Option<u32>,
    #[arg(long)]
    pub seed: Option<u64>,
    /// Default: the scene's (2D), L_s (3D), irradiance with `--sensor`.
    #[arg(long, value_enum)]
    pub quantity: Option<ProbeQuantity>,
    /// Outgoing direction ω_o of L_s in degrees (2D; in 3D L_s leaves towards the camera).
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
    /// Refinement of the march towards x: 0 spaces the samples evenly, k > 0 makes
    /// the first steps k/(e^k − 1) of the even step (see `pipeline::probe::March`).
    /// Default: measured per dimension (6 in 2D, 0 in 3D).
    #[arg(long)]
    pub grading: Option<f64>,
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

impl ProbeArgs {
    /// The `--at` points of a 2D scene.
    pub fn points2(&self) -> anyhow::Result<Vec<DVec2>> {
        self.at
            .iter()
            .map(|c| Ok(DVec2::from_array(coords(c, "--at", "X,Y")?)))
            .collect()
    }

    /// The `--at` points of a 3D scene.
    pub fn points3(&self) -> anyhow::Result<Vec<DVec3>> {
        self.at
            .iter()
            .map(|c| Ok(DVec3::from_array(coords(c, "--at", "X,Y,Z")?)))
            .collect()
    }
}

/// Exactly N numbers, else an error naming the option and the expected form.
pub fn coords<const N: usize>(c: &Coords, flag: &str, form: &str) -> anyhow::Result<[f64; N]> {
    c.values
        .as_slice()
        .try_into()
        .map_err(|_| anyhow::anyhow!("{flag} {}: expected {N} numbers {form}, got {}", c.text, c.values.len()))
}
