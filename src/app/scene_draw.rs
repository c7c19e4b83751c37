//! The scene over the canvas, with the legend of the figures (`figure::overlay`):
//! reflectors light grey over a dark outline (brighter for higher reflectance),
//! emitters thicker warm yellow, one-sided segments ticked on their front side,
//! point lights as yellow dots with rays, collimated lights as a dashed aperture
//! crossed by arrows along the beam, the medium's boundary dashed light blue.
//! Draggable vertices are small dots; the selection is cyan.

use super::edit::{Handle, Selection, region_vertices, segment_pieces, segment_vertices};
use super::view::Xform;
use crate::core::color::{Rgb, luminance};
use crate::flatland::scene_desc::{LightDesc, RegionDesc, SceneDesc};
use eframe::egui::{Color32, Painter, Pos2, Shape, Stroke, Vec2, vec2};
use glam::DVec2;

pub const OUTLINE: Color32 = Color32::from_rgb(24, 24, 24);
pub const EMITTER: Color32 = Color32::from_rgb(255, 196, 46);
pub const LIGHT: Color32 = Color32::from_rgb(255, 214, 92);
pub const MEDIUM: Color32 = Color32::from_rgb(140, 205, 255);
pub const SELECTED: Color32 = Color32::from_rgb(80, 225, 255);

/// Screen direction of a world direction.
fn screen_dir(d: DVec2) -> Vec2 {
    vec2(d.x as f32, -d.y as f32).normalized()
}

/// Draw the scene; returns the number of shapes added (for tests).
pub fn draw_scene(
    painter: &Painter,
    xf: &Xform,
    desc: &SceneDesc,
    hovered: Option<Handle>,
    selection: Option<Selection>,
) -> usize {
    let mut shapes: Vec<Shape> = Vec::new();
    medium_outline(&mut shapes, xf, desc);
    for (i, s) in desc.segments.iter().enumerate() {
        let emitter = !s.emission.is_zero();
        let selected = selection == Some(Selection::Segment(i));
        let hot = matches!(hovered, Some(Handle::Segment(j)) if j == i);
        let width = if emitter { 4.0 } else { 2.5 } + if hot || selected { 1.5 } else { 0.0 };
        let color = if selected {
            SELECTED
        } else if emitter {
            EMITTER
        } else {
            let g = (110.0 + 140.0 * luminance(Rgb::from_array(s.reflectance.0)).clamp(0.0, 1.0)) as u8;
            Color32::from_gray(g)
        };
        for (a, b) in segment_pieces(s) {
            let (pa, pb) = (xf.to_screen(a), xf.to_screen(b));
            shapes.push(Shape::line_segment([pa, pb], Stroke::new(width + 2.0, OUTLINE)));
            shapes.push(Shape::line_segment([pa, pb], Stroke::new(width, color)));
            if !s.two_sided {
                front_ticks(&mut shapes, pa, pb, b - a, color);
            }
        }
        for (k, p) in segment_vertices(s).into_iter().enumerate() {
            let hot = hovered == Some(Handle::Vertex { segment: i, vertex: k });
            let r = if hot { 5.0 } else { 3.0 };
            shapes.push(Shape::circle_filled(xf.to_screen(p), r + 1.0, OUTLINE));
            shapes.push(Shape::circle_filled(
                xf.to_screen(p),
                r,
                if hot { SELECTED } else { color },
            ));
        }
    }
    for (i, l) in desc.lights.iter().enumerate() {
        let hot = hovered == Some(Handle::Light(i)) || selection == Some(Selection::Light(i));
        let color = if hot { SELECTED } else { LIGHT };
        match l {
            LightDesc::Point { position, .. } => {
                let c = xf.to_screen(DVec2::from_array(*position));
                for k in 0..8 {
                    let d = Vec2::angled(k as f32 * std::f32::consts::FRAC_PI_4);
                    shapes.push(Shape::line_segment(
                        [c + d * 8.0, c + d * 13.0],
                        Stroke::new(1.5, color),
                    ));
                }
                shapes.push(Shape::circle_filled(c, 6.0, OUTLINE));
                shapes.push(Shape::circle_filled(c, 4.5, color));
            }
            LightDesc::Collimated {
                direction, aperture, ..
            } => {
                let (a, b) = (DVec2::from_array(aperture[0]), DVec2::from_array(aperture[1]));
                let pts = [xf.to_screen(a), xf.to_screen(b)];
                shapes.extend(Shape::dashed_line(&pts, Stroke::new(2.0, color), 6.0, 4.0));
                let d = screen_dir(DVec2::from_array(*direction));
                for t in [0.2, 0.5, 0.8] {
                    let p = xf.to_screen(a.lerp(b, t));
                    arrow(&mut shapes, p - d * 18.0, d * 36.0, Stroke::new(1.5, color));
                }
            }
        }
    }
    let n = shapes.len();
    painter.extend(shapes);
    n
}

fn arrow(shapes: &mut Vec<Shape>, origin: Pos2, v: Vec2, stroke: Stroke) {
    let tip = origin + v;
    let d = v.normalized() * 7.0;
    let side = vec2(-d.y, d.x) * 0.5;
    shapes.push(Shape::line_segment([origin, tip], stroke));
    shapes.push(Shape::line_segment([tip, tip - d + side], stroke));
    shapes.push(Shape::line_segment([tip, tip - d - side], stroke));
}

/// Short ticks on the front (left of a→b) side, every ~18 points.
fn front_ticks(shapes: &mut Vec<Shape>, pa: Pos2, pb: Pos2, d: DVec2, color: Color32) {
    let n = screen_dir(DVec2::new(-d.y, d.x));
    let len = (pb - pa).length();
    let count = ((len / 18.0).floor() as usize).max(1);
    for k in 0..count {
        let p = pa + (pb - pa) * ((k as f32 + 0.5) / count as f32);
        shapes.push(Shape::line_segment([p, p + n * 6.0], Stroke::new(1.5, color)));
    }
}

fn medium_outline(shapes: &mut Vec<Shape>, xf: &Xform, desc: &SceneDesc) {
    let Some(m) = &desc.medium else { return };
    let mut pts: Vec<Pos2> = match &m.region {
        RegionDesc::Everywhere => return,
        RegionDesc::Domain => {
            let (a, b) = (DVec2::from_array(desc.domain.min), DVec2::from_array(desc.domain.max));
            [a, DVec2::new(b.x, a.y), b, DVec2::new(a.x, b.y)]
                .iter()
                .map(|&p| xf.to_screen(p))
                .collect()
        }
        _ => region_vertices(desc).into_iter().map(|p| xf.to_screen(p)).collect(),
    };
    let handles = !matches!(m.region, RegionDesc::Domain);
    if handles {
        for &p in &pts {
            shapes.push(Shape::rect_filled(
                eframe::egui::Rect::from_center_size(p, vec2(7.0, 7.0)),
                0.0,
                MEDIUM,
            ));
        }
    }
    pts.push(pts[0]);
    shapes.extend(Shape::dashed_line(&pts, Stroke::new(1.5, MEDIUM), 8.0, 5.0));
}
