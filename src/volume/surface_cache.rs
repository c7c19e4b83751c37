//! The surface cache of a 3D render (issue 16 item 3): indirect-irradiance records
//! placed at the first surfaces the window's camera samples hit
//! (`pipeline::surface_cache`), and the radiance a camera sample gets there:
//! emission, plus direct lighting sampled per camera sample, plus ρ/π times the
//! interpolated indirect irradiance — in place of path tracing the reflected light.

use super::cached_params::{CachedRenderParams, SurfaceCache, SurfaceMemo};
use super::camera::Camera;
use super::camera_march::{CameraRay, window_order};
use super::mesh::Hit;
use super::render::camera;
use super::scene::Scene;
use crate::core::color::Rgb;
use crate::core::rng::{Sampler, mix64};
use crate::core::space::D3;
use crate::pipeline::lobe::Lobe;
use crate::pipeline::path::direct_at;
use crate::pipeline::record::CacheSettings;
use crate::pipeline::surface_cache::{SurfaceQuery, SurfaceSource, interpolate_surface, place_surfaces};
use crate::pipeline::world::World;
use crate::progress::{Cancelled, Progress};
use glam::DVec3;
use std::f64::consts::FRAC_1_PI;

/// The first surface of every camera sample of the window's pixels that reflects
/// (active side, reflectance above zero), pixel by pixel in the coarse-to-fine
/// order of the medium's query points.
struct CameraSurfaces<'a> {
    scene: &'a Scene,
    cam: Camera,
    params: &'a CachedRenderParams,
    order: Vec<usize>,
    size_key: u128,
}

impl<'a> CameraSurfaces<'a> {
    fn new(scene: &'a Scene, params: &'a CachedRenderParams) -> Self {
        let (order, size_key) = window_order(&params.image);
        CameraSurfaces {
            scene,
            cam: camera(scene, params.image.width, params.image.height),
            params,
            order,
            size_key,
        }
    }
}

impl SurfaceSource<D3> for CameraSurfaces<'_> {
    fn units(&self) -> usize {
        self.order.len()
    }

    fn points(&self, k: usize, out: &mut Vec<SurfaceQuery<D3>>) {
        let pixel = self.order[k];
        let ip = &self.params.image;
        for sample in 0..self.params.placed_spp() {
            let (ray, _) = CameraRay::trace(self.scene, &self.cam, pixel, sample, (ip.seed, ip.settings.sampling));
            let Some(hit) = ray.hit else { continue };
            let sp = self.scene.surface(&hit, ray.dir);
            if !sp.active || sp.reflectance == Rgb::ZERO {
                continue;
            }
            let (p, k) = (pixel as u64, sample as u64);
            out.push(SurfaceQuery {
                key: (self.size_key << 96) | ((p as u128) << 64) | ((k as u128) << 32),
                id: mix64((p << 32) | k),
                y: sp.point,
                normal: sp.normal,
                prim: hit.prim,
            });
        }
    }
}

/// The settings of surface records: the medium cache's (`cs`) with ours' method,
/// ε = `eps` and half the directions (a hemisphere at the sphere's density).
pub fn surface_settings(cs: &CacheSettings, eps: f64) -> CacheSettings {
    let mut s = CacheSettings {
        method: crate::core::metric::CacheMethod::Ours,
        eps,
        moment_bands: None,
        // Surface records say for themselves what they leave out (their receiver).
        direct_samples: None,
        ..cs.clone()
    };
    s.probe.rays = (cs.probe.rays / 2).max(16);
    s
}

/// Place surface records over the first surfaces of the window's camera samples.
pub fn place(
    scene: &Scene,
    params: &CachedRenderParams,
    cs: &CacheSettings,
    memo: &mut SurfaceMemo,
    progress: &Progress,
) -> Result<SurfaceCache, Cancelled> {
    place_surfaces(scene, &CameraSurfaces::new(scene, params), cs, memo, progress)
}

/// A starting ε for a scene's surface cache (ours' metric: a volume, scaled with
/// the scene).
pub fn default_surface_eps(scene: &Scene) -> f64 {
    1e-3 * scene.scale.powi(3)
}

/// The radiance leaving a camera sample's first surface (`hit`, seen along `dir`)
/// from the surface cache: emission, `paths` samples of the direct light, and ρ/π
/// times the records' indirect irradiance. None where the surface reflects and no
/// record serves it (the caller path traces it).
#[allow(clippy::too_many_arguments)] // the sample's state is spelled out
pub fn surface_radiance(
    scene: &Scene,
    sc: &SurfaceCache,
    hit: &Hit,
    dir: DVec3,
    (paths, second_order): (u32, bool),
    scratch: &mut Vec<(usize, f64)>,
    s: &mut Sampler,
    rays: &mut u64,
) -> Option<Rgb> {
    let sp = scene.surface(hit, dir);
    if !sp.active {
        return Some(Rgb::ZERO);
    }
    if sp.reflectance == Rgb::ZERO {
        return Some(sp.emission);
    }
    let indirect = interpolate_surface(scene, sc, (sp.point, sp.normal), second_order, scratch, rays)?;
    let lobe = Lobe::Lambert {
        normal: sp.normal,
        reflectance: sp.reflectance,
    };
    let paths = paths.max(1);
    let mut direct = Rgb::ZERO;
    for _ in 0..paths {
        direct += direct_at(scene, sp.point, &lobe, Some(hit.prim), s, rays);
    }
    Some(sp.emission + direct / paths as f64 + sp.reflectance * indirect * FRAC_1_PI)
}
