//! What `probe`'s point values ([`super::probe`]) and irradiance meters
//! ([`super::probe_sensor`]) share: samples and path settings over the scene's
//! defaults, and the JSON shape of an estimate's parts.

use super::common::check_spp;
use super::probe_args::ProbeArgs;
use serde::Serialize;
use volcache::core::space::Space;
use volcache::limits;
use volcache::pipeline::path::{Estimate, Parts, Settings};

#[derive(Serialize)]
pub struct PartsOut {
    pub direct: [f64; 3],
    pub single: [f64; 3],
    pub multiple: [f64; 3],
    pub total: [f64; 3],
}

impl From<&Parts> for PartsOut {
    fn from(p: &Parts) -> Self {
        PartsOut {
            direct: p.direct.to_array(),
            single: p.single.to_array(),
            multiple: p.multiple.to_array(),
            total: p.total().to_array(),
        }
    }
}

/// Standard errors per part, and of the total (not the parts' sum).
pub fn std_error_out(e: &Estimate) -> PartsOut {
    PartsOut {
        total: e.total_std_error.to_array(),
        ..(&e.std_error).into()
    }
}

/// A vector's coordinates, in either dimension.
pub fn coords_of<S: Space>(v: S::Vec) -> Vec<f64> {
    (0..S::DIM).map(|k| v[k]).collect()
}

/// What every quantity shares: samples, seed, path settings.
pub struct Common {
    pub spp: u32,
    pub seed: u64,
    pub settings: Settings,
}

impl Common {
    /// The options over the scene's `render` defaults (64 × its spp per point).
    pub fn new(a: &ProbeArgs, spp: u32, seed: u64, max_depth: u32) -> anyhow::Result<Common> {
        let spp = a.spp.unwrap_or(spp.saturating_mul(64));
        check_spp("--spp", spp, limits::MAX_PROBE_SPP)?;
        Ok(Common {
            spp,
            seed: a.seed.unwrap_or(seed),
            settings: Settings {
                max_depth,
                ..Settings::default()
            },
        })
    }
}
