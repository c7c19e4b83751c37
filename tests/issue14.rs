//! Issue 14, one test per failure it lists (each failed on the code it was filed
//! against: a hang, an abort, a NaN/inf/null in an output, an input destroyed, a
//! silent surprise). The ranges that fix most of them are `volcache::limits`; the
//! fuzz targets are in `fuzz_parsers.rs`, the extreme-parameter grid in
//! `extreme_grid.rs`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn volcache() -> Command {
    Command::new(env!("CARGO_BIN_EXE_volcache"))
}

/// Run to completion within `limit` (a hang fails the test instead of hanging it).
fn run_within(cmd: &mut Command, limit: Duration) -> Output {
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            panic!("{cmd:?} did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn run(cmd: &mut Command) -> Output {
    run_within(cmd, Duration::from_secs(60))
}

/// A refused run: exit code 2 and its message.
fn refused(cmd: &mut Command) -> String {
    let out = run(cmd);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(2),
        "expected a clear error from {cmd:?}, got: {err}"
    );
    err
}

fn succeeded(cmd: &mut Command) -> String {
    let out = run(cmd);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{cmd:?}: {err}");
    err
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

const FOG: &str = r#"{"domain": {"min": [-1, -1], "max": [1, 1]},
  "segments": [{"a": [0.3, 0.75], "b": [-0.3, 0.75], "emission": 4}],
  "medium": {"sigma_a": 0.1, "sigma_s": 0.9}}"#;

const FOG3: &str = r#"{"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_deg": 40},
  "shapes": [{"quad": {"origin": [-1, -1, -1], "u": [2, 0, 0], "v": [0, 2, 0]}, "reflectance": 0.5}],
  "lights": [{"sun": {"direction": [0.3, -1, 0.2], "irradiance": 2}}],
  "medium": {"sigma_a": 0.1, "sigma_s": 0.5, "g": 0.3,
             "region": {"box": {"min": [-1.5, -1.5, -1.5], "max": [1.5, 1.5, 1.5]}}}}"#;

/// Item 1: `caches` on a domain 10⁻³⁰⁷ wide looped for ever drawing its records: the
/// domain is refused (at least 10⁻⁶ across), in well under a second.
#[test]
fn item01_a_vanishing_domain_is_refused_not_drawn_for_ever() {
    let d = tempfile::tempdir().unwrap();
    let s = write(
        d.path(),
        "tiny.json",
        r#"{"domain":{"min":[0,0],"max":[1e-307,1e-307]},"medium":{"sigma_a":0.1,"sigma_s":0.9}}"#,
    );
    let err = refused(
        volcache()
            .arg("caches")
            .arg(&s)
            .args([
                "--res",
                "1x1",
                "--rays",
                "16",
                "--steps",
                "2",
                "--ref-spp",
                "1",
                "--quiet",
            ])
            .arg("--out")
            .arg(d.path().join("out"))
            .arg("--ref-cache")
            .arg(d.path().join("ref")),
    );
    assert!(
        err.contains("tiny.json") && err.contains("domain") && err.contains("at least 1e-6"),
        "{err}"
    );
}

/// Item 2: σ_s = 10⁸, g = 0.999 with max_depth 2³²−1 never finished: max_depth is
/// bounded (10⁵), and at the bound the same scene renders in seconds.
#[test]
fn item02_unbounded_path_depth_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let scene = |depth: u64| {
        format!(
            r#"{{"domain":{{"min":[-1,-1],"max":[1,1]}},"medium":{{"sigma_a":0,"sigma_s":1e8,"g":0.999}},
                "lights":[{{"type":"point","position":[0,0],"intensity":1}}],"render":{{"max_depth":{depth}}}}}"#
        )
    };
    let s = write(d.path(), "deep.json", &scene(4294967295));
    let field = |s: &Path| {
        let mut c = volcache();
        c.arg("field")
            .arg(s)
            .args(["--res", "2x2", "--spp", "1", "--quiet", "--out"])
            .arg(d.path().join("f.png"));
        c
    };
    let err = refused(&mut field(&s));
    assert!(
        err.contains("render.max_depth") && err.contains("at most 100000"),
        "{err}"
    );
    let s = write(d.path(), "deepest.json", &scene(100000));
    run_within(&mut field(&s), Duration::from_secs(60));
}

