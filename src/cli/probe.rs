//! `volcache probe`: L_s (or fluence) and its parts at points.

use super::common::{check_angle, check_spp, load_scene};
use super::probe_args::{Method, ProbeArgs};
use glam::DVec2;
use rayon::prelude::*;
use serde::Serialize;
use std::process::ExitCode;
use volcache::core::color::{Rgb, luminance};
use volcache::flatland::scene_desc::Quantity;
use volcache::limits;
use volcache::pipeline::path::{Parts, Query, Settings, estimate};
use volcache::pipeline::world::World;

#[derive(Serialize)]
struct PartsOut {
    direct: [f64; 3],
    single: [f64; 3],
    multiple: [f64; 3],
    total: [f64; 3],
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

#[derive(Serialize)]
struct ProbeOut {
    at: [f64; 2],
    method: Method,
    quantity: Quantity,
    omega_o_deg: f64,
    /// False where the quantity is not defined (L_s outside the medium: zero).
    inside_medium: bool,
    value: PartsOut,
    std_error: PartsOut,
    luminance: f64,
    spp: u32,
    seed: u64,
    rays: u64,
    seconds: f64,
}

pub fn run(a: ProbeArgs) -> anyhow::Result<ExitCode> {
    if a.method != Method::Pt {
        return super::probe_derivs::run(&a);
    }
    let scene = load_scene(a.scene.as_deref())?;
    let r = &scene.desc.render;
    let spp = a.spp.unwrap_or(r.spp.saturating_mul(64));
    check_spp("--spp", spp, limits::MAX_PROBE_SPP)?;
    let seed = a.seed.unwrap_or(r.seed);
    let quantity = a.quantity.map_or(r.quantity, Into::into);
    let omega_deg = a.omega_o.unwrap_or(r.omega_o_deg);
    check_angle("--omega-o", omega_deg)?;
    let q = Query::from_quantity(quantity, DVec2::from_angle(omega_deg.to_radians()));
    let settings = Settings {
        max_depth: r.max_depth,
        ..Settings::default()
    };
    let out: Vec<ProbeOut> =
        a.at.par_iter()
            .enumerate()
            .map(|(k, &x)| {
                let t = std::time::Instant::now();
                let e = estimate(&scene, x, &q, &settings, spp, seed, k as u64);
                let std_error = Parts {
                    direct: e.std_error.direct,
                    single: e.std_error.single,
                    multiple: e.std_error.multiple,
                };
                ProbeOut {
                    at: x.to_array(),
                    method: a.method,
                    quantity,
                    omega_o_deg: omega_deg,
                    inside_medium: scene.medium_at(x).is_some(),
                    value: (&e.mean).into(),
                    std_error: (&std_error).into(),
                    luminance: luminance(e.mean.total()),
                    spp,
                    seed,
                    rays: e.rays,
                    seconds: t.elapsed().as_secs_f64(),
                }
            })
            .collect();
    if a.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        let fmt = |c: [f64; 3]| format!("{:.5e}", luminance(Rgb::from_array(c)));
        println!(
            "{:>22} {:>12} {:>12} {:>12} {:>12} {:>10}",
            "point", "direct", "single", "multiple", "total", "rays"
        );
        for o in &out {
            println!(
                "{:>22} {:>12} {:>12} {:>12} {:>12} {:>10}",
                format!("({}, {})", o.at[0], o.at[1]),
                fmt(o.value.direct),
                fmt(o.value.single),
                fmt(o.value.multiple),
                fmt(o.value.total),
                o.rays
            );
        }
        println!("(luminance; {spp} samples per point, seed {seed})");
    }
    Ok(ExitCode::SUCCESS)
}
