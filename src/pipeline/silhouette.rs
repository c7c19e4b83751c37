//! Silhouette vertices for the proxy: where a ray's hit surface stops being visible
//! between it and a neighbouring ray that sees something at another depth, found
//! exactly from the primitive (a segment's end, the crossing of a triangle's edge).
//!
//! Why: the proxy's surface vertices are the rays' hit points, fixed in space, and
//! the gradient of a chain of surface elements comes from its end vertices (the
//! inner ones cancel). At a visibility boundary the chain's last hit lies up to one
//! ray spacing short of the true edge, at whatever distance that ray met the
//! surface. A ray grazing a surface meets it at r ≈ d/Δθ from a point d away, so
//! the end vertex's angle moved as 1/r and the aware gradient grew as 1/d next to
//! surfaces (issue 12 item 4: 3.5× off at d = 1e-4, 1300× at 1e-7). The true edge
//! is a fixed point at its own distance, as the paper's derivation assumes.

use super::dim::Dim;
use super::world::World;
use crate::core::color::Rgb;
use crate::core::space::Space;
use serde::Serialize;

type VecOf<W> = <<W as World>::S as Space>::Vec;

/// Cuts of a probe's simplex edges, sorted by ray pair.
type Cuts<W> = Vec<Cut<VecOf<W>>>;

/// Where a surface ends along an arc: the silhouette point, the primitive it lies
/// on, and a point just beyond it (outwards, in the plane of the arc).
type Edge<W> = (VecOf<W>, u32, VecOf<W>);

/// Neighbouring ends whose depths differ by more than this fraction lie on two
/// sides of a visibility boundary (the proxy calls such elements bridging).
pub const BRIDGE_RATIO: f64 = 0.1;

/// What the search needs of one probe ray: its direction, the primitive it hit (if
/// any), the hit point and the ray's length.
#[derive(Clone, Copy, Debug)]
pub struct RayEnd<V> {
    pub dir: V,
    pub prim: Option<u32>,
    pub point: V,
    pub length: f64,
}

/// Where the surface hit by ray `from` ends on the way to ray `to`'s direction: a
/// point of its silhouette on the simplex edge between them (see [`find_edges`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cut<V> {
    pub from: u32,
    pub to: u32,
    pub point: V,
    /// The unit direction of the boundary edge through `point`, where the world
    /// knows it (3D triangles; see [`World::edge_direction`]).
    pub edge: Option<V>,
    /// A far cut's surface: its radiance towards x where no probe ray measured it
    /// (the emission of a surface seen only past the near silhouette), and its
    /// normal facing x.
    pub radiance: Option<Rgb>,
    pub normal: Option<V>,
}

/// The silhouettes next to a probe's hits: per ray, the point its vertex moves to
/// (2D; stored by the probe in `SurfaceHit::edge`); in 3D, and where a move would
/// fold the triangulation, the cuts of the ray's simplex edges instead (sorted by
/// ray pair); and the rays cast.
pub struct Silhouettes<V> {
    pub moved: Vec<Option<V>>,
    pub cuts: Vec<Cut<V>>,
    /// Per cut, where the silhouette of what lies just beyond it, or of what the
    /// far ray sees (whichever is nearer), crosses the rest of the simplex edge:
    /// the edge of a farther surface partly hidden by the near one (3D; sorted by
    /// ray pair, as `cuts`).
    pub far_cuts: Vec<Cut<V>>,
    pub rays: u64,
}

/// A neighbouring ray (hit primitive `prim_j`, length `len_j`) sees something else
/// than a ray's hit on `prim` at `len`: nothing, or another primitive at a clearly
/// different depth.
pub fn sees_other(prim: u32, len: f64, prim_j: Option<u32>, len_j: f64) -> bool {
    match prim_j {
        None => true,
        Some(pj) => pj != prim && (len_j - len).abs() > BRIDGE_RATIO * len_j.min(len),
    }
}

