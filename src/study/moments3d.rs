//! Records that survive camera motion (issue 15), measured: a cache placed for one
//! camera, then the camera orbits, and the new view is rendered three ways —
//! - `recompute`: a fresh cache for the new camera (what a moved camera costs today);
//! - `moments`: the first camera's records with their moments over ω_o
//!   (`pipeline::moments`), extended by placement where they leave the new view's
//!   points uncovered, each march point combining the moments for its own ω_o;
//! - `stale`: the first camera's records without moments, extended the same way,
//!   each read as stored (L_s towards the first camera).
//!
//! Each against a converged reference of the new view; a run's time is what the new
//! view costs (its placement walk, its new records' capture, its reconstruction).
//! The first camera's placement is reported apart: with moments it costs more.

use super::runs3d::method_name;
use crate::core::stats::{ImageErrors, luminance_errors};
use crate::progress::{Cancelled, Progress};
use crate::volume::cached::{
    CacheSettings, CacheView, CachedRenderParams, Placement, RecordMemo, place, place_onto, reconstruct,
};
use crate::volume::camera::Camera;
use crate::volume::orbit::orbit;
use crate::volume::render::Rendered;
use crate::volume::scene::Scene;
use glam::DVec3;
use serde::Serialize;

/// The scene seen from its camera orbited by `yaw_deg` about the look-at point
/// (same geometry, bounds and length scale, so that every view's ε, march step and
/// metric are the first view's).
pub fn orbited(scene: &Scene, yaw_deg: f64) -> Scene {
    let mut s = scene.clone();
    s.desc.camera = orbit(&scene.desc.camera, yaw_deg.to_radians(), 0.0);
    let (c, r) = (&s.desc.camera, &s.desc.render);
    let v = DVec3::from_array;
    s.camera = Camera::new(
        v(c.position),
        v(c.look_at),
        v(c.up),
        c.fov_deg,
        r.resolution[0] as usize,
        r.resolution[1] as usize,
    );
    s
}

/// The first camera's placement and its cost.
#[derive(Clone, Debug, Serialize)]
pub struct FirstView {
    pub moments: bool,
    pub records: usize,
    pub seconds: f64,
    pub rays: u64,
}

/// One way of rendering a moved camera's view.
#[derive(Clone, Debug, Serialize)]
pub struct MotionRun {
    pub yaw_deg: f64,
    /// `recompute`, `moments` or `stale`.
    pub mode: String,
    pub method: String,
    /// Records used in the new view, and how many of them it had to place.
    pub records: usize,
    pub new_records: usize,
    pub seconds: f64,
    pub placement_seconds: f64,
    pub reconstruction_seconds: f64,
    pub errors: ImageErrors,
    pub medium_errors: ImageErrors,
}

/// The first view's placements: with moments (`cs.moment_bands`) and without.
pub struct FirstViews {
    pub with_moments: (Placement, FirstView),
    pub without: (Placement, FirstView),
}

/// Place the first camera's caches (`cs` with and without its moments).
pub fn first_views(
    scene: &Scene,
    cs: &CacheSettings,
    cp: &CachedRenderParams,
    progress: &Progress,
) -> Result<FirstViews, Cancelled> {
    let one = |cs: &CacheSettings| -> Result<(Placement, FirstView), Cancelled> {
        let p = place(scene, cp, cs, &mut RecordMemo::new(), progress)?;
        let info = FirstView {
            moments: cs.moment_bands.is_some(),
            records: p.record_count(),
            seconds: p.seconds,
            rays: p.rays,
        };
        Ok((p, info))
    };
    let plain = CacheSettings {
        moment_bands: None,
        ..cs.clone()
    };
    Ok(FirstViews {
        with_moments: one(cs)?,
        without: one(&plain)?,
    })
}

/// The three renders of `moved` (a view of the first scene, [`orbited`]) against
/// its `reference`.
pub fn moved_view(
    moved: &Scene,
    yaw_deg: f64,
    cs: &CacheSettings,
    cp: &CachedRenderParams,
    first: &FirstViews,
    reference: &Rendered,
    progress: &Progress,
) -> Result<Vec<MotionRun>, Cancelled> {
    let plain = CacheSettings {
        moment_bands: None,
        ..cs.clone()
    };
    let second_order = cs.second_order;
    let mut runs = Vec::new();
    let starts: [(&str, &CacheSettings, Option<&Placement>); 3] = [
        ("recompute", &plain, None),
        ("moments", cs, Some(&first.with_moments.0)),
        ("stale", &plain, Some(&first.without.0)),
    ];
    for (mode, settings, earlier) in starts {
        let before = earlier.map_or(0, |p| p.record_count());
        let memo = &mut RecordMemo::new();
        let p = match earlier {
            Some(e) => place_onto(moved, cp, settings, e.clone(), memo, progress)?,
            None => place(moved, cp, settings, memo, progress)?,
        };
        let view = match mode {
            "stale" => CacheView::records(&p.caches[0]),
            _ => CacheView::of(&p),
        };
        let r = reconstruct(moved, cp, view, second_order, progress)?;
        let img = r.image;
        runs.push(MotionRun {
            yaw_deg,
            mode: mode.into(),
            method: method_name(cs.method).into(),
            records: p.record_count(),
            new_records: p.record_count() - before,
            seconds: p.seconds + img.seconds,
            placement_seconds: p.seconds,
            reconstruction_seconds: img.seconds,
            errors: luminance_errors(&img.values, &reference.values),
            medium_errors: luminance_errors(&img.medium, &reference.medium),
        });
    }
    Ok(runs)
}
