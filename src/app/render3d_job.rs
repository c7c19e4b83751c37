//! What the 3D view computes, on a background job: the image by one of the
//! methods `render3d` offers, coarse to fine, each level exactly what
//! `volcache render3d` writes for the same resolution, samples and seed (the
//! view's "copy as command" reproduces the latest level).
//!
//! Path tracing goes through levels of growing resolution and then of growing
//! samples per pixel at the view's resolution (each level a fresh render: a
//! level's image is then the CLI's image, at the price of redoing the previous
//! level's samples, at most doubling the total). The caches place their records
//! for a half-resolution preview, then for the view's resolution, reusing light
//! fields already captured (the placement's memo).

use super::jobs::{Job, Notify, Priority, Reporter};
use crate::core::metric::CacheMethod;
use crate::core::space::D3;
use crate::pipeline::record::CacheSettings;
use crate::volume::cached::{
    CachedRenderParams, Placement, RecordInfo, RecordMemo, default_eps, render_cached, render_cached_onto,
};
use crate::volume::render::{RenderParams, Rendered, render};
use crate::volume::scene::Scene;
use crate::volume::surface_cache::default_surface_eps;
use std::sync::Arc;

/// The band the view's "keep records when the camera moves" starts at: on
/// scenes3d/lamp_fog.json (g = 0.8, `bench moments3d`), L = 4 kept a moved camera's
/// medium RMSE within 1.2–2.1× of a fresh cache's in 21–36% of its time
/// (stale records 1.5–5×); L = 2 was 1.4–2× worse than L = 4 at 15° and 60°, and
/// more bands cost every record placed with them more (3.2–4.2× at L = 4).
pub const DEFAULT_MOMENT_BANDS: usize = 4;

/// How the 3D view's image is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Method3d {
    #[value(name = "pt")]
    PathTracing,
    /// Second-order occlusion-aware radiance caching.
    Ours,
    /// Jarosz et al. 2008 radiance caching.
    Jarosz08,
}

impl Method3d {
    pub const ALL: [Method3d; 3] = [Method3d::PathTracing, Method3d::Ours, Method3d::Jarosz08];

    pub fn label(self) -> &'static str {
        match self {
            Method3d::PathTracing => "path tracing",
            Method3d::Ours => "ours",
            Method3d::Jarosz08 => "Jarosz 2008",
        }
    }

    /// The `render3d --method` value.
    pub fn cli_name(self) -> &'static str {
        match self {
            Method3d::PathTracing => "pt",
            Method3d::Ours => "ours",
            Method3d::Jarosz08 => "jarosz08",
        }
    }

    pub fn cache_method(self) -> Option<CacheMethod> {
        match self {
            Method3d::PathTracing => None,
            Method3d::Ours => Some(CacheMethod::Ours),
            Method3d::Jarosz08 => Some(CacheMethod::Jarosz08),
        }
    }
}

/// Everything the view's image depends on besides the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct View3dParams {
    pub method: Method3d,
    /// The view's image size (the last level's).
    pub width: usize,
    pub height: usize,
    /// Path tracing: the samples per pixel the refinement ends at.
    pub spp: u32,
    /// Caches: camera samples per pixel (placement and reconstruction).
    pub cache_spp: u32,
    /// Caches: directions per record.
    pub rays: usize,
    /// Caches: ray-marched medium samples per direction.
    pub steps: usize,
    /// Caches: ε (None: the scene-relative default of `render3d`).
    pub eps: Option<f64>,
    pub seed: u64,
    /// Caches: records also store their moments over ω_o to this band, and a
    /// camera move starts from the previous camera's records (`pipeline::moments`).
    pub moment_bands: Option<usize>,
    /// Caches: the first surfaces' reflected light from a surface cache at the
    /// scene-relative ε (`render3d --surface-cache ours`), not path traced.
    pub surface_cache: bool,
    /// Caches: records reach no farther than this multiple of their distance to
    /// the nearest silhouette edge they see (`render3d --edge-reach`).
    pub edge_reach: Option<f64>,
    /// Caches: records reach no farther than this multiple of their distance to
    /// the nearest point light (`render3d --lamp-reach`; None: `--no-lamp-reach`).
    pub lamp_reach: Option<f64>,
    /// Caches: a record serves only the points the camera sees within this
    /// half-angle (degrees) of it (`render3d --eye-cone`; None: off).
    pub eye_cone_deg: Option<f64>,
    /// Ours: records reach no farther than their multiple-scattering gradient's
    /// noise allows at ε (`render3d --gradient-noise-reach`).
    pub gradient_noise_reach: bool,
}