/// Item 3: `field --false-color` with σ_s = 5·10⁻³²⁴ asked for 5.4 GB for colour-bar
/// ticks: subnormal coefficients are refused (and the colour bar copes anyway:
/// `figure::colorbar` tests).
#[test]
fn item03_subnormal_coefficients_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let s = write(
        d.path(),
        "thin.json",
        r#"{"domain":{"min":[-1,-1],"max":[1,1]},"medium":{"sigma_a":0.1,"sigma_s":5e-324},
            "lights":[{"type":"point","position":[0,0.5],"intensity":1}]}"#,
    );
    let err = refused(
        volcache()
            .arg("field")
            .arg(&s)
            .args(["--res", "8x8", "--spp", "1", "--false-color", "--quiet", "--out"])
            .arg(d.path().join("f.png")),
    );
    assert!(
        err.contains("medium.sigma_s[0]") && err.contains("at least 1e-12"),
        "{err}"
    );
}

/// Item 4: `--res 16384x16384` was accepted and aborted allocating 6.4 GB: sizes beyond
/// what fits are refused up front, by every command.
#[test]
fn item04_images_that_cannot_fit_are_refused_up_front() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    for args in [
        vec!["field", "--res", "16384x16384", "--quiet", "--out", "o/f.png"],
        vec!["caches", "--res", "16384x16384", "--quiet", "--out", "o"],
        vec![
            "render3d",
            "scenes3d/fog_box.json",
            "--res",
            "16384x16384",
            "--quiet",
            "--out",
            "o",
        ],
    ] {
        let err = refused(volcache().args(&args).current_dir(env!("CARGO_MANIFEST_DIR")));
        assert!(err.contains("16384x16384") && err.contains("pixels"), "{args:?}: {err}");
    }
    assert!(!out.exists());
    // What grows beyond the image — here 3D records as ε → 0, about 5 kB each — is
    // watched too: past the memory limit the run stops with a clear error (the
    // limit is set low here; by default it is 80% of the memory available).
    let err = refused(
        volcache()
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("VOLCACHE_MEMORY_LIMIT_MB", "80")
            .args([
                "render3d",
                "scenes3d/fog_box.json",
                "--method",
                "ours",
                "--res",
                "64x48",
                "--spp",
                "1",
            ])
            .args(["--rays", "4", "--steps", "1", "--eps", "1e-9", "--quiet", "--out"])
            .arg(&out),
    );
    assert!(err.contains("outgrew the memory"), "{err}");
    assert!(!out.exists());
}

/// Item 5: Radiance above the f32 range became inf in the EXR: emission 10³⁹ is refused
/// (at most 10²⁰), and so are records whose values leave the f32 range.
#[test]
fn item05_radiance_beyond_f32_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let s = write(
        d.path(),
        "bright.json",
        &FOG.replace(r#""emission": 4"#, r#""emission": 1e39"#),
    );
    let err = refused(volcache().arg("field").arg(&s).arg("--quiet"));
    assert!(
        err.contains("segments[0].emission[0]") && err.contains("at most 1e20"),
        "{err}"
    );
    // A records file holding a value of 10³⁹.
    let scene = write(d.path(), "fog3.json", FOG3);
    let records = d.path().join("r.json");
    let base = [
        "--method", "ours", "--res", "4x3", "--spp", "1", "--rays", "64", "--steps", "2", "--quiet",
    ];
    succeeded(
        volcache()
            .arg("render3d")
            .arg(&scene)
            .args(base)
            .arg("--records-out")
            .arg(&records)
            .arg("--place-only"),
    );
    let mut v = json(&records);
    v["records"][0]["value"][1][0] = serde_json::json!(1e39);
    std::fs::write(&records, serde_json::to_vec(&v).unwrap()).unwrap();
    let err = refused(
        volcache()
            .arg("render3d")
            .arg(&scene)
            .args(base)
            .arg("--records-in")
            .arg(&records)
            .arg("--out")
            .arg(d.path().join("o")),
    );
    assert!(
        err.contains("r.json") && err.contains("records[0].value[1][0]"),
        "{err}"
    );
}

