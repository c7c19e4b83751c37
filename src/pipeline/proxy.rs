//! Light field → occlusion-free proxy elements fixed in world space (theory.md §5),
//! in any dimension.
//!
//! - Surface elements: each simplex of neighbouring directions (a pair of rays in
//!   2D, a triangle of the sphere's triangulation in 3D) with its vertices moved to
//!   the rays' end points (hits, or the hit surface's exact silhouette where a
//!   neighbour sees something else, see [`super::silhouette`]; escaped rays behind
//!   the simplex's hits with the radiance of [`ProbeRay::end`]). Where the vertices lie at very different
//!   depths the element bridges an occluder's edge and the background: its form
//!   factor (angle, solid angle) changes fast as x moves, which is how occlusion
//!   changes enter the derivatives. Vertices are ordered so that it is positive
//!   from x.
//! - Medium elements: at each shell i, the simplex of the i-th samples of its rays,
//!   with thickness Δt. Where some ray stopped before shell i (it hit an occluder),
//!   the element bridges that ray's end point and the others' samples. An element
//!   names its rays and shell; its samples stay in the light field
//!   ([`LightField::medium_sample`]), where the derivatives evaluate each once.
//!
//! A bridging surface element carries the radiance of its vertex **farther from x**
//! (Schwarzhaupt et al. 2012: what gets revealed or hidden as x moves);
//! [`RadianceRule::Average`] is the alternative to measure against. A piece of one
//! continuous surface carries its vertices' mean, anchored at their centroid. Medium elements
//! within a shell average their samples (the farther rule would shift every shell
//! outwards by the rays' jitter: a measured 5% loss through the transmittance). A
//! bridging medium element is anchored at its samples' centroid and carries their
//! sum over the simplex's vertex count (the ray ends count as zero), so that every
//! sample keeps the weight it has in the plain estimate. (Carrying the samples'
//! mean instead overweights them: +17% of the multiple-scattering value on
//! fog_box.json with 16 steps.)
//! What its edges reveal or hide as x moves, though, is the light next to the
//! occluder's edge, not that weight: its gradient carries the mean of the nearby
//! samples of its shell ([`Element::revealed`]), as a bridging surface element
//! carries its farther vertex (its Hessian keeps the weight, see
//! [`super::derivatives::element_contribution`]).
//! Transmittance and phase are evaluated towards the element's anchor.

use super::dim::Dim;
use super::probe::LightField;
use super::silhouette::BRIDGE_RATIO;
use crate::core::color::Rgb;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum RadianceRule {
    /// The farther vertex's radiance (Schwarzhaupt et al. 2012).
    #[default]
    Farther,
    /// The mean of the vertices' radiance.
    Average,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementKind {
    /// Contributes to single scattering (light from surfaces).
    Surface,
    /// Contributes to multiple scattering (light from the medium).
    Medium,
}

/// A proxy element: the simplex `v` (oriented so that its form factor from x is
/// positive), the anchor towards which transmittance and phase are evaluated, and
/// the radiance it carries (for medium elements already multiplied by the shell
/// thickness Δt).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Element<S: Dim> {
    pub v: S::Simplex<S::Vec>,
    pub anchor: S::Vec,
    pub radiance: Rgb,
    pub kind: ElementKind,
    /// The vertices lie at clearly different depths (an occlusion boundary).
    pub bridging: bool,
    /// Angle (solid angle) of the element's directions, 2π/N (4π/2N) on average.
    pub dir_measure: f64,
    /// For a bridging surface element under the farther rule: the far surface's
    /// tangent plane (a point on it, its normal), onto which the near vertices slide
    /// as x moves ([`super::slide`]).
    pub far_plane: Option<(S::Vec, S::Vec)>,
    /// A vertex that slides along a near silhouette as x moves, where it hides a
    /// farther surface's edge (3D; see [`super::proxy_cut::Corner`]).
    pub corner: Option<Corner<S::Vec>>,
    /// The rays (indices into [`LightField::rays`]) whose ends or samples the
    /// vertices are.
    pub rays: S::Simplex<u32>,
    /// For a bridging shell piece, the light its edges reveal or hide as x moves
    /// ([`revealed_light`]), which its gradient carries; `radiance` is its weight
    /// in the value (and the Hessian).
    pub revealed: Option<Rgb>,
    /// Medium elements: the shell whose samples ([`LightField::medium_sample`]) the
    /// vertices are (a ray that ended before it gives its end point instead).
    pub shell: Option<u32>,
}

