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
use super::silhouette::{BRIDGE_RATIO, Cut, cut_between, cut_of, sees_other};
use crate::core::color::Rgb;
use crate::core::space::Space;
use serde::Serialize;

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
    pub corner: Option<Corner<S::Vec>>,
    /// The vertex whose radiance and place (for phase and transmittance) the piece
    /// carries, where the farther-vertex rule does not apply (see [`Polygon`]).
    pub source: Option<Vertex<S>>,
}

/// A vertex that slides as x moves: where a near surface's silhouette (the segment
/// `a`–`b` of it) hides the edge of a farther surface (the line through `p` along
/// `d`). The visible part of the far surface has a corner there, on the far edge,
/// which moves along it with x; a vertex fixed in space in its place is right to
/// first order, but the region it leaves out or adds (O(Δθ²)) changes at a rate
/// that does not shrink with Δθ, and the Hessian erred by O(1) wherever a shadow's
/// edge crossed an emitter's (3D penumbrae: 20% median, unchanged from 4096 to
/// 16384 directions; 0.2–0.7% where the crossings lay far from x).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Corner<V> {
    pub a: V,
    pub b: V,
    pub p: V,
    pub d: V,
}

/// The corner's vertex seen from `x`: the point of `a`–`b` whose direction from x
/// meets the far edge's line, `None` when it leaves the segment or the two edges
/// are seen nearly along one another (the corner is then ill-defined: it moves
/// without bound as x moves).
pub fn corner_at<S: Space>(c: &Corner<S::Vec>, x: S::Vec) -> Option<S::Vec> {
    corner_param::<S>(c, x)
        .filter(|s| (0.0..=1.0).contains(s))
        .map(|s| c.a + (c.b - c.a) * s)
}

/// [`corner_at`] on the whole line through `a` and `b`: where differences at
/// nearby x evaluate it (a corner near the segment's end must not jump back to a
/// fixed vertex within the step).
pub fn corner_on_line<S: Space>(c: &Corner<S::Vec>, x: S::Vec) -> Option<S::Vec> {
    corner_param::<S>(c, x).map(|s| c.a + (c.b - c.a) * s)
}

