//! `volcache render3d` and `merge3d` end to end: outputs and summary, cache methods
//! with tiles sharing a records file, clear errors for bad options, crops, scenes and
//! records files, and Ctrl-C (exit 130, nothing written).

mod room3d;

use std::path::Path;
use std::process::Command;

fn volcache() -> Command {
    Command::new(env!("CARGO_BIN_EXE_volcache"))
}

/// Runs `cmd`, asserts that it fails and returns its error output.
fn failure(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{cmd:?} succeeded: {err}");
    err
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

/// `render3d scenes3d/deep_lamp.json --method METHOD ARGS --quiet --out DIR/SUB`:
/// whether it succeeded, its stderr and its JSON summary (if written).
fn deep_lamp(dir: &Path, method: &str, args: &[&str], sub: &str) -> (bool, String, Option<serde_json::Value>) {
    let out_dir = dir.join(sub);
    let out = volcache()
        .args(["render3d", "scenes3d/deep_lamp.json", "--method", method, "--quiet"])
        .args(args)
        .arg("--out")
        .arg(&out_dir)
        .output()
        .unwrap();
    let summary = std::fs::read_to_string(out_dir.join(format!("deep_lamp_{method}.json")))
        .ok()
        .map(|t| serde_json::from_str::<serde_json::Value>(&t).unwrap());
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).to_string(),
        summary,
    )
}

/// `--no-aimed-legs` leaves out the legs aimed near point lamps (to measure what
/// they gain): the summary says so, and the paths cast fewer rays.
#[test]
fn aimed_legs_can_be_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], sub: &str| {
        let args = [&["--res", "16x12", "--spp", "4", "--seed", "2"][..], extra].concat();
        let (ok, err, summary) = deep_lamp(dir.path(), "pt", &args, sub);
        assert!(ok, "{err}");
        summary.unwrap()
    };
    let (aimed, plain) = (run(&[], "aimed"), run(&["--no-aimed-legs"], "plain"));
    assert_eq!(aimed["params"]["settings"]["aimed_legs"], true);
    assert_eq!(plain["params"]["settings"]["aimed_legs"], false);
    let rays = |v: &serde_json::Value| v["rays"].as_u64().unwrap();
    assert!(rays(&aimed) > rays(&plain), "{} vs {} rays", rays(&aimed), rays(&plain));
}

/// `--lamp-reach K` limits records' radii to K × their distance to the nearest
/// point light, `VOLUME_LAMP_REACH` by default in 3D; `--no-lamp-reach` lets the
/// metric alone decide (to measure what the reach gains). The summary records the
/// setting, and a reach out of range is refused by name.
#[test]
fn lamp_reach_is_set_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], sub: &str| {
        let small = [
            "--res", "8x6", "--spp", "1", "--rays", "32", "--steps", "4", "--seed", "2",
        ];
        deep_lamp(dir.path(), "ours", &[&small[..], extra].concat(), sub)
    };
    let reach = |v: &Option<serde_json::Value>| v.as_ref().unwrap()["cache"]["settings"]["lamp_reach"].clone();
    let (ok, err, default) = run(&[], "default");
    assert!(ok, "{err}");
    assert_eq!(reach(&default), volcache::pipeline::budget::VOLUME_LAMP_REACH);
    let (ok, err, half) = run(&["--lamp-reach", "0.5"], "half");
    assert!(ok, "{err}");
    assert_eq!(reach(&half), 0.5);
    let (ok, err, free) = run(&["--no-lamp-reach"], "free");
    assert!(ok, "{err}");
    assert!(reach(&free).is_null());
    let (ok, err, none) = run(&["--lamp-reach", "0"], "zero");
    assert!(!ok && none.is_none());
    assert!(err.contains("--lamp-reach"), "{err}");
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

