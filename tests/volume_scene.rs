//! The 3D scene format: shipped scenes load and round-trip; malformed JSON, unknown
//! fields, invalid values and missing meshes are errors that name the file and the
//! JSON path — never a panic.

use std::path::Path;
use volcache::volume::scene::Scene;
use volcache::volume::scene_desc::SceneDesc;

fn err(json: &str) -> String {
    match Scene::from_json(json, "bad.json", Path::new("scenes3d")) {
        Ok(_) => panic!("accepted: {json}"),
        Err(e) => e.to_string(),
    }
}

const CAM: &str = r#""camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_deg": 40}"#;

#[test]
fn shipped_scenes_load_and_round_trip() {
    for name in ["fog_box", "staircase", "mesh_in_fog"] {
        let path = format!("scenes3d/{name}.json");
        let s = Scene::load(Path::new(&path)).unwrap_or_else(|e| panic!("{e}"));
        assert!(!s.geometry.is_empty() && s.medium.is_some(), "{name}");
        let text = serde_json::to_string(&s.desc).unwrap();
        let back: SceneDesc = serde_json::from_str(&text).unwrap();
        assert_eq!(back, s.desc, "{name}");
    }
    let mesh = Scene::load(Path::new("scenes3d/mesh_in_fog.json")).unwrap();
    assert_eq!(mesh.geometry.len(), 2 + 2 + 80);
    let fog = Scene::load(Path::new("scenes3d/fog_box.json")).unwrap();
    assert_eq!(fog.emitters.prims.len(), 2);
}

#[test]
fn errors_name_the_file_and_the_json_path() {
    let cases = [
        (
            format!(
                r#"{{ {CAM}, "shapes": [{{"quad": {{"origin": [0,0,0], "u": [1,0,0], "v": [0,1,0]}}, "colour": 1}}] }}"#
            ),
            "shapes[0].colour: unknown field `colour`",
        ),
        (
            format!(r#"{{ {CAM}, "shapes": [{{"quad": {{"origin": [0,0,0], "u": [1,0,0], "v": [2,0,0]}}}}] }}"#),
            "shapes[0].quad.v: u and v must span",
        ),
        (
            format!(r#"{{ {CAM}, "shapes": [{{"reflectance": 0.5}}] }}"#),
            "shapes[0]: give exactly one of",
        ),
        (
            format!(r#"{{ {CAM}, "shapes": [{{"box": {{"min": [0,0,0], "max": [1,0,1]}}, "reflectance": 1.5}}] }}"#),
            "shapes[0].box.max: must be greater",
        ),
        (
            format!(
                r#"{{ {CAM}, "shapes": [{{"box": {{"min": [0,0,0], "max": [1,1,1]}}, "reflectance": [0.5, 1.5, 0]}}] }}"#
            ),
            "shapes[0].reflectance[1]: must be at most 1",
        ),
        (
            format!(r#"{{ {CAM}, "shapes": [{{"mesh": {{"path": "missing.obj"}}}}] }}"#),
            "shapes[0].mesh.path: cannot load",
        ),
        (
            format!(r#"{{ {CAM}, "shapes": [{{"mesh": {{"path": "icosphere.obj", "scale": [1, 0, 1]}}}}] }}"#),
            "shapes[0].mesh.scale[1]: must be positive",
        ),
        (
            format!(r#"{{ {CAM}, "lights": [{{"spot": {{}}}}] }}"#),
            "lights[0]: unknown variant `spot`",
        ),
        (
            format!(r#"{{ {CAM}, "lights": [{{"sun": {{"direction": [0,0,0], "irradiance": 1}}}}] }}"#),
            "lights[0].sun.direction: must not be the zero vector",
        ),
        (
            format!(
                r#"{{ {CAM}, "lights": [{{"sun": {{"direction": [0,0,-1], "irradiance": 1, "angular_radius_deg": 90}}}}] }}"#
            ),
            "lights[0].sun.angular_radius_deg",
        ),
        (
            format!(r#"{{ {CAM}, "lights": [{{"point": {{"position": [0,0,0], "intensity": -1}}}}] }}"#),
            "lights[0].point.intensity[0]: must not be negative",
        ),
        (
            format!(r#"{{ {CAM}, "medium": {{"sigma_a": 0, "sigma_s": 1, "g": 1}} }}"#),
            "medium.g: must lie between -0.999 and 0.999",
        ),
        (
            format!(r#"{{ {CAM}, "medium": {{"sigma_a": 0, "sigma_s": 1, "region": {{"sphere": 1}}}} }}"#),
            "medium.region: unknown variant `sphere`",
        ),
        (
            format!(r#"{{ {CAM}, "render": {{"spp": 0}} }}"#),
            "render.spp: must be at least 1",
        ),
        (
            r#"{ "camera": {"position": [0, 0, 0], "look_at": [0, 0, 0], "fov_deg": 200} }"#.to_string(),
            "camera.look_at: must differ",
        ),
        (
            r#"{ "camera": {"position": [0, 0, 1], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 40} }"#
                .to_string(),
            "camera.up: must not be parallel",
        ),
        (r#"{ "shapes": [] }"#.to_string(), "missing field `camera`"),
        (r#"{ "camera": "#.to_string(), "bad.json"),
    ];
    let wrong: Vec<String> = cases
        .iter()
        .map(|(json, want)| (err(json), want))
        .filter(|(e, want)| !(e.starts_with("bad.json: ") && e.contains(*want)))
        .map(|(e, want)| format!("expected `{want}` in: {e}"))
        .collect();
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
