//! Cache extents from the error metric (theory.md §6, §7, §8).
//!
//! - [`second_order_extent`]: the paper's metric. The luminance Hessian H = Q Λ Qᵀ
//!   gives an ellipse (2D) or ellipsoid (3D) with axes e_k (columns of Q) and the
//!   seed's radii R_2D(λ) = (4Lε/(π|λ|))^{1/4}, R_3D(λ) = (15Lε/(4π|λ|))^{1/5}.
//! - [`first_order_extent`]: the Jarosz et al. 2008 baseline, an isotropic radius
//!   R = εL/‖∇L‖ (theory.md §4).
//!
//! Both apply the clamps of theory.md §7 from [`MetricParams`] and never return NaN:
//! non-finite input gives the smallest (safest) extent. The robust Hessian of §7
//! (≈1% of the mean radiance added to every element's radiance before
//! differentiating, unit radiance if every ray was black) is the caller's job: it
//! changes how H is estimated, not how an extent follows from it.

use super::color::Rgb;
use super::space::Space;
use super::taylor::Taylor2;
use serde::{Deserialize, Serialize};

/// Which metric turns a record's derivatives into its extent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum CacheMethod {
    /// Second-order occlusion-aware Hessian ellipses (the paper).
    Ours,
    /// First-order occlusion-unaware gradient circles (Jarosz et al. 2008).
    Jarosz08,
}

impl CacheMethod {
    /// The extent of a record with luminance `lum` (value and gradient) and the
    /// luminance Hessian its metric uses (`metric_hess`, ignored by the baseline).
    pub fn extent<S: Space>(self, lum: &Taylor2<S>, metric_hess: S::Mat, p: &MetricParams) -> Extent<S> {
        match self {
            CacheMethod::Ours => second_order_extent::<S>(lum.value, metric_hess, lum.grad, p),
            CacheMethod::Jarosz08 => first_order_extent::<S>(lum.value, lum.grad, p),
        }
    }
}

/// The radiance added to every proxy element before the metric's Hessian is taken
/// (theory.md §7, Schwarzhaupt et al. 2012): `fraction` × the elements' mean
/// radiance (the sum of the `n` elements' radiance over n), or unit radiance when
/// every element is black (a purely geometric Hessian). None when nothing is to be
/// added.
pub fn hessian_radiance_floor(radiance_sum: Rgb, n: usize, fraction: f64) -> Option<Rgb> {
    if n == 0 || fraction <= 0.0 {
        return None;
    }
    let mean = radiance_sum / n as f64;
    Some(if mean == Rgb::ZERO { Rgb::ONE } else { mean * fraction })
}

/// Parameters of the extent computation (lengths in scene units, L in luminance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetricParams {
    /// Error threshold ε. Second order (theory.md §6): the remainder integrated over
    /// the disc (ball) is bounded by εL/2, so ε has units of length^d and must scale
    /// as size^d to give the same extents in a scaled scene; the mean relative
    /// remainder over an extent is ε/(2·V_d·R^d). First order (§4): dimensionless.
    /// The same number therefore means different things for the two metrics
    /// (equal-count comparisons search ε per method).
    pub eps: f64,
    /// Smallest radius: L → 0 or an unbounded curvature clamps here.
    pub r_min: f64,
    /// Largest radius: λ → 0 (flat radiance) clamps here.
    pub r_max: f64,
    /// Largest allowed ratio of largest to smallest radius (≥ 1, `INFINITY` = none).
    pub max_anisotropy: f64,
    /// Absolute floor on L in the formulas (≥ 0).
    pub luminance_floor: f64,
    /// Limit each radius so that the first-order term stays below L (theory.md §7).
    pub limit_by_gradient: bool,
}

/// An invalid [`MetricParams`] field.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum MetricError {
    #[error("eps must be finite and >= 0, got {0}")]
    Eps(f64),
    #[error("radii need 0 < r_min <= r_max < inf, got r_min = {r_min}, r_max = {r_max}")]
    Radii { r_min: f64, r_max: f64 },
    #[error("max_anisotropy must be >= 1, got {0}")]
    Anisotropy(f64),
    #[error("luminance_floor must be finite and >= 0, got {0}")]
    Floor(f64),
}