impl<S: Dim> Element<S> {
    /// Longest edge.
    pub fn size(&self) -> f64 {
        let v = self.v.as_ref();
        let mut size = 0.0f64;
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                size = size.max(S::length(v[j] - v[i]));
            }
        }
        size
    }
}

use super::proxy_cut::{Corner, Vertex, split_at_cuts};

/// Where an element's vertices come from: its rays, and the shell of a medium
/// element.
type Source<S> = (<S as Dim>::Simplex<u32>, Option<u32>);

fn make<S: Dim>(
    x: S::Vec,
    v: S::Simplex<Vertex<S>>,
    rule: RadianceRule,
    (kind, bridging): (ElementKind, bool),
    dir_measure: f64,
    (rays, shell): Source<S>,
) -> Element<S> {
    let v = v.as_ref();
    let (anchor, radiance) = match rule {
        RadianceRule::Farther => {
            let far = (0..v.len())
                .max_by(|&i, &j| v[i].1.total_cmp(&v[j].1))
                .expect("a simplex has vertices");
            (v[far].3, v[far].2)
        }
        RadianceRule::Average => centroid::<S>(v.iter().map(|p| (p.3, p.2))),
    };
    Element {
        v: S::orient(x, S::simplex(|k| v[k].0)),
        anchor,
        radiance,
        revealed: None,
        kind,
        bridging,
        dir_measure,
        far_plane: None,
        corner: None,
        rays,
        shell,
    }
}

/// Mean position and mean radiance of vertices.
fn centroid<S: Dim>(v: impl Iterator<Item = (S::Vec, Rgb)>) -> (S::Vec, Rgb) {
    let (mut c, mut l, mut n) = (S::zero(), Rgb::ZERO, 0.0);
    for (p, r) in v {
        c += p;
        l += r;
        n += 1.0;
    }
    (c / n, l / n)
}

/// The proxy as the derivatives sum it. The shell pieces that bridge no occluder
/// (most of a proxy: 94k of 105k elements at a lamp_fog point, 4,096 rays × 24
/// steps) are summed per medium sample ([`SampleShares`]), so they are folded into
/// the samples' shares as they are made instead of being stored (≈ 200 bytes each
/// in 3D, 20 MB a record). Making them, not storing them, was the build's cost:
/// the build went from 6.9 to 6.1 ms there.
#[derive(Clone, Debug)]
pub struct Proxy<S: Dim> {
    /// The elements summed one by one: surfaces and bridging shell pieces, in the
    /// build order of [`elements`].
    pub elements: Vec<Element<S>>,
    /// Each of `elements`' index in the build order of [`elements`] (see
    /// [`Proxy::chunks`]).
    order: Vec<usize>,
    /// Each medium sample's share of the shell pieces not stored.
    pub shares: SampleShares,
    /// How many elements there are in all, and the sum of their radiance in build
    /// order (the Hessian floor's mean, [`crate::core::metric::hessian_radiance_floor`]).
    pub count: usize,
    pub radiance_sum: Rgb,
}

impl<S: Dim> Proxy<S> {
    /// The stored elements in groups of the build order's consecutive runs of
    /// `size` (empty groups included): a sum made per group and the groups' sums
    /// added in order is the same, bit for bit, as one made over the full list in
    /// chunks of `size` skipping the shell pieces, whatever the thread count.
    pub fn chunks(&self, size: usize) -> Vec<&[Element<S>]> {
        let bound = |c: usize| self.order.partition_point(|&i| i < c * size);
        (0..self.count.div_ceil(size))
            .map(|c| &self.elements[bound(c)..bound(c + 1)])
            .collect()
    }
}

