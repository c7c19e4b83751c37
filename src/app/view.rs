//! World ↔ screen mapping of the canvas: the domain fitted to the canvas, then the
//! user's zoom (about a point) and pan. World y points up, screen y down.

use eframe::egui::{Pos2, Rect, pos2};
use glam::DVec2;

/// Zoom and pan chosen by the user (1 and zero: the domain fits the canvas).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewState {
    pub zoom: f64,
    /// World offset of the view centre from the domain centre.
    pub pan: DVec2,
}

impl Default for ViewState {
    fn default() -> Self {
        ViewState {
            zoom: 1.0,
            pan: DVec2::ZERO,
        }
    }
}

/// The mapping of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Xform {
    pub rect: Rect,
    /// World point at the centre of `rect`.
    pub center: DVec2,
    /// Screen points per world unit.
    pub scale: f64,
}

/// Margin around the fitted domain, as a fraction of the canvas.
const FIT: f64 = 0.94;

impl Xform {
    pub fn new(rect: Rect, domain_min: DVec2, domain_max: DVec2, view: &ViewState) -> Self {
        let size = (domain_max - domain_min).max(DVec2::splat(1e-12));
        let fit = (rect.width() as f64 / size.x).min(rect.height() as f64 / size.y) * FIT;
        Xform {
            rect,
            center: 0.5 * (domain_min + domain_max) + view.pan,
            scale: fit.max(1e-9) * view.zoom,
        }
    }

    pub fn to_screen(&self, p: DVec2) -> Pos2 {
        let c = self.rect.center();
        let d = (p - self.center) * self.scale;
        pos2(c.x + d.x as f32, c.y - d.y as f32)
    }

    pub fn to_world(&self, s: Pos2) -> DVec2 {
        let c = self.rect.center();
        self.center + DVec2::new((s.x - c.x) as f64, (c.y - s.y) as f64) / self.scale
    }

    /// A screen length in world units.
    pub fn to_world_len(&self, px: f32) -> f64 {
        px as f64 / self.scale
    }

    /// The screen rectangle of a world rectangle.
    pub fn rect_of(&self, min: DVec2, max: DVec2) -> Rect {
        Rect::from_two_pos(self.to_screen(min), self.to_screen(max))
    }
}

/// Zoom by `factor` keeping the world point under `anchor` fixed.
pub fn zoom_about(view: &mut ViewState, xf: &Xform, anchor: Pos2, factor: f64) {
    let factor = factor.clamp(0.2, 5.0);
    let new_zoom = (view.zoom * factor).clamp(0.05, 1e4);
    let w = xf.to_world(anchor);
    // The anchor's world point w must stay at the same screen offset: centre'
    // = w − (w − centre)·(old scale / new scale).
    let ratio = view.zoom / new_zoom;
    let new_center = w - (w - xf.center) * ratio;
    view.pan += new_center - xf.center;
    view.zoom = new_zoom;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_fit_and_zoom_about_a_point() {
        let rect = Rect::from_min_size(pos2(10.0, 20.0), eframe::egui::vec2(400.0, 200.0));
        let (lo, hi) = (DVec2::new(-1.0, -1.0), DVec2::new(1.0, 1.0));
        let mut view = ViewState::default();
        let xf = Xform::new(rect, lo, hi, &view);
        // Height-limited: 2 world units over 200·0.94 points; y up.
        assert!((xf.scale - 94.0).abs() < 1e-9);
        assert_eq!(xf.to_screen(DVec2::ZERO), rect.center());
        assert!(xf.to_screen(DVec2::new(0.0, 1.0)).y < rect.center().y);
        let p = DVec2::new(0.3, -0.7);
        assert!((xf.to_world(xf.to_screen(p)) - p).length() < 1e-5);
        let anchor = pos2(300.0, 60.0);
        let w = xf.to_world(anchor);
        zoom_about(&mut view, &xf, anchor, 2.0);
        let xf2 = Xform::new(rect, lo, hi, &view);
        assert!((xf2.scale - 188.0).abs() < 1e-9);
        assert!(
            (xf2.to_world(anchor) - w).length() < 1e-5,
            "the point under the pointer stays"
        );
    }
}
