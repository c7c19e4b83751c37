//! The workbench driven through egui_kittest (no window, no GPU): the UI's logic
//! with real background computations kept tiny (a few thousand samples each).

mod app_common;

use app_common::{click_world, harness, press, step_until, tiny_compare, workbench};
use eframe::egui;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use std::sync::Arc;
use std::time::{Duration, Instant};
use volcache::app::compare::{CompareKey, CompareParams, METHODS, compare_command, spawn_compare};
use volcache::app::jobs::no_notify;
use volcache::app::overlay::Overlay;
use volcache::flatland::cached_field::CacheMethod;
use volcache::flatland::field::FieldParams;
use volcache::flatland::scene::Scene;
use volcache::flatland::scene_desc::Quantity;

#[test]
fn starts_on_the_default_scene_and_refines_the_field() {
    let mut h = harness(workbench());
    h.get_by_label("volcache workbench: occluder");
    assert_eq!(h.state().doc.desc(), &Scene::default_scene().desc);
    step_until(&mut h, "the field", |w| w.field_converged());
    let level = h.state().field_level().unwrap().clone();
    assert_eq!((level.level, level.levels), (1, 1), "24×24 needs no coarser level");
    assert_eq!((level.params.width, level.params.height), (24, 24));
    assert!(level.rendered.field.values.iter().all(|v| v.is_finite()));
    h.get_by_label_contains("field done");
}

#[test]
fn toggling_overlays_changes_what_is_drawn() {
    let mut h = harness(workbench());
    step_until(&mut h, "the field", |w| w.field_converged());
    let with_scene = h.state().shapes_drawn;
    assert!(with_scene > 10, "segments and handles: {with_scene}");
    h.get_by_label("Scene").click();
    h.run_steps(2);
    assert!(!h.state().overlays.is_on(Overlay::Scene));
    assert_eq!(h.state().shapes_drawn, 0);

    h.get_by_label("Gradient field").click();
    h.step();
    assert!(h.state().overlays.is_on(Overlay::Gradients));
    step_until(&mut h, "the gradient grid", |w| {
        w.gradient_grid().is_some_and(|g| g.points.len() == 16)
    });
    let g = h.state().gradient_grid().unwrap().clone();
    assert!(g.points.iter().all(|p| p.aware.is_some_and(|d| d.is_finite())));
    // The frame's closing tick can take in the last points after the canvas drew:
    // one more frame draws the finished grid. (A CI run still saw 45 shapes — the
    // image, the wheel and a 4-point grid's arrows — after it: most likely the
    // texture, then keyed by the grid's address, taken for a dropped grid's whose
    // address the final one reused; keyed by identity since, `app::result_id`.)
    h.step();
    // 16 cells with an arrow each (all inside the medium), and the colour wheel.
    assert!(h.state().shapes_drawn >= 16 * 3, "{}", h.state().shapes_drawn);
    h.get_by_label("Gradient field").click();
    h.run_steps(2);
    assert_eq!(h.state().shapes_drawn, 0);
    assert!(h.state().gradient_grid().is_none(), "turned off: cancelled and cleared");
}

#[test]
fn clicking_places_the_probe_and_the_inspector_shows_finite_numbers() {
    let mut h = harness(workbench());
    h.step();
    let at = DVec2::new(0.1, -0.3);
    click_world(&mut h, at);
    let probe = h.state().probe.expect("the click placed the probe");
    assert!((probe - at).length() < 0.01, "{probe}");
    step_until(&mut h, "the probe", |w| w.probe_done());
    let r = h.state().readouts();
    assert_eq!(r.iter().map(|r| r.name).collect::<Vec<_>>(), ["aware", "unaware"]);
    assert!(r.iter().all(|r| r.is_finite() && r.lum.value > 0.0), "{r:?}");
    h.get_by_label("∂L/∂x");
    // The reference on demand, with its progress bar, then three columns.
    let button = h.get_by_label("Compute reference (64 spp)");
    button.scroll_to_me();
    button.click();
    step_until(&mut h, "the reference", |w| w.reference_done());
    let r = h.state().readouts();
    assert_eq!(r.len(), 3);
    assert!(r[2].is_finite() && r[2].stderr.is_some_and(|e| e.grad.is_finite()));
    // Dragging the probe follows: a new light field at the new place.
    h.run_steps(2); // the layout settles with the new column
    let from = h.state().screen_pos(probe).unwrap();
    let to = h.state().screen_pos(DVec2::new(-0.2, -0.5)).unwrap();
    h.hover_at(from);
    press(&h, from, true);
    for k in 1..=4 {
        h.hover_at(from + (to - from) * (k as f32 / 4.0));
    }
    press(&h, to, false);
    h.step();
    let moved = h.state().probe.unwrap();
    assert!((moved - DVec2::new(-0.2, -0.5)).length() < 0.01, "{moved}");
    assert!(
        h.state().reference_result().is_none(),
        "the reference belongs to the old point"
    );
    step_until(&mut h, "the moved probe", |w| w.probe_done());
    assert_eq!(h.state().probe_result().unwrap().at, moved);
}