impl View3dParams {
    /// A view `width` pixels wide with the scene's aspect ratio and seed.
    pub fn for_scene(scene: &Scene, width: usize) -> Self {
        let [w, h] = scene.desc.render.resolution;
        let width = width.max(8);
        View3dParams {
            method: Method3d::PathTracing,
            width,
            height: ((width as f64 * h as f64 / w as f64).round() as usize).max(4),
            spp: 256,
            cache_spp: 1,
            rays: 1024,
            steps: 24,
            eps: None,
            seed: scene.desc.render.seed,
            moment_bands: None,
            surface_cache: false,
            edge_reach: None,
            lamp_reach: Some(crate::pipeline::budget::VOLUME_LAMP_REACH),
            eye_cone_deg: None,
            gradient_noise_reach: false,
        }
    }

    /// The image of one level: `scale` of the view's size, `spp` samples.
    pub fn image(&self, scene: &Scene, scale: f64, spp: u32) -> RenderParams {
        RenderParams {
            width: ((self.width as f64 * scale).round() as usize).max(1),
            height: ((self.height as f64 * scale).round() as usize).max(1),
            spp,
            seed: self.seed,
            ..RenderParams::from_scene(scene)
        }
    }

    /// The path tracer's levels: (fraction of the size, samples per pixel).
    pub fn pt_levels(&self) -> Vec<(f64, u32)> {
        let mut v = vec![(0.25, 1), (0.5, 1)];
        let mut spp = 1;
        while spp < self.spp {
            v.push((1.0, spp));
            spp *= 4;
        }
        v.push((1.0, self.spp.max(1)));
        v
    }

    /// The cache settings and image of a cached level.
    pub fn cached(&self, scene: &Scene, method: CacheMethod, scale: f64) -> (CacheSettings, CachedRenderParams) {
        let image = self.image(scene, scale, self.cache_spp.max(1));
        let (mut cs, mut cp) = cache_settings(scene, image, method, self.eps, self.rays, self.steps);
        cs.moment_bands = self.moment_bands;
        cp.surface_eps = self.surface_cache.then(|| default_surface_eps(scene));
        cs.edge_reach = self.edge_reach.map(crate::limits::clamp_edge_reach);
        cs.lamp_reach = self.lamp_reach.map(crate::limits::clamp_edge_reach);
        let (lo, hi) = crate::limits::EYE_CONE_DEG;
        cs.eye_cone_deg = self.eye_cone_deg.map(|a| a.clamp(lo, hi));
        // Jarosz 2008 measures no gradient noise: the reach would be infinite.
        cs.gradient_noise_reach = self.gradient_noise_reach && method == CacheMethod::Ours;
        (cs, cp)
    }
}

/// Cache settings and image as `render3d` and `figure compare3d` build them from
/// `--eps --rays --steps` with their other options at their defaults (the copied
/// commands name these three, so they reproduce the app's numbers).
pub fn cache_settings(
    scene: &Scene,
    image: RenderParams,
    method: CacheMethod,
    eps: Option<f64>,
    rays: usize,
    steps: usize,
) -> (CacheSettings, CachedRenderParams) {
    let eps = eps.unwrap_or_else(|| default_eps(method, scene));
    let mut cs = CacheSettings::new::<D3>(method, eps, image.first_vertex_settings());
    cs.probe.rays = rays;
    cs.probe.steps = steps;
    let mut cp = CachedRenderParams::from_scene(scene);
    cp.image = image;
    (cs, cp)
}