/// Item 6: Emission 10³⁰⁸ gave NaN near a corner, 5·10⁻³²⁴ NaN in 2D and 3D: both are
/// outside the radiometric range.
#[test]
fn item06_extreme_emissions_are_refused() {
    let d = tempfile::tempdir().unwrap();
    for e in ["1e308", "5e-324"] {
        let s = write(
            d.path(),
            "e.json",
            &FOG.replace(r#""emission": 4"#, &format!(r#""emission": {e}"#)),
        );
        let err = refused(volcache().arg("field").arg(&s).arg("--quiet"));
        assert!(err.contains("segments[0].emission[0]"), "{e}: {err}");
        let s = write(
            d.path(),
            "e3.json",
            &FOG3.replace(
                r#""reflectance": 0.5}"#,
                &format!(r#""reflectance": 0.5, "emission": {e}}}"#),
            ),
        );
        let err = refused(volcache().arg("render3d").arg(&s).arg("--quiet"));
        assert!(err.contains("shapes[0].emission[0]"), "{e}: {err}");
    }
}

/// Item 7: A scene without a medium wrote `luminance_min/max: null`: no pixel is valid,
/// the summary says so and its statistics are 0.
#[test]
fn item07_no_medium_summary_has_numbers() {
    let d = tempfile::tempdir().unwrap();
    let s = write(
        d.path(),
        "vacuum.json",
        r#"{"domain":{"min":[-1,-1],"max":[1,1]},"segments":[{"a":[-0.5,0.9],"b":[0.5,0.9],"emission":1}]}"#,
    );
    let j = d.path().join("f.json");
    succeeded(
        volcache()
            .arg("field")
            .arg(&s)
            .args(["--res", "8x8", "--spp", "2", "--quiet", "--out"])
            .arg(d.path().join("f.png"))
            .arg("--json")
            .arg(&j),
    );
    let v = json(&j);
    assert_eq!(v["valid_pixels"], 0);
    for k in ["luminance_min", "luminance_max", "luminance_mean"] {
        assert_eq!(v[k].as_f64(), Some(0.0), "{k}: {v}");
    }
}

/// Item 8: An all-zero reference gave relMSE 6.5·10³⁰³ up to inf: the floor falls back
/// to the image's own mean (unit test in `core::stats`), so relMSE is bounded by
/// 100 × pixels.
#[test]
fn item08_all_zero_reference_gives_a_finite_relmse() {
    let d = tempfile::tempdir().unwrap();
    let scene = write(d.path(), "fog3.json", FOG3);
    let zero = volcache::flatland::field::Field::new(4, 3, glam::DVec2::ZERO, glam::DVec2::ONE);
    let reference = d.path().join("zero.exr");
    volcache::output::write_exr(&reference, &zero).unwrap();
    succeeded(
        volcache()
            .arg("render3d")
            .arg(&scene)
            .args(["--res", "4x3", "--spp", "2", "--quiet", "--reference"])
            .arg(&reference)
            .arg("--out")
            .arg(d.path().join("o")),
    );
    let v = json(&d.path().join("o/fog3_pt.json"));
    let relmse = v["errors"]["total"]["relmse"].as_f64().unwrap();
    assert!(relmse > 0.0 && relmse <= 100.0 * 12.0, "{relmse}");
}

/// Item 9: `--fd-step 1e-300` gave a NaN Hessian, `--medium-clamp 1e308` NaN
/// derivatives, `caches --eps nan|inf` was accepted: all are out of range.
#[test]
fn item09_options_outside_their_ranges_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let s = write(d.path(), "fog.json", FOG);
    let probe = |method: &str, flag: &str, v: &str| {
        let mut c = volcache();
        c.arg("probe")
            .arg(&s)
            .args(["--at", "0,0", "--method", method, "--rays", "16", "--spp", "4", flag, v]);
        c
    };
    for v in ["1e-300", "0.9", "nan"] {
        let err = refused(&mut probe("reference", "--fd-step", v));
        assert!(err.contains("--fd-step must lie between 1e-9 and 5e-1"), "{v}: {err}");
    }
    for v in ["1e308", "0", "inf"] {
        let err = refused(&mut probe("aware", "--medium-clamp", v));
        assert!(err.contains("--medium-clamp must lie between"), "{v}: {err}");
    }
    for v in ["nan", "inf", "-1"] {
        let err = refused(
            volcache()
                .arg("caches")
                .arg(&s)
                .args(["--res", "4x4", "--quiet", &format!("--eps={v}")])
                .arg("--out")
                .arg(d.path().join("o")),
        );
        assert!(err.contains("--eps must lie between"), "{v}: {err}");
    }
    assert!(!d.path().join("o").exists());
}

/// Item 10: Probe points at 10³⁰⁸, segments at ±10¹⁵⁴ (NaN; beyond 10¹⁵⁵ the emitter
/// vanished), a camera at 10³⁰⁰, a sun direction of length 10⁻²⁰⁰ and σ_s = 10³⁰⁰
/// with g = 1 − 10⁻¹⁶: each is refused naming its field.
#[test]
fn item10_out_of_range_geometry_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let s = write(d.path(), "fog.json", FOG);
    let err = refused(volcache().arg("probe").arg(&s).args(["--at", "1e308,0"]));
    assert!(err.contains("1e308") && err.contains("±1e12"), "{err}");
    for far in ["1e154", "1e156", "1e11"] {
        let text = FOG.replace("[0.3, 0.75]", &format!("[{far}, 0.75]"));
        let s = write(d.path(), "far.json", &text);
        let err = refused(volcache().arg("field").arg(&s).arg("--quiet"));
        assert!(err.contains("far.json: segments[0].a"), "{far}: {err}");
    }
    // Entirely outside the world disc (10³ scene sizes): it would never be seen.
    let text = FOG
        .replace("[0.3, 0.75]", "[5e3, 0.75]")
        .replace("[-0.3, 0.75]", "[5e3, 1]");
    let s = write(d.path(), "gone.json", &text);
    let err = refused(volcache().arg("field").arg(&s).arg("--quiet"));
    assert!(err.contains("segments[0].b") && err.contains("world disc"), "{err}");
    let cases = [
        (
            r#""position": [0, 0, 3]"#,
            r#""position": [0, 0, 1e300]"#,
            "camera.position[2]",
        ),
        (
            r#""direction": [0.3, -1, 0.2]"#,
            r#""direction": [1e-200, -1e-200, 0]"#,
            "lights[0].sun.direction",
        ),
        (
            r#""sigma_s": 0.5, "g": 0.3"#,
            r#""sigma_s": 1e300, "g": 0.9999999999999999"#,
            "medium.sigma_s[0]",
        ),
        (
            r#""sigma_s": 0.5, "g": 0.3"#,
            r#""sigma_s": 0.5, "g": 0.9999999999999999"#,
            "medium.g",
        ),
    ];
    for (from, to, field) in cases {
        let s = write(d.path(), "bad3.json", &FOG3.replace(from, to));
        let err = refused(volcache().arg("render3d").arg(&s).arg("--quiet"));
        assert!(err.contains(&format!("bad3.json: {field}")), "{to}: {err}");
    }
}

