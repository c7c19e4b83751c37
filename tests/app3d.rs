//! The workbench's 3D mode, headless (egui_kittest): opening a 3D scene, the view
//! refining and restarting, camera motion, the records overlay, the probe on a
//! pixel's camera ray against the library's (and the command line's) numbers, and
//! a 3D file opened from the 2D mode.

use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec2;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use volcache::app::document3d::Document3d;
use volcache::app::render3d_job::Method3d;
use volcache::app::{App, Mode, Workbench, install_fonts};

mod room3d;
use room3d::ROOM;

fn room_file(dir: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("volcache_app3d_{dir}_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("room.json");
    std::fs::write(&p, ROOM).unwrap();
    p
}

/// The 3D mode on `path` with computations small enough for tests.
fn app(path: &Path) -> App {
    let mut app = App::volume(Document3d::open(path).unwrap());
    let w = app.volume_mut();
    let p = &mut w.params;
    (p.width, p.height, p.spp, p.rays, p.steps, p.cache_spp) = (16, 12, 4, 64, 4, 1);
    app
}

fn harness(app: App) -> Harness<'static, App> {
    Harness::builder()
        .with_size([1280.0, 800.0])
        .with_context_setup(install_fonts)
        .build_ui_state(|ui, app: &mut App| app.ui(ui), app)
}

fn step_until(h: &mut Harness<'_, App>, what: &str, done: impl Fn(&App) -> bool) {
    let start = Instant::now();
    while !done(h.state()) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "timed out waiting for {what}"
        );
        h.step();
        std::thread::sleep(Duration::from_millis(2));
    }
    h.step();
}

fn settled(a: &App) -> bool {
    a.volume.as_ref().is_some_and(|w| w.settled())
}

#[test]
fn a_3d_scene_opens_in_3d_mode_and_the_view_refines_to_the_command_lines_image() {
    let path = room_file("refine");
    let mut h = harness(app(&path));
    assert_eq!(h.state().mode, Mode::Volume);
    step_until(&mut h, "the view to refine", settled);
    let w = h.state().volume.as_ref().unwrap();
    let f = w.frame().unwrap();
    assert_eq!(f.level, f.levels, "the last level arrived");
    assert_eq!((f.image.width, f.image.height, f.image.spp), (16, 12, 4));
    assert!(f.image.values.iter().all(|v| v.is_finite()));
    assert!(f.image.values.iter().any(|v| v.x > 0.0));
    // The level is exactly the library render the command line runs.
    let scene = w.doc.scene();
    let direct = volcache::volume::render::render(scene, &f.image_params, &Default::default()).unwrap();
    assert_eq!(direct.values, f.image.values);
    let cmd = w.command().unwrap();
    assert!(cmd.contains("--method pt --res 16x12 --spp 4 --seed 3"), "{cmd}");
}

#[test]
fn switching_the_method_or_moving_the_camera_restarts_the_render() {
    let path = room_file("restart");
    let mut h = harness(app(&path));
    step_until(&mut h, "the first level", |a| {
        a.volume.as_ref().unwrap().frame().is_some()
    });
    let starts = h.state().volume.as_ref().unwrap().render.starts;
    let old = h.state().volume.as_ref().unwrap().render.job().unwrap().watch();
    h.state_mut().volume_mut().set_method(Method3d::Ours);
    h.step();
    let w = h.state().volume.as_ref().unwrap();
    assert_eq!(w.render.starts, starts + 1);
    assert!(old.is_cancel_requested() || !old.is_running());
    // A drag on the view orbits the camera, which restarts the render.
    let cam0 = w.doc.desc().camera.clone();
    let rect = h.state().volume.as_ref().unwrap().view_rect.unwrap();
    let c = rect.center();
    h.hover_at(c);
    h.event(egui::Event::PointerButton {
        pos: c,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: egui::Modifiers::NONE,
    });
    h.step();
    for k in 1..=5 {
        h.hover_at(c + egui::vec2(10.0 * k as f32, 0.0));
        h.step();
    }
    h.event(egui::Event::PointerButton {
        pos: c + egui::vec2(50.0, 0.0),
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: egui::Modifiers::NONE,
    });
    h.step();
    let w = h.state().volume.as_ref().unwrap();
    assert_ne!(w.doc.desc().camera, cam0, "the drag orbited the camera");
    assert!(w.render.starts > starts + 1);
    assert!(w.probe.is_none(), "a drag is not a click");
}

