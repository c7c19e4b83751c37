//! What the app computes in the background, through the same library calls as the
//! command line: `render_field` (as `volcache field`), aware and unaware on one
//! light field ([`aware_and_unaware`], as `volcache probe --method aware|unaware`,
//! same seed and item), the finite-difference reference in batches
//! ([`reference_batch`]), and a grid of light fields with the points and seeds of
//! `volcache figure gradients` ([`grid_points`], [`point_seed`]).

use super::jobs::{Job, Notify, Priority, Reporter};
use crate::core::space::D2;
use crate::flatland::field::{FieldParams, RenderedField, render_field};
use crate::flatland::scene::Scene;
use crate::pipeline::derivatives::{self, AwareSettings, ReferenceSettings};
use crate::pipeline::path::Settings;
use crate::pipeline::probe::{Outgoing, ProbeSettings};
use crate::pipeline::world::World;
use crate::study::gradients::grid_points;
use crate::study::light_field_derivs::{aware_and_unaware, mean_parts, reference_batch};
use crate::study::seeds::point_seed;

type PartDerivs = derivatives::PartDerivs<D2>;
type LightField = crate::pipeline::probe::LightField<D2>;
type Element = crate::pipeline::proxy::Element<D2>;
use crate::progress::Cancelled;
use glam::DVec2;
use std::sync::Arc;

/// Settings of the derivative methods and overlays (the side panel's "Method").
#[derive(Clone, Debug, PartialEq)]
pub struct MethodParams {
    /// Directions per light field of the probe (`probe --rays`).
    pub rays: usize,
    /// Ray-marched medium samples per ray (`--steps`).
    pub steps: usize,
    /// Recursive paths per hit and medium sample (`--paths`).
    pub paths: u32,
    /// Samples per stencil point of the finite-difference reference (`--spp`).
    pub ref_spp: u32,
    /// Finite-difference step, fraction of the scene size (`--fd-step`).
    pub fd_step: f64,
    /// Error threshold ε of the cache metric (ellipse / circle of the inspector).
    pub eps: f64,
    /// Gradient overlay: grid points per side and directions per light field.
    pub grid: usize,
    pub grid_rays: usize,
    /// Gradient overlay: after the `grid` level, refine by doubling up to the
    /// field's resolution (one light field per pixel), each level complete before
    /// it replaces the last.
    pub grid_refine: bool,
}

impl Default for MethodParams {
    fn default() -> Self {
        MethodParams {
            rays: 2048,
            steps: 24,
            paths: 1,
            ref_spp: ReferenceSettings::default().spp,
            fd_step: 1e-2,
            eps: 0.05,
            grid: 16,
            grid_rays: 256,
            grid_refine: true,
        }
    }
}

impl MethodParams {
    pub fn probe_settings(&self, rays: usize, settings: Settings) -> ProbeSettings {
        ProbeSettings {
            rays: rays.max(3),
            paths: self.paths.max(1),
            steps: self.steps.max(1),
            settings,
            ..ProbeSettings::default_for::<D2>()
        }
    }
}

/// One refinement level of the field.
pub struct FieldLevel {
    /// 1-based level and the number of levels.
    pub level: usize,
    pub levels: usize,
    pub params: FieldParams,
    pub rendered: RenderedField,
    /// The records the field was reconstructed from (empty when path traced).
    pub records: Vec<crate::flatland::cached_field::RecordInfo>,
}

/// Coarse-to-fine levels ending with `p` itself: longest side 32 at ≤ 4 spp, then
/// 128 at ≤ 16 spp, each only when clearly coarser than the final one.
pub fn field_levels(p: &FieldParams) -> Vec<FieldParams> {
    let longest = p.width.max(p.height).max(1);
    let mut out = Vec::new();
    for (side, spp) in [(32usize, 4u32), (128, 16)] {
        if longest as f64 >= 1.5 * side as f64 {
            let s = side as f64 / longest as f64;
            out.push(FieldParams {
                width: ((p.width as f64 * s).round() as usize).max(1),
                height: ((p.height as f64 * s).round() as usize).max(1),
                spp: spp.min(p.spp).max(1),
                ..p.clone()
            });
        }
    }
    out.push(p.clone());
    out
}

/// Render the levels one after the other, sending each as it lands.
pub fn spawn_field(scene: Arc<Scene>, params: FieldParams, notify: Notify) -> Job<Arc<FieldLevel>> {
    Job::spawn(
        "field",
        Priority::Background,
        notify,
        move |r: &Reporter<Arc<FieldLevel>>| {
            let levels = field_levels(&params);
            let n = levels.len();
            for (i, lp) in levels.into_iter().enumerate() {
                r.stage(format!(
                    "field {}/{n}: {}×{} @ {} spp",
                    i + 1,
                    lp.width,
                    lp.height,
                    lp.spp
                ));
                let rendered = render_field(&scene, &lp, r.progress())?;
                r.add_rays(rendered.rays);
                r.send(Arc::new(FieldLevel {
                    level: i + 1,
                    levels: n,
                    params: lp,
                    rendered,
                    records: Vec::new(),
                }));
            }
            Ok(())
        },
    )
}

