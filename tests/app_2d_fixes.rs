//! Issue 15 part 2, the workbench's 2D fixes, each driven through egui_kittest:
//! undo past a load, stale results, layout at small windows, the probe hint,
//! automatic exposure, opening scenes.

mod app_common;

use app_common::{click_world, harness, harness_sized, step_until, tiny_compare, workbench};
use eframe::egui;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use std::sync::Arc;
use volcache::app::layout::MIN_CANVAS_WIDTH;
use volcache::app::overlay::Overlay;
use volcache::figure::{FieldStyle, field_to_rgba};
use volcache::flatland::field::Field;
use volcache::flatland::scene::DEFAULT_SCENE_JSON;

/// Load A, edit it, load B, undo: A comes back with A's path, and Save writes A's
/// file, never B's (Save once wrote the restored A over B). Redo brings B back
/// with B's path.
#[test]
fn undo_past_a_load_restores_the_file_and_save_never_writes_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
    // Small renders: a load resets the field to the scene's own render block.
    let a_json = DEFAULT_SCENE_JSON.replace("[256, 256], \"spp\": 128", "[16, 16], \"spp\": 2");
    let b_json = a_json.replace("\"g\": 0.0", "\"g\": 0.2");
    assert!(a_json != DEFAULT_SCENE_JSON && b_json != a_json);
    std::fs::write(&a, &a_json).unwrap();
    std::fs::write(&b, &b_json).unwrap();
    let mut h = harness(workbench());
    h.step();
    let load = |h: &mut egui_kittest::Harness<'_, volcache::app::Workbench>, p: &std::path::Path| {
        *h.state_mut().scene_path_mut() = p.display().to_string();
        h.get_by_label("Load").click();
        h.run_steps(2);
    };
    load(&mut h, &a);
    h.get_by_label("volcache workbench: a");
    h.state_mut()
        .doc
        .edit("g", |d| d.medium.as_mut().unwrap().g = 0.6)
        .unwrap();
    h.run_steps(2);
    let edited_a = h.state().doc.desc().clone();
    load(&mut h, &b);
    h.get_by_label("volcache workbench: b");
    let b_desc = h.state().doc.desc().clone();

    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert_eq!(h.state().doc.desc(), &edited_a);
    h.get_by_label("volcache workbench: a (edited)");
    assert_eq!(h.state_mut().scene_path_mut().as_str(), a.display().to_string());
    h.get_by_label("Save").click();
    h.run_steps(2);
    assert_eq!(std::fs::read_to_string(&b).unwrap(), b_json, "B's file untouched");
    let saved: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&a).unwrap()).unwrap();
    assert_eq!(saved["medium"]["g"].as_f64(), Some(0.6), "A saved to A's own file");

    h.get_by_label("Redo").click();
    h.run_steps(2);
    assert_eq!(h.state().doc.desc(), &b_desc);
    h.get_by_label_contains("volcache workbench: b");
    assert_eq!(h.state_mut().scene_path_mut().as_str(), b.display().to_string());
}

/// The embedded scene has no file: Save asks for a name instead of inventing one,
/// and "copy as command" writes its copy without making it the scene's file.
#[test]
fn save_writes_only_a_named_file() {
    let mut h = harness(workbench());
    h.step();
    h.state_mut()
        .doc
        .edit("g", |d| d.medium.as_mut().unwrap().g = 0.3)
        .unwrap();
    h.get_by_label("Save").click();
    h.run_steps(2);
    let m = h.state().message.clone().unwrap();
    assert!(m.error && m.text.contains("file name"), "{}", m.text);
    assert!(h.state().doc.path().is_none() && h.state().doc.is_dirty());
}