#[test]
fn editing_a_parameter_cancels_and_restarts_the_computation() {
    let mut wb = workbench();
    // Big enough to still be running when the parameter changes.
    (wb.field_params.width, wb.field_params.height, wb.field_params.spp) = (200, 200, 256);
    let mut h = harness(wb);
    h.step();
    let first = h.state().field_watch().unwrap();
    let starts = h.state().field_starts();
    assert!(first.is_running());
    h.get_by_label("fluence").click();
    h.step();
    assert_eq!(h.state().field_params.quantity, Quantity::Fluence);
    assert!(first.is_cancel_requested(), "the stale job was told to stop");
    assert_eq!(h.state().field_starts(), starts + 1);
    let second = h.state().field_watch().unwrap();
    assert!(!second.is_cancel_requested());
    // The stale job stops soon (checked per pixel).
    let t = Instant::now();
    while first.is_running() {
        assert!(t.elapsed() < Duration::from_secs(10));
        std::thread::sleep(Duration::from_millis(5));
    }
    // The new one delivers fluence levels; the status bar's Cancel stops it.
    step_until(&mut h, "a fluence level", |w| {
        w.field_level().is_some_and(|l| l.params.quantity == Quantity::Fluence)
    });
    if h.query_by_label("Cancel field").is_none() {
        let status = h.state().field_status();
        panic!(
            "no Cancel button for the field job: {status:?}, running: {}",
            second.is_running()
        );
    }
    h.get_by_label("Cancel field").click();
    h.step();
    assert!(second.is_cancel_requested());
    assert_eq!(h.state().field_starts(), starts + 1, "no restart without a change");
}

#[test]
fn loading_an_invalid_scene_shows_the_error_and_keeps_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(
        &bad,
        r#"{ "domain": { "min": [-1, -1], "max": [1, 1] }, "medium": { "sigma_a": -0.2, "sigma_s": 1 } }"#,
    )
    .unwrap();
    let mut h = harness(workbench());
    h.step();
    let (before, rev) = (h.state().doc.desc().clone(), h.state().doc.revision());
    h.state_mut().scene_path_mut().clone_from(&bad.display().to_string());
    h.get_by_label("Load").click();
    h.run_steps(2);
    let m = h.state().message.clone().expect("an error is shown");
    assert!(m.error && m.text.contains("bad.json: medium.sigma_a"), "{}", m.text);
    h.get_by_label_contains("must not be negative");
    assert_eq!((h.state().doc.desc(), h.state().doc.revision()), (&before, rev));
    h.get_by_label("volcache workbench: occluder");
}

