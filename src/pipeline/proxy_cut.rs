//! Surface simplices split at the silhouette cuts of their edges (3D).
//!
//! In 3D the probe records where a hit surface's silhouette crosses the simplex
//! edges from the hit's ray towards neighbours that see nothing or something
//! farther ([`super::silhouette::find_edges`]) instead of moving the hit's vertex
//! there (a moved vertex folded the direction triangulation, or put one point on
//! the edge and left its neighbours' triangles short of it). A simplex with such a
//! cut is split there: the near part (the hit surface up to its edge) becomes
//! pieces of one continuous surface, the rest bridging pieces from the edge to what
//! lies behind, as an element with a vertex at the silhouette would be. The cuts
//! lie on shared edges, so neighbouring simplices split alike and the pieces tile
//! the directions.

use super::dim::Dim;
use super::probe::LightField;
use super::silhouette::{BRIDGE_RATIO, cut_between, sees_other};
use crate::core::color::Rgb;
use crate::core::space::Space;

/// A vertex of an element: position, distance from x (for the radiance rules),
/// radiance, and where its transmittance and phase are evaluated.
pub(super) type Vertex<S> = (<S as Space>::Vec, f64, Rgb, <S as Space>::Vec);

/// A piece of a split simplex: its vertices, the measure of its directions,
/// whether it bridges the silhouette and what lies behind, and then the far
/// surface's tangent plane (its farthest vertex and that hit's normal, if a hit).
pub(super) struct CutPiece<S: Dim> {
    pub v: [Vertex<S>; 3],
    pub measure: f64,
    pub bridging: bool,
    pub far_plane: Option<(S::Vec, S::Vec)>,
}

/// The pieces of surface simplex `t` split at its edges' cuts; `None` when no edge
/// of it is cut or its split is incomplete. `ends` are the rays' end vertices
/// before escaped rays are pushed back.
pub(super) fn split_at_cuts<S: Dim>(
    lf: &LightField<S>,
    t: &S::Simplex<u32>,
    ends: &[Vertex<S>],
) -> Option<Vec<CutPiece<S>>> {
    let idx = t.as_ref();
    if lf.cuts.is_empty() || idx.len() != 3 {
        return None;
    }
    let cut = |a: usize, b: usize| cut_between(&lf.cuts, idx[a], idx[b]);
    let h = (0..3).find(|&a| (0..3).any(|b| b != a && cut(a, b).is_some()))?;
    let ray = |a: usize| &lf.rays[idx[a] as usize];
    let hit = ray(h).hit.as_ref()?;
    // The vertices on the hit surface's side: the cut ones, and hits at its depth
    // or in its plane (a grazing plane's other primitives).
    let near: [bool; 3] = std::array::from_fn(|a| {
        a == h
            || (0..3).any(|b| b != a && cut(a, b).is_some())
            || ray(a).hit.as_ref().is_some_and(|ha| {
                let coplanar = S::dot(ha.normal, hit.normal) > 1.0 - 1e-12
                    && S::dot(hit.normal, ha.point - hit.point).abs() <= 1e-9 * ray(a).length.max(ray(h).length);
                coplanar || !sees_other(hit.prim, ray(h).length, Some(ha.prim), ray(a).length)
            })
    });
    // The polygons on either side of the silhouette, walking the triangle's edges.
    let (mut inside, mut outside): (Vec<Vertex<S>>, Vec<Vertex<S>>) = (vec![], vec![]);
    for a in 0..3 {
        let b = (a + 1) % 3;
        let va = ends[idx[a] as usize];
        if near[a] {
            inside.push(va);
        } else {
            outside.push(va);
        }
        if near[a] == near[b] {
            continue;
        }
        let (n, f) = if near[a] { (a, b) } else { (b, a) };
        let point = cut(n, f)?;
        let v: Vertex<S> = (point, S::length(point - lf.x), ends[idx[n] as usize].2, point);
        inside.push(v);
        outside.push(v);
    }
    let x = lf.x;
    let escaped = |v: &Vertex<S>| (0..3).any(|a| ray(a).hit.is_none() && v.0 == ends[idx[a] as usize].0);
    // Escaped rays' ends behind everything else of the piece (as `proxy` does).
    let far_hit = outside.iter().filter(|v| !escaped(v)).map(|v| v.1).fold(0.0, f64::max);
    let pushed: Vec<(Vertex<S>, bool)> = outside
        .iter()
        .map(|v| {
            let mut v = *v;
            let esc = escaped(&v);
            if esc && far_hit > 0.0 {
                let dir = (v.0 - x) / S::length(v.0 - x);
                v.1 = v.1.max(2.0 * far_hit);
                v.0 = x + dir * v.1;
            }
            (v, esc)
        })
        .collect();
    let far_normal = |v: &Vertex<S>| {
        (0..3)
            .find(|&a| !near[a] && ends[idx[a] as usize].0 == v.0)
            .and_then(|a| ray(a).hit.as_ref().map(|h| h.normal))
    };
    let measure = |tri: &[Vertex<S>; 3]| S::direction_measure(S::simplex(|k| (tri[k].0 - x) / S::length(tri[k].0 - x)));
    let mut pieces = Vec::new();
    for k in 1..inside.len().saturating_sub(1) {
        let v = [inside[0], inside[k], inside[k + 1]];
        let measure = measure(&v);
        if measure > 0.0 {
            pieces.push(CutPiece {
                v,
                measure,
                bridging: false,
                far_plane: None,
            });
        }
    }
    for k in 1..pushed.len().saturating_sub(1) {
        let v = [pushed[0].0, pushed[k].0, pushed[k + 1].0];
        let (dmin, dmax) = v
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), q| (lo.min(q.1), hi.max(q.1)));
        let far = (0..3)
            .max_by(|&i, &j| v[i].1.total_cmp(&v[j].1))
            .expect("three vertices");
        let measure = measure(&v);
        if measure > 0.0 {
            pieces.push(CutPiece {
                v,
                measure,
                bridging: dmax - dmin > BRIDGE_RATIO * dmin,
                far_plane: far_normal(&outside[[0, k, k + 1][far]]).map(|n| (v[far].0, n)),
            });
        }
    }
    Some(pieces)
}