/// Item 11: An output path equal to the input destroyed it, and the same path for
/// --out, --exr and --json kept only the last: both are refused before any work,
/// and the input is intact.
#[test]
fn item11_outputs_never_overwrite_inputs_or_each_other() {
    let d = tempfile::tempdir().unwrap();
    let s = write(d.path(), "s.json", FOG);
    let field = |extra: &[&str]| {
        let mut c = volcache();
        c.current_dir(d.path())
            .args(["field", "s.json", "--res", "4x4", "--spp", "1", "--quiet"])
            .args(extra);
        c
    };
    for flag in ["--out", "--exr", "--json"] {
        let err = refused(&mut field(&[flag, "s.json"]));
        assert!(err.contains(&format!("{flag} would overwrite the scene")), "{err}");
        // Spelled another way.
        let err = refused(&mut field(&[flag, "./sub/../s.json"]));
        assert!(err.contains("would overwrite the scene"), "{err}");
    }
    let err = refused(&mut field(&["--out", "x.png", "--exr", "x.png", "--json", "x.png"]));
    assert!(err.contains("--out and --exr name the same file (x.png)"), "{err}");
    assert_eq!(std::fs::read_to_string(&s).unwrap(), FOG);
    assert!(!d.path().join("x.png").exists());
    // render3d --records-out onto the scene, and onto its own outputs.
    let s3 = write(d.path(), "fog3.json", FOG3);
    let render3d = |extra: &[&str]| {
        let mut c = volcache();
        c.current_dir(d.path())
            .args(["render3d", "fog3.json", "--method", "ours", "--res", "4x3", "--quiet"])
            .args(extra);
        c
    };
    let err = refused(&mut render3d(&["--records-out", "fog3.json"]));
    assert!(err.contains("--records-out would overwrite the scene"), "{err}");
    let err = refused(&mut render3d(&["--records-out", "o/fog3_ours.json", "--out", "o"]));
    assert!(err.contains("name the same file"), "{err}");
    assert_eq!(std::fs::read_to_string(&s3).unwrap(), FOG3);
    // caches d/summary.json --out d
    std::fs::create_dir(d.path().join("c")).unwrap();
    write(&d.path().join("c"), "summary.json", FOG);
    let err = refused(volcache().current_dir(d.path()).args([
        "caches",
        "c/summary.json",
        "--out",
        "c",
        "--res",
        "4x4",
        "--quiet",
    ]));
    assert!(err.contains("would overwrite the scene"), "{err}");
    assert_eq!(std::fs::read_to_string(d.path().join("c/summary.json")).unwrap(), FOG);
}

