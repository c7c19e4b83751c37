//! Semantic validation of a parsed scene: every problem names its JSON path.

use super::scene_desc::*;

/// One problem with a scene: the JSON path of the field and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    pub path: String,
    pub message: String,
}

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
        if v.is_finite() {
            true
        } else {
            self.fail(path, format!("must be a finite number, got {v}"));
            false
        }
    }

    fn point(&mut self, path: &str, p: [f64; 2]) -> bool {
        self.finite(&format!("{path}[0]"), p[0]) & self.finite(&format!("{path}[1]"), p[1])
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

    fn inside(&mut self, path: &str, p: [f64; 2], dom: &RectDesc, what: &str) {
        let tol = 1e-9 * ((dom.max[0] - dom.min[0]) + (dom.max[1] - dom.min[1]));
        let ok = (0..2).all(|k| p[k] >= dom.min[k] - tol && p[k] <= dom.max[k] + tol);
        if !ok {
            self.fail(path, format!("{what} at ({}, {}) is outside the domain", p[0], p[1]));
        }
    }

    fn rect(&mut self, path: &str, r: &RectDesc) -> bool {
        let ok = self.point(&format!("{path}.min"), r.min) & self.point(&format!("{path}.max"), r.max);
        if ok && !(r.min[0] < r.max[0] && r.min[1] < r.max[1]) {
            self.fail(format!("{path}.max"), "must be greater than min in both coordinates");
            return false;
        }
        ok
    }
}

/// All the problems of a scene (empty when it is valid).
pub fn validate(d: &SceneDesc) -> Vec<Problem> {
    let mut c = Checker { problems: Vec::new() };
    let domain_ok = c.rect("domain", &d.domain);
    for (i, s) in d.segments.iter().enumerate() {
        let path = format!("segments[{i}]");
        validate_segment(&mut c, &path, s);
    }
    for (i, l) in d.lights.iter().enumerate() {
        let path = format!("lights[{i}]");
        match l {
            LightDesc::Point { position, intensity } => {
                if c.point(&format!("{path}.position"), *position) && domain_ok {
                    c.inside(&format!("{path}.position"), *position, &d.domain, "the point light");
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
                        c.inside(&format!("{path}.aperture[{k}]"), *end, &d.domain, "the aperture end");
                    }
                }
                c.color(&format!("{path}.irradiance"), irradiance, None);
            }
        }
    }
    if let Some(m) = &d.medium {
        c.color("medium.sigma_a", &m.sigma_a, None);
        c.color("medium.sigma_s", &m.sigma_s, None);
        if c.finite("medium.g", m.g) && !(m.g > -1.0 && m.g < 1.0) {
            c.fail("medium.g", format!("must lie strictly between -1 and 1, got {}", m.g));
        }
        match &m.region {
            RegionDesc::Everywhere | RegionDesc::Domain => {}
            RegionDesc::Rect(r) => {
                c.rect("medium.region.rect", r);
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