impl MetricParams {
    /// Defaults for a scene of extent `scene_size` (e.g. the diagonal of its bounds):
    /// - `r_max = 0.25·size`: the extrapolation is local, and the Hessian of a flat
    ///   region is mostly noise, so a record never reaches across the scene; a few
    ///   records still tile an empty region.
    /// - `r_min = 1e-3·size`: below a pixel of a 512–1024 px field, so it never
    ///   limits what placement can resolve, yet bounds the record count and keeps
    ///   extents away from zero where L → 0.
    /// - `max_anisotropy = 4`: the seed radii go as |λ|^{-1/(d+2)}, so a radius
    ///   ratio of 4 already allows an eigenvalue ratio of 4⁴ = 256 (2D) or 4⁵ = 1024
    ///   (3D): the visibly elongated ellipses along shadow edges of the paper.
    ///   Schwarzhaupt et al.'s 2 was set for radii ∝ |λ|^{-1/2}, where it caps the
    ///   eigenvalue ratio at 4; here 2 would cap it at 16 and round most ellipses.
    /// - `luminance_floor = 0`: the radii are invariant to the radiance scale (L and
    ///   H scale together); an absolute floor would break that. Set it (e.g. to 1%
    ///   of the mean luminance) when the radiance scale is known.
    /// - `limit_by_gradient = true` (theory.md §7).
    pub fn scene_relative(scene_size: f64, eps: f64) -> Self {
        MetricParams {
            eps,
            r_min: 1e-3 * scene_size,
            r_max: 0.25 * scene_size,
            max_anisotropy: 4.0,
            luminance_floor: 0.0,
            limit_by_gradient: true,
        }
    }

    /// Checks every field (the extent functions stay finite even without this).
    pub fn validate(&self) -> Result<(), MetricError> {
        if !(self.eps.is_finite() && self.eps >= 0.0) {
            return Err(MetricError::Eps(self.eps));
        }
        if !(self.r_min > 0.0 && self.r_min <= self.r_max && self.r_max.is_finite()) {
            return Err(MetricError::Radii {
                r_min: self.r_min,
                r_max: self.r_max,
            });
        }
        if self.max_anisotropy.is_nan() || self.max_anisotropy < 1.0 {
            return Err(MetricError::Anisotropy(self.max_anisotropy));
        }
        if !(self.luminance_floor.is_finite() && self.luminance_floor >= 0.0) {
            return Err(MetricError::Floor(self.luminance_floor));
        }
        Ok(())
    }
}

/// An ellipse (2D) or ellipsoid (3D) around a record's position: orthonormal axes
/// (the columns of `axes`) and one radius per axis (theory.md §6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent<S: Space> {
    pub axes: S::Mat,
    pub radii: S::Vec,
}

impl<S: Space> Extent<S> {
    /// Every radius limited to `reach` (the same axes; radii already below stay).
    pub fn within(self, reach: f64) -> Self {
        let radii = self.radii;
        Extent {
            axes: self.axes,
            radii: vec_from::<S>(|j| radii[j].min(reach)),
        }
    }

    /// A ball (disc) of radius `r`.
    pub fn isotropic(r: f64) -> Self {
        Extent {
            axes: S::identity(),
            radii: vec_from::<S>(|_| r),
        }
    }

    /// Normalised squared distance Σ_k ((y − x)·e_k / R_k)² (theory.md §8); +∞ for
    /// non-finite input.
    pub fn distance2(&self, center: S::Vec, y: S::Vec) -> f64 {
        let d = y - center;
        let s: f64 = (0..S::DIM)
            .map(|k| (S::dot(d, S::col(self.axes, k)) / self.radii[k]).powi(2))
            .sum();
        if s.is_nan() { f64::INFINITY } else { s }
    }

    /// y lies strictly inside (distance < 1).
    pub fn contains(&self, center: S::Vec, y: S::Vec) -> bool {
        self.distance2(center, y) < 1.0
    }

    /// Tent weight 1 − d(y) inside, 0 outside (theory.md §8): in (0, 1], 1 at the centre.
    pub fn tent_weight(&self, center: S::Vec, y: S::Vec) -> f64 {
        let d2 = self.distance2(center, y);
        if d2 < 1.0 { 1.0 - d2.sqrt() } else { 0.0 }
    }

    /// The largest radius: the extent lies in the ball of this radius.
    pub fn bounding_radius(&self) -> f64 {
        (0..S::DIM).map(|k| self.radii[k]).fold(0.0, f64::max)
    }

    pub fn min_radius(&self) -> f64 {
        (0..S::DIM).map(|k| self.radii[k]).fold(f64::INFINITY, f64::min)
    }

    /// Largest over smallest radius.
    pub fn anisotropy(&self) -> f64 {
        self.bounding_radius() / self.min_radius()
    }