#[test]
fn ours_draws_its_records_and_the_overlay_toggles() {
    let path = room_file("records");
    let mut a = app(&path);
    a.volume_mut().set_method(Method3d::Ours);
    let mut h = harness(a);
    step_until(&mut h, "the cached view", settled);
    let w = h.state().volume.as_ref().unwrap();
    let f = w.frame().unwrap();
    assert!(!f.records.is_empty());
    assert!(f.image.values.iter().all(|v| v.is_finite()));
    let drawn = w.records_drawn;
    assert!(drawn > 0, "records drawn over the image");
    h.state_mut().volume_mut().display.show_records = false;
    h.step();
    assert_eq!(h.state().volume.as_ref().unwrap().records_drawn, 0);
    assert!(
        h.state()
            .volume
            .as_ref()
            .unwrap()
            .command()
            .unwrap()
            .contains("--method ours")
    );
}

#[test]
fn a_click_places_a_probe_whose_numbers_are_the_librarys() {
    let path = room_file("probe");
    let mut h = harness(app(&path));
    step_until(&mut h, "the first level", |a| {
        a.volume.as_ref().unwrap().frame().is_some()
    });
    let rect = h.state().volume.as_ref().unwrap().view_rect.unwrap();
    let at = rect.min + egui::vec2(0.5 * rect.width(), 0.6 * rect.height());
    h.hover_at(at);
    for pressed in [true, false] {
        h.event(egui::Event::PointerButton {
            pos: at,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        });
    }
    h.step();
    assert!(
        h.state().volume.as_ref().unwrap().probe.is_some(),
        "the click placed a probe"
    );
    step_until(&mut h, "the probe", settled);
    let w = h.state().volume.as_ref().unwrap();
    let p = w.probe.as_ref().unwrap();
    assert!((p.pixel - DVec2::new(0.5, 0.6)).length() < 0.05, "{:?}", p.pixel);
    let r = w.probe_job.current().unwrap().clone();
    let scene = w.doc.scene();
    assert!(r.inside_medium);
    // The same point and seed through the function `volcache probe --method aware` calls.
    let ps = volcache::app::probe3d::probe_settings(scene, 64, 4);
    let d = volcache::study::light_field_derivs::derivatives_at(
        &**scene,
        r.at,
        volcache::pipeline::probe::Outgoing::TowardsPoint(scene.camera.position),
        volcache::pipeline::derivatives::Method::Aware,
        &ps,
        &Default::default(),
        &Default::default(),
        r.seed,
        &Default::default(),
    )
    .unwrap();
    assert_eq!(d.parts.total().luminance(), r.shared.aware.total().luminance());
    let rows = volcache::app::inspector3d::readouts(w, &r);
    assert!(rows.iter().all(|row| row.value.is_finite() && row.radii.is_finite()));
    assert!(rows[0].value > 0.0);
    let cmd = w.probe_command(&r, "aware");
    assert!(cmd.contains("--method aware --rays 64 --steps 4 --seed 3"), "{cmd}");
    // And the copied command, run, prints those numbers.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_volcache"))
        .args(cmd.split_whitespace().skip(1))
        .output()
        .unwrap();
    assert!(out.status.success(), "{cmd}: {}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let lum = r.shared.aware.total().luminance();
    let t = &json[0]["total"]["luminance"];
    assert_eq!(t["value"].as_f64().unwrap(), lum.value);
    let g: Vec<f64> = t["gradient"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(g, lum.grad.to_array().to_vec());
}

#[test]
fn editing_the_medium_is_validated_undone_and_saved_only_where_named() {
    let path = room_file("edit");
    let mut h = harness(app(&path));
    h.step();
    let w = h.state_mut().volume_mut();
    let starts = w.render.starts;
    w.doc.edit("g", |d| d.medium.as_mut().unwrap().g = -0.9).unwrap();
    assert!(w.doc.edit("g", |d| d.medium.as_mut().unwrap().g = -1.2).is_err());
    h.step();
    let w = h.state_mut().volume_mut();
    assert!(w.render.starts > starts, "an edit restarts the render");
    w.doc
        .set_camera(volcache::volume::orbit::dolly(&w.doc.desc().camera, 0.5, 1.0))
        .unwrap();
    let cam = w.doc.desc().camera.clone();
    w.undo();
    assert_eq!(w.doc.desc().medium.as_ref().unwrap().g, 0.4);
    assert_eq!(w.doc.desc().camera, cam);
    // Save writes the named file, with the moved camera, and only that file.
    let out = path.with_file_name("saved.json");
    w.scene_path = out.display().to_string();
    w.save();
    let saved = volcache::volume::scene::Scene::load(&out).unwrap();
    assert_eq!(saved.desc.camera, cam);
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        ROOM,
        "the opened file is untouched"
    );
}

#[test]
fn a_3d_file_opened_in_2d_mode_switches_to_3d() {
    let path = room_file("switch");
    let mut h = harness(App::flat(Workbench::new(volcache::app::Document::default_scene())));
    h.step();
    assert_eq!(h.state().mode, Mode::Flatland);
    h.state_mut().flat.load_scene(&path);
    h.step();
    assert_eq!(h.state().mode, Mode::Volume);
    let w = h.state().volume.as_ref().unwrap();
    assert_eq!(w.doc.path(), Some(path.as_path()));
    // The 2D scene is kept for when the user switches back.
    assert!(h.state().flat.doc.path().is_none());
    h.state_mut().set_mode(Mode::Flatland);
    h.step();
    assert_eq!(h.state().mode, Mode::Flatland);
}

#[test]
fn the_3d_compare_finishes_and_its_copied_command_reproduces_the_numbers() {
    let path = room_file("compare");
    let mut h = harness(app(&path));
    {
        let w = h.state_mut().volume_mut();
        w.compare_params = volcache::app::compare3d::Compare3dParams {
            caches: 40,
            width: 16,
            spp: 1,
            ref_spp: 64,
            rays: 64,
            steps: 4,
            seed: 1,
        };
        w.show_compare = true;
        w.run_compare();
    }
    step_until(&mut h, "the comparison", |a| {
        let w = a.volume.as_ref().unwrap();
        w.compare_is_current()
    });
    let w = h.state().volume.as_ref().unwrap();
    let result = w.compare.latest().unwrap().clone();
    let res = result.as_ref().as_ref().expect("40 records are reachable here");
    assert_eq!(res.runs.len(), 3);
    for r in &res.runs {
        assert!(
            r.errors.rmse.is_finite() && r.medium_errors.rmse.is_finite(),
            "{}",
            r.method
        );
    }
    assert!(res.runs[..2].iter().all(|r| r.records.abs_diff(40) <= 2));
    // The copied command, run by the command line, gives the same records and errors
    // for both caches (path tracing runs to a time budget: only its method is checked).
    let dir = path.parent().unwrap();
    let cmd = w.compare_command();
    let args: Vec<String> = cmd
        .split_whitespace()
        .skip(1)
        .map(String::from)
        .chain(
            [
                "--ref-cache",
                &dir.join("refs").display().to_string(),
                "--out",
                &dir.join("out").display().to_string(),
                "--quiet",
            ]
            .map(String::from),
        )
        .collect();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_volcache"))
        .args(&args)
        .output()
        .unwrap();
    assert!(out.status.success(), "{cmd}: {}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/compare3d_room.json")).unwrap()).unwrap();
    let runs = report["runs"].as_array().unwrap();
    for (app_run, cli_run) in res.runs.iter().zip(runs) {
        assert_eq!(cli_run["method"], app_run.method.as_str());
        if app_run.records > 0 {
            assert_eq!(cli_run["records"], app_run.records);
            assert_eq!(cli_run["errors"]["rmse"].as_f64().unwrap(), app_run.errors.rmse);
            assert_eq!(
                cli_run["medium_errors"]["rmse"].as_f64().unwrap(),
                app_run.medium_errors.rmse
            );
        }
    }
}