/// A cache method honours a time budget too: records first, then camera samples
/// beyond the placed ones while the budget lasts (points no record covers are path
/// traced and counted).
#[test]
fn a_cached_render_spends_its_time_budget_on_camera_samples() {
    let dir = tempfile::tempdir().unwrap();
    let out = volcache()
        .args([
            "render3d",
            "scenes3d/fog_box.json",
            "--method",
            "ours",
            "--res",
            "16x12",
            "--rays",
            "256",
            "--steps",
            "8",
            "--spp",
            "2",
            "--surface-cache",
            "ours",
            "--time-budget",
            "6",
            "--quiet",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("fog_box_ours.json")).unwrap()).unwrap();
    let (spp, secs) = (json["spp"].as_u64().unwrap(), json["seconds"].as_f64().unwrap());
    let cache = &json["cache"];
    assert!(spp > 2, "only the placed camera samples: {spp}");
    assert!(secs < 6.0 * 1.5, "{spp} spp in {secs} s");
    assert!(cache["surfaces"]["records"].as_u64().unwrap() > 0);
    // The records' own noise, which the image's standard error does not show.
    let noise = cache["records_relative_noise"].as_f64().unwrap();
    assert!(noise > 0.0 && noise.is_finite(), "{noise}");
    let placed = cache["placement_seconds"].as_f64().unwrap() + cache["surfaces"]["seconds"].as_f64().unwrap();
    assert!(placed < secs, "records {placed} s of {secs} s");
}

/// A budget too short for the records is not honoured silently: the run says it
/// was exceeded, by what, and what would fit.
#[test]
fn an_exceeded_time_budget_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let out = volcache()
        .args([
            "render3d",
            "scenes3d/fog_box.json",
            "--method",
            "ours",
            "--res",
            "16x12",
        ])
        .args([
            "--rays",
            "256",
            "--steps",
            "8",
            "--time-budget",
            "0.001",
            "--quiet",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("--time-budget 0.001 s exceeded") && err.contains("the records took") && err.contains("--eps"),
        "{err}"
    );
}

/// `--place-spp`: the records are placed over the first camera samples of each
/// pixel only, the image takes all of them; the summary says how many were
/// placed over, and the placement walked about that share of the march points.
#[test]
fn records_can_be_placed_over_fewer_camera_samples_than_the_image_takes() {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], out: &str| -> serde_json::Value {
        let o = volcache()
            .args([
                "render3d",
                "scenes3d/fog_box.json",
                "--method",
                "ours",
                "--res",
                "16x12",
            ])
            .args(["--rays", "128", "--steps", "6", "--spp", "8", "--quiet", "--out"])
            .arg(dir.path().join(out))
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_str(&std::fs::read_to_string(dir.path().join(out).join("fog_box_ours.json")).unwrap()).unwrap()
    };
    let all = run(&[], "all");
    let two = run(&["--place-spp", "2"], "two");
    assert_eq!(
        (all["cache"]["placed_spp"].as_u64(), two["cache"]["placed_spp"].as_u64()),
        (Some(8), Some(2))
    );
    assert_eq!(two["spp"], 8);
    let points = |j: &serde_json::Value| j["cache"]["query_points"].as_f64().unwrap();
    let share = points(&two) / points(&all);
    assert!(
        (0.2..0.3).contains(&share),
        "placed over 2 of 8 samples: {share:.3} of the march points"
    );
    let mean = |j: &serde_json::Value| j["mean_luminance"].as_f64().unwrap();
    let (a, b) = (mean(&all), mean(&two));
    println!(
        "mean luminance {a} placed over all, {b} over two; uncovered {}",
        two["cache"]["uncovered"]
    );
    assert!(a.is_finite() && b.is_finite() && (b / a - 1.0).abs() < 0.01, "{a} {b}");
    // The samples beyond the placed ones split adaptively: the summary says how,
    // and as many are taken as cost what the six fine ones would have.
    let split = run(&["--place-spp", "2", "--image-split", "adaptive"], "split");
    let chosen = &split["cache"]["image_split"];
    let c = mean(&split);
    println!("adaptive split {chosen}: {} samples, mean luminance {c}", split["spp"]);
    assert!(chosen["march_factor"].as_u64().is_some() && split["spp"].as_u64() >= Some(8));
    // (Its camera samples are others than the fixed renders', whose mean moves by
    // 7% between 8 and 16 samples here: unbiasedness is checked in
    // tests/image_split_3d.rs against the render's own noise.)
    assert!(c.is_finite() && c > 0.0, "{c}");
    // One camera sample in four beyond the placed ones marches when asked; the
    // summary says so and the adaptive split's table predicts the shares.
    let share = run(&["--place-spp", "2", "--image-march-every", "4"], "share");
    assert_eq!(
        share["cache"]["image_march_every"].as_u64(),
        Some(4),
        "{}",
        share["cache"]
    );
    assert!(mean(&share).is_finite() && mean(&share) > 0.0);
    let table = split["cache"]["image_split_candidates"].as_array().unwrap();
    assert!(table.iter().any(|c| c["march_every"].as_u64() == Some(4)), "{table:?}");
    // `auto`: the adaptive split chooses the share too, and the summary says
    // which (the share asked for stays unset).
    let auto = run(&["--place-spp", "2", "--image-march-every", "auto"], "auto");
    let chosen = &auto["cache"]["image_split"];
    assert!(chosen["march_every"].as_u64().is_some(), "{}", auto["cache"]);
    assert!(auto["cache"].get("image_march_every").is_none(), "{}", auto["cache"]);
    assert!(mean(&auto).is_finite() && mean(&auto) > 0.0);
}

