//! Triangles, and the shapes of the scene format turned into triangles: quads (two
//! triangles), boxes (twelve, optionally rotated about y) and OBJ meshes (tobj).
//! Every triangle keeps the index of the shape it came from (its material).

use crate::core::space::D3;
use crate::limits::MAX_COORD;
use crate::pipeline::bvh::Primitive;
use glam::{DMat3, DVec3};
use std::path::Path;

/// A triangle p0 + u·e1 + v·e2 (u, v ≥ 0, u + v ≤ 1); its front side is along
/// e1 × e2 (counter-clockwise vertices seen from the front).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub p0: DVec3,
    pub e1: DVec3,
    pub e2: DVec3,
    /// Unit geometric normal (front side).
    pub normal: DVec3,
    pub area: f64,
    /// Index of the shape (material) it belongs to.
    pub shape: u32,
}

/// A ray–triangle intersection (`prim` is the triangle).
pub use crate::pipeline::world::Hit;

impl Primitive<D3> for Triangle {
    /// p0, e1 and e2: what the intersection reads.
    type Leaf = [DVec3; 3];

    fn bounds(&self) -> (DVec3, DVec3) {
        let [a, b, c] = self.vertices();
        (a.min(b).min(c), a.max(b).max(c))
    }

    fn leaf(&self) -> [DVec3; 3] {
        [self.p0, self.e1, self.e2]
    }

    #[inline]
    fn intersect_leaf(
        &[p0, e1, e2]: &[DVec3; 3],
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<(f64, f64, f64)> {
        moller_trumbore(p0, e1, e2, o, d, t_min, t_max)
    }
}

impl Triangle {
    /// None for degenerate (zero-area) triangles.
    pub fn new(a: DVec3, b: DVec3, c: DVec3, shape: u32) -> Option<Triangle> {
        let (e1, e2) = (b - a, c - a);
        let n = e1.cross(e2);
        let len = n.length();
        (len > 0.0 && len.is_finite()).then(|| Triangle {
            p0: a,
            e1,
            e2,
            normal: n / len,
            area: 0.5 * len,
            shape,
        })
    }

    pub fn vertices(&self) -> [DVec3; 3] {
        [self.p0, self.p0 + self.e1, self.p0 + self.e2]
    }

    #[inline]
    pub fn point_at(&self, u: f64, v: f64) -> DVec3 {
        self.p0 + self.e1 * u + self.e2 * v
    }

    /// Möller–Trumbore: (t, u, v) for t in (t_min, t_max), both faces.
    #[inline]
    pub fn intersect(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
        moller_trumbore(self.p0, self.e1, self.e2, o, d, t_min, t_max)
    }