/// Build the proxy of a light field.
pub fn build<S: Dim>(lf: &LightField<S>, rule: RadianceRule) -> Proxy<S> {
    let mut p = Proxy {
        elements: Vec::new(),
        order: Vec::new(),
        shares: SampleShares::new(lf),
        count: 0,
        radiance_sum: Rgb::ZERO,
    };
    for_each_element(lf, rule, |piece| {
        match piece {
            Piece::Element(e) => {
                p.radiance_sum += e.radiance;
                p.elements.push(e);
                p.order.push(p.count);
            }
            Piece::Shared(s) => {
                // The element's radiance and size as `make` and `Element::size` give
                // them, without the element.
                let v = s.v.as_ref();
                p.radiance_sum += v.iter().fold(Rgb::ZERO, |l, q| l + q.2) / v.len() as f64;
                let mut size = 0.0f64;
                for i in 0..v.len() {
                    for j in i + 1..v.len() {
                        size = size.max(S::length(v[j].0 - v[i].0));
                    }
                }
                p.shares.add::<S>(s.rays.as_ref(), s.shell, s.dir_measure, size);
            }
        }
        p.count += 1;
    });
    p
}

/// Every element of the proxy of a light field, in build order (what the app
/// draws; [`build`] keeps only those summed one by one).
pub fn elements<S: Dim>(lf: &LightField<S>, rule: RadianceRule) -> Vec<Element<S>> {
    let mut out = Vec::with_capacity(lf.simplices.len() * 2);
    for_each_element(lf, rule, |piece| {
        out.push(match piece {
            Piece::Element(e) => e,
            Piece::Shared(s) => {
                let kind = (ElementKind::Medium, false);
                make(
                    lf.x,
                    s.v,
                    RadianceRule::Average,
                    kind,
                    s.dir_measure,
                    (s.rays, Some(s.shell)),
                )
            }
        })
    });
    out
}

/// An element as [`for_each_element`] hands it on: made, or (a shell piece that
/// bridges no occluder, summed per medium sample) only its vertices.
enum Piece<S: Dim> {
    Element(Element<S>),
    Shared(SharedPiece<S>),
}

struct SharedPiece<S: Dim> {
    v: S::Simplex<Vertex<S>>,
    rays: S::Simplex<u32>,
    shell: u32,
    dir_measure: f64,
}

