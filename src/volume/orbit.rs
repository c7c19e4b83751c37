//! Camera motion (the app's 3D view, `bench moments3d`), on the scene file's camera block (position,
//! look_at, up, fov): orbit about the look-at point, pan in the image plane, dolly
//! towards the look-at point. Pure functions, so the view's mouse handling stays
//! thin and the motions are tested without a window.
//!
//! Orbit turns about the scene's `up` axis (yaw) and the camera's right axis
//! (pitch); pitch stops short of the poles, where the right axis is undefined and
//! the view would flip. Dolly never reaches the look-at point (the camera's
//! direction would be undefined), and pan moves by a fraction of the visible
//! height at the look-at distance, so a drag feels the same at any scale.

use crate::volume::scene_desc::CameraDesc;
use glam::{DQuat, DVec3};

/// The closest the camera gets to either pole of `up`, radians from it.
const POLE_MARGIN: f64 = 0.02;
/// The closest dolly gets to the look-at point, as a fraction of `scale`.
const MIN_DISTANCE: f64 = 1e-3;

fn v(a: [f64; 3]) -> DVec3 {
    DVec3::from_array(a)
}

/// Turn the camera about the look-at point: `yaw` about `up`, `pitch` about the
/// camera's right axis (positive: the camera rises), radians.
pub fn orbit(c: &CameraDesc, yaw: f64, pitch: f64) -> CameraDesc {
    let (target, up) = (v(c.look_at), v(c.up).normalize());
    let offset = v(c.position) - target;
    let r = offset.length();
    if r == 0.0 || !up.is_finite() {
        return c.clone();
    }
    // Polar angle from up, kept inside (margin, π − margin).
    let polar = (offset.dot(up) / r).clamp(-1.0, 1.0).acos();
    let new_polar = (polar - pitch).clamp(POLE_MARGIN, std::f64::consts::PI - POLE_MARGIN);
    let forward = -offset / r;
    let right = forward.cross(up);
    let right = if right.length() > 1e-12 {
        right.normalize()
    } else {
        up.any_orthonormal_vector()
    };
    // About right = forward × up, a positive angle tips the offset away from up.
    let pitched = DQuat::from_axis_angle(right, new_polar - polar) * offset;
    let turned = DQuat::from_axis_angle(up, yaw) * pitched;
    CameraDesc {
        position: (target + turned).to_array(),
        ..c.clone()
    }
}

/// Move camera and look-at point together in the image plane by (`dx`, `dy`)
/// visible heights at the look-at distance (x right, y down: a drag's direction).
pub fn pan(c: &CameraDesc, dx: f64, dy: f64) -> CameraDesc {
    let (pos, target) = (v(c.position), v(c.look_at));
    let offset = target - pos;
    let r = offset.length();
    if r == 0.0 {
        return c.clone();
    }
    let forward = offset / r;
    let right = forward.cross(v(c.up));
    if right.length() < 1e-12 {
        return c.clone();
    }
    let right = right.normalize();
    let true_up = right.cross(forward);
    let height = 2.0 * r * (0.5 * c.fov_deg.to_radians()).tan();
    // Dragging right moves the scene right: the camera goes left.
    let shift = (-right * dx + true_up * dy) * height;
    CameraDesc {
        position: (pos + shift).to_array(),
        look_at: (target + shift).to_array(),
        ..c.clone()
    }
}

/// Scale the distance to the look-at point by `factor` (< 1: closer), never below
/// a thousandth of `scale` (the scene's size).
pub fn dolly(c: &CameraDesc, factor: f64, scale: f64) -> CameraDesc {
    let target = v(c.look_at);
    let offset = v(c.position) - target;
    let r = offset.length();
    if r == 0.0 || !factor.is_finite() || factor <= 0.0 {
        return c.clone();
    }
    let new_r = (r * factor).max(MIN_DISTANCE * scale);
    CameraDesc {
        position: (target + offset * (new_r / r)).to_array(),
        ..c.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> CameraDesc {
        CameraDesc {
            position: [0.0, 1.0, 4.0],
            look_at: [0.0, 1.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_deg: 40.0,
        }
    }

    fn dist(c: &CameraDesc) -> f64 {
        (v(c.position) - v(c.look_at)).length()
    }

    #[test]
    fn orbit_keeps_the_distance_and_the_target() {
        let c = orbit(&cam(), 0.7, 0.3);
        assert!((dist(&c) - 4.0).abs() < 1e-12);
        assert_eq!(c.look_at, cam().look_at);
        // A quarter turn about y takes +z to +x.
        let q = orbit(&cam(), std::f64::consts::FRAC_PI_2, 0.0);
        assert!((v(q.position) - DVec3::new(4.0, 1.0, 0.0)).length() < 1e-12);
        // Positive pitch raises the camera.
        assert!(orbit(&cam(), 0.0, 0.3).position[1] > 1.0);
    }

    #[test]
    fn orbit_stops_short_of_the_poles() {
        let c = orbit(&cam(), 0.0, 10.0);
        let offset = (v(c.position) - v(c.look_at)).normalize();
        assert!(offset.y < 1.0 && (offset.y.acos() - POLE_MARGIN).abs() < 1e-9);
        // And can come back from there.
        let back = orbit(&c, 0.0, -1.0);
        assert!(back.position.iter().all(|x| x.is_finite()));
        assert!(back.position[1] < c.position[1]);
    }

    #[test]
    fn pan_moves_both_points_in_the_image_plane() {
        let c = pan(&cam(), 0.25, 0.0);
        let shift = v(c.position) - v(cam().position);
        assert_eq!(shift, v(c.look_at) - v(cam().look_at));
        assert!(shift.x < 0.0 && shift.y.abs() < 1e-12 && shift.z.abs() < 1e-12);
        // A quarter of the visible height at distance 4.
        let h = 8.0 * 20f64.to_radians().tan();
        assert!((shift.length() - 0.25 * h).abs() < 1e-12);
        assert!(
            pan(&cam(), 0.0, 0.1).position[1] > 1.0,
            "dragging down moves the view up"
        );
    }

    #[test]
    fn dolly_scales_the_distance_and_never_reaches_the_target() {
        assert!((dist(&dolly(&cam(), 0.5, 10.0)) - 2.0).abs() < 1e-12);
        assert!((dist(&dolly(&cam(), 1e-9, 10.0)) - 1e-2).abs() < 1e-12);
        assert_eq!(dolly(&cam(), f64::NAN, 10.0), cam());
    }
}
