//! The dimension abstraction shared by the 2D (flatland) and 3D derivative code.
//!
//! [`Space`] is implemented by the zero-sized markers [`D2`] and [`D3`]; its
//! associated `Vec`/`Mat` types are glam's `DVec2`/`DMat2` and `DVec3`/`DMat3`.
//! Matrices are column-major as in glam: `col(m, j)` is the j-th column.
//!
//! Constants (theory.md §1, §6): the measure of the unit sphere of directions
//! (2π in 2D, 4π in 3D) and the volume of the unit ball (π, 4π/3).
//!
//! [`Space::sym_eigen`] returns the eigenvalues of a symmetric matrix sorted
//! ascending and an orthonormal, right-handed matrix of eigenvectors (as columns),
//! even for repeated or zero eigenvalues (the cache extent of theory.md §6 needs
//! the axes in every case).

use glam::{DMat2, DMat3, DVec2, DVec3};
use std::f64::consts::{PI, TAU};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Index, Mul, Neg, Sub, SubAssign};

/// Vector and matrix operations the dimension-generic derivative code needs.
pub trait Space: Copy + Clone + Debug + Default + PartialEq + Send + Sync + 'static {
    type Vec: Copy
        + Debug
        + PartialEq
        + Send
        + Sync
        + Add<Output = Self::Vec>
        + Sub<Output = Self::Vec>
        + Neg<Output = Self::Vec>
        + Mul<f64, Output = Self::Vec>
        + Div<f64, Output = Self::Vec>
        + AddAssign
        + SubAssign
        + Index<usize, Output = f64>;
    type Mat: Copy
        + Debug
        + PartialEq
        + Send
        + Sync
        + Add<Output = Self::Mat>
        + Sub<Output = Self::Mat>
        + Neg<Output = Self::Mat>
        + Mul<f64, Output = Self::Mat>
        + Mul<Self::Vec, Output = Self::Vec>
        + Mul<Self::Mat, Output = Self::Mat>
        + AddAssign
        + SubAssign;

    /// The dimension d.
    const DIM: usize;
    /// Measure of the unit sphere of directions: 2π (circle) or 4π (sphere).
    const SPHERE_MEASURE: f64;
    /// Volume (area in 2D) of the unit ball: π or 4π/3.
    const BALL_VOLUME: f64;

    fn zero() -> Self::Vec;
    /// The i-th unit axis.
    fn axis(i: usize) -> Self::Vec;
    fn dot(a: Self::Vec, b: Self::Vec) -> f64;
    fn length_squared(a: Self::Vec) -> f64 {
        Self::dot(a, a)
    }
    fn length(a: Self::Vec) -> f64 {
        Self::length_squared(a).sqrt()
    }
    fn vec_is_finite(a: Self::Vec) -> bool;

    /// Outer product a bᵀ.
    fn outer(a: Self::Vec, b: Self::Vec) -> Self::Mat;
    fn identity() -> Self::Mat;
    fn zero_mat() -> Self::Mat;
    fn diagonal(v: Self::Vec) -> Self::Mat;
    fn transpose(m: Self::Mat) -> Self::Mat;
    fn col(m: Self::Mat, j: usize) -> Self::Vec;
    /// Entry at (row i, column j).
    fn entry(m: Self::Mat, i: usize, j: usize) -> f64 {
        Self::col(m, j)[i]
    }
    fn trace(m: Self::Mat) -> f64 {
        (0..Self::DIM).map(|i| Self::entry(m, i, i)).sum()
    }
    /// Frobenius norm.
    fn frobenius(m: Self::Mat) -> f64 {
        (0..Self::DIM)
            .map(|j| Self::length_squared(Self::col(m, j)))
            .sum::<f64>()
            .sqrt()
    }
    fn mat_is_finite(m: Self::Mat) -> bool;
    /// (M + Mᵀ)/2.
    fn symmetrize(m: Self::Mat) -> Self::Mat {
        (m + Self::transpose(m)) * 0.5
    }

    /// Eigen-decomposition of the symmetric part of `m`: eigenvalues ascending (as the
    /// components of a vector) and orthonormal right-handed eigenvectors as the columns
    /// of a matrix Q, with `m ≈ Q diag(λ) Qᵀ`. Non-finite input gives NaN eigenvalues
    /// and the identity.
    fn sym_eigen(m: Self::Mat) -> (Self::Vec, Self::Mat);
}

