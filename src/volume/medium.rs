//! Homogeneous media in 3D, filling space or an axis-aligned box (index-matched).
//!
//! Scene parameters (`scene_desc::MediumDesc`): `sigma_a`, `sigma_s` (m⁻¹, RGB or
//! scalar), `g` (Henyey–Greenstein, in (−1, 1)), `region` ("everywhere" or a box).
//!
//! The medium itself is the pipeline's ([`crate::pipeline::medium`]); this module
//! gives it its 3D region.

use crate::core::space::D3;
use glam::DVec3;

#[derive(Clone, Debug, PartialEq)]
pub enum Region {
    Everywhere,
    Box { min: DVec3, max: DVec3 },
}

/// A homogeneous medium in 3D.
pub type Medium = crate::pipeline::medium::Medium<D3, Region>;

impl crate::pipeline::medium::Region<D3> for Region {
    type Pieces = Option<(f64, f64)>;

    fn contains(&self, p: DVec3) -> bool {
        match *self {
            Region::Everywhere => true,
            Region::Box { min, max } => p.cmpge(min).all() && p.cmple(max).all(),
        }
    }

    /// The piece [t0, t1] of o + t·d, 0 ≤ t ≤ t_max, inside the region (None if empty).
    #[inline]
    fn pieces(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<(f64, f64)> {
        match *self {
            Region::Everywhere => Some((0.0, t_max)),
            Region::Box { min, max } => {
                let (mut t0, mut t1) = (0.0f64, t_max);
                for k in 0..3 {
                    if d[k] == 0.0 {
                        // Parallel to this slab: inside it (closed) or never.
                        if o[k] < min[k] || o[k] > max[k] {
                            return None;
                        }
                        continue;
                    }
                    let (a, b) = ((min[k] - o[k]) / d[k], (max[k] - o[k]) / d[k]);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
                (t0 < t1).then_some((t0, t1))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::color::Rgb;
    use crate::pipeline::medium::Region as _;

    #[test]
    fn box_interval() {
        let m = Medium::new(
            Rgb::ONE,
            Rgb::ONE,
            0.0,
            Region::Box {
                min: DVec3::ZERO,
                max: DVec3::splat(2.0),
            },
        );
        assert_eq!(
            m.region.pieces(DVec3::new(-1.0, 1.0, 1.0), DVec3::X, 10.0),
            Some((1.0, 3.0))
        );
        assert_eq!(
            m.region.pieces(DVec3::new(1.0, 1.0, 1.0), DVec3::X, 0.5),
            Some((0.0, 0.5))
        );
        assert_eq!(m.region.pieces(DVec3::new(-1.0, 3.0, 1.0), DVec3::X, 10.0), None);
        // On a face, travelling along it: inside (closed box).
        assert_eq!(
            m.region.pieces(DVec3::new(-1.0, 0.0, 1.0), DVec3::X, 10.0),
            Some((1.0, 3.0))
        );
    }
}
