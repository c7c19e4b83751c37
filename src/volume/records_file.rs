//! A placed 3D radiance cache on disk, so that the tiles of a large render (jobs of
//! a scheduler, on other machines) reconstruct from the very records a full render
//! would use, and their merge is the full image bit for bit — as Radiance's
//! processes share an ambient file.
//!
//! JSON: a header naming what the records are valid for (a stable hash of the scene
//! description, the method, ε, the image's size, samples per pixel, seed and march
//! step: the query points placement covered) and the records (position, value,
//! gradient and Hessian per channel, extent axes and radii, rays); with a surface
//! cache (`--surface-cache ours`), its records too, each with its normal, placed at
//! the first surfaces of the same camera samples; with `--direct-samples`, that the
//! records leave the straight light out. Floats are written in their
//! shortest exact form and read back exactly. Loading checks the header against the
//! render that wants to use it and every record's validity, and names the file and
//! the JSON path of whatever is wrong.

use super::cached::{CachedRenderParams, Placement, RadianceCache};
use super::cached_params::SurfaceCache;
use super::scene::Scene;
use crate::core::cache::Record;
use crate::core::metric::{CacheMethod, Extent};
use crate::core::rng::fnv1a;
use crate::core::space::D3;
use crate::core::taylor::Taylor2;
use crate::core::taylor_rgb::TaylorRgb;
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};
use std::path::Path;

pub const FORMAT: &str = "volcache-records-3d/1";

/// What the records were placed for: a render may use them only if it asks for the
/// same query points (so that every one is covered).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ValidFor {
    /// FNV-1a of the scene description's JSON, hex.
    pub scene_hash: String,
    pub width: usize,
    pub height: usize,
    /// Window [x0, y0, x1, y1] whose query points placement walked.
    pub window: [usize; 4],
    pub spp: u32,
    pub seed: u64,
    pub march_step: f64,
}

impl ValidFor {
    pub fn of(scene: &Scene, params: &CachedRenderParams) -> Self {
        let ip = &params.image;
        ValidFor {
            scene_hash: scene_hash(scene),
            width: ip.width,
            height: ip.height,
            window: ip.window(),
            spp: params.placed_spp(),
            seed: ip.seed,
            march_step: params.march_step,
        }
    }

    /// Why records placed for `self` cannot serve a render of `want`, if they cannot.
    pub fn mismatch(&self, want: &ValidFor) -> Option<String> {
        if self.scene_hash != want.scene_hash {
            return Some("they were placed for another scene (or an edited one)".into());
        }
        let [x0, y0, x1, y1] = self.window;
        let [a0, b0, a1, b1] = want.window;
        let same_image = (self.width, self.height, self.spp, self.seed)
            == (want.width, want.height, want.spp, want.seed)
            && self.march_step == want.march_step;
        if !same_image {
            return Some(format!(
                "they cover {}x{} at {} spp, seed {}, march step {} but the render asks for {}x{} at {} spp, seed {}, march step {}",
                self.width,
                self.height,
                self.spp,
                self.seed,
                self.march_step,
                want.width,
                want.height,
                want.spp,
                want.seed,
                want.march_step
            ));
        }
        if !(x0 <= a0 && y0 <= b0 && a1 <= x1 && b1 <= y1) {
            return Some(format!(
                "they cover the window {:?}, which does not contain the render's {:?}",
                self.window, want.window
            ));
        }
        None
    }
}