/// For every ray whose hit primitive ends between it and a neighbour that sees
/// another depth (or nothing): in 2D the primitive's visible silhouette point,
/// where the ray's vertex moves; in 3D (and where a move would fold the
/// triangulation) the silhouette's crossings of the simplex edges towards farther
/// neighbours. With the shadow rays cast (one per candidate, to keep only edges x
/// sees).
pub fn find_edges<W: World>(
    world: &W,
    x: VecOf<W>,
    rays: &[RayEnd<VecOf<W>>],
    simplices: &[<W::S as Dim>::Simplex<u32>],
) -> Silhouettes<VecOf<W>> {
    // Which simplices each ray belongs to.
    let mut star: Vec<Vec<usize>> = vec![Vec::new(); rays.len()];
    for (k, t) in simplices.iter().enumerate() {
        for &i in t.as_ref() {
            star[i as usize].push(k);
        }
    }
    // In 3D every silhouette is a cut instead of a move: a moved vertex puts one
    // point of the edge in place and leaves the triangles to its neighbours short
    // of it, or folds them (below an emitter at d = 1e-2, 4096 directions: gradient
    // 73% off with moves where they did not fold, 0.02% with cuts).
    if W::S::DIM == 3 {
        let all: Vec<usize> = (0..rays.len()).filter(|&i| rays[i].prim.is_some()).collect();
        let (cuts, far_cuts, cost) = cuts_of(world, x, rays, simplices, &star, &all);
        return Silhouettes {
            moved: vec![None; rays.len()],
            cuts,
            far_cuts,
            rays: cost,
        };
    }
    // Per ray, the candidate nearest to it in angle: the silhouette next to the ray.
    let mut best: Vec<Option<(f64, VecOf<W>)>> = vec![None; rays.len()];
    for t in simplices {
        let idx = t.as_ref();
        for &i in idx {
            let ri = &rays[i as usize];
            let Some(prim) = ri.prim else { continue };
            for &j in idx.iter().filter(|&&j| j != i) {
                if !sees_other(prim, ri.length, rays[j as usize].prim, rays[j as usize].length) {
                    continue;
                }
                let Some(c) = world.silhouette(prim, x, ri.dir, rays[j as usize].dir) else {
                    continue;
                };
                let w = c - x;
                let cos = W::S::dot(w, ri.dir) / W::S::length(w);
                let slot = &mut best[i as usize];
                if slot.is_none_or(|(b, _)| cos > b) {
                    *slot = Some((cos, c));
                }
            }
        }
    }
    let mut pos: Vec<VecOf<W>> = rays.iter().map(|r| r.prim.map_or(x + r.dir, |_| r.point)).collect();
    let mut edges = vec![None; rays.len()];
    let turn = |t: &<W::S as Dim>::Simplex<u32>, pos: &[VecOf<W>]| {
        W::S::form_factor(W::S::simplex(|k| pos[t.as_ref()[k] as usize]), x).value
    };
    let mut cost = 0;
    let mut refused = Vec::new();
    for (i, found) in best.into_iter().enumerate() {
        let Some((_, c)) = found else { continue };
        let w = c - x;
        let len = W::S::length(w);
        if !(len > 0.0 && len.is_finite()) {
            continue;
        }
        // The move must not fold the triangulation (in 3D a vertex moved towards one
        // neighbour can cross another's edge): every simplex around the ray keeps
        // its orientation, as the directions give it, and a non-zero measure.
        let old = pos[i];
        let before: Vec<f64> = star[i].iter().map(|&k| turn(&simplices[k], &pos)).collect();
        pos[i] = c;
        let folds = star[i]
            .iter()
            .zip(&before)
            .any(|(&k, &b)| (turn(&simplices[k], &pos) * b).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater));
        if folds {
            pos[i] = old;
            refused.push(i);
            continue;
        }
        cost += 1;
        // Seen from x: nothing in front (the primitive itself and what meets it at
        // the edge end exactly there, so the test stops just short).
        if world.occluded(x, w / len, len * (1.0 - 1e-9), rays[i].prim) {
            pos[i] = old;
        } else {
            edges[i] = Some(c);
        }
    }
    let (cuts, far_cuts, c) = cuts_of(world, x, rays, simplices, &star, &refused);
    Silhouettes {
        moved: edges,
        cuts,
        far_cuts,
        rays: cost + c,
    }
}

