//! The toolbar (title, undo/redo, view, overlay toggles, compare view, which side
//! panels show) and keyboard shortcuts.

use super::overlay::Overlay;
use super::view::ViewState;
use super::workbench::Workbench;
use eframe::egui;

impl Workbench {
    pub(super) fn shortcuts(&mut self, ui: &mut egui::Ui) {
        if ui.ctx().text_edit_focused() {
            return; // text fields handle their own keys
        }
        use egui::{Key, Modifiers};
        // Shift+Ctrl+Z first: the Ctrl+Z pattern also matches with Shift held.
        let (redo, undo, redo_y, delete) = ui.input_mut(|i| {
            (
                i.consume_key(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z),
                i.consume_key(Modifiers::COMMAND, Key::Z),
                i.consume_key(Modifiers::COMMAND, Key::Y),
                i.consume_key(Modifiers::NONE, Key::Delete),
            )
        });
        if undo {
            self.doc.undo();
        }
        if redo || redo_y {
            self.doc.redo();
        }
        if delete {
            self.delete_selection();
        }
    }

    pub(super) fn delete_selection(&mut self) {
        if let Some(sel) = self.selection.take()
            && let Err(e) = self.doc.edit("delete", |d| super::edit::delete(d, sel))
        {
            self.error(e.to_string());
        }
        self.doc.end_gesture();
    }

    pub(super) fn toolbar(&mut self, ui: &mut egui::Ui) {
        // Wrapped: in a narrow window the last buttons go to a second row instead
        // of off-screen.
        ui.horizontal_wrapped(|ui| {
            let dirty = if self.doc.is_dirty() { " (edited)" } else { "" };
            ui.strong(format!("volcache workbench: {}{dirty}", self.doc.stem()));
            ui.separator();
            if ui.add_enabled(self.doc.can_undo(), egui::Button::new("Undo")).clicked() {
                self.doc.undo();
            }
            if ui.add_enabled(self.doc.can_redo(), egui::Button::new("Redo")).clicked() {
                self.doc.redo();
            }
            if ui.button("Fit view").clicked() {
                self.view = ViewState::default();
            }
            ui.separator();
            for o in Overlay::ALL {
                let mut on = self.overlays.is_on(o);
                if ui.checkbox(&mut on, o.label()).changed() {
                    self.overlays.set(o, on);
                }
            }
            ui.separator();
            ui.toggle_value(&mut self.show_compare, "Compare view");
            ui.separator();
            ui.toggle_value(&mut self.show_controls, "Side panel")
                .on_hover_text("show or hide the scene, field and method controls");
            ui.toggle_value(&mut self.show_inspector, "Inspector")
                .on_hover_text("show or hide the probe inspector");
        });
    }
}