/// The corner's parameter along `a`–`b` (0 at `a`, 1 at `b`).
fn corner_param<S: Space>(c: &Corner<S::Vec>, x: S::Vec) -> Option<f64> {
    // The part of a vector across the plane through x and the far edge's line
    // (Gram–Schmidt on p − x and d: no cross product in a generic space).
    let u = c.p - x;
    let e1 = u / S::length(u);
    let d2 = c.d - e1 * S::dot(c.d, e1);
    let l2 = S::length(d2);
    if !(l2 > 1e-6 && l2.is_finite()) {
        return None;
    }
    let e2 = d2 / l2;
    let across = |w: S::Vec| w - e1 * S::dot(w, e1) - e2 * S::dot(w, e2);
    let (r0, r1) = (across(c.a - x), across(c.b - c.a));
    let den = S::dot(r1, r1);
    // The segment crosses the plane at an angle of at least ~0.6° (sin² ≥ 1e-4).
    let s = -S::dot(r0, r1) / den;
    (den > 1e-4 * S::length_squared(c.b - c.a) && s.is_finite()).then_some(s)
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
    let ray = |a: usize| &lf.rays[idx[a] as usize];
    let has_cut = |a: usize| (0..3).any(|b| b != a && cut(a, b).is_some());
    // The nearest cut surface: a farther one's silhouette is split second.
    let h = (0..3)
        .filter(|&a| has_cut(a))
        .min_by(|&a, &b| ray(a).length.total_cmp(&ray(b).length))?;
    let hit = ray(h).hit.as_ref()?;
    // A cut vertex lies behind h's silhouette (a farther surface with an edge of
    // its own) when its plane, seen past h's cut towards it, is clearly farther
    // than the cut: not so across a fold of one surface (a box's edge).
    let behind = |a: usize| {
        let (Some(c), Some(ha)) = (cut(h, a), ray(a).hit.as_ref()) else {
            return false;
        };
        let w = c - lf.x;
        let den = S::dot(ha.normal, w);
        let t = S::dot(ha.normal, ha.point - lf.x) / den;
        den != 0.0 && t > 1.0 + BRIDGE_RATIO
    };
    // The vertices on the hit surface's side: the cut ones not behind it, and hits
    // at its depth or in its plane (a grazing plane's other primitives).
    let near: [bool; 3] = std::array::from_fn(|a| {
        a == h
            || (has_cut(a) && !behind(a))
            || ray(a).hit.as_ref().is_some_and(|ha| {
                let coplanar = S::dot(ha.normal, hit.normal) > 1.0 - 1e-12
                    && S::dot(hit.normal, ha.point - hit.point).abs() <= 1e-9 * ray(a).length.max(ray(h).length);
                coplanar || !sees_other(hit.prim, ray(h).length, Some(ha.prim), ray(a).length)
            })
    });
    // The polygons on either side of the silhouette, walking the triangle's edges;
    // outside, each vertex with the triangle's vertex it is (cut points: none) and
    // the normal of the far surface it lies on.
    let (mut inside, mut outside): (Vec<Vertex<S>>, Vec<Tagged<S>>) = (vec![], vec![]);
    for a in 0..3 {
        let b = (a + 1) % 3;
        let va = ends[idx[a] as usize];
        if near[a] {
            inside.push(va);
        } else {
            outside.push((va, Src::Ray(a), ray(a).hit.as_ref().map(|h| h.normal)));
        }
        if near[a] == near[b] {
            continue;
        }
        let (n, f) = if near[a] { (a, b) } else { (b, a) };
        let point = cut(n, f)?;
        let v: Vertex<S> = (point, S::length(point - lf.x), ends[idx[n] as usize].2, point);
        inside.push(v);
        outside.push((v, Src::Cut(n, f), None));
    }
    let x = lf.x;
    let polygons = edge_split::<S>(lf, t, ends, &outside).unwrap_or_else(|| vec![(outside, None, None)]);
    let escaped = |v: &Vertex<S>| (0..3).any(|a| ray(a).hit.is_none() && v.0 == ends[idx[a] as usize].0);
    // Escaped rays' ends behind everything else of the piece (as `proxy` does).
    let far_hit = polygons
        .iter()
        .flat_map(|p| &p.0)
        .filter(|v| !escaped(&v.0))
        .map(|v| v.0.1)
        .fold(0.0, f64::max);
    let measure = |tri: &[Vertex<S>; 3]| S::direction_measure(S::simplex(|k| (tri[k].0 - x) / S::length(tri[k].0 - x)));
    // Pieces below a billionth of the triangle are round-off slivers (a 1.7e-18 sr
    // corner piece was seen): their form factor is 0 and they only add noise.
    let sliver = 1e-9 * S::direction_measure(S::simplex(|k| ray(k).dir));
    let mut pieces = Vec::new();
    for k in 1..inside.len().saturating_sub(1) {
        let v = [inside[0], inside[k], inside[k + 1]];
        let measure = measure(&v);
        if measure > sliver {
            pieces.push(CutPiece {
                v,
                measure,
                bridging: false,
                far_plane: None,
                corner: None,
                source: None,
            });
        }
    }
    for (polygon, corner, side) in &polygons {
        let pushed: Vec<Tagged<S>> = polygon
            .iter()
            .map(|&(mut v, a, n)| {
                if escaped(&v) && far_hit > 0.0 {
                    let dir = (v.0 - x) / S::length(v.0 - x);
                    v.1 = v.1.max(2.0 * far_hit);
                    v.0 = x + dir * v.1;
                }
                (v, a, n)
            })
            .collect();
        let source = side.map(|s2| {
            s2.unwrap_or_else(|| {
                *pushed
                    .iter()
                    .filter(|q| q.1 != Src::Split)
                    .max_by(|a, b| a.0.1.total_cmp(&b.0.1))
                    .expect("a side has a ray end or a cut")
            })
        });
        for k in 1..pushed.len().saturating_sub(1) {
            let tri = [pushed[0], pushed[k], pushed[k + 1]];
            let v = tri.map(|q| q.0);
            let (dmin, dmax) = v
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), q| (lo.min(q.1), hi.max(q.1)));
            let far = (0..3)
                .max_by(|&i, &j| v[i].1.total_cmp(&v[j].1))
                .expect("three vertices");
            let measure = measure(&v);
            if measure > sliver {
                // The sliding vertex is the corner's only where the piece has it.
                let slides = corner.filter(|(_, q)| v.iter().any(|p| p.0 == *q));
                // The surface behind the piece: its side's source, else its farthest vertex.
                let (far_point, far_normal) = source.map_or((v[far].0, tri[far].2), |s| (s.0.0, s.2));
                pieces.push(CutPiece {
                    v,
                    measure,
                    bridging: dmax - dmin > BRIDGE_RATIO * dmin,
                    far_plane: far_normal.map(|n| (far_point, n)),
                    corner: slides.map(|(c, _)| c),
                    source: source.map(|s| s.0),
                });
            }
        }
    }
    Some(pieces)
}

/// Where an outside vertex comes from: a ray of the triangle (its index in it), the
/// cut of the simplex edge from a near vertex to a far one, or a corner split.
#[derive(Clone, Copy, PartialEq)]
enum Src {
    Ray(usize),
    Cut(usize, usize),
    Split,
}

/// An outside vertex, where it comes from and the normal of the far surface it lies
/// on (if known).
type Tagged<S> = (Vertex<S>, Src, Option<<S as Space>::Vec>);

/// A polygon of the outside, with the corner that slides along its edge (and the
/// corner's vertex), if it has one, and for the two sides of a farther surface's
/// edge, where their pieces' radiance comes from: that surface's crossing on its
/// side (`Some(Some(v))`), the polygon's farthest ray end on the other
/// (`Some(None)`). The farther-vertex rule per piece cannot tell: the crossing lies
/// on both sides, and is the farthest vertex of pieces that see nothing of its
/// surface (beside a corner, 0% of such a piece's directions saw the emitter it
/// carried).
type Polygon<S> = (
    Vec<Tagged<S>>,
    Option<(Corner<<S as Space>::Vec>, <S as Space>::Vec)>,
    Option<Option<Tagged<S>>>,
);

