//! A record's visibility tests from its listed occluders (`pipeline::sight`) give
//! the full ray cast's answer, in 2D and 3D, on scenes of our own: a soup of
//! rotated boxes (BVH) and a flatland forest of random segments, for random
//! records (random orientations and radii from 0.2% of the scene to a fifth of it) and
//! points of their extents, near the extent's boundary too, and from points
//! lifted off as the surface cache lifts them. Any disagreement would let a
//! record extrapolate across a surface (or refuse a point it sees).

use std::path::Path;
use volcache::core::metric::Extent;
use volcache::core::rng::Sampler;
use volcache::core::space::{D2, D3, Space};
use volcache::pipeline::dim::Dim;
use volcache::pipeline::sight::{Near, near_record, sees_near};
use volcache::pipeline::world::World;

/// A random orthonormal frame: Gram–Schmidt on random vectors.
fn random_axes<S: Dim>(s: &mut Sampler) -> S::Mat {
    let mut cols: Vec<S::Vec> = Vec::new();
    while cols.len() < S::DIM {
        let mut v = (0..S::DIM).fold(S::zero(), |v, i| v + S::axis(i) * (2.0 * s.next_f64() - 1.0));
        for c in &cols {
            v = v - *c * S::dot(v, *c);
        }
        let l = S::length(v);
        if l > 0.1 {
            cols.push(v / l);
        }
    }
    // The matrix whose column k is cols[k].
    (0..S::DIM).fold(S::zero_mat(), |m, k| m + S::outer(cols[k], S::axis(k)))
}

/// Counts of (Clear, Few, Many) records and of points that some occluder hides.
#[derive(Debug, Default)]
struct Tally {
    kinds: [usize; 3],
    hidden: usize,
    tests: usize,
    /// Points just behind a surface tested.
    behind: usize,
}

/// `records` random records in the box [lo, hi], 8 points of each extent and up
/// to 8 just behind the surfaces it holds: the listed occluders and the ray cast
/// agree on every one.
fn agree<W: World>(world: &W, lo: <W::S as Space>::Vec, hi: <W::S as Space>::Vec, records: usize, seed: u64) -> Tally {
    let mut s = Sampler::new(seed, 0);
    let scale = world.scale();
    let mut tally = Tally::default();
    let uniform = |s: &mut Sampler| {
        (0..W::S::DIM).fold(<W::S as Space>::zero(), |v, i| {
            v + <W::S as Space>::axis(i) * (lo[i] + (hi[i] - lo[i]) * s.next_f64())
        })
    };
    for _ in 0..records {
        let x = uniform(&mut s);
        let radii = (0..W::S::DIM).fold(<W::S as Space>::zero(), |v, i| {
            v + <W::S as Space>::axis(i) * (scale * 0.002 * 100f64.powf(s.next_f64()))
        });
        let extent = Extent::<W::S> {
            axes: random_axes::<W::S>(&mut s),
            radii,
        };
        let near = near_record(world, x, &extent);
        tally.kinds[match near {
            Near::Clear => 0,
            Near::Few(_) => 1,
            Near::Many => 2,
        }] += 1;
        for k in 0..8 {
            // A point of the extent: a random direction in its frame, at a distance
            // d < 1 in its metric, the last ones next to its boundary.
            let dir = <W::S as Dim>::sample_uniform(&mut s);
            let d = if k < 4 {
                s.next_f64()
            } else {
                1.0 - 1e-9 * (1.0 + s.next_f64())
            };
            let local = (0..W::S::DIM).fold(<W::S as Space>::zero(), |v, i| {
                v + <W::S as Space>::axis(i) * (dir[i] * radii[i] * d)
            });
            let mut y = x + extent.axes * local;
            let mut from = x;
            if k % 2 == 1 {
                // Lifted as the surface cache lifts its ends (1e-6 scene sizes).
                let lift = 1e-6 * scale;
                from = x + <W::S as Dim>::sample_uniform(&mut s) * lift;
                y += <W::S as Dim>::sample_uniform(&mut s) * lift;
            }
            if !extent.contains(x, y) && k % 2 == 0 {
                continue; // rounding put it outside: not a point the record serves
            }
            let (mut r1, mut r2) = (0, 0);
            let listed = sees_near(world, &near, from, y, &mut r1);
            let cast = sees_near(world, &Near::Many, from, y, &mut r2);
            assert_eq!(listed, cast, "record at {x:?} ({near:?}) and {y:?}");
            tally.hidden += !cast as usize;
            tally.tests += 1;
        }
        // Points just behind the first surface along random directions, where it
        // lies in the extent: each hidden by one occluder, often near the boundary.
        for _ in 0..8 {
            let dir = <W::S as Dim>::sample_uniform(&mut s);
            let Some(hit) = world.closest_hit(x, dir, f64::INFINITY, None) else {
                continue;
            };
            let y = x + dir * (hit.t + 1e-7 * scale);
            if !extent.contains(x, y) {
                continue;
            }
            let (mut r1, mut r2) = (0, 0);
            let listed = sees_near(world, &near, x, y, &mut r1);
            let cast = sees_near(world, &Near::Many, x, y, &mut r2);
            assert_eq!(listed, cast, "record at {x:?} ({near:?}) and {y:?} behind a surface");
            tally.behind += 1;
        }
    }
    tally
}

