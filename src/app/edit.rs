//! Scene edits on the description (what the JSON holds), independent of any UI:
//! picking the handle under the pointer, dragging handles, adding and deleting
//! segments and lights. The document ([`super::document`]) validates the result
//! and keeps the undo stack.

use crate::flatland::scene_desc::{Color, LightDesc, RegionDesc, SceneDesc, SegmentDesc};
use glam::DVec2;

/// Something on the canvas that can be dragged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Handle {
    /// Vertex `vertex` of segment entry `segment` (a/b are vertices 0/1).
    Vertex { segment: usize, vertex: usize },
    /// A whole segment entry (every vertex moves).
    Segment(usize),
    /// A light: a point light's position, or a collimated light's aperture.
    Light(usize),
    /// Vertex of the medium region (polygon vertex, or rect corner counter-clockwise
    /// from min).
    RegionVertex(usize),
    /// The probe of the inspector (not part of the scene).
    Probe,
}

/// What the side panel edits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    Segment(usize),
    Light(usize),
}

fn v(p: [f64; 2]) -> DVec2 {
    DVec2::new(p[0], p[1])
}

/// The vertices of a segment entry (a, b or its polyline points).
pub fn segment_vertices(s: &SegmentDesc) -> Vec<DVec2> {
    match (&s.a, &s.b, &s.points) {
        (Some(a), Some(b), _) => vec![v(*a), v(*b)],
        (_, _, Some(p)) => p.iter().map(|&q| v(q)).collect(),
        _ => Vec::new(),
    }
}

/// The straight pieces of a segment entry.
pub fn segment_pieces(s: &SegmentDesc) -> Vec<(DVec2, DVec2)> {
    let p = segment_vertices(s);
    let n = p.len();
    let count = if s.closed && n > 2 { n } else { n.saturating_sub(1) };
    (0..count).map(|i| (p[i], p[(i + 1) % n])).collect()
}

/// Move vertex k of a segment entry to p.
pub fn set_vertex(s: &mut SegmentDesc, k: usize, p: DVec2) {
    let p = p.to_array();
    match (&mut s.a, &mut s.b, &mut s.points) {
        (Some(a), Some(_), _) if k == 0 => *a = p,
        (Some(_), Some(b), _) if k == 1 => *b = p,
        (_, _, Some(pts)) if k < pts.len() => pts[k] = p,
        _ => {}
    }
}

/// The corners or vertices of the medium region that can be dragged.
pub fn region_vertices(desc: &SceneDesc) -> Vec<DVec2> {
    match desc.medium.as_ref().map(|m| &m.region) {
        Some(RegionDesc::Rect(r)) => {
            let (a, b) = (v(r.min), v(r.max));
            vec![a, DVec2::new(b.x, a.y), b, DVec2::new(a.x, b.y)]
        }
        Some(RegionDesc::Polygon(p)) => p.iter().map(|&q| v(q)).collect(),
        _ => Vec::new(),
    }
}

/// Distance from p to the segment [a, b].
pub fn distance_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = if d.length_squared() > 0.0 {
        ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t - p).length()
}

/// The handle within `tol` (world units) of `p`, by priority: probe, vertices,
/// lights, region vertices, segment bodies; the nearest within a class.
pub fn pick(desc: &SceneDesc, probe: Option<DVec2>, p: DVec2, tol: f64) -> Option<Handle> {
    let nearest = |items: Vec<(Handle, f64)>| {
        items
            .into_iter()
            .filter(|(_, d)| *d <= tol)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(h, _)| h)
    };
    if probe.is_some_and(|q| (q - p).length() <= tol) {
        return Some(Handle::Probe);
    }
    let vertices = desc
        .segments
        .iter()
        .enumerate()
        .flat_map(|(i, s)| {
            segment_vertices(s)
                .into_iter()
                .enumerate()
                .map(move |(k, q)| (Handle::Vertex { segment: i, vertex: k }, (q - p).length()))
        })
        .collect();
    let lights = desc
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let d = match l {
                LightDesc::Point { position, .. } => (v(*position) - p).length(),
                LightDesc::Collimated { aperture, .. } => distance_to_segment(p, v(aperture[0]), v(aperture[1])),
            };
            (Handle::Light(i), d)
        })
        .collect();
    let region = region_vertices(desc)
        .into_iter()
        .enumerate()
        .map(|(k, q)| (Handle::RegionVertex(k), (q - p).length()))
        .collect();
    let bodies = desc
        .segments
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let d = segment_pieces(s)
                .iter()
                .map(|&(a, b)| distance_to_segment(p, a, b))
                .fold(f64::INFINITY, f64::min);
            (Handle::Segment(i), d)
        })
        .collect();
    [vertices, lights, region, bodies].into_iter().find_map(nearest)
}