/// One level of the view's image.
pub struct Frame3d {
    pub level: usize,
    pub levels: usize,
    pub method: Method3d,
    /// The level's image parameters (size, samples, seed).
    pub image_params: RenderParams,
    pub image: Rendered,
    /// The cache's records (empty for path tracing).
    pub records: Vec<RecordInfo>,
    /// ε of the cache (0 for path tracing).
    pub eps: f64,
    /// The cache's placement (for the next camera to start from, with moments).
    pub placement: Option<Arc<Placement>>,
    /// Records carried over from an earlier camera (0: a fresh cache, which
    /// `volcache render3d` reproduces).
    pub carried: usize,
}

/// Compute the view's levels one after the other, sending each as it lands. A
/// cache starts each level from `earlier` (another camera's records with their
/// moments over ω_o) when given.
pub fn spawn_render3d(
    scene: Arc<Scene>,
    params: View3dParams,
    earlier: Option<Arc<Placement>>,
    notify: Notify,
) -> Job<Arc<Frame3d>> {
    Job::spawn(
        "3D view",
        Priority::Background,
        notify,
        move |r: &Reporter<Arc<Frame3d>>| match params.method.cache_method() {
            None => {
                let levels = params.pt_levels();
                let n = levels.len();
                for (i, (scale, spp)) in levels.into_iter().enumerate() {
                    let ip = params.image(&scene, scale, spp);
                    r.stage(format!(
                        "path tracing {}/{n}: {}×{} @ {spp} spp",
                        i + 1,
                        ip.width,
                        ip.height
                    ));
                    let image = render(&scene, &ip, r.progress())?;
                    r.add_rays(image.rays);
                    r.send(Arc::new(Frame3d {
                        level: i + 1,
                        levels: n,
                        method: params.method,
                        image_params: ip,
                        image,
                        records: Vec::new(),
                        eps: 0.0,
                        placement: None,
                        carried: 0,
                    }));
                }
                Ok(())
            }
            Some(cm) => {
                let mut memo = RecordMemo::default();
                let levels = [0.5, 1.0];
                for (i, scale) in levels.into_iter().enumerate() {
                    let (cs, cp) = params.cached(&scene, cm, scale);
                    r.stage(format!(
                        "{} {}/2: records for {}×{}",
                        params.method.label(),
                        i + 1,
                        cp.image.width,
                        cp.image.height
                    ));
                    let out = match &earlier {
                        Some(e) => render_cached_onto(&scene, &cp, &cs, (**e).clone(), &mut memo, r.progress())?,
                        None => {
                            render_cached(&scene, &cp, &cs, None, &mut memo, r.progress()).map_err(|e| match e {
                                crate::volume::cached::CountError::Cancelled(c) => c,
                                // Without a record-count target the search cannot fail.
                                other => panic!("cached render: {other}"),
                            })?
                        }
                    };
                    r.add_rays(out.rays());
                    r.send(Arc::new(Frame3d {
                        level: i + 1,
                        levels: levels.len(),
                        method: params.method,
                        image_params: cp.image.clone(),
                        records: out.placement.records().into_iter().next().unwrap_or_default(),
                        image: out.reconstruction.image,
                        eps: cs.eps,
                        placement: Some(Arc::new(out.placement)),
                        carried: earlier.as_ref().map_or(0, |e| e.record_count()),
                    }));
                }
                Ok(())
            }
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_tracing_levels_refine_size_then_samples() {
        let scene = Scene::from_json(
            super::super::document3d::SHIPPED_SCENES_3D[0].1,
            "fog_box",
            std::path::Path::new("."),
        )
        .unwrap();
        let p = View3dParams {
            spp: 64,
            ..View3dParams::for_scene(&scene, 160)
        };
        assert_eq!(
            p.pt_levels(),
            vec![(0.25, 1), (0.5, 1), (1.0, 1), (1.0, 4), (1.0, 16), (1.0, 64)]
        );
        assert_eq!(p.image(&scene, 0.5, 2).width, 80);
    }
}
