//! `volcache probe --method aware|unaware|reference`: L_s with gradient and Hessian
//! (and the Hessian's eigen-decomposition) per part.

use super::common::{check_angle, check_count, check_range, check_spp};
use super::probe_args::{Method, ProbeArgs};
use super::probe_common::coords_of;
use glam::{DVec2, DVec3};
use serde::Serialize;
use std::process::ExitCode;
use volcache::core::space::{D2, D3, Space};
use volcache::core::taylor::Taylor2;
use volcache::core::taylor_rgb::TaylorRgb;
use volcache::limits;
use volcache::pipeline::derivatives::{self, AwareSettings, Derivatives, PartDerivs, ReferenceSettings};
use volcache::pipeline::dim::Dim;
use volcache::pipeline::path::Settings;
use volcache::pipeline::probe::{Outgoing, ProbeSettings};
use volcache::pipeline::world::{VecOf, World};
use volcache::progress::Progress;
use volcache::study::light_field_derivs::derivatives_at;

/// A value with its gradient and Hessian (2 or 3 components: the scene's dimension).
#[derive(Serialize)]
pub struct TaylorOut {
    pub value: f64,
    pub gradient: Vec<f64>,
    pub hessian: Vec<Vec<f64>>,
    /// Ascending eigenvalues of the Hessian and their unit eigenvectors.
    pub eigenvalues: Vec<f64>,
    pub eigenvectors: Vec<Vec<f64>>,
}

fn matrix<S: Space>(m: S::Mat) -> Vec<Vec<f64>> {
    (0..S::DIM).map(|c| coords_of::<S>(S::col(m, c))).collect()
}

fn taylor_out<S: Space>(t: &Taylor2<S>) -> TaylorOut {
    let (vals, vecs) = S::sym_eigen(t.hess);
    TaylorOut {
        value: t.value,
        gradient: coords_of::<S>(t.grad),
        hessian: matrix::<S>(t.hess),
        eigenvalues: coords_of::<S>(vals),
        eigenvectors: matrix::<S>(vecs),
    }
}

#[derive(Serialize)]
pub struct PartOut {
    /// Luminance with its derivatives (what the error metric uses).
    pub luminance: TaylorOut,
    /// Per channel value, gradient and Hessian.
    pub rgb: [TaylorOut; 3],
}

fn part_out<S: Space>(t: &TaylorRgb<S>) -> PartOut {
    PartOut {
        luminance: taylor_out(&t.luminance()),
        rgb: t.channels.each_ref().map(taylor_out),
    }
}

#[derive(Serialize)]
pub struct DerivOut {
    /// X,Y (2D) or X,Y,Z (3D).
    pub at: Vec<f64>,
    pub method: Method,
    pub has_hessian: bool,
    /// 3D: the unit direction L_s leaves in (towards the camera).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega_o: Option<Vec<f64>>,
    pub direct: PartOut,
    pub single: PartOut,
    pub multiple: PartOut,
    pub total: PartOut,
    pub rays: u64,
    pub seconds: f64,
}

/// The settings every point shares, from the options (checked).
struct Shared {
    ps: ProbeSettings,
    rs: ReferenceSettings,
    aw: AwareSettings,
    method: derivatives::Method,
    seed: u64,
}

fn shared<S: Dim>(a: &ProbeArgs, max_depth: u32, scene_seed: u64) -> anyhow::Result<Shared> {
    check_count("--rays", a.rays as u64, 1 << 20)?;
    anyhow::ensure!(a.rays >= 3, "--rays must be at least 3");
    check_count("--steps", a.steps as u64, 4096)?;
    check_count("--paths", a.paths as u64, 1024)?;
    check_range("--fd-step", a.fd_step, limits::FD_STEP)?;
    check_range("--medium-clamp", a.medium_clamp, limits::MEDIUM_CLAMP)?;
    let grading = a.grading.unwrap_or(S::PROBE_GRADING);
    check_range("--grading", grading, limits::GRADING)?;
    if let Some(spp) = a.spp {
        check_spp("--spp", spp, limits::MAX_PROBE_SPP)?;
    }
    let settings = Settings {
        max_depth,
        ..Settings::default()
    };
    Ok(Shared {
        ps: ProbeSettings {
            rays: a.rays,
            paths: a.paths.max(1),
            steps: a.steps.max(1),
            grading,
            settings,
            ..ProbeSettings::default_for::<S>()
        },
        rs: ReferenceSettings {
            spp: a.spp.unwrap_or(ReferenceSettings::default().spp),
            relative_step: a.fd_step,
        },
        aw: AwareSettings {
            medium_clamp: a.medium_clamp,
            rule: a.rule,
            ..AwareSettings::default()
        },
        method: match a.method {
            Method::Aware => derivatives::Method::Aware,
            Method::Unaware => derivatives::Method::Unaware,
            Method::Reference => derivatives::Method::Reference,
            Method::Pt => unreachable!("`probe` runs pt itself"),
        },
        seed: a.seed.unwrap_or(scene_seed),
    })
}

