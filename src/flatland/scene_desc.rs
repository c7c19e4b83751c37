//! The flatland scene file format (JSON, serde, unknown fields rejected).
//!
//! Units: lengths in scene units (metres); radiance in W m⁻¹ rad⁻¹ (2D);
//! point-light intensity in W rad⁻¹; collimated irradiance in W m⁻¹ measured
//! across the beam; σ_a, σ_s in m⁻¹. Colours are RGB triples or a scalar (grey).
//! The README documents the format with an annotated example. These structs
//! serialise back exactly what was loaded, so the app can save scenes.

use serde::{Deserialize, Serialize};

pub use crate::core::color::Color;
pub use crate::pipeline::path::{Part, Quantity};

/// A whole flatland scene file.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// One line saying what the scene is for.
    #[serde(default)]
    pub description: String,
    /// The rectangle shown and rendered.
    pub domain: RectDesc,
    #[serde(default)]
    pub segments: Vec<SegmentDesc>,
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// No medium at all (vacuum) when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub medium: Option<MediumDesc>,
    #[serde(default)]
    pub render: RenderDesc,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RectDesc {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

/// A straight segment `a`–`b`, or a polyline through `points` (closed if `closed`),
/// with a diffuse material. The front side is to the left of a→b.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SegmentDesc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "is_false")]
    pub closed: bool,
    /// Diffuse reflectance ρ in [0, 1] (BRDF ρ/2 in flatland).
    #[serde(default)]
    pub reflectance: Color,
    /// Emitted radiance (W m⁻¹ rad⁻¹), ≥ 0.
    #[serde(default, skip_serializing_if = "Color::is_zero")]
    pub emission: Color,
    /// Reflect and emit on both sides (default), or only on the front (left) side.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub two_sided: bool,
}

fn yes() -> bool {
    true
}
fn is_true(b: &bool) -> bool {
    *b
}
fn is_false(b: &bool) -> bool {
    !*b
}

/// A light. In JSON: an object with `"type": "point"` or `"type": "collimated"`
/// and that type's fields (parsed through [`RawLight`] so that errors keep the
/// JSON path of the offending field).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(try_from = "RawLight", into = "RawLight")]
pub enum LightDesc {
    /// Isotropic point light; `intensity` in W rad⁻¹ (power = 2π · intensity).
    Point { position: [f64; 2], intensity: Color },
    /// A collimated beam travelling along `direction`, entering the scene through
    /// the `aperture` segment (a window); `irradiance` in W m⁻¹ across the beam.
    Collimated {
        direction: [f64; 2],
        aperture: [[f64; 2]; 2],
        irradiance: Color,
    },
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LightKind {
    Point,
    Collimated,
}

/// The JSON shape of a light: every field optional, checked per type.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawLight {
    #[serde(rename = "type")]
    pub kind: Option<LightKind>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intensity: Option<Color>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aperture: Option<[[f64; 2]; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub irradiance: Option<Color>,
}

impl TryFrom<RawLight> for LightDesc {
    type Error = String;
    fn try_from(r: RawLight) -> Result<Self, String> {
        let need = |name: &str, present: bool, kind: &str| {
            if present {
                Ok(())
            } else {
                Err(format!("missing field `{name}` (required for a {kind} light)"))
            }
        };
        let forbid = |name: &str, present: bool, kind: &str| {
            if present {
                Err(format!("field `{name}` does not apply to a {kind} light"))
            } else {
                Ok(())
            }
        };
        match r.kind {
            None => Err("missing field `type` (\"point\" or \"collimated\")".into()),
            Some(LightKind::Point) => {
                need("position", r.position.is_some(), "point")?;
                need("intensity", r.intensity.is_some(), "point")?;
                forbid("direction", r.direction.is_some(), "point")?;
                forbid("aperture", r.aperture.is_some(), "point")?;
                forbid("irradiance", r.irradiance.is_some(), "point")?;
                Ok(LightDesc::Point {
                    position: r.position.unwrap(),
                    intensity: r.intensity.unwrap(),
                })
            }
            Some(LightKind::Collimated) => {
                need("direction", r.direction.is_some(), "collimated")?;
                need("aperture", r.aperture.is_some(), "collimated")?;
                need("irradiance", r.irradiance.is_some(), "collimated")?;
                forbid("position", r.position.is_some(), "collimated")?;
                forbid("intensity", r.intensity.is_some(), "collimated")?;
                Ok(LightDesc::Collimated {
                    direction: r.direction.unwrap(),
                    aperture: r.aperture.unwrap(),
                    irradiance: r.irradiance.unwrap(),
                })
            }
        }
    }
}

impl From<LightDesc> for RawLight {
    fn from(l: LightDesc) -> Self {
        match l {
            LightDesc::Point { position, intensity } => RawLight {
                kind: Some(LightKind::Point),
                position: Some(position),
                intensity: Some(intensity),
                ..Default::default()
            },
            LightDesc::Collimated {
                direction,
                aperture,
                irradiance,
            } => RawLight {
                kind: Some(LightKind::Collimated),
                direction: Some(direction),
                aperture: Some(aperture),
                irradiance: Some(irradiance),
                ..Default::default()
            },
        }
    }
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

/// Where the medium is. Its boundary is index-matched (no refraction).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum RegionDesc {
    /// The whole (unbounded) plane.
    #[default]
    Everywhere,
    /// The scene's domain rectangle.
    Domain,
    Rect(RectDesc),
    /// A simple polygon (even-odd rule), at least three vertices.
    Polygon(Vec<[f64; 2]>),
}

/// Defaults for rendering the scene's field with no flags.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderDesc {
    pub resolution: [u32; 2],
    pub spp: u32,
    pub seed: u64,
    pub quantity: Quantity,
    pub part: Part,
    /// Exposure in stops for tone-mapped figures.
    pub exposure: f64,
    /// Outgoing direction ω_o of L_s, as an angle in degrees (matters only for g ≠ 0).
    pub omega_o_deg: f64,
    /// Maximum path length in scattering/reflection events.
    pub max_depth: u32,
}

impl Default for RenderDesc {
    fn default() -> Self {
        RenderDesc {
            resolution: [256, 256],
            spp: 64,
            seed: 0,
            quantity: Quantity::Ls,
            part: Part::All,
            exposure: 0.0,
            omega_o_deg: 0.0,
            max_depth: 256,
        }
    }
}
