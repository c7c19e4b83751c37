//! Second-order Taylor data of a scalar field at a receiving point x: value,
//! gradient and Hessian with respect to x (theory.md §5).
//!
//! An element's contribution L_j = f · T · L_o · F is a product of such fields, so
//! [`Taylor2`] carries the product rule (`*`), sums (`+`, `-`, [`Sum`]), scaling by a
//! constant (`* f64`) and the chain rule for a scalar function ([`Taylor2::compose`]).

use super::space::Space;
use std::iter::Sum;
use std::ops::{Add, AddAssign, Mul, Neg, Sub};

/// Value, gradient ∇ and Hessian H of a scalar function of the receiving point x.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Taylor2<S: Space> {
    pub value: f64,
    pub grad: S::Vec,
    pub hess: S::Mat,
}

impl<S: Space> Taylor2<S> {
    pub fn new(value: f64, grad: S::Vec, hess: S::Mat) -> Self {
        Taylor2 { value, grad, hess }
    }

    /// A constant: zero gradient and Hessian.
    pub fn constant(value: f64) -> Self {
        Taylor2::new(value, S::zero(), S::zero_mat())
    }

    pub fn zero() -> Self {
        Self::constant(0.0)
    }

    /// The i-th coordinate of x itself (gradient e_i, Hessian 0).
    pub fn coordinate(x: S::Vec, i: usize) -> Self {
        Taylor2::new(x[i], S::axis(i), S::zero_mat())
    }

    /// Chain rule for h(u(x)) given h(u), h'(u), h''(u):
    /// ∇ = h' ∇u, H = h'' ∇u ∇uᵀ + h' H_u.
    pub fn compose(self, h: f64, dh: f64, d2h: f64) -> Self {
        Taylor2::new(h, self.grad * dh, S::outer(self.grad, self.grad) * d2h + self.hess * dh)
    }

    /// Multiply the value and its derivatives by a constant k (same as `self * k`).
    pub fn scale(self, k: f64) -> Self {
        self * k
    }

    pub fn is_finite(&self) -> bool {
        self.value.is_finite() && S::vec_is_finite(self.grad) && S::mat_is_finite(self.hess)
    }

    /// Value, gradient and Hessian of a smooth function of x with `C` channels by
    /// central differences with step `h` (1 + 2d + 2d(d − 1) evaluations): exact to
    /// O(h²), for closed-form functions whose own derivatives are awkward to write.
    pub fn central_differences<const C: usize>(f: impl Fn(S::Vec) -> [f64; C], x: S::Vec, h: f64) -> [Self; C] {
        let c = f(x);
        let mut out = c.map(Taylor2::constant);
        let e = |i: usize| S::axis(i) * h;
        for i in 0..S::DIM {
            let (p, m) = (f(x + e(i)), f(x - e(i)));
            for k in 0..C {
                out[k].grad += S::axis(i) * ((p[k] - m[k]) / (2.0 * h));
                out[k].hess += S::outer(S::axis(i), S::axis(i)) * ((p[k] - 2.0 * c[k] + m[k]) / (h * h));
            }
            for j in 0..i {
                let at = |a: f64, b: f64| f(x + e(i) * a + e(j) * b);
                let (pp, pm, mp, mm) = (at(1.0, 1.0), at(1.0, -1.0), at(-1.0, 1.0), at(-1.0, -1.0));
                for k in 0..C {
                    let hij = (pp[k] - pm[k] - mp[k] + mm[k]) / (4.0 * h * h);
                    out[k].hess += (S::outer(S::axis(i), S::axis(j)) + S::outer(S::axis(j), S::axis(i))) * hij;
                }
            }
        }
        out
    }

