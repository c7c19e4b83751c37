//! Equivalent scenes in 2D and 3D for the checks that hold in every dimension.
//!
//! [`Fixture`] is implemented by the dimension markers `D2` and `D3`: each writes a
//! [`Spec`] in its own scene format (`flatland_scenes/*.json`, `scenes3d/*.json`) and
//! wraps its own entry points (fields and cached fields in 2D, images and cached
//! images in 3D), so that a test body is written once, `fn furnace<F: Fixture>()`,
//! and instantiated as `furnace_2d` / `furnace_3d`. Coordinates are written in 3D;
//! flatland drops z.

#![allow(dead_code)] // each test file uses part of the fixture

use std::fmt::Write;
use std::path::Path;
use volcache::core::color::Rgb;
use volcache::core::element::segment_form_factor;
use volcache::core::metric::CacheMethod;
use volcache::core::rng::Sampler;
use volcache::core::space::{D2, D3, Space};
use volcache::core::taylor::Taylor2;
use volcache::core::triangle::triangle_form_factor;
use volcache::flatland;
use volcache::pipeline::bvh::Primitive;
use volcache::pipeline::dim::Dim;
use volcache::pipeline::world::World;
use volcache::progress::Progress;
use volcache::volume;

/// A scene described once for both dimensions.
#[derive(Clone, Debug, Default)]
pub struct Spec {
    /// The closed box [−1, 1]^d whose walls all emit `.0` and reflect `.1` (two-sided).
    pub walls: Option<(Rgb, Rgb)>,
    /// A one-sided black emitter of radiance `ceiling` on the face y = 1 of that box
    /// (2D: x ∈ [−1, 1]; 3D: x, z ∈ [−1, 1]), shining down.
    pub ceiling: Option<Rgb>,
    /// A one-sided diffuse floor y = 0 of reflectance `floor`, |x|, |z| ≤ 5, facing up.
    pub floor: Option<Rgb>,
    /// A point light: position and intensity (per unit angle or solid angle).
    pub point_light: Option<([f64; 3], Rgb)>,
    /// A homogeneous medium everywhere: σ_a, σ_s, g.
    pub medium: Option<(Rgb, Rgb, f64)>,
}

/// JSON of a colour.
pub fn rgb(c: Rgb) -> String {
    format!("[{:?}, {:?}, {:?}]", c.x, c.y, c.z)
}

/// The medium block, the same in both formats (region: everywhere).
fn medium_json(spec: &Spec) -> String {
    spec.medium.map_or(String::new(), |(a, s, g)| {
        format!(
            r#", "medium": {{"sigma_a": {}, "sigma_s": {}, "g": {g:?}}}"#,
            rgb(a),
            rgb(s)
        )
    })
}

/// A path-traced field (2D) or image (3D): values, where they are defined (a 2D
/// field of L_s is undefined outside the medium), per-pixel standard errors, rays.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub values: Vec<Rgb>,
    pub defined: Vec<bool>,
    pub std_error: Vec<f64>,
    pub rays: u64,
}

/// A cached field (2D) or image (3D).
#[derive(Clone, Debug)]
pub struct CachedRun {
    pub values: Vec<Rgb>,
    pub defined: Vec<bool>,
    /// Every record of every cache, printed (Rust prints floats so that they read
    /// back exactly: equal text is equal bits).
    pub records: String,
    pub record_count: usize,
    /// Query points (pixels, march points) no record covered.
    pub uncovered: usize,
}

/// A shipped scene with the bounds rays are cast from.
pub struct Shipped<W, V> {
    pub name: &'static str,
    pub world: W,
    pub lo: V,
    pub hi: V,
}

pub trait Fixture: Dim {
    type W: World<S = Self>;
    type Prim: Primitive<Self> + Clone;

    /// A point from 3D coordinates (flatland drops z).
    fn point(c: [f64; 3]) -> Self::Vec;
    /// The scene of `spec`, written in this dimension's file format and parsed.
    fn scene(spec: &Spec) -> Self::W;
    /// The closed-form angle (solid angle) the ceiling emitter of [`Spec`] subtends
    /// at `x`, with its gradient and Hessian, positive.
    fn ceiling_form_factor(x: Self::Vec) -> Taylor2<Self>;

    /// The shipped fog scene with occluders (2D `windows.json`, 3D `fog_box.json`)
    /// and a point inside its medium.
    fn fog_scene() -> (Self::W, Self::Vec);
    /// The shipped scenes with their bounds.
    fn shipped() -> Vec<Shipped<Self::W, Self::Vec>>;
    fn prims(world: &Self::W) -> &[Self::Prim];
    /// A random primitive (segment, triangle) of size about 0.05–1 in [0, 10]^d.
    fn random_prim(s: &mut Sampler) -> Option<Self::Prim>;