#[test]
fn undo_restores_a_moved_segment() {
    let mut h = harness(workbench());
    h.step();
    let original = h.state().doc.desc().clone();
    // Drag the occluder (from (-0.35, 0.25) to (0.35, 0.25)) by its middle.
    let from = h.state().screen_pos(DVec2::new(0.0, 0.25)).unwrap();
    let to = h.state().screen_pos(DVec2::new(0.2, 0.0)).unwrap();
    h.hover_at(from);
    press(&h, from, true);
    for k in 1..=5 {
        h.hover_at(from + (to - from) * (k as f32 / 5.0));
    }
    press(&h, to, false);
    h.step();
    let a = h.state().doc.desc().segments[1].a.unwrap();
    assert!((DVec2::from_array(a) - DVec2::new(-0.15, 0.0)).length() < 0.01, "{a:?}");
    assert_eq!(
        h.state().doc.desc().segments[0],
        original.segments[0],
        "only the occluder moved"
    );
    let moved = h.state().doc.desc().clone();
    h.get_by_label("Undo").click();
    h.step();
    assert_eq!(h.state().doc.desc(), &original, "one drag is one undo step");
    h.get_by_label("Redo").click();
    h.step();
    assert_eq!(h.state().doc.desc(), &moved);
    // The same with the keyboard.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.step();
    assert_eq!(h.state().doc.desc(), &original);
    h.key_press_modifiers(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
    h.step();
    assert_eq!(h.state().doc.desc(), &moved);
}

#[test]
fn export_and_copied_command_give_the_same_png() {
    let dir = tempfile::tempdir().unwrap();
    let (app_png, cli_png) = (dir.path().join("app.png"), dir.path().join("cli.png"));
    let mut wb = workbench();
    wb.display.false_color = true;
    let mut h = harness(wb);
    step_until(&mut h, "the field", |w| w.field_converged());
    *h.state_mut().export_path_mut() = app_png.display().to_string();
    h.state_mut().export_png().unwrap();
    let command = h.state_mut().field_command().unwrap();
    assert!(!h.state().doc.is_dirty(), "the default scene needs no saving");
    let mut args: Vec<String> = command.split_whitespace().skip(1).map(String::from).collect();
    let out = args.iter().position(|a| a == "--out").unwrap() + 1;
    args[out] = cli_png.display().to_string();
    args.push("--quiet".into());
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_volcache"))
        .args(&args)
        .status()
        .unwrap();
    assert!(status.success(), "{command}");
    let (a, b) = (std::fs::read(&app_png).unwrap(), std::fs::read(&cli_png).unwrap());
    assert!(a == b, "`{command}` reproduces the exported figure byte for byte");
}

#[test]
fn without_a_display_the_app_names_the_headless_commands() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_volcache"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("volcache field") && err.contains("volcache probe"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn a_compare_run_finishes_with_finite_numbers_for_both_methods() {
    let mut wb = workbench();
    tiny_compare(&mut wb);
    let mut h = harness(wb);
    h.step();
    assert_eq!(h.state().compare_starts(), 0, "nothing computed until asked");
    h.get_by_label("Compare view").click();
    h.step();
    assert!(h.state().show_compare);
    h.run_steps(3); // a new window's first frame only measures it
    h.get_by_label_contains("equal cache count: 16 records of 24 rays");
    step_until(&mut h, "the comparison", |w| w.compare_done());
    let res = h.state().compare_result().unwrap().clone();
    assert_eq!((res.fp.width, res.fp.height), (12, 12));
    for m in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        let r = res.run(m).expect("both methods ran");
        assert!(r.is_finite() && r.errors.rmse >= 0.0, "{r:?}");
        assert!(!r.records.is_empty() && r.rays > 0);
    }
    h.run_steps(2);
    // The numbers are on screen, one caption per method, with the records' own
    // noise (which the error against the reference contains but does not name).
    assert_eq!(h.query_all_by_label_contains("RMSE").count(), 2);
    assert_eq!(h.query_all_by_label_contains("records' noise").count(), 2);
    h.get_by_label_contains("compare done");
    let command = h.state_mut().compare_command().unwrap();
    assert_eq!(
        command,
        "volcache figure compare --caches 16 --rays 24 --steps 2 --res 12x12 --ref-spp 4 --seed 1 --out out/compare"
    );
    // The command reproduces the records and errors headless.
    let dir = tempfile::tempdir().unwrap();
    let mut args: Vec<String> = command.split_whitespace().skip(1).map(String::from).collect();
    let out = args.iter().position(|a| a == "--out").unwrap() + 1;
    args[out] = dir.path().join("out").display().to_string();
    args.extend([
        "--ref-cache".into(),
        dir.path().join("rc").display().to_string(),
        "--quiet".into(),
    ]);
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_volcache"))
        .args(&args)
        .status()
        .unwrap();
    assert!(status.success(), "{command}");
    let json = std::fs::read_to_string(dir.path().join("out/compare_occluder.json")).unwrap();
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    for (run, m) in report["runs"]
        .as_array()
        .unwrap()
        .iter()
        .zip([CacheMethod::Ours, CacheMethod::Jarosz08])
    {
        let app = res.run(m).unwrap();
        assert_eq!(run["records"].as_u64(), Some(app.records.len() as u64), "{m:?}");
        let rmse = run["errors"]["rmse"].as_f64().unwrap();
        assert!(
            (rmse - app.errors.rmse).abs() <= 1e-12 * rmse.abs().max(1e-300),
            "{m:?}: {rmse} vs {}",
            app.errors.rmse
        );
    }
    // A parameter change restarts it; closing the window stops it.
    h.state_mut().compare_params.caches = 7;
    h.step();
    assert_eq!(h.state().compare_starts(), 2);
    h.get_by_label("Compare view").click();
    h.step();
    assert!(!h.state().show_compare && h.state().compare_starts() == 2);
}

