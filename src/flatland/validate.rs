//! Semantic validation of a parsed scene: every problem names its JSON path. The
//! ranges are [`crate::limits`]; the scene's size ℓ is the domain's diagonal. Every
//! point lies within `MAX_SIZES_FROM_ORIGIN`·ℓ of the origin, and every segment
//! reaches into the world disc (`pipeline::world::WORLD_RADIUS` sizes around the domain's
//! centre): beyond it nothing is ever seen, so a segment entirely outside would
//! silently vanish.

use super::scene_desc::*;

use crate::limits;
pub use crate::scene_check::Problem;
use crate::scene_check::{Checker, Extent, distance};

/// The domain's centre and size, once the domain itself is valid.
#[derive(Clone, Copy)]
struct Frame {
    centre: [f64; 2],
    size: f64,
}

impl Frame {
    /// Within `MAX_SIZES_FROM_ORIGIN` scene sizes of the origin (f64 resolves the
    /// scene's details there).
    fn near(&self, c: &mut Checker, path: &str, p: [f64; 2]) {
        let reach = p[0].abs().max(p[1].abs());
        let max = limits::MAX_SIZES_FROM_ORIGIN * self.size;
        if reach > max {
            c.fail(
                path,
                format!(
                    "({:e}, {:e}) lies more than {:e} scene sizes ({max:e}) from the origin",
                    p[0],
                    p[1],
                    limits::MAX_SIZES_FROM_ORIGIN
                ),
            );
        }
    }

    /// The segment a–b reaches into the world disc.
    fn reaches(&self, c: &mut Checker, path: &str, a: [f64; 2], b: [f64; 2]) {
        let r = crate::pipeline::world::WORLD_RADIUS * self.size;
        let (ab, ac) = (
            [b[0] - a[0], b[1] - a[1]],
            [self.centre[0] - a[0], self.centre[1] - a[1]],
        );
        let len2 = ab[0] * ab[0] + ab[1] * ab[1];
        let t = ((ac[0] * ab[0] + ac[1] * ab[1]) / len2).clamp(0.0, 1.0);
        let closest = [a[0] + t * ab[0], a[1] + t * ab[1]];
        if distance(closest, self.centre) > r {
            c.fail(
                path,
                format!(
                    "lies entirely outside the world disc ({r:e} around the domain's centre), where nothing is seen"
                ),
            );
        }
    }
}

/// Report `p` when it lies outside the domain (with a tiny tolerance).
fn inside(c: &mut Checker, path: &str, p: [f64; 2], dom: &RectDesc, what: &str) {
    let tol = 1e-9 * ((dom.max[0] - dom.min[0]) + (dom.max[1] - dom.min[1]));
    let ok = (0..2).all(|k| p[k] >= dom.min[k] - tol && p[k] <= dom.max[k] + tol);
    if !ok {
        c.fail(path, format!("{what} at ({}, {}) is outside the domain", p[0], p[1]));
    }
}

/// A point's coordinates, and where it lies (when the frame is known).
fn place(c: &mut Checker, frame: Option<Frame>, path: &str, p: [f64; 2]) -> bool {
    let ok = c.point(path, p);
    if let (true, Some(f)) = (ok, frame) {
        f.near(c, path, p);
    }
    ok
}

/// A segment's ends (already placed) are apart, and it reaches into the world.
fn piece(c: &mut Checker, frame: Option<Frame>, path: &str, a: [f64; 2], b: [f64; 2], what: &str) {
    let size = frame.map_or(0.0, |f| f.size);
    if c.apart(path, a, b, size, what)
        && let Some(f) = frame
    {
        f.reaches(c, path, a, b);
    }
}

