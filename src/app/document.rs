//! The scene being edited: its description, the built (validated) scene, undo/redo,
//! load and save. Every change goes through [`Scene::from_desc`] — the command
//! line's validation — and an invalid change is refused, so the document always
//! holds a valid scene (errors are returned for the UI to show).
//!
//! An undo step remembers which file its scene came from, so undoing past a load
//! brings back the previous file's path with its scene: the path shown, the title
//! and what Save writes always belong to the scene on screen (issue 15: Save once
//! overwrote the newly loaded file with the previous scene).

use crate::flatland::scene::{Scene, SceneError};
use crate::flatland::scene_desc::SceneDesc;
use crate::flatland::shipped::{embedded_name, embedded_source};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One undo or redo step: a scene and the file it belongs to.
#[derive(Clone)]
struct Snapshot {
    desc: SceneDesc,
    /// The name errors use (`Scene::source`).
    source: String,
    path: Option<PathBuf>,
    /// Which load this scene descends from (see `Document::loaded`).
    loaded: u64,
}

pub struct Document {
    scene: Arc<Scene>,
    /// Where the scene was loaded from or saved to (None: embedded, never saved).
    path: Option<PathBuf>,
    history: super::history::History<Snapshot>,
    /// Counts loads: restoring a step of another load switches the file back.
    loaded: u64,
    /// Bumps on every change of the scene: jobs key on it.
    revision: u64,
    /// Bumps when a different scene is loaded, or undo/redo crosses a load (the app
    /// resets its render settings and shows the restored file's path).
    generation: u64,
    /// Changed since loaded or saved.
    dirty: bool,
}

impl Document {
    pub fn new(scene: Scene, path: Option<PathBuf>) -> Self {
        Document {
            scene: Arc::new(scene),
            path,
            history: Default::default(),
            loaded: 0,
            revision: 0,
            generation: 0,
            dirty: false,
        }
    }

    /// The embedded default scene.
    pub fn default_scene() -> Self {
        Self::new(Scene::default_scene(), None)
    }

    /// Load a scene file (`None`: the embedded default).
    pub fn open(path: Option<&Path>) -> Result<Self, SceneError> {
        Ok(match path {
            Some(p) => Self::new(Scene::load(p)?, Some(p.to_path_buf())),
            None => Self::default_scene(),
        })
    }

    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    pub fn desc(&self) -> &SceneDesc {
        &self.scene.desc
    }

    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    pub fn revision(&self) -> u64 {
        self.revision
    }

    pub fn generation(&self) -> u64 {
        self.generation
    }

    pub fn is_dirty(&self) -> bool {
        self.dirty
    }

    /// A short name: the file stem, or the embedded scene's.
    pub fn stem(&self) -> String {
        self.path.as_deref().and_then(|p| p.file_stem()).map_or_else(
            || {
                let name = embedded_name(&self.scene.source).unwrap_or(crate::flatland::scene::DEFAULT_SCENE_NAME);
                name.trim_end_matches(".json").to_string()
            },
            |s| s.to_string_lossy().into_owned(),
        )
    }

    fn install(&mut self, scene: Scene) {
        self.scene = Arc::new(scene);
        self.revision += 1;
    }

    fn snapshot(&self) -> Snapshot {
        Snapshot {
            desc: self.scene.desc.clone(),
            source: self.scene.source.clone(),
            path: self.path.clone(),
            loaded: self.loaded,
        }
    }

    fn push_undo(&mut self) {
        let s = self.snapshot();
        self.history.push(s);
    }

    /// Change the description with `f`. Refused (with the validation error) if the
    /// result is invalid; `Ok(false)` if nothing changed. Consecutive edits with the
    /// same `key` form one undo step until [`Document::end_gesture`].
    pub fn edit(&mut self, key: &str, f: impl FnOnce(&mut SceneDesc)) -> Result<bool, SceneError> {
        let mut desc = self.scene.desc.clone();
        f(&mut desc);
        if desc == self.scene.desc {
            return Ok(false);
        }
        let scene = Scene::from_desc(desc, &self.scene.source)?;
        let before = self.snapshot();
        self.history.edit(key, || before);
        self.install(scene);
        self.dirty = true;
        Ok(true)
    }

    /// The current gesture (drag, slider) ended: the next edit is a new undo step.
    pub fn end_gesture(&mut self) {
        self.history.end_gesture();
    }

    pub fn can_undo(&self) -> bool {
        self.history.can_undo()
    }

    pub fn can_redo(&self) -> bool {
        self.history.can_redo()
    }

    fn restore(&mut self, s: Snapshot) {
        // Every stored description was valid when stored.
        let scene = Scene::from_desc(s.desc, &s.source).expect("undo states are valid");
        self.install(scene);
        if s.loaded != self.loaded {
            // Across a load: the scene's own file comes back with it.
            self.generation += 1;
        }
        (self.path, self.loaded) = (s.path, s.loaded);
        self.dirty = true;
    }

    pub fn undo(&mut self) -> bool {
        let now = self.snapshot();
        let Some(prev) = self.history.undo(now) else {
            return false;
        };
        self.restore(prev);
        true
    }

    pub fn redo(&mut self) -> bool {
        let now = self.snapshot();
        let Some(next) = self.history.redo(now) else {
            return false;
        };
        self.restore(next);
        true
    }

