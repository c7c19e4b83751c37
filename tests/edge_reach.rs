//! `CacheSettings::edge_reach`: a record reaches no farther than a multiple of its
//! distance to the nearest surface edge it sees. That distance comes from the
//! light field's silhouette points; here it is checked against exact geometry
//! (a segment's ends in 2D, a box's edges in 3D), and placement is checked to
//! honour the limit. A visible point light counts as an edge (the light scattered
//! around it peaks as sharply).

use glam::{DVec2, DVec3};
use volcache::flatland::cached_field::{CacheMethod, CacheSettings, RecordMemo, render_cached};
use volcache::flatland::field::FieldParams;
use volcache::flatland::scene::Scene;
use volcache::pipeline::probe::Outgoing;
use volcache::pipeline::record::compute_record;
use volcache::pipeline::seen_ends::nearest_seen_end;
use volcache::pipeline::world::World;
use volcache::progress::Progress;

/// One segment in fog lit by a point light: nothing else to see, so from anywhere
/// both of its ends are visible edges (a segment cannot hide its own ends).
const BAR: &str = r#"{
  "domain": {"min": [-1, -1], "max": [1, 1]},
  "segments": [{"name": "bar", "a": [-0.3, 0.1], "b": [0.4, -0.05], "reflectance": 0.5}],
  "lights": [{"type": "point", "position": [0.1, 0.7], "intensity": 1.0}],
  "medium": {"sigma_a": 0.1, "sigma_s": 0.9, "g": 0.3, "region": "everywhere"},
  "render": {"resolution": [64, 64], "spp": 16, "seed": 1}
}"#;

const BAR_ENDS: [DVec2; 2] = [DVec2::new(-0.3, 0.1), DVec2::new(0.4, -0.05)];

fn bar() -> Scene {
    Scene::from_json(BAR, "<bar>").unwrap_or_else(|e| panic!("{e}"))
}

fn settings_2d(rays: usize, edge_reach: Option<f64>) -> CacheSettings {
    let mut cs = CacheSettings::new::<volcache::core::space::D2>(CacheMethod::Ours, 0.05, Default::default());
    (cs.probe.rays, cs.probe.steps, cs.edge_reach) = (rays, 4, edge_reach);
    cs
}

fn nearest_end(x: DVec2) -> f64 {
    BAR_ENDS.iter().map(|e| e.distance(x)).fold(f64::INFINITY, f64::min)
}

/// From points 0.01 to 0.6 away from the bar, above, below, beyond its ends and
/// level with it, the light field's nearest edge is the nearer end of the bar to
/// 1% (the silhouette point is found exactly on the primitive).
#[test]
fn nearest_edge_is_the_nearer_end_of_a_segment() {
    let s = bar();
    let points = [
        DVec2::new(-0.31, 0.12),
        DVec2::new(-0.35, 0.3),
        DVec2::new(0.0, 0.2),
        DVec2::new(0.05, -0.4),
        DVec2::new(0.45, -0.1),
        DVec2::new(0.8, 0.5),
        DVec2::new(0.39, -0.03),
    ];
    for (k, &x) in points.iter().enumerate() {
        let d = compute_record(
            &s,
            x,
            Outgoing::Direction(DVec2::X),
            &settings_2d(1024, Some(1.0)),
            k as u64,
            &Progress::new(),
        )
        .unwrap();
        let exact = nearest_end(x);
        println!("{x:?}: nearest edge {:.5}, exact {exact:.5}", d.nearest_edge);
        assert!(
            (d.nearest_edge - exact).abs() < 0.01 * exact,
            "{x:?}: {} vs {exact}",
            d.nearest_edge
        );
    }
}

/// A record beside the bar's line sees it edge-on: the bar subtends less than
/// one ray spacing of 64 directions, yet the nearer end is its nearest edge, to
/// 1% (the world finds the ends the rays pass between). Without that the first
/// point, 1e-7 beside the line and 0.15 from the end, reported the other end
/// (0.79), and such records reached across the end (`occluder.json` at 256²,
/// budget 4: RMSE 0.024 → 0.009 with the ends found).
#[test]
fn an_end_seen_edge_on_is_an_edge() {
    let s = bar();
    let (a, b) = (BAR_ENDS[0], BAR_ENDS[1]);
    let along = (b - a).normalize();
    let across = along.perp();
    let mut k = 0;
    for h in [1e-7, 1e-4, 2e-3] {
        for (base, dir, dist) in [(a, -along, 0.15), (b, along, 0.3), (a, -along, 0.5)] {
            for side in [-1.0, 1.0] {
                let x = base + dir * dist + across * (side * h);
                k += 1;
                let d = compute_record(
                    &s,
                    x,
                    Outgoing::Direction(DVec2::X),
                    &settings_2d(64, Some(1.0)),
                    k,
                    &Progress::new(),
                )
                .unwrap();
                let exact = nearest_end(x);
                assert!(
                    (d.nearest_edge - exact).abs() < 0.01 * exact,
                    "{x:?}: {} vs {exact}",
                    d.nearest_edge
                );
            }
        }
    }
}

