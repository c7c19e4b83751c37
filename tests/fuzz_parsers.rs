//! Fuzz targets, one per parser (issue 14): 2D scenes, 3D scenes, OBJ meshes and
//! records files, fed mutations of the shipped files and of every input the issue
//! reported (`tests/corpus/`). Every input is either refused with an error naming
//! the file, or accepted and then gives finite results: a tiny render (2D, 3D), a
//! BVH and rays (OBJ), interpolation (records). Nothing panics or hangs. See
//! `fuzz/mod.rs` for the harness and for long runs.

mod fuzz;

use glam::DVec3;
use std::path::Path;
use volcache::core::color::{Rgb, is_finite};
use volcache::flatland::field::{FieldParams, render_field};
use volcache::flatland::scene::Scene;
use volcache::pipeline::path::estimate;
use volcache::progress::Progress;
use volcache::volume::records_file::RecordsFile;

/// Cases per target in CI (about a second each on 2 cores).
const CI_CASES: usize = 2000;

fn fits(v: Rgb) -> bool {
    is_finite(v) && v.abs().max_element() <= f32::MAX as f64
}

fn refused_naming(file: &str, msg: String) -> Result<bool, String> {
    if msg.contains(file) {
        Ok(false)
    } else {
        Err(format!("the error does not name {file}: {msg}"))
    }
}

#[test]
fn fuzz_2d_scenes() {
    let corpus = fuzz::corpus(&["flatland_scenes", "tests/corpus/2d"], ".json");
    let tally = fuzz::run("scene2d", &corpus, fuzz::cases(CI_CASES), |bytes| {
        let text = String::from_utf8_lossy(bytes);
        let scene = match Scene::from_json(&text, "fuzz.json") {
            Ok(s) => s,
            Err(e) => return refused_naming("fuzz.json: ", e.to_string()),
        };
        // The format round-trips what it accepted.
        let again = Scene::from_json(&serde_json::to_string(&scene.desc).unwrap(), "again.json")
            .map_err(|e| format!("accepted, but not once saved: {e}"))?;
        if again.desc != scene.desc {
            return Err("the saved scene differs".into());
        }
        let mut fp = FieldParams::from_scene(&scene);
        (fp.width, fp.height, fp.spp) = (2, 2, 1);
        let f = render_field(&scene, &fp, &Progress::new()).unwrap();
        if !f.field.values.iter().all(|v| fits(*v)) || !f.std_error.iter().all(|e| e.is_finite()) {
            return Err(format!("non-finite field {:?}", f.field.values));
        }
        let centre = 0.5 * (scene.domain_min + scene.domain_max);
        let e = estimate(&scene, centre, &fp.query(), &fp.settings, 1, 0, 0);
        if !fits(e.mean.total()) {
            return Err(format!("non-finite estimate {:?}", e.mean.total()));
        }
        Ok(true)
    });
    tally.assert_clean("2D scenes");
}

#[test]
fn fuzz_3d_scenes() {
    use volcache::volume::render::{RenderParams, render};
    use volcache::volume::scene::Scene as Scene3;
    let corpus = fuzz::corpus(&["scenes3d", "tests/corpus/3d"], ".json");
    // Mesh paths are relative to the scene's folder: one target per folder.
    for folder in ["scenes3d", "tests/corpus/3d"] {
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join(folder);
        let mine: Vec<_> = corpus.iter().filter(|(n, _)| n.contains(folder)).cloned().collect();
        let tally = fuzz::run("scene3d", &mine, fuzz::cases(CI_CASES) / 2, |bytes| {
            let text = String::from_utf8_lossy(bytes);
            let scene = match Scene3::from_json(&text, "fuzz.json", &base) {
                Ok(s) => s,
                Err(e) => return refused_naming("fuzz.json: ", e.to_string()),
            };
            let again = Scene3::from_json(&serde_json::to_string(&scene.desc).unwrap(), "again.json", &base)
                .map_err(|e| format!("accepted, but not once saved: {e}"))?;
            if again.desc != scene.desc {
                return Err("the saved scene differs".into());
            }
            let mut rp = RenderParams::from_scene(&scene);
            (rp.width, rp.height, rp.spp) = (2, 2, 1);
            let img = render(&scene, &rp, &Progress::new()).unwrap();
            if !img.values.iter().chain(&img.medium).all(|v| fits(*v)) {
                return Err(format!("non-finite image {:?}", img.values));
            }
            Ok(true)
        });
        tally.assert_clean(&format!("3D scenes ({folder})"));
    }
}

#[test]
fn fuzz_obj_meshes() {
    use volcache::pipeline::bvh::Geometry;
    use volcache::volume::mesh::parse_obj;
    let corpus = fuzz::corpus(&["scenes3d", "tests/corpus/obj"], ".obj");
    let tally = fuzz::run("obj", &corpus, fuzz::cases(CI_CASES), |bytes| {
        let tris = match parse_obj(bytes, "fuzz.obj", DVec3::ONE, DVec3::ZERO, 0) {
            Ok(t) => t,
            Err(e) => return refused_naming("fuzz.obj", e),
        };
        let limit = volcache::limits::MAX_COORD;
        for t in &tris {
            let ok = t
                .vertices()
                .iter()
                .all(|v| v.is_finite() && v.abs().max_element() <= limit)
                && t.normal.is_finite()
                && t.area.is_finite()
                && t.area > 0.0;
            if !ok {
                return Err(format!("accepted a bad triangle {t:?}"));
            }
        }
        // The renderer's use of them: a BVH and rays through it.
        let geometry = Geometry::new(tris);
        for d in [DVec3::X, DVec3::NEG_Y, DVec3::new(0.3, 0.5, -0.8).normalize()] {
            if let Some((t, _, u, v)) = geometry.closest_hit(DVec3::new(0.1, 0.2, 5.0), -d, 1e-9, f64::INFINITY, None)
                && !(t.is_finite() && u.is_finite() && v.is_finite())
            {
                return Err(format!("non-finite hit t {t}, u {u}, v {v}"));
            }
        }
        Ok(true)
    });
    tally.assert_clean("OBJ meshes");
}

#[test]
fn fuzz_records_files() {
    let corpus = fuzz::corpus(&["tests/corpus/records"], ".json");
    let tally = fuzz::run("records", &corpus, fuzz::cases(CI_CASES), |bytes| {
        let text = String::from_utf8_lossy(bytes);
        let cache = match RecordsFile::parse(&text, "fuzz.json") {
            Ok(r) => r.cache,
            Err(e) => return refused_naming("fuzz.json", e),
        };
        // Reconstruction's use of them: interpolation at and around each record.
        for r in cache.records() {
            for off in [DVec3::ZERO, DVec3::splat(0.01), DVec3::new(-0.2, 0.1, 0.05)] {
                for second_order in [false, true] {
                    if let Some(v) = cache.interpolate(r.position + off, second_order)
                        && !fits(v)
                    {
                        return Err(format!("non-finite interpolation {v:?}"));
                    }
                }
            }
        }
        Ok(true)
    });
    tally.assert_clean("records files");
}