/// The compare panel's "reach ≤ gradient noise" reaches the parameters, restarts
/// the comparison and is carried by the command that reproduces it.
#[test]
fn the_gradient_noise_reach_box_reaches_the_comparison() {
    a_methods_box_reaches_the_comparison("reach ≤ gradient noise", " --gradient-noise-reach ", |p| {
        p.gradient_noise_reach
    });
}

/// The compare panel's "reach ≤ lamp distance ×" (off in 2D by default) sets the
/// 3D default factor, restarts the comparison and is carried by the command.
#[test]
fn the_lamp_reach_box_reaches_the_comparison() {
    a_methods_box_reaches_the_comparison("reach ≤ lamp distance ×", " --lamp-reach 2 ", |p| {
        p.lamp_reach == Some(volcache::pipeline::budget::VOLUME_LAMP_REACH)
    });
}

/// Ticks the "Methods" section's box `label` and checks that `set` holds of the
/// parameters, that the comparison restarted and that its command has `flag`
/// (which it had not before).
fn a_methods_box_reaches_the_comparison(label: &str, flag: &str, set: fn(&CompareParams) -> bool) {
    let mut wb = workbench();
    tiny_compare(&mut wb);
    // Tall enough that the open "Methods" section is on screen unscrolled.
    let mut h = app_common::harness_sized(wb, [1280.0, 1600.0]);
    h.get_by_label("Compare view").click();
    h.step();
    assert_eq!(h.state().compare_starts(), 1);
    assert!(!h.state_mut().compare_command().unwrap().contains(flag.trim()));
    assert!(!set(&h.state().compare_params));
    h.get_by_label("Methods").click(); // closed by default
    h.run_steps(2);
    h.get_by_label(label).click();
    h.step();
    assert!(set(&h.state().compare_params), "{label}");
    assert_eq!(h.state().compare_starts(), 2);
    let command = h.state_mut().compare_command().unwrap();
    assert!(command.contains(flag), "{command}");
}

#[test]
fn toggling_the_records_and_error_overlays_changes_what_is_drawn() {
    let mut wb = workbench();
    tiny_compare(&mut wb);
    let mut h = harness(wb);
    step_until(&mut h, "the field", |w| w.field_converged());
    let base = h.state().shapes_drawn;
    h.get_by_label("Cache records").click();
    h.step();
    assert!(h.state().overlays.is_on(Overlay::Records));
    step_until(&mut h, "the comparison", |w| w.compare_done());
    h.run_steps(2);
    let ours = h
        .state()
        .compare_result()
        .unwrap()
        .run(CacheMethod::Ours)
        .unwrap()
        .records
        .len();
    let with_records = h.state().shapes_drawn;
    assert!(with_records > base, "{with_records} vs {base}");
    assert!(with_records - base <= ours, "at most a shape per record");
    // The other method's records.
    h.state_mut().overlay_method = CacheMethod::Jarosz08;
    h.run_steps(2);
    let jarosz = h
        .state()
        .compare_result()
        .unwrap()
        .run(CacheMethod::Jarosz08)
        .unwrap()
        .records
        .len();
    assert!(h.state().shapes_drawn > base && h.state().shapes_drawn - base <= jarosz);
    // The error map is one more layer.
    let before = h.state().shapes_drawn;
    h.get_by_label("Error map").click();
    h.run_steps(2);
    assert_eq!(h.state().shapes_drawn, before + 1);
    h.get_by_label("Error map").click();
    h.get_by_label("Cache records").click();
    h.run_steps(2);
    assert_eq!(h.state().shapes_drawn, base);
}