    /// All radii equal to a relative 1e-12.
    pub fn is_isotropic(&self) -> bool {
        self.bounding_radius() - self.min_radius() <= 1e-12 * self.bounding_radius()
    }

    /// Half-widths of the tight axis-aligned box: h_i = sqrt(Σ_k (e_k[i] R_k)²),
    /// computed at unit scale so that huge or tiny radii neither overflow nor vanish
    /// (finite radii give finite half-widths).
    pub fn half_widths(&self) -> S::Vec {
        let m = self.bounding_radius();
        if m == 0.0 {
            return S::zero();
        }
        vec_from::<S>(|i| {
            let s: f64 = (0..S::DIM)
                .map(|k| (S::col(self.axes, k)[i] * (self.radii[k] / m)).powi(2))
                .sum();
            m * s.sqrt()
        })
    }
}

/// The paper's second-order extent from the luminance `l`, its Hessian and gradient
/// (theory.md §6, seed R_2D / R_3D), clamped as in theory.md §7, in this order:
/// seed radii → [r_min, r_max] → raise short radii to longest/max_anisotropy →
/// gradient limit |∇L·e_k| R_k ≤ L → shrink long radii to shortest·max_anisotropy
/// (so a gradient-limited axis keeps the ratio bound) → [r_min, r_max].
/// Axes are the Hessian's eigenvectors, ascending eigenvalues. The gradient limit
/// is per axis, as specified: over the whole ellipse |∇L·Δx| ≤ √d·L.
pub fn second_order_extent<S: Space>(l: f64, hess: S::Mat, grad: S::Vec, p: &MetricParams) -> Extent<S> {
    let b = Bounds::of(p);
    if !(l.is_finite() && S::mat_is_finite(hess) && S::vec_is_finite(grad)) {
        return Extent::isotropic(b.r_min);
    }
    let l_eff = l.max(b.floor);
    let (lambda, axes) = S::sym_eigen(hess);
    let n = S::DIM;
    // Generic form of the seed's radii: ½|λ|∫_ball (u·e)² = |λ| V_d R^{d+2} / (2(d+2))
    // bounded by εL/2 gives R^{d+2} = (d+2) L ε / (V_d |λ|): 4/π in 2D, 15/(4π) in 3D.
    // Roots taken factor by factor so that no product overflows or underflows.
    let inv = 1.0 / (n + 2) as f64;
    let c = (n + 2) as f64 / S::BALL_VOLUME;
    let num = c.powf(inv) * b.eps.powf(inv) * l_eff.powf(inv);
    let mut r = [0.0f64; 3];
    for (k, rk) in r.iter_mut().enumerate().take(n) {
        let lam = lambda[k].abs();
        *rk = if num.is_nan() || num <= 0.0 || lam.is_nan() {
            b.r_min // L → 0 (also when λ = 0 too: the safe choice) or ε = 0
        } else if lam == 0.0 {
            b.r_max
        } else {
            num / lam.powf(inv)
        };
        *rk = b.clamp(*rk);
    }
    let r = &mut r[..n];
    let longest = r.iter().copied().fold(0.0, f64::max);
    r.iter_mut().for_each(|rk| *rk = rk.max(longest / b.anisotropy));
    if p.limit_by_gradient {
        for (k, rk) in r.iter_mut().enumerate() {
            let gk = S::dot(grad, S::col(axes, k)).abs();
            if gk > 0.0 {
                *rk = rk.min(l_eff / gk);
            }
        }
        let shortest = r.iter().copied().fold(f64::INFINITY, f64::min);
        r.iter_mut().for_each(|rk| *rk = rk.min(shortest * b.anisotropy));
    }
    let radii = vec_from::<S>(|k| b.clamp(r[k]));
    Extent { axes, radii }
}

