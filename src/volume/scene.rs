//! A loaded, validated 3D scene ready for ray casting.
//!
//! [`Scene::load`] (a file; OBJ paths are relative to its folder) and
//! [`Scene::from_json`] reject malformed JSON, unknown fields and invalid values with
//! an error naming the file, the JSON path and the problem, never a panic.

use super::camera::Camera;
use super::medium::{Medium, Region};
use super::mesh::{self, Triangle};
use super::scene_desc::{LightDesc, RegionDesc, SceneDesc};
use super::validate::{Problem, validate};
use crate::core::color::Rgb;
use crate::core::space::D3;
use crate::pipeline::bvh::{Aabb, Geometry};
use crate::pipeline::emitters::Emitters;
use crate::scene_check;
pub use crate::scene_check::SceneError;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::Path;

/// A shape's diffuse material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    pub reflectance: Rgb,
    /// Radiance, W m⁻² sr⁻¹.
    pub emission: Rgb,
    pub two_sided: bool,
}

/// A point light; intensity in W sr⁻¹.
pub type PointLight = crate::pipeline::nee::PointLight<D3>;

/// A distant light: a delta direction when `cos_max == 1`, else a uniform cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit direction *towards* the sun (−direction of travel).
    pub to_sun: DVec3,
    /// W m⁻² on a plane facing the sun.
    pub irradiance: Rgb,
    /// Cosine of the angular radius.
    pub cos_max: f64,
    /// Radiance inside the cone, E / (π sin²α) (0 for a delta sun).
    pub radiance: Rgb,
}

impl Sun {
    pub fn is_delta(&self) -> bool {
        self.cos_max >= 1.0
    }
    /// Solid angle of the cone, 2π(1 − cos α).
    pub fn solid_angle(&self) -> f64 {
        2.0 * PI * (1.0 - self.cos_max)
    }
}

#[derive(Clone, Debug)]
pub struct Scene {
    pub desc: SceneDesc,
    pub source: String,
    pub camera: Camera,
    /// The scene's triangles and their BVH.
    pub geometry: Geometry<D3, Triangle>,
    /// One per shape, indexed by `Triangle::shape`.
    pub surfaces: Vec<Surface>,
    pub point_lights: Vec<PointLight>,
    pub suns: Vec<Sun>,
    /// Total constant sky radiance (zero: no sky).
    pub sky: Rgb,
    /// Emissive triangles, picked for NEE ∝ luminance × area.
    pub emitters: Emitters,
    pub medium: Option<Medium>,
    pub bounds: Aabb<D3>,
    /// Length scale: diagonal of everything placed in the scene.
    pub scale: f64,
}

