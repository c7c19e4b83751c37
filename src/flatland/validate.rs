//! Semantic validation of a parsed scene: every problem names its JSON path.

use super::scene_desc::*;

use crate::scene_check::Checker;
pub use crate::scene_check::Problem;

/// Report `p` when it lies outside the domain (with a tiny tolerance).
fn inside(c: &mut Checker, path: &str, p: [f64; 2], dom: &RectDesc, what: &str) {
    let tol = 1e-9 * ((dom.max[0] - dom.min[0]) + (dom.max[1] - dom.min[1]));
    let ok = (0..2).all(|k| p[k] >= dom.min[k] - tol && p[k] <= dom.max[k] + tol);
    if !ok {
        c.fail(path, format!("{what} at ({}, {}) is outside the domain", p[0], p[1]));
    }
}

/// All the problems of a scene (empty when it is valid).
pub fn validate(d: &SceneDesc) -> Vec<Problem> {
    let mut c = Checker::default();
    let domain_ok = c.bounds("domain", d.domain.min, d.domain.max);
    for (i, s) in d.segments.iter().enumerate() {
        let path = format!("segments[{i}]");
        validate_segment(&mut c, &path, s);
    }
    for (i, l) in d.lights.iter().enumerate() {
        let path = format!("lights[{i}]");
        match l {
            LightDesc::Point { position, intensity } => {
                if c.point(&format!("{path}.position"), *position) && domain_ok {
                    inside(
                        &mut c,
                        &format!("{path}.position"),
                        *position,
                        &d.domain,
                        "the point light",
                    );
                }
                c.color(&format!("{path}.intensity"), intensity, None);
            }
            LightDesc::Collimated {
                direction,
                aperture,
                irradiance,
            } => {
                if c.point(&format!("{path}.direction"), *direction) && direction[0] == 0.0 && direction[1] == 0.0 {
                    c.fail(format!("{path}.direction"), "must not be the zero vector");
                }
                let ok = c.point(&format!("{path}.aperture[0]"), aperture[0])
                    & c.point(&format!("{path}.aperture[1]"), aperture[1]);
                if ok && aperture[0] == aperture[1] {
                    c.fail(format!("{path}.aperture"), "zero-length aperture segment");
                }
                if ok && domain_ok {
                    for (k, end) in aperture.iter().enumerate() {
                        inside(
                            &mut c,
                            &format!("{path}.aperture[{k}]"),
                            *end,
                            &d.domain,
                            "the aperture end",
                        );
                    }
                }
                c.color(&format!("{path}.irradiance"), irradiance, None);
            }
        }
    }
    if let Some(m) = &d.medium {
        c.color("medium.sigma_a", &m.sigma_a, None);
        c.color("medium.sigma_s", &m.sigma_s, None);
        c.hg_g("medium.g", m.g);
        match &m.region {
            RegionDesc::Everywhere | RegionDesc::Domain => {}
            RegionDesc::Rect(r) => {
                c.bounds("medium.region.rect", r.min, r.max);
            }
            RegionDesc::Polygon(pts) => {
                let all = pts
                    .iter()
                    .enumerate()
                    .all(|(k, p)| c.point(&format!("medium.region.polygon[{k}]"), *p));
                if pts.len() < 3 {
                    c.fail(
                        "medium.region.polygon",
                        format!("needs at least 3 vertices, got {}", pts.len()),
                    );
                } else if all && polygon_area(pts).abs() == 0.0 {
                    c.fail("medium.region.polygon", "has zero area");
                }
            }
        }
    }
    let r = &d.render;
    c.render_block(r.resolution, r.spp, r.max_depth, r.exposure);
    c.finite("render.omega_o_deg", r.omega_o_deg);
    c.problems
}

fn validate_segment(c: &mut Checker, path: &str, s: &SegmentDesc) {
    match (&s.a, &s.b, &s.points) {
        (Some(a), Some(b), None) => {
            if c.point(&format!("{path}.a"), *a) & c.point(&format!("{path}.b"), *b) && a == b {
                c.fail(format!("{path}.b"), "zero-length segment: a and b coincide");
            }
        }
        (None, None, Some(pts)) => {
            if pts.len() < 2 {
                c.fail(
                    format!("{path}.points"),
                    format!("needs at least 2 points, got {}", pts.len()),
                );
            }
            for (k, p) in pts.iter().enumerate() {
                let pp = format!("{path}.points[{k}]");
                if c.point(&pp, *p) && k > 0 && pts[k - 1] == *p {
                    c.fail(pp, "zero-length segment: repeats the previous point");
                }
            }
            if s.closed && pts.len() >= 2 && pts.first() == pts.last() {
                c.fail(
                    format!("{path}.points"),
                    "closed polyline repeats its first point at the end",
                );
            }
        }
        _ => c.fail(path.to_string(), "give either both `a` and `b`, or `points`"),
    }
    if s.closed && s.points.is_none() {
        c.fail(
            format!("{path}.closed"),
            "only a polyline given by `points` can be closed",
        );
    }
    c.color(&format!("{path}.reflectance"), &s.reflectance, Some(1.0));
    c.color(&format!("{path}.emission"), &s.emission, None);
}

/// Signed area (positive for counter-clockwise).
pub fn polygon_area(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    (0..n)
        .map(|i| pts[i][0] * pts[(i + 1) % n][1] - pts[(i + 1) % n][0] * pts[i][1])
        .sum::<f64>()
        / 2.0
}