/// A probe placed by a click lies inside the fog when its ray crosses any: the
/// middle of the ray's piece inside the medium, not halfway to the hit.
#[test]
fn a_clicked_probe_lands_in_the_fog() {
    let path = room_file("infog");
    let a = app(&path);
    let w = a.volume.as_ref().unwrap();
    let scene = w.doc.scene();
    for (u, v) in [(0.5, 0.5), (0.1, 0.9), (0.9, 0.2)] {
        let p = volcache::app::probe3d::Probe3d::at_pixel(scene, DVec2::new(u, v));
        let x = p.point(scene);
        assert!(scene.medium.as_ref().unwrap().contains(x), "({u}, {v}) → {x}");
    }
}

#[test]
fn the_error_map_measures_the_view_against_a_reference_of_the_same_camera() {
    use volcache::app::error_map3d::reference_params;
    use volcache::core::stats::luminance_errors;
    use volcache::volume::render::render;
    let path = room_file("errormap");
    let mut a = app(&path);
    a.volume_mut().set_method(Method3d::Ours);
    a.volume_mut().display.error_map = true;
    a.volume_mut().reference_spp = 16;
    let mut h = harness(a);
    step_until(&mut h, "the cached view and its reference", settled);
    let w = h.state().volume.as_ref().unwrap();
    let f = w.frame().unwrap().clone();
    // The reference is the command line's path-traced image of the same camera and
    // size, at the reference seed (never the judged image's seed).
    let scene = w.doc.scene();
    let rp = reference_params(scene, &w.params, 16);
    assert_eq!((rp.width, rp.height, rp.spp), (16, 12, 16));
    assert_ne!(rp.seed, f.image_params.seed);
    let reference = render(scene, &rp, &Default::default()).unwrap();
    assert_eq!(w.reference.current().unwrap().values, reference.values);
    // The view shows the library's error map of ours against it, with its errors.
    let want = luminance_errors(&f.image.values, &reference.values);
    assert!(want.rmse > 0.0 && want.rmse.is_finite());
    assert_eq!(w.error_shown.map(|e| e.0), Some(want));
    let map = w.current_error_map(&f).unwrap();
    assert_ne!(map.rgba, w.display_rgba(&f), "the error map, not the image");
    // The medium part alone is measured on the medium parts.
    h.state_mut().volume_mut().display.medium_only = true;
    h.step();
    let w = h.state().volume.as_ref().unwrap();
    let medium = luminance_errors(&f.image.medium, &reference.medium);
    assert_eq!(w.error_shown.map(|e| e.0), Some(medium));
    // A camera move makes both stale: nothing is shown as the error of the new
    // view until its image and its own reference arrive.
    let starts = w.reference.starts;
    let mut cam = w.doc.desc().camera.clone();
    cam.position[0] += 0.3;
    h.state_mut().volume_mut().doc.set_camera(cam).unwrap();
    h.step();
    let w = h.state().volume.as_ref().unwrap();
    assert_eq!(w.reference.starts, starts + 1, "a new reference for the new camera");
    assert!(w.error_shown.is_none(), "no error shown for the old camera");
    step_until(&mut h, "the moved view and its reference", settled);
    let w = h.state().volume.as_ref().unwrap();
    let f = w.frame().unwrap();
    let rp = reference_params(w.doc.scene(), &w.params, 16);
    let reference = render(w.doc.scene(), &rp, &Default::default()).unwrap();
    let medium = luminance_errors(&f.image.medium, &reference.medium);
    assert_eq!(w.error_shown.map(|e| e.0), Some(medium));
    // Off: the image again, and a reference for another state is not rendered.
    h.state_mut().volume_mut().display.error_map = false;
    h.step();
    assert!(h.state().volume.as_ref().unwrap().error_shown.is_none());
}

