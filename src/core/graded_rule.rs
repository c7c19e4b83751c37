//! Radon's degree-5 rule on a triangle, alone or on bands where the distance from
//! a point halves (for triangles seen at a grazing angle), and Gauss–Legendre's
//! five points on a segment.

/// Gauss–Legendre on [0, 1], 5 points (exact for degree 9): nodes, weights.
pub const GAUSS5: [(f64, f64); 5] = [
    (0.046_910_077_030_668, 0.118_463_442_528_094_5),
    (0.230_765_344_947_158_5, 0.239_314_335_249_683_2),
    (0.5, 0.284_444_444_444_444_4),
    (0.769_234_655_052_841_5, 0.239_314_335_249_683_2),
    (0.953_089_922_969_332, 0.118_463_442_528_094_5),
];

/// Radon's 7-point rule on a triangle, exact for polynomials of degree 5:
/// barycentric points and weights (summing to 1).
pub const RADON7: [([f64; 3], f64); 7] = {
    const A1: f64 = 0.059_715_871_789_770;
    const B1: f64 = 0.470_142_064_105_115;
    const W1: f64 = 0.132_394_152_788_506;
    const A2: f64 = 0.797_426_985_353_087;
    const B2: f64 = 0.101_286_507_323_456;
    const W2: f64 = 0.125_939_180_544_827;
    [
        ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
        ([A1, B1, B1], W1),
        ([B1, A1, B1], W1),
        ([B1, B1, A1], W1),
        ([A2, B2, B2], W2),
        ([B2, A2, B2], W2),
        ([B2, B2, A2], W2),
    ]
};

/// Quadrature nodes (barycentric point, weight; the weights sum to 1) over a
/// triangle element whose vertices lie at distances `r` from x, for
/// `pipeline::slide::mean_over_directions` and `core::lobe_boundary`: Radon's 7-point rule where the distances differ by
/// at most 2×, else the rule on each band between the level lines where the
/// distance halves. The point a direction meets lies at |p| / Σ(b_k / r_k) from
/// x, whose denominator is linear in the barycentric coordinates: its level
/// lines are straight. A grazing element below an emitter spans distances from
/// ≈ 20 d to the emitter's edge (10⁴ times more at d = 1e-5); seven points saw
/// only its near part and missed the transmittance's share of the gradient,
/// ∫ T′(r)/r dr over the grazing directions, which grows as ln(1/d) (at σ_s = 1
/// the gradient grows by 1.5 ln 10 a decade of d below an emitter of radiance 3,
/// `tests/near_surface_3d.rs`).
pub fn graded_nodes(r: [f64; 3]) -> Vec<([f64; 3], f64)> {
    let w = r.map(|r| 1.0 / r);
    let (lo, hi) = (
        w.iter().copied().fold(f64::INFINITY, f64::min),
        w.iter().copied().fold(0.0, f64::max),
    );
    if !(lo > 0.0 && hi.is_finite()) || hi <= 2.0 * lo {
        return RADON7.to_vec();
    }
    let level = |b: &[f64; 3]| b[0] * w[0] + b[1] * w[1] + b[2] * w[2];
    // The part of a convex polygon (barycentric points) where the level is ≥ `at`
    // (`above`) or ≤ it.
    let clip = |poly: &[[f64; 3]], at: f64, above: bool| -> Vec<[f64; 3]> {
        let keep = |b: &[f64; 3]| if above { level(b) >= at } else { level(b) <= at };
        let mut out = Vec::with_capacity(poly.len() + 1);
        for k in 0..poly.len() {
            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
            if keep(&p) {
                out.push(p);
            }
            if keep(&p) != keep(&q) {
                let t = (at - level(&p)) / (level(&q) - level(&p));
                out.push(std::array::from_fn(|i| p[i] + (q[i] - p[i]) * t));
            }
        }
        out
    };
    // Twice the area of a barycentric triangle, as a share of the whole one's.
    let area = |a: &[f64; 3], b: &[f64; 3], c: &[f64; 3]| {
        ((b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1])).abs()
    };
    let whole = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut nodes = Vec::new();
    // At most 64 bands (distance ratios beyond 2^64 take one more for the rest).
    let mut from = lo;
    for band in 0..64 {
        let to = if band == 63 { hi } else { (2.0 * from).min(hi) };
        let piece = clip(&clip(&whole, from, true), to, false);
        for k in 1..piece.len().saturating_sub(1) {
            let (a, b, c) = (piece[0], piece[k], piece[k + 1]);
            let share = area(&a, &b, &c);
            for (z, wt) in RADON7 {
                let point = std::array::from_fn(|i| a[i] * z[0] + b[i] * z[1] + c[i] * z[2]);
                nodes.push((point, wt * share));
            }
        }
        if to >= hi {
            break;
        }
        from = to;
    }
    nodes
}