    /// A uniformly distributed point for (ξ1, ξ2) in [0, 1)².
    pub fn sample_point(&self, xi1: f64, xi2: f64) -> DVec3 {
        let s = xi1.sqrt();
        self.point_at(s * (1.0 - xi2), s * xi2)
    }
}

/// Möller–Trumbore for the triangle p0 + u·e1 + v·e2 (the one test of both the
/// triangle and the BVH's leaf copy of it, so their answers are the same bits).
#[inline]
fn moller_trumbore(
    p0: DVec3,
    e1: DVec3,
    e2: DVec3,
    o: DVec3,
    d: DVec3,
    t_min: f64,
    t_max: f64,
) -> Option<(f64, f64, f64)> {
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    // The edge tests on the numerators, scaled by det's sign, and the division
    // only for a triangle the ray meets: most a query tests are missed.
    let sign = if det < 0.0 { -1.0 } else { 1.0 };
    let s = o - p0;
    let u_num = s.dot(p);
    let (u_s, det_s) = (u_num * sign, det * sign);
    if !(0.0..=det_s).contains(&u_s) {
        return None;
    }
    let q = s.cross(e1);
    let v_num = d.dot(q);
    let v_s = v_num * sign;
    if v_s < 0.0 || u_s + v_s > det_s {
        return None;
    }
    let inv = 1.0 / det;
    let t = e2.dot(q) * inv;
    (t > t_min && t < t_max).then_some((t, u_num * inv, v_num * inv))
}

/// The two triangles of the parallelogram origin + s·u + t·v.
pub fn quad(origin: DVec3, u: DVec3, v: DVec3, shape: u32) -> Vec<Triangle> {
    [
        Triangle::new(origin, origin + u, origin + u + v, shape),
        Triangle::new(origin, origin + u + v, origin + v, shape),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The twelve outward-facing triangles of a box, rotated by `rotate_y_deg` about
/// the vertical axis through its centre.
pub fn cuboid(min: DVec3, max: DVec3, rotate_y_deg: f64, shape: u32) -> Vec<Triangle> {
    let c = 0.5 * (min + max);
    let rot = DMat3::from_rotation_y(rotate_y_deg.to_radians());
    let p = |x: f64, y: f64, z: f64| c + rot * (DVec3::new(x, y, z) - c);
    let (a, b) = (min, max);
    // Each face as (origin, u, v) with u × v pointing outwards.
    let faces = [
        (p(a.x, a.y, a.z), p(a.x, a.y, b.z), p(a.x, b.y, a.z)), // −x
        (p(b.x, a.y, a.z), p(b.x, b.y, a.z), p(b.x, a.y, b.z)), // +x
        (p(a.x, a.y, a.z), p(b.x, a.y, a.z), p(a.x, a.y, b.z)), // −y
        (p(a.x, b.y, a.z), p(a.x, b.y, b.z), p(b.x, b.y, a.z)), // +y
        (p(a.x, a.y, a.z), p(a.x, b.y, a.z), p(b.x, a.y, a.z)), // −z
        (p(a.x, a.y, b.z), p(b.x, a.y, b.z), p(a.x, b.y, b.z)), // +z
    ];
    faces
        .iter()
        .flat_map(|&(o, pu, pv)| quad(o, pu - o, pv - o, shape))
        .collect()
}

/// A UV sphere of unit radius at the origin: `bands` rings of latitude, `segments`
/// of longitude, one triangle per segment in the two polar bands and two elsewhere
/// (2·segments·(bands − 1) triangles, counter-clockwise seen from outside). The ray
/// benchmark's mesh: 200 × 399 gives 158,802 triangles; `scripts/embree_mitsuba_compare.py`
/// builds the same vertices for Embree.
pub fn uv_sphere(bands: usize, segments: usize, shape: u32) -> Vec<Triangle> {
    let vertex = |i: usize, j: usize| {
        let theta = std::f64::consts::PI * i as f64 / bands as f64;
        let phi = std::f64::consts::TAU * j as f64 / segments as f64;
        DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    let mut tris = Vec::with_capacity(2 * segments * bands.saturating_sub(1));
    for i in 0..bands {
        for j in 0..segments {
            let (a, b) = (vertex(i, j), vertex(i, j + 1));
            let (c, d) = (vertex(i + 1, j), vertex(i + 1, j + 1));
            if i + 1 < bands {
                tris.extend(Triangle::new(a, d, c, shape));
            }
            if i > 0 {
                tris.extend(Triangle::new(a, b, d, shape));
            }
        }
    }
    tris
}

/// Every vertex line (`v x y z …`) of an OBJ text has three finite coordinates
/// that lie within ±[`MAX_COORD`] once scaled and translated, and every face index
/// refers to a vertex, texture coordinate or normal of the file; errors name the
/// file and the line. (tobj would read `nan` or `1e39` as an f32 NaN or inf, and
/// the triangles using it would silently vanish; an index of −2⁶³ overflows in it.)
pub fn check_obj_text(file: &str, text: &str, scale: DVec3, translate: DVec3) -> Result<(), String> {
    // Totals (positive indices may refer ahead) and counts so far (negative ones
    // count back from the current line), for v, vt, vn.
    let kinds = ["v", "vt", "vn"];
    let mut total = [0i64; 3];
    for line in text.lines() {
        if let Some(k) = line
            .split_whitespace()
            .next()
            .and_then(|w| kinds.iter().position(|&x| x == w))
        {
            total[k] += 1;
        }
    }
    let mut seen = [0i64; 3];
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let at = || format!("`{file}` line {}", n + 1);
        match words.next() {
            Some("v") => {
                seen[0] += 1;
                check_vertex(&at(), words, scale, translate)?;
            }
            Some("vt") => seen[1] += 1,
            Some("vn") => seen[2] += 1,
            Some("f") => {
                for w in words {
                    for (k, part) in w.split('/').take(3).enumerate() {
                        let ok = (part.is_empty() && k > 0)
                            || part
                                .parse::<i64>()
                                .is_ok_and(|i| (1..=total[k]).contains(&i) || (-seen[k]..0).contains(&i));
                        if !ok {
                            return Err(format!(
                                "{}: face index `{w}` refers to no {} of the file",
                                at(),
                                ["vertex", "texture coordinate", "normal"][k]
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

fn check_vertex<'a>(
    at: &str,
    mut words: impl Iterator<Item = &'a str>,
    scale: DVec3,
    translate: DVec3,
) -> Result<(), String> {
    for k in 0..3 {
        let w = words
            .next()
            .ok_or_else(|| format!("{at}: a vertex needs three coordinates"))?;
        let v: f64 = w
            .parse()
            .map_err(|_| format!("{at}: vertex coordinate `{w}` is not a number"))?;
        if !v.is_finite() || v.abs() > f32::MAX as f64 {
            return Err(format!("{at}: vertex coordinate `{w}` is not a finite number"));
        }
        let placed = v * scale[k] + translate[k];
        if placed.abs() > MAX_COORD {
            return Err(format!(
                "{at}: the vertex lies at {placed:e} once scaled and translated, beyond ±{MAX_COORD:e}"
            ));
        }
    }
    Ok(())
}

/// Triangles of every model in an OBJ file, each vertex scaled then translated.
/// Zero-area faces are dropped (they neither block nor emit light).
pub fn load_obj(path: &Path, scale: DVec3, translate: DVec3, shape: u32) -> Result<Vec<Triangle>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot load `{}`: {e}", path.display()))?;
    parse_obj(&bytes, &path.display().to_string(), scale, translate, shape)
}

/// [`load_obj`] on the bytes of an OBJ file named `file` (materials are not read:
/// surfaces come from the scene).
pub fn parse_obj(
    bytes: &[u8],
    file: &str,
    scale: DVec3,
    translate: DVec3,
    shape: u32,
) -> Result<Vec<Triangle>, String> {
    check_obj_text(file, &String::from_utf8_lossy(bytes), scale, translate)?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let no_materials = |_: &Path| Ok((Vec::new(), Default::default()));
    let (models, _) = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &opts, no_materials)
        .map_err(|e| format!("cannot load `{file}`: {e}"))?;
    let mut tris = Vec::new();
    for m in &models {
        let pos = &m.mesh.positions;
        let vertex = |i: u32| -> Result<DVec3, String> {
            let k = 3 * i as usize;
            pos.get(k..k + 3)
                .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * scale + translate)
                .ok_or_else(|| format!("`{file}`: vertex index {} out of range", i + 1))
        };
        for f in m.mesh.indices.chunks_exact(3) {
            tris.extend(Triangle::new(vertex(f[0])?, vertex(f[1])?, vertex(f[2])?, shape));
        }
    }
    if tris.is_empty() {
        return Err(format!("`{file}` has no triangles"));
    }
    Ok(tris)
}

/// The point of triangle `tri`'s boundary that x sees strictly between the
/// directions `d_in` (which meets the triangle) and `d_out` (a neighbouring ray that
/// does not), in the plane through x they span: where the triangle stops being
/// visible along that arc (see `flatland::geometry::segment_silhouette`).
pub fn triangle_silhouette(tri: &Triangle, x: DVec3, d_in: DVec3, d_out: DVec3) -> Option<DVec3> {
    let n = d_in.cross(d_out);
    let v = tri.vertices();
    let mut best: Option<(f64, DVec3)> = None;
    for k in 0..3 {
        let (p, q) = (v[k], v[(k + 1) % 3]);
        let (sp, sq) = (n.dot(p - x), n.dot(q - x));
        // The edge crosses the plane (an end on it counts once, from either side).
        if sp == sq || (sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0) {
            continue;
        }
        let c = p + (q - p) * (sp / (sp - sq));
        let w = c - x;
        let inside = d_in.cross(w).dot(n) > 0.0 && w.cross(d_out).dot(n) > 0.0 && w.dot(d_in + d_out) > 0.0;
        let cos = w.normalize().dot(d_in);
        if inside && best.is_none_or(|(b, _)| cos > b) {
            best = Some((cos, c));
        }
    }
    best.map(|(_, c)| c)
}

/// The unit direction of the edge of `tri` nearest `p` (a point on its boundary),
/// `None` for a degenerate edge.
pub fn triangle_edge_through(tri: &Triangle, p: DVec3) -> Option<DVec3> {
    let v = tri.vertices();
    let off_line = |k: usize| {
        let (a, b) = (v[k], v[(k + 1) % 3]);
        let d = (b - a).normalize_or_zero();
        let w = p - a;
        (w - d * w.dot(d)).length_squared()
    };
    let k = (0..3).min_by(|&i, &j| off_line(i).total_cmp(&off_line(j)))?;
    let d = (v[(k + 1) % 3] - v[k]).normalize_or_zero();
    (d != DVec3::ZERO).then_some(d)
}

/// For each edge of `tri`, its point nearest `x` and the unit direction in the
/// triangle's plane, across the edge, that leaves the triangle there
/// (`World::primitive_ends`); degenerate edges are left out.
pub fn triangle_edge_points(tri: &Triangle, x: DVec3, out: &mut Vec<(DVec3, DVec3)>) {
    let v = tri.vertices();
    for k in 0..3 {
        let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
        let along = b - a;
        let len2 = along.length_squared();
        if len2 <= 0.0 {
            continue;
        }
        let q = a + along * ((x - a).dot(along) / len2).clamp(0.0, 1.0);
        let inwards = (c - a) - along * ((c - a).dot(along) / len2);
        let leaving = -inwards.normalize_or_zero();
        if leaving != DVec3::ZERO && q.is_finite() {
            out.push((q, leaving));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_faces_point_outwards_and_close() {
        let (a, b) = (DVec3::new(-1.0, 0.0, -2.0), DVec3::new(1.0, 1.0, 2.0));
        for rot in [0.0, 30.0] {
            let tris = cuboid(a, b, rot, 0);
            assert_eq!(tris.len(), 12);
            let c = 0.5 * (a + b);
            let area: f64 = tris.iter().map(|t| t.area).sum();
            assert!((area - 2.0 * (2.0 * 1.0 + 2.0 * 4.0 + 1.0 * 4.0)).abs() < 1e-12);
            for t in &tris {
                let centre = t.p0 + (t.e1 + t.e2) / 3.0;
                assert!(t.normal.dot(centre - c) > 0.0, "inward face {t:?}");
            }
            // Divergence theorem: the area-weighted normals sum to zero for a closed surface.
            let s: DVec3 = tris.iter().map(|t| t.normal * t.area).sum();
            assert!(s.length() < 1e-12);
        }
    }

    /// Bad OBJ text is an error naming the file and the line (issue 14: a NaN
    /// vertex silently dropped its triangles; an index of −2⁶³ overflowed in tobj).
    #[test]
    fn bad_obj_text_names_file_and_line() {
        let check = |text: &str| check_obj_text("m.obj", text, DVec3::ONE, DVec3::ZERO);
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n";
        assert_eq!(check(&format!("{quad}f 1//1 2//1 3//-1 -1//1\n")), Ok(()));
        for (text, want) in [
            (
                "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
                "`m.obj` line 2: vertex coordinate `nan`",
            ),
            ("v 0 1e39 0\n", "line 1: vertex coordinate `1e39` is not a finite"),
            ("v 0 1\n", "line 1: a vertex needs three coordinates"),
            (
                &format!("{quad}f 1 2 5\n"),
                "line 6: face index `5` refers to no vertex",
            ),
            (&format!("{quad}f 1 2 3//-9223372036854775808\n"), "refers to no normal"),
            (&format!("{quad}f 1/1 2 3\n"), "refers to no texture coordinate"),
            (&format!("{quad}f 0 1 2\n"), "face index `0`"),
        ] {
            let err = check(text).unwrap_err();
            assert!(err.contains(want), "{err}");
        }
        let far = check_obj_text("m.obj", "v 2 0 0\n", DVec3::splat(1e12), DVec3::ZERO).unwrap_err();
        assert!(far.contains("beyond ±1e12"), "{far}");
    }

    #[test]
    fn uv_sphere_is_closed_and_sized() {
        let tris = uv_sphere(200, 399, 0);
        assert_eq!(tris.len(), 158_802);
        let s: DVec3 = tris.iter().map(|t| t.normal * t.area).sum();
        assert!(s.length() < 1e-9, "not closed: {s}");
        assert!(tris.iter().all(|t| t.normal.dot(t.p0 + (t.e1 + t.e2) / 3.0) > 0.0));
    }

    #[test]
    fn intersection_and_sampling() {
        let t = Triangle::new(DVec3::ZERO, DVec3::X, DVec3::Y, 0).unwrap();
        let (d, u, v) = t.intersect(DVec3::new(0.2, 0.3, 1.0), -DVec3::Z, 0.0, 10.0).unwrap();
        assert!((d - 1.0).abs() < 1e-15 && (u - 0.2).abs() < 1e-15 && (v - 0.3).abs() < 1e-15);
        assert!(t.intersect(DVec3::new(0.8, 0.3, 1.0), -DVec3::Z, 0.0, 10.0).is_none());
        let p = t.sample_point(0.99, 0.5);
        assert!(p.x >= 0.0 && p.y >= 0.0 && p.x + p.y <= 1.0);
    }
}
