//! `volcache render3d` end to end: outputs and summary, clear errors for methods not
//! built yet, bad crops and scenes, and Ctrl-C (exit 130, nothing written).

use std::process::Command;

fn volcache() -> Command {
    Command::new(env!("CARGO_BIN_EXE_volcache"))
}

#[test]
fn render3d_writes_exr_png_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let out = volcache()
        .args([
            "render3d",
            "scenes3d/mesh_in_fog.json",
            "--method",
            "pt",
            "--res",
            "32x24",
            "--spp",
            "2",
        ])
        .args([
            "--seed",
            "4",
            "--crop",
            "4,2,20,18",
            "--bench-rays",
            "10000",
            "--quiet",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (w, h, px) = volcache::output::read_exr(&dir.path().join("mesh_in_fog_pt.exr")).unwrap();
    assert_eq!((w, h), (16, 16));
    assert!(px.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    assert!(px.iter().any(|p| p[0] > 0.0));
    assert!(tiny_skia::Pixmap::load_png(dir.path().join("mesh_in_fog_pt.png")).is_ok());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("mesh_in_fog_pt.json")).unwrap()).unwrap();
    assert_eq!(json["spp"], 2);
    assert_eq!(json["samples"], 16 * 16 * 2);
    assert!(json["rays_per_second"].as_f64().unwrap() > 0.0);
    assert!(json["rays3d_closest_hit_per_second"].as_f64().unwrap() > 0.0);
}

#[test]
fn time_budget_limits_the_samples() {
    let dir = tempfile::tempdir().unwrap();
    let out = volcache()
        .args([
            "render3d",
            "scenes3d/fog_box.json",
            "--res",
            "16x16",
            "--time-budget",
            "0.5",
            "--quiet",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("fog_box_pt.json")).unwrap()).unwrap();
    let (spp, secs) = (json["spp"].as_u64().unwrap(), json["seconds"].as_f64().unwrap());
    assert!(spp >= 1 && secs < 2.0, "{spp} spp in {secs} s");
}

#[test]
fn unimplemented_methods_and_bad_input_are_clear_errors() {
    for method in ["ours", "jarosz08"] {
        let dir = tempfile::tempdir().unwrap();
        let out = volcache()
            .args(["render3d", "scenes3d/fog_box.json", "--method", method, "--out"])
            .arg(dir.path())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains("not implemented yet (issue 6)"),
            "{err}"
        );
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            0,
            "wrote output for {method}"
        );
    }
    let out = volcache()
        .args([
            "render3d",
            "scenes3d/fog_box.json",
            "--res",
            "10x10",
            "--crop",
            "0,0,11,5",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("--crop"));
    let out = volcache().args(["render3d", "does/not/exist.json"]).output().unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("does/not/exist.json"));
}

#[cfg(unix)]
#[test]
fn interrupt_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut child = volcache()
        .args([
            "render3d",
            "scenes3d/staircase.json",
            "--res",
            "400x300",
            "--spp",
            "100000",
            "--quiet",
            "--out",
        ])
        .arg(dir.path())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(800));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    assert_eq!(child.wait().unwrap().code(), Some(130));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}