/// Make the proxy's elements, surfaces first, and hand each to `sink`.
fn for_each_element<S: Dim>(lf: &LightField<S>, rule: RadianceRule, mut sink: impl FnMut(Piece<S>)) {
    let x = lf.x;
    let ends: Vec<Vertex<S>> = lf
        .rays
        .iter()
        .map(|r| {
            let (p, d, l) = r.end(x);
            // A hit next to a visibility boundary stands at the surface's true edge
            // (see `silhouette`), with the radiance its ray found.
            match r.hit.as_ref().and_then(|h| h.edge) {
                Some(e) => (e, S::length(e - x), l, e),
                None => (p, d, l, p),
            }
        })
        .collect();
    let measure = |t: &S::Simplex<u32>| S::direction_measure(S::simplex(|k| lf.rays[t.as_ref()[k] as usize].dir));
    // Which rays have cut edges (most simplices have none: no search for them).
    let mut cut_from = vec![false; if lf.cuts.is_empty() { 0 } else { lf.rays.len() }];
    for c in &lf.cuts {
        cut_from[c.from as usize] = true;
    }
    for t in &lf.simplices {
        let cut = !cut_from.is_empty() && t.as_ref().iter().any(|&i| cut_from[i as usize]);
        if let Some(pieces) = split_at_cuts(lf, t, &ends).filter(|_| cut) {
            for p in pieces {
                // The hit surface's side is one continuous surface; the other side
                // bridges its edge and what lies behind, as below.
                let rule = if p.bridging { rule } else { RadianceRule::Average };
                let v = S::simplex(|k| p.v[k]);
                let mut e = make(x, v, rule, (ElementKind::Surface, p.bridging), p.measure, (*t, None));
                if p.bridging && rule == RadianceRule::Farther {
                    e.far_plane = p.far_plane;
                }
                e.corner = p.corner;
                // The sides of a farther surface's edge carry what they see, under
                // either rule (see `proxy_cut::edge_split`).
                if let Some(src) = p.source {
                    (e.radiance, e.anchor) = (src.2, src.3);
                }
                sink(Piece::Element(e));
            }
            continue;
        }
        let mut v: S::Simplex<Vertex<S>> = S::simplex(|k| ends[t.as_ref()[k] as usize]);
        // An escaped ray sees the background, which lies beyond anything hit: its
        // vertex is pushed behind the simplex's farthest hit (twice as far; its
        // transmittance and radiance stay those of its cut length). The element then
        // carries the background and its form factor moves with the hit silhouette.
        // At the cut length the invented end point could sit in front of a distant
        // emitter in thick fog, and the element carry the emitter with the near point's
        // derivatives: measured 40-200% gradient errors beside an emitter at σ_t = 50.
        let escaped = |k: usize| lf.rays[t.as_ref()[k] as usize].hit.is_none();
        let far_hit = (0..S::DIM)
            .filter(|&k| !escaped(k))
            .map(|k| v.as_ref()[k].1)
            .fold(0.0, f64::max);
        for k in (0..S::DIM).filter(|&k| escaped(k) && far_hit > 0.0) {
            let dir = lf.rays[t.as_ref()[k] as usize].dir;
            let e = &mut v.as_mut()[k];
            e.1 = e.1.max(2.0 * far_hit);
            e.0 = x + dir * e.1;
        }
        let (dmin, dmax) = v
            .as_ref()
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), e| (lo.min(e.1), hi.max(e.1)));
        // Ends at clearly different depths bridge an occluder's edge and what lies
        // behind it, unless they are all hits in one plane: a continuous surface seen
        // at a grazing angle (below an emitter, 1e-4 away, elements 10% apart in depth
        // were "bridging", and their transmittance, evaluated at their ends, erred).
        let one_plane = || {
            let hits: Vec<_> = t
                .as_ref()
                .iter()
                .filter_map(|&k| lf.rays[k as usize].hit.as_ref())
                .collect();
            hits.len() == S::DIM
                && v.as_ref().iter().all(|q| {
                    let n = hits[0].normal;
                    S::dot(n, q.0 - v.as_ref()[0].0).abs() <= 1e-9 * dmax
                        && hits.iter().all(|h| S::dot(h.normal, n) > 1.0 - 1e-12)
                })
        };
        let bridging = dmax - dmin > BRIDGE_RATIO * dmin && !one_plane();
        // A piece of one continuous surface carries its vertices' mean, phase and
        // transmittance at their centroid (second order along a chain; the farther
        // vertex's values are first order, and where vertices are near x their
        // angles move fast: the gradient grew as 1/d next to a surface at g = 0.99).
        let rule = if bridging { rule } else { RadianceRule::Average };
        let mut e = make(x, v, rule, (ElementKind::Surface, bridging), measure(t), (*t, None));
        if bridging && rule == RadianceRule::Farther {
            let far = (0..S::DIM)
                .max_by(|&i, &j| v.as_ref()[i].1.total_cmp(&v.as_ref()[j].1))
                .expect("a simplex has vertices");
            e.far_plane = lf.rays[t.as_ref()[far] as usize]
                .hit
                .as_ref()
                .map(|h| (v.as_ref()[far].0, h.normal));
        }
        sink(Piece::Element(e));
    }
    let shells = lf.rays.iter().map(|r| r.samples.len()).max().unwrap_or(0);
    let mut neighbours = None;
    for t in &lf.simplices {
        let omega = measure(t);
        for i in 0..shells {
            // Each vertex's sample of shell i, where its ray reaches that far.
            let mut samples = [None; 3];
            for (s, &j) in samples.iter_mut().zip(t.as_ref()) {
                *s = lf.medium_point(j as usize, i);
            }
            let present: S::Simplex<bool> = S::simplex(|k| samples[k].is_some());
            if !present.as_ref().iter().any(|&p| p) {
                continue;
            }
            let v: S::Simplex<Vertex<S>> = S::simplex(|k| match samples[k] {
                Some((at, depth, light, _)) => (at, depth, light, at),
                None => {
                    let e = ends[t.as_ref()[k] as usize];
                    (e.0, e.1, Rgb::ZERO, e.3)
                }
            });
            if v.as_ref().iter().all(|e| e.2 == Rgb::ZERO) {
                continue; // outside the medium region: nothing to carry
            }
            if present.as_ref().iter().all(|&p| p) {
                let (rays, shell, dir_measure) = (*t, i as u32, omega);
                sink(Piece::Shared(SharedPiece {
                    v,
                    rays,
                    shell,
                    dir_measure,
                }));
                continue;
            }
            let kind = (ElementKind::Medium, true);
            let mut e = make(x, v, RadianceRule::Average, kind, omega, (*t, Some(i as u32)));
            // See the module docs: the samples' sum over the vertex count.
            let (mut c, mut l, mut m) = (S::zero(), Rgb::ZERO, 0.0);
            for (p, _) in v.as_ref().iter().zip(present.as_ref()).filter(|(_, p)| **p) {
                c += p.3;
                l += p.2;
                m += 1.0;
            }
            (e.anchor, e.radiance) = (c / m, l / S::DIM as f64);
            let neighbours = neighbours.get_or_insert_with(|| ray_neighbours(lf));
            e.revealed = Some(revealed_light(lf, neighbours, t.as_ref(), i));
            sink(Piece::Element(e));
        }
    }
}

