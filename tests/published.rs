//! The published flatland values of `../shared/design/benchmarks.md` (E. d'Eon's
//! closed forms), reproduced by the path tracer within its own error bars.

use glam::DVec2;
use volcache::flatland::scene::Scene;
use volcache::pipeline::path::{Query, Settings, estimate};

fn point_source(c: f64) -> Scene {
    let json = format!(
        r#"{{ "domain": {{ "min": [-6, -6], "max": [6, 6] }},
            "lights": [ {{ "type": "point", "position": [0, 0], "intensity": {} }} ],
            "medium": {{ "sigma_a": {}, "sigma_s": {} }} }}"#,
        1.0 / std::f64::consts::TAU,
        1.0 - c,
        c
    );
    Scene::from_json(&json, "point_source").unwrap()
}

/// φ(r) of a unit-power isotropic point source in an infinite medium (σ_t = 1).
#[test]
fn point_source_fluence_matches_published_values() {
    let table = [
        (0.5, [(0.5, 0.3040237), (1.0, 0.1168853), (2.0, 0.03051825)]),
        (0.9, [(0.5, 0.5882582), (1.0, 0.3234545), (2.0, 0.1486884)]),
    ];
    for (c, rows) in table {
        let scene = point_source(c);
        for (k, (r, want)) in rows.into_iter().enumerate() {
            let e = estimate(
                &scene,
                DVec2::new(r, 0.0),
                &Query::Fluence,
                &Settings::default(),
                400_000,
                7,
                k as u64,
            );
            let got = e.mean.total().x;
            let se = e
                .std_error
                .direct
                .x
                .hypot(e.std_error.single.x)
                .hypot(e.std_error.multiple.x);
            println!("c={c} r={r}: {got:.6} ± {se:.6} (published {want})");
            assert!(
                (got - want).abs() < 4.0 * se + 1e-4 * want,
                "c={c} r={r}: {got} ± {se} vs {want}"
            );
            assert!(se < 0.01 * want, "error bar too wide to discriminate: {se}");
        }
    }
}

fn half_space(c: f64) -> Scene {
    let json = format!(
        r#"{{ "domain": {{ "min": [-10000, -2], "max": [10000, 10000] }},
            "lights": [ {{ "type": "collimated", "direction": [0, 1],
                          "aperture": [[-10000, -1], [10000, -1]], "irradiance": 1 }} ],
            "medium": {{ "sigma_a": {}, "sigma_s": {},
                         "region": {{ "rect": {{ "min": [-10000, 0], "max": [10000, 10000] }} }} }} }}"#,
        1.0 - c,
        c
    );
    Scene::from_json(&json, "half_space").unwrap()
}

/// Half-space albedo problem at normal incidence: reflected fraction R(c).
#[test]
fn half_space_reflectance_matches_published_values() {
    for (c, want, spp) in [
        (0.5, 0.13294292, 200_000),
        (0.9, 0.4522522, 200_000),
        (0.99, 0.77835416, 50_000),
    ] {
        let scene = half_space(c);
        let q = Query::Irradiance { normal: DVec2::Y };
        let e = estimate(
            &scene,
            DVec2::new(0.0, -0.5),
            &q,
            &Settings {
                max_depth: 100_000,
                rr_depth: 3,
                ..Default::default()
            },
            spp,
            3,
            0,
        );
        let got = e.mean.total().x;
        let se = e.std_error.multiple.x.hypot(e.std_error.single.x);
        println!("c={c}: R = {got:.6} ± {se:.6} (published {want})");
        assert!((got - want).abs() < 4.0 * se, "c={c}: {got} ± {se} vs {want}");
        assert!(se < 0.01 * want);
    }
}