fn flat_scene(segments: &str) -> Scene {
    let json = format!(
        r#"{{"domain": {{"min": [-1, -1], "max": [1, 1]}}, "segments": [{segments}],
        "medium": {{"sigma_a": 0.1, "sigma_s": 0.9, "g": 0.0, "region": "everywhere"}},
        "render": {{"resolution": [8, 8], "spp": 1, "seed": 1}}}}"#
    );
    Scene::from_json(&json, "<seen_ends>").unwrap_or_else(|e| panic!("{e}"))
}

const LEVEL_BAR: &str = r#"{"name": "bar", "a": [-0.35, 0.25], "b": [0.35, 0.25], "reflectance": 0.5}"#;

/// `nearest_seen_end` beside a bar's line, however near (down to 1e-9): the
/// nearer end, exactly, with at most two rays.
#[test]
fn the_geometry_finds_an_end_seen_edge_on_exactly() {
    let s = flat_scene(LEVEL_BAR);
    for h in [1e-9, 1e-6, 1e-3, 0.004, 0.05] {
        for (x0, end) in [(-0.5, -0.35), (0.9, 0.35), (-0.36, -0.35)] {
            for side in [-1.0, 1.0] {
                let x = DVec2::new(x0, 0.25 + side * h);
                let exact = x.distance(DVec2::new(end, 0.25));
                let (d, rays) = nearest_seen_end(&s, x, 10.0);
                assert_eq!(d, exact, "{x:?}");
                assert!(rays <= 2, "{rays}");
            }
        }
    }
}

/// No end farther than `within` is reported, and an end hidden behind another
/// segment is passed over for the next one in sight.
#[test]
fn only_ends_within_reach_and_in_sight_count() {
    let s = flat_scene(LEVEL_BAR);
    let x = DVec2::new(-0.5, 0.3);
    let exact = x.distance(DVec2::new(-0.35, 0.25));
    assert_eq!(nearest_seen_end(&s, x, exact * 0.99).0, f64::INFINITY);
    assert_eq!(nearest_seen_end(&s, x, exact * 1.01).0, exact);
    // A wall between x and the bar's left end; its own ends are farther.
    let wall = r#"{"name": "wall", "a": [-0.42, 0.0], "b": [-0.42, 0.5], "reflectance": 0.5}"#;
    let s = flat_scene(&format!("{LEVEL_BAR}, {wall}"));
    let (d, _) = nearest_seen_end(&s, x, 10.0);
    let wall_end = x
        .distance(DVec2::new(-0.42, 0.5))
        .min(x.distance(DVec2::new(-0.42, 0.0)));
    assert_eq!(d, wall_end);
    assert!(d > exact);
}

/// Where two segments meet and x sees both, the corner is no silhouette (the
/// probe's rays see one depth on both sides of it); seen with one face only, it is.
#[test]
fn a_corner_seen_from_both_faces_is_no_silhouette() {
    let l = r#"{"name": "top", "a": [-0.3, 0.2], "b": [0.2, 0.2], "reflectance": 0.5},
               {"name": "side", "a": [0.2, 0.2], "b": [0.2, -0.3], "reflectance": 0.5}"#;
    let s = flat_scene(l);
    let corner = DVec2::new(0.2, 0.2);
    let x = DVec2::new(0.3, 0.3);
    let (d, _) = nearest_seen_end(&s, x, 10.0);
    assert_eq!(
        d,
        x.distance(DVec2::new(0.2, -0.3)).min(x.distance(DVec2::new(-0.3, 0.2)))
    );
    assert!(d > x.distance(corner) * 1.5, "{d}");
    // Above the top, short of the side's line: the side is hidden, the corner ends the top.
    let x = DVec2::new(0.1, 0.5);
    assert_eq!(nearest_seen_end(&s, x, 10.0).0, x.distance(corner));
}

