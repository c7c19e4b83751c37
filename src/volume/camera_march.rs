//! Camera rays of a cached 3D render: each camera sample's ray, its first hit, and
//! the stratified march points where in-scattered radiance is looked up.
//!
//! Sample k of pixel (i, j) draws from the stream (seed, j·W + i, k) of the *full*
//! image, as the path tracer does (`render`): two numbers for the position in the
//! pixel (the same camera rays as a path-traced render of the same seed), one for
//! the march offset ξ; surface and direct-light sampling follow. The march points
//! are t_n = t0 + (n + ξ)·Δ for t_n < t1, where [t0, t1] is the medium's piece of
//! the ray before its hit: Σ_n T(t_n) L_s(t_n) Δ is an unbiased (stratified)
//! estimate of ∫ T L_s dt. Placement and reconstruction derive the same points from
//! the same streams, so every point the render looks up was visited by placement.

use super::camera::Camera;
use super::mesh::Hit;
use super::scene::Scene;
use crate::core::rng::{Sampler, mix64};
use crate::pipeline::medium::Region;
use crate::pipeline::path::Sampling;
use crate::pipeline::world::World;
use glam::{DVec2, DVec3};

/// At most this many march points per camera ray: a step far below the scene's
/// size is stretched on long rays rather than allowed to hang the render.
pub const MAX_MARCH_POINTS: usize = 1 << 14;

/// One camera sample's ray.
#[derive(Clone, Copy, Debug)]
pub struct CameraRay {
    pub origin: DVec3,
    pub dir: DVec3,
    pub hit: Option<Hit>,
    /// The medium's piece [t0, t1] of the ray before the hit (or the world's edge).
    pub medium: Option<(f64, f64)>,
    /// March offset ξ in [0, 1).
    pub offset: f64,
    /// Beyond this t the transmittance from the camera is exactly 0 in f64 (optical
    /// depth past [`OPAQUE_DEPTH`] in every channel): march points there add 0 to
    /// the image, so they are not visited (placement would spend records on them).
    pub opaque_from: f64,
    /// The least attenuated channel's σ_t (0 without a medium): the march's
    /// roulette follows its optical depth.
    pub sigma_min: f64,
}

/// Optical depth from the medium's start past which march points are kept by
/// Russian roulette (camera transmittance 10⁻³): see [`CameraRay::march`].
pub const ROULETTE_DEPTH: f64 = 6.907_755_278_982_137;

/// Optical depth at which e^{−τ} underflows to exactly 0.0 in f64 (e^{−745.2} is
/// the smallest subnormal; 746 leaves a margin for rounding).
pub const OPAQUE_DEPTH: f64 = 746.0;

impl CameraRay {
    /// Sample `k` of full-image pixel `pixel` (row-major, `cam.width` wide). Returns
    /// the ray and its stream, positioned after the draws the ray used.
    /// `sampling` as the path tracer's camera samples (so both see the same rays).
    pub fn trace(
        scene: &Scene,
        cam: &Camera,
        pixel: usize,
        k: u32,
        (seed, sampling): (u64, Sampling),
    ) -> (CameraRay, Sampler) {
        let mut s = sampling.stream(seed, pixel as u64, k as u64);
        let (i, j) = (pixel % cam.width, pixel / cam.width);
        let p = DVec2::new(i as f64 + s.next_f64(), j as f64 + s.next_f64());
        let offset = s.next_f64();
        let dir = cam.direction(p);
        let origin = cam.position;
        let hit = scene.closest_hit(origin, dir, f64::INFINITY, None);
        let end = hit.map_or_else(|| scene.world_exit(origin, dir), |h| h.t);
        let medium = scene.medium.as_ref().and_then(|m| m.region.pieces(origin, dir, end));
        // The medium is homogeneous: optical depth σ_t (t − t0) from the piece's start;
        // the least attenuated channel sets where every channel has reached 0.
        let sigma_min = scene.medium.as_ref().map_or(0.0, |m| m.sigma_t.min_element().max(0.0));
        let opaque_from = match (&scene.medium, medium) {
            (Some(m), Some((t0, _))) if m.sigma_t.min_element() > 0.0 => t0 + OPAQUE_DEPTH / m.sigma_t.min_element(),
            _ => f64::INFINITY,
        };
        (
            CameraRay {
                origin,
                dir,
                hit,
                medium,
                offset,
                opaque_from,
                sigma_min,
            },
            s,
        )
    }

