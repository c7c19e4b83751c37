//! `volcache probe --quantity irradiance --sensor …`: the mean irradiance over the
//! front of a sensor segment (2D) or parallelogram (3D) and the power crossing it,
//! with standard errors ([`volcache::pipeline::sensor`]). The reflectance of the
//! half-space problem (`flatland_scenes/half_space.json`) is the mean irradiance on a
//! sensor below the medium facing it, under a beam of unit irradiance.

use super::common::{AnyScene, Coords};
use super::probe_args::{Method, ProbeArgs, ProbeQuantity, coords};
use super::probe_common::{Common, PartsOut, coords_of, std_error_out};
use glam::{DVec2, DVec3};
use serde::Serialize;
use std::process::ExitCode;
use volcache::core::color::luminance;
use volcache::pipeline::sensor::{Sensor, estimate_irradiance};
use volcache::pipeline::world::World;

#[derive(Serialize)]
struct SensorOut {
    /// The sensor as given: origin + s·u (+ t·v), s, t ∈ [0, 1] (2D: origin = a, u = b − a).
    origin: Vec<f64>,
    u: Vec<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    v: Option<Vec<f64>>,
    /// Unit normal of the measuring (front) side.
    normal: Vec<f64>,
    /// Length (2D, m) or area (3D, m²).
    measure: f64,
    quantity: ProbeQuantity,
    /// Mean irradiance over the sensor (W m⁻¹ in 2D, W m⁻² in 3D), per part.
    value: PartsOut,
    std_error: PartsOut,
    /// Power crossing the sensor towards its back: value × measure (W).
    flux: [f64; 3],
    flux_std_error: [f64; 3],
    luminance: f64,
    spp: u32,
    seed: u64,
    rays: u64,
    seconds: f64,
}

/// What the options must say for an irradiance meter (each error names the option).
fn check_options(a: &ProbeArgs, quantity: ProbeQuantity) -> anyhow::Result<()> {
    anyhow::ensure!(
        quantity == ProbeQuantity::Irradiance,
        "--sensor measures irradiance; it does not apply to --quantity {}",
        format!("{quantity:?}").to_lowercase()
    );
    anyhow::ensure!(
        !a.sensor.is_empty(),
        "--quantity irradiance needs a --sensor: 2D AX,AY,BX,BY (front left of a→b), \
         3D OX,OY,OZ,UX,UY,UZ,VX,VY,VZ (front along u × v)"
    );
    anyhow::ensure!(
        a.method == Method::Pt,
        "--method {}: irradiance is path traced (--method pt); derivatives are of L_s",
        format!("{:?}", a.method).to_lowercase()
    );
    anyhow::ensure!(
        a.at.is_empty(),
        "--at: irradiance is measured on a --sensor, not at points"
    );
    anyhow::ensure!(a.omega_o.is_none(), "--omega-o does not apply to irradiance");
    Ok(())
}

pub fn run(a: &ProbeArgs, quantity: ProbeQuantity, scene: &AnyScene) -> anyhow::Result<ExitCode> {
    check_options(a, quantity)?;
    let bad = |c: &Coords, e| anyhow::anyhow!("--sensor {}: {e}", c.text);
    let out = match scene {
        AnyScene::Flat(s) => {
            let r = &s.desc.render;
            let c = Common::new(a, r.spp, r.seed, r.max_depth)?;
            let sensors = a.sensor.iter().map(|t| {
                let [ax, ay, bx, by] = coords(t, "--sensor", "AX,AY,BX,BY (a 2D sensor segment)")?;
                Sensor::segment(DVec2::new(ax, ay), DVec2::new(bx, by), s.scale()).map_err(|e| bad(t, e))
            });
            measure(&**s, &sensors.collect::<anyhow::Result<Vec<_>>>()?, &c)
        }
        AnyScene::Volume(s) => {
            let r = &s.desc.render;
            let c = Common::new(a, r.spp, r.seed, r.max_depth)?;
            let sensors = a.sensor.iter().map(|t| {
                let form = "OX,OY,OZ,UX,UY,UZ,VX,VY,VZ (a 3D sensor parallelogram: corner, edge u, edge v)";
                let v: [f64; 9] = coords(t, "--sensor", form)?;
                let p = |k: usize| DVec3::new(v[k], v[k + 1], v[k + 2]);
                Sensor::parallelogram(p(0), p(3), p(6), s.scale()).map_err(|e| bad(t, e))
            });
            measure(&**s, &sensors.collect::<anyhow::Result<Vec<_>>>()?, &c)
        }
    };
    print(&out, a.json)
}

/// Each sensor's estimate (sensor k draws from the streams of item k; the samples
/// of one sensor run in parallel blocks, so one long measurement uses every core).
fn measure<W: World>(world: &W, sensors: &[Sensor<W::S>], c: &Common) -> Vec<SensorOut> {
    let mut out = Vec::new();
    for (k, sn) in sensors.iter().enumerate() {
        let t = std::time::Instant::now();
        let e = estimate_irradiance(world, sn, &c.settings, c.spp, c.seed, k as u64);
        let (total, se) = (e.mean.total(), e.total_std_error);
        out.push(SensorOut {
            origin: coords_of::<W::S>(sn.origin),
            u: coords_of::<W::S>(sn.u),
            v: sn.v.map(coords_of::<W::S>),
            normal: coords_of::<W::S>(sn.normal),
            measure: sn.measure,
            quantity: ProbeQuantity::Irradiance,
            value: (&e.mean).into(),
            std_error: std_error_out(&e),
            flux: (total * sn.measure).to_array(),
            flux_std_error: (se * sn.measure).to_array(),
            luminance: luminance(total),
            spp: c.spp,
            seed: c.seed,
            rays: e.rays,
            seconds: t.elapsed().as_secs_f64(),
        });
    }
    out
}

fn print(out: &[SensorOut], json: bool) -> anyhow::Result<ExitCode> {
    if json {
        println!("{}", serde_json::to_string_pretty(out)?);
        return Ok(ExitCode::SUCCESS);
    }
    for o in out {
        let lum = |c: [f64; 3]| luminance(volcache::core::color::Rgb::from_array(c));
        println!(
            "sensor origin {:?} u {:?}{}: irradiance {:.6e} ± {:.2e} (direct {:.4e}, single {:.4e}, multiple {:.4e}); \
             flux {:.6e} ± {:.2e}; {} samples, seed {}, {} rays, {:.2} s",
            o.origin,
            o.u,
            o.v.as_ref().map_or(String::new(), |v| format!(" v {v:?}")),
            o.luminance,
            lum(o.std_error.total),
            lum(o.value.direct),
            lum(o.value.single),
            lum(o.value.multiple),
            lum(o.flux),
            lum(o.flux_std_error),
            o.spp,
            o.seed,
            o.rays,
            o.seconds
        );
    }
    Ok(ExitCode::SUCCESS)
}
