//! `volcache probe --method aware|unaware|reference`: L_s with gradient and Hessian
//! (and the Hessian's eigen-decomposition) per part.

use super::common::{check_angle, check_count, check_range, check_spp, load_scene};
use super::probe_args::{Method, ProbeArgs};
use glam::DVec2;
use serde::Serialize;
use std::process::ExitCode;
use volcache::core::space::{D2, Space};
use volcache::core::taylor::Taylor2;
use volcache::core::taylor_rgb::TaylorRgb;
use volcache::limits;
use volcache::pipeline::derivatives::{self, AwareSettings, ReferenceSettings};
use volcache::pipeline::path::Settings;
use volcache::pipeline::probe::{Outgoing, ProbeSettings};
use volcache::progress::Progress;
use volcache::study::light_field_derivs::derivatives_at;

type PartDerivs = volcache::pipeline::derivatives::PartDerivs<D2>;
type Derivatives = volcache::pipeline::derivatives::Derivatives<D2>;

#[derive(Serialize)]
pub struct TaylorOut {
    pub value: f64,
    pub gradient: [f64; 2],
    pub hessian: [[f64; 2]; 2],
    /// Ascending eigenvalues of the Hessian and their unit eigenvectors.
    pub eigenvalues: [f64; 2],
    pub eigenvectors: [[f64; 2]; 2],
}

impl From<&Taylor2<D2>> for TaylorOut {
    fn from(t: &Taylor2<D2>) -> Self {
        let (vals, vecs) = D2::sym_eigen(t.hess);
        TaylorOut {
            value: t.value,
            gradient: t.grad.to_array(),
            hessian: [t.hess.x_axis.to_array(), t.hess.y_axis.to_array()],
            eigenvalues: vals.to_array(),
            eigenvectors: [vecs.x_axis.to_array(), vecs.y_axis.to_array()],
        }
    }
}

#[derive(Serialize)]
pub struct PartOut {
    /// Luminance with its derivatives (what the error metric uses).
    pub luminance: TaylorOut,
    /// Per channel value, gradient and Hessian.
    pub rgb: [TaylorOut; 3],
}

impl From<&TaylorRgb<D2>> for PartOut {
    fn from(t: &TaylorRgb<D2>) -> Self {
        PartOut {
            luminance: (&t.luminance()).into(),
            rgb: t.channels.each_ref().map(|c| c.into()),
        }
    }
}

#[derive(Serialize)]
pub struct DerivOut {
    pub at: [f64; 2],
    pub method: Method,
    pub has_hessian: bool,
    pub direct: PartOut,
    pub single: PartOut,
    pub multiple: PartOut,
    pub total: PartOut,
    pub rays: u64,
    pub seconds: f64,
}

pub fn run(a: &ProbeArgs) -> anyhow::Result<ExitCode> {
    let scene = load_scene(a.scene.as_deref())?;
    let r = &scene.desc.render;
    check_count("--rays", a.rays as u64, 1 << 20)?;
    anyhow::ensure!(a.rays >= 3, "--rays must be at least 3");
    check_count("--steps", a.steps as u64, 4096)?;
    check_count("--paths", a.paths as u64, 1024)?;
    check_range("--fd-step", a.fd_step, limits::FD_STEP)?;
    check_range("--medium-clamp", a.medium_clamp, limits::MEDIUM_CLAMP)?;
    if let Some(spp) = a.spp {
        check_spp("--spp", spp, limits::MAX_PROBE_SPP)?;
    }
    let seed = a.seed.unwrap_or(r.seed);
    let omega_deg = a.omega_o.unwrap_or(r.omega_o_deg);
    check_angle("--omega-o", omega_deg)?;
    let omega_o = DVec2::from_angle(omega_deg.to_radians());
    let settings = Settings {
        max_depth: r.max_depth,
        ..Settings::default()
    };
    let ps = ProbeSettings {
        rays: a.rays,
        paths: a.paths.max(1),
        steps: a.steps.max(1),
        settings,
        ..ProbeSettings::default_for::<volcache::core::space::D2>()
    };
    let rs = ReferenceSettings {
        spp: a.spp.unwrap_or(ReferenceSettings::default().spp),
        relative_step: a.fd_step,
    };
    let aw = AwareSettings {
        medium_clamp: a.medium_clamp,
        rule: a.rule,
    };
    let method = match a.method {
        Method::Aware => derivatives::Method::Aware,
        Method::Unaware => derivatives::Method::Unaware,
        Method::Reference => derivatives::Method::Reference,
        Method::Pt => unreachable!("`probe` runs pt itself"),
    };
    let out = Outgoing::Direction(omega_o);
    let mut outs = Vec::new();
    for &x in &a.at {
        // A handle of its own: nothing cancels a probe (it takes a second).
        let d = derivatives_at(&scene, x, out, method, &ps, &rs, &aw, seed, &Progress::new())?;
        outs.push(to_out(&d, a.method));
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&outs)?);
    } else {
        for o in &outs {
            let t = &o.total.luminance;
            println!(
                "({}, {}) {:?}: L = {:.5e}  ∇L = ({:.4e}, {:.4e})  λ(H) = ({:.4e}, {:.4e})  [{} rays, {:.2} s]",
                o.at[0],
                o.at[1],
                o.method,
                t.value,
                t.gradient[0],
                t.gradient[1],
                t.eigenvalues[0],
                t.eigenvalues[1],
                o.rays,
                o.seconds
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn to_out(d: &Derivatives, method: Method) -> DerivOut {
    let p: &PartDerivs = &d.parts;
    DerivOut {
        at: d.at.to_array(),
        method,
        has_hessian: d.has_hessian,
        direct: (&p.direct).into(),
        single: (&p.single).into(),
        multiple: (&p.multiple).into(),
        total: (&p.total()).into(),
        rays: d.rays,
        seconds: d.seconds,
    }
}