#[test]
fn bad_input_is_a_clear_error() {
    let fails_with = |args: &[&str], want: &str| {
        let dir = tempfile::tempdir().unwrap();
        let out = volcache().args(args).arg("--out").arg(dir.path()).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(want), "{args:?}: {err}");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            0,
            "{args:?} wrote output"
        );
    };
    let s = "scenes3d/fog_box.json";
    fails_with(&["render3d", s, "--res", "10x10", "--crop", "0,0,11,5"], "--crop");
    fails_with(&["render3d", "does/not/exist.json"], "does/not/exist.json");
    fails_with(
        &["render3d", s, "--method", "ours", "--time-budget", "0"],
        "--time-budget",
    );
    fails_with(&["render3d", s, "--method", "ours", "--rays", "2"], "--rays");
    fails_with(
        &["render3d", s, "--method", "ours", "--surface-eps", "0.1"],
        "--surface-eps",
    );
    fails_with(
        &["render3d", s, "--method", "ours", "--march-step", "0"],
        "--march-step",
    );
    fails_with(
        &["render3d", s, "--method", "ours", "--image-march-step", "0.5"],
        "--time-budget",
    );
    fails_with(
        &[
            "render3d",
            s,
            "--method",
            "ours",
            "--time-budget",
            "5",
            "--image-march-step",
            "0",
        ],
        "--image-march-step",
    );
    fails_with(&["render3d", s, "--method", "ours", "--place-spp", "0"], "--place-spp");
    fails_with(
        &["render3d", s, "--method", "ours", "--spp", "4", "--place-spp", "8"],
        "more than the image's 4",
    );
    fails_with(
        &[
            "render3d",
            s,
            "--method",
            "ours",
            "--time-budget",
            "5",
            "--spp",
            "2",
            "--place-spp",
            "1",
        ],
        "not both",
    );
    // An adaptive split needs camera samples beyond the placed ones, and chooses
    // the march step itself.
    fails_with(
        &["render3d", s, "--method", "ours", "--image-split", "adaptive"],
        "--image-split adaptive splits",
    );
    fails_with(
        &[
            "render3d",
            s,
            "--method",
            "ours",
            "--time-budget",
            "5",
            "--image-split",
            "adaptive",
            "--image-march-step",
            "0.1",
        ],
        "--image-split adaptive chooses",
    );
    // A march share needs samples beyond the placed ones, a count in range, and
    // is not chosen beside an adaptive split.
    fails_with(
        &["render3d", s, "--method", "ours", "--image-march-every", "4"],
        "--image-march-every sets",
    );
    fails_with(
        &[
            "render3d",
            s,
            "--method",
            "ours",
            "--place-spp",
            "1",
            "--image-march-every",
            "0",
        ],
        "--image-march-every must be",
    );
    fails_with(
        &[
            "render3d",
            s,
            "--method",
            "ours",
            "--place-spp",
            "1",
            "--image-split",
            "adaptive",
            "--image-march-every",
            "2",
        ],
        "--image-split adaptive chooses",
    );
    // `auto` is the adaptive split's choice: not beside a fixed split or march
    // step, and only with samples beyond the placed ones; a share is a count or
    // `auto`.
    let ours_placed = ["render3d", s, "--method", "ours", "--place-spp", "1"];
    for (extra, want) in [
        (
            &["--image-march-every", "auto", "--image-split", "fixed"][..],
            "--image-march-every auto is chosen",
        ),
        (
            &["--image-march-every", "auto", "--image-march-step", "0.1"][..],
            "--image-march-every auto is chosen",
        ),
        (
            &["--image-march-every", "often"][..],
            "expected a whole number or `auto`",
        ),
        (
            &["--image-march-every", "auto", "--spp", "1"][..],
            "--image-march-every auto splits",
        ),
    ] {
        fails_with(&[&ours_placed[..], extra].concat(), want);
    }
    fails_with(&["render3d", s, "--method", "ours", "--eps", "nan"], "--eps");
    fails_with(
        &["render3d", s, "--method", "ours", "--direct-samples", "0"],
        "--direct-samples",
    );
    fails_with(
        &["render3d", s, "--method", "ours", "--edge-reach", "nan"],
        "--edge-reach",
    );
    fails_with(&["render3d", s, "--res", "10x4", "--tile", "0/5"], "at most 4 tiles");
    fails_with(&["render3d", s, "--tile", "3/3"], "0 <= i < n");
    fails_with(
        &["render3d", s, "--method", "ours", "--records-in", "missing.json"],
        "missing.json",
    );
}