    /// The march step actually used: `step`, stretched so that the ray has at most
    /// [`MAX_MARCH_POINTS`] points.
    pub fn step(&self, step: f64) -> f64 {
        match self.medium {
            Some((t0, t1)) => step.max((t1 - t0) / MAX_MARCH_POINTS as f64),
            None => step,
        }
    }

    /// The march points (n, t_n, w_n) for a step `step` (> 0), up to where the
    /// camera's transmittance is 0 (`opaque_from`; the step does not depend on it).
    ///
    /// Past the optical depth [`ROULETTE_DEPTH`] from the medium's start (camera
    /// transmittance below 10⁻³ in every channel) a point is kept with probability
    /// q = e^{−(τ − ROULETTE_DEPTH)} and weight w = 1/q (else w = 1): unbiased, and
    /// each kept point counts as if seen through 10⁻³, so the variance stays
    /// bounded; a camera ray escaping into unbounded fog visits ~1/(σ_t Δ) points
    /// past that depth instead of up to [`MAX_MARCH_POINTS`] (an open fog of
    /// σ_t = 0.65 made placement put 41,713 records on an 8×6 image, 45 s). The
    /// decision comes from the ray's own offset and n, so placement and
    /// reconstruction visit the same points.
    pub fn march(&self, step: f64) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        let (t0, t1) = self.medium.unwrap_or((0.0, 0.0));
        let dt = self.step(step);
        let end = t1.min(self.opaque_from);
        let sigma = self.sigma_min;
        (0..)
            .map(move |n| (n, t0 + (n as f64 + self.offset) * dt))
            .take_while(move |&(n, t)| t < end && n < MAX_MARCH_POINTS)
            .filter_map(move |(n, t)| {
                let excess = sigma * (t - t0) - ROULETTE_DEPTH;
                if excess <= 0.0 {
                    return Some((n, t, 1.0));
                }
                let q = (-excess).exp();
                let u = (mix64(self.offset.to_bits() ^ mix64(n as u64)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
                (u < q).then(|| (n, t, 1.0 / q))
            })
    }

    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }
}

