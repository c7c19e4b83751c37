//! Test helpers for the derivative core: forward-mode AD with hyper-dual numbers
//! (num-dual), central finite differences, error measures and random inputs.

use super::distance::MIN_DISTANCE;
use super::rng::Sampler;
use super::space::Space;
use super::taylor::Taylor2;
use num_dual::{DualNum, HyperDual64};

pub type HD = HyperDual64;

/// Value, gradient and Hessian of `f` at `x` by hyper-dual numbers: seeding
/// coordinate i in ε₁ and j in ε₂ gives ∂f/∂x_i in ε₁ and ∂²f/∂x_i∂x_j in ε₁ε₂,
/// exactly (no truncation error).
pub fn ad_taylor<S: Space>(f: impl Fn(&[HD]) -> HD, x: S::Vec) -> Taylor2<S> {
    let n = S::DIM;
    let mut out = Taylor2::<S>::zero();
    for i in 0..n {
        for j in 0..n {
            let xs: Vec<HD> = (0..n)
                .map(|k| HD::new(x[k], (k == i) as u8 as f64, (k == j) as u8 as f64, 0.0))
                .collect();
            let r = f(&xs);
            out.value = r.re;
            if j == 0 {
                out.grad += S::axis(i) * r.eps1;
            }
            out.hess += S::outer(S::axis(i), S::axis(j)) * r.eps1eps2;
        }
    }
    out
}

/// atan2 for hyper-dual numbers that stays exact when x's real part is 0 (num-dual's
/// goes through y/x): rotate (x, y) by −φ₀ with real coefficients first.
pub fn atan2_hd(y: HD, x: HD) -> HD {
    let phi0 = y.re.atan2(x.re);
    let rho = y.re.hypot(x.re);
    let (s, c) = (y.re / rho, x.re / rho);
    let yr = y * c - x * s;
    let xr = x * c + y * s;
    let mut t = (yr / xr).atan();
    t.re = phi0;
    t
}

/// The phase factor f(μ) written directly (1 + g² − 2gμ, μ = −u·w, u the softened
/// direction to c), for AD.
pub fn phase_ref<S: Space>(g: f64, xs: &[HD], c: S::Vec, w: S::Vec, soft: f64) -> HD {
    let mut r2 = HD::from(soft.max(MIN_DISTANCE).powi(2));
    let mut dw = HD::from(0.0);
    for k in 0..S::DIM {
        let dk = -xs[k] + c[k];
        r2 += dk * dk;
        dw += dk * w[k];
    }
    let mu = -dw / r2.sqrt();
    let den = -mu * (2.0 * g) + (1.0 + g * g);
    let n = if S::DIM == 2 { 1.0 } else { 1.5 };
    den.powf(-n) * ((1.0 - g * g) / S::SPHERE_MEASURE)
}

/// The phase factor with ω_o towards the point e: μ = −u_c·u_e, u_c softened
/// towards c and u_e = (e − x)/|e − x|, for AD.
pub fn phase_ref_point<S: Space>(g: f64, xs: &[HD], c: S::Vec, e: S::Vec, soft: f64) -> HD {
    let mut rc2 = HD::from(soft.max(MIN_DISTANCE).powi(2));
    let mut re2 = HD::from(MIN_DISTANCE.powi(2));
    let mut dot = HD::from(0.0);
    for k in 0..S::DIM {
        let dc = -xs[k] + c[k];
        let de = -xs[k] + e[k];
        rc2 += dc * dc;
        re2 += de * de;
        dot += dc * de;
    }
    let mu = -dot / (rc2.sqrt() * re2.sqrt());
    let den = -mu * (2.0 * g) + (1.0 + g * g);
    let n = if S::DIM == 2 { 1.0 } else { 1.5 };
    den.powf(-n) * ((1.0 - g * g) / S::SPHERE_MEASURE)
}

