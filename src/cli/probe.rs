//! `volcache probe`: L_s (or fluence) and its parts at points of a 2D or 3D scene,
//! or the mean irradiance over a sensor ([`super::probe_sensor`]). Every number is
//! `pipeline::path`'s estimate, the same in both dimensions.

use super::common::{AnyScene, check_angle, load_any_scene};
use super::probe_args::{Method, ProbeArgs, ProbeQuantity};
use super::probe_common::{Common, PartsOut, coords_of, std_error_out};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;
use std::process::ExitCode;
use volcache::core::color::{Rgb, luminance};
use volcache::pipeline::path::{Query, estimate};
use volcache::pipeline::world::{VecOf, World};

#[derive(Serialize)]
struct ProbeOut {
    /// X,Y (2D) or X,Y,Z (3D).
    at: Vec<f64>,
    method: Method,
    quantity: ProbeQuantity,
    /// ω_o of L_s in degrees (2D only; 3D: towards the camera, see `omega_o`).
    #[serde(skip_serializing_if = "Option::is_none")]
    omega_o_deg: Option<f64>,
    /// The unit direction in which L_s leaves the point.
    omega_o: Vec<f64>,
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
    let scene = load_any_scene(a.scene.as_deref())?;
    let quantity = match (a.quantity, &scene) {
        (Some(q), _) => q,
        (None, _) if !a.sensor.is_empty() => ProbeQuantity::Irradiance,
        (None, AnyScene::Flat(s)) => s.desc.render.quantity.into(),
        (None, AnyScene::Volume(_)) => ProbeQuantity::Ls,
    };
    if quantity == ProbeQuantity::Irradiance || !a.sensor.is_empty() {
        return super::probe_sensor::run(&a, quantity, &scene);
    }
    anyhow::ensure!(
        !a.at.is_empty(),
        "--at: give at least one point (X,Y; in 3D X,Y,Z), or a --sensor for irradiance"
    );
    let out = match &scene {
        AnyScene::Flat(s) if a.method != Method::Pt => return super::probe_derivs::run(&a, s),
        AnyScene::Flat(s) => {
            let r = &s.desc.render;
            let c = Common::new(&a, r.spp, r.seed, r.max_depth)?;
            let deg = a.omega_o.unwrap_or(r.omega_o_deg);
            check_angle("--omega-o", deg)?;
            let w = DVec2::from_angle(deg.to_radians());
            at_points(&**s, &a.points2()?, &c, a.method, quantity, Some(deg), |_| w)
        }
        AnyScene::Volume(s) if a.method != Method::Pt => return super::probe_derivs::run3(&a, s),
        AnyScene::Volume(s) => {
            anyhow::ensure!(
                a.omega_o.is_none(),
                "--omega-o: in a 3D scene L_s leaves each point towards the camera, as render3d caches it"
            );
            let r = &s.desc.render;
            let c = Common::new(&a, r.spp, r.seed, r.max_depth)?;
            let cam = &s.camera;
            // ω_o towards the camera; at the camera itself, against the view.
            let towards = |x: DVec3| (cam.position - x).try_normalize().unwrap_or(-cam.forward);
            at_points(&**s, &a.points3()?, &c, a.method, quantity, None, towards)
        }
    };
    print_points(&out, a.json)
}

/// The estimate at each point (in parallel over points; each point's streams
/// are its own, so the result does not depend on the thread count).
fn at_points<W: World>(
    world: &W,
    points: &[VecOf<W>],
    c: &Common,
    method: Method,
    quantity: ProbeQuantity,
    omega_o_deg: Option<f64>,
    omega_o: impl Fn(VecOf<W>) -> VecOf<W> + Sync,
) -> Vec<ProbeOut> {
    points
        .par_iter()
        .enumerate()
        .map(|(k, &x)| {
            let t = std::time::Instant::now();
            let w = omega_o(x);
            let q = match quantity {
                ProbeQuantity::Fluence => Query::Fluence,
                _ => Query::InScattered { omega_o: w },
            };
            let e = estimate(world, x, &q, &c.settings, c.spp, c.seed, k as u64);
            ProbeOut {
                at: coords_of::<W::S>(x),
                method,
                quantity,
                omega_o_deg,
                omega_o: coords_of::<W::S>(w),
                inside_medium: world.medium_at(x).is_some(),
                value: (&e.mean).into(),
                std_error: std_error_out(&e),
                luminance: luminance(e.mean.total()),
                spp: c.spp,
                seed: c.seed,
                rays: e.rays,
                seconds: t.elapsed().as_secs_f64(),
            }
        })
        .collect()
}

fn print_points(out: &[ProbeOut], json: bool) -> anyhow::Result<ExitCode> {
    if json {
        println!("{}", serde_json::to_string_pretty(out)?);
        return Ok(ExitCode::SUCCESS);
    }
    let fmt = |c: [f64; 3]| format!("{:.5e}", luminance(Rgb::from_array(c)));
    println!(
        "{:>28} {:>12} {:>12} {:>12} {:>12} {:>10}",
        "point", "direct", "single", "multiple", "total", "rays"
    );
    for o in out {
        let at: Vec<String> = o.at.iter().map(|v| v.to_string()).collect();
        println!(
            "{:>28} {:>12} {:>12} {:>12} {:>12} {:>10}",
            format!("({})", at.join(", ")),
            fmt(o.value.direct),
            fmt(o.value.single),
            fmt(o.value.multiple),
            fmt(o.value.total),
            o.rays
        );
    }
    if let Some(o) = out.first() {
        println!("(luminance; {} samples per point, seed {})", o.spp, o.seed);
    }
    Ok(ExitCode::SUCCESS)
}
