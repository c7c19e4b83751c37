//! Issue 14: every method stays finite, ends in bounded time and stops promptly when
//! cancelled, across the validated ranges (`volcache::limits`): g = ±0.999 and 0,
//! σ_t = 10⁻⁶…10⁵, albedo 0…1, radiance 10⁻²⁰…10²⁰, scenes from 10⁻⁶ to 10¹² across
//! and 10⁶ of their sizes from the origin, ε, finite-difference step and near-field
//! clamp at their ends. Each run is what a command computes (field, probe with every
//! method, caches with every method, render3d with every method), at tiny sizes, and
//! what it writes is checked too (EXR range, figures).

use glam::DVec2;
use std::time::{Duration, Instant};
use volcache::core::color::{Rgb, is_finite};
use volcache::core::metric::CacheMethod;
use volcache::core::taylor_rgb::TaylorRgb;
use volcache::figure::{FieldStyle, RecordColor, RecordStyle, error_map_figure, field_figure, records_figure};
use volcache::flatland::cached_field::{self, RecordMemo};
use volcache::flatland::field::{Field, FieldParams, field_errors, render_field};
use volcache::flatland::scene::Scene;
use volcache::pipeline::derivatives::{self, AwareSettings, PartDerivs, ReferenceSettings};
use volcache::pipeline::path::{Query, estimate};
use volcache::pipeline::probe::{Outgoing, ProbeSettings, capture};
use volcache::pipeline::proxy;
use volcache::progress::Progress;
use volcache::volume::cached as cached3;
use volcache::volume::render::{RenderParams, render};
use volcache::volume::scene::Scene as Scene3;

/// Generous wall-time bound of one run (a tiny image or one probe point). The
/// slowest measured on the 2-core machine was 1.3 s (caches at ε = 10³⁰ on the huge
/// scene; dense albedo-1 media with paths to max_depth take 0.6 s); noisy
/// neighbours can slow a run down several times.
const RUN_BOUND: Duration = Duration::from_secs(20);

/// Where a scene sits: half its size and its centre.
#[derive(Clone, Copy, Debug)]
struct Placement {
    name: &'static str,
    half: f64,
    centre: f64,
}

const TINY: Placement = Placement {
    name: "tiny",
    half: 5e-7,
    centre: 0.0,
};
const UNIT: Placement = Placement {
    name: "unit",
    half: 1.0,
    centre: 0.0,
};
const HUGE: Placement = Placement {
    name: "huge",
    half: 5e11,
    centre: 0.0,
};
/// 10⁶ scene sizes from the origin, the most `limits` allow (ℓ = 2.8 here).
const FAR: Placement = Placement {
    name: "far",
    half: 1.0,
    centre: 2.5e6,
};

#[derive(Clone, Copy, Debug)]
struct Medium {
    g: f64,
    sigma_t: f64,
    albedo: f64,
}

impl Medium {
    fn json(&self) -> String {
        format!(
            r#""sigma_a": {:e}, "sigma_s": {:e}, "g": {}"#,
            self.sigma_t * (1.0 - self.albedo),
            self.sigma_t * self.albedo,
            self.g
        )
    }
}

/// The full medium grid, and its corners (used on the other placements).
fn media(full: bool) -> Vec<Medium> {
    let (gs, sigmas, albedos): (&[f64], &[f64], &[f64]) = if full {
        (&[-0.999, 0.0, 0.999], &[1e-6, 1.0, 1e5], &[0.0, 0.5, 1.0])
    } else {
        (&[-0.999, 0.999], &[1e-6, 1e5], &[0.0, 1.0])
    };
    let mut v = Vec::new();
    for &g in gs {
        for &sigma_t in sigmas {
            for &albedo in albedos {
                v.push(Medium { g, sigma_t, albedo });
            }
        }
    }
    v
}

/// Every (placement, medium, radiance) of the grid.
fn grid() -> Vec<(Placement, Medium, f64)> {
    let mut v: Vec<(Placement, Medium, f64)> = media(true).into_iter().map(|m| (UNIT, m, 1.0)).collect();
    for p in [TINY, HUGE, FAR] {
        v.extend(media(false).into_iter().map(|m| (p, m, 1.0)));
    }
    for radiance in [1e-20, 1e20] {
        v.extend(media(false).into_iter().map(|m| (UNIT, m, radiance)));
    }
    v
}

