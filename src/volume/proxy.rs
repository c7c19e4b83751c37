//! Light field → occlusion-free proxy elements fixed in world space (the 3D
//! counterpart of `flatland::proxy`).
//!
//! - Surface elements: each triangle of the directions' triangulation with its
//!   vertices moved to the rays' end points (hits; escaped rays end at the cut length
//!   with the radiance of [`super::probe::ProbeRay::end`]). Where the vertices lie at
//!   very different depths the element bridges an occluder's edge and the background:
//!   its solid angle changes fast as x moves, which is how occlusion changes enter
//!   the derivatives. Its form factor is `core::triangle_form_factor`; vertices are
//!   ordered so that it is positive from x.
//! - Medium elements: at each shell i, the triangle of the i-th samples of the three
//!   rays, with thickness Δt. Where some ray stopped before shell i (it hit an
//!   occluder), the element bridges that ray's end point and the others' samples.
//!
//! A surface element carries the radiance of its vertex **farther from x**
//! (Schwarzhaupt et al. 2012); [`RadianceRule::Average`] is the alternative. Medium
//! elements within a shell average their samples; a bridging medium element carries
//! the sum of its samples over three (the ray ends count as zero), anchored at the
//! samples' centroid.

use super::probe::LightField;
use crate::core::color::Rgb;
use glam::DVec3;
use serde::Serialize;

pub use crate::flatland::proxy::{ElementKind, RadianceRule};

/// A proxy element: the triangle `v` (counter-clockwise seen from x, so its signed
/// solid angle from x is positive), the radiance it carries (for medium elements
/// already multiplied by the shell thickness Δt) and the anchor towards which
/// transmittance and phase are evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Element {
    pub v: [DVec3; 3],
    pub anchor: DVec3,
    pub radiance: Rgb,
    pub kind: ElementKind,
    /// The vertices lie at clearly different depths (an occlusion boundary).
    pub bridging: bool,
    /// Solid angle of the element's direction triangle (unit sphere), 4π/(2N) on average.
    pub dir_solid_angle: f64,
}

impl crate::core::metric::Radiant for Element {
    fn radiance_mut(&mut self) -> &mut Rgb {
        &mut self.radiance
    }
}

impl Element {
    /// Longest edge.
    pub fn size(&self) -> f64 {
        let [a, b, c] = self.v;
        (b - a).length().max((c - b).length()).max((a - c).length())
    }
}

/// Vertices whose depths differ by more than this fraction bridge a discontinuity.
const BRIDGE_RATIO: f64 = 0.1;

/// Orient (a, b, c) counter-clockwise as seen from x.
fn orient(x: DVec3, v: [DVec3; 3]) -> [DVec3; 3] {
    let [a, b, c] = v;
    if (a - x).dot((b - a).cross(c - a)) >= 0.0 {
        v
    } else {
        [a, c, b]
    }
}

fn make(
    x: DVec3,
    v: [(DVec3, f64, Rgb); 3],
    rule: RadianceRule,
    kind: ElementKind,
    bridging: bool,
    omega: f64,
) -> Element {
    let (anchor, radiance) = match rule {
        RadianceRule::Farther => {
            let far = (0..3)
                .max_by(|&i, &j| v[i].1.total_cmp(&v[j].1))
                .expect("three vertices");
            (v[far].0, v[far].2)
        }
        RadianceRule::Average => ((v[0].0 + v[1].0 + v[2].0) / 3.0, (v[0].2 + v[1].2 + v[2].2) / 3.0),
    };
    Element {
        v: orient(x, [v[0].0, v[1].0, v[2].0]),
        anchor,
        radiance,
        kind,
        bridging,
        dir_solid_angle: omega,
    }
}

/// Build the proxy of a light field.
pub fn build(lf: &LightField, rule: RadianceRule) -> Vec<Element> {
    let x = lf.x;
    let ends: Vec<(DVec3, f64, Rgb)> = lf.rays.iter().map(|r| r.end(x)).collect();
    let mut out = Vec::with_capacity(lf.triangles.len() * 2);
    let omega_of = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| lf.rays[i as usize].dir);
        super::sphere::solid_angle(a, b, c).abs()
    };
    for t in &lf.triangles {
        let v = t.map(|i| ends[i as usize]);
        let (dmin, dmax) = v
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), e| (lo.min(e.1), hi.max(e.1)));
        let bridging = dmax - dmin > BRIDGE_RATIO * dmin;
        out.push(make(x, v, rule, ElementKind::Surface, bridging, omega_of(t)));
    }
    let shells = lf.rays.iter().map(|r| r.samples.len()).max().unwrap_or(0);
    for t in &lf.triangles {
        let rs = t.map(|i| &lf.rays[i as usize]);
        let omega = omega_of(t);
        for i in 0..shells {
            let present = rs.map(|r| i < r.samples.len());
            if !present.iter().any(|&p| p) {
                continue;
            }
            let v: [(DVec3, f64, Rgb); 3] = [0, 1, 2].map(|k| {
                let r = rs[k];
                if present[k] {
                    let d = lf.sample_depth(r, i);
                    (x + r.dir * d, d, r.samples[i] * lf.step)
                } else {
                    let e = ends[t[k] as usize];
                    (e.0, e.1, Rgb::ZERO)
                }
            });
            if v.iter().all(|e| e.2 == Rgb::ZERO) {
                continue; // outside the medium region: nothing to carry
            }
            let bridging = !present.iter().all(|&p| p);
            let mut e = make(x, v, RadianceRule::Average, ElementKind::Medium, bridging, omega);
            if bridging {
                // The ray ends carry no medium radiance: the piece is anchored at the
                // samples' centroid and carries their sum over three vertices (the
                // ends count as zero), so that every sample keeps the weight it has
                // in the plain estimate. (Carrying the samples' mean instead, as the
                // 2D proxy does for its two-vertex pieces, overweights them: +17% of
                // the multiple-scattering value on fog_box.json with 16 steps.)
                let (mut c, mut l, mut m) = (DVec3::ZERO, Rgb::ZERO, 0.0);
                for k in (0..3).filter(|&k| present[k]) {
                    c += v[k].0;
                    l += v[k].2;
                    m += 1.0;
                }
                (e.anchor, e.radiance) = (c / m, l / 3.0);
            }
            out.push(e);
        }
    }
    out
}
