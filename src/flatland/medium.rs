//! Homogeneous media in flatland, filling the plane or a polygonal region with an
//! index-matched boundary.
//!
//! Scene parameters (see `scene_desc::MediumDesc`): `sigma_a`, `sigma_s` (m⁻¹, RGB or
//! scalar), `g` (Henyey–Greenstein, in (−1, 1)), `region`.
//!
//! The medium itself is the pipeline's ([`crate::pipeline::medium`]); this module
//! gives it its 2D region.

use crate::core::space::D2;
use glam::DVec2;
use smallvec::SmallVec;

/// Where the medium is.
#[derive(Clone, Debug, PartialEq)]
pub enum Region {
    Everywhere,
    /// Simple polygon, even–odd rule.
    Polygon(Vec<DVec2>),
}

/// Pieces [t0, t1] of a ray inside the medium, in increasing order.
pub type Intervals = SmallVec<[(f64, f64); 4]>;

/// A homogeneous medium in flatland.
pub type Medium = crate::pipeline::medium::Medium<D2, Region>;

impl crate::pipeline::medium::Region<D2> for Region {
    type Pieces = Intervals;

    fn contains(&self, p: DVec2) -> bool {
        match self {
            Region::Everywhere => true,
            Region::Polygon(poly) => crossings(poly, p, DVec2::X).len() % 2 == 1,
        }
    }

    fn pieces(&self, o: DVec2, d: DVec2, t_max: f64) -> Intervals {
        let mut out = Intervals::new();
        match self {
            Region::Everywhere => out.push((0.0, t_max)),
            Region::Polygon(poly) => {
                let mut ts = crossings(poly, o, d);
                ts.sort_by(f64::total_cmp);
                // Parity of all crossings to infinity says whether o is inside, which
                // keeps the inside test consistent with the crossings themselves.
                let mut inside = ts.len() % 2 == 1;
                let mut start = 0.0;
                for &t in &ts {
                    if t >= t_max {
                        break;
                    }
                    if inside {
                        out.push((start, t));
                    }
                    inside = !inside;
                    start = t;
                }
                if inside {
                    out.push((start, t_max));
                }
            }
        }
        out
    }
}

/// Parameters t > 0 where o + t·d crosses the polygon's edges. Edges are half-open
/// (u in [0, 1)) so a ray through a vertex counts one crossing, not two.
fn crossings(poly: &[DVec2], o: DVec2, d: DVec2) -> SmallVec<[f64; 8]> {
    let mut ts = SmallVec::new();
    let Some(&last) = poly.last() else {
        return ts;
    };
    // Every transmittance query in a region walks all edges, and a ray crosses
    // few: u rejects most edges before t's division is paid (a sixth of a
    // windows.json record's time went here, 17% in a one-thread profile).
    let mut a = last;
    for &b in poly {
        let e = b - a;
        let denom = super::geometry::cross(d, e);
        let ao = a - o;
        a = b;
        if denom == 0.0 {
            continue;
        }
        let u = super::geometry::cross(ao, d) / denom;
        if !(0.0..1.0).contains(&u) {
            continue;
        }
        let t = super::geometry::cross(ao, e) / denom;
        if t > 0.0 {
            ts.push(t);
        }
    }
    ts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::color::Rgb;
    use crate::pipeline::medium::Region as _;

    fn square() -> Region {
        Region::Polygon(vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(0.0, 2.0),
        ])
    }

    #[test]
    fn intervals_clip_to_region() {
        let m = Medium::new(Rgb::ONE, Rgb::ONE, 0.0, square());
        let iv = m.region.pieces(DVec2::new(-1.0, 1.0), DVec2::X, 10.0);
        assert_eq!(iv.as_slice(), &[(1.0, 3.0)]);
        let iv = m.region.pieces(DVec2::new(1.0, 1.0), DVec2::X, 0.5);
        assert_eq!(iv.as_slice(), &[(0.0, 0.5)]);
        assert!(m.contains(DVec2::new(1.0, 1.0)) && !m.contains(DVec2::new(3.0, 1.0)));
        // Through a vertex diagonally: one piece of length 2√2.
        let d = DVec2::ONE.normalize();
        let len = m.length_inside(DVec2::new(-1.0, -1.0), d, 100.0);
        assert!((len - 8f64.sqrt()).abs() < 1e-12, "{len}");
    }
}
