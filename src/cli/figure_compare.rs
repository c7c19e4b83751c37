//! `volcache figure compare`: the paper's comparison at equal cache count —
//! reference, ours and Jarosz 2008 side by side with their cache distributions,
//! error maps (shared range) and the numbers in the captions.

use super::caches::{CacheArgs, check_cache_args, field_params, reference, run_method};
use super::common::{ProgressUi, load_scene, scene_stem, wrote};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use volcache::figure::{
    FieldStyle, RecordColor, RecordStyle, compose_grid, error_map_figure, field_figure, record_color_scale,
    records_figure, shared_error_range,
};
use volcache::flatland::field::FieldParams;
use volcache::output::{write_json, write_png};
use volcache::pipeline::placement::CountError;
use volcache::study::field_runs::{FieldMethod, MethodRun};
use volcache::study::reference2d::ReferenceInfo;

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// Scene JSON (default: the embedded occluder scene).
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub cache: CacheArgs,
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
}

#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    params: &'a FieldParams,
    target_records: Option<usize>,
    reference: &'a ReferenceInfo,
    runs: &'a [MethodRun],
}

fn caption(r: &MethodRun) -> String {
    let e = r.errors.unwrap_or_default();
    format!(
        "{} records, ε = {:.3e}\n{:.2} s, {:.2e} rays\nRMSE {:.3e}, relMSE {:.3e}",
        r.records,
        r.eps.unwrap_or(f64::NAN),
        r.seconds_total,
        (r.rays_placement + r.rays_reconstruction) as f64,
        e.rmse,
        e.relmse
    )
}

pub fn run(a: CompareArgs) -> anyhow::Result<ExitCode> {
    let scene = load_scene(a.scene.as_deref())?;
    let stem = scene_stem(a.scene.as_deref());
    anyhow::ensure!(
        a.cache.budget.is_none(),
        "figure compare runs both caches at one record count (--caches) or ε (--eps): --budget schedules ours alone (use caches or bench tradeoff --budgets)"
    );
    let mut cache = a.cache.clone();
    if cache.caches.is_none() && cache.eps.is_none() {
        cache.caches = Some(200);
    }
    let fp = field_params(&scene, &cache);
    check_cache_args(&cache, &fp)?;
    let (reference, ref_info) = reference(&scene, &fp, &cache)?;
    let mut runs = Vec::new();
    for method in [FieldMethod::Ours, FieldMethod::Jarosz08] {
        let ui = ProgressUi::new(&format!("{stem} {method:?}"), !cache.quiet);
        let r = run_method(&scene, &fp, method, 0, &cache, &reference, &ui.progress);
        ui.finish();
        let r = match r {
            Ok(r) => r,
            Err(CountError::Cancelled(_)) => {
                eprintln!("cancelled: no output written");
                return Ok(ExitCode::from(130));
            }
            Err(e) => anyhow::bail!("{method:?} at --caches: {e}"),
        };
        runs.push(r);
    }
    let tone = FieldStyle::Tonemapped {
        exposure: scene.desc.render.exposure,
    };
    let range = shared_error_range(&[(&runs[0].field, &reference), (&runs[1].field, &reference)], false);
    // One colour range for both distributions, so radii compare across methods.
    let both: Vec<_> = runs.iter().flat_map(MethodRun::all_records).collect();
    let mut style = RecordStyle::colored(RecordColor::ByRadius);
    style.range = record_color_scale(&both, &style).map(|s| (s.min, s.max));
    let ref_caption = format!(
        "{} spp path tracing\nrel. std error {:.2}%",
        ref_info.spp,
        100.0 * ref_info.mean_relative_std_error
    );
    let names = [
        "ours (aware, Hessian ellipses)",
        "Jarosz 2008 (unaware, gradient circles)",
    ];
    let mut row_fields = vec![(
        Some("reference".to_string()),
        field_figure(&reference, Some(&scene), &tone, None),
        Some(ref_caption),
    )];
    let mut row_records = Vec::new();
    let mut row_errors = Vec::new();
    for (r, name) in runs.iter().zip(names) {
        row_fields.push((
            Some(name.to_string()),
            field_figure(&r.field, Some(&scene), &tone, None),
            Some(caption(r)),
        ));
        row_records.push((
            Some(format!("{name}: records")),
            records_figure(None, &scene, &r.all_records(), &style, None),
            None,
        ));
        row_errors.push((
            Some(format!("{name}: |error|")),
            error_map_figure(&r.field, &reference, Some(&scene), Some(range), false, None),
            None,
        ));
    }
    let title = format!("{stem}: equal cache count comparison ({}×{})", fp.width, fp.height);
    let pix = compose_grid(&[row_fields, row_records, row_errors], Some(&title));
    let png = a.out.join(format!("compare_{stem}.png"));
    wrote(&png, write_png(&png, &pix))?;
    let report = Report {
        scene: &scene.source,
        params: &fp,
        target_records: cache.caches,
        reference: &ref_info,
        runs: &runs,
    };
    let json = a.out.join(format!("compare_{stem}.json"));
    wrote(&json, write_json(&json, &report))?;
    Ok(ExitCode::SUCCESS)
}
