//! Equal-count comparisons (theory.md §8): search the error threshold ε until a
//! method places a target number of records. Placement is monotone in ε only on
//! average: a record placed earlier changes what later points see, so the count can
//! jump by ±50% within 1% of ε (seen with Jarosz 2008's noisy gradient balls in 3D).
//! This brackets the target in log ε, bisects, and if the bisection ends outside the
//! tolerance, probes ε around the best attempt — a few tenths of a percent apart
//! close to it, then a percent apart out to ±15% — keeping the closest.

/// Relative offsets of the probes around the bisection's best ε, nearest first,
/// alternating sides: 0.3% apart out to ±3.6%, then 1% apart out to ±15%.
fn probe_offsets() -> impl Iterator<Item = f64> {
    let near = (1..=12).map(|k| 0.003 * k as f64);
    let far = (4..=15).map(|k| 0.01 * k as f64);
    near.chain(far).flat_map(|d| [d, -d])
}

/// Search ε from `eps0` until `place(ε)` reports within ±`tol` of `target` records
/// (or the bracket closes): returns the closest attempt's result and its ε. More
/// records for smaller ε. `place` returns (record count, result).
pub fn search_eps<T, E>(
    target: usize,
    tol: f64,
    eps0: f64,
    mut place: impl FnMut(f64) -> Result<(usize, T), E>,
) -> Result<(T, f64), E> {
    let miss = |n: usize| (n as f64 - target as f64).abs();
    let (mut lo, mut hi) = (eps0, eps0);
    let mut best = place(eps0)?;
    let mut best_eps = eps0;
    let (mut n_lo, mut n_hi) = (best.0, best.0);
    // Bracket: ε too large gives too few records, too small too many.
    for _ in 0..40 {
        if n_lo >= target {
            break;
        }
        lo /= 4.0;
        let r = place(lo)?;
        n_lo = r.0;
        if miss(r.0) < miss(best.0) {
            (best, best_eps) = (r, lo);
        }
    }
    for _ in 0..40 {
        if n_hi <= target {
            break;
        }
        hi *= 4.0;
        let r = place(hi)?;
        n_hi = r.0;
        if miss(r.0) < miss(best.0) {
            (best, best_eps) = (r, hi);
        }
    }
    for _ in 0..40 {
        if miss(best.0) <= tol {
            break;
        }
        let mid = (lo * hi).sqrt();
        let r = place(mid)?;
        if r.0 > target {
            lo = mid;
        } else {
            hi = mid;
        }
        if miss(r.0) < miss(best.0) {
            (best, best_eps) = (r, mid);
        }
        if hi / lo < 1.0 + 1e-9 {
            break;
        }
    }
    let centre = best_eps;
    for d in probe_offsets() {
        if miss(best.0) <= tol {
            break;
        }
        let eps = centre * (1.0 + d);
        let r = place(eps)?;
        if miss(r.0) < miss(best.0) {
            (best, best_eps) = (r, eps);
        }
    }
    Ok((best.1, best_eps))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A monotone staircase count(ε) = floor(1000/ε): the search lands within the
    /// tolerance from far above or below, and reports the ε it used.
    #[test]
    fn finds_the_target_from_either_side() {
        for eps0 in [1e-6, 0.3, 5.0, 1e6] {
            let mut calls = 0;
            let (n, eps) = search_eps::<usize, ()>(200, 2.0, eps0, |e| {
                calls += 1;
                let n = (1000.0 / e).floor().min(1e9) as usize;
                Ok((n, n))
            })
            .unwrap();
            assert!((n as f64 - 200.0).abs() <= 2.0, "eps0 {eps0}: {n} records at ε {eps}");
            assert_eq!(n, (1000.0 / eps).floor() as usize);
            assert!(calls < 80, "{calls} placements");
        }
    }

    /// A count that jumps across the target (200 below ε = 1, 20 above) but for a
    /// narrow window just above the jump: bisection closes in on the jump without
    /// seeing the window; the probes around its best attempt find it.
    #[test]
    fn probes_around_the_best_find_a_narrow_window() {
        let count = |e: f64| match e {
            e if e < 1.0 => 200,
            e if (1.005..1.0075).contains(&e) => 80,
            _ => 20,
        };
        let (n, eps) = search_eps::<usize, ()>(80, 1.0, 1.0, |e| Ok((count(e), count(e)))).unwrap();
        assert_eq!(n, 80, "ε {eps}");
    }

    #[test]
    fn errors_stop_the_search() {
        let r = search_eps::<(), &str>(10, 1.0, 1.0, |_| Err("cancelled"));
        assert_eq!(r, Err("cancelled"));
    }
}