/// Renders the `n` tiles of a cached render with `run` (its extra options) from
/// `d/records.json` into `d/tiles`, merges them into `d/merged` and asserts that
/// the image and its medium part equal `d/full`'s byte for byte. Returns the
/// tiles' summaries.
fn tiles_merge_into_the_full_render(d: &std::path::Path, stem: &str, n: usize, run: impl Fn(&[&str])) -> Vec<String> {
    let path = |p: &str| d.join(p).display().to_string();
    for i in 0..n {
        let tile = format!("{i}/{n}");
        run(&[
            "--records-in",
            &path("records.json"),
            "--tile",
            &tile,
            "--out",
            &path("tiles"),
        ]);
    }
    let tiles: Vec<String> = (0..n)
        .map(|i| path(&format!("tiles/{stem}_tile{i}of{n}.json")))
        .collect();
    let out = volcache()
        .arg("merge3d")
        .args(&tiles)
        .args(["--out", &path("merged")])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for f in [format!("{stem}.exr"), format!("{stem}_medium.exr")] {
        let (a, b) = (
            std::fs::read(d.join("full").join(&f)).unwrap(),
            std::fs::read(d.join("merged").join(&f)).unwrap(),
        );
        assert!(a == b, "{f}: merged tiles differ from the full render");
    }
    tiles
}

