//! `volcache figure compare3d`: the paper's 3D comparison — a converged reference,
//! ours and Jarosz 2008 at equal cache count, and path tracing in the time ours took
//! — side by side with zoomed insets, the records projected into the image, error
//! maps on one range, and the numbers (records, time, rays, RMSE of the image and of
//! its medium part) in the captions and a JSON report.

use super::common::{ProgressUi, wrote};
use super::image3d::parse_crop;
use super::render3d_cache::Cache3dArgs;
use super::setup3d::{Setup3d, Setup3dArgs, setup3d};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::core::color::Rgb;
use volcache::core::metric::CacheMethod;
use volcache::figure::image3d::{
    Image, Window, error_panel, image_panel, inset_panel, largest_difference_window, outline_window, record_size_scale,
    records_panel,
};
use volcache::figure::{Cell, compose_grid, shared_error_range, upscale_factor};
use volcache::output::{image_field, write_exr, write_json, write_png};
use volcache::study::reference3d::ReferenceInfo3d;
use volcache::study::runs3d::{Run3d, compare3d};
use volcache::volume::render::{RenderParams, camera};

#[derive(Args, Debug)]
pub struct Compare3dArgs {
    #[command(flatten)]
    pub setup: Setup3dArgs,
    #[command(flatten)]
    pub cache: Cache3dArgs,
    /// The zoomed window x0,y0,x1,y1 (default: where the two caches differ most).
    #[arg(long, value_parser = parse_crop)]
    pub inset: Option<[usize; 4]>,
    #[arg(long, default_value = "out/compare3d")]
    pub out: PathBuf,
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    params: &'a RenderParams,
    target_records: Option<usize>,
    reference: &'a ReferenceInfo3d,
    inset: Window,
    runs: &'a [Run3d],
}

fn caption(r: &Run3d) -> String {
    let cost = if r.records > 0 {
        format!(
            "{} records, {:.1} s ({:.1} s placement)",
            r.records, r.seconds, r.placement_seconds
        )
    } else {
        format!("{} spp, {:.1} s", r.spp, r.seconds)
    };
    format!(
        "{cost}\n{:.3e} rays\nRMSE {:.3e} (medium part {:.3e})",
        r.rays as f64, r.errors.rmse, r.medium_errors.rmse
    )
}