/// Item 12: A run killed between writing and renaming left `.f.png.<pid>-0.tmp` that no
/// later run removed, and the files of one run were replaced one at a time: stale
/// temporary files of our naming are removed, and the JSON summary, written last,
/// names every file of the set with its hash (so a reader can tell a mixed set).
#[test]
fn item12_outputs_are_written_as_a_set_and_strays_are_cleaned() {
    let d = tempfile::tempdir().unwrap();
    let s = write(d.path(), "fog.json", FOG);
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    // A temporary file left by a process that no longer exists.
    let mut gone = Command::new("true").spawn().unwrap();
    let pid = gone.id();
    gone.wait().unwrap();
    let stray = out.join(format!(".f.png.{pid}-0.tmp"));
    std::fs::write(&stray, b"complete but never renamed").unwrap();
    let render = |seed: &str| {
        succeeded(
            volcache()
                .arg("field")
                .arg(&s)
                .args(["--res", "6x4", "--spp", "2", "--quiet", "--seed", seed])
                .arg("--out")
                .arg(out.join("f.png"))
                .arg("--exr")
                .arg(out.join("f.exr"))
                .arg("--json")
                .arg(out.join("f.json")),
        )
    };
    render("1");
    assert!(!stray.exists(), "the stray temporary file is still there");
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["f.exr", "f.json", "f.png"]);
    // (Checked by hand, not with `output::WrittenFile::matches`: what any reader does.)
    let matches = |f: &serde_json::Value, path: &Path| {
        let bytes = std::fs::read(path).unwrap();
        f["bytes"] == bytes.len() && f["fnv1a64"] == format!("{:016x}", volcache::core::rng::fnv1a(&bytes))
    };
    let first = json(&out.join("f.json"));
    let files = first["outputs"].as_array().cloned().unwrap_or_default();
    assert_eq!(files.len(), 2, "{first}");
    assert!(
        files.iter().all(|f| matches(f, &out.join(f["path"].as_str().unwrap()))),
        "{files:?}"
    );
    // A kill after the PNG of a second run was renamed: the old summary's hashes no
    // longer match, so a reader can tell the set is mixed.
    let old_exr = std::fs::read(out.join("f.exr")).unwrap();
    render("2");
    std::fs::write(out.join("f.exr"), old_exr).unwrap();
    std::fs::write(out.join("f.json"), serde_json::to_vec(&first).unwrap()).unwrap();
    let png = files.iter().find(|f| f["path"] == "f.png").unwrap();
    assert!(!matches(png, &out.join("f.png")), "a mixed set looked whole");
}

/// Item 13: `caches` exited 2 ("error: cancelled") on Ctrl-C where `field` and
/// `render3d` exit 130: Ctrl-C while its reference renders exits 130 and writes
/// nothing.
#[cfg(unix)]
#[test]
fn item13_caches_exits_130_on_ctrl_c() {
    let d = tempfile::tempdir().unwrap();
    let mut child = volcache()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "caches",
            "flatland_scenes/windows.json",
            "--res",
            "64x48",
            "--ref-spp",
            "1000000",
            "--quiet",
        ])
        .arg("--out")
        .arg(d.path().join("o"))
        .arg("--ref-cache")
        .arg(d.path().join("ref"))
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(800));
    // SAFETY: signalling our own child.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < Duration::from_secs(30), "caches ignored Ctrl-C");
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!d.path().join("o").exists() && !d.path().join("ref").exists());
}

