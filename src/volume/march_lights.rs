//! Point lights along a camera ray's march: the light they scatter towards the
//! camera, ∫ T(t) σ_s f I T_L V / r² dt over the ray's medium piece, estimated
//! per camera sample with stratified equiangular distances (`core::equiangular`)
//! instead of at the march points.
//!
//! Why: the march evaluates the direct part at stratified points t_n, and a point
//! that lands near a point light brings I/r² into the pixel — unbiased, but a
//! spike whose variance has no bound as the ray passes closer to the light (the
//! rings of fireflies around a lamp in fog). Equiangular distances follow the
//! 1/r² peak, so what is left to vary is visibility, phase and transmittance.
//! The march points then leave the point lights out (`PointLights::Left`). The
//! estimator is the one 2D fields use per pixel (`pipeline::point_scatter`).

use super::camera_march::CameraRay;
use super::scene::Scene;
use crate::core::color::Rgb;
use crate::core::rng::Sampler;
use crate::pipeline::point_scatter::point_lights_along as scattered_along;

/// The point lights' light scattered towards the camera along `ray` (camera
/// transmittance included), over its medium piece up to where the camera's
/// transmittance is zero; zero without a medium or point lights. Per light, as
/// many stratified equiangular distances as the march has points at step `dt`
/// (the march's cost: one shadow ray a point), at least one.
pub fn point_lights_along(scene: &Scene, ray: &CameraRay, dt: f64, s: &mut Sampler, rays: &mut u64) -> Rgb {
    let (Some(m), Some((t0, t1))) = (&scene.medium, ray.medium) else {
        return Rgb::ZERO;
    };
    let end = t1.min(ray.opaque_from);
    if scene.point_lights.is_empty() || end <= t0 || !end.is_finite() {
        return Rgb::ZERO;
    }
    let n = ((end - t0) / dt)
        .ceil()
        .clamp(1.0, super::camera_march::MAX_MARCH_POINTS as f64) as u32;
    // The medium's pieces along the ray up to `end` are its piece (t0, end).
    scattered_along(scene, m, (ray.origin, ray.dir, end), n, s, rays)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// No surfaces: the estimate's mean over many camera samples is the integral
    /// by quadrature in θ = atan((t − t_c)/h) (dt = r²/h dθ, a smooth integrand),
    /// for a ray passing the light at 10⁻³ and at 0.3, chromatic fog, g = 0.7.
    #[test]
    fn the_estimate_is_the_single_scattering_integral() {
        let json = r#"{
          "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_deg": 40},
          "shapes": [],
          "lights": [{"point": {"position": [0.1, 0.2, -0.3], "intensity": [2, 1.5, 1]}}],
          "medium": {"sigma_a": [0.1, 0.3, 0.5], "sigma_s": [0.9, 0.6, 0.4], "g": 0.7,
                     "region": {"box": {"min": [-2, -2, -2], "max": [2, 2, 2]}}}
        }"#;
        let scene = Scene::from_json(json, "<test>", std::path::Path::new(".")).unwrap();
        let m = scene.medium.as_ref().unwrap();
        let light = scene.point_lights[0];
        for miss in [1e-3, 0.3] {
            let dir = DVec3::new(0.0, 0.0, -1.0);
            let origin = light.position + DVec3::new(miss, 0.0, 1.5);
            // The medium's piece of the ray: from the origin (inside) to z = −2.
            let (t0, t1) = (0.0, 3.2);
            let ray = CameraRay {
                origin,
                dir,
                hit: None,
                medium: Some((t0, t1)),
                offset: 0.5,
                opaque_from: f64::INFINITY,
                sigma_min: m.sigma_t.min_element(),
            };
            let n = 4000;
            let mut rays = 0;
            let (mut sum, mut sum2) = (Rgb::ZERO, Rgb::ZERO);
            for k in 0..n {
                let v = point_lights_along(&scene, &ray, 0.5, &mut Sampler::new(3, k), &mut rays);
                (sum, sum2) = (sum + v, sum2 + v * v);
            }
            let got = sum / n as f64;
            let se = ((sum2 / n as f64 - got * got) / (n - 1) as f64).powf(0.5);
            // Quadrature: t_c = 1.5 along the ray, h = miss.
            let (tc, h) = (1.5, miss);
            let (a, b) = (((t0 - tc) / h).atan(), ((t1 - tc) / h).atan());
            let steps = 200_000;
            let mut want = Rgb::ZERO;
            for j in 0..steps {
                let th = a + (j as f64 + 0.5) * (b - a) / steps as f64;
                let t = tc + h * th.tan();
                let x = origin + dir * t;
                let to = light.position - x;
                let r = to.length();
                let f = <crate::core::space::D3 as crate::pipeline::dim::Dim>::phase_eval(&m.phase, dir, to / r);
                let tr = (-m.sigma_t * (t + r)).exp();
                want += m.sigma_s * tr * light.intensity * (f / (r * r) * r * r / h * (b - a) / steps as f64);
            }
            let rel = ((got - want) / want).abs().max_element();
            println!("miss {miss}: {got} ± {se} vs {want} ({rel:.2e})");
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() <= 4.0 * se[c],
                    "miss {miss}: {got} ± {se} vs {want}"
                );
                assert!(se[c] <= 0.01 * want[c], "miss {miss}: standard error {se}");
            }
        }
    }
}
