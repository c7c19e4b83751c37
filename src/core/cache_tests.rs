//! Tests of the cache: exact reconstruction of linear and quadratic fields, the
//! index against a linear scan, tent weights, coverage, and the documented
//! deterministic placement loop.

use super::*;
use crate::core::metric::{MetricParams, second_order_extent};
use crate::core::rng::Sampler;
use crate::core::space::{D2, D3};
use glam::{DMat2, DMat3, DVec2, DVec3};
use std::f64::consts::TAU;
use std::time::Instant;

fn rotation2(s: &mut Sampler) -> DMat2 {
    DMat2::from_angle(TAU * s.next_f64())
}

fn rotation3(s: &mut Sampler) -> DMat3 {
    let axis = DVec3::new(s.next_f64() - 0.5, s.next_f64() - 0.5, s.next_f64() - 0.5);
    DMat3::from_axis_angle(axis.normalize(), TAU * s.next_f64())
}

/// Log-uniform radius in [1e-3, 0.25] (the default r_min..r_max of a unit scene),
/// each axis up to 8× shorter than the longest.
fn radius(s: &mut Sampler) -> f64 {
    1e-3 * 250f64.powf(s.next_f64())
}

fn extent2(s: &mut Sampler) -> Extent<D2> {
    let r = radius(s);
    Extent {
        axes: rotation2(s),
        radii: DVec2::new(r, r / (1.0 + 7.0 * s.next_f64())),
    }
}

fn extent3(s: &mut Sampler) -> Extent<D3> {
    let r = radius(s);
    let mut k = || r / (1.0 + 7.0 * s.next_f64());
    let radii = DVec3::new(r, k(), k());
    Extent {
        axes: rotation3(s),
        radii,
    }
}

fn point2(s: &mut Sampler) -> DVec2 {
    DVec2::new(s.next_f64(), s.next_f64()) * 1.2 - DVec2::splat(0.1)
}

fn point3(s: &mut Sampler) -> DVec3 {
    DVec3::new(s.next_f64(), s.next_f64(), s.next_f64()) * 1.2 - DVec3::splat(0.1)
}

fn record<S: Space, V>(position: S::Vec, value: V, extent: Extent<S>) -> Record<S, V> {
    Record {
        position,
        value,
        extent,
        cost_rays: 7,
    }
}

fn linear_scan<S: Space, V>(c: &Cache<S, V>, y: S::Vec) -> Vec<(usize, f64)> {
    let all = c.records().iter().enumerate();
    all.map(|(i, r)| (i, r.weight(y))).filter(|&(_, w)| w > 0.0).collect()
}

/// The quadratic field f(y) = a + b·y + ½ yᵀAy as Taylor data at x.
fn quadratic<S: Space>(a: f64, b: S::Vec, m: S::Mat, x: S::Vec) -> Taylor2<S> {
    Taylor2::new(a + S::dot(b, x) + 0.5 * S::dot(x, m * x), b + m * x, m)
}

fn check_reconstruction<S: Space>(
    s: &mut Sampler,
    b: S::Vec,
    m: S::Mat,
    ext: impl Fn(&mut Sampler) -> Extent<S>,
    point: impl Fn(&mut Sampler) -> S::Vec,
) {
    let mut lin = Cache::<S, Taylor2<S>>::new();
    let mut quad = Cache::<S, [TaylorRgb<S>; 2]>::new();
    for _ in 0..400 {
        let (x, e) = (point(s), ext(s));
        lin.insert(record(x, quadratic(0.7, b, S::zero_mat(), x), e)).unwrap();
        let q = quadratic(0.7, b, m, x);
        let parts = [
            TaylorRgb::tint(q, Rgb::new(1.0, 0.5, 2.0)),
            TaylorRgb::tint(q, Rgb::splat(-3.0)),
        ];
        quad.insert(record(x, parts, e)).unwrap();
    }
    let (mut covered, mut first_order_err) = (0, 0.0f64);
    for _ in 0..4000 {
        let y = point(s);
        let exact_lin = 0.7 + S::dot(b, y);
        let exact = exact_lin + 0.5 * S::dot(y, m * y);
        let got = lin.interpolate(y, false);
        assert_eq!(got.is_some(), lin.is_covered(y));
        if let Some(v) = got {
            assert!((v - exact_lin).abs() < 1e-12, "linear: {v} vs {exact_lin}");
            // The linear field's Hessian is zero: second order changes nothing.
            assert!((lin.interpolate(y, true).unwrap() - exact_lin).abs() < 1e-12);
        }
        if let Some([p, q]) = quad.interpolate(y, true) {
            covered += 1;
            assert!(
                (p - Rgb::new(1.0, 0.5, 2.0) * exact).abs().max_element() < 1e-12,
                "{p} vs {exact}"
            );
            assert!((q - Rgb::splat(-3.0) * exact).abs().max_element() < 1e-11);
            let [p1, _] = quad.interpolate(y, false).unwrap();
            first_order_err = first_order_err.max((p1.x - exact).abs());
        }
    }
    assert!(covered > 100, "too few covered queries: {covered}");
    assert!(first_order_err > 1e-6, "first order should not be exact on a quadratic");
}

