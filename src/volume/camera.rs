//! The pinhole camera (`camera` block: `position`, `look_at`, `up`, vertical
//! `fov_deg`), with the image size from `render.resolution`. Pixel (i, j) covers
//! [i, i+1) × [j, j+1) in image coordinates, x right and y down (row 0 on top).

use glam::{DVec2, DVec3};

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    /// Unit viewing direction, and the image plane's right and down axes scaled so
    /// that the plane at distance 1 spans the field of view.
    pub forward: DVec3,
    pub right: DVec3,
    pub down: DVec3,
    pub width: usize,
    pub height: usize,
}

impl Camera {
    pub fn new(position: DVec3, look_at: DVec3, up: DVec3, fov_deg: f64, width: usize, height: usize) -> Camera {
        let forward = (look_at - position).normalize();
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        let half_h = (0.5 * fov_deg.to_radians()).tan();
        let half_w = half_h * width as f64 / height as f64;
        Camera {
            position,
            forward,
            right: right * half_w,
            down: -true_up * half_h,
            width,
            height,
        }
    }

    /// Unit direction through image point `p` (pixel units, x right, y down).
    pub fn direction(&self, p: DVec2) -> DVec3 {
        let sx = 2.0 * p.x / self.width as f64 - 1.0;
        let sy = 2.0 * p.y / self.height as f64 - 1.0;
        (self.forward + self.right * sx + self.down * sy).normalize()
    }

    /// Image point (pixel units) where direction `d` from the camera lands, if in front.
    pub fn project(&self, d: DVec3) -> Option<DVec2> {
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let q = d / z;
        let sx = q.dot(self.right) / self.right.length_squared();
        let sy = q.dot(self.down) / self.down.length_squared();
        Some(DVec2::new(
            (sx + 1.0) * 0.5 * self.width as f64,
            (sy + 1.0) * 0.5 * self.height as f64,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_and_corners() {
        let c = Camera::new(DVec3::ZERO, -DVec3::Z, DVec3::Y, 90.0, 200, 100);
        let d = c.direction(DVec2::new(100.0, 50.0));
        assert!((d - -DVec3::Z).length() < 1e-15);
        // Top edge is 45° up; the left edge is atan(2) to the left.
        let top = c.direction(DVec2::new(100.0, 0.0));
        assert!((top.y - (0.5f64).sqrt()).abs() < 1e-12 && top.y > 0.0);
        let left = c.direction(DVec2::new(0.0, 50.0));
        assert!((left.x / -left.z + 2.0).abs() < 1e-12);
        let p = c.project(c.direction(DVec2::new(17.0, 83.0))).unwrap();
        assert!((p - DVec2::new(17.0, 83.0)).length() < 1e-9);
    }
}
