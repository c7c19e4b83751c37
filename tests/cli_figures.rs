//! `volcache figure gradients`, `volcache bench derivatives` and `volcache bench records`, end to end with tiny
//! settings: the outputs exist, the JSON holds finite numbers for every method, and
//! the same seed gives the same numbers.

use serde_json::Value;
use std::path::Path;
use std::process::Command;

fn volcache() -> Command {
    Command::new(env!("CARGO_BIN_EXE_volcache"))
}

fn run_figure(dir: &Path, threads: &str) -> Value {
    let out = volcache()
        .args([
            "--threads",
            threads,
            "figure",
            "gradients",
            "flatland_scenes/occluder.json",
        ])
        .args(["--line", "-0.8,0.0,0.8,0.0", "--out", dir.to_str().unwrap()])
        .args([
            "--grid",
            "4",
            "--line-samples",
            "4",
            "--rays",
            "256",
            "--ref-spp",
            "200",
        ])
        .args(["--line-ref-spp", "200", "--seed", "5", "--quiet"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&std::fs::read(dir.join("gradients.json")).unwrap()).unwrap()
}

fn finite(v: &Value) -> bool {
    v.as_f64().is_some_and(f64::is_finite)
}

#[test]
fn figure_gradients_writes_pngs_and_json_with_all_methods() {
    let dir = tempfile::tempdir().unwrap();
    let j = run_figure(dir.path(), "2");
    for name in [
        "gradients_single.png",
        "gradients_multiple.png",
        "gradients_total.png",
        "profile_single.png",
        "profile_multiple.png",
    ] {
        let bytes = std::fs::read(dir.path().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(&bytes[1..4], b"PNG", "{name}");
        let img = tiny_skia::Pixmap::load_png(dir.path().join(name)).unwrap();
        assert!(img.width() > 600 && img.height() > 300, "{name}");
    }
    assert_eq!(j["params"]["grid"], 4);
    assert_eq!(j["params"]["seed"], 5);
    let grid = j["grid"].as_array().unwrap();
    let line = j["line"].as_array().unwrap();
    assert_eq!((grid.len(), line.len()), (16, 4));
    // occluder.json is fog everywhere: every point is inside and fully populated.
    for p in grid.iter().chain(line) {
        assert_eq!(p["inside_medium"], true);
        for method in ["aware", "unaware", "reference"] {
            for part in ["direct", "single", "multiple", "total"] {
                let t = &p[method][part];
                assert!(finite(&t["value"]), "{method} {part}: {t}");
                let g = t["gradient"].as_array().unwrap();
                assert!(g.len() == 2 && g.iter().all(finite), "{method} {part}: {t}");
                let h = &t["hessian"];
                if method == "unaware" {
                    assert!(h.is_null(), "unaware has no Hessian");
                } else {
                    let rows = h.as_array().unwrap();
                    assert!(
                        rows.iter().flat_map(|r| r.as_array().unwrap()).all(finite),
                        "{method} {part}"
                    );
                }
            }
        }
        for part in ["single", "multiple", "total"] {
            assert!(finite(&p["reference_gradient_noise"][part]));
        }
        assert!(p["cost"]["capture_rays"].as_u64().unwrap() > 0);
        assert!(p["cost"]["reference_rays"].as_u64().unwrap() > 0);
    }
    // Line points run from s = 0 to 1 along the line.
    assert_eq!(line[0]["s"], 0.0);
    assert_eq!(line[3]["s"], 1.0);
    assert_eq!(line[3]["at"][0], 0.8);
    // The lit single-scattering value beside the shadow is clearly positive.
    assert!(line[0]["reference"]["single"]["value"].as_f64().unwrap() > 0.0);
    for s in ["summary_grid", "summary_line"] {
        assert!(finite(&j[s]["single"]["aware"]["median_angle_error_deg"]), "{s}");
    }

    // Deterministic per seed, whatever the thread count (timings aside).
    let dir2 = tempfile::tempdir().unwrap();
    let k = run_figure(dir2.path(), "1");
    for (a, b) in grid.iter().zip(k["grid"].as_array().unwrap()) {
        for method in ["aware", "unaware", "reference"] {
            assert_eq!(a[method], b[method]);
        }
    }
}

#[test]
fn figure_gradients_rejects_a_bad_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = volcache()
        .args([
            "figure",
            "gradients",
            "flatland_scenes/occluder.json",
            "--line",
            "0,0,1",
        ])
        .args(["--out", dir.path().to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("X0,Y0,X1,Y1"));
    assert!(
        std::fs::read_dir(dir.path()).unwrap().next().is_none(),
        "nothing written"
    );
}

#[test]
fn bench_derivatives_writes_json() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bench.json");
    let out = volcache()
        .args(["bench", "derivatives", "flatland_scenes/occluder.json"])
        .args(["--points", "1", "--sizes", "256,512", "--min-eval-ms", "1"])
        .args(["--out", path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("aware") && stdout.contains("plain"), "{stdout}");
    let j: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let rows = j["results"].as_array().unwrap();
    assert_eq!(rows.len(), 2 * 3);
    for row in rows {
        assert!(["plain", "unaware", "aware"].contains(&row["method"].as_str().unwrap()));
        assert!(row["rays_traced"].as_f64().unwrap() >= row["rays_per_light_field"].as_f64().unwrap());
        for k in ["capture_seconds", "eval_seconds", "total_seconds"] {
            let v = row[k].as_f64().unwrap();
            assert!(v.is_finite() && v > 0.0, "{k}: {row}");
        }
    }
    // The capture is shared: the same rays for every method at one N.
    assert_eq!(rows[0]["rays_traced"], rows[2]["rays_traced"]);
    assert_eq!(j["points"].as_array().unwrap().len(), 1);
}

/// `bench records`, 2D and 3D, tiny: the JSON holds finite errors for every
/// variant and point, the baseline's efficiency is one, the truth's errors are
/// there when asked for, and a malformed variant is refused by name.
#[test]
fn bench_records_writes_json() {
    let dir = tempfile::tempdir().unwrap();
    for (scene, reference, variants, truth) in [
        ("flatland_scenes/shaded_lamp.json", "512x8", "128x8,64x8g0", true),
        ("scenes3d/lamp_fog.json", "256x4", "64x4,64x2", false),
    ] {
        let path = dir.path().join("records.json");
        let mut cmd = volcache();
        cmd.args(["bench", "records", scene, "--points", "2", "--seeds", "2"])
            .args(["--reference", reference, "--variants", variants])
            .args(["--out", path.to_str().unwrap()]);
        if truth {
            cmd.args(["--truth-spp", "2000", "--truth-batches", "2"]);
        }
        let out = cmd.output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let j: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        let summary = j["summary"].as_array().unwrap();
        assert_eq!(summary.len(), 2);
        for k in ["value", "gradient", "hessian"] {
            assert_eq!(summary[0]["efficiency"][k].as_f64(), Some(1.0), "{scene}");
        }
        let share = summary[0]["capture_share"].as_f64().unwrap();
        assert!(share > 0.0 && share <= 1.0, "{scene}: capture share {share}");
        for p in j["points"].as_array().unwrap() {
            for c in p["costs"].as_array().unwrap() {
                for k in ["value", "gradient", "hessian"] {
                    let e = c["errors"][k].as_f64().unwrap();
                    assert!(e.is_finite() && e >= 0.0, "{scene}: {c}");
                }
                assert_eq!(c.get("gradient_vs_truth").is_some(), truth, "{scene}: {c}");
            }
        }
    }
    let out = volcache()
        .args(["bench", "records", "--variants", "128by8"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("128by8") && err.contains("RAYSxSTEPS"), "{err}");
}