fn scene2(p: Placement, m: Medium, radiance: f64) -> Scene {
    let at = |x: f64, y: f64| format!("[{:e}, {:e}]", p.centre + p.half * x, p.centre + p.half * y);
    let json = format!(
        r#"{{ "domain": {{"min": {}, "max": {}}},
             "segments": [
               {{"a": {}, "b": {}, "emission": {radiance:e}, "two_sided": false}},
               {{"points": [{}, {}, {}], "reflectance": 0.5}}
             ],
             "lights": [
               {{"type": "point", "position": {}, "intensity": {radiance:e}}},
               {{"type": "collimated", "direction": [1, -0.5], "aperture": [{}, {}], "irradiance": {radiance:e}}}
             ],
             "medium": {{ {}, "region": "domain" }},
             "render": {{"max_depth": 64}} }}"#,
        at(-1.0, -1.0),
        at(1.0, 1.0),
        at(0.5, 0.8),
        at(-0.5, 0.8),
        at(-0.3, 0.0),
        at(0.3, 0.0),
        at(0.3, -0.4),
        at(0.6, -0.6),
        at(-1.0, 0.2),
        at(-1.0, 0.6),
        m.json()
    );
    Scene::from_json(&json, "<grid>").unwrap_or_else(|e| panic!("{e}"))
}