/// How far a record may extrapolate with a gradient known only to within noise of
/// variance `grad_var` (|noise|², summed over the axes): the radius at which the
/// error that noise adds, integrated over the ball, reaches the εL/2 the seed's
/// radii allow the second-order remainder (theory.md §6). With σ = √grad_var,
/// ∫_ball σ |u·e| dV = σ A_d R^{d+1} / (d+1), A_d = ∫ |cos θ| over the unit sphere
/// = 2 V_{d−1} (4 in 2D, 2π in 3D), so R^{d+1} = (d+1) ε L / (2 A_d σ).
/// Why: a record's gradient estimate from a few hundred directions is mostly noise
/// in thick or forward-scattering fog; the extrapolation then shrinks it (and so
/// leaves out the true gradient), and the metric, which bounds only the Hessian's
/// term, let such records reach their largest radius. +∞ for an exact gradient
/// (σ = 0; also Jarosz 2008, which measures none); `r_min` when L, ε or σ is not
/// finite, or ε or L (raised to the luminance floor) is zero. Never NaN.
pub fn gradient_noise_radius<S: Space>(l: f64, grad_var: f64, p: &MetricParams) -> f64 {
    let b = Bounds::of(p);
    if grad_var == 0.0 {
        return f64::INFINITY;
    }
    let l_eff = l.abs().max(b.floor);
    let sigma = grad_var.sqrt();
    if !(l_eff.is_finite() && sigma.is_finite() && l_eff > 0.0 && b.eps > 0.0) {
        return b.r_min;
    }
    let n = S::DIM as f64;
    let a = if S::DIM == 2 { 4.0 } else { 2.0 * std::f64::consts::PI };
    // Roots factor by factor, as in the seed's radii, so that nothing overflows.
    let inv = 1.0 / (n + 1.0);
    let r = ((n + 1.0) / (2.0 * a)).powf(inv) * b.eps.powf(inv) * (l_eff / sigma).powf(inv);
    if r.is_nan() { b.r_min } else { r.max(b.r_min) }
}

/// The Jarosz et al. 2008 baseline (theory.md §4): isotropic R = ε L / ‖∇L‖,
/// ‖∇L‖ = 0 ⇒ r_max, L → 0 or ε = 0 ⇒ r_min (also when ∇L = 0 too), then
/// [r_min, r_max]. With `limit_by_gradient` also R ≤ L/‖∇L‖ (binds only for ε > 1).
pub fn first_order_extent<S: Space>(l: f64, grad: S::Vec, p: &MetricParams) -> Extent<S> {
    let b = Bounds::of(p);
    if !(l.is_finite() && S::vec_is_finite(grad)) {
        return Extent::isotropic(b.r_min);
    }
    let l_eff = l.max(b.floor);
    let g = robust_norm::<S>(grad);
    let r = if !(l_eff > 0.0 && b.eps > 0.0) {
        b.r_min
    } else if g == 0.0 {
        b.r_max
    } else {
        let reach = l_eff / g; // may overflow to +∞: then r_max, which is right
        let r = b.eps * reach;
        if p.limit_by_gradient { r.min(reach) } else { r }
    };
    Extent::isotropic(b.clamp(r))
}

/// Parameters made safe to compute with: any input, even invalid, gives finite
/// 0 < r_min ≤ r_max, ε ≥ 0, floor ≥ 0, anisotropy ≥ 1 ([`MetricParams::validate`]
/// reports the invalid ones).
struct Bounds {
    r_min: f64,
    r_max: f64,
    eps: f64,
    floor: f64,
    anisotropy: f64,
}

impl Bounds {
    fn of(p: &MetricParams) -> Self {
        let r_min = if p.r_min > 0.0 && p.r_min.is_finite() {
            p.r_min
        } else {
            f64::MIN_POSITIVE
        };
        let r_max = if p.r_max.is_finite() { p.r_max.max(r_min) } else { r_min };
        let pos = |v: f64| if v > 0.0 { v } else { 0.0 };
        Bounds {
            r_min,
            r_max,
            eps: pos(p.eps),
            floor: if p.luminance_floor.is_finite() {
                pos(p.luminance_floor)
            } else {
                0.0
            },
            anisotropy: if p.max_anisotropy >= 1.0 { p.max_anisotropy } else { 1.0 },
        }
    }

    /// Into [r_min, r_max]; NaN → r_min.
    fn clamp(&self, r: f64) -> f64 {
        if r.is_nan() {
            self.r_min
        } else {
            r.max(self.r_min).min(self.r_max)
        }
    }
}

/// The vector with components f(0), …, f(d−1). Components must be finite.
fn vec_from<S: Space>(f: impl Fn(usize) -> f64) -> S::Vec {
    (0..S::DIM).fold(S::zero(), |v, i| v + S::axis(i) * f(i))
}

/// ‖v‖ without overflow or underflow of the squares.
fn robust_norm<S: Space>(v: S::Vec) -> f64 {
    let m = (0..S::DIM).map(|i| v[i].abs()).fold(0.0, f64::max);
    if m == 0.0 || !m.is_finite() {
        m
    } else {
        m * S::length(v / m)
    }
}

#[cfg(test)]
#[path = "metric_tests.rs"]
mod tests;
