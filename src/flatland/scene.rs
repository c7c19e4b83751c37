//! A loaded, validated flatland scene ready for ray casting.
//!
//! Load with [`Scene::load`] (a file) or [`Scene::from_json`] (text); both reject
//! malformed JSON, unknown fields and invalid values with an error naming the file,
//! the JSON path of the field and the problem. The default scene is embedded.

use super::geometry::{Segment, SegmentSet};
use super::medium::{Medium, Region};
use super::scene_desc::{LightDesc, RegionDesc, SceneDesc};
use super::validate::validate;
use crate::core::color::Rgb;
use crate::core::space::D2;
use crate::pipeline::emitters::Emitters;
use crate::scene_check;
use glam::DVec2;
use std::path::Path;

/// The embedded default scene (`flatland_scenes/occluder.json`).
pub const DEFAULT_SCENE_NAME: &str = "occluder.json";
pub const DEFAULT_SCENE_JSON: &str = include_str!("../../flatland_scenes/occluder.json");

pub use crate::scene_check::SceneError;

/// A point light; intensity in W rad⁻¹.
pub type PointLight = crate::pipeline::nee::PointLight<D2>;

#[derive(Clone, Debug, PartialEq)]
pub struct CollimatedLight {
    /// Unit direction of travel.
    pub direction: DVec2,
    pub aperture: [DVec2; 2],
    /// W m⁻¹ across the beam.
    pub irradiance: Rgb,
}

/// A scene ready for the transport code.
#[derive(Clone, Debug)]
pub struct Scene {
    /// What was loaded (serialises back to the same JSON).
    pub desc: SceneDesc,
    /// Where it came from (a file name, or "<embedded …>").
    pub source: String,
    pub domain_min: DVec2,
    pub domain_max: DVec2,
    pub geometry: SegmentSet,
    pub point_lights: Vec<PointLight>,
    pub collimated_lights: Vec<CollimatedLight>,
    /// Emitting segments, picked for NEE ∝ luminance × length.
    pub emitters: Emitters,
    pub medium: Option<Medium>,
    /// Minimum hit distance (avoids re-hitting at corners), relative to the size.
    pub t_min: f64,
}

impl Scene {
    /// Read, parse and validate a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Self::from_json(&scene_check::read(path)?, &path.display().to_string())
    }

    /// The embedded default scene.
    pub fn default_scene() -> Scene {
        Self::from_json(DEFAULT_SCENE_JSON, &super::shipped::embedded_source(DEFAULT_SCENE_NAME))
            .expect("the embedded default scene is valid (tested)")
    }

    /// Parse and validate scene JSON; `file` names the source in errors.
    pub fn from_json(text: &str, file: &str) -> Result<Scene, SceneError> {
        Ok(Self::build(scene_check::parse(text, file, validate)?, file))
    }

    /// Validate a description and build the scene.
    pub fn from_desc(desc: SceneDesc, file: &str) -> Result<Scene, SceneError> {
        Ok(Self::build(scene_check::validated(desc, file, validate)?, file))
    }

    fn build(desc: SceneDesc, file: &str) -> Scene {
        let v = |p: [f64; 2]| DVec2::new(p[0], p[1]);
        let rgb = |c: &super::scene_desc::Color| Rgb::from_array(c.0);
        let domain_min = v(desc.domain.min);
        let domain_max = v(desc.domain.max);
        let mut segments = Vec::new();
        for s in &desc.segments {
            let (refl, emit) = (rgb(&s.reflectance), rgb(&s.emission));
            let pts: Vec<DVec2> = match (&s.a, &s.b, &s.points) {
                (Some(a), Some(b), _) => vec![v(*a), v(*b)],
                (_, _, Some(p)) => p.iter().map(|&q| v(q)).collect(),
                _ => unreachable!("validated"),
            };
            let n = pts.len();
            let count = if s.closed { n } else { n - 1 };
            for i in 0..count {
                segments.push(Segment::new(pts[i], pts[(i + 1) % n], refl, emit, s.two_sided));
            }
        }
        let mut point_lights = Vec::new();
        let mut collimated_lights = Vec::new();
        for l in &desc.lights {
            match l {
                LightDesc::Point { position, intensity } => point_lights.push(PointLight {
                    position: v(*position),
                    intensity: rgb(intensity),
                }),
                LightDesc::Collimated {
                    direction,
                    aperture,
                    irradiance,
                } => collimated_lights.push(CollimatedLight {
                    direction: v(*direction).normalize(),
                    aperture: [v(aperture[0]), v(aperture[1])],
                    irradiance: rgb(irradiance),
                }),
            }
        }
        let medium = desc.medium.as_ref().map(|m| {
            let region = match &m.region {
                RegionDesc::Everywhere => Region::Everywhere,
                RegionDesc::Domain => Region::Polygon(rect_polygon(domain_min, domain_max)),
                RegionDesc::Rect(r) => Region::Polygon(rect_polygon(v(r.min), v(r.max))),
                RegionDesc::Polygon(p) => Region::Polygon(p.iter().map(|&q| v(q)).collect()),
            };
            Medium::new(rgb(&m.sigma_a), rgb(&m.sigma_s), m.g, region)
        });
        // A medium that neither scatters nor absorbs costs nothing: drop it.
        let medium = medium.filter(|m| m.sigma_t.max_element() > 0.0);
        let emitters = Emitters::new(
            segments
                .iter()
                .enumerate()
                .filter(|(_, s)| s.is_emitter())
                .map(|(i, s)| (i as u32, s.emission, s.length())),
        );
        let scale = (domain_max - domain_min).length();
        Scene {
            desc,
            source: file.to_string(),
            domain_min,
            domain_max,
            geometry: SegmentSet::new(segments),
            point_lights,
            collimated_lights,
            emitters,
            medium,
            t_min: 1e-10 * scale.max(1e-300),
        }
    }
}

fn rect_polygon(a: DVec2, b: DVec2) -> Vec<DVec2> {
    vec![a, DVec2::new(b.x, a.y), b, DVec2::new(a.x, b.y)]
}
