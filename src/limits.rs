//! The ranges a scene and an option may have (README, "Ranges"): wide enough for
//! every physical use, narrow enough that every computation stays finite in f64,
//! every radiance an output holds fits an f32 (EXR), and every run ends in bounded
//! time and memory. The scene validators ([`crate::scene_check`]) and the command
//! line check against these numbers, so an input outside them is an error naming
//! its file and field rather than a NaN, an inf, a hang or an abort later.
//!
//! Why these numbers:
//! - Lengths: a scene's size ℓ (2D: the domain's diagonal; 3D: the diagonal of
//!   everything placed) is at least [`MIN_SCENE_SIZE`], every coordinate lies within
//!   ±[`MAX_COORD`] and within [`MAX_SIZES_FROM_ORIGIN`]·ℓ of the origin, and points
//!   that must differ (a segment's ends, a box's sides) are [`MIN_SEPARATION`]·ℓ
//!   apart. At 10⁶ ℓ from the origin an f64 still resolves 10⁻¹⁰ ℓ, the order of
//!   the ray offsets (10⁻¹⁰…10⁻⁹ ℓ); squares and products of lengths stay far from
//!   f64 under- and overflow.
//! - Radiometric values (emission, intensities, irradiance, sky radiance) are 0 or
//!   within [`RADIANCE`]; coefficients σ_a, σ_s are 0 or within [`SIGMA`]; |g| is at
//!   most [`MAX_ABS_G`]. In-scattered radiance is at most σ_s × (the largest phase
//!   value, 1.6·10⁵ for 3D HG at g = 0.999) × radiance ≤ 1.6·10³⁴ < f32::MAX; a
//!   nonzero value at least 10⁻²⁰ keeps sums of tiny weights (emitter selection,
//!   luminance floors) away from 0/0.
//! - Work: [`MAX_DEPTH`] bounds a path's events (σ_s = 10⁸, g = 0.999 never escape:
//!   a depth of 4·10⁹ hung), [`MAX_SPP`] a pixel's samples, [`MAX_PIXELS`] an image
//!   (≈ 100–200 bytes per pixel in memory). Cancellation is checked per pixel, so
//!   these also bound how long Ctrl-C waits.

/// Largest |coordinate| of any point (scene units).
pub const MAX_COORD: f64 = 1e12;
/// Smallest scene size ℓ (scene units).
pub const MIN_SCENE_SIZE: f64 = 1e-6;
/// Every coordinate within this many scene sizes of the origin.
pub const MAX_SIZES_FROM_ORIGIN: f64 = 1e6;
/// Points that must differ are at least this fraction of ℓ apart.
pub const MIN_SEPARATION: f64 = 1e-9;
/// Nonzero radiometric values (radiance, intensity, irradiance), any unit.
pub const RADIANCE: (f64, f64) = (1e-20, 1e20);
/// Nonzero extinction coefficients σ_a, σ_s (m⁻¹).
pub const SIGMA: (f64, f64) = (1e-12, 1e9);
/// Largest |g| of the Henyey–Greenstein phase function.
pub const MAX_ABS_G: f64 = 0.999;
/// Length of a direction vector (it is normalised; too short a one is a typo, and its
/// square would underflow).
pub const DIRECTION_LENGTH: (f64, f64) = (1e-9, 1e12);
/// Smallest nonzero angular radius of a sun (degrees): its radiance E/(π sin²α)
/// stays finite (the real sun: 0.27°).
pub const MIN_SUN_RADIUS_DEG: f64 = 1e-3;
/// Vertical field of view (degrees).
pub const FOV_DEG: (f64, f64) = (1e-2, 179.0);
/// Mesh scale factors.
pub const MESH_SCALE: (f64, f64) = (1e-12, 1e12);
/// Largest path length in scattering/reflection events.
pub const MAX_DEPTH: u32 = 100_000;
/// Largest samples per pixel (field, caches, render3d; probe points take more).
pub const MAX_SPP: u32 = 1 << 20;
/// Largest samples per probe point.
pub const MAX_PROBE_SPP: u32 = 1 << 30;
/// Largest pixels per side, and per image.
pub const MAX_SIDE: u32 = 16384;
pub const MAX_PIXELS: u64 = 1 << 24;
/// Largest |exposure| in stops: 2^100 × the largest radiance stays finite.
pub const MAX_EXPOSURE: f64 = 100.0;
/// Finite-difference step as a fraction of the scene size (`probe --fd-step`):
/// below ~10⁻¹⁵⁴ its square underflows; below 10⁻⁹ it is lost in the ray offsets.
pub const FD_STEP: (f64, f64) = (1e-9, 0.5);
/// Near-field clamp of medium elements, in march steps (`probe --medium-clamp`).
pub const MEDIUM_CLAMP: (f64, f64) = (1e-6, 1e6);
/// Refinement k of the probes' march (`--grading`): 0 (even steps) or up to 30
/// (first step k/(e^k − 1) ≈ 3·10⁻¹² of the even one; beyond, e^k overflows the
/// useful range of depths).
pub const GRADING: (f64, f64) = (0.0, 30.0);
/// Reach of a record past the nearest edge it sees, as a multiple of that
/// distance (`--edge-reach`; also bounds `--lamp-reach`, the same kind of limit
/// past the nearest point light): below 0.01 every record shrinks to the smallest
/// radius (one per query point); above 100 it limits nothing.
pub const EDGE_REACH: (f64, f64) = (0.01, 100.0);

/// An edge reach brought into [`EDGE_REACH`] (the app's fields, which the CLI
/// would refuse outside it).
pub fn clamp_edge_reach(k: f64) -> f64 {
    k.clamp(EDGE_REACH.0, EDGE_REACH.1)
}

/// `--eye-cone`: a half-angle in degrees (`CacheSettings::eye_cone_deg`); beyond
/// 90° a record would serve points the eye sees on its other side.
pub const EYE_CONE_DEG: (f64, f64) = (0.01, 90.0);

/// `--record-noise`: a relative standard error (below 1e-4 a record would want
/// millions of directions).
pub const RECORD_NOISE: (f64, f64) = (1e-4, 10.0);
/// Error threshold ε of the caches (`--eps`).
pub const EPS: (f64, f64) = (0.0, 1e30);

/// `v` is 0 or within `[lo, hi]` (and finite).
pub fn zero_or_within(v: f64, (lo, hi): (f64, f64)) -> bool {
    v == 0.0 || (lo..=hi).contains(&v)
}

/// The problem with a resolution, if any.
pub fn resolution_problem(w: u32, h: u32) -> Option<String> {
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Some(format!("must be between 1 and {MAX_SIDE} pixels per side, got {w}x{h}"));
    }
    let pixels = w as u64 * h as u64;
    (pixels > MAX_PIXELS).then(|| {
        format!("{w}x{h} is {pixels} pixels; at most {MAX_PIXELS} (e.g. 4096x4096) fit in memory with their statistics")
    })
}

/// Largest |angle| in degrees (ω_o, a box's rotation): beyond, f64 keeps no
/// fraction of a degree.
pub const MAX_ANGLE_DEG: f64 = 1e6;