/// One record as stored: per channel [value, ∇ (3), H (9, column-major)].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoredRecord {
    pub position: [f64; 3],
    pub value: [[f64; 13]; 3],
    /// Unit axes (columns of the extent's rotation) and their radii.
    pub axes: [[f64; 3]; 3],
    pub radii: [f64; 3],
    pub rays: u64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordsFile {
    pub format: String,
    pub valid_for: ValidFor,
    pub method: CacheMethod,
    pub eps: f64,
    pub query_points: u64,
    pub placement_rays: u64,
    pub placement_seconds: f64,
    pub records: Vec<StoredRecord>,
    /// The records leave out the light straight from the lights, sampled this many
    /// times per point instead (`CacheSettings::direct_samples`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direct_samples: Option<u32>,
    /// The surface cache placed beside the records, when the render had one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surfaces: Option<StoredSurfaces>,
    /// The records serve only the points the camera sees within this half-angle
    /// (degrees) of them (`CacheSettings::eye_cone_deg`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eye_cone_deg: Option<f64>,
}

/// A surface cache as stored: its placement's numbers and its records.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoredSurfaces {
    pub eps: f64,
    pub query_points: u64,
    pub rays: u64,
    pub seconds: f64,
    pub records: Vec<StoredSurfaceRecord>,
}

/// A surface record: its irradiance record and the unit normal of its side.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoredSurfaceRecord {
    pub record: StoredRecord,
    pub normal: [f64; 3],
}

/// A surface cache read from a file, before its records' occluders are listed
/// ([`Loaded::surface_cache`]).
pub struct LoadedSurfaces {
    pub cache: RadianceCache,
    pub normals: Vec<DVec3>,
}

/// A parsed and checked records file.
pub struct Loaded {
    pub file: RecordsFile,
    pub cache: RadianceCache,
    pub surfaces: Option<LoadedSurfaces>,
}

impl Loaded {
    /// The surface cache, ready to serve `scene` (the occluders near each record
    /// listed as placement lists them), when the file holds one.
    pub fn surface_cache(&self, scene: &Scene) -> Option<SurfaceCache> {
        let (stored, loaded) = (self.file.surfaces.as_ref()?, self.surfaces.as_ref()?);
        Some(SurfaceCache {
            near: crate::pipeline::sight::near_table(scene, &loaded.cache),
            cache: loaded.cache.clone(),
            normals: loaded.normals.clone(),
            eps: stored.eps,
            query_points: stored.query_points,
            rays: stored.rays,
            seconds: stored.seconds,
        })
    }
}

fn stored(r: &Record<D3, TaylorRgb<D3>>) -> StoredRecord {
    StoredRecord {
        position: r.position.to_array(),
        value: r.value.channels.map(|c| {
            let mut a = [0.0; 13];
            a[0] = c.value;
            a[1..4].copy_from_slice(&c.grad.to_array());
            a[4..].copy_from_slice(&c.hess.to_cols_array());
            a
        }),
        axes: r.extent.axes.to_cols_array_2d(),
        radii: r.extent.radii.to_array(),
        rays: r.cost_rays,
    }
}

fn record_of(r: &StoredRecord) -> Record<D3, TaylorRgb<D3>> {
    let channels = r
        .value
        .map(|a| Taylor2::<D3>::new(a[0], DVec3::from_slice(&a[1..4]), DMat3::from_cols_slice(&a[4..])));
    Record {
        position: DVec3::from_array(r.position),
        value: TaylorRgb { channels },
        extent: Extent::<D3> {
            axes: DMat3::from_cols_array_2d(&r.axes),
            radii: DVec3::from_array(r.radii),
        },
        cost_rays: r.rays,
    }
}

/// Stable hash of what a scene is (its parsed description, not the file's bytes).
pub fn scene_hash(scene: &Scene) -> String {
    let text = serde_json::to_string(&scene.desc).unwrap_or_default();
    format!("{:016x}", fnv1a(text.as_bytes()))
}