/// All the problems of a scene (empty when it is valid).
pub fn validate(d: &SceneDesc) -> Vec<Problem> {
    let mut c = Checker::default();
    let domain_ok = c.bounds("domain", d.domain.min, d.domain.max, 0.0) && {
        let mut e = Extent::new();
        e.grow(d.domain.min);
        e.grow(d.domain.max);
        c.scene_size("domain", &e)
    };
    let frame = domain_ok.then(|| Frame {
        centre: [0, 1].map(|k| 0.5 * (d.domain.min[k] + d.domain.max[k])),
        size: distance(d.domain.min, d.domain.max),
    });
    for (i, s) in d.segments.iter().enumerate() {
        let path = format!("segments[{i}]");
        validate_segment(&mut c, frame, &path, s);
    }
    for (i, l) in d.lights.iter().enumerate() {
        let path = format!("lights[{i}]");
        match l {
            LightDesc::Point { position, intensity } => {
                if place(&mut c, frame, &format!("{path}.position"), *position) && domain_ok {
                    inside(
                        &mut c,
                        &format!("{path}.position"),
                        *position,
                        &d.domain,
                        "the point light",
                    );
                }
                c.radiometric(&format!("{path}.intensity"), intensity);
            }
            LightDesc::Collimated {
                direction,
                aperture,
                irradiance,
            } => {
                c.direction(&format!("{path}.direction"), *direction);
                let ok = place(&mut c, frame, &format!("{path}.aperture[0]"), aperture[0])
                    & place(&mut c, frame, &format!("{path}.aperture[1]"), aperture[1]);
                if let (true, Some(f)) = (ok, frame) {
                    c.apart(
                        &format!("{path}.aperture"),
                        aperture[0],
                        aperture[1],
                        f.size,
                        "zero-length aperture segment",
                    );
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
                c.radiometric(&format!("{path}.irradiance"), irradiance);
            }
        }
    }
    if let Some(m) = &d.medium {
        c.coefficient("medium.sigma_a", &m.sigma_a);
        c.coefficient("medium.sigma_s", &m.sigma_s);
        c.hg_g("medium.g", m.g);
        let size = frame.map_or(0.0, |f| f.size);
        match &m.region {
            RegionDesc::Everywhere | RegionDesc::Domain => {}
            RegionDesc::Rect(r) => {
                if c.bounds("medium.region.rect", r.min, r.max, size) {
                    place(&mut c, frame, "medium.region.rect.min", r.min);
                    place(&mut c, frame, "medium.region.rect.max", r.max);
                }
            }
            RegionDesc::Polygon(pts) => {
                let all = pts.iter().enumerate().fold(true, |ok, (k, p)| {
                    place(&mut c, frame, &format!("medium.region.polygon[{k}]"), *p) & ok
                });
                // (The smallest area a polygon of sides MIN_SEPARATION·ℓ can have.)
                let min_area = (limits::MIN_SEPARATION * size).powi(2);
                if pts.len() < 3 {
                    c.fail(
                        "medium.region.polygon",
                        format!("needs at least 3 vertices, got {}", pts.len()),
                    );
                } else if all && polygon_area(pts).abs() <= min_area {
                    c.fail("medium.region.polygon", "has zero area");
                }
            }
        }
    }
    let r = &d.render;
    c.render_block(r.resolution, r.spp, r.max_depth, r.exposure);
    c.within(
        "render.omega_o_deg",
        r.omega_o_deg,
        (-limits::MAX_ANGLE_DEG, limits::MAX_ANGLE_DEG),
    );
    c.problems
}

fn validate_segment(c: &mut Checker, frame: Option<Frame>, path: &str, s: &SegmentDesc) {
    let size = frame.map_or(0.0, |f| f.size);
    match (&s.a, &s.b, &s.points) {
        (Some(a), Some(b), None) => {
            if place(c, frame, &format!("{path}.a"), *a) & place(c, frame, &format!("{path}.b"), *b) {
                piece(
                    c,
                    frame,
                    &format!("{path}.b"),
                    *a,
                    *b,
                    "zero-length segment: a and b coincide",
                );
            }
        }
        (None, None, Some(pts)) => {
            if pts.len() < 2 {
                c.fail(
                    format!("{path}.points"),
                    format!("needs at least 2 points, got {}", pts.len()),
                );
            }
            let mut all = true;
            for (k, p) in pts.iter().enumerate() {
                let pp = format!("{path}.points[{k}]");
                let ok = place(c, frame, &pp, *p);
                if ok && k > 0 && pts[k - 1].iter().all(|v| v.is_finite()) {
                    piece(
                        c,
                        frame,
                        &pp,
                        pts[k - 1],
                        *p,
                        "zero-length segment: repeats the previous point",
                    );
                }
                all &= ok;
            }
            if s.closed && pts.len() >= 2 && all {
                let (first, last) = (pts[0], pts[pts.len() - 1]);
                let d = distance(first, last);
                if d == 0.0 || d < limits::MIN_SEPARATION * size {
                    c.fail(
                        format!("{path}.points"),
                        "closed polyline repeats its first point at the end",
                    );
                }
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
    c.reflectance(&format!("{path}.reflectance"), &s.reflectance);
    c.radiometric(&format!("{path}.emission"), &s.emission);
}

/// Signed area (positive for counter-clockwise).
pub fn polygon_area(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    (0..n)
        .map(|i| pts[i][0] * pts[(i + 1) % n][1] - pts[(i + 1) % n][0] * pts[i][1])
        .sum::<f64>()
        / 2.0
}