/// The cuts of the simplex edges from each ray in `from` (whose vertex does not
/// move to its silhouette) towards the neighbours that see nothing or something
/// farther: where its surface's silhouette crosses each such edge, if x sees it.
///
/// Why: a grazing surface next to x (a point 1e-3 below an emitter) is met by the
/// probe's lowest rays only ≈ d/Δθ from x's foot, far short of its true edge, and
/// the vertex cannot always move to the edge without folding its neighbours'
/// triangles. The band left out is seen at grazing elevation: its solid angle
/// shrinks as d, its gradient does not (A/r³), so the gradient's error grew as 1/d.
/// Cutting the edges instead covers the surface up to its silhouette without moving
/// any vertex (the proxy splits the simplices at the cuts).
fn cuts_of<W: World>(
    world: &W,
    x: VecOf<W>,
    rays: &[RayEnd<VecOf<W>>],
    simplices: &[<W::S as Dim>::Simplex<u32>],
    star: &[Vec<usize>],
    from: &[usize],
) -> (Cuts<W>, Cuts<W>, u64) {
    let (mut cuts, mut far_cuts) = (Vec::new(), Vec::new());
    let mut cost = 0;
    for &i in from {
        let ri = &rays[i];
        let Some(prim) = ri.prim else { continue };
        let mut towards: Vec<u32> = star[i]
            .iter()
            .flat_map(|&k| simplices[k].as_ref().iter().copied())
            .filter(|&j| {
                let rj = &rays[j as usize];
                j as usize != i
                    && sees_other(prim, ri.length, rj.prim, rj.length)
                    && (rj.prim.is_none() || rj.length > ri.length)
            })
            .collect();
        towards.sort_unstable();
        towards.dedup();
        for j in towards {
            let (found, rays_cast) = silhouette_along(world, x, prim, ri, rays[j as usize].dir);
            cost += rays_cast;
            let Some((c, last, beyond)) = found else { continue };
            let w = c - x;
            let len = W::S::length(w);
            if !(len > 0.0 && len.is_finite()) {
                continue;
            }
            cost += 1;
            if !world.occluded(x, w / len, len * (1.0 - 1e-9), Some(last)) {
                cuts.push(Cut {
                    from: i as u32,
                    to: j,
                    point: c,
                    edge: world.edge_direction(last, c),
                    radiance: None,
                    normal: None,
                });
                let (far, rays_cast) = far_cut(world, x, beyond, last, &rays[j as usize]);
                cost += rays_cast;
                if let Some(f) = far {
                    far_cuts.push(Cut {
                        from: i as u32,
                        to: j,
                        ..f
                    });
                }
            }
        }
    }
    (cuts, far_cuts, cost)
}

/// Past a cut (the point `beyond` just outside the near surface's silhouette, on
/// primitive `near`), what x sees, against what the far ray `rj` sees: where they
/// differ, the edge of the nearer of the two crosses the arc between their
/// directions (a farther surface partly hidden by the near one: its visible part
/// has a corner on the near silhouette, see `proxy_cut::Corner`). That crossing,
/// if x sees it, with the edge's direction; the rays cast.
fn far_cut<W: World>(
    world: &W,
    x: VecOf<W>,
    beyond: VecOf<W>,
    near: u32,
    rj: &RayEnd<VecOf<W>>,
) -> (Option<Cut<VecOf<W>>>, u64) {
    let w = beyond - x;
    let len = W::S::length(w);
    // (2D silhouettes are points: no corners.)
    if W::S::DIM != 3 || !(len > 0.0 && len.is_finite()) {
        return (None, 0);
    }
    let d = w / len;
    let behind = world.closest_hit(x, d, f64::INFINITY, Some(near));
    let mut cost = 1;
    let (b_prim, b_len) = (
        behind.as_ref().map(|h| h.prim),
        behind.as_ref().map_or(f64::INFINITY, |h| h.t),
    );
    let differs = match b_prim {
        Some(p) => sees_other(p, b_len, rj.prim, rj.length),
        None => rj.prim.is_some(),
    };
    if !differs {
        return (None, cost);
    }
    // The nearer surface's edge, towards the other's direction.
    let (found, radiance) = match (&behind, rj.prim) {
        (Some(h), pj) if pj.is_none() || h.t < rj.length => {
            let s = world.surface(h, d);
            let end = RayEnd {
                dir: d,
                prim: Some(h.prim),
                point: s.point,
                length: h.t,
            };
            let (found, c) = silhouette_along(world, x, h.prim, &end, rj.dir);
            cost += c;
            let emitted = if s.active { s.emission } else { Rgb::ZERO };
            (found.map(|f| (f, Some(s.normal))), Some(emitted))
        }
        (_, Some(pj)) => {
            let (found, c) = silhouette_along(world, x, pj, rj, d);
            cost += c;
            // Its radiance and normal are the far ray's own.
            (found.map(|f| (f, None)), None)
        }
        _ => (None, None),
    };
    let Some(((c, last, _), normal)) = found else {
        return (None, cost);
    };
    let wc = c - x;
    let lc = W::S::length(wc);
    if !(lc > 0.0 && lc.is_finite()) {
        return (None, cost);
    }
    cost += 1;
    if world.occluded(x, wc / lc, lc * (1.0 - 1e-9), Some(last)) {
        return (None, cost);
    }
    let cut = Cut {
        from: 0,
        to: 0,
        point: c,
        edge: world.edge_direction(last, c),
        radiance,
        normal,
    };
    (Some(cut), cost)
}

