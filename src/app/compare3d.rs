//! The 3D compare view: the paper's comparison on the current scene and camera —
//! a converged path-traced reference, ours and Jarosz 2008 at equal record count,
//! path tracing in the time ours took — by the library protocol `volcache figure
//! compare3d` runs ([`study::runs3d::compare3d`]), with the images, the error maps
//! on one range and the numbers, and the command that reproduces them.

use super::jobs::{Job, Notify, Priority, Reporter};
use super::render3d_job::cache_settings;
use crate::figure::image3d::{Image, error_panel};
use crate::figure::{colormap::tonemap, shared_error_range};
use crate::output::image_field;
use crate::study::reference3d::reference_params;
use crate::study::runs3d::{Run3d, compare3d, comparison_image};
use crate::volume::render::{RenderParams, Rendered, render};
use crate::volume::scene::Scene;
use eframe::egui;
use std::sync::Arc;

/// What the comparison runs (`figure compare3d`'s options of the same names).
#[derive(Clone, Debug, PartialEq)]
pub struct Compare3dParams {
    /// Equal cache count (`--caches`).
    pub caches: usize,
    /// The image (`--res`): width, the height follows the scene's aspect.
    pub width: usize,
    /// Camera samples per pixel of the caches (`--spp`).
    pub spp: u32,
    /// Samples per pixel of the reference (`--ref-spp`).
    pub ref_spp: u32,
    pub rays: usize,
    pub steps: usize,
    pub seed: u64,
}

impl Default for Compare3dParams {
    fn default() -> Self {
        Compare3dParams {
            caches: 100,
            width: 96,
            spp: 1,
            ref_spp: 1024,
            rays: 1024,
            steps: 24,
            seed: 1,
        }
    }
}

impl Compare3dParams {
    /// The compared image.
    pub fn image(&self, scene: &Scene) -> RenderParams {
        let [w, h] = scene.desc.render.resolution;
        let height = ((self.width as f64 * h as f64 / w as f64).round() as usize).max(1);
        comparison_image(scene, Some([self.width.max(1), height]), self.spp.max(1), self.seed)
    }

    /// `volcache figure compare3d …` with these parameters on `scene_file`.
    pub fn command(&self, scene: &Scene, scene_file: &str) -> String {
        let im = self.image(scene);
        format!(
            "volcache figure compare3d {scene_file} --res {}x{} --spp {} --seed {} --ref-spp {} --caches {} --rays {} --steps {}",
            im.width, im.height, self.spp, self.seed, self.ref_spp, self.caches, self.rays, self.steps
        )
    }
}

/// A finished comparison, or why the record count could not be reached.
pub type Compare3dOutcome = Result<Compare3dResult, String>;

pub struct Compare3dResult {
    pub params: Compare3dParams,
    pub reference: Rendered,
    /// Ours, Jarosz 2008, path tracing at equal time.
    pub runs: Vec<Run3d>,
}

/// Reference, then the comparison; a count no ε reaches is reported, not hidden.
pub fn spawn_compare3d(scene: Arc<Scene>, params: Compare3dParams, notify: Notify) -> Job<Arc<Compare3dOutcome>> {
    Job::spawn("3D compare", Priority::Background, notify, move |r: &Reporter<_>| {
        let image = params.image(&scene);
        let ref_params = reference_params(&image, params.ref_spp);
        r.stage(format!("reference: {} spp", ref_params.spp));
        let reference = render(&scene, &ref_params, r.progress())?;
        let settings = |m| cache_settings(&scene, image.clone(), m, None, params.rays, params.steps);
        let progress = |label: &str| {
            r.stage(format!("compare: {label}"));
            r.progress()
        };
        let out = match compare3d(&scene, settings, Some(params.caches), &reference, progress) {
            Ok(runs) => Ok(Compare3dResult {
                params: params.clone(),
                reference,
                runs,
            }),
            Err(crate::pipeline::placement::CountError::Cancelled(c)) => return Err(c),
            Err(e) => Err(e.to_string()),
        };
        r.send(Arc::new(out));
        Ok(())
    })
}

/// The tone-mapped image (exposure from the reference) and the error maps of a
/// result, as egui images: reference, ours, Jarosz 2008, path tracing; then the
/// three errors.
pub fn compare_images(res: &Compare3dResult, exposure: f64) -> Vec<egui::ColorImage> {
    let (w, h) = (res.reference.width, res.reference.height);
    let tone = |values: &[crate::core::color::Rgb]| {
        let rgba: Vec<u8> = values
            .iter()
            .flat_map(|v| {
                let [r, g, b] = tonemap(*v, exposure);
                [r, g, b, 255]
            })
            .collect();
        egui::ColorImage::from_rgba_unmultiplied([w, h], &rgba)
    };
    let mut out = vec![tone(&res.reference.values)];
    out.extend(res.runs.iter().map(|r| tone(&r.image.values)));
    let refr = image_field(w, h, &res.reference.values);
    let tests: Vec<_> = res.runs.iter().map(|r| image_field(w, h, &r.image.values)).collect();
    let pairs: Vec<_> = tests.iter().map(|t| (t, &refr)).collect();
    let range = shared_error_range(&pairs, false);
    let img = |values| Image {
        width: w,
        height: h,
        values,
    };
    for r in &res.runs {
        let pm = error_panel(&img(&r.image.values), &img(&res.reference.values), range, 1);
        out.push(egui::ColorImage::from_rgba_premultiplied(
            [pm.width() as usize, pm.height() as usize],
            pm.data(),
        ));
    }
    out
}

/// A run's caption: cost and errors.
pub fn caption(r: &Run3d) -> String {
    let cost = if r.records > 0 {
        format!("{} records, {:.2} s", r.records, r.seconds)
    } else {
        format!("{} spp, {:.2} s", r.spp, r.seconds)
    };
    format!(
        "{cost}\nRMSE {:.3e}\nmedium {:.3e}",
        r.errors.rmse, r.medium_errors.rmse
    )
}
