//! The scene drawn over a figure panel: segments, lights and the medium's outline.
//!
//! Draws through a [`View`] (world → pixels), so the same code serves a whole figure
//! or one panel of a composite; everything is clipped to the view's rectangle, and
//! geometry reaching far beyond it is handled (see [`super::panel`]).
//!
//! Legend (sizes scale with [`OverlayStyle::scale`]):
//! - reflecting segments: light grey (brighter for higher reflectance) over a dark
//!   outline, readable on any background;
//! - emitting segments: thicker, warm yellow;
//! - one-sided segments: short ticks on the front (normal) side;
//! - point lights: a yellow dot with a soft halo and eight short rays;
//! - collimated lights: the aperture dashed, and parallel arrows crossing it along
//!   the beam;
//! - a medium bounded by a polygon: dashed light-blue outline (edges lying on the
//!   view's border are left out, so a medium filling the domain draws nothing).

use super::panel::{Canvas, View};
use crate::core::color::luminance;
use crate::flatland::medium::Region;
use crate::flatland::scene::Scene;
use glam::DVec2;
use tiny_skia::Pixmap;

/// How the scene is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OverlayStyle {
    /// Multiplies every line width, mark size and spacing (1 suits ~512 px panels).
    pub scale: f32,
    pub show_medium: bool,
    pub show_lights: bool,
}

impl Default for OverlayStyle {
    fn default() -> Self {
        OverlayStyle {
            scale: 1.0,
            show_medium: true,
            show_lights: true,
        }
    }
}

impl OverlayStyle {
    /// Sizes suited to a panel whose longest side is `px` pixels.
    pub fn for_panel(px: f32) -> Self {
        OverlayStyle {
            scale: (px / 512.0).clamp(0.6, 3.0),
            ..Default::default()
        }
    }
}

const OUTLINE: [u8; 4] = [24, 24, 24, 255];
const EMITTER: [u8; 4] = [255, 196, 46, 255];
const LIGHT: [u8; 4] = [255, 214, 92, 255];
const MEDIUM: [u8; 4] = [140, 205, 255, 255];

/// One stroke of the overlay, drawn twice: its dark outline first, then its core.
struct Mark {
    pts: Vec<DVec2>,
    width: f32,
    color: [u8; 4],
}

/// Draw `scene` over the `view` rectangle of `pixmap`.
pub fn draw_scene(pixmap: &mut Pixmap, scene: &Scene, view: &View, style: &OverlayStyle) {
    let u = style.scale.max(0.1);
    let edge = 1.0 * u; // outline thickness on each side
    let mut canvas = Canvas::new(pixmap, view, 40.0 * u as f64);

    if style.show_medium
        && let Some(Region::Polygon(poly)) = scene.medium.as_ref().map(|m| &m.region)
    {
        draw_medium_outline(&mut canvas, poly, view, u, edge);
    }

    // Segments: every outline before any core, so that joints read as one line.
    let mut marks: Vec<Mark> = Vec::new();
    for s in &scene.geometry.prims {
        let (a, b) = (view.to_pixel_f64(s.a), view.to_pixel_f64(s.b));
        let (width, color) = if s.is_emitter() {
            (3.5 * u, EMITTER)
        } else {
            let g = (150.0 + 90.0 * luminance(s.reflectance).clamp(0.0, 1.0)) as u8;
            (2.0 * u, [g, g, g, 255])
        };
        marks.push(Mark {
            pts: vec![a, b],
            width,
            color,
        });
        if !s.two_sided {
            marks.extend(front_ticks(
                a,
                b,
                view.direction_to_pixel(s.normal),
                width,
                color,
                u,
                &canvas,
            ));
        }
    }
    for m in &marks {
        canvas.polyline(&m.pts, false, m.width + 2.0 * edge, OUTLINE, None);
    }
    for m in &marks {
        canvas.polyline(&m.pts, false, m.width, m.color, None);
    }

    if style.show_lights {
        for l in &scene.collimated_lights {
            draw_collimated(&mut canvas, view, l.aperture, l.direction, u, edge);
        }
        for l in &scene.point_lights {
            let c = view.to_pixel_f64(l.position);
            if canvas.inside(c) {
                draw_point_light(&mut canvas, c, u, edge);
            }
        }
    }
}

