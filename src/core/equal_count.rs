//! Equal-count comparisons (theory.md §8): search the error threshold ε until a
//! method places a target number of records. Placement is monotone in ε only on
//! average (a record placed earlier changes what later points see), so this brackets
//! the target in log ε, bisects, and keeps the closest attempt.

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

    #[test]
    fn errors_stop_the_search() {
        let r = search_eps::<(), &str>(10, 1.0, 1.0, |_| Err("cancelled"));
        assert_eq!(r, Err("cancelled"));
    }
}