/// Radiance arriving at the probe from one direction (luminance): from the surface
/// the ray hits, and from the medium along it (Σ T·L_s·Δt over its samples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incoming {
    pub angle: f64,
    pub surface: f64,
    pub medium: f64,
}

/// The probe inspector's data.
pub struct ProbeResult {
    pub at: DVec2,
    pub inside_medium: bool,
    pub light_field: LightField,
    pub elements: Vec<Element>,
    pub incoming: Vec<Incoming>,
    pub aware: PartDerivs,
    pub unaware: PartDerivs,
    pub rays: u64,
    pub seconds: f64,
}

fn incoming(scene: &Scene, lf: &LightField) -> Vec<Incoming> {
    let lum = crate::study::light_field_derivs::incoming_luminance(scene, lf);
    (lf.rays.iter().zip(lum))
        .map(|(r, (surface, medium))| Incoming {
            angle: r.dir.y.atan2(r.dir.x),
            surface,
            medium,
        })
        .collect()
}

/// Light field, proxy, aware and unaware derivatives at `x` (`volcache probe
/// --method aware|unaware --seed seed`: the same light field).
pub fn spawn_probe(
    scene: Arc<Scene>,
    x: DVec2,
    omega_o: DVec2,
    ps: ProbeSettings,
    seed: u64,
    notify: Notify,
) -> Job<Arc<ProbeResult>> {
    Job::spawn(
        "probe",
        Priority::Interactive,
        notify,
        move |r: &Reporter<Arc<ProbeResult>>| {
            r.stage(format!("probe: light field, {} rays", ps.rays));
            r.progress().start(1);
            let start = std::time::Instant::now();
            let aw = AwareSettings::default();
            let out = Outgoing::Direction(omega_o);
            let shared = aware_and_unaware(&*scene, x, out, &ps, &aw, seed, r.progress())?;
            let lf = shared.light_field;
            r.add_rays(lf.cost_rays);
            r.progress().advance(1);
            r.send(Arc::new(ProbeResult {
                at: x,
                inside_medium: scene.medium_at(x).is_some(),
                incoming: incoming(&scene, &lf),
                rays: lf.cost_rays,
                light_field: lf,
                elements: shared.elements,
                aware: shared.aware,
                unaware: shared.unaware,
                seconds: start.elapsed().as_secs_f64(),
            }));
            Ok(())
        },
    )
}

/// The finite-difference reference as the mean of independent batches (so it has a
/// progress bar, can be cancelled, and carries its own standard error).
pub struct ReferenceResult {
    pub batches: Vec<PartDerivs>,
    /// Batches planned.
    pub planned: usize,
    pub spp_per_batch: u32,
    pub rays: u64,
    pub seconds: f64,
}

impl ReferenceResult {
    pub fn mean(&self) -> PartDerivs {
        mean_parts(&self.batches)
    }
}

/// Batches of the reference (their spread estimates its error).
pub const REFERENCE_BATCHES: usize = 8;

#[allow(clippy::too_many_arguments)]
pub fn spawn_reference(
    scene: Arc<Scene>,
    x: DVec2,
    omega_o: DVec2,
    spp: u32,
    relative_step: f64,
    settings: Settings,
    seed: u64,
    notify: Notify,
) -> Job<Arc<ReferenceResult>> {
    Job::spawn(
        "reference",
        Priority::Interactive,
        notify,
        move |r: &Reporter<Arc<ReferenceResult>>| {
            let n = REFERENCE_BATCHES;
            let rs = ReferenceSettings {
                spp: spp.div_ceil(n as u32).max(1),
                relative_step,
            };
            r.stage(format!("reference: {n} × {} spp per stencil point", rs.spp));
            r.progress().start(n as u64);
            let start = std::time::Instant::now();
            let mut res = ReferenceResult {
                batches: Vec::new(),
                planned: n,
                spp_per_batch: rs.spp,
                rays: 0,
                seconds: 0.0,
            };
            for k in 0..n {
                r.progress().check()?;
                let d = reference_batch(
                    &*scene,
                    x,
                    Outgoing::Direction(omega_o),
                    &rs,
                    &settings,
                    seed,
                    k as u64 + 1,
                );
                r.add_rays(d.rays);
                res.rays += d.rays;
                res.batches.push(d.parts);
                res.seconds = start.elapsed().as_secs_f64();
                r.progress().advance(1);
                r.send(Arc::new(ReferenceResult {
                    batches: res.batches.clone(),
                    ..res
                }));
            }
            Ok(())
        },
    )
}

/// One point of the gradient overlay (None outside the medium: L_s undefined).
#[derive(Clone, Copy, Debug)]
pub struct GridPoint {
    pub at: DVec2,
    pub aware: Option<PartDerivs>,
    pub unaware: Option<PartDerivs>,
}