// The compare view's state logic, apart from the UI.
#[test]
fn params_follow_the_app_resolution_unless_set() {
    let scene = Scene::default_scene();
    let mut app = FieldParams::from_scene(&scene);
    app.seed = 7;
    app.omega_o_deg = 33.0; // app-only display choice: the comparison keeps the scene's
    let p = CompareParams::default();
    let fp = p.field_params(&scene, &app);
    assert_eq!((fp.width, fp.height, fp.seed), (app.width / 2, app.height / 2, 7));
    assert_eq!(fp.omega_o_deg, FieldParams::from_scene(&scene).omega_o_deg);
    let fixed = CompareParams {
        res: Some([40, 0]),
        ..p.clone()
    };
    let fp2 = fixed.field_params(&scene, &app);
    assert_eq!((fp2.width, fp2.height), (40, 1));
    let rp = p.reference_params(&fp);
    assert_eq!((rp.spp, rp.seed), (256, 7 ^ 0x5EED));
    let cs = p.cache_settings(CacheMethod::Jarosz08, &fp);
    assert_eq!((cs.probe.rays, cs.probe.steps, cs.seed), (512, 16, 7));
    assert_eq!(
        compare_command(Some("a b.json"), &fp, &p, "out/compare"),
        "volcache figure compare 'a b.json' --caches 150 --rays 512 --steps 16 --res 128x128 \
         --ref-spp 256 --seed 7 --out out/compare"
    );
    // The straight light per pixel and the edge reach reach the settings and the
    // command that reproduces the comparison.
    let tuned = CompareParams {
        direct_samples: Some(32),
        point_scatter: Some(48),
        near_light_paths: Some(300),
        edge_reach: Some(0.5),
        ..p.clone()
    };
    let cs = tuned.cache_settings(CacheMethod::Ours, &fp);
    assert_eq!(
        (cs.direct_samples, cs.point_scatter, cs.near_light_paths, cs.edge_reach),
        (Some(32), Some(48), Some(300), Some(0.5))
    );
    assert_eq!(
        compare_command(None, &fp, &tuned, "o"),
        "volcache figure compare --caches 150 --rays 512 --steps 16 --direct-samples 32 --point-scatter 48 \
         --near-light-paths 300 --edge-reach 0.5 --res 128x128 --ref-spp 256 --seed 7 --out o"
    );
    // The gradient-noise reach reaches ours' settings (Jarosz 2008 measures no
    // gradient noise) and the command.
    let noisy = CompareParams {
        gradient_noise_reach: true,
        ..p.clone()
    };
    assert!(noisy.cache_settings(CacheMethod::Ours, &fp).gradient_noise_reach);
    assert!(!noisy.cache_settings(CacheMethod::Jarosz08, &fp).gradient_noise_reach);
    assert!(!p.cache_settings(CacheMethod::Ours, &fp).gradient_noise_reach);
    assert_eq!(
        compare_command(None, &fp, &noisy, "o"),
        "volcache figure compare --caches 150 --rays 512 --steps 16 --gradient-noise-reach \
         --res 128x128 --ref-spp 256 --seed 7 --out o"
    );
    // The lamp reach (off by default in 2D) reaches both methods' settings and the
    // command; out-of-range factors are clamped as the edge reach's are.
    assert_eq!(p.cache_settings(CacheMethod::Ours, &fp).lamp_reach, None);
    let lamp = CompareParams {
        lamp_reach: Some(1.5),
        ..p.clone()
    };
    for m in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        assert_eq!(lamp.cache_settings(m, &fp).lamp_reach, Some(1.5));
    }
    assert_eq!(
        compare_command(None, &fp, &lamp, "o"),
        "volcache figure compare --caches 150 --rays 512 --steps 16 --lamp-reach 1.5 \
         --res 128x128 --ref-spp 256 --seed 7 --out o"
    );
    let huge = CompareParams {
        lamp_reach: Some(1e9),
        ..p.clone()
    };
    let k = huge.cache_settings(CacheMethod::Ours, &fp).lamp_reach.unwrap();
    assert_eq!(k, volcache::limits::EDGE_REACH.1);
}