/// Ticks on the front side of a one-sided segment from pixel a to b; `normal` is the
/// front normal in pixel space. Only the visible part carries ticks.
fn front_ticks(a: DVec2, b: DVec2, normal: DVec2, width: f32, color: [u8; 4], u: f32, p: &Canvas) -> Vec<Mark> {
    let Some((ca, cb)) = p.clip(a, b) else {
        return Vec::new();
    };
    let along = cb - ca;
    let len = along.length();
    // The front side in pixel space: perpendicular to the drawn segment, on the
    // side of the mapped normal (exact under non-uniform scaling too).
    let mut n = along.perp().normalize_or_zero();
    if n.dot(normal) < 0.0 {
        n = -n;
    }
    let spacing = 12.0 * u as f64;
    let count = ((len / spacing).floor() as usize).max(1);
    let tick = 0.5 * width as f64 + 3.5 * u as f64;
    (0..count)
        .map(|k| {
            let q = ca + along * ((k as f64 + 0.5) / count as f64);
            Mark {
                pts: vec![q, q + n * tick],
                width: (1.3 * u).max(1.0),
                color,
            }
        })
        .collect()
}

fn draw_medium_outline(p: &mut Canvas, poly: &[DVec2], view: &View, u: f32, edge: f32) {
    let pts: Vec<DVec2> = poly.iter().map(|&q| view.to_pixel_f64(q)).collect();
    let (lo, hi) = (view.min(), view.max());
    // Edges on (or beyond) one border of the view add nothing but a frame.
    let on_border = |a: DVec2, b: DVec2| {
        let tol = 0.75;
        (a.x <= lo.x + tol && b.x <= lo.x + tol)
            || (a.x >= hi.x - tol && b.x >= hi.x - tol)
            || (a.y <= lo.y + tol && b.y <= lo.y + tol)
            || (a.y >= hi.y - tol && b.y >= hi.y - tol)
    };
    let n = pts.len();
    let mut runs: Vec<Vec<DVec2>> = Vec::new();
    let mut all_kept = true;
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        if on_border(a, b) {
            all_kept = false;
            continue;
        }
        match runs.last_mut() {
            Some(run) if run.last() == Some(&a) => run.push(b),
            _ => runs.push(vec![a, b]),
        }
    }
    if runs.len() >= 2 && runs[runs.len() - 1].last() == runs[0].first() {
        let first = runs.remove(0);
        runs.last_mut().unwrap().extend_from_slice(&first[1..]);
    }
    let dash = Some((7.0 * u, 5.0 * u));
    let width = 1.5 * u;
    for run in &runs {
        // A fully kept polygon is one closed run (first point repeated at the end).
        let closed = all_kept && run.len() > 2;
        let pts = if closed { &run[..run.len() - 1] } else { &run[..] };
        p.polyline(pts, closed, width + 2.0 * edge, OUTLINE, dash);
        p.polyline(pts, closed, width, MEDIUM, dash);
    }
}

fn draw_point_light(p: &mut Canvas, c: DVec2, u: f32, edge: f32) {
    p.halo(c, 16.0 * u, [255, 220, 120, 150]);
    let rays: Vec<(DVec2, DVec2)> = (0..8)
        .map(|k| {
            let d = DVec2::from_angle(k as f64 * std::f64::consts::FRAC_PI_4);
            (c + d * (6.5 * u) as f64, c + d * (11.0 * u) as f64)
        })
        .collect();
    for &(a, b) in &rays {
        p.line(a, b, 1.5 * u + 2.0 * edge, OUTLINE);
    }
    for &(a, b) in &rays {
        p.line(a, b, 1.5 * u, LIGHT);
    }
    p.disc(c, 4.0 * u + edge, OUTLINE);
    p.disc(c, 4.0 * u, LIGHT);
}

