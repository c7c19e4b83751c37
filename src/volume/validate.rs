//! Semantic validation of a parsed 3D scene: every problem names its JSON path.
//! (OBJ files are read when the scene is built; their errors name `shapes[i].mesh.path`.)

use super::scene_desc::*;
pub use crate::flatland::validate::Problem;

#[derive(Default)]
struct Checker {
    problems: Vec<Problem>,
}

impl Checker {
    fn fail(&mut self, path: impl Into<String>, message: impl Into<String>) {
        self.problems.push(Problem {
            path: path.into(),
            message: message.into(),
        });
    }

    fn finite(&mut self, path: &str, v: f64) -> bool {
        if !v.is_finite() {
            self.fail(path, format!("must be a finite number, got {v}"));
        }
        v.is_finite()
    }

    fn vec3(&mut self, path: &str, p: [f64; 3]) -> bool {
        (0..3).fold(true, |ok, k| self.finite(&format!("{path}[{k}]"), p[k]) & ok)
    }

    fn nonzero(&mut self, path: &str, p: [f64; 3]) -> bool {
        if self.vec3(path, p) && p == [0.0; 3] {
            self.fail(path, "must not be the zero vector");
            return false;
        }
        true
    }

    fn color(&mut self, path: &str, c: &Color, max: Option<f64>) {
        for (i, &v) in c.0.iter().enumerate() {
            let p = format!("{path}[{i}]");
            if !self.finite(&p, v) {
                continue;
            }
            if v < 0.0 {
                self.fail(p, format!("must not be negative, got {v}"));
            } else if let Some(m) = max.filter(|&m| v > m) {
                self.fail(p, format!("must be at most {m}, got {v}"));
            }
        }
    }

    fn aabb(&mut self, path: &str, min: [f64; 3], max: [f64; 3]) {
        let ok = self.vec3(&format!("{path}.min"), min) & self.vec3(&format!("{path}.max"), max);
        if ok && !(0..3).all(|k| min[k] < max[k]) {
            self.fail(format!("{path}.max"), "must be greater than min in every coordinate");
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// All the problems of a scene (empty when it is valid).
pub fn validate(d: &SceneDesc) -> Vec<Problem> {
    let mut c = Checker::default();
    let cam = &d.camera;
    let placed = c.vec3("camera.position", cam.position) & c.vec3("camera.look_at", cam.look_at);
    if placed && cam.position == cam.look_at {
        c.fail("camera.look_at", "must differ from camera.position");
    }
    if c.nonzero("camera.up", cam.up) {
        let view = [0, 1, 2].map(|k| cam.look_at[k] - cam.position[k]);
        if cross(view, cam.up) == [0.0; 3] && view != [0.0; 3] {
            c.fail("camera.up", "must not be parallel to the viewing direction");
        }
    }
    if c.finite("camera.fov_deg", cam.fov_deg) && !(cam.fov_deg > 0.0 && cam.fov_deg < 180.0) {
        c.fail(
            "camera.fov_deg",
            format!("must lie strictly between 0 and 180, got {}", cam.fov_deg),
        );
    }
    for (i, s) in d.shapes.iter().enumerate() {
        validate_shape(&mut c, &format!("shapes[{i}]"), s);
    }
    for (i, l) in d.lights.iter().enumerate() {
        match l {
            LightDesc::Point(p) => {
                c.vec3(&format!("lights[{i}].point.position"), p.position);
                c.color(&format!("lights[{i}].point.intensity"), &p.intensity, None);
            }
            LightDesc::Sun(s) => {
                let path = format!("lights[{i}].sun");
                c.nonzero(&format!("{path}.direction"), s.direction);
                c.color(&format!("{path}.irradiance"), &s.irradiance, None);
                let a = s.angular_radius_deg;
                if c.finite(&format!("{path}.angular_radius_deg"), a) && !(0.0..=45.0).contains(&a) {
                    c.fail(
                        format!("{path}.angular_radius_deg"),
                        format!("must lie between 0 and 45, got {a}"),
                    );
                }
            }
            LightDesc::Sky(s) => c.color(&format!("lights[{i}].sky.radiance"), &s.radiance, None),
        }
    }
    if let Some(m) = &d.medium {
        c.color("medium.sigma_a", &m.sigma_a, None);
        c.color("medium.sigma_s", &m.sigma_s, None);
        if c.finite("medium.g", m.g) && !(m.g > -1.0 && m.g < 1.0) {
            c.fail("medium.g", format!("must lie strictly between -1 and 1, got {}", m.g));
        }
        if let RegionDesc::Box(b) = &m.region {
            c.aabb("medium.region.box", b.min, b.max);
        }
    }
    let r = &d.render;
    if r.resolution[0] == 0 || r.resolution[1] == 0 || r.resolution[0] > 16384 || r.resolution[1] > 16384 {
        c.fail(
            "render.resolution",
            format!("must be between 1 and 16384 pixels per side, got {:?}", r.resolution),
        );
    }
    if r.spp == 0 {
        c.fail("render.spp", "must be at least 1");
    }
    if r.max_depth == 0 {
        c.fail("render.max_depth", "must be at least 1");
    }
    c.finite("render.exposure", r.exposure);
    c.problems
}

fn validate_shape(c: &mut Checker, path: &str, s: &ShapeDesc) {
    let n = s.quad.is_some() as u8 + s.cuboid.is_some() as u8 + s.mesh.is_some() as u8;
    if n != 1 {
        c.fail(path, "give exactly one of `quad`, `box`, `mesh`");
    }
    if let Some(q) = &s.quad {
        c.vec3(&format!("{path}.quad.origin"), q.origin);
        if c.vec3(&format!("{path}.quad.u"), q.u) & c.vec3(&format!("{path}.quad.v"), q.v)
            && cross(q.u, q.v) == [0.0; 3]
        {
            c.fail(
                format!("{path}.quad.v"),
                "u and v must span a parallelogram (not parallel or zero)",
            );
        }
    }
    if let Some(b) = &s.cuboid {
        c.aabb(&format!("{path}.box"), b.min, b.max);
        c.finite(&format!("{path}.box.rotate_y_deg"), b.rotate_y_deg);
    }
    if let Some(m) = &s.mesh {
        if m.path.trim().is_empty() {
            c.fail(format!("{path}.mesh.path"), "must name an OBJ file");
        }
        if let Some(t) = m.translate {
            c.vec3(&format!("{path}.mesh.translate"), t);
        }
        if let Some(sc) = &m.scale {
            for (k, &v) in sc.0.iter().enumerate() {
                let p = format!("{path}.mesh.scale[{k}]");
                if c.finite(&p, v) && v <= 0.0 {
                    c.fail(p, format!("must be positive, got {v}"));
                }
            }
        }
    }
    c.color(&format!("{path}.reflectance"), &s.reflectance, Some(1.0));
    c.color(&format!("{path}.emission"), &s.emission, None);
}