/// With "keep records when the camera moves" a cached view starts a moved camera
/// from the previous camera's records (their moments over ω_o) and says so; any
/// other edit, or the option off, places afresh.
#[test]
fn a_camera_move_keeps_the_records_with_moments() {
    let path = room_file("moments");
    let mut h = harness(app(&path));
    let frame = |h: &Harness<'_, App>| h.state().volume.as_ref().unwrap().frame().unwrap().clone();
    let orbit = |h: &mut Harness<'_, App>, yaw: f64| {
        let w = h.state_mut().volume_mut();
        let cam = volcache::volume::orbit::orbit(&w.doc.desc().camera, yaw, 0.0);
        w.doc.set_camera(cam).unwrap();
        h.step();
    };
    {
        let w = h.state_mut().volume_mut();
        w.set_method(Method3d::Ours);
        w.params.moment_bands = Some(2);
    }
    h.step();
    step_until(&mut h, "the first camera's cache", settled);
    let first = frame(&h);
    assert_eq!((first.method, first.carried), (Method3d::Ours, 0));
    let placed = first.records.len();
    assert!(placed > 0);
    orbit(&mut h, 0.3);
    step_until(&mut h, "the moved camera's cache", settled);
    let moved = frame(&h);
    assert_eq!(moved.carried, placed, "the first camera's records were carried over");
    assert!(moved.records.len() >= placed);
    assert!(moved.image.values.iter().all(|v| v.is_finite()));
    let w = h.state().volume.as_ref().unwrap();
    assert!(w.command().unwrap().contains("records from earlier cameras"));
    // An edit of the medium drops them.
    h.state_mut()
        .volume_mut()
        .doc
        .edit("σ_s", |d| {
            d.medium.as_mut().unwrap().sigma_s = volcache::volume::scene_desc::Color([0.3; 3])
        })
        .unwrap();
    h.step();
    step_until(&mut h, "the edited scene's cache", settled);
    assert_eq!(frame(&h).carried, 0, "an edit places afresh");
    // Without moments a camera move places afresh too.
    h.state_mut().volume_mut().params.moment_bands = None;
    h.step();
    step_until(&mut h, "the cache without moments", settled);
    orbit(&mut h, -0.3);
    step_until(&mut h, "the moved camera without moments", settled);
    assert_eq!(frame(&h).carried, 0);
}