impl RecordsFile {
    /// The file of a placement and, when the render has one, its surface cache.
    pub fn from_placement(
        scene: &Scene,
        params: &CachedRenderParams,
        method: CacheMethod,
        p: &Placement,
        surfaces: Option<&SurfaceCache>,
    ) -> Self {
        let records = p.caches[0].records().iter().map(stored).collect();
        let surfaces = surfaces.map(|s| StoredSurfaces {
            eps: s.eps,
            query_points: s.query_points,
            rays: s.rays,
            seconds: s.seconds,
            records: s
                .cache
                .records()
                .iter()
                .zip(&s.normals)
                .map(|(r, n)| StoredSurfaceRecord {
                    record: stored(r),
                    normal: n.to_array(),
                })
                .collect(),
        });
        RecordsFile {
            format: FORMAT.into(),
            valid_for: ValidFor::of(scene, params),
            method,
            eps: p.eps,
            query_points: p.query_points,
            placement_rays: p.rays,
            placement_seconds: p.seconds,
            records,
            direct_samples: p.direct_samples,
            surfaces,
            eye_cone_deg: p.eye_cone.map(|c| c.half_angle_deg),
        }
    }

    /// Parse and check the records (not yet against a render: see [`ValidFor::mismatch`]).
    pub fn parse(text: &str, file: &str) -> Result<Loaded, String> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let f: RecordsFile =
            serde_path_to_error::deserialize(de).map_err(|e| format!("{file}: at `{}`: {}", e.path(), e.inner()))?;
        if f.format != FORMAT {
            return Err(format!(
                "{file}: at `format`: expected \"{FORMAT}\", found {:?}",
                f.format
            ));
        }
        check_header(&f).map_err(|(path, why)| format!("{file}: at `{path}`: {why}"))?;
        let cache = cache_of(f.records.iter(), |i| format!("records[{i}]"), file)?;
        let surfaces = match &f.surfaces {
            None => None,
            Some(s) => {
                check_surfaces(s).map_err(|(path, why)| format!("{file}: at `surfaces.{path}`: {why}"))?;
                Some(LoadedSurfaces {
                    cache: cache_of(
                        s.records.iter().map(|r| &r.record),
                        |i| format!("surfaces.records[{i}].record"),
                        file,
                    )?,
                    normals: s.records.iter().map(|r| DVec3::from_array(r.normal)).collect(),
                })
            }
        };
        Ok(Loaded {
            file: f,
            cache,
            surfaces,
        })
    }

    /// Read and check a records file; errors name the file and the JSON path.
    pub fn load(path: &Path) -> Result<Loaded, String> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| format!("{file}: {e}"))?;
        Self::parse(&text, &file)
    }
}

/// The cache of checked `records` (`at(i)`: record i's JSON path, for errors).
fn cache_of<'a>(
    records: impl Iterator<Item = &'a StoredRecord>,
    at: impl Fn(usize) -> String,
    file: &str,
) -> Result<RadianceCache, String> {
    let mut cache = RadianceCache::new();
    for (i, r) in records.enumerate() {
        check_record(r).map_err(|(path, why)| format!("{file}: at `{}.{path}`: {why}", at(i)))?;
        cache
            .insert(record_of(r))
            .map_err(|e| format!("{file}: at `{}`: {e}", at(i)))?;
    }
    Ok(cache)
}

/// The surface cache's numbers and normals are in range (a problem: JSON path
/// within `surfaces`, why); its records are checked as the medium's.
fn check_surfaces(s: &StoredSurfaces) -> Result<(), (String, String)> {
    let (lo, hi) = crate::limits::EPS;
    if !(s.eps.is_finite() && (lo..=hi).contains(&s.eps)) {
        return Err((
            "eps".into(),
            format!("must lie between {lo:e} and {hi:e}, got {}", s.eps),
        ));
    }
    if !(s.seconds.is_finite() && s.seconds >= 0.0) {
        return Err((
            "seconds".into(),
            format!("must be a finite duration, got {}", s.seconds),
        ));
    }
    for (i, r) in s.records.iter().enumerate() {
        let n = DVec3::from_array(r.normal);
        // Unit to well within what the serving test (cos ≥ 0.95) can tell apart.
        if !(n.is_finite() && (n.length() - 1.0).abs() <= 1e-9) {
            return Err((
                format!("records[{i}].normal"),
                format!("must be a unit vector, got {:?}", r.normal),
            ));
        }
    }
    Ok(())
}