    /// Replace the scene with parsed and validated JSON (`name` names it in errors).
    /// On error the current scene stays. Undoable.
    pub fn load_json(&mut self, text: &str, name: &str, path: Option<PathBuf>) -> Result<(), SceneError> {
        let scene = Scene::from_json(text, name)?;
        self.end_gesture();
        self.push_undo();
        self.install(scene);
        self.path = path;
        self.loaded += 1;
        self.generation += 1;
        self.dirty = false;
        Ok(())
    }

    /// Load a scene shipped in the binary (`flatland::shipped`): it has no file, so
    /// Save asks for one.
    pub fn load_embedded(&mut self, name: &str, json: &str) -> Result<(), SceneError> {
        self.load_json(json, &embedded_source(name), None)
    }

    /// Load a scene file; on error the current scene stays.
    pub fn load_file(&mut self, path: &Path) -> Result<(), SceneError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::Io {
            file: name.clone(),
            message: e.to_string(),
        })?;
        self.load_json(&text, &name, Some(path.to_path_buf()))
    }

    /// The scene as JSON (the format `Scene::load` reads).
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(&self.scene.desc).expect("scene descriptions serialise");
        s.push('\n');
        s
    }

    /// Write the scene to `path` (atomically) and make it the document's path.
    pub fn save(&mut self, path: &Path) -> anyhow::Result<()> {
        self.write_copy(path)?;
        self.path = Some(path.to_path_buf());
        self.dirty = false;
        Ok(())
    }

    /// Write the scene to `path` (atomically), leaving the document's own file as it
    /// is: "copy as command" needs the edited scene on disk without Save then
    /// writing to a file the user never named.
    pub fn write_copy(&self, path: &Path) -> anyhow::Result<()> {
        crate::output::write_atomic(path, self.to_json().as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::edit::{Handle, drag};
    use glam::DVec2;

    #[test]
    fn a_drag_is_one_undo_step_and_redo_replays_it() {
        let mut d = Document::default_scene();
        let original = d.desc().clone();
        let h = Handle::Segment(1);
        for k in 1..=5 {
            let step = DVec2::new(0.01 * k as f64, 0.0);
            assert!(d.edit("drag", |s| drag(s, h, step - DVec2::X * 0.01, step)).unwrap());
        }
        d.end_gesture();
        assert_eq!(d.revision(), 5);
        let moved = d.desc().clone();
        assert_ne!(moved, original);
        assert!(d.undo());
        assert_eq!(d.desc(), &original);
        assert!(!d.can_undo());
        assert!(d.redo());
        assert_eq!(d.desc(), &moved);
        assert!(d.is_dirty());
    }

    #[test]
    fn invalid_edits_are_refused_and_change_nothing() {
        let mut d = Document::default_scene();
        let before = d.desc().clone();
        let err = d
            .edit("g", |s| s.medium.as_mut().unwrap().g = 1.5)
            .unwrap_err()
            .to_string();
        assert!(err.contains("medium.g"), "{err}");
        assert_eq!(d.desc(), &before);
        assert_eq!((d.revision(), d.can_undo()), (0, false));
        // An edit that changes nothing is no undo step either.
        assert!(!d.edit("g", |_| {}).unwrap());
        assert!(!d.can_undo());
    }

    #[test]
    fn loading_invalid_json_keeps_the_scene_and_save_round_trips() {
        let mut d = Document::default_scene();
        let before = d.desc().clone();
        let err = d
            .load_json("{\"domain\": 3}", "bad.json", None)
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("bad.json: domain"), "{err}");
        assert_eq!((d.desc(), d.generation()), (&before, 0));

        d.edit("sigma", |s| s.medium.as_mut().unwrap().sigma_s.0[1] = 0.3)
            .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("edited.json");
        d.save(&path).unwrap();
        assert!(!d.is_dirty());
        assert_eq!(d.stem(), "edited");
        let mut e = Document::default_scene();
        e.load_file(&path).unwrap();
        assert_eq!(e.desc(), d.desc());
        assert_eq!(e.generation(), 1);
        assert!(e.undo(), "loading is undoable");
        assert_eq!(e.desc(), &before);
    }

    #[test]
    fn undo_past_a_load_brings_back_the_previous_file_with_its_scene() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
        let b_json = crate::flatland::scene::DEFAULT_SCENE_JSON.replace("\"spp\": 128", "\"spp\": 3");
        std::fs::write(&a, crate::flatland::scene::DEFAULT_SCENE_JSON).unwrap();
        std::fs::write(&b, &b_json).unwrap();
        let mut d = Document::default_scene();
        d.load_file(&a).unwrap();
        d.edit("g", |s| s.medium.as_mut().unwrap().g = 0.4).unwrap();
        let edited_a = d.desc().clone();
        d.load_file(&b).unwrap();
        let (b_desc, generation) = (d.desc().clone(), d.generation());
        assert!(d.undo());
        assert_eq!((d.desc(), d.path()), (&edited_a, Some(a.as_path())));
        assert_eq!(d.generation(), generation + 1, "the app resets to A's settings");
        assert_eq!(d.scene().source, a.display().to_string());
        assert!(d.undo(), "A's own edit");
        assert_eq!(d.path(), Some(a.as_path()));
        assert_eq!(d.generation(), generation + 1, "no load crossed");
        assert!(d.redo() && d.redo());
        assert_eq!((d.desc(), d.path()), (&b_desc, Some(b.as_path())));
        // Writing a copy leaves the document's file alone.
        let copy = dir.path().join("copy.json");
        d.write_copy(&copy).unwrap();
        assert_eq!(d.path(), Some(b.as_path()));
        assert_eq!(std::fs::read_to_string(&b).unwrap(), b_json);
    }
}
