//! `render3d --eye-cone DEG` (`CacheSettings::eye_cone_deg`, `pipeline::eye_cone`):
//! a record serves only the points the camera sees within DEG of it. Checked on
//! scenes of our own: a camera inside forward-scattering fog with a lamp ahead,
//! and the same fog made isotropic (where L_s does not depend on ω_o and the cone
//! is off).

use std::path::Path;
use std::process::Command;

/// A camera inside g = 0.6 fog, a lamp 0.8 ahead, a pillar beside it; `G` is
/// replaced by the phase's g.
const CAMERA_IN_FOG: &str = r#"{
  "camera": {"position": [0.1, 1.1, 0.9], "look_at": [0, 1, 0], "fov_deg": 60},
  "shapes": [
    {"quad": {"origin": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}, "reflectance": 0.5},
    {"box": {"min": [0.3, 0, -0.3], "max": [0.45, 1.8, -0.15]}, "reflectance": 0.4}
  ],
  "lights": [{"point": {"position": [0, 1.0, 0.1], "intensity": [2, 1.8, 1.5]}}],
  "medium": {"sigma_a": 0.1, "sigma_s": 2.0, "g": G,
             "region": {"box": {"min": [-2, 0, -2], "max": [2, 2.5, 2]}}},
  "render": {"resolution": [16, 12], "spp": 2, "seed": 5, "max_depth": 16}
}"#;

/// `render3d SCENE --method ours` at 16×12, 2 spp, 32 directions of 4 steps, and
/// `extra`, into `dir/sub`: whether it succeeded, its stderr, its summary.
fn render(dir: &Path, scene: &Path, extra: &[&str], sub: &str) -> (bool, String, Option<serde_json::Value>) {
    let out_dir = dir.join(sub);
    let out = Command::new(env!("CARGO_BIN_EXE_volcache"))
        .arg("render3d")
        .arg(scene)
        .args([
            "--method", "ours", "--res", "16x12", "--spp", "2", "--seed", "3", "--quiet",
        ])
        .args(["--rays", "32", "--steps", "4"])
        .args(extra)
        .arg("--out")
        .arg(&out_dir)
        .output()
        .unwrap();
    let stem = scene.file_stem().unwrap().to_string_lossy();
    let summary = std::fs::read_to_string(out_dir.join(format!("{stem}_ours.json")))
        .ok()
        .map(|t| serde_json::from_str::<serde_json::Value>(&t).unwrap());
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    (out.status.success(), err, summary)
}

fn scene_file(dir: &Path, g: &str) -> std::path::PathBuf {
    let path = dir.join(format!("camera_in_fog_{}.json", g.replace('.', "_")));
    std::fs::write(&path, CAMERA_IN_FOG.replace('G', g)).unwrap();
    path
}

fn records(s: &serde_json::Value) -> u64 {
    s["cache"]["records"].as_u64().unwrap()
}

/// The cone reaches the settings, the summary and the records file; a camera in
/// anisotropic fog needs more records with it (those near the camera serve less
/// of the view); read back, the records serve the same points (the image is the
/// same bit for bit), and without the file's cone they serve more (another image).
#[test]
fn the_eye_cone_travels_from_the_command_line_to_the_image() {
    let d = tempfile::tempdir().unwrap();
    let scene = scene_file(d.path(), "0.6");
    let file = d.path().join("records.json");
    let file_arg = file.to_str().unwrap();
    let (ok, err, cone) = render(
        d.path(),
        &scene,
        &["--eye-cone", "6", "--records-out", file_arg],
        "cone",
    );
    assert!(ok, "{err}");
    let cone = cone.unwrap();
    assert_eq!(cone["cache"]["settings"]["eye_cone_deg"], 6.0);
    let (ok, err, free) = render(d.path(), &scene, &[], "free");
    assert!(ok, "{err}");
    let free = free.unwrap();
    assert!(
        free["cache"]["settings"].get("eye_cone_deg").is_none(),
        "off by default"
    );
    println!("records: {} with the cone, {} without", records(&cone), records(&free));
    assert!(
        records(&cone) > records(&free),
        "{} vs {}",
        records(&cone),
        records(&free)
    );

    let stored: serde_json::Value = serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
    assert_eq!(stored["eye_cone_deg"], 6.0);
    let exr = |sub: &str| std::fs::read(d.path().join(sub).join("camera_in_fog_0_6_ours.exr")).unwrap();
    let (ok, err, _) = render(d.path(), &scene, &["--records-in", file_arg], "read");
    assert!(ok, "{err}");
    assert!(exr("read") == exr("cone"), "read back, the records give another image");
    let mut wide = stored.clone();
    wide.as_object_mut().unwrap().remove("eye_cone_deg");
    let wide_file = d.path().join("wide.json");
    std::fs::write(&wide_file, serde_json::to_string(&wide).unwrap()).unwrap();
    let (ok, err, _) = render(d.path(), &scene, &["--records-in", wide_file.to_str().unwrap()], "wide");
    assert!(ok, "{err}");
    assert!(
        exr("wide") != exr("cone"),
        "without the cone the records serve the same points"
    );
}

/// In isotropic fog L_s does not turn with ω_o: the cone changes nothing.
#[test]
fn the_eye_cone_is_off_in_isotropic_fog() {
    let d = tempfile::tempdir().unwrap();
    let scene = scene_file(d.path(), "0");
    let (ok, err, cone) = render(d.path(), &scene, &["--eye-cone", "6"], "cone");
    assert!(ok, "{err}");
    let (ok, err, free) = render(d.path(), &scene, &[], "free");
    assert!(ok, "{err}");
    let exr = |sub: &str| std::fs::read(d.path().join(sub).join("camera_in_fog_0_ours.exr")).unwrap();
    assert_eq!(records(&cone.unwrap()), records(&free.unwrap()));
    assert!(exr("cone") == exr("free"));
}

/// A cone out of range, or beside records read from a file (which carry their
/// own), is refused naming the option, and nothing is written.
#[test]
fn a_bad_eye_cone_is_refused_by_name() {
    let d = tempfile::tempdir().unwrap();
    let scene = scene_file(d.path(), "0.6");
    for (bad, sub) in [("0", "zero"), ("91", "wide"), ("nan", "nan")] {
        let (ok, err, summary) = render(d.path(), &scene, &["--eye-cone", bad], sub);
        assert!(!ok && summary.is_none(), "--eye-cone {bad} accepted");
        assert!(err.contains("--eye-cone"), "{err}");
        assert!(!d.path().join(sub).exists(), "--eye-cone {bad} wrote something");
    }
    let (ok, err, _) = render(d.path(), &scene, &["--eye-cone", "6", "--records-in", "x.json"], "both");
    assert!(!ok && err.contains("--eye-cone"), "{err}");
}
