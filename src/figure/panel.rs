//! One panel of a figure: a [`View`] maps a world rectangle (y up) onto a pixel
//! rectangle of a pixmap (y down), with [`Field::world_to_pixel`] semantics, and a
//! [`Canvas`] draws in it, clipped to it. Several panels can share one pixmap.
//!
//! Clipping is done twice: geometrically (Cohen–Sutherland, in f64) to the view grown
//! by a margin, so that huge or distant coordinates never reach the rasteriser, then
//! exactly by a mask of the view's rectangle.

use crate::flatland::field::Field;
use glam::DVec2;
use tiny_skia::{
    Color, FillRule, GradientStop, LineCap, LineJoin, Mask, Paint, PathBuilder, Pixmap, Point, RadialGradient, Rect,
    SpreadMode, Stroke, StrokeDash, Transform,
};

/// A world rectangle shown in a pixel rectangle (x0, y0, width, height) of a pixmap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub world_min: DVec2,
    pub world_max: DVec2,
    pub x0: f32,
    pub y0: f32,
    pub width: f32,
    pub height: f32,
}

impl View {
    pub fn new(world_min: DVec2, world_max: DVec2, x0: f32, y0: f32, width: f32, height: f32) -> Self {
        View {
            world_min,
            world_max,
            x0,
            y0,
            width,
            height,
        }
    }

    /// The view of a field drawn at `scale` pixels per field pixel with its top-left
    /// corner at (x0, y0).
    pub fn of_field(field: &Field, x0: f32, y0: f32, scale: f32) -> Self {
        View {
            world_min: field.world_min,
            world_max: field.world_max,
            x0,
            y0,
            width: field.width as f32 * scale,
            height: field.height as f32 * scale,
        }
    }

    /// Pixel coordinates of a world point, in f64 (no overflow or precision loss for
    /// far-away points; [`Canvas`] clips in f64).
    pub fn to_pixel_f64(&self, p: DVec2) -> DVec2 {
        let size = self.world_max - self.world_min;
        DVec2::new(
            self.x0 as f64 + (p.x - self.world_min.x) / size.x * self.width as f64,
            self.y0 as f64 + (self.world_max.y - p.y) / size.y * self.height as f64,
        )
    }

    /// Pixel coordinates (x right, y down) of a world point (y up).
    pub fn to_pixel(&self, p: DVec2) -> (f32, f32) {
        let q = self.to_pixel_f64(p);
        (q.x as f32, q.y as f32)
    }

    /// The world point at pixel coordinates (x, y).
    pub fn to_world(&self, x: f32, y: f32) -> DVec2 {
        let size = self.world_max - self.world_min;
        DVec2::new(
            self.world_min.x + (x - self.x0) as f64 / self.width as f64 * size.x,
            self.world_max.y - (y - self.y0) as f64 / self.height as f64 * size.y,
        )
    }

    /// A world direction as a unit pixel-space direction.
    pub fn direction_to_pixel(&self, d: DVec2) -> DVec2 {
        let size = self.world_max - self.world_min;
        DVec2::new(d.x / size.x * self.width as f64, -d.y / size.y * self.height as f64).normalize_or_zero()
    }

    /// Top-left pixel corner.
    pub fn min(&self) -> DVec2 {
        DVec2::new(self.x0 as f64, self.y0 as f64)
    }

    /// Bottom-right pixel corner.
    pub fn max(&self) -> DVec2 {
        DVec2::new((self.x0 + self.width) as f64, (self.y0 + self.height) as f64)
    }
}

fn paint(c: [u8; 4]) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color_rgba8(c[0], c[1], c[2], c[3]);
    p.anti_alias = true;
    p
}

fn stroke(width: f32, dash: Option<(f32, f32)>, cap: LineCap) -> Stroke {
    Stroke {
        width,
        line_cap: cap,
        line_join: LineJoin::Round,
        dash: dash.and_then(|(on, off)| StrokeDash::new(vec![on, off], 0.0)),
        ..Stroke::default()
    }
}