/// Largest |value| a record may carry, and may reach when extrapolated across its
/// extent (|∇L|·r, |H|·r²): above any in-scattered radiance a valid scene gives
/// (σ_s × phase × radiance ≤ 1.6·10³⁴, `crate::limits`) and below f32::MAX, so a
/// reconstructed image fits its EXR.
pub const MAX_RECORD_VALUE: f64 = 1e35;

/// The header's numbers are in range (a problem: JSON path, why).
fn check_header(f: &RecordsFile) -> Result<(), (String, String)> {
    let v = &f.valid_for;
    let side = |n: usize| n.min(u32::MAX as usize) as u32;
    if let Some(why) = crate::limits::resolution_problem(side(v.width), side(v.height)) {
        return Err(("valid_for.width".into(), format!("the image {why}")));
    }
    if !(v.march_step.is_finite() && v.march_step > 0.0) {
        return Err((
            "valid_for.march_step".into(),
            format!("must be a positive distance, got {}", v.march_step),
        ));
    }
    let (lo, hi) = crate::limits::EPS;
    if !(f.eps.is_finite() && (lo..=hi).contains(&f.eps)) {
        return Err((
            "eps".into(),
            format!("must lie between {lo:e} and {hi:e}, got {}", f.eps),
        ));
    }
    let (lo, hi) = crate::limits::EYE_CONE_DEG;
    if let Some(a) = f.eye_cone_deg.filter(|a| !(a.is_finite() && (lo..=hi).contains(a))) {
        return Err((
            "eye_cone_deg".into(),
            format!("must lie between {lo} and {hi} degrees, got {a}"),
        ));
    }
    if let Some(n) = f.direct_samples.filter(|n| !(1..=4096).contains(n)) {
        return Err(("direct_samples".into(), format!("must be between 1 and 4096, got {n}")));
    }
    if !(f.placement_seconds.is_finite() && f.placement_seconds >= 0.0) {
        return Err((
            "placement_seconds".into(),
            format!("must be a finite duration, got {}", f.placement_seconds),
        ));
    }
    Ok(())
}

/// A record's numbers are in range (a problem: JSON path within the record, why).
fn check_record(r: &StoredRecord) -> Result<(), (String, String)> {
    for (k, &x) in r.position.iter().enumerate() {
        if !(x.is_finite() && x.abs() <= crate::limits::MAX_COORD) {
            return Err((
                format!("position[{k}]"),
                format!("must lie within ±{:e}, got {x:e}", crate::limits::MAX_COORD),
            ));
        }
    }
    for (k, &x) in r.radii.iter().enumerate() {
        if !(x.is_finite() && x > 0.0 && x <= 2.0 * crate::limits::MAX_COORD) {
            return Err((
                format!("radii[{k}]"),
                format!("must be a positive finite length, got {x:e}"),
            ));
        }
    }
    let r_max = r.radii.iter().cloned().fold(0.0, f64::max);
    for (c, channel) in r.value.iter().enumerate() {
        for (k, &x) in channel.iter().enumerate() {
            // [value, ∇ (3), H (9)]: each term's reach over the extent.
            let reach = match k {
                0 => x.abs(),
                1..=3 => x.abs() * r_max,
                _ => x.abs() * r_max * r_max,
            };
            if !(x.is_finite() && reach <= MAX_RECORD_VALUE) {
                let what = match k {
                    0 => "the value",
                    1..=3 => "the gradient times the extent",
                    _ => "the Hessian times the extent squared",
                };
                return Err((
                    format!("value[{c}][{k}]"),
                    format!("{what} must be finite and at most {MAX_RECORD_VALUE:e} in size, got {x:e}"),
                ));
            }
        }
    }
    Ok(())
}
