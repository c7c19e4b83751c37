//! "Open…": the scenes shipped in the binary, wherever the app was started from,
//! and a small file browser (the sub-folders and scene files of one folder, Up, a
//! typed folder); its state is [`super::open_dialog::OpenDialog`].

use super::open_dialog::listing;
use super::workbench::Workbench;
use crate::flatland::shipped::SHIPPED_SCENES;
use eframe::egui;
use std::path::{Path, PathBuf};

fn name_of(p: &Path) -> String {
    p.file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned())
}

impl Workbench {
    /// Load a scene shipped in the binary; on error keep the scene and show why.
    pub fn load_shipped(&mut self, name: &str) {
        let Some((_, json)) = SHIPPED_SCENES.iter().find(|(n, _)| *n == name) else {
            return self.error(format!("no shipped scene {name}"));
        };
        match self.doc.load_embedded(name, json) {
            Ok(()) => self.info(format!("loaded the shipped {name} (Save asks for a file name)")),
            Err(e) => self.error(e.to_string()),
        }
    }

    /// The "Open a scene" window, while open.
    pub(super) fn open_window(&mut self, ctx: &egui::Context) {
        let mut open = self.open_dialog.open;
        let mut chosen: Option<Result<String, PathBuf>> = None;
        egui::Window::new("Open a scene")
            .open(&mut open)
            .default_size([360.0, 420.0])
            .show(ctx, |ui| {
                ui.strong("Shipped with volcache");
                ui.horizontal_wrapped(|ui| {
                    for (name, _) in SHIPPED_SCENES {
                        if ui.button(name).clicked() {
                            chosen = Some(Ok(name.to_string()));
                        }
                    }
                });
                ui.separator();
                ui.strong("Files");
                let d = &mut self.open_dialog;
                ui.horizontal(|ui| {
                    if ui.button("Up").clicked()
                        && let Some(parent) = d.dir.parent()
                    {
                        d.go(parent.to_path_buf());
                    }
                    let l = ui.label("folder");
                    let r = ui
                        .add(egui::TextEdit::singleline(&mut d.dir_text).desired_width(f32::INFINITY))
                        .labelled_by(l.id);
                    if r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
                        d.dir = PathBuf::from(d.dir_text.trim());
                    }
                });
                match listing(&d.dir) {
                    Err(e) => {
                        ui.colored_label(
                            egui::Color32::from_rgb(255, 110, 100),
                            format!("{}: {e}", d.dir.display()),
                        );
                    }
                    Ok((dirs, files)) => {
                        egui::ScrollArea::vertical().show(ui, |ui| {
                            for p in dirs {
                                if ui.selectable_label(false, format!("{}/", name_of(&p))).clicked() {
                                    d.go(p);
                                }
                            }
                            for p in files {
                                if ui.selectable_label(false, name_of(&p)).clicked() {
                                    chosen = Some(Err(p));
                                }
                            }
                        });
                    }
                }
            });
        let generation = self.doc.generation();
        match chosen {
            Some(Ok(name)) => self.load_shipped(&name),
            Some(Err(path)) => self.load_scene(&path),
            None => {}
        }
        // A load closes the window; an error keeps it open beside the message.
        self.open_dialog.open = open && self.doc.generation() == generation;
    }
}