/// A cache method's render split into tiles, each reconstructing from the records a
/// full render placed (`--records-out`), merges into the full render bit for bit;
/// records placed for another image are refused, and the summary has the costs.
#[test]
fn tiles_sharing_records_merge_into_the_full_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = [
        "render3d",
        "scenes3d/fog_box.json",
        "--method",
        "ours",
        "--spp",
        "2",
        "--rays",
        "256",
        "--steps",
        "8",
        "--quiet",
    ];
    let run = |extra: &[&str]| {
        let out = volcache().args(base).args(extra).output().unwrap();
        assert!(
            out.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let path = |p: &str| d.join(p).display().to_string();
    // A fixed ε: the equal-count search (tested on the staircase and by `figure
    // compare3d`) took 75 of this test's 80 s.
    run(&[
        "--eps",
        "0.1",
        "--records-out",
        &path("records.json"),
        "--out",
        &path("full"),
    ]);
    let tiles = tiles_merge_into_the_full_render(d, "fog_box_ours", 3, run);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("full/fog_box_ours.json")).unwrap()).unwrap();
    let records = json["cache"]["records"].as_u64().unwrap();
    assert!(records > 10, "{records} records");
    assert_eq!(json["cache"]["uncovered"], 0);
    assert!(json["cache"]["placement_seconds"].as_f64().unwrap() > 0.0);
    // Two tiles are not the image; the same tile twice covers rows twice.
    let err = failure(
        volcache()
            .arg("merge3d")
            .args(&tiles[..2])
            .args(["--out", &path("bad")]),
    );
    assert!(err.contains("exactly once"), "{err}");
    // Records placed for 24x18 cannot serve a 24x20 render.
    let with_records = |res: &str, records: &str| {
        failure(
            volcache()
                .args(base)
                .args(["--res", res, "--records-in", &path(records), "--out", &path("bad")]),
        )
    };
    let err = with_records("24x20", "records.json");
    assert!(err.contains("records.json") && err.contains("24x20"), "{err}");
    // A damaged records file names itself and the JSON path.
    std::fs::write(d.join("broken.json"), "{\"format\": 3}").unwrap();
    let err = with_records("24x18", "broken.json");
    assert!(err.contains("broken.json") && err.contains("format"), "{err}");
    // A file without surface records cannot serve a render with a surface cache.
    let err = failure(volcache().args(base).args([
        "--surface-cache",
        "ours",
        "--records-in",
        &path("records.json"),
        "--out",
        &path("bad"),
    ]));
    assert!(
        err.contains("records.json") && err.contains("no surface records"),
        "{err}"
    );
    // Records that hold the straight light cannot have it sampled per point too.
    let err = failure(volcache().args(base).args([
        "--direct-samples",
        "4",
        "--records-in",
        &path("records.json"),
        "--out",
        &path("bad"),
    ]));
    assert!(
        err.contains("records.json") && err.contains("--direct-samples"),
        "{err}"
    );
    assert!(!d.join("bad").exists());
}

/// With a surface cache, the records file carries the surface records too: tiles
/// reconstructing from it merge into the full render bit for bit, the merge counts
/// both placements once, and another --surface-eps than the file's is refused.
#[test]
fn tiles_share_the_surface_cache_through_the_records_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let path = |p: &str| d.join(p).display().to_string();
    std::fs::write(d.join("room.json"), room3d::ROOM).unwrap();
    let scene = path("room.json");
    let render = |extra: &[&str]| {
        let mut cmd = volcache();
        cmd.args([
            "render3d",
            &scene,
            "--method",
            "ours",
            "--res",
            "20x15",
            "--spp",
            "2",
            "--rays",
            "128",
            "--steps",
            "4",
            "--surface-cache",
            "ours",
            "--quiet",
        ])
        .args(extra);
        cmd
    };
    let ok = |extra: &[&str]| {
        let out = render(extra).output().unwrap();
        assert!(
            out.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    ok(&["--records-out", &path("records.json"), "--out", &path("full")]);
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("records.json")).unwrap()).unwrap();
    let surface_records = file["surfaces"]["records"].as_array().unwrap().len();
    assert!(surface_records > 3, "{surface_records} surface records");
    tiles_merge_into_the_full_render(d, "room_ours", 2, ok);
    let read =
        |f: &str| -> serde_json::Value { serde_json::from_str(&std::fs::read_to_string(d.join(f)).unwrap()).unwrap() };
    let (full, merged) = (read("full/room_ours.json"), read("merged/room_ours.json"));
    assert_eq!(full["cache"]["surfaces"]["records"], surface_records);
    assert_eq!(merged["cache"]["surfaces"]["records"], surface_records);
    // The merge's time holds both placements once, beside the tiles' reconstructions.
    let placed =
        full["cache"]["placement_seconds"].as_f64().unwrap() + full["cache"]["surfaces"]["seconds"].as_f64().unwrap();
    assert!(merged["seconds"].as_f64().unwrap() > placed, "{merged}");
    let err = failure(&mut render(&[
        "--records-in",
        &path("records.json"),
        "--surface-eps",
        "0.5",
        "--out",
        &path("bad"),
    ]));
    assert!(err.contains("records.json") && err.contains("--surface-eps"), "{err}");
    assert!(!d.join("bad").exists());
}