/// Each ray's neighbours: the rays it shares a simplex with.
fn ray_neighbours<S: Dim>(lf: &LightField<S>) -> Vec<Vec<u32>> {
    let mut n: Vec<Vec<u32>> = vec![Vec::new(); lf.rays.len()];
    for t in &lf.simplices {
        for &a in t.as_ref() {
            for &b in t.as_ref() {
                if a != b && !n[a as usize].contains(&b) {
                    n[a as usize].push(b);
                }
            }
        }
    }
    n
}

/// The light a bridging shell piece's edges reveal or hide as x moves: the mean
/// of shell i's samples on the piece's rays and their neighbours' (the samples
/// next to the occluder's edge), not the piece's value weight, their sum over the
/// vertex count. Why the neighbours: in 2D such a piece holds one sample, taken
/// by one path, and with the piece's own samples alone the 2D gradient's median
/// error rose (g = 0.6: 0.12 → 0.16, `tests/anisotropic_multiple_scattering.rs`);
/// more rings of neighbours reach light farther from the edge (3D, the point under
/// the box: the mean of 8 seeds 0.26, 0.31, 0.38, 0.46 off with 0, 1, 3, 6 rings).
fn revealed_light<S: Dim>(lf: &LightField<S>, neighbours: &[Vec<u32>], rays: &[u32], i: usize) -> Rgb {
    // Each present sample with its light, read once.
    let sample = |j: u32| lf.medium_point(j as usize, i).map(|p| (j, p.2));
    let mut near: Vec<(u32, Rgb)> = rays.iter().filter_map(|&j| sample(j)).collect();
    for k in 0..near.len() {
        for &j in &neighbours[near[k].0 as usize] {
            if near.iter().all(|n| n.0 != j)
                && let Some(n) = sample(j)
            {
                near.push(n);
            }
        }
    }
    let sum = near.iter().fold(Rgb::ZERO, |l, n| l + n.1);
    sum / near.len().max(1) as f64
}

/// Each medium sample's share of the measure of the non-bridging shell pieces it
/// is a vertex of, and their sizes weighted by share (see
/// [`super::derivatives::aware_with_floor`]).
#[derive(Clone, Debug)]
pub struct SampleShares {
    /// Where each ray's samples start in `measure` and `size`.
    first: Vec<usize>,
    measure: Vec<f64>,
    size: Vec<f64>,
}

impl SampleShares {
    fn new<S: Dim>(lf: &LightField<S>) -> Self {
        let mut first = Vec::with_capacity(lf.rays.len() + 1);
        let mut n = 0;
        for r in &lf.rays {
            first.push(n);
            n += r.samples.len();
        }
        first.push(n);
        SampleShares {
            first,
            measure: vec![0.0; n],
            size: vec![0.0; n],
        }
    }

    /// Add the shares of a shell piece (its rays, shell, measure of directions and
    /// longest edge) to its vertices' samples.
    fn add<S: Dim>(&mut self, rays: &[u32], shell: u32, dir_measure: f64, size: f64) {
        let share = dir_measure / S::DIM as f64;
        let sized = share * size;
        for &j in rays {
            let k = self.first[j as usize] + shell as usize;
            self.measure[k] += share;
            self.size[k] += sized;
        }
    }

    /// Sample i of ray j's measure and mean piece size, if it has a share.
    pub fn of(&self, j: usize, i: usize) -> Option<(f64, f64)> {
        let k = self.first[j] + i;
        let m = self.measure[k];
        (m > 0.0).then(|| (m, self.size[k] / m))
    }
}
