//! The 3D scene file format (JSON, serde, unknown fields rejected).
//!
//! Units: lengths in scene units (metres); radiance in W m⁻² sr⁻¹; point-light
//! intensity in W sr⁻¹; sun irradiance in W m⁻² on a plane facing the sun; σ_a, σ_s
//! in m⁻¹; angles in degrees. Colours are RGB triples or a scalar (grey). These
//! structs serialise back exactly what was loaded.
//!
//! ```jsonc
//! {
//!   "description": "one line",
//!   "camera": { "position": [0, 1, 4], "look_at": [0, 1, 0], "up": [0, 1, 0], "fov_deg": 40 },
//!   "shapes": [   // each has exactly one of "quad", "box", "mesh"
//!     { "name": "floor", "quad": { "origin": [-1, 0, -1], "u": [2, 0, 0], "v": [0, 0, 2] },
//!       "reflectance": 0.7,          // ρ in [0, 1], BRDF ρ/π
//!       "emission": 0,               // radiance, W m⁻² sr⁻¹
//!       "two_sided": true },         // false: only the side of u × v (box/mesh: outside) is active
//!     { "box": { "min": [..], "max": [..], "rotate_y_deg": 15 } },
//!     { "mesh": { "path": "ico.obj", "translate": [0, 0.5, 0], "scale": 0.3 } }  // path relative to the scene file
//!   ],
//!   "lights": [
//!     { "point": { "position": [0, 1.8, 0], "intensity": 2.0 } },
//!     { "sun": { "direction": [0.3, -1, 0.2], "irradiance": 8, "angular_radius_deg": 0.27 } },  // direction of travel
//!     { "sky": { "radiance": [0.3, 0.4, 0.6] } }
//!   ],
//!   "medium": { "sigma_a": 0.01, "sigma_s": 0.2, "g": 0.3,
//!               "region": "everywhere" },   // or { "box": { "min": [..], "max": [..] } }
//!   "render": { "resolution": [320, 240], "spp": 64, "seed": 0, "max_depth": 64, "exposure": 0 }
//! }
//! ```

pub use crate::core::color::Color;
use serde::{Deserialize, Serialize};

/// A whole 3D scene file.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    #[serde(default)]
    pub description: String,
    pub camera: CameraDesc,
    #[serde(default)]
    pub shapes: Vec<ShapeDesc>,
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// Vacuum when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub medium: Option<MediumDesc>,
    #[serde(default)]
    pub render: RenderDesc,
}

/// A pinhole camera; the aspect ratio comes from `render.resolution`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    #[serde(default = "y_up")]
    pub up: [f64; 3],
    /// Vertical field of view, degrees, in (0, 180).
    pub fov_deg: f64,
}

fn y_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

/// A shape with a diffuse material: exactly one of `quad`, `box`, `mesh`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ShapeDesc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quad: Option<QuadDesc>,
    #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
    pub cuboid: Option<BoxDesc>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<MeshDesc>,
    /// Diffuse reflectance ρ in [0, 1].
    #[serde(default)]
    pub reflectance: Color,
    /// Emitted radiance, W m⁻² sr⁻¹.
    #[serde(default, skip_serializing_if = "Color::is_zero")]
    pub emission: Color,
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub two_sided: bool,
}

fn yes() -> bool {
    true
}
fn is_true(b: &bool) -> bool {
    *b
}

/// The parallelogram origin + s·u + t·v, s, t ∈ [0, 1]; front side along u × v.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct QuadDesc {
    pub origin: [f64; 3],
    pub u: [f64; 3],
    pub v: [f64; 3],
}

/// An axis-aligned box, optionally rotated about the vertical (y) axis through its
/// centre; front sides face outwards.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoxDesc {
    pub min: [f64; 3],
    pub max: [f64; 3],
    #[serde(default, skip_serializing_if = "is_zero")]
    pub rotate_y_deg: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// A triangle mesh from a Wavefront OBJ file (counter-clockwise faces are front),
/// scaled then translated.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    /// Relative to the scene file's folder.
    pub path: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
    /// Uniform (a number) or per axis ([sx, sy, sz]); each > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<Color>,
}

/// A light (externally tagged: `{"point": {...}}`, `{"sun": {...}}`, `{"sky": {...}}`).
/// Area lights are emissive shapes.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum LightDesc {
    Point(PointDesc),
    Sun(SunDesc),
    Sky(SkyDesc),
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PointDesc {
    pub position: [f64; 3],
    /// W sr⁻¹ (power 4π·I).
    pub intensity: Color,
}

/// A distant disc light: parallel light (a collimated beam filling space) when
/// `angular_radius_deg` is 0, else uniform radiance over a cone of that half-angle.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SunDesc {
    /// Direction of travel of the light.
    pub direction: [f64; 3],
    /// W m⁻² on a plane facing the sun.
    pub irradiance: Color,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub angular_radius_deg: f64,
}

/// Constant radiance arriving from every direction where rays leave the scene.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SkyDesc {
    pub radiance: Color,
}

/// A homogeneous medium with a Henyey–Greenstein phase function.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MediumDesc {
    pub sigma_a: Color,
    pub sigma_s: Color,
    #[serde(default)]
    pub g: f64,
    #[serde(default)]
    pub region: RegionDesc,
}

/// Where the medium is; its boundary is index-matched.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum RegionDesc {
    #[default]
    Everywhere,
    Box(AabbDesc),
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AabbDesc {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

/// Defaults for `render3d`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderDesc {
    pub resolution: [u32; 2],
    pub spp: u32,
    pub seed: u64,
    /// Maximum number of scattering/reflection vertices per path.
    pub max_depth: u32,
    /// Exposure in stops for the tone-mapped PNG.
    pub exposure: f64,
}

impl Default for RenderDesc {
    fn default() -> Self {
        RenderDesc {
            resolution: [320, 240],
            spp: 16,
            seed: 0,
            max_depth: 64,
            exposure: 0.0,
        }
    }
}