/// 3D: a square lamp seen from beside its plane is found at its outline's
/// nearest point with 256 directions (0.2 rad apart; the lamp subtends 0.001–0.02
/// rad from these points); an edge of a box where x sees both faces is none, the
/// box's outline beyond them is.
#[test]
fn the_geometry_finds_edges_seen_edge_on_3d() {
    let json = r#"{
      "camera": {"position": [0, 1, 3], "look_at": [0, 0.5, 0], "fov_deg": 50},
      "shapes": [
        {"quad": {"origin": [-0.25, 1.0, -0.25], "u": [0.5, 0, 0], "v": [0, 0, 0.5]},
         "reflectance": 0, "emission": [5, 5, 5], "two_sided": true},
        {"box": {"min": [-0.2, -0.6, -0.2], "max": [0.2, -0.2, 0.2]}, "reflectance": 0.4}
      ],
      "medium": {"sigma_a": 0.05, "sigma_s": 0.5, "g": 0.0, "region": {"box": {"min": [-2, -2, -2], "max": [2, 2, 2]}}},
      "render": {"resolution": [16, 12], "spp": 1, "seed": 1, "max_depth": 4}
    }"#;
    let s = volcache::volume::scene::Scene::from_json(json, "<lamp>", std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut cs = CacheSettings::new::<volcache::core::space::D3>(CacheMethod::Ours, 1.0, Default::default());
    (cs.probe.rays, cs.probe.steps, cs.edge_reach) = (256, 2, Some(1.0));
    for (k, (x, nearest)) in [
        (DVec3::new(0.5, 1.0 + 1e-6, 0.1), DVec3::new(0.25, 1.0, 0.1)),
        (DVec3::new(-0.45, 1.0 - 1e-3, 0.0), DVec3::new(-0.25, 1.0, 0.0)),
        (DVec3::new(0.0, 1.004, 0.5), DVec3::new(0.0, 1.0, 0.25)),
    ]
    .into_iter()
    .enumerate()
    {
        let exact = x.distance(nearest);
        assert!((nearest_seen_end(&s, x, 10.0).0 - exact).abs() < 1e-5, "{x:?}");
        let d = compute_record(&s, x, Outgoing::Direction(DVec3::Z), &cs, k as u64, &Progress::new()).unwrap();
        assert!(
            (d.nearest_edge - exact).abs() < 1e-5,
            "{x:?}: {} vs {exact}",
            d.nearest_edge
        );
    }
    // Beside the box's +x/+z edge, seeing both faces: the nearest outline point
    // is on the vertical edges' neighbours, the top and bottom rims.
    let x = DVec3::new(0.25, -0.4, 0.25);
    let shared = (0.05f64 * 0.05 * 2.0).sqrt();
    let (d, _) = nearest_seen_end(&s, x, 10.0);
    assert!(d > 2.0 * shared && d.is_finite(), "{d} vs {shared}");
}

