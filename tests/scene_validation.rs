//! Bad input gets a clear error naming the file and the JSON path, never a panic.

use volcache::flatland::scene::{Scene, SceneError};
use volcache::flatland::scene_desc::SceneDesc;

const GOOD: &str = r#"{
  "domain": { "min": [-1, -1], "max": [1, 1] },
  "segments": [ { "a": [-0.5, 0], "b": [0.5, 0], "reflectance": 0.5 } ],
  "lights": [ { "type": "point", "position": [0, 0.5], "intensity": 1 } ],
  "medium": { "sigma_a": 0.1, "sigma_s": 0.5, "g": 0.2 }
}"#;

/// Parse `GOOD` with one textual replacement and return the error message.
fn error_of(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "test typo: {from}");
    let text = GOOD.replacen(from, to, 1);
    match Scene::from_json(&text, "scenes/bad.json") {
        Ok(_) => panic!("accepted: {text}"),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("scenes/bad.json: "), "file not named: {msg}");
            msg
        }
    }
}

fn assert_names(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{msg}` does not mention `{p}`");
    }
}

#[test]
fn good_scene_loads() {
    let s = Scene::from_json(GOOD, "good.json").unwrap();
    assert_eq!(s.geometry.len(), 1);
    assert!(s.medium.is_some());
}

#[test]
fn malformed_json_names_line_and_column() {
    let msg = error_of(r#""max": [1, 1] },"#, r#""max": [1, 1] "#);
    assert_names(&msg, &["line", "column"]);
}

#[test]
fn unknown_field_is_named_with_its_path() {
    let msg = error_of(r#""reflectance": 0.5"#, r#""reflectance": 0.5, "colour": 1"#);
    assert_names(&msg, &["segments[0]", "unknown field `colour`"]);
}

#[test]
fn negative_coefficient_is_rejected() {
    let msg = error_of(r#""sigma_a": 0.1"#, r#""sigma_a": [0.1, -0.2, 0.1]"#);
    assert_names(&msg, &["medium.sigma_a[1]", "negative"]);
    let msg = error_of(r#""intensity": 1"#, r#""intensity": -1"#);
    assert_names(&msg, &["lights[0].intensity[0]", "negative"]);
}

#[test]
fn reflectance_above_one_is_rejected() {
    let msg = error_of(r#""reflectance": 0.5"#, r#""reflectance": 1.5"#);
    assert_names(&msg, &["segments[0].reflectance[0]", "at most 1"]);
}

#[test]
fn g_outside_the_validated_range_is_rejected() {
    // |g| ≤ 0.999 (crate::limits): closer to ±1 the phase function's peak and its
    // derivatives leave f64.
    for g in ["1", "-1", "1.5", "0.9999", "-0.9995", "0.9999999999999999"] {
        let msg = error_of(r#""g": 0.2"#, &format!(r#""g": {g}"#));
        assert_names(&msg, &["medium.g", "between -0.999 and 0.999"]);
    }
}

#[test]
fn non_finite_numbers_are_rejected() {
    // JSON has no NaN literal; overflowing numbers are the textual way to get inf.
    let msg = error_of(r#""sigma_s": 0.5"#, r#""sigma_s": 1e999"#);
    assert_names(&msg, &["medium.sigma_s"]);
    let msg = error_of(r#""sigma_s": 0.5"#, r#""sigma_s": NaN"#);
    assert_names(&msg, &["line"]);
    // Programmatic NaN (the app edits descriptions directly).
    let mut desc: SceneDesc = serde_json::from_str(GOOD).unwrap();
    desc.segments[0].a = Some([f64::NAN, 0.0]);
    desc.lights.clear();
    let err = Scene::from_desc(desc, "edited").unwrap_err().to_string();
    assert_names(&err, &["segments[0].a[0]", "finite"]);
}

#[test]
fn zero_length_segment_is_rejected() {
    let msg = error_of(r#""b": [0.5, 0]"#, r#""b": [-0.5, 0]"#);
    assert_names(&msg, &["segments[0].b", "zero-length"]);
}

#[test]
fn light_outside_domain_is_rejected() {
    let msg = error_of(r#""position": [0, 0.5]"#, r#""position": [0, 3]"#);
    assert_names(&msg, &["lights[0].position", "outside the domain"]);
}

#[test]
fn degenerate_domain_and_region_are_rejected() {
    let msg = error_of(r#""max": [1, 1]"#, r#""max": [-1, 1]"#);
    assert_names(&msg, &["domain.max"]);
    let msg = error_of(r#""g": 0.2"#, r#""g": 0.2, "region": {"polygon": [[0,0],[1,1]]}"#);
    assert_names(&msg, &["medium.region.polygon", "at least 3"]);
}

#[test]
fn missing_field_and_wrong_type_are_named() {
    let msg = error_of(r#""intensity": 1"#, r#""intensity": "bright""#);
    assert_names(&msg, &["lights[0].intensity"]);
    let msg = error_of(r#""type": "point", "#, r#""type": "spot", "#);
    assert_names(&msg, &["lights[0]", "spot"]);
}

#[test]
fn missing_file_names_the_file() {
    let err = Scene::load(std::path::Path::new("no/such/scene.json")).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(err.to_string().contains("no/such/scene.json"));
}

/// Every shipped scene loads, says what it is for, and round-trips through JSON.
#[test]
fn shipped_scenes_load_and_round_trip() {
    let mut n = 0;
    for entry in std::fs::read_dir("flatland_scenes").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "json") {
            continue;
        }
        let s = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(!s.desc.description.is_empty(), "{} has no description", path.display());
        let text = serde_json::to_string_pretty(&s.desc).unwrap();
        let again = Scene::from_json(&text, "round trip").unwrap();
        assert_eq!(again.desc, s.desc, "{}", path.display());
        n += 1;
    }
    assert!(n >= 6, "expected the shipped scenes, found {n}");
    let forest = Scene::load(std::path::Path::new("flatland_scenes/forest.json")).unwrap();
    assert!(forest.geometry.len() >= 200);
    assert_eq!(forest.geometry.accel(), volcache::pipeline::bvh::Accel::Bvh);
}

#[test]
fn light_fields_are_checked_per_type() {
    let msg = error_of(r#""intensity": 1 }"#, r#""intensity": 1, "irradiance": 2 }"#);
    assert_names(&msg, &["lights[0]", "`irradiance` does not apply to a point light"]);
    let msg = error_of(r#", "intensity": 1 }"#, " }");
    assert_names(&msg, &["lights[0]", "missing field `intensity`"]);
}
