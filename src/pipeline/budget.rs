//! One budget parameter for a radiance cache: a budget B (1 = the reference point
//! below, 4 = four times its cost) decides the error threshold ε and the rays of
//! each record, so that a user who wants a better image asks for more budget and
//! the schedule spends it where the error model says it pays.
//!
//! The error model (measured with `volcache caches` at 64², ours, seeds 1–2,
//! ε 0.1 … 0.00625, 256 / 1024 / 4096 rays; numbers in the commit):
//! - records K ∝ ε^−q with q ≈ 0.5 (occluder 0.49–0.52, windows 0.49–0.56), and
//!   the placement's time ∝ K · rays (0.46–0.54 against ε);
//! - the interpolation error ∝ ε^p with p ≈ 0.3 (occluder 0.24–0.37, windows
//!   0.24–0.30);
//! - the records' noise ∝ rays^−½ (Monte Carlo).
//!
//! Minimising E² = A ε^{2p} + C / rays at a cost T ∝ ε^−q · rays gives
//! ε ∝ T^{−1/(2p+q)}, rays ∝ T^{2p/(2p+q)}, and an error falling as
//! T^{−p/(2p+q)} ≈ T^−0.27 (the two error terms in the ratio q : 2p). B = 1 is a
//! point where the grid measured both terms alike: ε = 0.025 with 256 rays (at
//! ε ≤ 0.0125 more rays began to pay, above it they did not).

/// Exponent of the interpolation error in ε (see the module's model).
pub const ERROR_EXPONENT_P: f64 = 0.3;
/// Exponent of the record count in 1/ε.
pub const COUNT_EXPONENT_Q: f64 = 0.5;
/// ε at budget 1.
pub const EPS_AT_ONE: f64 = 0.025;
/// Rays per record at budget 1.
pub const RAYS_AT_ONE: f64 = 256.0;
/// The smallest budget (ε ≈ 0.31, 56 rays per record: below, records are noise).
pub const MIN_BUDGET: f64 = 1.0 / 16.0;
/// The largest budget (ε ≈ 1.3·10^−5, ≈ 23,000 rays per record).
pub const MAX_BUDGET: f64 = 4096.0;

/// What a budget sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    pub eps: f64,
    pub rays: usize,
}

/// The schedule of budget `b` (in [`MIN_BUDGET`], [`MAX_BUDGET`]; callers check).
pub fn schedule(b: f64) -> Schedule {
    let b = b.clamp(MIN_BUDGET, MAX_BUDGET);
    let denom = 2.0 * ERROR_EXPONENT_P + COUNT_EXPONENT_Q;
    let eps = EPS_AT_ONE * b.powf(-1.0 / denom);
    // At least 56 directions: the budget is clamped.
    let rays = (RAYS_AT_ONE * b.powf(2.0 * ERROR_EXPONENT_P / denom)).round() as usize;
    Schedule { eps, rays }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_one_is_the_reference_point_and_cost_grows_with_the_budget() {
        let s = schedule(1.0);
        assert_eq!((s.eps, s.rays), (EPS_AT_ONE, RAYS_AT_ONE as usize));
        // The model's cost K · rays ∝ ε^−q · rays grows as the budget (rays rounded).
        for b in [MIN_BUDGET, 0.25, 4.0, 16.0, MAX_BUDGET] {
            let s = schedule(b);
            let cost = (s.eps / EPS_AT_ONE).powf(-COUNT_EXPONENT_Q) * s.rays as f64 / RAYS_AT_ONE;
            assert!((cost / b - 1.0).abs() < 0.02, "budget {b}: model cost {cost}");
        }
    }

    #[test]
    fn the_schedule_is_monotone() {
        let mut last = schedule(MIN_BUDGET);
        for k in 1..=32 {
            let s = schedule(MIN_BUDGET * 2f64.powf(k as f64 * 0.5));
            assert!(s.eps < last.eps && s.rays >= last.rays, "{s:?} after {last:?}");
            last = s;
        }
    }
}