/// Grid points computed so far, in order.
pub struct GradientGrid {
    pub n: usize,
    pub cell: DVec2,
    pub points: Vec<GridPoint>,
}

/// The gradient overlay's levels: `n`, then doubling while below `n_max`, ending
/// at `n_max` (the field's resolution) when it is larger than `n`.
pub fn gradient_levels(n: usize, n_max: usize) -> Vec<usize> {
    let mut v = vec![n.max(1)];
    while *v.last().unwrap() < n_max {
        let next = (2 * v.last().unwrap()).min(n_max);
        v.push(next);
    }
    v
}

/// The gradient overlay, level after level (`gradient_levels(n, n_max)`): each the
/// points and seeds of `volcache figure gradients --grid n`. The first level is
/// sent row by row as it fills; finer ones only when complete, so the overlay
/// never shows a partial finer level over a complete coarser one.
pub fn spawn_gradients(
    scene: Arc<Scene>,
    (n, n_max): (usize, usize),
    omega_o: DVec2,
    ps: ProbeSettings,
    seed: u64,
    notify: Notify,
) -> Job<Arc<GradientGrid>> {
    Job::spawn(
        "gradients",
        Priority::Background,
        notify,
        move |r: &Reporter<Arc<GradientGrid>>| {
            let levels = gradient_levels(n, n_max);
            let count = levels.len();
            for (level, &n) in levels.iter().enumerate() {
                let pts = grid_points(&scene, n);
                r.stage(format!(
                    "gradient overlay {}/{count}: {n}×{n} light fields of {} rays",
                    level + 1,
                    ps.rays
                ));
                r.progress().start(pts.len() as u64);
                let cell = (scene.domain_max - scene.domain_min) / n as f64;
                let mut done = Vec::with_capacity(pts.len());
                let aw = AwareSettings::default();
                for (k, &x) in pts.iter().enumerate() {
                    let mut p = GridPoint {
                        at: x,
                        aware: None,
                        unaware: None,
                    };
                    if scene.medium_at(x).is_some() {
                        // The points and seeds of `volcache figure gradients --grid n`.
                        let out = Outgoing::Direction(omega_o);
                        let shared =
                            aware_and_unaware(&*scene, x, out, &ps, &aw, point_seed(seed, k, false), r.progress())?;
                        r.add_rays(shared.light_field.cost_rays);
                        p.aware = Some(shared.aware);
                        p.unaware = Some(shared.unaware);
                    }
                    done.push(p);
                    r.progress().advance(1);
                    let row_done = (k + 1) % n == 0;
                    if (level == 0 && row_done) || k + 1 == pts.len() {
                        r.send(Arc::new(GradientGrid {
                            n,
                            cell,
                            points: done.clone(),
                        }));
                    }
                }
            }
            Result::<(), Cancelled>::Ok(())
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::jobs::no_notify;

    #[test]
    fn gradient_levels_double_up_to_the_fields_resolution() {
        assert_eq!(gradient_levels(16, 16), vec![16]);
        assert_eq!(gradient_levels(16, 256), vec![16, 32, 64, 128, 256]);
        assert_eq!(gradient_levels(4, 24), vec![4, 8, 16, 24]);
        assert_eq!(gradient_levels(0, 0), vec![1]);
    }

    #[test]
    fn levels_go_coarse_to_fine_and_end_with_the_request() {
        let p = FieldParams::from_scene(&Scene::default_scene());
        let l = field_levels(&p);
        let sizes: Vec<_> = l.iter().map(|q| (q.width, q.height, q.spp)).collect();
        assert_eq!(sizes, vec![(32, 32, 4), (128, 128, 16), (256, 256, 128)]);
        assert_eq!(l[2], p);
        let small = FieldParams {
            width: 40,
            height: 20,
            spp: 2,
            ..p.clone()
        };
        assert_eq!(field_levels(&small), vec![small.clone()]);
        let wide = FieldParams {
            width: 300,
            height: 100,
            ..p
        };
        let l = field_levels(&wide);
        assert_eq!((l[0].width, l[0].height, l[1].width, l[1].height), (32, 11, 128, 43));
    }

    #[test]
    fn field_job_sends_every_level_and_matches_a_direct_render() {
        let scene = Arc::new(Scene::default_scene());
        let p = FieldParams {
            width: 48,
            height: 48,
            spp: 2,
            ..FieldParams::from_scene(&scene)
        };
        let job = spawn_field(scene.clone(), p.clone(), no_notify());
        let mut got = Vec::new();
        let t = std::time::Instant::now();
        while got.len() < 2 {
            got.extend(job.poll());
            assert!(t.elapsed().as_secs() < 30);
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        assert_eq!((got[0].level, got[1].level, got[1].levels), (1, 2, 2));
        let direct = render_field(&scene, &p, &crate::progress::Progress::new()).unwrap();
        assert_eq!(got[1].rendered.field, direct.field, "same as `volcache field`");
    }
}
