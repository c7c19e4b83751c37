//! The field shown on the canvas by a radiance cache instead of path tracing (the
//! paper's method as the app's own preview): records placed over the field's
//! pixels and every pixel reconstructed from them, by the library function
//! `volcache caches` runs (`flatland::cached_field::render_cached`, settings as
//! `study::field_runs::cache_settings`), coarse (longest side 32) then at the
//! field's resolution. The records come with the field, for the records overlay.

use super::compute::FieldLevel;
use super::jobs::{Job, Notify, Priority, Reporter};
use crate::flatland::cached_field::{CacheMethod, RecordMemo, render_cached};
use crate::flatland::field::{FieldParams, RenderedField};
use crate::flatland::scene::Scene;
use crate::pipeline::placement::CountError;
use crate::study::field_runs::cache_settings;
use std::sync::Arc;

/// How the canvas' field is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldMethod {
    PathTracing,
    Cache(CacheMethod),
}

impl FieldMethod {
    pub const ALL: [FieldMethod; 3] = [
        FieldMethod::PathTracing,
        FieldMethod::Cache(CacheMethod::Ours),
        FieldMethod::Cache(CacheMethod::Jarosz08),
    ];

    pub fn label(self) -> &'static str {
        match self {
            FieldMethod::PathTracing => "path tracing",
            FieldMethod::Cache(CacheMethod::Ours) => "ours (cache)",
            FieldMethod::Cache(CacheMethod::Jarosz08) => "Jarosz 2008 (cache)",
        }
    }
}

/// The cache's parameters (`volcache caches --eps --rays --steps`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheFieldParams {
    pub eps: f64,
    pub rays: usize,
    pub steps: usize,
}

impl Default for CacheFieldParams {
    fn default() -> Self {
        // `volcache caches`' ε default; fewer rays than its 1024 for a preview.
        CacheFieldParams {
            eps: 0.05,
            rays: 256,
            steps: 12,
        }
    }
}

/// The levels of a cached field: longest side 32 when clearly coarser, then `p`.
pub fn cached_levels(p: &FieldParams) -> Vec<FieldParams> {
    let longest = p.width.max(p.height).max(1);
    let mut out = Vec::new();
    if longest >= 64 {
        let s = 32.0 / longest as f64;
        out.push(FieldParams {
            width: ((p.width as f64 * s).round() as usize).max(1),
            height: ((p.height as f64 * s).round() as usize).max(1),
            ..p.clone()
        });
    }
    out.push(p.clone());
    out
}

/// The field reconstructed from `method`'s cache, level by level (each level's
/// placement with a memo of its own: memoised light fields belong to pixels).
pub fn spawn_cached_field(
    scene: Arc<Scene>,
    params: FieldParams,
    method: CacheMethod,
    cp: CacheFieldParams,
    notify: Notify,
) -> Job<Arc<FieldLevel>> {
    Job::spawn("field", Priority::Background, notify, move |r: &Reporter<_>| {
        let levels = cached_levels(&params);
        let n = levels.len();
        for (i, lp) in levels.into_iter().enumerate() {
            r.stage(format!("{method:?} cache {}/{n}: {}×{}", i + 1, lp.width, lp.height));
            let cs = cache_settings(method, cp.eps, &lp, cp.rays, cp.steps);
            let c = match render_cached(&scene, &lp, &cs, None, &mut RecordMemo::new(), r.progress()) {
                Ok(c) => c,
                Err(CountError::Cancelled(c)) => return Err(c),
                Err(e) => unreachable!("no record-count target: {e}"),
            };
            let rays = c.placement_rays + c.reconstruction_rays;
            r.add_rays(rays);
            let pixels = c.field.values.len();
            r.send(Arc::new(FieldLevel {
                level: i + 1,
                levels: n,
                params: lp,
                rendered: RenderedField {
                    field: c.field,
                    // A cached field has no per-pixel sampling noise to report.
                    std_error: vec![0.0; pixels],
                    rays,
                    seconds: c.placement_seconds + c.reconstruction_seconds,
                },
                records: c.records.concat(),
            }));
        }
        Ok(())
    })
}
