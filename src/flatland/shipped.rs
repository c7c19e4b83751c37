//! The scenes of `flatland_scenes/`, embedded in the binary so that the workbench
//! offers them wherever it is started from (issue 15: "Open…" listed
//! `./flatland_scenes` relative to the working directory only). An embedded scene
//! has no file: errors name it `<embedded NAME>`.

/// (file name, JSON) of every scene in `flatland_scenes/`, by name.
pub const SHIPPED_SCENES: [(&str, &str); 7] = [
    ("forest.json", include_str!("../../flatland_scenes/forest.json")),
    ("furnace.json", include_str!("../../flatland_scenes/furnace.json")),
    ("half_space.json", include_str!("../../flatland_scenes/half_space.json")),
    ("occluder.json", include_str!("../../flatland_scenes/occluder.json")),
    (
        "point_in_fog.json",
        include_str!("../../flatland_scenes/point_in_fog.json"),
    ),
    (
        "shaded_lamp.json",
        include_str!("../../flatland_scenes/shaded_lamp.json"),
    ),
    ("windows.json", include_str!("../../flatland_scenes/windows.json")),
];

/// The source name (`Scene::source`) of the embedded scene `name`.
pub fn embedded_source(name: &str) -> String {
    format!("<embedded {name}>")
}

/// The scene's name if `source` names an embedded scene.
pub fn embedded_name(source: &str) -> Option<&str> {
    source.strip_prefix("<embedded ")?.strip_suffix('>')
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flatland::scene::{DEFAULT_SCENE_NAME, Scene};

    #[test]
    fn every_scene_of_the_folder_is_shipped_and_valid() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/flatland_scenes");
        let mut on_disk: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".json"))
            .collect();
        on_disk.sort();
        let shipped: Vec<&str> = SHIPPED_SCENES.iter().map(|(n, _)| *n).collect();
        assert_eq!(on_disk, shipped);
        for (name, json) in SHIPPED_SCENES {
            let s = Scene::from_json(json, &embedded_source(name)).unwrap();
            assert_eq!(embedded_name(&s.source), Some(name));
        }
        assert_eq!(Scene::default_scene().source, embedded_source(DEFAULT_SCENE_NAME));
        assert_eq!(embedded_name("flatland_scenes/a.json"), None);
    }
}
