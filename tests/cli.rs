//! The command line, end to end: outputs exist and are sane, errors are clear,
//! Ctrl-C leaves no partial file in place of a good one.

use std::path::Path;
use std::process::Command;

fn volcache() -> Command {
    Command::new(env!("CARGO_BIN_EXE_volcache"))
}

#[test]
fn field_writes_png_exr_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let (png, exr, json) = (
        dir.path().join("f.png"),
        dir.path().join("f.exr"),
        dir.path().join("f.json"),
    );
    let out = volcache()
        .args([
            "field",
            "flatland_scenes/windows.json",
            "--res",
            "40x30",
            "--spp",
            "4",
            "--seed",
            "3",
            "--quiet",
        ])
        .args([
            "--out",
            png.to_str().unwrap(),
            "--exr",
            exr.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let png_bytes = std::fs::read(&png).unwrap();
    assert_eq!(&png_bytes[1..4], b"PNG");
    let (w, h, px) = volcache::output::read_exr(&exr).unwrap();
    assert_eq!((w, h), (40, 30));
    assert!(px.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    assert!(px.iter().any(|p| p[0] > 0.0));
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(j["params"]["width"], 40);
    assert_eq!(j["params"]["seed"], 3);
    assert_eq!(j["samples"], 40 * 30 * 4);
    assert!(j["rays"].as_u64().unwrap() > 0);
    assert!(j["samples_per_second"].as_f64().unwrap() > 0.0);
    // Same seed, same EXR.
    let exr2 = dir.path().join("g.exr");
    let out = volcache()
        .args([
            "--threads",
            "1",
            "field",
            "flatland_scenes/windows.json",
            "--res",
            "40x30",
            "--spp",
            "4",
        ])
        .args([
            "--seed",
            "3",
            "--quiet",
            "--out",
            dir.path().join("g.png").to_str().unwrap(),
        ])
        .args(["--exr", exr2.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(volcache::output::read_exr(&exr2).unwrap().2, px);
}

#[test]
fn probe_prints_parts_as_json() {
    let out = volcache()
        .args([
            "probe",
            "flatland_scenes/point_in_fog.json",
            "--at",
            "1,0",
            "--at",
            "-0.5,0.5",
            "--spp",
            "2000",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let arr = j.as_array().unwrap();
    assert_eq!(arr.len(), 2);
    let total = arr[0]["value"]["total"][0].as_f64().unwrap();
    // point_in_fog renders fluence by default: φ(1) = 0.3234545 (benchmarks.md).
    assert!((total - 0.3234545).abs() < 0.03, "{total}");
    for k in ["direct", "single", "multiple", "total"] {
        assert!(arr[1]["value"][k].is_array(), "missing part {k}");
    }
}

#[test]
fn bad_scene_fails_with_file_and_field_named() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(
        &bad,
        r#"{"domain": {"min": [0,0], "max": [1,1]}, "medium": {"sigma_a": -1, "sigma_s": 1}}"#,
    )
    .unwrap();
    let out = volcache()
        .args(["field", bad.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.json") && err.contains("medium.sigma_a"), "{err}");
    let out = volcache().args(["field", "does/not/exist.json"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("does/not/exist.json"));
}

/// Ctrl-C stops the render and leaves the previous good PNG untouched.
#[cfg(unix)]
#[test]
fn interrupt_keeps_previous_output() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("keep.png");
    std::fs::write(&png, b"previous good file").unwrap();
    let mut child = volcache()
        .args([
            "field",
            "flatland_scenes/windows.json",
            "--res",
            "400x300",
            "--spp",
            "100000",
            "--quiet",
        ])
        .args(["--out", png.to_str().unwrap()])
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(800));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    assert_eq!(std::fs::read(&png).unwrap(), b"previous good file");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(leftovers.len(), 1, "temporary files left behind");
    assert!(Path::new(&png).exists());
}