    /// [`Self::central_differences`] with the mixed derivatives from the points
    /// x ± h(e_i + e_j) beside the axis points already there (1 + 2d + d(d − 1)
    /// evaluations: 13 instead of 19 in 3D): f(x ± h(e_i + e_j)) sum to
    /// 2f + h²(f_ii + 2f_ij + f_jj) + O(h⁴), the axis pairs to 2f + h² f_ii + O(h⁴).
    /// Also O(h²), but a mixed derivative sums seven values instead of four, so
    /// the rounding of f is amplified 4× more: for closed forms on the records' hot
    /// path, not for quadratures (the exact references keep the four-point rule).
    pub fn central_differences_compact<const C: usize>(f: impl Fn(S::Vec) -> [f64; C], x: S::Vec, h: f64) -> [Self; C] {
        let c = f(x);
        let mut out = c.map(Taylor2::constant);
        let e = |i: usize| S::axis(i) * h;
        // f(x ± h e_i) per axis (at most three; no allocation on this hot path).
        let mut axis = [(c, c); 3];
        for (i, pm) in axis.iter_mut().enumerate().take(S::DIM) {
            *pm = (f(x + e(i)), f(x - e(i)));
        }
        for (i, (p, m)) in axis.iter().enumerate().take(S::DIM) {
            for k in 0..C {
                out[k].grad += S::axis(i) * ((p[k] - m[k]) / (2.0 * h));
                out[k].hess += S::outer(S::axis(i), S::axis(i)) * ((p[k] - 2.0 * c[k] + m[k]) / (h * h));
            }
            for (j, (pj, mj)) in axis.iter().enumerate().take(i) {
                let (pp, mm) = (f(x + e(i) + e(j)), f(x - e(i) - e(j)));
                for k in 0..C {
                    let hij = (pp[k] + mm[k] - p[k] - m[k] - pj[k] - mj[k] + 2.0 * c[k]) / (2.0 * h * h);
                    out[k].hess += (S::outer(S::axis(i), S::axis(j)) + S::outer(S::axis(j), S::axis(i))) * hij;
                }
            }
        }
        out
    }

    /// Second-order extrapolation to x + dx.
    pub fn extrapolate(&self, dx: S::Vec) -> f64 {
        self.value + S::dot(self.grad, dx) + 0.5 * S::dot(dx, self.hess * dx)
    }
}

impl<S: Space> Add for Taylor2<S> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Taylor2::new(self.value + o.value, self.grad + o.grad, self.hess + o.hess)
    }
}

impl<S: Space> AddAssign for Taylor2<S> {
    fn add_assign(&mut self, o: Self) {
        self.value += o.value;
        self.grad += o.grad;
        self.hess += o.hess;
    }
}

impl<S: Space> Sub for Taylor2<S> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Taylor2::new(self.value - o.value, self.grad - o.grad, self.hess - o.hess)
    }
}

impl<S: Space> Neg for Taylor2<S> {
    type Output = Self;
    fn neg(self) -> Self {
        Taylor2::new(-self.value, -self.grad, -self.hess)
    }
}

impl<S: Space> Mul<f64> for Taylor2<S> {
    type Output = Self;
    fn mul(self, k: f64) -> Self {
        Taylor2::new(self.value * k, self.grad * k, self.hess * k)
    }
}

/// Product rule: ∇(fg) = f∇g + g∇f, H(fg) = fH_g + gH_f + ∇f∇gᵀ + ∇g∇fᵀ.
impl<S: Space> Mul for Taylor2<S> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        let cross = S::outer(self.grad, o.grad);
        Taylor2::new(
            self.value * o.value,
            self.grad * o.value + o.grad * self.value,
            self.hess * o.value + o.hess * self.value + cross + S::transpose(cross),
        )
    }
}

impl<S: Space> Sum for Taylor2<S> {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::zero(), |a, b| a + b)
    }
}

impl<S: Space> Default for Taylor2<S> {
    fn default() -> Self {
        Self::zero()
    }
}

#[cfg(test)]
mod tests {
    /// Central differences are exact for a quadratic (up to rounding).
    #[test]
    fn central_differences_of_a_quadratic() {
        use crate::core::space::D3;
        use glam::{DMat3, DVec3};
        let a = DMat3::from_cols_array(&[2.0, 0.5, -1.0, 0.5, 3.0, 0.25, -1.0, 0.25, 1.0]);
        let b = DVec3::new(0.3, -0.7, 1.1);
        let f = |x: DVec3| [0.5 * x.dot(a * x) + b.dot(x) + 4.0, x.x * 2.0];
        let x = DVec3::new(0.2, -0.4, 0.9);
        let [t, u] = Taylor2::<D3>::central_differences(f, x, 1e-3);
        assert!((t.value - f(x)[0]).abs() < 1e-14);
        assert!((t.grad - (a * x + b)).length() < 1e-9, "{:?}", t.grad);
        assert!(
            (t.hess - a).to_cols_array().iter().all(|e| e.abs() < 1e-6),
            "{:?}",
            t.hess
        );
        assert!((u.grad - DVec3::X * 2.0).length() < 1e-9 && u.hess.to_cols_array().iter().all(|e| e.abs() < 1e-6));
    }