fn scene3(p: Placement, m: Medium, radiance: f64) -> Scene3 {
    let v = |x: f64, y: f64, z: f64| {
        format!(
            "[{:e}, {:e}, {:e}]",
            p.centre + p.half * x,
            p.centre + p.half * y,
            p.centre + p.half * z
        )
    };
    let d = |x: f64, y: f64, z: f64| format!("[{:e}, {:e}, {:e}]", p.half * x, p.half * y, p.half * z);
    let json = format!(
        r#"{{ "camera": {{"position": {}, "look_at": {}, "fov_deg": 50}},
             "shapes": [
               {{"quad": {{"origin": {}, "u": {}, "v": {}}}, "reflectance": 0.6}},
               {{"box": {{"min": {}, "max": {}, "rotate_y_deg": 20}}, "reflectance": 0.4}},
               {{"quad": {{"origin": {}, "u": {}, "v": {}}}, "emission": {radiance:e}, "two_sided": false}}
             ],
             "lights": [
               {{"point": {{"position": {}, "intensity": {radiance:e}}}}},
               {{"sun": {{"direction": [0.3, -1, 0.2], "irradiance": {radiance:e}, "angular_radius_deg": 0.27}}}},
               {{"sky": {{"radiance": {radiance:e}}}}}
             ],
             "medium": {{ {}, "region": {{"box": {{"min": {}, "max": {}}}}} }},
             "render": {{"max_depth": 16}} }}"#,
        v(0.0, 0.5, 1.9),
        v(0.0, 0.3, 0.0),
        v(-1.0, -0.5, -1.0),
        d(0.0, 0.0, 2.0),
        d(2.0, 0.0, 0.0),
        v(-0.3, -0.5, -0.3),
        v(0.2, 0.3, 0.2),
        v(-0.2, 0.99, -0.2),
        d(0.4, 0.0, 0.0),
        d(0.0, 0.0, 0.4),
        v(0.5, 0.6, 0.4),
        m.json(),
        v(-1.0, -0.5, -1.0),
        v(1.0, 1.0, 1.0),
    );
    Scene3::from_json(&json, "<grid>", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// Run `f`, check its time and return its value.
fn timed<T>(what: &str, slowest: &mut (Duration, String), f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let out = f();
    let dt = t.elapsed();
    assert!(dt <= RUN_BOUND, "{what} took {dt:?}");
    if dt > slowest.0 {
        *slowest = (dt, what.to_string());
    }
    out
}

fn finite_field(f: &Field) -> bool {
    f.values.iter().all(|v| is_finite(*v))
}

fn finite_parts(p: &PartDerivs<volcache::core::space::D2>) -> bool {
    let ok = |t: &TaylorRgb<volcache::core::space::D2>| {
        t.channels
            .iter()
            .all(|c| c.value.is_finite() && c.grad.is_finite() && c.hess.is_finite())
    };
    ok(&p.direct) && ok(&p.single) && ok(&p.multiple) && ok(&p.total())
}

/// What every output of a field goes through: both figure styles and the EXR.
fn outputs_hold(scene: &Scene, f: &Field) {
    for style in [
        FieldStyle::FalseColor { log: true, range: None },
        FieldStyle::Tonemapped { exposure: 0.0 },
    ] {
        field_figure(f, Some(scene), &style, None);
    }
    volcache::output::encode_exr(f).unwrap();
}

#[test]
fn flatland_methods_stay_finite_over_the_grid() {
    let mut slowest = (Duration::ZERO, String::new());
    let mut runs = 0;
    for (p, m, radiance) in grid() {
        let scene = scene2(p, m, radiance);
        let name = format!("{} {m:?} L {radiance:e}", p.name);
        let mut fp = FieldParams::from_scene(&scene);
        (fp.width, fp.height, fp.spp) = (4, 3, 1);
        // field, and caches --method pt (the same renderer)
        let field = timed(&format!("field {name}"), &mut slowest, || {
            render_field(&scene, &fp, &Progress::new()).unwrap()
        });
        assert!(finite_field(&field.field), "field {name}");
        assert!(field.std_error.iter().all(|e| e.is_finite()), "field {name}");
        outputs_hold(&scene, &field.field);
        // probe at the centre and near a corner, every method
        let (c, h) = (DVec2::splat(p.centre), p.half);
        for x in [c + DVec2::new(0.01, 0.02) * h, c + DVec2::new(0.97, -0.98) * h] {
            let q = Query::from_quantity(fp.quantity, DVec2::X);
            let e = timed(&format!("probe pt {name}"), &mut slowest, || {
                estimate(&scene, x, &q, &fp.settings, 4, 1, 0)
            });
            assert!(
                is_finite(e.mean.total()) && is_finite(e.std_error.total()),
                "probe pt {name}"
            );
            let ps = ProbeSettings {
                rays: 32,
                steps: 3,
                settings: fp.settings,
                ..ProbeSettings::default_for::<volcache::core::space::D2>()
            };
            let lf = capture(&scene, x, Outgoing::Direction(DVec2::X), &ps, 1, 0, &Progress::new()).unwrap();
            let aw = AwareSettings::default();
            let aware = timed(&format!("probe aware {name}"), &mut slowest, || {
                derivatives::aware(&lf, &proxy::build(&lf, aw.rule), &aw)
            });
            assert!(finite_parts(&aware), "probe aware {name} at {x}: {aware:?}");
            assert!(finite_parts(&derivatives::unaware(&lf)), "probe unaware {name} at {x}");
            let rs = ReferenceSettings {
                spp: 2,
                relative_step: 1e-2,
            };
            let r = timed(&format!("probe reference {name}"), &mut slowest, || {
                derivatives::reference_at(&scene, x, Outgoing::Direction(DVec2::X), &rs, &fp.settings, 1)
            });
            assert!(finite_parts(&r.parts), "probe reference {name} at {x}");
            runs += 4;
        }
        // caches, both cache methods
        for method in [cached_field::CacheMethod::Ours, cached_field::CacheMethod::Jarosz08] {
            let mut cs = cached_field::CacheSettings::new::<volcache::core::space::D2>(method, 0.05, fp.settings);
            (cs.probe.rays, cs.probe.steps) = (24, 3);
            let cf = timed(&format!("caches {method:?} {name}"), &mut slowest, || {
                cached_field::render_cached(&scene, &fp, &cs, None, &mut RecordMemo::new(), &Progress::new()).unwrap()
            });
            assert!(finite_field(&cf.field), "caches {method:?} {name}");
            let e = field_errors(&cf.field, &field.field);
            assert!(
                e.rmse.is_finite() && e.relmse.is_finite(),
                "caches {method:?} {name}: {e:?}"
            );
            outputs_hold(&scene, &cf.field);
            error_map_figure(&cf.field, &field.field, Some(&scene), None, false, None);
            let records: Vec<_> = cf.records.iter().flatten().cloned().collect();
            records_figure(
                Some(&cf.field),
                &scene,
                &records,
                &RecordStyle::colored(RecordColor::ByRadius),
                None,
            );
            runs += 1;
        }
        runs += 1;
    }
    eprintln!("{runs} flatland runs; slowest {:?} ({})", slowest.0, slowest.1);
}

/// The option ends on one scene per medium corner: ε ∈ {0, 10³⁰}, finite-difference
/// steps 10⁻⁹ and 0.5 of the scene, near-field clamps 10⁻⁶ and 10⁶ march steps.
#[test]
fn flatland_option_extremes_stay_finite() {
    let mut slowest = (Duration::ZERO, String::new());
    for m in media(false) {
        for p in [TINY, UNIT, HUGE] {
            let scene = scene2(p, m, 1.0);
            let name = format!("{} {m:?}", p.name);
            let x = DVec2::splat(p.centre) + DVec2::new(0.1, -0.2) * p.half;
            let mut fp = FieldParams::from_scene(&scene);
            (fp.width, fp.height, fp.spp) = (4, 4, 1);
            for relative_step in [volcache::limits::FD_STEP.0, volcache::limits::FD_STEP.1] {
                let rs = ReferenceSettings { spp: 4, relative_step };
                let r = timed(&format!("reference h {relative_step} {name}"), &mut slowest, || {
                    derivatives::reference_at(&scene, x, Outgoing::Direction(DVec2::X), &rs, &fp.settings, 3)
                });
                assert!(finite_parts(&r.parts), "reference h {relative_step} {name}");
            }
            let ps = ProbeSettings {
                rays: 48,
                steps: 4,
                settings: fp.settings,
                ..ProbeSettings::default_for::<volcache::core::space::D2>()
            };
            let lf = capture(&scene, x, Outgoing::Direction(DVec2::X), &ps, 1, 0, &Progress::new()).unwrap();
            for medium_clamp in [volcache::limits::MEDIUM_CLAMP.0, volcache::limits::MEDIUM_CLAMP.1] {
                let aw = AwareSettings {
                    medium_clamp,
                    ..Default::default()
                };
                let d = derivatives::aware(&lf, &proxy::build(&lf, aw.rule), &aw);
                assert!(finite_parts(&d), "aware clamp {medium_clamp} {name}");
            }
            for eps in [volcache::limits::EPS.0, volcache::limits::EPS.1] {
                for method in [cached_field::CacheMethod::Ours, cached_field::CacheMethod::Jarosz08] {
                    let mut cs =
                        cached_field::CacheSettings::new::<volcache::core::space::D2>(method, eps, fp.settings);
                    (cs.probe.rays, cs.probe.steps, cs.second_order) = (32, 4, true);
                    let cf = timed(&format!("caches ε {eps} {method:?} {name}"), &mut slowest, || {
                        cached_field::render_cached(&scene, &fp, &cs, None, &mut RecordMemo::new(), &Progress::new())
                            .unwrap()
                    });
                    assert!(finite_field(&cf.field), "caches ε {eps} {method:?} {name}");
                }
            }
        }
    }
    eprintln!("slowest {:?} ({})", slowest.0, slowest.1);
}

fn finite_image(v: &[Rgb]) -> bool {
    v.iter()
        .all(|c| is_finite(*c) && c.abs().max_element() <= f32::MAX as f64)
}

#[test]
fn render3d_methods_stay_finite_over_the_grid() {
    let mut slowest = (Duration::ZERO, String::new());
    let mut runs = 0;
    for (p, m, radiance) in grid() {
        let scene = scene3(p, m, radiance);
        let name = format!("{} {m:?} L {radiance:e}", p.name);
        let mut rp = RenderParams::from_scene(&scene);
        (rp.width, rp.height, rp.spp) = (4, 3, 2);
        let img = timed(&format!("render3d pt {name}"), &mut slowest, || {
            render(&scene, &rp, &Progress::new()).unwrap()
        });
        assert!(finite_image(&img.values) && finite_image(&img.medium), "pt {name}");
        let mut cp = cached3::CachedRenderParams::from_scene(&scene);
        cp.image = rp.clone();
        cp.surface_paths = 1;
        for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
            let mut cs = cached3::CacheSettings::new::<volcache::core::space::D3>(
                method,
                cached3::default_eps(method, &scene),
                rp.settings,
            );
            (cs.probe.rays, cs.probe.steps) = (32, 4);
            let r = timed(&format!("render3d {method:?} {name}"), &mut slowest, || {
                cached3::render_cached(
                    &scene,
                    &cp,
                    &cs,
                    None,
                    &mut cached3::RecordMemo::new(),
                    &Progress::new(),
                )
                .unwrap()
            });
            let img = &r.reconstruction.image;
            assert!(
                finite_image(&img.values) && finite_image(&img.medium),
                "{method:?} {name}"
            );
            assert_eq!(r.reconstruction.uncovered, 0, "{method:?} {name}");
            runs += 1;
        }
        runs += 1;
    }
    eprintln!("{runs} render3d runs; slowest {:?} ({})", slowest.0, slowest.1);
}

