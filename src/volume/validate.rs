//! Semantic validation of a parsed 3D scene: every problem names its JSON path.
//! (OBJ files are read when the scene is built; their errors name `shapes[i].mesh.path`.)

use super::scene_desc::*;
use crate::scene_check::Checker;
pub use crate::scene_check::Problem;

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
    let placed = c.point("camera.position", cam.position) & c.point("camera.look_at", cam.look_at);
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
                c.point(&format!("lights[{i}].point.position"), p.position);
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
        c.hg_g("medium.g", m.g);
        if let RegionDesc::Box(b) = &m.region {
            c.bounds("medium.region.box", b.min, b.max);
        }
    }
    let r = &d.render;
    c.render_block(r.resolution, r.spp, r.max_depth, r.exposure);
    c.problems
}

fn validate_shape(c: &mut Checker, path: &str, s: &ShapeDesc) {
    let n = s.quad.is_some() as u8 + s.cuboid.is_some() as u8 + s.mesh.is_some() as u8;
    if n != 1 {
        c.fail(path, "give exactly one of `quad`, `box`, `mesh`");
    }
    if let Some(q) = &s.quad {
        c.point(&format!("{path}.quad.origin"), q.origin);
        if c.point(&format!("{path}.quad.u"), q.u) & c.point(&format!("{path}.quad.v"), q.v)
            && cross(q.u, q.v) == [0.0; 3]
        {
            c.fail(
                format!("{path}.quad.v"),
                "u and v must span a parallelogram (not parallel or zero)",
            );
        }
    }
    if let Some(b) = &s.cuboid {
        c.bounds(&format!("{path}.box"), b.min, b.max);
        c.finite(&format!("{path}.box.rotate_y_deg"), b.rotate_y_deg);
    }
    if let Some(m) = &s.mesh {
        if m.path.trim().is_empty() {
            c.fail(format!("{path}.mesh.path"), "must name an OBJ file");
        }
        if let Some(t) = m.translate {
            c.point(&format!("{path}.mesh.translate"), t);
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
