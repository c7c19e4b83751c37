//! The window's two modes: the 2D flatland workbench ([`Workbench`]) and the 3D
//! renderer ([`Workbench3d`]), one bar above both to switch. Each mode keeps its
//! state while the other is shown (switching never loses work); opening a 3D scene
//! file (from the command line or the 2D "Open…") switches to 3D.

use super::document3d::Document3d;
use super::workbench::Workbench;
use super::workbench3d::Workbench3d;
use eframe::egui;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Flatland,
    Volume,
}

pub struct App {
    pub mode: Mode,
    pub flat: Workbench,
    /// Created the first time 3D is opened.
    pub volume: Option<Workbench3d>,
}

impl App {
    /// The 2D workbench, in 2D mode.
    pub fn flat(flat: Workbench) -> Self {
        App {
            mode: Mode::Flatland,
            flat,
            volume: None,
        }
    }

    /// 3D mode on `doc`, with the 2D workbench on its default scene beside it.
    pub fn volume(doc: Document3d) -> Self {
        App {
            mode: Mode::Volume,
            flat: Workbench::new(super::Document::default_scene()),
            volume: Some(Workbench3d::new(doc)),
        }
    }

    /// The 3D workbench, opened on the shipped staircase if there is none yet.
    pub fn volume_mut(&mut self) -> &mut Workbench3d {
        self.volume.get_or_insert_with(|| {
            Workbench3d::new(Document3d::shipped("staircase.json").expect("the shipped scenes are valid"))
        })
    }

    pub fn set_mode(&mut self, mode: Mode) {
        if mode == Mode::Volume {
            self.volume_mut();
        }
        self.mode = mode;
    }

    /// One frame: the mode bar, then the current mode.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        egui::Panel::top("mode").show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.label("Mode");
                for (m, name) in [(Mode::Flatland, "2D flatland"), (Mode::Volume, "3D volume")] {
                    if ui.selectable_label(self.mode == m, name).clicked() {
                        self.set_mode(m);
                    }
                }
            });
        });
        match self.mode {
            Mode::Flatland => self.flat.ui(ui),
            Mode::Volume => self.volume_mut().ui(ui),
        }
        // A 3D file chosen in the 2D "Open…" opens in 3D mode.
        if let Some(path) = self.flat.open_3d.take() {
            self.volume_mut().load_file(&path);
            self.mode = Mode::Volume;
            ui.ctx().request_repaint();
        }
    }
}

impl eframe::App for App {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        App::ui(self, ui);
    }
}