/// Flatland (d = 2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct D2;

/// Three dimensions (d = 3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct D3;

impl Space for D2 {
    type Vec = DVec2;
    type Mat = DMat2;
    const DIM: usize = 2;
    const SPHERE_MEASURE: f64 = TAU;
    const BALL_VOLUME: f64 = PI;

    fn zero() -> DVec2 {
        DVec2::ZERO
    }
    fn axis(i: usize) -> DVec2 {
        DVec2::AXES[i]
    }
    fn dot(a: DVec2, b: DVec2) -> f64 {
        a.dot(b)
    }
    fn vec_is_finite(a: DVec2) -> bool {
        a.is_finite()
    }
    fn outer(a: DVec2, b: DVec2) -> DMat2 {
        DMat2::from_cols(a * b.x, a * b.y)
    }
    fn identity() -> DMat2 {
        DMat2::IDENTITY
    }
    fn zero_mat() -> DMat2 {
        DMat2::ZERO
    }
    fn diagonal(v: DVec2) -> DMat2 {
        DMat2::from_diagonal(v)
    }
    fn transpose(m: DMat2) -> DMat2 {
        m.transpose()
    }
    fn col(m: DMat2, j: usize) -> DVec2 {
        m.col(j)
    }
    fn mat_is_finite(m: DMat2) -> bool {
        m.is_finite()
    }

    /// Closed form: λ = mean ± hypot((a − c)/2, b), eigenvector of the larger one at
    /// angle ½ atan2(b, (a − c)/2). No cancellation-prone discriminant, no division,
    /// and atan2(0, 0) = 0 gives the axes for m = c·I.
    fn sym_eigen(m: DMat2) -> (DVec2, DMat2) {
        if !m.is_finite() {
            return (DVec2::splat(f64::NAN), DMat2::IDENTITY);
        }
        let a = m.x_axis.x;
        let c = m.y_axis.y;
        let b = 0.5 * m.y_axis.x + 0.5 * m.x_axis.y;
        let mean = 0.5 * a + 0.5 * c;
        let half_diff = 0.5 * a - 0.5 * c;
        let r = half_diff.hypot(b);
        let (s, co) = (0.5 * b.atan2(half_diff)).sin_cos();
        // Columns (s, −c) then (c, s): orthonormal with determinant +1.
        let q = DMat2::from_cols(DVec2::new(s, -co), DVec2::new(co, s));
        (DVec2::new(mean - r, mean + r), q)
    }
}

impl Space for D3 {
    type Vec = DVec3;
    type Mat = DMat3;
    const DIM: usize = 3;
    const SPHERE_MEASURE: f64 = 4.0 * PI;
    const BALL_VOLUME: f64 = 4.0 * PI / 3.0;

    fn zero() -> DVec3 {
        DVec3::ZERO
    }
    fn axis(i: usize) -> DVec3 {
        DVec3::AXES[i]
    }
    fn dot(a: DVec3, b: DVec3) -> f64 {
        a.dot(b)
    }
    fn vec_is_finite(a: DVec3) -> bool {
        a.is_finite()
    }
    fn outer(a: DVec3, b: DVec3) -> DMat3 {
        DMat3::from_cols(a * b.x, a * b.y, a * b.z)
    }
    fn identity() -> DMat3 {
        DMat3::IDENTITY
    }
    fn zero_mat() -> DMat3 {
        DMat3::ZERO
    }
    fn diagonal(v: DVec3) -> DMat3 {
        DMat3::from_diagonal(v)
    }
    fn transpose(m: DMat3) -> DMat3 {
        m.transpose()
    }
    fn col(m: DMat3, j: usize) -> DVec3 {
        m.col(j)
    }
    fn mat_is_finite(m: DMat3) -> bool {
        m.is_finite()
    }

    fn sym_eigen(m: DMat3) -> (DVec3, DMat3) {
        sym_eigen3(m)
    }
}

