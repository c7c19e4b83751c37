//! Multiple importance sampling weights, shared by the 2D and 3D path tracers.

/// Power heuristic (β = 2) weight of strategy `a` against `b`, given their pdfs;
/// a delta-like (infinite) `a` takes everything, two zero pdfs give zero.
#[inline]
pub fn power_heuristic(a: f64, b: f64) -> f64 {
    if a.is_infinite() {
        return 1.0;
    }
    if a <= 0.0 {
        return 0.0;
    }
    // As 1 / (1 + (b/a)²): squaring tiny or huge pdfs would underflow or overflow.
    let r = b / a;
    1.0 / (1.0 + r * r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_handle_extremes() {
        for (a, b) in [(1.0, 3.0), (1e-300, 1e-300), (5.0, 0.0), (1e200, 3e200)] {
            assert!((power_heuristic(a, b) + power_heuristic(b, a) - 1.0).abs() < 1e-12);
        }
        assert_eq!(power_heuristic(f64::INFINITY, 1.0), 1.0);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    }
}
