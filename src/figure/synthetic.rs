//! Test-only synthetic data for figure examples: an occluder scene, a radiance
//! field with its shadow, and caches shaped like those of the two methods.

use crate::core::color::Rgb;
use crate::core::rng::mix64;
use crate::flatland::cached_field::RecordInfo;
use crate::flatland::field::Field;
use crate::flatland::scene::Scene;
use glam::DVec2;

/// A point light at (0, 0.8) above a segment from (−0.4, 0.3) to (0.4, 0.3), in a
/// medium filling [−1, 1]².
pub(crate) fn example_scene() -> Scene {
    let json = r#"{ "domain": { "min": [-1, -1], "max": [1, 1] },
        "segments": [{ "a": [-0.4, 0.3], "b": [0.4, 0.3], "reflectance": 0.5 }],
        "lights": [{ "type": "point", "position": [0.0, 0.8], "intensity": 1 }],
        "medium": { "sigma_a": 0.1, "sigma_s": 1, "region": "domain" } }"#;
    Scene::from_json(json, "test").unwrap()
}

const LIGHT: DVec2 = DVec2::new(0.0, 0.8);
const ENDS: [DVec2; 2] = [DVec2::new(-0.4, 0.3), DVec2::new(0.4, 0.3)];

fn uniform(k: u64) -> f64 {
    (mix64(k) >> 11) as f64 / (1u64 << 53) as f64
}

/// Distance to the nearer shadow edge (the rays from the light through the
/// segment's ends) and that edge's direction.
fn shadow_edge(p: DVec2) -> (f64, DVec2) {
    ENDS.iter()
        .map(|&e| {
            let dir = (e - LIGHT).normalize();
            let off = p - e;
            let d = if off.dot(dir) > 0.0 {
                off.perp_dot(dir).abs()
            } else {
                off.length()
            };
            (d, dir)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap()
}

/// A smooth field lit from the light with the segment's shadow below it, its
/// edges softened over `penumbra` (world units); `half_width` scales the occluder.
pub(crate) fn shadow_field(w: usize, h: usize, half_width: f64, penumbra: f64) -> Field {
    let mut f = Field::new(w, h, DVec2::splat(-1.0), DVec2::splat(1.0));
    for j in 0..h {
        for i in 0..w {
            let p = f.pixel_center(i, j);
            let lit = 0.05 + 0.6 / (0.15 + (p - LIGHT).length_squared());
            let shade = if p.y < 0.3 {
                // Where the ray towards the light crosses y = 0.3.
                let x = LIGHT.x + (p.x - LIGHT.x) * (LIGHT.y - 0.3) / (LIGHT.y - p.y);
                let s = ((x.abs() - half_width) / penumbra).clamp(-1.0, 1.0);
                0.5 + 0.5 * s
            } else {
                1.0
            };
            f.values[j * w + i] = Rgb::new(1.0, 0.85, 0.7) * (lit * (0.08 + 0.92 * shade));
        }
    }
    f
}

/// A synthetic cache over `scene`'s domain: a quadtree refined where records must
/// be small, one record per leaf. Occlusion-aware: small and elongated along the
/// shadow edges; unaware: circles shrinking only towards the light.
pub(crate) fn synthetic_records(scene: &Scene, aware: bool) -> Vec<RecordInfo> {
    let mut out = Vec::new();
    let mut stack = vec![(scene.domain_min, (scene.domain_max - scene.domain_min).x)];
    while let Some((lo, size)) = stack.pop() {
        let k = out.len() as u64 * 7 + stack.len() as u64;
        let c = lo + DVec2::splat(0.5 * size);
        let (across, along, dir) = if aware {
            let (d, dir) = shadow_edge(c);
            let across = (0.012 + 0.45 * d).min(0.2);
            // Elongated along the edge near it, round far from it.
            (across, (across * (1.0 + 2.0 * (-d / 0.06).exp())).min(0.2), dir)
        } else {
            let r = (0.03 + 0.25 * (c - LIGHT).length()).min(0.2);
            (r, r, DVec2::X)
        };
        if size > 1.2 * across && size > 0.02 {
            let h = 0.5 * size;
            for (i, j) in [(0.0, 0.0), (h, 0.0), (0.0, h), (h, h)] {
                stack.push((lo + DVec2::new(i, j), h));
            }
            continue;
        }
        let jitter = DVec2::new(uniform(k) - 0.5, uniform(k + 1) - 0.5) * 0.4 * size;
        let r = 0.8 * size;
        out.push(RecordInfo {
            position: c + jitter,
            axes: [dir, dir.perp()],
            radii: if aware { [along.max(r), r] } else { [r, r] },
            luminance: 0.1 + uniform(k + 2),
            rays: 1000 + (4000.0 * uniform(k + 3)) as u64,
        });
    }
    out
}