/// Item 14: An OBJ vertex `v nan 0 0` silently dropped its triangles: an error naming
/// the file and the line.
#[test]
fn item14_a_bad_obj_vertex_names_its_file_and_line() {
    let d = tempfile::tempdir().unwrap();
    let obj = "# a triangle\nv 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n";
    write(d.path(), "tri.obj", obj);
    let s = write(
        d.path(),
        "mesh.json",
        &FOG3.replace(
            r#"{"quad": {"origin": [-1, -1, -1], "u": [2, 0, 0], "v": [0, 2, 0]}, "reflectance": 0.5}"#,
            r#"{"mesh": {"path": "tri.obj"}, "reflectance": 0.5}"#,
        ),
    );
    let err = refused(volcache().arg("render3d").arg(&s).arg("--quiet"));
    assert!(
        err.contains("shapes[0].mesh.path") && err.contains("tri.obj` line 3") && err.contains("`nan`"),
        "{err}"
    );
}

/// Item 15: σ_s = 10⁵, g ≈ 1 at 4×3 pixels placed 885 records for 888 query points
/// where the camera's transmittance had underflowed to 0: such points are not
/// visited, so placement makes at most a handful.
#[test]
fn item15_points_the_camera_cannot_see_get_no_records() {
    use volcache::core::metric::CacheMethod;
    use volcache::volume::cached::{CacheSettings, CachedRenderParams, RecordMemo, render_cached};
    let text = FOG3.replace(
        r#""sigma_a": 0.1, "sigma_s": 0.5, "g": 0.3"#,
        r#""sigma_a": 0, "sigma_s": 1e5, "g": 0.999"#,
    );
    let scene = volcache::volume::scene::Scene::from_json(&text, "dense", Path::new(".")).unwrap();
    let mut p = CachedRenderParams::from_scene(&scene);
    (p.image.width, p.image.height, p.image.spp) = (4, 3, 4);
    p.surface_paths = 1;
    let mut cs =
        CacheSettings::new::<volcache::core::space::D3>(CacheMethod::Ours, 1e-9, p.image.first_vertex_settings());
    (cs.probe.rays, cs.probe.steps) = (64, 2);
    let r = render_cached(
        &scene,
        &p,
        &cs,
        None,
        &mut RecordMemo::new(),
        &volcache::progress::Progress::new(),
    )
    .unwrap();
    // Transmittance vanishes 746/σ_t = 7.5·10⁻³ into the medium, a quarter of the
    // march step (scene size / 128): at most one point per camera sample.
    assert!(
        r.placement.query_points <= 4 * 3 * 4,
        "{} query points",
        r.placement.query_points
    );
    assert!(r.placement.record_count() as u64 <= r.placement.query_points);
    let img = &r.reconstruction.image;
    assert!(img.values.iter().all(|v| v.is_finite()));
}

/// Item 16: `caches` gave other RMSEs on a re-run, once its reference came from the
/// on-disk cache (f32): the store now keeps the reference at full precision, so both
/// runs measure against the same values.
#[test]
fn item16_rerun_with_the_cached_reference_gives_the_same_errors() {
    let d = tempfile::tempdir().unwrap();
    let s = write(d.path(), "fog.json", FOG);
    let caches = |out: &str| {
        succeeded(
            volcache()
                .arg("caches")
                .arg(&s)
                .args([
                    "--res",
                    "8x6",
                    "--rays",
                    "32",
                    "--steps",
                    "4",
                    "--ref-spp",
                    "16",
                    "--quiet",
                ])
                .arg("--out")
                .arg(d.path().join(out))
                .arg("--ref-cache")
                .arg(d.path().join("ref")),
        );
        json(&d.path().join(out).join("summary.json"))
    };
    let (a, b) = (caches("a"), caches("b"));
    assert_eq!(a["reference"]["from_disk"], false);
    assert_eq!(b["reference"]["from_disk"], true);
    assert_eq!(a["run"]["errors"], b["run"]["errors"]);
}