pub fn run(a: Compare3dArgs) -> anyhow::Result<ExitCode> {
    let setup = setup3d(&a.setup, a.quiet)?;
    let mut cache = a.cache.clone();
    if cache.caches.is_none() && cache.eps.is_none() {
        cache.caches = Some(200);
    }
    // Settings checked before anything runs.
    let settings = [CacheMethod::Ours, CacheMethod::Jarosz08]
        .map(|m| cache.settings(&setup.scene, &setup.image, m))
        .into_iter()
        .collect::<anyhow::Result<Vec<_>>>()?;
    let quiet = a.quiet;
    let runs = compare3d(
        &setup.scene,
        |m| settings[(m == CacheMethod::Jarosz08) as usize].clone(),
        cache.caches,
        &setup.reference,
        |label| ProgressUi::new(&format!("{} {label}", setup.stem), !quiet),
    )?;
    let Setup3d {
        scene,
        stem,
        image,
        reference,
        ref_info,
    } = setup;
    for r in &runs {
        eprintln!(
            "{:>8}: {:>5} records, {:>8.2} s, {:.3e} rays, RMSE {:.4e}, medium part {:.4e}",
            r.method, r.records, r.seconds, r.rays as f64, r.errors.rmse, r.medium_errors.rmse
        );
    }

    let (w, h) = (image.width, image.height);
    fn img(w: usize, h: usize, values: &[Rgb]) -> Image<'_> {
        Image {
            width: w,
            height: h,
            values,
        }
    }
    let exposure = scene.desc.render.exposure;
    let scale = upscale_factor(w, h);
    let inset = match a.inset {
        Some(c) => {
            anyhow::ensure!(c[2] <= w && c[3] <= h, "--inset {c:?} exceeds the image ({w}x{h})");
            c
        }
        None => largest_difference_window(
            &img(w, h, &runs[0].image.medium),
            &img(w, h, &runs[1].image.medium),
            ((w / 4).max(4), (h / 4).max(4)),
        ),
    };
    let inset_scale = (scale * w as u32 / (inset[2] - inset[0]) as u32).max(1);
    let names = [
        "reference".to_string(),
        "ours (aware, Hessian ellipsoids)".into(),
        "Jarosz 2008 (unaware, gradient balls)".into(),
        "path tracing, equal time".into(),
    ];
    let ref_caption = format!(
        "{} spp path tracing\nrel. std error {:.2}%",
        ref_info.spp,
        100.0 * ref_info.relative_std_error
    );
    let all: Vec<(&[Rgb], String)> = std::iter::once((&reference.values[..], ref_caption))
        .chain(runs.iter().map(|r| (&r.image.values[..], caption(r))))
        .collect();
    let mut row_images: Vec<Cell> = Vec::new();
    let mut row_insets: Vec<Cell> = Vec::new();
    for ((values, cap), name) in all.iter().zip(&names) {
        let mut p = image_panel(&img(w, h, values), exposure, scale);
        outline_window(&mut p, inset, scale, [255, 80, 40, 255]);
        row_images.push((Some(name.clone()), p, Some(cap.clone())));
        row_insets.push((
            None,
            inset_panel(&img(w, h, values), inset, exposure, inset_scale),
            None,
        ));
    }
    let cam = camera(&scene, w, h);
    let size = |r: &volcache::volume::cached::RecordInfo| (r.radii[0] * r.radii[1] * r.radii[2]).cbrt();
    let sizes = record_size_scale(runs[..2].iter().flat_map(|r| r.record_list.iter().map(size)));
    let row_records: Vec<Cell> = runs[..2]
        .iter()
        .zip(&names[1..3])
        .map(|(r, name)| {
            let dots: Vec<_> = r
                .record_list
                .iter()
                .map(|rec| (cam.project(rec.position - cam.position), size(rec)))
                .collect();
            (
                Some(format!("{name}: {} records", r.records)),
                records_panel(
                    &img(w, h, &r.image.values),
                    exposure,
                    scale,
                    &dots,
                    &sizes,
                    "mean radius",
                ),
                None,
            )
        })
        .collect();
    let ref_img = img(w, h, &reference.values);
    let pairs: Vec<_> = runs
        .iter()
        .map(|r| (image_field(w, h, &r.image.values), image_field(w, h, &reference.values)))
        .collect();
    let range = shared_error_range(&pairs.iter().map(|(t, r)| (t, r)).collect::<Vec<_>>(), false);
    let row_errors: Vec<Cell> = runs
        .iter()
        .zip(&names[1..])
        .map(|(r, name)| {
            (
                Some(format!("{name}: |error|")),
                error_panel(&img(w, h, &r.image.values), &ref_img, range, scale),
                None,
            )
        })
        .collect();
    let title = format!(
        "{stem}: equal cache count ({} / {} records) and equal time ({w}×{h})",
        runs[0].records, runs[1].records
    );
    let pix = compose_grid(&[row_images, row_insets, row_records, row_errors], Some(&title));
    let png = a.out.join(format!("compare3d_{stem}.png"));
    wrote(&png, write_png(&png, &pix))?;
    for r in &runs {
        let exr = a.out.join(format!("{stem}_{}.exr", r.method));
        wrote(&exr, write_exr(&exr, &image_field(w, h, &r.image.values)))?;
    }
    let report = Report {
        scene: &scene.source,
        params: &image,
        target_records: cache.caches,
        reference: &ref_info,
        inset,
        runs: &runs,
    };
    let json = a.out.join(format!("compare3d_{stem}.json"));
    wrote(&json, write_json(&json, &report))?;
    Ok(ExitCode::SUCCESS)
}