/// The outside of a split triangle (`outside`: the near surface's two cuts with the
/// far vertices between them) split where the edge of a farther surface crosses
/// it — a cut on a simplex edge between far vertices, or a far cut beyond a near
/// cut (`LightField::far_cuts`). Crossed once, the edge ends on the near
/// silhouette, where the near surface hides it: the outside splits along it from
/// the crossing to that corner, which slides (see [`Corner`]). Crossed twice, it
/// passes through: the outside splits along the chord between the crossings, both
/// on the edge. `None` where nothing crosses (or more than twice).
fn edge_split<S: Dim>(
    lf: &LightField<S>,
    t: &S::Simplex<u32>,
    ends: &[Vertex<S>],
    outside: &[Tagged<S>],
) -> Option<Vec<Polygon<S>>> {
    let idx = t.as_ref();
    // From the near silhouette round to it again: the walk rotated to start at the
    // second of the two adjacent cuts.
    let m = outside.len();
    let is_cut = |k: usize| matches!(outside[k % m].1, Src::Cut(..));
    let start = (0..m).find(|&k| is_cut(k) && is_cut(k + m - 1))?;
    let outside: Vec<Tagged<S>> = (0..m).map(|k| outside[(start + k) % m]).collect();
    // The far edge's crossing of each walked side, with the ray whose surface it is
    // when a ray saw that surface.
    let far = |n: usize, f: usize| cut_of(&lf.far_cuts, idx[n], idx[f]);
    // Each with the outside vertex on its surface's side: the far ray that saw the
    // surface, or the near cut it lies just behind.
    let crossing = |p: Src, r: Src| match (p, r) {
        (Src::Cut(n, f), Src::Ray(g)) | (Src::Ray(g), Src::Cut(n, f)) if f == g => far(n, f).map(|c| {
            let side = if c.radiance.is_some() {
                Src::Cut(n, f)
            } else {
                Src::Ray(f)
            };
            (c, f, side)
        }),
        (Src::Ray(a), Src::Ray(b)) => cut_of(&lf.cuts, idx[a], idx[b])
            .map(|c| (c, a, Src::Ray(a)))
            .or_else(|| cut_of(&lf.cuts, idx[b], idx[a]).map(|c| (c, b, Src::Ray(b)))),
        _ => None,
    };
    let tagged = |(c, f, _): (&Cut<S::Vec>, usize, Src)| -> Tagged<S> {
        // A far cut of a surface no ray saw carries its own radiance and normal.
        let radiance = c.radiance.unwrap_or(ends[idx[f] as usize].2);
        let normal = c.normal.or(lf.rays[idx[f] as usize].hit.as_ref().map(|h| h.normal));
        (
            (c.point, S::length(c.point - lf.x), radiance, c.point),
            Src::Split,
            normal,
        )
    };
    let found: Vec<_> = (0..m - 1)
        .filter_map(|k| crossing(outside[k].1, outside[k + 1].1).map(|c| (k, c)))
        .collect();
    match found[..] {
        [(k, crossed)] => {
            let (first, last) = (&outside[0], &outside[m - 1]);
            let corner = Corner {
                a: last.0.0,
                b: first.0.0,
                p: crossed.0.point,
                d: crossed.0.edge?,
            };
            let q = corner_at::<S>(&corner, lf.x)?;
            let cv = tagged(crossed);
            // The corner lies on the near silhouette: the near surface's radiance.
            let qv: Tagged<S> = ((q, S::length(q - lf.x), first.0.2, q), Src::Split, None);
            let mut a: Vec<Tagged<S>> = outside[..=k].to_vec();
            a.extend([cv, qv]);
            let mut b = vec![qv, cv];
            b.extend_from_slice(&outside[k + 1..]);
            let on_a = a.iter().any(|v| v.1 == crossed.2);
            let (sa, sb) = if on_a { (Some(cv), None) } else { (None, Some(cv)) };
            Some(vec![(a, Some((corner, q)), Some(sa)), (b, Some((corner, q)), Some(sb))])
        }
        [(k1, c1), (k2, c2)] => {
            let (v1, v2) = (tagged(c1), tagged(c2));
            let mut a = vec![v1];
            a.extend_from_slice(&outside[k1 + 1..=k2]);
            a.push(v2);
            let mut b: Vec<Tagged<S>> = outside[..=k1].to_vec();
            b.extend([v1, v2]);
            b.extend_from_slice(&outside[k2 + 1..]);
            // Both crossings must put the surface on one side.
            let on_a = |side: Src| a.iter().any(|v| v.1 == side);
            if on_a(c1.2) != on_a(c2.2) {
                return None;
            }
            let (sa, sb) = if on_a(c1.2) { (Some(v1), None) } else { (None, Some(v1)) };
            Some(vec![(a, None, Some(sa)), (b, None, Some(sb))])
        }
        _ => None,
    }
}