#[cfg(unix)]
#[test]
fn interrupt_writes_nothing() {
    for method in ["pt", "ours"] {
        let dir = tempfile::tempdir().unwrap();
        let records = dir.path().join("records.json");
        let mut cmd = volcache();
        cmd.args([
            "render3d",
            "scenes3d/staircase.json",
            "--method",
            method,
            "--res",
            "400x300",
        ]);
        if method == "pt" {
            cmd.args(["--spp", "100000"]);
        } else {
            cmd.arg("--records-out").arg(&records);
        }
        let mut child = cmd.args(["--quiet", "--out"]).arg(dir.path()).spawn().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(800));
        let killed = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        assert_eq!(child.wait().unwrap().code(), Some(130), "{method}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "{method}");
    }
}

/// `figure compare3d` and `bench tradeoff3d` on a tiny fog box: every output is
/// written, the numbers are finite, the second command reuses the first's reference
/// from disk, and the sweep has one run per count and per sample count.
#[test]
fn compare3d_and_tradeoff3d_write_their_reports() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let common = [
        "scenes3d/fog_box.json",
        "--res",
        "24x18",
        "--spp",
        "1",
        "--ref-spp",
        "32",
        "--rays",
        "256",
        "--steps",
        "4",
        "--quiet",
    ];
    let run = |args: &[&str]| {
        let out = volcache()
            .args(args)
            .args(common)
            .arg("--ref-cache")
            .arg(d.join("ref"))
            .arg("--out")
            .arg(d)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    };
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join(name)).unwrap()).unwrap()
    };
    let finite = |v: &serde_json::Value| v.as_f64().is_some_and(f64::is_finite);

    run(&["figure", "compare3d", "--caches", "24"]);
    for f in [
        "compare3d_fog_box.png",
        "fog_box_ours.exr",
        "fog_box_jarosz08.exr",
        "fog_box_pt.exr",
    ] {
        assert!(d.join(f).is_file(), "{f}");
    }
    let c = read("compare3d_fog_box.json");
    assert_eq!(c["reference"]["from_disk"], false);
    let methods: Vec<&str> = c["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert_eq!(methods, ["ours", "jarosz08", "pt"]);
    for r in c["runs"].as_array().unwrap() {
        assert!(
            finite(&r["errors"]["rmse"]) && finite(&r["medium_errors"]["rmse"]),
            "{r}"
        );
    }

    run(&["bench", "tradeoff3d", "--counts", "24,48", "--spps", "1,4"]);
    assert!(d.join("tradeoff3d_fog_box.png").is_file());
    let t = read("tradeoff3d_fog_box.json");
    assert_eq!(t["reference"]["from_disk"], true, "the reference is reused");
    let runs = t["runs"].as_array().unwrap();
    let count = |m: &str| runs.iter().filter(|r| r["method"] == m).count();
    assert_eq!((count("ours"), count("jarosz08"), count("pt")), (2, 2, 2));
    assert!(
        runs.iter()
            .all(|r| finite(&r["seconds"]) && finite(&r["medium_errors"]["rmse"]))
    );
    for s in t["speedups"].as_array().unwrap() {
        assert!(finite(&s["speedup"]) && s["speedup"].as_f64().unwrap() > 0.0, "{s}");
    }
    // The time-to-error table: 3%, 1%, 0.3% of the image and of its medium part,
    // each judged against the reference's noise and timed per method when above it.
    let targets = t["targets"].as_array().unwrap();
    let of = |r: &serde_json::Value| (r["of"].as_str().unwrap().to_string(), r["relative"].as_f64().unwrap());
    let rows: Vec<(String, f64)> = targets.iter().map(of).collect();
    let expected: Vec<(String, f64)> = ["image", "medium"]
        .iter()
        .flat_map(|o| [0.03, 0.01, 0.003].map(|r| (o.to_string(), r)))
        .collect();
    assert_eq!(rows, expected);
    for r in targets {
        let noise = r["reference_noise"].as_f64().unwrap();
        assert!(noise.is_finite() && noise > 0.0, "{r}");
        let measurable = r["error"].as_f64().unwrap() > noise;
        assert_eq!(r["measurable"], measurable, "{r}");
        assert_eq!(
            r["times"].as_array().unwrap().len(),
            if measurable { 3 } else { 0 },
            "{r}"
        );
    }
}
