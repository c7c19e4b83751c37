//! The textures of a comparison result (the reference's field, each run's field and
//! error map, on one shared error range), made once per result and exposure. Apart
//! from the compare view so that the workbench, which keeps them, and the view,
//! which draws them, do not import each other.

use super::compare::CompareResult;
use super::overlay::error_image;
use super::result_id::ResultId;
use crate::figure::{FieldStyle, field_to_rgba, shared_error_range};
use crate::flatland::field::Field;
use eframe::egui::{self, TextureOptions};
use std::sync::Arc;

/// Textures of one comparison result.
pub struct CompareTextures {
    /// The result and exposure they were made for.
    key: (ResultId<CompareResult>, u64),
    /// The reference's field, then each run's.
    pub fields: Vec<egui::TextureHandle>,
    /// Each run's error map.
    pub errors: Vec<egui::TextureHandle>,
    /// The error maps' shared (log) range.
    pub error_range: (f64, f64),
}

fn texture(ctx: &egui::Context, name: &str, f: &Field, style: &FieldStyle) -> egui::TextureHandle {
    let m = field_to_rgba(f, style);
    let image = egui::ColorImage::from_rgba_unmultiplied([f.width, f.height], &m.rgba);
    ctx.load_texture(name, image, TextureOptions::NEAREST)
}

fn key_of(res: &Arc<CompareResult>, exposure: f64) -> (ResultId<CompareResult>, u64) {
    (ResultId::of(res), exposure.to_bits())
}

impl CompareTextures {
    /// The textures of `res` tone-mapped at `exposure`.
    pub fn new(ctx: &egui::Context, res: &Arc<CompareResult>, exposure: f64) -> Self {
        let tone = FieldStyle::Tonemapped { exposure };
        let mut fields = vec![texture(ctx, "compare_ref", &res.reference, &tone)];
        for r in &res.runs {
            fields.push(texture(ctx, "compare_field", &r.field, &tone));
        }
        let pairs: Vec<(&Field, &Field)> = res.runs.iter().map(|r| (&r.field, &res.reference)).collect();
        let error_range = if pairs.is_empty() {
            (1e-3, 1.0)
        } else {
            shared_error_range(&pairs, false)
        };
        let errors = res
            .runs
            .iter()
            .map(|r| {
                let image = error_image(&r.field, &res.reference, error_range);
                ctx.load_texture("compare_error", image, TextureOptions::NEAREST)
            })
            .collect();
        CompareTextures {
            key: key_of(res, exposure),
            fields,
            errors,
            error_range,
        }
    }

    /// Made for this result and exposure?
    pub fn is_for(&self, res: &Arc<CompareResult>, exposure: f64) -> bool {
        self.key == key_of(res, exposure)
    }
}