/// Everything computed for one scene — the probe's numbers, the gradient overlay,
/// the comparison — is gone from the screen the moment the scene changes, and the
/// new scene's results take its place.
#[test]
fn results_of_an_older_scene_are_dropped_when_it_changes() {
    let mut wb = workbench();
    tiny_compare(&mut wb);
    wb.overlays.set(Overlay::Gradients, true);
    wb.show_compare = true;
    wb.probe = Some(DVec2::new(0.1, -0.3));
    let mut h = harness(wb);
    step_until(&mut h, "probe, gradients and comparison", |w| {
        w.probe_done() && w.gradient_grid().is_some() && w.compare_done()
    });
    h.run_steps(2);
    let old_probe = h.state().probe_result().unwrap().clone();
    let old_grid = h.state().gradient_grid().unwrap().clone();
    let old_compare = h.state().compare_result().unwrap().clone();
    let old_ls = format!("{:.2e}", h.state().readouts()[0].lum.value);
    assert!(
        h.query_all_by_label(&old_ls).count() > 0,
        "the inspector shows L_s = {old_ls}"
    );
    assert_eq!(h.query_all_by_label_contains("RMSE").count(), 2);

    h.state_mut()
        .doc
        .edit("sigma_s", |d| d.medium.as_mut().unwrap().sigma_s.0 = [3.0; 3])
        .unwrap();
    h.step();
    let w = h.state();
    assert!(w.probe_result().is_none_or(|p| !Arc::ptr_eq(p, &old_probe)));
    assert!(w.gradient_grid().is_none_or(|g| !Arc::ptr_eq(g, &old_grid)));
    assert!(w.compare_result().is_none_or(|c| !Arc::ptr_eq(c, &old_compare)));
    assert_eq!(h.query_all_by_label(&old_ls).count(), 0, "the old L_s is gone");
    assert_eq!(
        h.query_all_by_label_contains("RMSE").count(),
        0,
        "the old errors are gone"
    );

    step_until(&mut h, "the new scene's results", |w| {
        w.probe_done() && w.gradient_grid().is_some() && w.compare_done()
    });
    let new_ls = h.state().readouts()[0].lum.value;
    assert_ne!(format!("{new_ls:.2e}"), old_ls);
}

/// The window's rectangle in a harness of `size`.
fn screen(size: [f32; 2]) -> egui::Rect {
    egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(size[0], size[1]))
}

/// At 1024×700 every toolbar button is on screen (the toolbar wraps), and the
/// canvas keeps its minimum width with the inspector open; neither placing the
/// probe nor switching to false colour moves the field on screen.
#[test]
fn at_1024x700_the_toolbar_fits_and_the_canvas_neither_shrinks_nor_jumps() {
    let size = [1024.0, 700.0];
    let mut h = harness_sized(workbench(), size);
    step_until(&mut h, "the field", |w| w.field_converged());
    for label in ["Undo", "Fit view", "Compare view", "Side panel", "Inspector"] {
        let r = h.get_by_label(label).rect();
        assert!(screen(size).contains_rect(r), "{label} at {r:?}");
    }
    let canvas = h.state().canvas_rect().unwrap();
    assert!(canvas.width() >= MIN_CANVAS_WIDTH, "{canvas:?}");
    let world = DVec2::new(0.1, -0.3);
    let at = h.state().screen_pos(world).unwrap();
    click_world(&mut h, world);
    step_until(&mut h, "the probe", |w| w.probe_done());
    h.run_steps(2);
    assert_eq!(
        h.state().canvas_rect().unwrap(),
        canvas,
        "the inspector did not move the canvas"
    );
    assert_eq!(h.state().screen_pos(world).unwrap(), at);
    h.get_by_label("false colour (log)").click();
    h.run_steps(2);
    assert!(h.state().display.false_color);
    assert_eq!(h.state().canvas_rect().unwrap(), canvas);
    assert_eq!(
        h.state().screen_pos(world).unwrap(),
        at,
        "false colour did not move the field"
    );
}

/// At 800×500 with the probe inspector open the canvas stays visible and usable;
/// the side panel scrolls to its last button; hiding the inspector gives its
/// width to the canvas.
#[test]
fn at_800x500_the_canvas_stays_and_the_panels_give_way() {
    let size = [800.0, 500.0];
    let mut wb = workbench();
    wb.probe = Some(DVec2::new(0.1, -0.3));
    let mut h = harness_sized(wb, size);
    step_until(&mut h, "the probe", |w| w.probe_done());
    h.run_steps(2);
    let canvas = h.state().canvas_rect().unwrap();
    assert!(screen(size).contains_rect(canvas), "{canvas:?}");
    assert!(
        canvas.width() >= MIN_CANVAS_WIDTH && canvas.height() >= 250.0,
        "{canvas:?}"
    );
    let export = h.get_by_label("Export PNG");
    export.scroll_to_me();
    h.run_steps(30); // the scroll animates
    let r = h.get_by_label("Export PNG").rect();
    assert!(screen(size).contains_rect(r), "scrolled to: {r:?}");
    h.get_by_label("Inspector").click();
    h.run_steps(2);
    assert!(!h.state().show_inspector);
    let wider = h.state().canvas_rect().unwrap();
    assert!(wider.width() > canvas.width() + 100.0, "{wider:?} vs {canvas:?}");
}

