//! Semantic validation of a parsed 3D scene: every problem names its JSON path.
//! The ranges are [`crate::limits`]; the scene's size ℓ is measured on the points
//! the description places (camera, look-at point, shapes, lights, medium box; a
//! mesh by its translation). OBJ files are read when the scene is built; their
//! errors name `shapes[i].mesh.path` and the file's line.

use super::scene_desc::*;
use crate::limits;
pub use crate::scene_check::Problem;
use crate::scene_check::{Checker, Extent, length};

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let l = length(a);
    a.map(|v| v / l)
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// The points a description places, with their JSON paths.
pub fn extent(d: &SceneDesc) -> Extent<3> {
    let mut e = Extent::new();
    e.grow_named("camera.position", d.camera.position);
    e.grow_named("camera.look_at", d.camera.look_at);
    for (i, s) in d.shapes.iter().enumerate() {
        if let Some(q) = &s.quad {
            for (name, p) in [
                ("origin", q.origin),
                ("u", add(q.origin, q.u)),
                ("v", add(q.origin, q.v)),
                ("u", add(add(q.origin, q.u), q.v)),
            ] {
                e.grow_named(&format!("shapes[{i}].quad.{name}"), p);
            }
        }
        if let Some(b) = &s.cuboid {
            e.grow_named(&format!("shapes[{i}].box.min"), b.min);
            e.grow_named(&format!("shapes[{i}].box.max"), b.max);
        }
        if let Some(t) = s.mesh.as_ref().and_then(|m| m.translate) {
            e.grow_named(&format!("shapes[{i}].mesh.translate"), t);
        }
    }
    for (i, l) in d.lights.iter().enumerate() {
        if let LightDesc::Point(p) = l {
            e.grow_named(&format!("lights[{i}].point.position"), p.position);
        }
    }
    if let Some(RegionDesc::Box(b)) = d.medium.as_ref().map(|m| &m.region) {
        e.grow_named("medium.region.box.min", b.min);
        e.grow_named("medium.region.box.max", b.max);
    }
    e
}

/// All the problems of a scene (empty when it is valid).
pub fn validate(d: &SceneDesc) -> Vec<Problem> {
    let mut c = Checker::default();
    let cam = &d.camera;
    let placed = c.point("camera.position", cam.position) & c.point("camera.look_at", cam.look_at);
    let ext = extent(d);
    let size = if placed && c.scene_size("camera", &ext) {
        ext.size()
    } else {
        0.0
    };
    let aimed = placed
        && c.apart(
            "camera.look_at",
            cam.position,
            cam.look_at,
            size,
            "must differ from camera.position",
        );
    if c.direction("camera.up", cam.up) && aimed {
        let view = unit([0, 1, 2].map(|k| cam.look_at[k] - cam.position[k]));
        // sin of the angle between them: the camera's frame is their cross product.
        if length(cross(view, unit(cam.up))) < 1e-6 {
            c.fail("camera.up", "must not be parallel to the viewing direction");
        }
    }
    c.within("camera.fov_deg", cam.fov_deg, limits::FOV_DEG);
    for (i, s) in d.shapes.iter().enumerate() {
        validate_shape(&mut c, &format!("shapes[{i}]"), s, size);
    }
    for (i, l) in d.lights.iter().enumerate() {
        match l {
            LightDesc::Point(p) => {
                c.point(&format!("lights[{i}].point.position"), p.position);
                c.radiometric(&format!("lights[{i}].point.intensity"), &p.intensity);
            }
            LightDesc::Sun(s) => {
                let path = format!("lights[{i}].sun");
                c.direction(&format!("{path}.direction"), s.direction);
                c.radiometric(&format!("{path}.irradiance"), &s.irradiance);
                let a = s.angular_radius_deg;
                let min = limits::MIN_SUN_RADIUS_DEG;
                if c.finite(&format!("{path}.angular_radius_deg"), a) && !(a == 0.0 || (min..=45.0).contains(&a)) {
                    c.fail(
                        format!("{path}.angular_radius_deg"),
                        format!("must be 0 (parallel light) or lie between {min} and 45, got {a}"),
                    );
                }
            }
            LightDesc::Sky(s) => c.radiometric(&format!("lights[{i}].sky.radiance"), &s.radiance),
        }
    }
    if let Some(m) = &d.medium {
        c.coefficient("medium.sigma_a", &m.sigma_a);
        c.coefficient("medium.sigma_s", &m.sigma_s);
        c.hg_g("medium.g", m.g);
        if let RegionDesc::Box(b) = &m.region {
            c.bounds("medium.region.box", b.min, b.max, size);
        }
    }
    let r = &d.render;
    c.render_block(r.resolution, r.spp, r.max_depth, r.exposure);
    c.problems
}

fn validate_shape(c: &mut Checker, path: &str, s: &ShapeDesc, size: f64) {
    let n = s.quad.is_some() as u8 + s.cuboid.is_some() as u8 + s.mesh.is_some() as u8;
    if n != 1 {
        c.fail(path, "give exactly one of `quad`, `box`, `mesh`");
    }
    if let Some(q) = &s.quad {
        c.point(&format!("{path}.quad.origin"), q.origin);
        let sides = c.point(&format!("{path}.quad.u"), q.u) & c.point(&format!("{path}.quad.v"), q.v);
        let min = limits::MIN_SEPARATION * size;
        // Each side at least MIN_SEPARATION·ℓ long and the sides not parallel (the
        // sine of their angle at least 1e-9), so the two triangles have an area.
        if sides
            && (length(q.u) < min.max(f64::MIN_POSITIVE)
                || length(q.v) < min.max(f64::MIN_POSITIVE)
                || length(cross(unit(q.u), unit(q.v))) < 1e-9)
        {
            c.fail(
                format!("{path}.quad.v"),
                "u and v must span a parallelogram (not parallel, and each at least 1e-9 of the scene size)",
            );
        }
    }
    if let Some(b) = &s.cuboid {
        c.bounds(&format!("{path}.box"), b.min, b.max, size);
        let a = limits::MAX_ANGLE_DEG;
        c.within(&format!("{path}.box.rotate_y_deg"), b.rotate_y_deg, (-a, a));
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
                let (lo, hi) = limits::MESH_SCALE;
                if c.finite(&p, v) && v <= 0.0 {
                    c.fail(p, format!("must be positive, got {v}"));
                } else if v.is_finite() && !(lo..=hi).contains(&v) {
                    c.fail(p, format!("must lie between {lo:e} and {hi:e}, got {v:e}"));
                }
            }
        }
    }
    c.reflectance(&format!("{path}.reflectance"), &s.reflectance);
    c.radiometric(&format!("{path}.emission"), &s.emission);
}
