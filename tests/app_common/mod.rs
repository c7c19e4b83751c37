//! What the workbench's kittest files share: a workbench with tiny computations,
//! a harness of a given window size, stepping until a condition, pointer clicks.

#![allow(dead_code)] // each test file uses part of it

use eframe::egui;
use egui_kittest::Harness;
use glam::DVec2;
use std::time::{Duration, Instant};
use volcache::app::{Document, Workbench, install_fonts};

/// The default scene with computations small enough for tests.
pub fn workbench() -> Workbench {
    let mut wb = Workbench::new(Document::default_scene());
    let p = &mut wb.field_params;
    (p.width, p.height, p.spp) = (24, 24, 2);
    let m = &mut wb.method;
    (m.rays, m.steps, m.ref_spp, m.grid, m.grid_rays) = (96, 4, 64, 4, 24);
    wb
}

pub fn harness(wb: Workbench) -> Harness<'static, Workbench> {
    harness_sized(wb, [1280.0, 800.0])
}

/// A harness whose window is `size` points.
pub fn harness_sized(wb: Workbench, size: [f32; 2]) -> Harness<'static, Workbench> {
    Harness::builder()
        .with_size(size)
        .with_context_setup(install_fonts)
        .build_ui_state(|ui, wb: &mut Workbench| wb.ui(ui), wb)
}

/// Step frames until `done` holds (30 s at most).
pub fn step_until(h: &mut Harness<'_, Workbench>, what: &str, done: impl Fn(&Workbench) -> bool) {
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

pub fn press(h: &Harness<'_, Workbench>, pos: egui::Pos2, pressed: bool) {
    h.event(egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    });
}

pub fn click_at(h: &mut Harness<'_, Workbench>, pos: egui::Pos2) {
    h.hover_at(pos);
    press(h, pos, true);
    press(h, pos, false);
    h.step();
}

pub fn click_world(h: &mut Harness<'_, Workbench>, p: DVec2) {
    let pos = h.state().screen_pos(p).expect("the canvas was drawn");
    click_at(h, pos);
}

/// A comparison small enough for tests (12×12, a handful of records).
/// 16 records: a count the equal-count search reaches exactly for both methods in
/// the default scene and with σ_s = 3 (6 stopped being reachable there once the
/// Hessians at occlusion boundaries grew to their exact size: at most ε 8 records).
pub fn tiny_compare(wb: &mut Workbench) {
    wb.compare_params = volcache::app::compare::CompareParams {
        caches: 16,
        rays: 24,
        steps: 2,
        res: Some([12, 12]),
        ref_spp: 4,
        ..Default::default()
    };
}