#[test]
fn a_tiny_comparison_runs_both_methods() {
    let scene = Arc::new(Scene::default_scene());
    let params = CompareParams {
        caches: 16,
        rays: 24,
        steps: 2,
        res: Some([12, 12]),
        ref_spp: 4,
        ..Default::default()
    };
    let key = CompareKey {
        revision: 0,
        fp: params.field_params(&scene, &FieldParams::from_scene(&scene)),
        params,
    };
    let job = spawn_compare(scene, &key, no_notify());
    let t = std::time::Instant::now();
    while job.is_running() {
        assert!(t.elapsed().as_secs() < 60, "compare did not finish");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let got = job.poll();
    assert_eq!(got.len(), 3, "reference, then each method");
    let last = got.last().unwrap();
    assert!(last.is_complete() && got[0].runs.is_empty());
    for m in METHODS {
        let run = last.run(m).unwrap();
        assert!(run.is_finite() && !run.records.is_empty(), "{run:?}");
    }
}

#[test]
fn compare_state_runs_only_when_needed_and_restarts_on_change() {
    let mut wb = workbench();
    (wb.field_params.width, wb.field_params.height) = (8, 8);
    wb.compare_params = CompareParams {
        caches: 4,
        rays: 8,
        steps: 1,
        res: Some([8, 8]),
        ref_spp: 2,
        ..Default::default()
    };
    wb.tick();
    assert_eq!(wb.compare_starts(), 0, "closed and no overlay: nothing");
    wb.overlays.set(Overlay::Records, true);
    wb.tick();
    assert_eq!(wb.compare_starts(), 1, "the records overlay needs it");
    wb.overlays.set(Overlay::Records, false);
    wb.show_compare = true;
    wb.tick();
    assert_eq!(wb.compare_starts(), 1, "same key: no restart");
    // The app's resolution matters only without an explicit compare resolution.
    wb.field_params.width = 10;
    wb.tick();
    assert_eq!(wb.compare_starts(), 1);
    wb.compare_params.res = None;
    wb.tick();
    assert_eq!(wb.compare_starts(), 2);
    assert_eq!(wb.compare_key().fp.width, 5);
    let old = wb.compare_watch().unwrap();
    wb.compare_params.caches = 5;
    wb.tick();
    assert_eq!(wb.compare_starts(), 3);
    assert!(old.is_cancel_requested());
    wb.doc.edit("g", |d| d.medium.as_mut().unwrap().g = 0.3).unwrap();
    wb.tick();
    assert_eq!(wb.compare_starts(), 4, "a scene edit restarts it");
    // Closing stops a running comparison.
    let running = wb.compare_watch().unwrap();
    wb.show_compare = false;
    wb.tick();
    assert!(running.is_cancel_requested() || !running.is_running());
}

#[test]
fn record_outlines_lie_on_their_extents_and_skip_what_is_not_shown() {
    use volcache::app::overlay::{record_outline, record_shapes, records_scale};
    use volcache::app::view::{ViewState, Xform};
    use volcache::figure::RecordColor;
    use volcache::flatland::cached_field::RecordInfo;
    let rect = egui::Rect::from_min_size(egui::pos2(0.0, 0.0), egui::vec2(400.0, 400.0));
    let xf = Xform::new(rect, DVec2::splat(-1.0), DVec2::splat(1.0), &ViewState::default());
    let a0 = DVec2::new(1.0, 1.0).normalize();
    let record = |at: DVec2, radii: [f64; 2]| RecordInfo {
        position: at,
        axes: [a0, a0.perp()],
        radii,
        luminance: radii[0],
        rays: 10,
    };
    let r = record(DVec2::new(0.1, 0.2), [0.3, 0.1]);
    let pts = record_outline(&r, &xf, rect, 64).unwrap();
    assert_eq!(pts.len(), 64);
    for p in pts {
        let w = xf.to_world(p) - r.position;
        let q = (w.dot(a0) / 0.3).powi(2) + (w.dot(a0.perp()) / 0.1).powi(2);
        assert!((q - 1.0).abs() < 1e-2, "{q}");
    }
    assert!(record_outline(&record(DVec2::new(50.0, 0.0), [0.3, 0.1]), &xf, rect, 64).is_none());
    assert!(record_outline(&record(DVec2::new(f64::NAN, 0.0), [0.3, 0.1]), &xf, rect, 64).is_none());
    // Coloured by radius: small and large records differ; one shape per shown record.
    let rs = [record(DVec2::ZERO, [0.05, 0.05]), record(DVec2::ZERO, [0.5, 0.5])];
    let scale = records_scale(&[&rs], RecordColor::ByRadius);
    let shapes = record_shapes(&rs, RecordColor::ByRadius, scale.as_ref(), &xf);
    assert_eq!(shapes.len(), 2);
    let color = |s: &egui::Shape| match s {
        egui::Shape::Path(p) => format!("{:?}", p.stroke.color),
        other => panic!("{other:?}"),
    };
    assert_ne!(color(&shapes[0]), color(&shapes[1]));
}