#[test]
fn reconstruction_is_exact_for_linear_and_quadratic_fields() {
    let mut s = Sampler::new(21, 0);
    let m2 = DMat2::from_cols(DVec2::new(3.0, -1.0), DVec2::new(-1.0, 0.5));
    check_reconstruction::<D2>(&mut s, DVec2::new(2.0, -1.5), m2, extent2, point2);
    let m3 = DMat3::from_cols(
        DVec3::new(2.0, 0.5, -1.0),
        DVec3::new(0.5, -1.0, 0.3),
        DVec3::new(-1.0, 0.3, 4.0),
    );
    let ext3 = |s: &mut Sampler| {
        let mut e = extent3(s);
        e.radii *= 3.0; // fewer, larger records so that enough 3D queries are covered
        e
    };
    check_reconstruction::<D3>(&mut s, DVec3::new(1.0, 2.0, -0.5), m3, ext3, point3);
}

fn check_index<S: Space>(
    name: &str,
    s: &mut Sampler,
    n: usize,
    ext: impl Fn(&mut Sampler) -> Extent<S>,
    point: impl Fn(&mut Sampler) -> S::Vec,
) {
    let mut cache = Cache::<S, Taylor2<S>>::new();
    for i in 0..n {
        let x = point(s);
        assert_eq!(cache.insert(record(x, Taylor2::constant(1.0), ext(s))).unwrap(), i);
    }
    let queries: Vec<S::Vec> = (0..20_000).map(|_| point(s)).collect();
    let (mut hits, mut max_cover) = (0usize, 0usize);
    let t = Instant::now();
    let fast: Vec<Vec<(usize, f64)>> = queries.iter().map(|&y| cache.covering(y)).collect();
    let t_index = t.elapsed();
    let t = Instant::now();
    let slow: Vec<Vec<(usize, f64)>> = queries.iter().map(|&y| linear_scan(&cache, y)).collect();
    let t_scan = t.elapsed();
    let mut candidates = 0usize;
    let t = Instant::now();
    for y in &queries {
        cache
            .index
            .for_candidates(to_array::<S>(*y), S::DIM, |_| candidates += 1);
    }
    eprintln!("candidates only {:?}", t.elapsed());
    let t = Instant::now();
    let mut buf = Vec::new();
    let mut nn = 0;
    for y in &queries {
        cache.covering_into(*y, &mut buf);
        nn += buf.len();
    }
    eprintln!("covering_into {:?} {nn}", t.elapsed());
    for ((y, f), l) in queries.iter().zip(&fast).zip(&slow) {
        assert_eq!(f, l, "index and linear scan differ at {y:?}");
        assert_eq!(cache.is_covered(*y), !f.is_empty());
        assert!(f.iter().all(|&(_, w)| w > 0.0 && w <= 1.0));
        hits += !f.is_empty() as usize;
        max_cover = max_cover.max(f.len());
    }
    // Record centres are covered with weight exactly 1.
    for (i, r) in cache.records().iter().enumerate().take(500) {
        assert!(cache.covering(r.position).contains(&(i, 1.0)));
    }
    assert!(hits > queries.len() / 10, "{name}: too few covered queries ({hits})");
    eprintln!(
        "{name}: {n} records, {} index entries, {hits}/{} queries covered (max {max_cover} records, \
         {:.1} candidates per query): index {t_index:?}, linear scan {t_scan:?} ({:.0}x)",
        cache.index_entries(),
        queries.len(),
        candidates as f64 / queries.len() as f64,
        t_scan.as_secs_f64() / t_index.as_secs_f64().max(1e-9)
    );
}

#[test]
fn index_matches_linear_scan_2d() {
    check_index::<D2>("2D", &mut Sampler::new(22, 0), 5000, extent2, point2);
}

#[test]
fn index_matches_linear_scan_3d() {
    let ext = |s: &mut Sampler| {
        let mut e = extent3(s);
        e.radii *= 2.0;
        e
    };
    check_index::<D3>("3D", &mut Sampler::new(23, 0), 5000, ext, point3);
}

#[test]
fn index_handles_extreme_scales_and_positions() {
    let mut cache = Cache::<D2, Taylor2<D2>>::new();
    let cases = [
        (DVec2::new(1e12, -1e12), 1e-3),
        (DVec2::new(1e-300, 0.0), 1e-300),
        (DVec2::new(0.5, 0.5), 1e100),
        (DVec2::new(-3.0, 7.0), 5e-324),
        (DVec2::new(1e300, 1e300), 1e280),
    ];
    for &(x, r) in &cases {
        let e = Extent::isotropic(r);
        cache.insert(record(x, Taylor2::constant(2.0), e)).unwrap();
    }
    for (i, &(x, r)) in cases.iter().enumerate() {
        assert!(cache.covering(x).contains(&(i, 1.0)), "centre {i}");
        let near = x + DVec2::new(0.9 * r, 0.0);
        if near != x {
            assert_eq!(cache.covering(near), linear_scan(&cache, near), "near {i}");
        }
    }
    assert_eq!(
        cache.covering(DVec2::new(1e10, 1e10)),
        linear_scan(&cache, DVec2::new(1e10, 1e10))
    );
    assert!(!cache.is_covered(DVec2::NAN) && cache.interpolate(DVec2::INFINITY, false).is_none());
}

