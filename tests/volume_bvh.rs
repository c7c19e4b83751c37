//! The 3D BVH returns exactly the brute-force closest hit and occlusion on
//! thousands of random rays, for a random triangle soup and for the shipped scenes;
//! and the ray-casting throughput is printed (run with --nocapture).

use glam::DVec3;
use std::path::Path;
use volcache::core::rng::Sampler;
use volcache::core::space::D3;
use volcache::pipeline::bvh::{Accel, Geometry};
use volcache::volume::mesh::{Hit, Triangle};
use volcache::volume::render::ray_cast_rate;
use volcache::volume::scene::Scene;

fn random_unit(s: &mut Sampler) -> DVec3 {
    let z = 1.0 - 2.0 * s.next_f64();
    let phi = std::f64::consts::TAU * s.next_f64();
    let r = (1.0 - z * z).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn brute_force(tris: &[Triangle], o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    for (i, t) in tris.iter().enumerate() {
        let far = best.map_or(t_max, |b| b.t);
        if let Some((t, u, v)) = t.intersect(o, d, t_min, far) {
            best = Some(Hit {
                t,
                prim: i as u32,
                u,
                v,
            });
        }
    }
    best
}

/// Same distance (bit for bit) and same triangle unless two triangles tie.
fn compare(tris: &[Triangle], rays: usize, lo: DVec3, hi: DVec3, seed: u64) -> usize {
    let bvh = Geometry::<D3, Triangle>::with_accel(tris.to_vec(), Accel::Bvh);
    let mut s = Sampler::new(seed, 0);
    let mut hits = 0;
    for k in 0..rays {
        let o = lo + (hi - lo) * DVec3::new(s.next_f64(), s.next_f64(), s.next_f64());
        let d = random_unit(&mut s);
        let t_max = if k % 3 == 0 {
            0.5 * (hi - lo).length() * s.next_f64()
        } else {
            f64::INFINITY
        };
        let a = bvh
            .closest_hit(o, d, 1e-9, t_max, None)
            .map(|(t, prim, u, v)| Hit { t, prim, u, v });
        let b = brute_force(tris, o, d, 1e-9, t_max);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert_eq!(a.t, b.t, "ray {k}: {a:?} vs {b:?}");
                hits += 1;
            }
            _ => panic!("ray {k} from {o} along {d}: BVH {a:?}, brute force {b:?}"),
        }
        assert_eq!(bvh.occluded(o, d, 1e-9, t_max, None), b.is_some(), "ray {k}");
        // Skipping the hit triangle gives the next hit along the ray.
        if let Some(b) = b {
            let next = bvh.closest_hit(o, d, 1e-9, t_max, Some(b.prim));
            let others: Vec<Triangle> = tris
                .iter()
                .enumerate()
                .filter(|(i, _)| *i as u32 != b.prim)
                .map(|(_, t)| *t)
                .collect();
            assert_eq!(next.map(|h| h.0), brute_force(&others, o, d, 1e-9, t_max).map(|h| h.t));
        }
    }
    hits
}

#[test]
fn bvh_matches_brute_force_on_a_random_soup() {
    let mut s = Sampler::new(7, 0);
    let tris: Vec<Triangle> = (0..3000)
        .filter_map(|_| {
            let c = DVec3::new(s.next_f64(), s.next_f64(), s.next_f64()) * 10.0;
            let size = 0.05 + 0.6 * s.next_f64();
            let mut p = || c + random_unit(&mut s) * size;
            Triangle::new(p(), p(), p(), 0)
        })
        .collect();
    let hits = compare(&tris, 4000, DVec3::splat(-1.0), DVec3::splat(11.0), 8);
    assert!(hits > 1000, "only {hits} rays hit: the test would be toothless");
}

#[test]
fn bvh_matches_brute_force_on_the_shipped_scenes() {
    for name in ["fog_box", "staircase", "mesh_in_fog"] {
        let scene = Scene::load(Path::new(&format!("scenes3d/{name}.json"))).unwrap();
        let hits = compare(&scene.geometry.prims, 3000, scene.bounds.min, scene.bounds.max, 9);
        assert!(hits > 500, "{name}: only {hits} hits");
        let rate = ray_cast_rate(&scene, 200_000, 1);
        eprintln!(
            "{name}: {} triangles, {:.2} M closest-hit rays/s on {} threads",
            scene.geometry.len(),
            rate / 1e6,
            rayon::current_num_threads()
        );
    }
}