/// Cancel `f` (given the progress handle) after `after`; it must return within
/// `bound` of the cancel.
fn stops_promptly<T: Send>(what: &str, f: impl FnOnce(&Progress) -> T + Send) {
    let progress = Progress::new();
    let done = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|s| {
        let watcher = s.spawn(|| {
            let start = Instant::now();
            while start.elapsed() < Duration::from_millis(300) {
                if done.load(std::sync::atomic::Ordering::Relaxed) {
                    return None;
                }
                std::thread::sleep(Duration::from_millis(5));
            }
            progress.cancel();
            Some(Instant::now())
        });
        f(&progress);
        let end = Instant::now();
        done.store(true, std::sync::atomic::Ordering::Relaxed);
        let cancelled_at = watcher
            .join()
            .unwrap()
            .unwrap_or_else(|| panic!("{what} ended before it could be cancelled"));
        let waited = end.saturating_duration_since(cancelled_at);
        eprintln!("{what}: stopped {waited:?} after the cancel");
        // Measured: 4 ms (render3d caches) to 1.9 s (a probe of 65536 rays, whose
        // rays in flight finish their 10⁵-event paths).
        assert!(waited <= Duration::from_secs(10), "{what} took {waited:?} to stop");
    });
}

/// The slowest corner of the ranges — σ_t = 10⁵, albedo 1, g = 0.999, the deepest
/// paths allowed (max_depth 10⁵) — at sizes that would take minutes: each method
/// returns soon after a cancel.
#[test]
fn every_method_stops_promptly_when_cancelled() {
    let m = Medium {
        g: 0.999,
        sigma_t: 1e5,
        albedo: 1.0,
    };
    let depth = volcache::limits::MAX_DEPTH;
    let mut s2 = scene2(UNIT, m, 1.0);
    s2.desc.render.max_depth = depth;
    let mut fp = FieldParams::from_scene(&s2);
    (fp.width, fp.height, fp.spp) = (64, 64, 64);
    fp.settings.max_depth = depth;
    stops_promptly("field", |pr| assert!(render_field(&s2, &fp, pr).is_err()));
    for method in [cached_field::CacheMethod::Ours, cached_field::CacheMethod::Jarosz08] {
        let mut cs = cached_field::CacheSettings::new::<volcache::core::space::D2>(method, 1e-3, fp.settings);
        cs.probe.settings.max_depth = depth;
        stops_promptly(&format!("caches {method:?}"), |pr| {
            assert!(cached_field::render_cached(&s2, &fp, &cs, None, &mut RecordMemo::new(), pr).is_err())
        });
    }
    let ps = ProbeSettings {
        rays: 1 << 16,
        settings: fp.settings,
        ..ProbeSettings::default_for::<volcache::core::space::D2>()
    };
    stops_promptly("probe capture", |pr| {
        assert!(capture(&s2, DVec2::new(0.1, 0.1), Outgoing::Direction(DVec2::X), &ps, 1, 0, pr).is_err())
    });
    let s3 = scene3(UNIT, m, 1.0);
    let mut rp = RenderParams::from_scene(&s3);
    (rp.width, rp.height, rp.spp) = (64, 48, 64);
    rp.settings.max_depth = depth;
    stops_promptly("render3d pt", |pr| assert!(render(&s3, &rp, pr).is_err()));
    let mut cp = cached3::CachedRenderParams::from_scene(&s3);
    cp.image = rp.clone();
    for method in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        let cs = cached3::CacheSettings::new::<volcache::core::space::D3>(method, 1e-6, rp.settings);
        stops_promptly(&format!("render3d {method:?}"), |pr| {
            assert!(cached3::render_cached(&s3, &cp, &cs, None, &mut cached3::RecordMemo::new(), pr).is_err())
        });
    }
}
