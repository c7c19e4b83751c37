//! The 3D probe: a point on a pixel's camera ray (the pixel clicked in the view,
//! a depth along its ray), the light field captured there and what ours and
//! Jarosz 2008 derive from it — one shared light field, as in 2D, computed by
//! the library function `volcache probe --method aware|unaware` calls with the
//! same point and seed ([`study::light_field_derivs`]) — plus, on demand, the
//! finite-difference reference. L_s leaves the point towards the camera, as the
//! 3D cache caches it.

use super::jobs::{Job, Notify, Priority, Reporter};
use super::render3d_job::View3dParams;
use crate::core::color::Rgb;
use crate::core::metric::{CacheMethod, MetricParams};
use crate::core::space::D3;
use crate::pipeline::derivatives::{AwareSettings, Derivatives, Method, ReferenceSettings};
use crate::pipeline::medium::Region;
use crate::pipeline::path::Settings;
use crate::pipeline::probe::{LightField, Outgoing, ProbeSettings};
use crate::pipeline::record::CacheSettings;
use crate::pipeline::world::World;
use crate::study::light_field_derivs::{SharedLightField, aware_and_unaware, derivatives_at};
use crate::volume::cached::default_eps;
use crate::volume::scene::Scene;
use glam::{DVec2, DVec3};
use std::sync::Arc;

/// Where the probe is: a point of the view's image and a depth along its ray.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe3d {
    /// Image position as fractions of the width and height (x right, y down).
    pub pixel: DVec2,
    /// Distance from the camera along the pixel's ray.
    pub depth: f64,
    /// Also compute the finite-difference reference (expensive).
    pub reference: bool,
    /// Samples per stencil point of the reference.
    pub reference_spp: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Probe3dKey {
    revision: u64,
    probe: Probe3d,
    rays: usize,
    steps: usize,
    seed: u64,
}

impl Probe3d {
    /// A probe on the pixel at `pixel` (fractions): in the middle of the ray's
    /// piece inside the medium before what it hits, else halfway to the hit (or to
    /// the scene's size when it hits nothing).
    pub fn at_pixel(scene: &Scene, pixel: DVec2) -> Self {
        let far = ray_length(scene, pixel);
        let (o, d) = camera_ray(scene, pixel);
        let piece = scene.medium.as_ref().and_then(|m| m.region.pieces(o, d, far));
        let depth = piece.map_or(0.5 * far, |(t0, t1)| 0.5 * (t0 + t1));
        Probe3d {
            pixel,
            depth,
            reference: false,
            reference_spp: 4096,
        }
    }

    pub fn key(&self, revision: u64, p: &View3dParams) -> Probe3dKey {
        Probe3dKey {
            revision,
            probe: self.clone(),
            rays: p.rays,
            steps: p.steps,
            seed: p.seed,
        }
    }

    /// The probed point.
    pub fn point(&self, scene: &Scene) -> DVec3 {
        let (o, d) = camera_ray(scene, self.pixel);
        o + d * self.depth
    }
}

/// The camera ray through image point `pixel` (fractions).
pub fn camera_ray(scene: &Scene, pixel: DVec2) -> (DVec3, DVec3) {
    let c = &scene.camera;
    let p = pixel * DVec2::new(c.width as f64, c.height as f64);
    (c.position, c.direction(p))
}

/// How far the pixel's ray goes before it hits a surface (the scene's size if it
/// hits nothing): the probe's depth slider ends there.
pub fn ray_length(scene: &Scene, pixel: DVec2) -> f64 {
    let (o, d) = camera_ray(scene, pixel);
    scene
        .closest_hit(o, d, f64::INFINITY, None)
        .map_or(scene.scale, |h| h.t)
}

/// The settings `volcache probe SCENE --at X,Y,Z --rays R --steps S` uses.
pub fn probe_settings(scene: &Scene, rays: usize, steps: usize) -> ProbeSettings {
    ProbeSettings {
        rays,
        paths: 1,
        steps,
        settings: Settings {
            max_depth: scene.desc.render.max_depth,
            ..Settings::default()
        },
        ..ProbeSettings::default_for::<D3>()
    }
}

/// The metric parameters of the view's cache for `method` (its ε, the scene's scale).
pub fn metric(scene: &Scene, method: CacheMethod, p: &View3dParams) -> MetricParams {
    let eps = p.eps.unwrap_or_else(|| default_eps(method, scene));
    CacheSettings::new::<D3>(method, eps, Settings::default()).metric(scene.scale)
}

/// Radiance arriving at the probe along one of its rays (luminance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incoming3 {
    pub dir: DVec3,
    pub surface: f64,
    pub medium: f64,
}

#[derive(Clone)]
pub struct Probe3dResult {
    pub at: DVec3,
    /// The camera position (ω_o points there).
    pub eye: DVec3,
    pub inside_medium: bool,
    pub shared: SharedLightField<D3>,
    pub incoming: Vec<Incoming3>,
    pub reference: Option<Derivatives<D3>>,
    pub seed: u64,
    pub rays: u64,
    pub seconds: f64,
}

fn incoming(scene: &Scene, lf: &LightField<D3>) -> Vec<Incoming3> {
    let lum = crate::study::light_field_derivs::incoming_luminance(scene, lf);
    (lf.rays.iter().zip(lum))
        .map(|(r, (surface, medium))| Incoming3 {
            dir: r.dir,
            surface,
            medium,
        })
        .collect()
}

/// Light field, aware and unaware derivatives (then the reference, if asked) at
/// the probe, sent as each lands.
pub fn spawn_probe3d(
    scene: Arc<Scene>,
    probe: Probe3d,
    params: View3dParams,
    notify: Notify,
) -> Job<Arc<Probe3dResult>> {
    Job::spawn("3D probe", Priority::Interactive, notify, move |r: &Reporter<_>| {
        let x = probe.point(&scene);
        let eye = scene.camera.position;
        let out = Outgoing::TowardsPoint(eye);
        let ps = probe_settings(&scene, params.rays, params.steps);
        let aw = AwareSettings::default();
        r.stage("3D probe: light field");
        let shared = aware_and_unaware(&*scene, x, out, &ps, &aw, params.seed, r.progress())?;
        r.add_rays(shared.light_field.cost_rays);
        let mut result = Probe3dResult {
            at: x,
            eye,
            inside_medium: shared.light_field.sigma_t != Rgb::ZERO,
            incoming: incoming(&scene, &shared.light_field),
            rays: shared.light_field.cost_rays,
            seconds: shared.light_field.seconds + shared.aware_seconds + shared.unaware_seconds,
            shared,
            reference: None,
            seed: params.seed,
        };
        if !probe.reference {
            r.send(Arc::new(result));
            return Ok(());
        }
        let rs = ReferenceSettings {
            spp: probe.reference_spp,
            ..ReferenceSettings::default()
        };
        // The incomplete result first: the reference takes much longer.
        r.send(Arc::new(result.clone()));
        r.stage("3D probe: finite-difference reference");
        let d = derivatives_at(
            &*scene,
            x,
            out,
            Method::Reference,
            &ps,
            &rs,
            &aw,
            params.seed,
            r.progress(),
        )?;
        r.add_rays(d.rays);
        result.rays += d.rays;
        result.seconds += d.seconds;
        result.reference = Some(d);
        r.send(Arc::new(result));
        Ok(())
    })
}