/// 3D: 120 rotated boxes (1440 triangles, a BVH) in a unit room.
#[test]
fn listed_occluders_answer_as_the_ray_cast_in_3d() {
    let mut s = Sampler::new(11, 3);
    let boxes: Vec<String> = (0..120)
        .map(|_| {
            let c: Vec<f64> = (0..3).map(|_| 4.0 * s.next_f64() - 2.0).collect();
            let h: Vec<f64> = (0..3).map(|_| 0.02 + 0.25 * s.next_f64()).collect();
            format!(
                r#"{{"box": {{"min": [{}, {}, {}], "max": [{}, {}, {}], "rotate_y_deg": {}}}, "reflectance": 0.5}}"#,
                c[0] - h[0],
                c[1] - h[1],
                c[2] - h[2],
                c[0] + h[0],
                c[1] + h[1],
                c[2] + h[2],
                360.0 * s.next_f64()
            )
        })
        .collect();
    let json = format!(
        r#"{{"camera": {{"position": [0, 0, 6], "look_at": [0, 0, 0], "fov_deg": 50}},
            "shapes": [{}],
            "medium": {{"sigma_a": 0.1, "sigma_s": 0.5, "g": 0.0, "region": "everywhere"}},
            "render": {{"resolution": [8, 8], "spp": 1, "seed": 1, "max_depth": 8}}}}"#,
        boxes.join(",")
    );
    let scene = volcache::volume::scene::Scene::from_json(&json, "<box soup>", Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let t = agree(&scene, D3::splat(-2.3), D3::splat(2.3), 3000, 1);
    eprintln!("3D: {t:?}");
    // Discriminating: every kind of record occurs, and many points are hidden.
    assert!(t.kinds.iter().all(|&k| k >= 100), "{t:?}");
    assert!(t.hidden * 20 >= t.tests, "{t:?}");
}

/// 2D: 1000 random segments (a BVH) in the unit square.
#[test]
fn listed_occluders_answer_as_the_ray_cast_in_2d() {
    let mut s = Sampler::new(12, 2);
    let segments: Vec<String> = (0..1000)
        .map(|_| {
            let a = [2.0 * s.next_f64() - 1.0, 2.0 * s.next_f64() - 1.0];
            let angle = std::f64::consts::TAU * s.next_f64();
            let l = 0.01 + 0.1 * s.next_f64();
            format!(
                r#"{{"a": [{}, {}], "b": [{}, {}], "reflectance": 0.5}}"#,
                a[0],
                a[1],
                a[0] + l * angle.cos(),
                a[1] + l * angle.sin()
            )
        })
        .collect();
    let json = format!(
        r#"{{"domain": {{"min": [-1.0, -1.0], "max": [1.0, 1.0]}},
            "segments": [{}],
            "medium": {{"sigma_a": 0.1, "sigma_s": 0.9, "g": 0.0, "region": "everywhere"}},
            "render": {{"resolution": [8, 8], "spp": 1, "seed": 1}}}}"#,
        segments.join(",")
    );
    let scene =
        volcache::flatland::scene::Scene::from_json(&json, "<segment forest>").unwrap_or_else(|e| panic!("{e}"));
    let t = agree(&scene, D2::splat(-1.0), D2::splat(1.0), 3000, 2);
    eprintln!("2D: {t:?}");
    assert!(t.kinds.iter().all(|&k| k >= 100), "{t:?}");
    assert!(t.hidden * 20 >= t.tests, "{t:?}");
}