/// "surface cache" in the 3D panel: the cached view's last level is the library's
/// cached render with the surface cache at the scene-relative ε, bit for bit, and
/// the copied command says `--surface-cache ours`.
#[test]
fn the_surface_cache_option_renders_the_librarys_image() {
    let path = room_file("surface_cache");
    let mut h = harness(app(&path));
    {
        let w = h.state_mut().volume_mut();
        w.set_method(Method3d::Ours);
        w.params.surface_cache = true;
    }
    h.step();
    step_until(&mut h, "the cache with surfaces", settled);
    let w = h.state().volume.as_ref().unwrap();
    let (direct, _, cp) = last_level_is_the_librarys_render(w);
    assert!(cp.surface_eps.is_some());
    assert!(direct.surfaces.as_ref().unwrap().record_count() > 0);
    assert!(w.command().unwrap().contains("--surface-cache ours"));
}

/// The view's frame is its last level and equals the library's cached render of
/// ours with the view's settings, bit for bit; returns that render and settings.
fn last_level_is_the_librarys_render(
    w: &volcache::app::workbench3d::Workbench3d,
) -> (
    volcache::volume::cached::CachedRender,
    volcache::pipeline::record::CacheSettings,
    volcache::volume::cached_params::CachedRenderParams,
) {
    let f = w.frame().unwrap();
    assert_eq!(f.level, f.levels);
    let scene = w.doc.scene();
    let (cs, cp) = w.params.cached(scene, volcache::core::metric::CacheMethod::Ours, 1.0);
    let direct =
        volcache::volume::cached::render_cached(scene, &cp, &cs, None, &mut Default::default(), &Default::default())
            .unwrap();
    assert_eq!(direct.reconstruction.image.values, f.image.values);
    (direct, cs, cp)
}

