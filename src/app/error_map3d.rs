//! The main 3D view's error map: the view's image against a converged path-traced
//! reference of the same scene, camera and size — the image `volcache render3d
//! SCENE --method pt --res W×H --spp REF --seed S` writes, S the reference seed of
//! the view's seed, as `figure compare3d` makes its reference — rendered on demand
//! on a background job, with the errors the compare view reports (RMSE of
//! luminance, of the whole image or of its medium part).

use super::jobs::{Job, Notify, Priority, Reporter};
use super::render3d_job::View3dParams;
use crate::core::stats::{ImageErrors, luminance_errors};
use crate::figure::error_map::error_field;
use crate::figure::field_figure::{FieldStyle, field_to_rgba};
use crate::output::image_field;
use crate::volume::render::{RenderParams, Rendered, render};
use crate::volume::scene::Scene;
use std::sync::Arc;

/// Reference samples per pixel the view offers first: at the view's default size
/// a few seconds of path tracing, converged well below the caches' errors there.
pub const DEFAULT_REFERENCE_SPP: u32 = 256;

/// What a reference depends on: the scene as edited (its revision changes with
/// every edit and camera move), the view's full size and seed, and the samples.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceKey {
    pub revision: u64,
    pub params: RenderParams,
}

/// The reference's image: the view's last level's size, `spp` samples, the
/// reference seed (never the seed of the images it judges).
pub fn reference_params(scene: &Scene, view: &View3dParams, spp: u32) -> RenderParams {
    crate::study::reference3d::reference_params(&view.image(scene, 1.0, 1), spp)
}

/// Render the reference, sending it once done.
pub fn spawn_reference3d(scene: Arc<Scene>, params: RenderParams, notify: Notify) -> Job<Arc<Rendered>> {
    Job::spawn("3D reference", Priority::Background, notify, move |r: &Reporter<_>| {
        r.stage(format!("reference: {} spp", params.spp));
        let img = render(&scene, &params, r.progress())?;
        r.send(Arc::new(img));
        Ok(())
    })
}

/// An image's error map against its reference.
pub struct ErrorMap {
    /// |L − L_ref| of luminance per pixel, log false colour, RGBA at the image's size.
    pub rgba: Vec<u8>,
    /// The colour scale's range (absolute luminance error).
    pub range: (f64, f64),
    pub errors: ImageErrors,
}

/// The error map of `image` against `reference` (their medium parts if
/// `medium_only`), or None when their sizes differ (a coarse level of the view).
pub fn error_map<'a>(image: &'a Rendered, reference: &'a Rendered, medium_only: bool) -> Option<ErrorMap> {
    let (w, h) = (image.width, image.height);
    if (w, h) != (reference.width, reference.height) {
        return None;
    }
    let part = |r: &'a Rendered| if medium_only { &r.medium } else { &r.values };
    let (test, refr) = (part(image), part(reference));
    let e = error_field(&image_field(w, h, test), &image_field(w, h, refr), false);
    let mapped = field_to_rgba(&e, &FieldStyle::FalseColor { log: true, range: None });
    let range = mapped.scale.as_ref().map_or((0.0, 0.0), |s| (s.min, s.max));
    Some(ErrorMap {
        rgba: mapped.rgba,
        range,
        errors: luminance_errors(test, refr),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::color::Rgb;

    fn rendered(w: usize, h: usize, v: f64) -> Rendered {
        Rendered {
            width: w,
            height: h,
            values: vec![Rgb::splat(v); w * h],
            medium: vec![Rgb::splat(0.5 * v); w * h],
            std_error: vec![0.0; w * h],
            spp: 1,
            rays: 0,
            seconds: 0.0,
        }
    }

    #[test]
    fn the_map_measures_the_chosen_part_and_refuses_other_sizes() {
        let (a, b) = (rendered(4, 3, 2.0), rendered(4, 3, 1.0));
        let whole = error_map(&a, &b, false).unwrap();
        assert_eq!(whole.rgba.len(), 4 * 3 * 4);
        assert!((whole.errors.rmse - 1.0).abs() < 1e-12, "{}", whole.errors.rmse);
        let medium = error_map(&a, &b, true).unwrap();
        assert!((medium.errors.rmse - 0.5).abs() < 1e-12, "{}", medium.errors.rmse);
        assert!(error_map(&a, &rendered(2, 2, 1.0), false).is_none());
    }
}