/// Cyclic Jacobi on the symmetric part of `m`, scaled so its largest entry is 1
/// (no overflow or underflow in the rotations for huge or tiny matrices). Jacobi
/// rotations keep the eigenvectors orthonormal to rounding and handle repeated
/// eigenvalues without special cases; it converges quadratically (≈ 5 sweeps).
fn sym_eigen3(m: DMat3) -> (DVec3, DMat3) {
    if !m.is_finite() {
        return (DVec3::splat(f64::NAN), DMat3::IDENTITY);
    }
    let mut a = [[0.0f64; 3]; 3];
    let mut scale = 0.0f64;
    for (i, row) in a.iter_mut().enumerate() {
        for (j, e) in row.iter_mut().enumerate() {
            *e = 0.5 * m.col(j)[i] + 0.5 * m.col(i)[j];
            scale = scale.max(e.abs());
        }
    }
    if scale == 0.0 {
        return (DVec3::ZERO, DMat3::IDENTITY);
    }
    for e in a.iter_mut().flatten() {
        *e /= scale;
    }
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    // The Frobenius norm of the scaled matrix is in [1, 3]: dropping off-diagonal
    // entries below 1e-18 changes the reconstruction by far less than an ulp.
    const NEGLIGIBLE: f64 = 1e-18;
    for _sweep in 0..64 {
        if a[0][1].abs() <= NEGLIGIBLE && a[0][2].abs() <= NEGLIGIBLE && a[1][2].abs() <= NEGLIGIBLE {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq.abs() <= NEGLIGIBLE {
                a[p][q] = 0.0;
                a[q][p] = 0.0;
                continue;
            }
            // The rotation that zeroes a[p][q] (Numerical Recipes §11.1, smaller angle).
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = if theta.abs() > 1e150 {
                0.5 / theta
            } else {
                theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
            };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            a[p][p] -= t * apq;
            a[q][q] += t * apq;
            a[p][q] = 0.0;
            a[q][p] = 0.0;
            let r = 3 - p - q;
            let (arp, arq) = (a[r][p], a[r][q]);
            a[r][p] = c * arp - s * arq;
            a[p][r] = a[r][p];
            a[r][q] = s * arp + c * arq;
            a[q][r] = a[r][q];
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let lambda = DVec3::new(a[order[0]][order[0]], a[order[1]][order[1]], a[order[2]][order[2]]) * scale;
    let column = |k: usize| DVec3::new(v[0][k], v[1][k], v[2][k]);
    let (e0, e1) = (column(order[0]), column(order[1]));
    let mut e2 = column(order[2]);
    if e0.cross(e1).dot(e2) < 0.0 {
        e2 = -e2;
    }
    (lambda, DMat3::from_cols(e0, e1, e2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Sampler;

    fn check_decomposition<S: Space>(m: S::Mat, tol: f64) {
        let (lambda, q) = S::sym_eigen(m);
        // Compare at unit scale so that squares neither overflow nor underflow.
        let mut k = 0.0f64;
        for i in 0..S::DIM {
            for j in 0..S::DIM {
                k = k.max(S::entry(m, i, j).abs());
            }
        }
        let k = if k == 0.0 { 1.0 } else { k };
        let sym = S::symmetrize(m) * (1.0 / k);
        let lambda = lambda * (1.0 / k);
        let recon = q * S::diagonal(lambda) * S::transpose(q);
        let scale = S::frobenius(sym).max(f64::MIN_POSITIVE);
        let err = S::frobenius(recon - sym) / scale;
        assert!(err <= tol, "reconstruction error {err:e} for {m:?}");
        let ortho = S::frobenius(S::transpose(q) * q - S::identity());
        assert!(ortho <= 1e-13, "Q not orthonormal ({ortho:e}) for {m:?}");
        for i in 1..S::DIM {
            assert!(lambda[i - 1] <= lambda[i], "not ascending: {lambda:?}");
        }
        // Each column is an eigenvector: M q = λ q.
        for j in 0..S::DIM {
            let qj = S::col(q, j);
            let res = S::length(sym * qj - qj * lambda[j]) / scale;
            assert!(res <= tol, "eigen residual {res:e} for {m:?}");
        }
    }

    fn random_sym2(s: &mut Sampler, scale: f64) -> DMat2 {
        let mut u = || (2.0 * s.next_f64() - 1.0) * scale;
        let (a, b, c) = (u(), u(), u());
        DMat2::from_cols(DVec2::new(a, b), DVec2::new(b, c))
    }

    fn random_rotation3(s: &mut Sampler) -> DMat3 {
        let axis = DVec3::new(s.next_f64() - 0.5, s.next_f64() - 0.5, s.next_f64() - 0.5);
        DMat3::from_axis_angle(axis.normalize(), TAU * s.next_f64())
    }

    #[test]
    fn random_symmetric_matrices_reconstruct() {
        let mut s = Sampler::new(3, 0);
        for i in 0..2000 {
            let scale = 10f64.powi((i % 13) * 50 - 300);
            check_decomposition::<D2>(random_sym2(&mut s, scale), 1e-14);
            let mut u = || (2.0 * s.next_f64() - 1.0) * scale;
            let (a, b, c, d, e, f) = (u(), u(), u(), u(), u(), u());
            let m = DMat3::from_cols(DVec3::new(a, b, c), DVec3::new(b, d, e), DVec3::new(c, e, f));
            check_decomposition::<D3>(m, 1e-13);
        }
    }

    #[test]
    fn repeated_zero_and_rank_one() {
        for c in [0.0, 1.0, -3.5, 1e-300, 1e300, -1e-200] {
            check_decomposition::<D2>(DMat2::IDENTITY * c, 1e-15);
            check_decomposition::<D3>(DMat3::IDENTITY * c, 1e-15);
        }
        let (l, q) = D3::sym_eigen(DMat3::ZERO);
        assert_eq!((l, q), (DVec3::ZERO, DMat3::IDENTITY));
        let mut s = Sampler::new(4, 0);
        for _ in 0..500 {
            let r = random_rotation3(&mut s);
            // Repeated eigenvalues in a random basis, in both orders, and rank one.
            for lam in [
                DVec3::new(1.0, 1.0, 2.0),
                DVec3::new(-2.0, 5.0, 5.0),
                DVec3::new(0.0, 0.0, 7.0),
                DVec3::new(1.0, 1.0 + 1e-12, 1.0 - 1e-12),
                DVec3::new(0.0, 1e-17, 1.0),
                DVec3::new(-1e150, 1e150, 1e150),
            ] {
                let m = r * DMat3::from_diagonal(lam) * r.transpose();
                check_decomposition::<D3>(m, 1e-13);
                let (l, _) = D3::sym_eigen(m);
                let mut sorted = lam.to_array();
                sorted.sort_by(f64::total_cmp);
                let tol = 1e-13 * lam.abs().max_element();
                assert!((l - DVec3::from(sorted)).abs().max_element() <= tol, "{l:?} vs {lam:?}");
            }
            let v = DVec3::new(s.next_f64() - 0.5, s.next_f64() - 0.5, s.next_f64() - 0.5);
            check_decomposition::<D3>(D3::outer(v, v) * 1e-100, 1e-13);
            let w = DVec2::new(s.next_f64() - 0.5, s.next_f64() - 0.5);
            check_decomposition::<D2>(D2::outer(w, w), 1e-14);
            check_decomposition::<D2>(-D2::outer(w, w) * 1e250, 1e-14);
        }
    }

    #[test]
    fn known_2d_eigenvectors() {
        let (l, q) = D2::sym_eigen(DMat2::from_cols(DVec2::new(2.0, 0.0), DVec2::new(0.0, 1.0)));
        assert_eq!(l, DVec2::new(1.0, 2.0));
        assert!((q.col(1).x.abs() - 1.0).abs() < 1e-15 && q.col(0).y.abs() > 1.0 - 1e-15);
        assert!((q.determinant() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn constants() {
        assert_eq!(D2::SPHERE_MEASURE, TAU);
        assert_eq!(D3::SPHERE_MEASURE, 4.0 * PI);
        assert_eq!(D2::BALL_VOLUME, PI);
        assert!((D3::BALL_VOLUME - 4.18879020478639).abs() < 1e-13);
        let m = DMat3::from_cols_array(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        assert_eq!(D3::entry(m, 0, 1), 4.0);
        assert_eq!(D3::trace(m), 15.0);
        assert_eq!(D3::outer(DVec3::X, DVec3::Y).col(1), DVec3::X);
    }
}