/// Before there is a probe the inspector says how to place one; the hint goes
/// once a click in the fog placed it.
#[test]
fn a_hint_says_a_click_in_the_fog_places_the_probe() {
    let mut h = harness(workbench());
    h.run_steps(2);
    h.get_by_label_contains("Click in the fog to place the probe");
    click_world(&mut h, DVec2::new(0.1, -0.3));
    h.run_steps(2);
    assert!(h.state().probe.is_some());
    assert!(h.query_by_label_contains("Click in the fog").is_none());
    h.get_by_label("Remove").click();
    h.run_steps(2);
    h.get_by_label_contains("Click in the fog to place the probe");
}

/// The fraction of `field`'s defined pixels the canvas shows white (every channel
/// 255) and black (every channel under 8).
fn white_and_black(field: &Field, style: &FieldStyle) -> (f64, f64) {
    let mapped = field_to_rgba(field, style);
    let (mut white, mut black, mut n) = (0, 0, 0);
    for (px, ok) in mapped.rgba.chunks(4).zip(&field.valid) {
        if *ok {
            n += 1;
            white += px[..3].iter().all(|c| *c == 255) as usize;
            black += px[..3].iter().all(|c| *c < 8) as usize;
        }
    }
    (white as f64 / n as f64, black as f64 / n as f64)
}

/// Automatic exposure is the default, and shows a field whatever its absolute
/// level: with the emitter 10⁴ times dimmer or brighter the canvas shows the same
/// image, neither white nor black, where the scene's fixed exposure shows it black
/// or white. The colour bar explains the tone-mapped image too.
#[test]
fn automatic_exposure_shows_a_field_at_any_level() {
    let mut images = Vec::new();
    for k in [1e-4, 1.0, 1e4] {
        let mut wb = workbench();
        wb.doc
            .edit("emission", |d| d.segments[0].emission.0 = [4.0 * k; 3])
            .unwrap();
        assert!(wb.display.auto_exposure && !wb.display.false_color, "the default");
        let mut h = harness(wb);
        step_until(&mut h, "the field", |w| w.field_converged());
        h.run_steps(2);
        let w = h.state();
        let field = &w.field_level().unwrap().rendered.field;
        let (white, black) = white_and_black(field, &w.field_style());
        assert!(
            white < 0.05 && black < 0.5,
            "emission × {k}: {white} white, {black} black"
        );
        let bar = w.colorbar_scale().expect("a colour bar in tone-mapped mode");
        assert_eq!((bar.min, bar.max), (0.0, (-w.exposure()).exp2()));
        images.push(field_to_rgba(field, &w.field_style()).rgba);
        let fixed = FieldStyle::Tonemapped {
            exposure: w.doc.desc().render.exposure,
        };
        let (white, black) = white_and_black(field, &fixed);
        match k {
            1e-4 => assert!(black > 0.9, "the fixed exposure shows it black: {black}"),
            1e4 => assert!(white > 0.5, "the fixed exposure shows it white: {white}"),
            _ => {}
        }
    }
    for other in &images[1..] {
        let most = images[0].iter().zip(other).map(|(a, b)| a.abs_diff(*b)).max();
        assert!(
            most <= Some(1),
            "the same image at every level (up to rounding): {most:?}"
        );
    }
}

/// "Open…" offers the scenes shipped in the binary, wherever the app started,
/// and browses folders for scene files.
#[test]
fn open_offers_the_shipped_scenes_and_browses_folders() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    let small = DEFAULT_SCENE_JSON.replace("[256, 256], \"spp\": 128", "[16, 16], \"spp\": 2");
    std::fs::write(sub.join("c.json"), &small).unwrap();
    std::fs::write(dir.path().join("notes.txt"), "not a scene").unwrap();
    let mut wb = workbench();
    // Not the checkout's flatland_scenes/, whose files have the shipped names.
    wb.open_dialog.go(dir.path().join("sub"));
    let mut h = harness(wb);
    h.step();
    h.get_by_label("Open…").click();
    h.run_steps(3);
    h.get_by_label("windows.json").click();
    h.run_steps(2);
    h.get_by_label("volcache workbench: windows");
    assert!(
        h.state().doc.path().is_none(),
        "a shipped scene has no file to overwrite"
    );
    assert!(!h.state().open_dialog.open, "loading closes the window");

    h.state_mut().open_dialog.go(dir.path().to_path_buf());
    h.state_mut().open_dialog.open = true;
    h.run_steps(3);
    assert!(h.query_by_label("notes.txt").is_none(), "scene files only");
    h.get_by_label("sub/").click();
    h.run_steps(2);
    assert_eq!(h.state().open_dialog.dir, sub);
    h.get_by_label("c.json").click();
    h.run_steps(2);
    h.get_by_label("volcache workbench: c");
    assert_eq!(h.state().doc.path(), Some(sub.join("c.json").as_path()));
}