/// Move `handle` by the pointer going from `from` to `to` (world units). The probe
/// is not part of the scene: nothing happens for it.
pub fn drag(desc: &mut SceneDesc, handle: Handle, from: DVec2, to: DVec2) {
    let delta = to - from;
    let shift = |p: &mut [f64; 2]| *p = (v(*p) + delta).to_array();
    match handle {
        Handle::Vertex { segment, vertex } => {
            if let Some(s) = desc.segments.get_mut(segment) {
                let old = segment_vertices(s).get(vertex).copied();
                if let Some(q) = old {
                    set_vertex(s, vertex, q + delta);
                }
            }
        }
        Handle::Segment(i) => {
            if let Some(s) = desc.segments.get_mut(i) {
                s.a.iter_mut().chain(s.b.iter_mut()).for_each(shift);
                s.points.iter_mut().flatten().for_each(shift);
            }
        }
        Handle::Light(i) => match desc.lights.get_mut(i) {
            Some(LightDesc::Point { position, .. }) => shift(position),
            Some(LightDesc::Collimated { aperture, .. }) => aperture.iter_mut().for_each(shift),
            None => {}
        },
        Handle::RegionVertex(k) => match desc.medium.as_mut().map(|m| &mut m.region) {
            Some(RegionDesc::Polygon(p)) => {
                if let Some(q) = p.get_mut(k) {
                    shift(q);
                }
            }
            Some(RegionDesc::Rect(r)) => {
                // Corner k: 0 = min, 1 = (max.x, min.y), 2 = max, 3 = (min.x, max.y).
                let x = if matches!(k % 4, 0 | 3) {
                    &mut r.min[0]
                } else {
                    &mut r.max[0]
                };
                *x += delta.x;
                let y = if k % 4 < 2 { &mut r.min[1] } else { &mut r.max[1] };
                *y += delta.y;
            }
            _ => {}
        },
        Handle::Probe => {}
    }
}

/// A new grey reflector of length `len` centred at `at`; returns its index.
pub fn add_segment(desc: &mut SceneDesc, at: DVec2, len: f64) -> usize {
    let h = DVec2::new(0.5 * len, 0.0);
    desc.segments.push(SegmentDesc {
        name: None,
        a: Some((at - h).to_array()),
        b: Some((at + h).to_array()),
        points: None,
        closed: false,
        reflectance: Color::grey(0.5),
        emission: Color::default(),
        two_sided: true,
    });
    desc.segments.len() - 1
}

/// A new unit-intensity point light at `at`; returns its index.
pub fn add_point_light(desc: &mut SceneDesc, at: DVec2) -> usize {
    desc.lights.push(LightDesc::Point {
        position: at.to_array(),
        intensity: Color::grey(1.0),
    });
    desc.lights.len() - 1
}

/// Delete the selected item.
pub fn delete(desc: &mut SceneDesc, sel: Selection) {
    match sel {
        Selection::Segment(i) if i < desc.segments.len() => {
            desc.segments.remove(i);
        }
        Selection::Light(i) if i < desc.lights.len() => {
            desc.lights.remove(i);
        }
        _ => {}
    }
}

