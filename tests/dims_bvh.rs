//! The BVH over each dimension's own primitives (segments, triangles) answers as a
//! brute-force scan on random rays, for a random soup and for the shipped scenes,
//! written once and run in 2D and in 3D (the BVH itself is tested on balls in any
//! dimension in `pipeline::bvh`).

mod common;

use common::{Fixture, with_threads};
use volcache::core::rng::Sampler;
use volcache::core::space::{D2, D3};
use volcache::pipeline::bvh::{Accel, Geometry, Primitive};

const T_MIN: f64 = 1e-9;

/// The closest hit among `prims` but `skip`: (t, primitive).
fn brute_force<F: Fixture>(
    prims: &[F::Prim],
    o: F::Vec,
    d: F::Vec,
    t_max: f64,
    skip: Option<u32>,
) -> Option<(f64, u32)> {
    let mut best: Option<(f64, u32)> = None;
    for (i, p) in prims.iter().enumerate().filter(|(i, _)| Some(*i as u32) != skip) {
        let far = best.map_or(t_max, |b| b.0);
        if let Some((t, _, _)) = p.intersect(o, d, T_MIN, far) {
            best = Some((t, i as u32));
        }
    }
    best
}

/// Random rays from the box [lo, hi] (a third of them with a finite t_max): the
/// BVH and the flat list give the brute-force distance bit for bit, the same
/// occlusion, and skipping the hit primitive gives the next hit. Returns the hits.
fn compare<F: Fixture>(prims: &[F::Prim], rays: usize, lo: F::Vec, hi: F::Vec, seed: u64) -> usize {
    let geometries = [Accel::Bvh, Accel::Linear].map(|a| Geometry::<F, F::Prim>::with_accel(prims.to_vec(), a));
    let mut s = Sampler::new(seed, F::DIM as u64);
    let mut hits = 0;
    for k in 0..rays {
        let o = (0..F::DIM).fold(F::zero(), |v, i| {
            v + F::axis(i) * (lo[i] + (hi[i] - lo[i]) * s.next_f64())
        });
        let d = F::sample_uniform(&mut s);
        let t_max = if k % 3 == 0 {
            0.5 * F::length(hi - lo) * s.next_f64()
        } else {
            f64::INFINITY
        };
        let want = brute_force::<F>(prims, o, d, t_max, None);
        for g in &geometries {
            let got = g.closest_hit(o, d, T_MIN, t_max, None);
            assert_eq!(
                got.map(|h| h.0),
                want.map(|w| w.0),
                "ray {k} from {o:?} along {d:?}: {got:?} vs {want:?}"
            );
            assert_eq!(g.occluded(o, d, T_MIN, t_max, None), want.is_some(), "ray {k}");
        }
        let Some((_, first)) = want else { continue };
        hits += 1;
        let next = brute_force::<F>(prims, o, d, t_max, Some(first));
        for g in &geometries {
            let got = g.closest_hit(o, d, T_MIN, t_max, Some(first));
            assert_eq!(got.map(|h| h.0), next.map(|w| w.0), "ray {k} skipping {first}");
            assert_eq!(
                g.occluded(o, d, T_MIN, t_max, Some(first)),
                next.is_some(),
                "ray {k} skipping {first}"
            );
        }
    }
    hits
}

fn bvh_matches_brute_force<F: Fixture>() {
    let mut s = Sampler::new(7, 0);
    let soup: Vec<F::Prim> = (0..3000).filter_map(|_| F::random_prim(&mut s)).collect();
    let hits = compare::<F>(&soup, 4000, F::splat(-1.0), F::splat(11.0), 8);
    eprintln!("{}D soup of {}: {hits} of 4000 rays hit", F::DIM, soup.len());
    assert!(
        hits > 1000,
        "{}D: only {hits} rays hit: the test would be toothless",
        F::DIM
    );
    for common::Shipped { name, world, lo, hi } in F::shipped() {
        let prims = F::prims(&world);
        let hits = compare::<F>(prims, 3000, lo, hi, 9);
        eprintln!(
            "{}D {name}: {} primitives, {hits} of 3000 rays hit",
            F::DIM,
            prims.len()
        );
        assert!(hits > 500, "{}D {name}: only {hits} hits", F::DIM);
    }
}

#[test]
fn bvh_matches_brute_force_2d() {
    bvh_matches_brute_force::<D2>();
}

#[test]
fn bvh_matches_brute_force_3d() {
    bvh_matches_brute_force::<D3>();
}

/// The parallel build gives the same tree, bit for bit, on 1, 2 and 3 threads: for
/// soups of 100,000 random primitives (large enough to bin in parallel chunks and
/// to build subtrees as tasks) and for the ray benchmark's 158,802-triangle sphere.
fn build_independent_of_threads<F: Fixture>(extra: Vec<F::Prim>) {
    let mut s = Sampler::new(17, 0);
    let soup: Vec<F::Prim> = (0..100_000).filter_map(|_| F::random_prim(&mut s)).collect();
    for (name, prims) in [("soup", soup), ("extra", extra)] {
        if prims.is_empty() {
            continue;
        }
        let hashes: Vec<u64> = [1, 2, 3]
            .map(|t| {
                with_threads(t, || {
                    Geometry::<F, F::Prim>::with_accel(prims.clone(), Accel::Bvh).layout_hash()
                })
            })
            .to_vec();
        assert!(
            hashes.iter().all(|h| *h == hashes[0]),
            "{}D {name}: {hashes:x?}",
            F::DIM
        );
    }
}

#[test]
fn build_independent_of_threads_2d() {
    build_independent_of_threads::<D2>(Vec::new());
}

#[test]
fn build_independent_of_threads_3d() {
    build_independent_of_threads::<D3>(volcache::volume::mesh::uv_sphere(200, 399, 0));
}