/// exp(−σ √(|c − x|² + soft²)), for AD.
pub fn transmittance_ref<S: Space>(sigma: f64, xs: &[HD], c: S::Vec, soft: f64) -> HD {
    let mut r2 = HD::from(soft.max(MIN_DISTANCE).powi(2));
    for k in 0..S::DIM {
        let dk = -xs[k] + c[k];
        r2 += dk * dk;
    }
    (-r2.sqrt() * sigma).exp()
}

/// Norm-relative error of value, gradient and Hessian (the worst of the three);
/// a zero reference is compared absolutely.
pub fn rel_err<S: Space>(got: &Taylor2<S>, want: &Taylor2<S>) -> f64 {
    let rel = |e: f64, n: f64| if n > 0.0 { e / n } else { e };
    let ev = rel((got.value - want.value).abs(), want.value.abs());
    let eg = rel(S::length(got.grad - want.grad), S::length(want.grad));
    let eh = rel(S::frobenius(got.hess - want.hess), S::frobenius(want.hess));
    ev.max(eg).max(eh)
}

/// Error of the derivatives only (gradient, Hessian), relative to their norms.
pub fn rel_err_derivs<S: Space>(got: &Taylor2<S>, want: &Taylor2<S>) -> f64 {
    let mut g = *got;
    g.value = want.value;
    rel_err(&g, want)
}

pub fn random_vec<S: Space>(s: &mut Sampler, scale: f64) -> S::Vec {
    let mut v = S::zero();
    for i in 0..S::DIM {
        v += S::axis(i) * ((2.0 * s.next_f64() - 1.0) * scale);
    }
    v
}

pub fn random_unit<S: Space>(s: &mut Sampler) -> S::Vec {
    loop {
        let v = random_vec::<S>(s, 1.0);
        let l = S::length(v);
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// Errors of central-difference gradient (from values) and Hessian (from the
/// closed-form gradient) against the closed form, at step h.
pub fn fd_errors<S: Space>(f: impl Fn(S::Vec) -> Taylor2<S>, x: S::Vec, h: f64) -> (f64, f64) {
    let t = f(x);
    let mut eg = 0.0f64;
    let mut eh = 0.0f64;
    for j in 0..S::DIM {
        let e = S::axis(j) * h;
        let (p, m) = (f(x + e), f(x - e));
        let dg = (p.value - m.value) / (2.0 * h);
        eg = eg.hypot(dg - t.grad[j]);
        let dh = (p.grad - m.grad) / (2.0 * h);
        eh = eh.hypot(S::length(dh - S::col(t.hess, j)));
    }
    (eg, eh)
}

/// Asserts that central differences converge at O(h²): the error ratio between
/// steps h and h/2 is ≈ 4 for both the gradient and the Hessian, at two values of h.
/// Returns false (checks nothing) when the truncation error is too small to measure.
pub fn assert_fd_order2<S: Space>(f: impl Fn(S::Vec) -> Taylor2<S>, x: S::Vec, h: f64) -> bool {
    let t = f(x);
    let (g1, h1) = fd_errors(&f, x, h);
    let (g2, h2) = fd_errors(&f, x, h / 2.0);
    let (g3, h3) = fd_errors(&f, x, h / 4.0);
    let gscale = S::length(t.grad);
    let hscale = S::frobenius(t.hess);
    // Truncation must dominate rounding (≈1e-16 · scale / h) for the ratio to mean anything.
    let measurable = g3 > 1e-9 * gscale && h3 > 1e-9 * hscale && g3 > 0.0 && h3 > 0.0;
    if !measurable {
        return false;
    }
    for (a, b, what) in [
        (g1, g2, "grad h"),
        (g2, g3, "grad h/2"),
        (h1, h2, "hess h"),
        (h2, h3, "hess h/2"),
    ] {
        let ratio = a / b;
        assert!(
            (3.6..=4.4).contains(&ratio),
            "FD {what}: error ratio {ratio} ({a:e} → {b:e}) at {x:?}"
        );
    }
    true
}
