//! Equiangular sampling (Kulla and Fajardo 2012, extended to flatland): a distance
//! t ∈ [a, b] along a ray drawn with density ∝ 1/r^{d−1}, r the distance from the
//! ray's point at t to a point light that lies at distance h from the ray's line,
//! at parameter t₀. The point light's unoccluded, unattenuated light scattered
//! along the ray then costs one sample with bounded weight, where free-flight
//! sampling gives it infinite variance (I/r^{d−1} at vertices that land near it).
//!
//! - 3D: ∫ dt/(h² + (t−t₀)²) = (θ_b − θ_a)/h with θ = atan((t−t₀)/h);
//! - 2D: ∫ dt/√(h² + (t−t₀)²) = asinh((t_b−t₀)/h) − asinh((t_a−t₀)/h).

use super::space::Space;

/// The distribution along one ray towards one light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equiangular {
    /// 2 or 3.
    dim: usize,
    t0: f64,
    h: f64,
    /// The warped ends (atan or asinh of (t − t₀)/h) of [a, b].
    lo: f64,
    hi: f64,
}

impl Equiangular {
    /// The distribution on [a, b] (a < b, finite) of a ray passing a point at
    /// distance `h` > 0 from its line, nearest at parameter `t0`, in dimension `dim`.
    pub fn new(dim: usize, t0: f64, h: f64, a: f64, b: f64) -> Self {
        debug_assert!(dim == 2 || dim == 3);
        debug_assert!(h > 0.0 && a < b && b.is_finite());
        let warp = |t: f64| {
            let x = (t - t0) / h;
            if dim == 3 { x.atan() } else { x.asinh() }
        };
        Equiangular {
            dim,
            t0,
            h,
            lo: warp(a),
            hi: warp(b),
        }
    }

    /// The distribution on [a, b] of the ray o + t·d (unit d) towards the point
    /// `p`, in `S`'s dimension: nearest at t₀ = (p − o)·d, at distance h from the
    /// line, h taken at least `h_min` (a point on the line has no finite density).
    pub fn towards<S: Space>((o, d): (S::Vec, S::Vec), p: S::Vec, h_min: f64, (a, b): (f64, f64)) -> Self {
        let to = p - o;
        let t0 = S::dot(to, d);
        let h = S::length(to - d * t0).max(h_min);
        Self::new(S::DIM, t0, h, a, b)
    }

    /// The distance for a uniform number `u` in [0, 1) (inverting the CDF).
    pub fn sample(&self, u: f64) -> f64 {
        let w = self.lo + u * (self.hi - self.lo);
        self.t0 + self.h * if self.dim == 3 { w.tan() } else { w.sinh() }
    }

    /// The density at distance `t` (within [a, b]).
    pub fn pdf(&self, t: f64) -> f64 {
        let r2 = self.h * self.h + (t - self.t0) * (t - self.t0);
        let span = self.hi - self.lo;
        if self.dim == 3 {
            self.h / (span * r2)
        } else {
            1.0 / (span * r2.sqrt())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ pdf over [a, b] by the midpoint rule on a fine grid.
    fn integral(e: &Equiangular, a: f64, b: f64) -> f64 {
        let n = 200_000;
        let dt = (b - a) / n as f64;
        (0..n).map(|k| e.pdf(a + (k as f64 + 0.5) * dt) * dt).sum()
    }

    #[test]
    fn the_density_normalises_and_sampling_inverts_its_cdf() {
        for dim in [2, 3] {
            for (t0, h, a, b) in [(0.3, 0.05, 0.0, 1.0), (-2.0, 0.5, 0.0, 3.0), (5.0, 1e-3, 0.0, 4.0)] {
                let e = Equiangular::new(dim, t0, h, a, b);
                let total = integral(&e, a, b);
                assert!((total - 1.0).abs() < 1e-4, "d = {dim}: ∫ pdf = {total}");
                for u in [0.0, 0.1, 0.37, 0.5, 0.9, 0.999] {
                    let t = e.sample(u);
                    assert!(
                        (a - 1e-9..=b + 1e-9).contains(&t),
                        "d = {dim}: t = {t} outside [{a}, {b}]"
                    );
                    let cdf = integral(&e, a, t);
                    assert!((cdf - u).abs() < 1e-4, "d = {dim}: CDF({t}) = {cdf}, want {u}");
                }
            }
        }
    }

    /// One sample of ∫ dt / r^{d−1} is exact: the density is the integrand's shape.
    #[test]
    fn one_sample_of_the_falloff_is_exact() {
        for dim in [2, 3] {
            let (t0, h, a, b) = (0.4, 0.02, 0.0, 2.0);
            let e = Equiangular::new(dim, t0, h, a, b);
            let n = 100_000;
            let dt = (b - a) / n as f64;
            let exact: f64 = (0..n)
                .map(|k| {
                    let t = a + (k as f64 + 0.5) * dt;
                    (h * h + (t - t0) * (t - t0)).powf(-0.5 * (dim - 1) as f64) * dt
                })
                .sum();
            for u in [0.01, 0.5, 0.93] {
                let t = e.sample(u);
                let f = (h * h + (t - t0) * (t - t0)).powf(-0.5 * (dim - 1) as f64);
                let one = f / e.pdf(t);
                assert!((one / exact - 1.0).abs() < 1e-5, "d = {dim}: {one} vs {exact}");
            }
        }
    }
}
