//! Records placed for an eye serve only the points the eye sees within a small
//! angle of the record (`CacheSettings::eye_cone_deg`).
//!
//! Why: a record placed for a camera caches L_s(x, ω_o) towards the eye,
//! ω_o(x) = (eye − x)/|eye − x|, and its derivatives include how ω_o turns with x
//! (`probe::Outgoing::TowardsPoint`). That direction is singular at the eye: its
//! Taylor expansion about a record converges only within the record's distance
//! to the eye — the same argument as the lamp reach (`CacheSettings::lamp_reach`).
//! Near a camera inside fog the metric's radii pass that distance, and in an
//! anisotropic medium a record then hands its L_s to points whose ω_o is tens of
//! degrees away (`scenes3d/deep_lamp.json`, g = 0.6: a record 0.22 from the
//! camera, radii up to 0.35, gave 2.4 where the light is 1.4; README). Along the
//! eye's ray ω_o does not turn at all, so the limit is an angle at the eye, not a
//! radius: a record serves a point y only if the eye sees y within the cone's
//! half-angle of the record. Records near the eye become needles along the
//! camera's rays, and none of them covers more than that cone of the view.
//!
//! With an isotropic phase L_s does not depend on ω_o and nothing is limited.

use super::dim::Dim;
use crate::core::phase::Outgoing;
use crate::core::space::Space;

/// The half-angle the app's box starts from: 0.1 rad, the best of 0.1 and 0.2 rad
/// on deep_lamp (README, "The eye cone").
pub const SUGGESTED_EYE_CONE_DEG: f64 = 5.73;

/// The cone at an eye within which a record serves points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeCone<S: Space> {
    pub eye: S::Vec,
    /// The half-angle, in degrees, and its cosine.
    pub half_angle_deg: f64,
    pub cos_max: f64,
}

impl<S: Space> EyeCone<S> {
    /// The cone of `half_angle_deg` at the point records' L_s leaves towards, if
    /// it leaves towards a point (a camera), the angle is set and the phase is
    /// anisotropic (`g ≠ 0`); None otherwise.
    pub fn towards(outgoing: Outgoing<S::Vec>, half_angle_deg: Option<f64>, g: f64) -> Option<Self> {
        match (outgoing, half_angle_deg) {
            (Outgoing::TowardsPoint(eye), Some(a)) if g != 0.0 && a.is_finite() && a > 0.0 => {
                let a = a.min(crate::limits::EYE_CONE_DEG.1);
                Some(EyeCone {
                    eye,
                    half_angle_deg: a,
                    cos_max: a.to_radians().cos(),
                })
            }
            _ => None,
        }
    }

    /// Does the eye see `y` within the cone's half-angle of the record at `x`?
    /// A point at the eye itself is seen in every direction: served.
    pub fn serves(&self, x: S::Vec, y: S::Vec) -> bool {
        let (u, v) = (self.eye - x, self.eye - y);
        let (uu, vv) = (S::length_squared(u), S::length_squared(v));
        if uu == 0.0 || vv == 0.0 {
            return true;
        }
        S::dot(u, v) >= self.cos_max * (uu * vv).sqrt()
    }
}

/// [`EyeCone::serves`] when there is a cone; every point otherwise.
pub fn served<S: Dim>(cone: Option<&EyeCone<S>>, x: S::Vec, y: S::Vec) -> bool {
    cone.is_none_or(|c| c.serves(x, y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::space::D3;
    use glam::DVec3;

    #[test]
    fn a_record_serves_the_points_seen_within_the_angle() {
        let eye = DVec3::new(0.0, 0.0, 1.0);
        let c = EyeCone::<D3>::towards(Outgoing::TowardsPoint(eye), Some(6.0), 0.6).unwrap();
        let x = DVec3::new(0.0, 0.0, 0.0);
        // Along the eye's ray, near or far: the same ω_o.
        assert!(c.serves(x, DVec3::new(0.0, 0.0, 0.9)) && c.serves(x, DVec3::new(0.0, 0.0, -5.0)));
        // 5° and 7° off the record's ray, seen from the eye.
        let at = |deg: f64| eye + DVec3::new(deg.to_radians().sin(), 0.0, -deg.to_radians().cos());
        assert!(c.serves(x, at(5.0)));
        assert!(!c.serves(x, at(7.0)));
        // Behind the eye: ω_o reversed.
        assert!(!c.serves(x, DVec3::new(0.0, 0.0, 2.0)));
        // The eye itself, and a record at the eye, serve and are served.
        assert!(c.serves(x, eye) && c.serves(eye, x));
        assert!(served::<D3>(None, x, DVec3::new(0.0, 0.0, 2.0)));
    }

    #[test]
    fn no_cone_without_an_eye_an_angle_or_anisotropy() {
        let eye = DVec3::ONE;
        assert!(EyeCone::<D3>::towards(Outgoing::Direction(eye), Some(6.0), 0.6).is_none());
        assert!(EyeCone::<D3>::towards(Outgoing::TowardsPoint(eye), None, 0.6).is_none());
        assert!(EyeCone::<D3>::towards(Outgoing::TowardsPoint(eye), Some(6.0), 0.0).is_none());
        assert!(EyeCone::<D3>::towards(Outgoing::TowardsPoint(eye), Some(f64::NAN), 0.5).is_none());
        assert!(EyeCone::<D3>::towards(Outgoing::TowardsPoint(eye), Some(6.0), -0.3).is_some());
    }
}