/// The gradient overlay as the paper draws it: after the first grid it refines
/// level by level up to one cell per pixel of the field (24² here), each level's
/// angle-coded image at that resolution; the arrows are optional (and at most 24
/// per side); with refinement off the grid stays as set.
#[test]
fn the_gradient_image_refines_to_the_fields_resolution_and_arrows_are_optional() {
    let mut wb = workbench();
    wb.overlays.set(Overlay::Gradients, true);
    let mut h = harness(wb);
    step_until(&mut h, "the per-pixel gradient image", |w| {
        w.gradient_grid()
            .is_some_and(|g| g.n == 24 && g.points.len() == 24 * 24)
    });
    h.step();
    let g = h.state().gradient_grid().unwrap().clone();
    assert!(g.points.iter().all(|p| p.aware.is_none_or(|d| d.is_finite())));
    let view = volcache::app::overlay::gradient_view(&g, true, h.state().field_params.part);
    assert_eq!(view.image.size, [24, 24]);
    let with_arrows = h.state().shapes_drawn;
    h.state_mut().gradient_arrows = false;
    h.run_steps(2);
    let without = h.state().shapes_drawn;
    assert!(with_arrows >= without + 2 * 24 * 24 / 2, "{with_arrows} vs {without}");
    assert_eq!(volcache::app::overlay::arrow_stride(24), 1);
    assert_eq!(volcache::app::overlay::arrow_stride(256), 11);
    // Refinement off: the grid stays at the 4 × 4 asked for.
    h.state_mut().method.grid_refine = false;
    step_until(&mut h, "the 4 × 4 grid", |w| {
        w.gradient_grid().is_some_and(|g| g.n == 4 && g.points.len() == 16)
    });
}

/// A reference of a few samples per stencil point has Hessian eigenvalues within
/// their standard errors: the inspector says so (and its ellipse is dashed, see
/// `app::overlay`'s unit test) instead of drawing it as if exact.
#[test]
fn a_noisy_reference_hessian_is_flagged_not_drawn_as_exact() {
    let mut wb = workbench();
    wb.method.ref_spp = 2;
    wb.probe = Some(DVec2::new(0.1, -0.3));
    wb.want_reference = true;
    wb.overlays.set(Overlay::Extents, true);
    let mut h = harness(wb);
    step_until(&mut h, "probe and reference", |w| w.probe_done() && w.reference_done());
    h.run_steps(2);
    let r = h.state().readouts();
    let reference = r.iter().find(|r| r.name == "reference").unwrap();
    assert!(reference.hessian_is_noise(), "{:?}", reference.stderr);
    h.get_by_label_contains("reference Hessian too noisy");
}

/// The field from a radiance cache: switching the field method restarts the field
/// job, the field is the library's cached reconstruction (`volcache caches`' function,
/// same settings: pixels equal), and the records overlay draws the field's records
/// without running a comparison.
#[test]
fn the_field_can_come_from_the_cache_with_its_records() {
    use volcache::app::field_method::FieldMethod;
    use volcache::flatland::cached_field::{CacheMethod, RecordMemo, render_cached};
    let mut h = harness(workbench());
    step_until(&mut h, "the path-traced field", |w| w.field_converged());
    let starts = h.state().field_starts();
    h.state_mut().field_method = FieldMethod::Cache(CacheMethod::Ours);
    h.state_mut().overlays.set(Overlay::Records, true);
    h.step();
    assert_eq!(
        h.state().field_starts(),
        starts + 1,
        "switching the method restarts the field"
    );
    step_until(&mut h, "the cached field", |w| w.field_converged());
    h.run_steps(2);
    let w = h.state();
    let level = w.field_level().unwrap().clone();
    assert!(!level.records.is_empty());
    assert!(!w.compare_needed(), "the records come with the field");
    assert!(
        w.shapes_drawn >= level.records.len(),
        "records drawn: {}",
        w.shapes_drawn
    );
    let c = w.cache_field;
    let cs = volcache::study::field_runs::cache_settings(CacheMethod::Ours, c.eps, &level.params, c.rays, c.steps);
    let direct = render_cached(
        w.doc.scene(),
        &level.params,
        &cs,
        None,
        &mut RecordMemo::new(),
        &Default::default(),
    )
    .unwrap();
    assert_eq!(direct.field.values, level.rendered.field.values);
    assert_eq!(direct.record_count(), level.records.len());
    let err = h.state_mut().field_command().unwrap_err().to_string();
    assert!(err.contains("volcache caches"), "{err}");
}