/// The selection a handle belongs to.
pub fn selection_of(h: Handle) -> Option<Selection> {
    match h {
        Handle::Vertex { segment, .. } | Handle::Segment(segment) => Some(Selection::Segment(segment)),
        Handle::Light(i) => Some(Selection::Light(i)),
        Handle::RegionVertex(_) | Handle::Probe => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flatland::scene::DEFAULT_SCENE_JSON;

    fn desc() -> SceneDesc {
        let mut d: SceneDesc = serde_json::from_str(DEFAULT_SCENE_JSON).unwrap();
        d.lights.push(LightDesc::Point {
            position: [0.5, -0.5],
            intensity: Color::grey(1.0),
        });
        d.segments.push(SegmentDesc {
            points: Some(vec![[-0.9, -0.9], [-0.7, -0.9], [-0.7, -0.7]]),
            a: None,
            b: None,
            closed: true,
            ..d.segments[1].clone()
        });
        d.medium.as_mut().unwrap().region = RegionDesc::Rect(crate::flatland::scene_desc::RectDesc {
            min: [-0.8, -0.8],
            max: [0.8, 0.8],
        });
        d
    }

    #[test]
    fn pick_prefers_probe_then_vertices_then_bodies() {
        let d = desc();
        // The occluder runs from (-0.35, 0.25) to (0.35, 0.25).
        assert_eq!(
            pick(&d, None, DVec2::new(0.34, 0.26), 0.02),
            Some(Handle::Vertex { segment: 1, vertex: 1 })
        );
        assert_eq!(pick(&d, None, DVec2::new(0.0, 0.26), 0.02), Some(Handle::Segment(1)));
        assert_eq!(
            pick(&d, Some(DVec2::new(0.0, 0.25)), DVec2::new(0.0, 0.26), 0.02),
            Some(Handle::Probe)
        );
        assert_eq!(pick(&d, None, DVec2::new(0.5, -0.49), 0.02), Some(Handle::Light(0)));
        assert_eq!(
            pick(&d, None, DVec2::new(0.8, 0.79), 0.02),
            Some(Handle::RegionVertex(2))
        );
        // The closed polyline's closing piece (-0.7,-0.7)→(-0.9,-0.9) is pickable.
        assert_eq!(
            pick(&d, None, DVec2::new(-0.8, -0.8), 0.02),
            Some(Handle::RegionVertex(0))
        );
        assert_eq!(
            pick(&d, None, DVec2::new(-0.85, -0.848), 0.005),
            Some(Handle::Segment(2))
        );
        assert_eq!(pick(&d, None, DVec2::new(0.0, -0.3), 0.02), None);
    }

    fn close(a: [f64; 2], b: [f64; 2]) -> bool {
        (v(a) - v(b)).length() < 1e-12
    }

    #[test]
    fn drags_move_what_they_hold() {
        let mut d = desc();
        let (from, to) = (DVec2::new(0.0, 0.0), DVec2::new(0.1, -0.2));
        drag(&mut d, Handle::Vertex { segment: 1, vertex: 0 }, from, to);
        assert!(close(d.segments[1].a.unwrap(), [-0.25, 0.05]));
        assert_eq!(d.segments[1].b, Some([0.35, 0.25]));
        drag(&mut d, Handle::Segment(0), from, to);
        assert!(close(d.segments[0].a.unwrap(), [0.4, 0.55]));
        drag(&mut d, Handle::Segment(2), from, to);
        assert!(close(d.segments[2].points.as_ref().unwrap()[2], [-0.6, -0.9]));
        drag(&mut d, Handle::Vertex { segment: 2, vertex: 1 }, from, to);
        assert!(close(d.segments[2].points.as_ref().unwrap()[1], [-0.5, -1.3]));
        drag(&mut d, Handle::Light(0), from, to);
        let LightDesc::Point { position, .. } = d.lights[0] else {
            panic!()
        };
        assert!(close(position, [0.6, -0.7]));
        drag(&mut d, Handle::RegionVertex(1), from, to);
        let Some(RegionDesc::Rect(r)) = d.medium.as_ref().map(|m| &m.region) else {
            panic!()
        };
        assert!(close(r.min, [-0.8, -1.0]) && close(r.max, [0.9, 0.8]));
    }

    #[test]
    fn add_and_delete() {
        let mut d = desc();
        let i = add_segment(&mut d, DVec2::ZERO, 0.4);
        assert_eq!(
            segment_pieces(&d.segments[i]),
            vec![(DVec2::new(-0.2, 0.0), DVec2::new(0.2, 0.0))]
        );
        let l = add_point_light(&mut d, DVec2::new(0.1, 0.1));
        assert_eq!(d.lights.len(), 2);
        delete(&mut d, Selection::Light(l));
        delete(&mut d, Selection::Segment(i));
        assert_eq!(d, desc());
        assert_eq!(
            selection_of(Handle::Vertex { segment: 3, vertex: 1 }),
            Some(Selection::Segment(3))
        );
    }
}