    /// A small path-traced field (image) of `world` on `threads` threads.
    fn render(world: &Self::W, threads: usize) -> Image;
    /// Whether the cached quantity can be split into per-part caches (the 2D field
    /// can show single and multiple scattering apart; 3D images cache their sum).
    const PER_PART: &'static [bool];
    /// A small cached field (image) of `world` on `threads` threads.
    fn render_cached(world: &Self::W, method: CacheMethod, per_part: bool, threads: usize) -> CachedRun;
}

/// Run `f` on a pool of `threads` threads.
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// The same form factor whatever the orientation of the vertices.
fn positive<S: Space>(f: Taylor2<S>) -> Taylor2<S> {
    if f.value < 0.0 { f * -1.0 } else { f }
}

fn manifest(rel: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

impl Fixture for D2 {
    type W = flatland::scene::Scene;
    type Prim = flatland::geometry::Segment;

    fn point(c: [f64; 3]) -> glam::DVec2 {
        glam::DVec2::new(c[0], c[1])
    }

    fn scene(spec: &Spec) -> Self::W {
        let mut segs = Vec::new();
        if let Some((e, r)) = spec.walls {
            segs.push(format!(
                r#"{{"points": [[-1, -1], [1, -1], [1, 1], [-1, 1]], "closed": true, "emission": {}, "reflectance": {}}}"#,
                rgb(e),
                rgb(r)
            ));
        }
        if let Some(e) = spec.ceiling {
            // The front side is left of a→b: down.
            segs.push(format!(
                r#"{{"a": [1, 1], "b": [-1, 1], "emission": {}, "two_sided": false}}"#,
                rgb(e)
            ));
        }
        if let Some(r) = spec.floor {
            segs.push(format!(
                r#"{{"a": [-5, 0], "b": [5, 0], "reflectance": {}, "two_sided": false}}"#,
                rgb(r)
            ));
        }
        let mut text = format!(
            r#"{{"domain": {{"min": [-2, -2], "max": [2, 2]}}, "segments": [{}]"#,
            segs.join(", ")
        );
        if let Some((p, i)) = spec.point_light {
            write!(
                text,
                r#", "lights": [{{"type": "point", "position": [{:?}, {:?}], "intensity": {}}}]"#,
                p[0],
                p[1],
                rgb(i)
            )
            .unwrap();
        }
        text += &medium_json(spec);
        text += "}";
        flatland::scene::Scene::from_json(&text, "<test 2D>").unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    fn ceiling_form_factor(x: glam::DVec2) -> Taylor2<D2> {
        positive(segment_form_factor(
            glam::DVec2::new(1.0, 1.0),
            glam::DVec2::new(-1.0, 1.0),
            x,
        ))
    }

    fn fog_scene() -> (Self::W, glam::DVec2) {
        let s = flatland::scene::Scene::load(&manifest("flatland_scenes/windows.json")).unwrap();
        (s, glam::DVec2::new(0.3, 1.2))
    }

    fn shipped() -> Vec<Shipped<Self::W, glam::DVec2>> {
        ["windows", "forest", "furnace"]
            .into_iter()
            .map(|name| {
                let s = flatland::scene::Scene::load(&manifest(&format!("flatland_scenes/{name}.json"))).unwrap();
                let (lo, hi) = (s.domain_min, s.domain_max);
                Shipped { name, world: s, lo, hi }
            })
            .collect()
    }

    fn prims(world: &Self::W) -> &[Self::Prim] {
        &world.geometry.prims
    }

    fn random_prim(s: &mut Sampler) -> Option<Self::Prim> {
        let c = glam::DVec2::new(s.next_f64(), s.next_f64()) * 10.0;
        let d = glam::DVec2::from_angle(s.next_f64() * std::f64::consts::TAU) * (0.05 + 0.5 * s.next_f64());
        Some(flatland::geometry::Segment::new(
            c - d,
            c + d,
            Rgb::ZERO,
            Rgb::ZERO,
            true,
        ))
    }

    fn render(world: &Self::W, threads: usize) -> Image {
        let mut p = flatland::field::FieldParams::from_scene(world);
        (p.width, p.height, p.spp) = (22, 15, 4);
        let r = with_threads(threads, || {
            flatland::field::render_field(world, &p, &Progress::new()).unwrap()
        });
        Image {
            values: r.field.values,
            defined: r.field.valid,
            std_error: r.std_error,
            rays: r.rays,
        }
    }

    const PER_PART: &'static [bool] = &[false, true];

    fn render_cached(world: &Self::W, method: CacheMethod, per_part: bool, threads: usize) -> CachedRun {
        use flatland::cached_field::{CacheSettings, RecordMemo, render_cached};
        let mut fp = flatland::field::FieldParams::from_scene(world);
        (fp.width, fp.height) = (40, 28);
        let mut cs = CacheSettings::new::<D2>(method, 0.05, Default::default());
        (cs.probe.rays, cs.probe.steps, cs.seed, cs.per_part) = (512, 8, 3, per_part);
        let f = with_threads(threads, || {
            render_cached(world, &fp, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap()
        });
        CachedRun {
            records: format!("{:?}", f.records),
            record_count: f.record_count(),
            uncovered: f.uncovered_pixels,
            defined: f.field.valid,
            values: f.field.values,
        }
    }
}

impl Fixture for D3 {
    type W = volume::scene::Scene;
    type Prim = volume::mesh::Triangle;

    fn point(c: [f64; 3]) -> glam::DVec3 {
        glam::DVec3::from_array(c)
    }

    fn scene(spec: &Spec) -> Self::W {
        let quad = |o: [f64; 3], u: [f64; 3], v: [f64; 3], rest: String| {
            format!(r#"{{"quad": {{"origin": {o:?}, "u": {u:?}, "v": {v:?}}}, {rest}}}"#)
        };
        let mut shapes = Vec::new();
        if let Some((e, r)) = spec.walls {
            let m = || format!(r#""emission": {}, "reflectance": {}"#, rgb(e), rgb(r));
            let (x, y, z) = ([2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]);
            for (o, u, v) in [
                ([-1.0, -1.0, -1.0], x, y),
                ([-1.0, -1.0, 1.0], x, y),
                ([-1.0, -1.0, -1.0], y, z),
                ([1.0, -1.0, -1.0], y, z),
                ([-1.0, -1.0, -1.0], x, z),
                ([-1.0, 1.0, -1.0], x, z),
            ] {
                shapes.push(quad(o, u, v, m()));
            }
        }
        if let Some(e) = spec.ceiling {
            // u × v points down.
            let rest = format!(r#""emission": {}, "reflectance": 0, "two_sided": false"#, rgb(e));
            shapes.push(quad([-1.0, 1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0], rest));
        }
        if let Some(r) = spec.floor {
            let rest = format!(r#""reflectance": {}, "two_sided": false"#, rgb(r));
            shapes.push(quad([-5.0, 0.0, -5.0], [0.0, 0.0, 10.0], [10.0, 0.0, 0.0], rest));
        }
        let mut text = format!(
            r#"{{"camera": {{"position": [0, 0, 1.5], "look_at": [0, 0, 0], "fov_deg": 40}}, "shapes": [{}]"#,
            shapes.join(", ")
        );
        if let Some((p, i)) = spec.point_light {
            write!(
                text,
                r#", "lights": [{{"point": {{"position": {p:?}, "intensity": {}}}}}]"#,
                rgb(i)
            )
            .unwrap();
        }
        text += &medium_json(spec);
        text += "}";
        volume::scene::Scene::from_json(&text, "<test 3D>", Path::new(".")).unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    fn ceiling_form_factor(x: glam::DVec3) -> Taylor2<D3> {
        let v = glam::DVec3::new;
        let (a, b, c, d) = (
            v(-1.0, 1.0, -1.0),
            v(1.0, 1.0, -1.0),
            v(1.0, 1.0, 1.0),
            v(-1.0, 1.0, 1.0),
        );
        positive(triangle_form_factor([a, b, c], x) + triangle_form_factor([a, c, d], x))
    }

    fn fog_scene() -> (Self::W, glam::DVec3) {
        let s = volume::scene::Scene::load(&manifest("scenes3d/fog_box.json")).unwrap();
        (s, glam::DVec3::new(0.3, 0.6, 0.2))
    }

    fn shipped() -> Vec<Shipped<Self::W, glam::DVec3>> {
        ["fog_box", "staircase", "mesh_in_fog"]
            .into_iter()
            .map(|name| {
                let s = volume::scene::Scene::load(&manifest(&format!("scenes3d/{name}.json"))).unwrap();
                let (lo, hi) = (s.bounds.min, s.bounds.max);
                Shipped { name, world: s, lo, hi }
            })
            .collect()
    }

    fn prims(world: &Self::W) -> &[Self::Prim] {
        &world.geometry.prims
    }

    fn random_prim(s: &mut Sampler) -> Option<Self::Prim> {
        let mut v = || glam::DVec3::new(s.next_f64(), s.next_f64(), s.next_f64());
        let c = v() * 10.0;
        let size = 0.05 + 0.6 * v().x;
        let mut p = || c + (v() * 2.0 - glam::DVec3::ONE).normalize_or_zero() * size;
        volume::mesh::Triangle::new(p(), p(), p(), 0)
    }

    fn render(world: &Self::W, threads: usize) -> Image {
        let mut p = volume::render::RenderParams::from_scene(world);
        (p.width, p.height, p.spp) = (40, 30, 3);
        let r = with_threads(threads, || volume::render::render(world, &p, &Progress::new()).unwrap());
        assert_eq!(r.spp, 3);
        Image {
            defined: vec![true; r.values.len()],
            values: r.values,
            std_error: r.std_error,
            rays: r.rays,
        }
    }

    const PER_PART: &'static [bool] = &[false];

    fn render_cached(world: &Self::W, method: CacheMethod, _per_part: bool, threads: usize) -> CachedRun {
        use volume::cached::{CacheSettings, CachedRenderParams, RecordMemo, default_eps, render_cached};
        let mut p = CachedRenderParams::from_scene(world);
        (p.image.width, p.image.height, p.image.spp, p.image.seed) = (20, 20, 2, 7);
        (p.march_step, p.surface_paths) = (world.scale / 48.0, 1);
        let paths = volume::render::RenderParams::from_scene(world).first_vertex_settings();
        let mut cs = CacheSettings::new::<D3>(method, default_eps(method, world), paths);
        (cs.probe.rays, cs.probe.steps, cs.seed) = (256, 8, 3);
        let r = with_threads(threads, || {
            render_cached(world, &p, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap()
        });
        let records: Vec<_> = r.placement.caches.iter().map(|c| c.records().to_vec()).collect();
        CachedRun {
            records: format!("{records:?}"),
            record_count: r.placement.record_count(),
            uncovered: r.reconstruction.uncovered as usize,
            defined: vec![true; r.reconstruction.image.values.len()],
            values: r.reconstruction.image.values,
        }
    }
}

/// A 2D scene's field parameters (its own), its `spp` reference field (seed 99,
/// apart from the methods' seeds) and that reference's squared rms noise.
pub fn reference_2d(
    scene: &volcache::flatland::scene::Scene,
    spp: u32,
) -> (flatland::field::FieldParams, flatland::field::Field, f64) {
    let fp = flatland::field::FieldParams::from_scene(scene);
    let reference = flatland::field::render_field(
        scene,
        &flatland::field::FieldParams {
            spp,
            seed: 99,
            ..fp.clone()
        },
        &Progress::new(),
    )
    .unwrap();
    let noise = reference.rms_std_error().powi(2);
    println!("reference rms std error {:.3e}", noise.sqrt());
    (fp, reference.field, noise)
}

/// A point light beside a tilted plate in thick, forward-scattering fog (σ_t = 3,
/// g = 0.8) over a floor: a 2D scene where one light field's records are noisy
/// (`gradient_noise.rs`, `record_noise.rs`).
pub fn noisy_fog_2d() -> volcache::flatland::scene::Scene {
    let json = r#"{
  "domain": {"min": [-1, -1], "max": [1, 1]},
  "segments": [
    {"name": "floor", "a": [-1, -0.85], "b": [1, -0.85], "reflectance": 0.5},
    {"name": "plate", "a": [-0.45, 0.35], "b": [0.2, 0.5], "reflectance": 0.6}
  ],
  "lights": [{"type": "point", "position": [0.15, 0.25], "intensity": 1.0}],
  "medium": {"sigma_a": 0.3, "sigma_s": 2.7, "g": 0.8, "region": "everywhere"},
  "render": {"resolution": [96, 96], "spp": 64, "seed": 1}
}"#;
    volcache::flatland::scene::Scene::from_json(json, "<noisy fog 2d>").unwrap_or_else(|e| panic!("{e}"))
}

/// A small square lamp hanging tilted in strongly forward-scattering fog over a
/// floor (`gradient_noise_reach.rs`, `gradient_noise.rs`).
pub const HANGING_LAMP_3D: &str = r#"{
  "camera": {"position": [0.3, 1.0, 3.2], "look_at": [0, 0.9, 0], "fov_deg": 40},
  "shapes": [
    {"quad": {"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}, "reflectance": 0.4},
    {"quad": {"origin": [-0.25, 1.3, -0.1], "u": [0.4, 0.1, 0], "v": [0, -0.25, 0.3]},
     "reflectance": 0, "emission": [20, 18, 14], "two_sided": true}
  ],
  "medium": {"sigma_a": 0.08, "sigma_s": 0.9, "g": 0.85, "region": {"box": {"min": [-1.5, 0, -1.5], "max": [1.5, 2, 1.5]}}},
  "render": {"resolution": [24, 18], "spp": 16, "seed": 1, "max_depth": 16}
}"#;

/// [`HANGING_LAMP_3D`], parsed.
pub fn hanging_lamp_3d() -> volcache::volume::scene::Scene {
    volcache::volume::scene::Scene::from_json(HANGING_LAMP_3D, "<hanging lamp 3d>", Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"))
}