/// Clip a pixel-space segment to the rectangle [lo, hi] (Cohen–Sutherland): the
/// clipped ends and whether each end was moved. Each moved end is computed from the
/// boundary it lands on, so the result stays exact for far-away endpoints.
fn clip_segment(a: DVec2, b: DVec2, lo: DVec2, hi: DVec2) -> Option<(DVec2, DVec2, bool, bool)> {
    if !(a.is_finite() && b.is_finite()) {
        return None;
    }
    let code = |p: DVec2| {
        (p.x < lo.x) as u8 | ((p.x > hi.x) as u8) << 1 | ((p.y < lo.y) as u8) << 2 | ((p.y > hi.y) as u8) << 3
    };
    let (mut a, mut b, mut a_moved, mut b_moved) = (a, b, false, false);
    // Each pass puts one end on a boundary; four passes suffice, eight allow rounding.
    for _ in 0..8 {
        let (ca, cb) = (code(a), code(b));
        if ca | cb == 0 {
            return Some((a, b, a_moved, b_moved));
        }
        if ca & cb != 0 {
            return None;
        }
        // p is outside, q on the other side of p's boundary (so no division by 0).
        let (p, q, c) = if ca != 0 { (a, b, ca) } else { (b, a, cb) };
        let at_x = |x: f64| DVec2::new(x, p.y + (q.y - p.y) * (x - p.x) / (q.x - p.x));
        let at_y = |y: f64| DVec2::new(p.x + (q.x - p.x) * (y - p.y) / (q.y - p.y), y);
        let moved = if c & 1 != 0 {
            at_x(lo.x)
        } else if c & 2 != 0 {
            at_x(hi.x)
        } else if c & 4 != 0 {
            at_y(lo.y)
        } else {
            at_y(hi.y)
        };
        if ca != 0 {
            (a, a_moved) = (moved, true);
        } else {
            (b, b_moved) = (moved, true);
        }
    }
    None
}

/// Cut a pixel-space polyline to [lo, hi] into the runs that remain.
fn clip_polyline(pts: &[DVec2], closed: bool, lo: DVec2, hi: DVec2) -> Vec<Vec<DVec2>> {
    let mut runs: Vec<Vec<DVec2>> = Vec::new();
    let mut cur: Vec<DVec2> = Vec::new();
    let flush = |cur: &mut Vec<DVec2>, runs: &mut Vec<Vec<DVec2>>| {
        if cur.len() >= 2 {
            runs.push(std::mem::take(cur));
        } else {
            cur.clear();
        }
    };
    let n = pts.len();
    let edges = if closed && n > 2 { n } else { n.saturating_sub(1) };
    for i in 0..edges {
        match clip_segment(pts[i], pts[(i + 1) % n], lo, hi) {
            None => flush(&mut cur, &mut runs),
            Some((a, b, a_moved, b_moved)) => {
                if cur.is_empty() || a_moved {
                    flush(&mut cur, &mut runs);
                    cur.push(a);
                }
                cur.push(b);
                if b_moved {
                    flush(&mut cur, &mut runs);
                }
            }
        }
    }
    flush(&mut cur, &mut runs);
    // A closed outline cut open only at its first vertex: rejoin the two ends there.
    if closed && runs.len() >= 2 && runs[runs.len() - 1].last() == Some(&pts[0]) && runs[0].first() == Some(&pts[0]) {
        let first = runs.remove(0);
        runs.last_mut().unwrap().extend_from_slice(&first[1..]);
    }
    runs
}

/// Draws into one view of a pixmap, clipped to it: pixel-space strokes and fills
/// (anti-aliased), cut geometrically to the view grown by a margin, then masked to
/// the view exactly.
pub struct Canvas<'a> {
    pixmap: &'a mut Pixmap,
    mask: Option<Mask>,
    /// Geometric clip rectangle: the view grown by a margin wider than any mark.
    lo: DVec2,
    hi: DVec2,
}

impl<'a> Canvas<'a> {
    /// `margin`: how far (pixels) outside the view marks may start and still show.
    pub fn new(pixmap: &'a mut Pixmap, view: &View, margin: f64) -> Self {
        let (pw, ph) = (pixmap.width() as f32, pixmap.height() as f32);
        let covers_all = view.x0 <= 0.0 && view.y0 <= 0.0 && view.x0 + view.width >= pw && view.y0 + view.height >= ph;
        let mask = if covers_all {
            None
        } else {
            Rect::from_xywh(view.x0, view.y0, view.width, view.height).and_then(|r| {
                let mut m = Mask::new(pixmap.width(), pixmap.height())?;
                m.fill_path(
                    &PathBuilder::from_rect(r),
                    FillRule::Winding,
                    false,
                    Transform::identity(),
                );
                Some(m)
            })
        };
        Canvas {
            pixmap,
            mask,
            lo: view.min() - margin,
            hi: view.max() + margin,
        }
    }

    /// Stroke a pixel-space polyline (clipped); `dash` = (on, off) lengths.
    pub fn polyline(&mut self, pts: &[DVec2], closed: bool, width: f32, color: [u8; 4], dash: Option<(f32, f32)>) {
        let mut pb = PathBuilder::new();
        for run in clip_polyline(pts, closed, self.lo, self.hi) {
            pb.move_to(run[0].x as f32, run[0].y as f32);
            for p in &run[1..] {
                pb.line_to(p.x as f32, p.y as f32);
            }
            if closed && run.len() > 2 && run.first() == run.last() {
                pb.close();
            }
        }
        if let Some(path) = pb.finish() {
            let cap = if dash.is_some() { LineCap::Butt } else { LineCap::Round };
            self.pixmap.stroke_path(
                &path,
                &paint(color),
                &stroke(width, dash, cap),
                Transform::identity(),
                self.mask.as_ref(),
            );
        }
    }

