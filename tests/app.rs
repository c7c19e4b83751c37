//! The workbench driven through egui_kittest (no window, no GPU): the UI's logic
//! with real background computations kept tiny (a few thousand samples each).

use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use std::time::{Duration, Instant};
use volcache::app::overlay::Overlay;
use volcache::app::{Document, Workbench, install_fonts};
use volcache::flatland::scene::Scene;
use volcache::flatland::scene_desc::Quantity;

/// The default scene with computations small enough for tests.
fn workbench() -> Workbench {
    let mut wb = Workbench::new(Document::default_scene());
    let p = &mut wb.field_params;
    (p.width, p.height, p.spp) = (24, 24, 2);
    let m = &mut wb.method;
    (m.rays, m.steps, m.ref_spp, m.grid, m.grid_rays) = (96, 4, 64, 4, 24);
    wb
}

fn harness(wb: Workbench) -> Harness<'static, Workbench> {
    Harness::builder()
        .with_size([1280.0, 800.0])
        .with_context_setup(install_fonts)
        .build_ui_state(|ui, wb: &mut Workbench| wb.ui(ui), wb)
}

/// Step frames until `done` holds (30 s at most).
fn step_until(h: &mut Harness<'_, Workbench>, what: &str, done: impl Fn(&Workbench) -> bool) {
    let start = Instant::now();
    while !done(h.state()) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "timed out waiting for {what}"
        );
        h.step();
        std::thread::sleep(Duration::from_millis(2));
    }
    h.step();
}

fn press(h: &Harness<'_, Workbench>, pos: egui::Pos2, pressed: bool) {
    h.event(egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    });
}

fn click_world(h: &mut Harness<'_, Workbench>, p: DVec2) {
    let pos = h.state().screen_pos(p).expect("the canvas was drawn");
    h.hover_at(pos);
    press(h, pos, true);
    press(h, pos, false);
    h.step();
}

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