/// "reach ≤ edge distance ×" and "reach ≤ gradient noise" in the 3D panel reach
/// the cache settings (the view's last level is the library's render with them,
/// bit for bit, and they place more records than without) and the copied command.
#[test]
fn the_reach_options_reach_the_cache_and_the_command() {
    let path = room_file("reach");
    let mut h = harness(app(&path));
    h.state_mut().volume_mut().set_method(Method3d::Ours);
    h.step();
    step_until(&mut h, "the cache without reach limits", settled);
    let without = h.state().volume.as_ref().unwrap().frame().unwrap().records.len();
    // The boxes are in the panel; the edge reach's factor is set directly.
    h.get_by_label("reach ≤ gradient noise").click();
    h.get_by_label("reach ≤ edge distance ×").click();
    h.step();
    h.state_mut().volume_mut().params.edge_reach = Some(0.5);
    h.step();
    step_until(&mut h, "the cache with reach limits", settled);
    let w = h.state().volume.as_ref().unwrap();
    let (_, cs, _) = last_level_is_the_librarys_render(w);
    assert_eq!((cs.edge_reach, cs.gradient_noise_reach), (Some(0.5), true));
    let with = w.frame().unwrap().records.len();
    println!("records {without} without the limits, {with} with them");
    assert!(with > without);
    let command = w.command().unwrap();
    assert!(
        command.contains(" --edge-reach 0.5") && command.contains(" --gradient-noise-reach"),
        "{command}"
    );
    // Jarosz 2008 measures no gradient noise: its settings leave the reach off.
    let (cs, _) = w
        .params
        .cached(w.doc.scene(), volcache::core::metric::CacheMethod::Jarosz08, 1.0);
    assert!(!cs.gradient_noise_reach);
}

/// "reach ≤ lamp distance ×" is on by default at `VOLUME_LAMP_REACH`, as in
/// `render3d`; unticked, the cache settings leave it out and the copied command
/// says `--no-lamp-reach`; another factor is copied as `--lamp-reach K`.
#[test]
fn the_lamp_reach_reaches_the_cache_and_the_command() {
    use volcache::pipeline::budget::VOLUME_LAMP_REACH;
    let path = room_file("lamp_reach");
    let mut h = harness(app(&path));
    h.state_mut().volume_mut().set_method(Method3d::Ours);
    h.step();
    step_until(&mut h, "the cache with the lamp reach", settled);
    let w = h.state().volume.as_ref().unwrap();
    let (_, cs, _) = last_level_is_the_librarys_render(w);
    assert_eq!(cs.lamp_reach, Some(VOLUME_LAMP_REACH));
    let command = w.command().unwrap();
    assert!(!command.contains("lamp-reach"), "{command}");
    h.get_by_label("reach ≤ lamp distance ×").click();
    h.step();
    step_until(&mut h, "the cache without the lamp reach", settled);
    let w = h.state().volume.as_ref().unwrap();
    let (_, cs, _) = last_level_is_the_librarys_render(w);
    assert_eq!(cs.lamp_reach, None);
    let command = w.command().unwrap();
    assert!(command.contains(" --no-lamp-reach"), "{command}");
    h.state_mut().volume_mut().params.lamp_reach = Some(0.5);
    h.step();
    step_until(&mut h, "the cache with half the lamp reach", settled);
    let w = h.state().volume.as_ref().unwrap();
    let command = w.command().unwrap();
    assert!(command.contains(" --lamp-reach 0.5"), "{command}");
}

/// The 3D panel's "serve within ° of the camera" box sets the eye cone at the
/// suggested angle; the view's last level is the library's render with it, and
/// the copied command carries `--eye-cone`.
#[test]
fn the_eye_cone_reaches_the_cache_and_the_command() {
    use volcache::pipeline::eye_cone::SUGGESTED_EYE_CONE_DEG;
    let path = room_file("eye_cone");
    let mut h = harness(app(&path));
    h.state_mut().volume_mut().set_method(Method3d::Ours);
    h.step();
    step_until(&mut h, "the cache without the eye cone", settled);
    let w = h.state().volume.as_ref().unwrap();
    let (_, cs, _) = last_level_is_the_librarys_render(w);
    assert_eq!(cs.eye_cone_deg, None);
    assert!(!w.command().unwrap().contains("eye-cone"));
    h.get_by_label("serve within ° of the camera").click();
    h.step();
    step_until(&mut h, "the cache with the eye cone", settled);
    let w = h.state().volume.as_ref().unwrap();
    let (_, cs, _) = last_level_is_the_librarys_render(w);
    assert_eq!(cs.eye_cone_deg, Some(SUGGESTED_EYE_CONE_DEG));
    let command = w.command().unwrap();
    assert!(
        command.contains(&format!(" --eye-cone {SUGGESTED_EYE_CONE_DEG}")),
        "{command}"
    );
}