    /// A solid line with round caps.
    pub fn line(&mut self, a: DVec2, b: DVec2, width: f32, color: [u8; 4]) {
        self.polyline(&[a, b], false, width, color, None);
    }

    /// The part of a pixel-space segment within the view grown by the margin.
    pub fn clip(&self, a: DVec2, b: DVec2) -> Option<(DVec2, DVec2)> {
        clip_segment(a, b, self.lo, self.hi).map(|(a, b, _, _)| (a, b))
    }

    /// Is the pixel-space point within the view (grown by the margin)?
    pub fn inside(&self, p: DVec2) -> bool {
        p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }

    /// A filled disc.
    pub fn disc(&mut self, c: DVec2, r: f32, color: [u8; 4]) {
        if let Some(path) = PathBuilder::from_circle(c.x as f32, c.y as f32, r) {
            self.pixmap.fill_path(
                &path,
                &paint(color),
                FillRule::Winding,
                Transform::identity(),
                self.mask.as_ref(),
            );
        }
    }

    /// A filled polygon (not clipped geometrically: keep it near the view).
    pub fn polygon(&mut self, pts: &[DVec2], color: [u8; 4]) {
        let mut pb = PathBuilder::new();
        pb.move_to(pts[0].x as f32, pts[0].y as f32);
        for p in &pts[1..] {
            pb.line_to(p.x as f32, p.y as f32);
        }
        pb.close();
        if let Some(path) = pb.finish() {
            self.pixmap.fill_path(
                &path,
                &paint(color),
                FillRule::Winding,
                Transform::identity(),
                self.mask.as_ref(),
            );
        }
    }

    /// A disc fading from `color` at the centre to transparent at radius r.
    pub fn halo(&mut self, c: DVec2, r: f32, color: [u8; 4]) {
        let (x, y) = (c.x as f32, c.y as f32);
        let stops = vec![
            GradientStop::new(0.0, Color::from_rgba8(color[0], color[1], color[2], color[3])),
            GradientStop::new(1.0, Color::from_rgba8(color[0], color[1], color[2], 0)),
        ];
        let shader = RadialGradient::new(
            Point::from_xy(x, y),
            0.0,
            Point::from_xy(x, y),
            r,
            stops,
            SpreadMode::Pad,
            Transform::identity(),
        );
        if let (Some(shader), Some(path)) = (shader, PathBuilder::from_circle(x, y, r)) {
            let p = Paint {
                shader,
                anti_alias: true,
                ..Paint::default()
            };
            self.pixmap
                .fill_path(&path, &p, FillRule::Winding, Transform::identity(), self.mask.as_ref());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_matches_field_convention() {
        let f = Field::new(40, 20, DVec2::new(-2.0, -1.0), DVec2::new(2.0, 1.0));
        let v = View::of_field(&f, 10.0, 5.0, 3.0);
        for p in [DVec2::new(0.3, -0.7), DVec2::new(-2.0, 1.0), DVec2::new(1.9, 0.2)] {
            let q = f.world_to_pixel(p) * 3.0 + DVec2::new(10.0, 5.0);
            let (x, y) = v.to_pixel(p);
            assert!((x as f64 - q.x).abs() < 1e-4 && (y as f64 - q.y).abs() < 1e-4);
            assert!((v.to_world(x, y) - p).length() < 1e-5);
        }
        // World up is pixel up.
        assert!(v.direction_to_pixel(DVec2::Y).y < 0.0);
    }

    #[test]
    fn clipping_handles_far_and_crossing_lines() {
        let (lo, hi) = (DVec2::ZERO, DVec2::splat(10.0));
        let (a, b, ma, mb) = clip_segment(DVec2::new(-1e30, 5.0), DVec2::new(1e30, 5.0), lo, hi).unwrap();
        assert_eq!(
            (a, b, ma, mb),
            (DVec2::new(0.0, 5.0), DVec2::new(10.0, 5.0), true, true)
        );
        assert!(clip_segment(DVec2::new(-5.0, -1.0), DVec2::new(20.0, -1.0), lo, hi).is_none());
        assert!(clip_segment(DVec2::new(f64::NAN, 0.0), DVec2::ONE, lo, hi).is_none());
        // A closed square straddling the right border becomes one open run.
        let sq = [
            DVec2::new(2.0, 2.0),
            DVec2::new(12.0, 2.0),
            DVec2::new(12.0, 8.0),
            DVec2::new(2.0, 8.0),
        ];
        let runs = clip_polyline(&sq, true, lo, hi);
        assert_eq!(runs.len(), 1, "{runs:?}");
        assert_eq!(runs[0].first(), Some(&DVec2::new(10.0, 8.0)));
        assert_eq!(runs[0].last(), Some(&DVec2::new(10.0, 2.0)));
        assert_eq!(runs[0].len(), 4);
    }
}