/// Where the surface that ray `ri` hit (on `prim`) ends, seen along the arc from its
/// direction towards `d_out`: the silhouette of its primitive, followed across
/// coplanar primitives of the same material (a quad's two triangles, a mesh's
/// flat faces), which are one surface to the light: the point, the primitive it
/// lies on and a point just beyond it (none where the surface reaches `d_out`),
/// and the rays cast. Without following, a cut at a quad's diagonal left the rest
/// of the quad to the bridging elements behind it.
fn silhouette_along<W: World>(
    world: &W,
    x: VecOf<W>,
    prim: u32,
    ri: &RayEnd<VecOf<W>>,
    d_out: VecOf<W>,
) -> (Option<Edge<W>>, u64) {
    use super::world::Hit;
    let props = |p: u32| {
        let s = world.surface(
            &Hit {
                t: 0.0,
                prim: p,
                u: 1.0 / 3.0,
                v: 1.0 / 3.0,
            },
            ri.dir,
        );
        (s.normal, s.emission, s.reflectance)
    };
    let (n0, e0, r0) = props(prim);
    let (mut cur, mut prev) = (prim, ri.point);
    let Some(mut c) = world.silhouette(prim, x, ri.dir, d_out) else {
        return (None, 0);
    };
    let mut cost = 0;
    for _ in 0..16 {
        // Just beyond c on the line the arc's directions meet the plane in.
        let beyond = c + (c - prev) * 1e-6;
        let w = beyond - x;
        let len = W::S::length(w);
        if !(len > 0.0 && len.is_finite()) {
            break;
        }
        cost += 1;
        let Some(h) = world.closest_hit(x, w / len, len * 1.001, None) else {
            break;
        };
        if h.prim == cur || (h.t - len).abs() > 1e-4 * len {
            break;
        }
        let s = world.surface(&h, w / len);
        if W::S::dot(s.normal, n0) < 1.0 - 1e-9 || s.emission != e0 || s.reflectance != r0 {
            break;
        }
        // The surface reaches d_out's direction: no silhouette between them.
        let Some(next) = world.silhouette(h.prim, x, w / len, d_out) else {
            return (None, cost);
        };
        (prev, c, cur) = (c, next, h.prim);
    }
    (Some((c, cur, c + (c - prev) * 1e-6)), cost)
}

/// The cut of the simplex edge from ray `from` towards ray `to`, if any (`cuts`
/// sorted by ray pair, as [`find_edges`] makes them).
pub fn cut_between<V: Copy>(cuts: &[Cut<V>], from: u32, to: u32) -> Option<V> {
    cut_of(cuts, from, to).map(|c| c.point)
}

/// The cut of the simplex edge from ray `from` towards ray `to`, if any.
pub fn cut_of<V: Copy>(cuts: &[Cut<V>], from: u32, to: u32) -> Option<&Cut<V>> {
    cuts.binary_search_by(|c| (c.from, c.to).cmp(&(from, to)))
        .ok()
        .map(|k| &cuts[k])
}

/// Distance from x to the nearest silhouette point among `ends` (hit point, unit
/// normal facing x, silhouette point) where the surface truly ends, +∞ when none
/// does, and the rays cast. A silhouette found between two primitives of one
/// surface (a mesh's inner edge, seen grazing: neighbouring hits then differ in
/// depth like a boundary's) is no boundary: a ray to just beyond it, in the hit
/// primitive's plane, meets the surface there and the candidate is passed over.
pub fn nearest_boundary<W: World>(world: &W, x: VecOf<W>, ends: &[(VecOf<W>, VecOf<W>, VecOf<W>)]) -> (f64, u64) {
    let mut candidates: Vec<(f64, usize)> = ends
        .iter()
        .enumerate()
        .map(|(k, &(_, _, e))| (W::S::length(e - x), k))
        .filter(|(d, _)| d.is_finite() && *d > 0.0)
        .collect();
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut rays = 0;
    for (d, k) in candidates {
        let (point, normal, e) = ends[k];
        // Outwards across the edge, in the primitive's plane.
        let along = e - point;
        let out = along - normal * W::S::dot(along, normal);
        let len = W::S::length(out);
        if len.is_nan() || len <= 1e-12 * d {
            return (d, rays);
        }
        let beyond = e + out * (1e-3 * d / len);
        let to = beyond - x;
        let t = W::S::length(to);
        rays += 1;
        let continues = world
            .closest_hit(x, to / t, 1.02 * t, None)
            .is_some_and(|h| h.t > 0.98 * t);
        if !continues {
            return (d, rays);
        }
    }
    (f64::INFINITY, rays)
}