fn draw_collimated(p: &mut Canvas, view: &View, aperture: [DVec2; 2], direction: DVec2, u: f32, edge: f32) {
    let (a, b) = (view.to_pixel_f64(aperture[0]), view.to_pixel_f64(aperture[1]));
    let dash = Some((6.0 * u, 4.0 * u));
    p.polyline(&[a, b], false, 1.5 * u + 2.0 * edge, OUTLINE, dash);
    p.polyline(&[a, b], false, 1.5 * u, LIGHT, dash);

    // Arrows along the visible part of the aperture (all of it, usually).
    let Some((a, b)) = p.clip(a, b) else {
        return;
    };
    let d = view.direction_to_pixel(direction);
    let aperture_len = (b - a).length();
    let count = ((aperture_len / (28.0 * u as f64)).round() as usize).clamp(2, 7);
    let length = (32.0 * u) as f64;
    let head = (7.0 * u) as f64;
    let arrows: Vec<(DVec2, DVec2)> = (0..count)
        .map(|k| {
            let q = a + (b - a) * ((k as f64 + 0.5) / count as f64);
            (q - d * 0.35 * length, q + d * 0.65 * length)
        })
        .collect();
    let heads: Vec<[DVec2; 3]> = arrows
        .iter()
        .map(|&(_, tip)| {
            let base = tip - d * head;
            let side = d.perp() * 0.5 * head;
            [tip, base + side, base - side]
        })
        .collect();
    let shaft_end = |&(s, t): &(DVec2, DVec2)| (s, t - d * 0.6 * head);
    for (arrow, h) in arrows.iter().zip(&heads) {
        let (s, t) = shaft_end(arrow);
        p.line(s, t, 1.5 * u + 2.0 * edge, OUTLINE);
        // The head's outline: the same triangle, stroked.
        p.polyline(h, true, 2.0 * edge, OUTLINE, None);
    }
    for (arrow, h) in arrows.iter().zip(&heads) {
        let (s, t) = shaft_end(arrow);
        p.line(s, t, 1.5 * u, LIGHT);
        if h.iter().all(|&q| p.inside(q)) {
            p.polygon(h, LIGHT);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(segments: &str, extra: &str) -> Scene {
        let json = format!(r#"{{ "domain": {{ "min": [-1, -1], "max": [1, 1] }}, "segments": [{segments}] {extra} }}"#);
        Scene::from_json(&json, "test").unwrap()
    }

    /// Count of pixels with any ink in the rectangle [x0, x1) × [y0, y1).
    fn ink(p: &Pixmap, x0: u32, y0: u32, x1: u32, y1: u32) -> usize {
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| p.pixel(x, y).unwrap().alpha() > 0)
            .count()
    }

    #[test]
    fn far_geometry_is_clipped_to_the_panel() {
        // A segment a million domains long, drawn in the right half of the pixmap.
        let s = scene(r#"{ "a": [-1e6, 0.0], "b": [1e6, 0.0], "reflectance": 0.5 }"#, "");
        let mut p = Pixmap::new(200, 100).unwrap();
        let view = View::new(DVec2::splat(-1.0), DVec2::splat(1.0), 100.0, 0.0, 100.0, 100.0);
        draw_scene(&mut p, &s, &view, &OverlayStyle::default());
        assert_eq!(ink(&p, 0, 0, 100, 100), 0, "ink left of the panel");
        assert_eq!(ink(&p, 100, 0, 200, 45), 0);
        assert_eq!(ink(&p, 100, 55, 200, 100), 0);
        // The line crosses the whole panel at y = 50.
        assert!((100..200).all(|x| p.pixel(x, 50).unwrap().alpha() == 255));
    }

    #[test]
    fn one_sided_segments_have_ticks_on_their_front() {
        // a → b along −x: the front (left) side faces −y, i.e. down in the figure.
        let s = scene(
            r#"{ "a": [0.5, 0.0], "b": [-0.5, 0.0], "emission": 1.0, "two_sided": false }"#,
            "",
        );
        let mut p = Pixmap::new(100, 100).unwrap();
        let view = View::new(DVec2::splat(-1.0), DVec2::splat(1.0), 0.0, 0.0, 100.0, 100.0);
        draw_scene(&mut p, &s, &view, &OverlayStyle::default());
        let (above, below) = (ink(&p, 0, 40, 100, 47), ink(&p, 0, 53, 100, 60));
        assert!(above == 0 && below > 20, "above {above}, below {below}");
    }

    #[test]
    fn medium_outline_skips_the_domain_border() {
        let medium = |region: &str| format!(r#", "medium": {{ "sigma_a": 0.1, "sigma_s": 1, "region": {region} }}"#);
        let view = View::new(DVec2::splat(-1.0), DVec2::splat(1.0), 0.0, 0.0, 100.0, 100.0);
        for (region, inked) in [
            (r#""domain""#, false),
            (r#""everywhere""#, false),
            (r#"{ "rect": { "min": [-0.5, -0.5], "max": [2, 0.5] } }"#, true),
        ] {
            let s = scene("", &medium(region));
            let mut p = Pixmap::new(100, 100).unwrap();
            draw_scene(&mut p, &s, &view, &OverlayStyle::default());
            assert_eq!(ink(&p, 0, 0, 100, 100) > 0, inked, "{region}");
        }
    }

    #[test]
    fn lights_are_drawn() {
        let lights = r#", "lights": [
            { "type": "point", "position": [-0.5, 0.5], "intensity": 1 },
            { "type": "collimated", "direction": [0, -1], "aperture": [[0.2, 0.5], [0.8, 0.5]], "irradiance": 1 }
        ]"#;
        let s = scene("", lights);
        let mut p = Pixmap::new(100, 100).unwrap();
        let view = View::new(DVec2::splat(-1.0), DVec2::splat(1.0), 0.0, 0.0, 100.0, 100.0);
        draw_scene(&mut p, &s, &view, &OverlayStyle::default());
        // The point light's dot is light yellow at its centre.
        let c = p.pixel(25, 25).unwrap();
        assert_eq!([c.red(), c.green(), c.blue(), c.alpha()], LIGHT);
        // The beam's arrows point down: ink below the aperture, within its extent.
        assert!(ink(&p, 60, 28, 90, 40) > 20 && ink(&p, 0, 60, 100, 100) == 0);
    }
}