/// Placement with an edge reach k: every record's radii are at most k × its
/// distance to the nearer end of the bar (to the 1% above) or the metric's
/// smallest radius; without it, records near the ends reach past them.
#[test]
fn placement_keeps_records_within_their_reach() {
    let s = bar();
    let mut fp = FieldParams::from_scene(&s);
    (fp.width, fp.height) = (48, 48);
    let r_min = settings_2d(256, None).metric(s.scale()).r_min;
    let worst = |edge_reach: Option<f64>, k: f64| {
        let cached = render_cached(
            &s,
            &fp,
            &settings_2d(256, edge_reach),
            None,
            &mut RecordMemo::new(),
            &Progress::new(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let records = cached.records.concat();
        let ratio = records
            .iter()
            .map(|r| r.radii.iter().fold(0.0f64, |a, &b| a.max(b)) / (k * nearest_end(r.position)).max(r_min))
            .fold(0.0f64, f64::max);
        (ratio, records.len(), cached.uncovered_pixels)
    };
    for k in [0.5, 1.0] {
        let (ratio, n, holes) = worst(Some(k), k);
        println!("reach {k}: {n} records, worst radius / reach {ratio:.4}, {holes} uncovered");
        assert!(ratio <= 1.01, "reach {k}: {ratio}");
        assert_eq!(holes, 0);
    }
    let (ratio, n, _) = worst(None, 0.5);
    println!("no reach: {n} records, worst radius / (0.5 x edge distance) {ratio:.2}");
    assert!(ratio > 1.5, "{ratio}");
}

/// 3D: a box in fog under a lamp. From points that see one face of the box, the
/// light field's nearest edge is the distance to the nearest edge of that face's
/// outline (all of it silhouette), to the spacing of 16384 directions. (An edge
/// between two faces x sees is no visibility boundary and does not count.)
#[test]
fn nearest_edge_is_the_nearest_box_edge_3d() {
    let json = r#"{
      "camera": {"position": [0, 1, 3], "look_at": [0, 0.5, 0], "fov_deg": 50},
      "shapes": [
        {"box": {"min": [-0.2, 0.5, -0.3], "max": [0.3, 0.7, 0.2]}, "reflectance": 0.4},
        {"quad": {"origin": [-0.5, 1.5, -0.5], "u": [1, 0, 0], "v": [0, 0, 1]},
         "reflectance": 0, "emission": [5, 5, 5], "two_sided": true}
      ],
      "medium": {"sigma_a": 0.05, "sigma_s": 0.5, "g": 0.0, "region": {"box": {"min": [-2, -2, -2], "max": [2, 2, 2]}}},
      "render": {"resolution": [16, 12], "spp": 1, "seed": 1, "max_depth": 4}
    }"#;
    let s = volcache::volume::scene::Scene::from_json(json, "<box>", std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let (lo, hi) = (DVec3::new(-0.2, 0.5, -0.3), DVec3::new(0.3, 0.7, 0.2));
    // Distance from x to the box's 12 edges (segments).
    let edge_distance = |x: DVec3| {
        let corner = |i: usize| DVec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2]);
        let mut best = f64::INFINITY;
        for i in 0..8 {
            for bit in [1, 2, 4] {
                if i & bit == 0 {
                    let (a, b) = (corner(i), corner(i | bit));
                    let t = ((x - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
                    best = best.min(x.distance(a + (b - a) * t));
                }
            }
        }
        best
    };
    let mut cs = CacheSettings::new::<volcache::core::space::D3>(CacheMethod::Ours, 1.0, Default::default());
    (cs.probe.rays, cs.probe.steps, cs.edge_reach) = (16384, 2, Some(1.0));
    let points = [
        DVec3::new(0.05, 0.9, 0.0),   // above the top face
        DVec3::new(-0.3, 0.6, -0.05), // beside the -x face
        DVec3::new(0.05, 0.6, 0.35),  // in front of the +z face
        DVec3::new(0.31, 0.65, 0.0),  // 0.01 from the +x face
        DVec3::new(0.05, 0.3, -0.05), // below the bottom face
    ];
    for (k, &x) in points.iter().enumerate() {
        let d = compute_record(&s, x, Outgoing::Direction(DVec3::Z), &cs, k as u64, &Progress::new()).unwrap();
        // The nearest point of the face's outline is the nearest point of any
        // edge of the box; the lamp's outline is farther from every point.
        let exact = edge_distance(x);
        println!("{x:?}: nearest edge {:.5}, exact {exact:.5}", d.nearest_edge);
        assert!(
            d.nearest_edge >= exact * 0.999 && d.nearest_edge < exact * 1.1,
            "{x:?}: {} vs {exact}",
            d.nearest_edge
        );
    }
}

/// A point light is a peak the records must not reach across either: from points
/// nearer to the bar scene's light than to either end of the bar and seeing it,
/// the nearest edge is the light's distance (exactly: no rays find it); from
/// below the bar, where the bar hides the light, it is the nearer end again; and
/// with the straight light sampled per point (the light field then holds no delta
/// lights) the light is still found, by its shadow ray.
#[test]
fn a_visible_point_light_is_an_edge() {
    let s = bar();
    let light = DVec2::new(0.1, 0.7);
    let seen = [
        DVec2::new(0.1, 0.6),
        DVec2::new(-0.2, 0.75),
        DVec2::new(0.45, 0.9),
        DVec2::new(0.1, 0.35),
    ];
    for direct_samples in [None, Some(16)] {
        for (k, &x) in seen.iter().enumerate() {
            let mut cs = settings_2d(256, Some(1.0));
            cs.direct_samples = direct_samples;
            let d = compute_record(&s, x, Outgoing::Direction(DVec2::X), &cs, k as u64, &Progress::new()).unwrap();
            assert!(
                x.distance(light) < nearest_end(x),
                "{x:?}: the test wants the light nearer"
            );
            assert_eq!(d.nearest_edge, x.distance(light), "{x:?} ({direct_samples:?})");
        }
    }
    let hidden = DVec2::new(0.05, -0.2);
    let d = compute_record(
        &s,
        hidden,
        Outgoing::Direction(DVec2::X),
        &settings_2d(1024, Some(1.0)),
        9,
        &Progress::new(),
    )
    .unwrap();
    let exact = nearest_end(hidden);
    assert!(
        (d.nearest_edge - exact).abs() < 0.01 * exact,
        "{} vs {exact}",
        d.nearest_edge
    );
}

/// The same in 3D: in fog with a point light and nothing else, a record's nearest
/// edge is its distance to the light.
#[test]
fn a_visible_point_light_is_an_edge_3d() {
    let json = r#"{
      "camera": {"position": [0, 1, 3], "look_at": [0, 0.5, 0], "fov_deg": 50},
      "shapes": [],
      "lights": [{"point": {"position": [0.2, 0.9, -0.1], "intensity": [2, 2, 2]}}],
      "medium": {"sigma_a": 0.05, "sigma_s": 0.5, "g": 0.5, "region": {"box": {"min": [-2, -2, -2], "max": [2, 2, 2]}}},
      "render": {"resolution": [16, 12], "spp": 1, "seed": 1, "max_depth": 4}
    }"#;
    let s = volcache::volume::scene::Scene::from_json(json, "<point>", std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut cs = CacheSettings::new::<volcache::core::space::D3>(CacheMethod::Ours, 1.0, Default::default());
    (cs.probe.rays, cs.probe.steps, cs.edge_reach) = (256, 2, Some(1.0));
    for (k, x) in [DVec3::new(0.0, 0.5, 0.0), DVec3::new(1.0, -0.3, 0.4)]
        .into_iter()
        .enumerate()
    {
        let d = compute_record(&s, x, Outgoing::Direction(DVec3::Z), &cs, k as u64, &Progress::new()).unwrap();
        assert_eq!(d.nearest_edge, x.distance(DVec3::new(0.2, 0.9, -0.1)), "{x:?}");
    }
}

/// A one-sided lamp above a bar in fog: the lamp's ends and the bar's throw the
/// light around them, the fields the records extrapolate worst.
const LAMP: &str = r#"{
  "domain": {"min": [-1, -1], "max": [1, 1]},
  "segments": [
    {"name": "lamp", "a": [0.35, 0.55], "b": [-0.4, 0.5], "emission": 4.0, "two_sided": false},
    {"name": "bar", "a": [-0.2, -0.05], "b": [0.45, 0.05], "reflectance": 0.3}
  ],
  "medium": {"sigma_a": 0.1, "sigma_s": 1.5, "g": 0.3, "region": "everywhere"},
  "render": {"resolution": [48, 48], "spp": 16, "seed": 1}
}"#;

/// On the lamp scene at 120 records (512 directions, the straight light per pixel,
/// 256 samples), limiting the reach to the distance of the nearest edge lowers the
/// field's error for every record seed: against a 4096-spp reference, seeds 1-4,
/// 0.955, 0.835, 0.765, 0.897 of the error without the limit (mean 0.86; against
/// 8192 spp the same to 0.01; at 200 records 0.96, 0.82, 0.95, 0.86).
#[test]
fn reaching_no_farther_than_the_edges_lowers_the_error() {
    use volcache::flatland::field::{field_errors, render_field};
    let s = Scene::from_json(LAMP, "<lamp>").unwrap_or_else(|e| panic!("{e}"));
    let mut fp = FieldParams::from_scene(&s);
    (fp.width, fp.height) = (48, 48);
    let reference_params = FieldParams {
        spp: 4096,
        seed: 999,
        ..fp.clone()
    };
    let reference = render_field(&s, &reference_params, &Progress::new()).unwrap().field;
    let mut ratios = Vec::new();
    for seed in 1..=4 {
        let error = |reach| {
            let mut cs = settings_2d(512, reach);
            (cs.seed, cs.direct_samples) = (seed, Some(256));
            let c = render_cached(&s, &fp, &cs, Some(120), &mut RecordMemo::new(), &Progress::new())
                .unwrap_or_else(|e| panic!("{e}"));
            field_errors(&c.field, &reference).rmse
        };
        let (without, with) = (error(None), error(Some(1.0)));
        println!("seed {seed}: RMSE {without:.4e} without the limit, {with:.4e} with it");
        ratios.push(with / without);
    }
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!(mean < 0.93 && ratios.iter().all(|&r| r < 1.02), "{ratios:?}");
}
