//! What a cached 3D render covers ([`CachedRenderParams`]) and the 3D names of the
//! pipeline's cache types: the vocabulary that placement ([`super::cached`]),
//! reconstruction ([`super::reconstruct`]) and the records file share, apart from
//! all three so that none imports another for it.

use super::render::RenderParams;
use super::scene::Scene;
use crate::core::space::D3;
use crate::pipeline::eye_cone::EyeCone;
use crate::pipeline::moments::RecordMoments;
use serde::Serialize;

pub type RecordMemo = crate::pipeline::placement::RecordMemo<D3>;
pub type RadianceCache = crate::pipeline::placement::RadianceCache<D3>;
pub type Placement = crate::pipeline::placement::Placement<D3>;
pub type RecordInfo = crate::pipeline::record::RecordInfo<D3>;
pub type SurfaceCache = crate::pipeline::surface_cache::SurfaceCache<D3>;
pub type SurfaceMemo = crate::pipeline::surface_cache::SurfaceMemo<D3>;

/// The image a cached render covers and how camera rays are marched.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CachedRenderParams {
    /// Size, window, camera samples per pixel, seed, path settings; a time budget
    /// bounds the whole cached render (records and image).
    pub image: RenderParams,
    /// Distance Δ between march points along camera rays (scene units).
    pub march_step: f64,
    /// Reflected-light samples (NEE + a path each) per camera sample at the first
    /// surface: surfaces are path traced as in the reference, at a cost far below
    /// a record's, so they need not be the noise floor of a cached image.
    pub surface_paths: u32,
    /// ε of a surface cache (`super::surface_cache`: indirect irradiance cached,
    /// direct light sampled with `surface_paths` samples), or None: the reflected
    /// light is path traced. (Left out of JSON when None.)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_eps: Option<f64>,
    /// Camera samples per pixel whose query points placement visits (None: all of
    /// `image.spp`). With `image.time_budget` the reconstruction renders these,
    /// then more while the budget lasts; points no record covers are path traced.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub place_spp: Option<u32>,
    /// March step of the camera samples beyond the placed ones (None: `march_step`).
    /// Their march is as unbiased at any step (stratified, jittered), and a coarser
    /// one makes a sample cheaper: the time budget's samples are then spent across
    /// the pixel rather than along its rays.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image_march_step: Option<f64>,
    /// One camera sample in this many beyond the placed ones marches (None: all);
    /// the others see the first surface only, the medium part being averaged over
    /// the marched ones: the surface's light is then sampled more often than the
    /// medium's, for a fraction of a march's cost (`super::image_split`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image_march_every: Option<u32>,
    /// The camera samples beyond the placed ones take the march step and
    /// straight-light samples of least variance × cost, measured on the placed
    /// ones (`super::image_split`); without a time budget, as many as cost what
    /// the remaining `image.spp` would have at `march_step`. (Left out of JSON
    /// when false.)
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub adapt_image: bool,
    /// With `adapt_image`: the march share too is chosen from the placed samples'
    /// statistics (`super::image_split::share_cost`), in place of
    /// `image_march_every`. (Left out of JSON when false.)
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub adapt_march_share: bool,
}

/// The march step of camera rays unless given: the scene's size / 128.
pub fn default_march_step(scene: &Scene) -> f64 {
    scene.scale / 128.0
}

impl CachedRenderParams {
    pub fn from_scene(scene: &Scene) -> Self {
        CachedRenderParams {
            image: RenderParams::from_scene(scene),
            march_step: default_march_step(scene),
            surface_paths: 4,
            surface_eps: None,
            place_spp: None,
            image_march_step: None,
            image_march_every: None,
            adapt_image: false,
            adapt_march_share: false,
        }
    }

    /// Camera samples per pixel placement visits (at least 1, at most `image.spp`).
    pub fn placed_spp(&self) -> u32 {
        let spp = self.image.spp.max(1);
        self.place_spp.map_or(spp, |p| p.clamp(1, spp))
    }

    /// The march step of camera sample `k` of a pixel.
    pub fn march_step_of(&self, k: u32) -> f64 {
        match self.image_march_step {
            Some(step) if k >= self.placed_spp() => step,
            _ => self.march_step,
        }
    }
}

/// What a reconstruction reads: the records, and their moments over ω_o when they
/// carry them (`pipeline::moments`; then L_s is combined for each camera ray's ω_o
/// rather than read as stored for the camera that placed them).
#[derive(Clone, Copy, Debug)]
pub struct CacheView<'a> {
    pub cache: &'a RadianceCache,
    /// Per record, its moments (all of bands 0..=L), if every record has them.
    pub moments: Option<&'a [RecordMoments<D3>]>,
    /// A surface cache, if surfaces are read from one.
    pub surfaces: Option<&'a SurfaceCache>,
    /// The records leave out the light arriving straight from the lights: sample it
    /// this many times at every march point ([`Placement::direct_samples`]).
    pub direct_samples: Option<u32>,
    /// The records serve only the points their eye sees near them
    /// ([`Placement::eye_cone`]).
    pub eye_cone: Option<EyeCone<D3>>,
}

impl<'a> CacheView<'a> {
    /// The records alone, as stored.
    pub fn records(cache: &'a RadianceCache) -> Self {
        CacheView {
            cache,
            moments: None,
            surfaces: None,
            direct_samples: None,
            eye_cone: None,
        }
    }

    /// A placement's first cache, with its moments when it has them.
    pub fn of(placement: &'a Placement) -> Self {
        let table = &placement.moments[0];
        let complete = table.len() == placement.caches[0].len() && table.iter().all(|m| !m.is_empty());
        CacheView {
            cache: &placement.caches[0],
            moments: (complete && !table.is_empty()).then_some(table.as_slice()),
            surfaces: None,
            direct_samples: placement.direct_samples,
            eye_cone: placement.eye_cone,
        }
    }

    /// The same with the surfaces read from `surfaces`.
    pub fn with_surfaces(self, surfaces: Option<&'a SurfaceCache>) -> Self {
        CacheView { surfaces, ..self }
    }
}