impl Scene {
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let base = path.parent().unwrap_or(Path::new("."));
        Self::from_json(&scene_check::read(path)?, &path.display().to_string(), base)
    }

    /// Parse, validate and build; `file` names the source in errors, `base` is the
    /// folder mesh paths are relative to.
    pub fn from_json(text: &str, file: &str, base: &Path) -> Result<Scene, SceneError> {
        Self::build(scene_check::parse(text, file, validate)?, file, base)
    }

    /// Validate a description and build the scene.
    pub fn from_desc(desc: SceneDesc, file: &str, base: &Path) -> Result<Scene, SceneError> {
        Self::build(scene_check::validated(desc, file, validate)?, file, base)
    }

    fn build(desc: SceneDesc, file: &str, base: &Path) -> Result<Scene, SceneError> {
        let v = |p: [f64; 3]| DVec3::from_array(p);
        let rgb = |c: &super::scene_desc::Color| Rgb::from_array(c.0);
        let mut triangles = Vec::new();
        let mut surfaces = Vec::new();
        for (i, s) in desc.shapes.iter().enumerate() {
            let k = i as u32;
            let tris = if let Some(q) = &s.quad {
                mesh::quad(v(q.origin), v(q.u), v(q.v), k)
            } else if let Some(b) = &s.cuboid {
                mesh::cuboid(v(b.min), v(b.max), b.rotate_y_deg, k)
            } else if let Some(m) = &s.mesh {
                let scale = m.scale.map_or(DVec3::ONE, |c| rgb(&c));
                let translate = m.translate.map_or(DVec3::ZERO, v);
                mesh::load_obj(&base.join(&m.path), scale, translate, k)
                    .map_err(|e| invalid(file, format!("shapes[{i}].mesh.path"), e))?
            } else {
                unreachable!("validated: one geometry per shape")
            };
            triangles.extend(tris);
            surfaces.push(Surface {
                reflectance: rgb(&s.reflectance),
                emission: rgb(&s.emission),
                two_sided: s.two_sided,
            });
        }
        let mut bounds = Aabb::<D3>::empty();
        triangles.iter().flat_map(|t| t.vertices()).for_each(|p| bounds.grow(p));
        bounds.grow(v(desc.camera.position));
        let (mut point_lights, mut suns, mut sky) = (Vec::new(), Vec::new(), Rgb::ZERO);
        for l in &desc.lights {
            match l {
                LightDesc::Point(p) => {
                    bounds.grow(v(p.position));
                    point_lights.push(PointLight {
                        position: v(p.position),
                        intensity: rgb(&p.intensity),
                    });
                }
                LightDesc::Sun(s) => {
                    let a = s.angular_radius_deg.to_radians();
                    let e = rgb(&s.irradiance);
                    suns.push(Sun {
                        to_sun: -v(s.direction).normalize(),
                        irradiance: e,
                        cos_max: if a > 0.0 { a.cos() } else { 1.0 },
                        radiance: if a > 0.0 { e / (PI * a.sin().powi(2)) } else { Rgb::ZERO },
                    });
                }
                LightDesc::Sky(s) => sky += rgb(&s.radiance),
            }
        }
        let medium = desc.medium.as_ref().map(|m| {
            let region = match &m.region {
                RegionDesc::Everywhere => Region::Everywhere,
                RegionDesc::Box(b) => {
                    bounds.grow(v(b.min));
                    bounds.grow(v(b.max));
                    Region::Box {
                        min: v(b.min),
                        max: v(b.max),
                    }
                }
            };
            Medium::new(rgb(&m.sigma_a), rgb(&m.sigma_s), m.g, region)
        });
        // A medium that neither scatters nor absorbs costs nothing: drop it.
        let medium = medium.filter(|m| m.sigma_t.max_element() > 0.0);
        let emitters = Emitters::new(triangles.iter().enumerate().filter_map(|(i, t)| {
            let e = surfaces[t.shape as usize].emission;
            (e.max_element() > 0.0).then_some((i as u32, e, t.area))
        }));
        let r = &desc.render;
        let camera = Camera::new(
            v(desc.camera.position),
            v(desc.camera.look_at),
            v(desc.camera.up),
            desc.camera.fov_deg,
            r.resolution[0] as usize,
            r.resolution[1] as usize,
        );
        let scale = (bounds.max - bounds.min).length().max(1e-6);
        // The description's points passed validation; the meshes' vertices (known
        // only now) must keep the scene within reach of f64 too (crate::limits).
        let reach = bounds.min.abs().max(bounds.max.abs()).max_element();
        if bounds.min.x <= bounds.max.x && reach > crate::limits::MAX_SIZES_FROM_ORIGIN * scale {
            return Err(invalid(
                file,
                "shapes".into(),
                format!(
                    "the meshes place the scene ({scale:e} across) {reach:e} from the origin, more than {:e} of its sizes",
                    crate::limits::MAX_SIZES_FROM_ORIGIN
                ),
            ));
        }
        Ok(Scene {
            geometry: Geometry::new(triangles),
            desc,
            source: file.to_string(),
            camera,
            surfaces,
            point_lights,
            suns,
            sky,
            emitters,
            medium,
            bounds,
            scale,
        })
    }

    /// Ray offsets guarding against self-intersection (relative to the scene size).
    #[inline]
    pub fn t_min(&self) -> f64 {
        1e-9 * self.scale
    }

    /// The material of triangle `tri`.
    pub fn material(&self, tri: u32) -> &Surface {
        &self.surfaces[self.geometry.prims[tri as usize].shape as usize]
    }
}

fn invalid(file: &str, path: String, message: String) -> SceneError {
    SceneError::Invalid {
        file: file.to_string(),
        problems: vec![Problem { path, message }],
    }
}
