//! Radiance-cache placement through each dimension's entry points (2D cached
//! fields, 3D cached images), written once and run in 2D and in 3D (theory.md §8):
//! no query point is left uncovered, and the records and the reconstruction are the
//! same bit for bit with one and two threads.

mod common;

use common::Fixture;
use volcache::core::metric::CacheMethod;
use volcache::core::space::{D2, D3};

fn hole_free_and_thread_independent<F: Fixture>() {
    let (s, _) = F::fog_scene();
    for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        for &per_part in F::PER_PART {
            let what = format!("{}D {method:?} per_part = {per_part}", F::DIM);
            let (a, b) = (
                F::render_cached(&s, method, per_part, 1),
                F::render_cached(&s, method, per_part, 2),
            );
            eprintln!("{what}: {} records", a.record_count);
            assert_eq!(a.uncovered, 0, "{what}: holes");
            assert!(a.record_count > 5, "{what}: {} records", a.record_count);
            assert_eq!(a.records, b.records, "{what}: records differ between 1 and 2 threads");
            assert_eq!(a.values, b.values, "{what}: values differ between 1 and 2 threads");
            assert_eq!(a.defined, b.defined, "{what}");
            assert!(
                a.values.iter().all(|v| v.is_finite() && v.min_element() >= 0.0),
                "{what}"
            );
            assert!(a.values.iter().any(|v| v.max_element() > 0.0), "{what}");
        }
    }
}

#[test]
fn hole_free_and_thread_independent_2d() {
    hole_free_and_thread_independent::<D2>();
}

#[test]
fn hole_free_and_thread_independent_3d() {
    hole_free_and_thread_independent::<D3>();
}