    /// The compact stencil is exact for a quadratic too, and on a smooth
    /// non-polynomial function (a Gaussian times a cosine, 3D) agrees with the
    /// four-point rule and the closed form to O(h²).
    #[test]
    fn compact_central_differences_agree() {
        use crate::core::space::D3;
        use glam::{DMat3, DVec3};
        let a = DMat3::from_cols_array(&[2.0, 0.5, -1.0, 0.5, 3.0, 0.25, -1.0, 0.25, 1.0]);
        let quad = |x: DVec3| [0.5 * x.dot(a * x) + 4.0];
        let x = DVec3::new(0.2, -0.4, 0.9);
        let [q] = Taylor2::<D3>::central_differences_compact(quad, x, 1e-3);
        assert!(
            (q.hess - a).to_cols_array().iter().all(|e| e.abs() < 1e-6),
            "{:?}",
            q.hess
        );
        // f = exp(−|x|²) cos(x·k), against Taylor2's own arithmetic (exact
        // derivatives).
        let k = DVec3::new(1.3, -0.4, 0.7);
        let f = |x: DVec3| [(-x.length_squared()).exp() * x.dot(k).cos()];
        let exact = {
            let t = Taylor2::<D3>::coordinate(x, 0) * k.x
                + Taylor2::coordinate(x, 1) * k.y
                + Taylor2::coordinate(x, 2) * k.z;
            let r2 = (0..3)
                .map(|i| Taylor2::<D3>::coordinate(x, i) * Taylor2::coordinate(x, i))
                .fold(Taylor2::zero(), |s, v| s + v);
            let g = r2.compose((-r2.value).exp(), -(-r2.value).exp(), (-r2.value).exp());
            g * t.compose(t.value.cos(), -t.value.sin(), -t.value.cos())
        };
        for h in [1e-3, 1e-4] {
            let [c] = Taylor2::<D3>::central_differences_compact(f, x, h);
            let [o] = Taylor2::<D3>::central_differences(f, x, h);
            let err = |t: Taylor2<D3>| {
                (t.hess - exact.hess)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f64, |m, e| m.max(e.abs()))
            };
            assert!(
                err(c) < 1e-5 && err(o) < 1e-5,
                "h {h}: compact {:e}, four-point {:e}",
                err(c),
                err(o)
            );
            assert!((c.grad - exact.grad).length() < 1e-6, "{:?}", c.grad);
        }
    }

    use super::*;
    use crate::core::space::{D2, D3};
    use glam::{DMat2, DVec2, DVec3};

    #[test]
    fn product_and_chain_rule_on_polynomials() {
        // f = x² y, g = x + 3y at (2, -1): fg = x³y + 3x²y².
        let p = DVec2::new(2.0, -1.0);
        let x = Taylor2::<D2>::coordinate(p, 0);
        let y = Taylor2::<D2>::coordinate(p, 1);
        let f = x * x * y;
        let g = x + y * 3.0;
        let fg = f * g;
        let (xv, yv) = (p.x, p.y);
        assert_eq!(fg.value, xv.powi(3) * yv + 3.0 * xv * xv * yv * yv);
        let grad = DVec2::new(3.0 * xv * xv * yv + 6.0 * xv * yv * yv, xv.powi(3) + 6.0 * xv * xv * yv);
        assert!((fg.grad - grad).length() < 1e-12);
        let hxx = 6.0 * xv * yv + 6.0 * yv * yv;
        let hxy = 3.0 * xv * xv + 12.0 * xv * yv;
        let hyy = 6.0 * xv * xv;
        let h = DMat2::from_cols(DVec2::new(hxx, hxy), DVec2::new(hxy, hyy));
        assert!((fg.hess - h).abs_diff_eq(DMat2::ZERO, 1e-12));
        // exp(g): ∇ = e^g ∇g, H = e^g ∇g∇gᵀ.
        let e = g.compose(g.value.exp(), g.value.exp(), g.value.exp());
        assert!((e.hess - D2::outer(g.grad, g.grad) * g.value.exp()).abs_diff_eq(DMat2::ZERO, 1e-15));
        let s: Taylor2<D2> = [f, g, -g].into_iter().sum();
        assert_eq!(s, f);
    }

    #[test]
    fn extrapolation_is_exact_for_quadratics() {
        let p = DVec3::new(0.5, 1.0, -2.0);
        let x = Taylor2::<D3>::coordinate(p, 0);
        let z = Taylor2::<D3>::coordinate(p, 2);
        let q = x * z * 2.0 + z * z - x + Taylor2::constant(4.0);
        let dx = DVec3::new(0.3, -0.2, 0.7);
        let (a, c) = (p.x + dx.x, p.z + dx.z);
        let exact = 2.0 * a * c + c * c - a + 4.0;
        assert!((q.extrapolate(dx) - exact).abs() < 1e-13);
        assert!(q.is_finite());
    }
}