#[test]
fn insert_refuses_invalid_records() {
    let mut c = Cache::<D2, TaylorRgb<D2>>::new();
    let v = TaylorRgb::constant(Rgb::ONE);
    let e = Extent::isotropic(0.1);
    assert_eq!(c.insert(record(DVec2::NAN, v, e)), Err(CacheError::NonFinitePosition));
    let nan = TaylorRgb::constant(Rgb::new(1.0, f64::NAN, 0.0));
    assert_eq!(c.insert(record(DVec2::ZERO, nan, e)), Err(CacheError::NonFiniteValue));
    for radii in [
        DVec2::new(0.0, 1.0),
        DVec2::new(-1.0, 1.0),
        DVec2::new(f64::INFINITY, 1.0),
    ] {
        let bad = Extent {
            axes: DMat2::IDENTITY,
            radii,
        };
        assert_eq!(c.insert(record(DVec2::ZERO, v, bad)), Err(CacheError::InvalidExtent));
    }
    let skew = Extent {
        axes: DMat2::from_cols(DVec2::X, DVec2::new(1.0, 1.0)),
        radii: DVec2::ONE,
    };
    assert_eq!(c.insert(record(DVec2::ZERO, v, skew)), Err(CacheError::InvalidExtent));
    let huge = Extent::isotropic(1e308);
    assert_eq!(c.insert(record(DVec2::ZERO, v, huge)), Err(CacheError::TooLarge));
    assert!(c.is_empty() && c.interpolate(DVec2::ZERO, true).is_none());
    assert_eq!(c.insert(record(DVec2::ZERO, v, e)), Ok(0));
    assert_eq!((c.len(), c.cost_rays()), (1, 7));
    assert_eq!(c.interpolate(DVec2::new(0.05, 0.0), false), Some(Rgb::ONE));
}

#[test]
fn cache_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Cache<D2, [TaylorRgb<D2>; 2]>>();
    check::<Cache<D3, TaylorRgb<D3>>>();
}

/// The placement loop of the module docs on a grid of query points, with records
/// from the real metric on a synthetic field: no holes, and the same records with
/// 1 and 2 threads.
#[test]
fn documented_placement_is_deterministic_and_leaves_no_holes() {
    use rayon::prelude::*;
    let field = |y: DVec2| {
        let d = y - DVec2::new(0.5, 0.4);
        let t = Taylor2::<D2>::coordinate(y, 0) * 2.0 + Taylor2::constant(1.0);
        // A bump: value 1 + 2x + exp(−|d|²/0.02).
        let g = (-d.length_squared() / 0.02).exp();
        let grad = -d * (2.0 / 0.02) * g;
        let hess = (D2::outer(d, d) * (4.0 / 0.0004) - DMat2::IDENTITY * (2.0 / 0.02)) * g;
        t + Taylor2::new(g, grad, hess)
    };
    let params = MetricParams::scene_relative(1.0, 0.02);
    let n = 96;
    let queries: Vec<DVec2> = (0..n * n)
        .map(|i| DVec2::new((i % n) as f64 + 0.5, (i / n) as f64 + 0.5) / n as f64)
        .collect();
    let place = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut cache = Cache::<D2, Taylor2<D2>>::new();
            for batch in queries.chunks(64) {
                let uncovered: Vec<DVec2> = batch.par_iter().copied().filter(|&y| !cache.is_covered(y)).collect();
                let records: Vec<_> = uncovered
                    .par_iter()
                    .map(|&y| {
                        let t = field(y);
                        record(y, t, second_order_extent::<D2>(t.value, t.hess, t.grad, &params))
                    })
                    .collect();
                for (y, r) in uncovered.into_iter().zip(records) {
                    if !cache.is_covered(y) {
                        cache.insert(r).unwrap();
                    }
                }
            }
            cache
        })
    };
    let (one, two) = (place(1), place(2));
    assert_eq!(one.records(), two.records());
    assert!(queries.iter().all(|&y| one.interpolate(y, false).is_some()), "hole");
    let mut max_err = 0.0f64;
    for &y in &queries {
        max_err = max_err.max((one.interpolate(y, true).unwrap() - field(y).value).abs());
    }
    eprintln!(
        "placement: {} records for {} queries, max error {max_err:.2e}",
        one.len(),
        queries.len()
    );
    assert!(one.len() > 10 && one.len() < queries.len() / 4);
}