/// Each point's derivatives (one after the other: each parallelises inside).
fn at_points<W: World>(
    world: &W,
    points: &[VecOf<W>],
    out: impl Fn(VecOf<W>) -> Outgoing<VecOf<W>>,
    sh: &Shared,
    method: Method,
    omega_o: impl Fn(VecOf<W>) -> Option<Vec<f64>>,
) -> anyhow::Result<Vec<DerivOut>> {
    let mut outs = Vec::new();
    for &x in points {
        // A handle of its own: nothing cancels a probe (it takes a second).
        let d = derivatives_at(
            world,
            x,
            out(x),
            sh.method,
            &sh.ps,
            &sh.rs,
            &sh.aw,
            sh.seed,
            &Progress::new(),
        )?;
        outs.push(to_out(&d, method, omega_o(x)));
    }
    Ok(outs)
}

/// A 2D scene: L_s towards `--omega-o` (the scene's ω_o by default).
pub fn run(a: &ProbeArgs, scene: &volcache::flatland::scene::Scene) -> anyhow::Result<ExitCode> {
    let r = &scene.desc.render;
    let sh = shared::<D2>(a, r.max_depth, r.seed)?;
    let omega_deg = a.omega_o.unwrap_or(r.omega_o_deg);
    check_angle("--omega-o", omega_deg)?;
    let w = DVec2::from_angle(omega_deg.to_radians());
    let outs = at_points(
        scene,
        &a.points2()?,
        |_| Outgoing::Direction(w),
        &sh,
        a.method,
        |_| None,
    )?;
    print(&outs, a.json)
}

/// A 3D scene: L_s leaves each point towards the camera, as the 3D cache caches it
/// and the app's 3D probe computes it (same seed, same numbers).
pub fn run3(a: &ProbeArgs, scene: &volcache::volume::scene::Scene) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(
        a.omega_o.is_none(),
        "--omega-o: in a 3D scene L_s leaves each point towards the camera, as render3d caches it"
    );
    let r = &scene.desc.render;
    let sh = shared::<D3>(a, r.max_depth, r.seed)?;
    let eye = scene.camera.position;
    let towards = |x: DVec3| {
        Some(coords_of::<D3>(
            (eye - x).try_normalize().unwrap_or(-scene.camera.forward),
        ))
    };
    let outs = at_points(
        scene,
        &a.points3()?,
        |_| Outgoing::TowardsPoint(eye),
        &sh,
        a.method,
        towards,
    )?;
    print(&outs, a.json)
}

fn print(outs: &[DerivOut], json: bool) -> anyhow::Result<ExitCode> {
    if json {
        println!("{}", serde_json::to_string_pretty(outs)?);
        return Ok(ExitCode::SUCCESS);
    }
    for o in outs {
        let t = &o.total.luminance;
        let v = |x: &[f64]| x.iter().map(|c| format!("{c:.4e}")).collect::<Vec<_>>().join(", ");
        println!(
            "({}) {:?}: L = {:.5e}  ∇L = ({})  λ(H) = ({})  [{} rays, {:.2} s]",
            o.at.iter().map(|c| c.to_string()).collect::<Vec<_>>().join(", "),
            o.method,
            t.value,
            v(&t.gradient),
            v(&t.eigenvalues),
            o.rays,
            o.seconds
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn to_out<S: Dim>(d: &Derivatives<S>, method: Method, omega_o: Option<Vec<f64>>) -> DerivOut {
    let p: &PartDerivs<S> = &d.parts;
    DerivOut {
        at: coords_of::<S>(d.at),
        method,
        has_hessian: d.has_hessian,
        omega_o,
        direct: part_out(&p.direct),
        single: part_out(&p.single),
        multiple: part_out(&p.multiple),
        total: part_out(&p.total()),
        rays: d.rays,
        seconds: d.seconds,
    }
}