/// The window's full-image pixel indices in placement order (coarse to fine), and
/// the image's width and height (16 bits each) as the top of a memo's keys: the
/// walk of every query source of a cached render.
pub fn window_order(params: &super::render::RenderParams) -> (Vec<usize>, u128) {
    let [x0, y0, x1, y1] = params.window();
    let w = x1 - x0;
    let order = crate::core::cache::placement_order(w, y1 - y0)
        .into_iter()
        .map(|k| (y0 + k / w) * params.width + x0 + k % w)
        .collect();
    (
        order,
        (((params.width & 0xFFFF) << 16) | (params.height & 0xFFFF)) as u128,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fog_room_json() -> String {
        r#"{ "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40},
             "shapes": [{"quad": {"origin": [-5, -5, -1], "u": [10, 0, 0], "v": [0, 10, 0]}, "reflectance": 0.5}],
             "lights": [{"sky": {"radiance": 1}}],
             "medium": {"sigma_a": 0.1, "sigma_s": 0.2, "g": 0,
                        "region": {"box": {"min": [-2, -2, -1], "max": [2, 2, 2]}}} }"#
            .to_string()
    }

    fn fog_room() -> Scene {
        Scene::from_json(&fog_room_json(), "<test>", std::path::Path::new(".")).unwrap()
    }

    /// March points lie in the medium's piece before the hit, one per step, and
    /// the same (pixel, sample) always gives the same ray.
    #[test]
    fn march_points_stratify_the_medium_piece() {
        let s = fog_room();
        let cam = super::super::render::camera(&s, 8, 8);
        let (r, _) = CameraRay::trace(&s, &cam, 27, 3, (9, Sampling::Stratified));
        let (again, _) = CameraRay::trace(&s, &cam, 27, 3, (9, Sampling::Stratified));
        assert_eq!(r.dir, again.dir);
        assert_eq!(r.offset, again.offset);
        let (t0, t1) = r.medium.expect("the centre pixels see the fog box");
        let h = r.hit.expect("the wall behind the fog").t;
        assert!(t0 > 2.9 && t1 <= h + 1e-12, "{t0} {t1} {h}");
        let pts: Vec<(usize, f64, f64)> = r.march(0.1).collect();
        assert_eq!(pts.len(), ((t1 - t0) / 0.1 - r.offset).ceil() as usize);
        assert!(pts.iter().all(|&(_, t, w)| t >= t0 && t < t1 && w == 1.0));
        // A step far too small is stretched to the cap.
        assert_eq!(r.march(1e-300).count(), MAX_MARCH_POINTS);
    }

    /// Past the roulette depth few points are kept, with weights 1/q, and the march
    /// still estimates ∫ T dt without bias: averaged over many camera samples,
    /// Σ T(t_n) w_n Δ matches (1 − e^{−σ_t L})/σ_t on a ray whose medium piece is
    /// 15 optical depths long; no point is visited where T is exactly 0.
    #[test]
    fn march_roulette_keeps_the_estimate_unbiased() {
        let s = Scene::from_json(
            &fog_room_json().replace(r#""sigma_a": 0.1, "sigma_s": 0.2"#, r#""sigma_a": 1, "sigma_s": 4"#),
            "<test>",
            std::path::Path::new("."),
        )
        .unwrap();
        let m = s.medium.as_ref().unwrap();
        let cam = super::super::render::camera(&s, 8, 8);
        let step = 0.05;
        let (mut sum, mut sum2, mut deep, mut kept_deep) = (0.0, 0.0, 0usize, 0usize);
        let n = 4000;
        let (mut t0, mut t1) = (0.0, 0.0);
        for k in 0..n {
            let (r, _) = CameraRay::trace(&s, &cam, 27, k, (9, Sampling::Stratified));
            (t0, t1) = r.medium.unwrap();
            let dt = r.step(step);
            let mut est = 0.0;
            for (_, t, w) in r.march(step) {
                let tr = m.transmittance(r.origin, r.dir, t).x;
                assert!(tr > 0.0);
                est += tr * w * dt;
                kept_deep += (5.0 * (t - t0) > ROULETTE_DEPTH) as usize;
            }
            deep += (((t1 - t0) - ROULETTE_DEPTH / 5.0) / dt).max(0.0) as usize;
            sum += est;
            sum2 += est * est;
        }
        let len = t1 - t0;
        assert!(5.0 * len > 14.0, "the piece is {len}");
        let exact = (1.0 - (-5.0 * len).exp()) / 5.0;
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / (n - 1) as f64).sqrt();
        assert!(
            (mean - exact).abs() < 4.0 * se + 1e-3 * exact,
            "{mean} vs {exact} ± {se}"
        );
        assert!((mean - exact).abs() < 0.01 * exact, "{mean} vs {exact}");
        // About 1/(σ_t Δ) = 4 deep points per ray are kept, of 32.
        let per_ray = kept_deep as f64 / n as f64;
        assert!(
            per_ray < 1.25 / (5.0 * step) && deep > 7 * kept_deep,
            "kept {kept_deep} of {deep}"
        );
    }
}
