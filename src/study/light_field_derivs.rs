//! One point's derivatives by every method: ours (aware) and Jarosz 2008 (unaware)
//! from **one shared light field**, so their differences are the methods' and not
//! the noise's, and the finite-difference reference in independent batches, whose
//! spread estimates its own noise. The gradient study, `volcache probe` and the
//! app's probe inspector and gradient overlay all compute them here.

use super::seeds::reference_batch_seed;
use crate::core::color::luminance;
use crate::pipeline::derivatives::{self, AwareSettings, Derivatives, Method, PartDerivs, ReferenceSettings};
use crate::pipeline::dim::Dim;
use crate::pipeline::path::Settings;
use crate::pipeline::probe::{LightField, Outgoing, ProbeSettings, capture};
use crate::pipeline::proxy::{self, Element};
use crate::pipeline::world::World;
use crate::progress::{Cancelled, Progress};
use std::time::Instant;

type VecOf<W> = <<W as World>::S as crate::core::space::Space>::Vec;

/// The light field at a point and what both cache methods derive from it.
#[derive(Clone, Debug)]
pub struct SharedLightField<S: Dim> {
    pub light_field: LightField<S>,
    /// The occlusion-free proxy ours builds from it.
    pub elements: Vec<Element<S>>,
    pub aware: PartDerivs<S>,
    pub unaware: PartDerivs<S>,
    /// Proxy construction and evaluation of the aware derivatives.
    pub aware_seconds: f64,
    pub unaware_seconds: f64,
}

/// Capture the light field at `x` (`seed`, item 0, as `volcache probe`) and
/// evaluate ours and Jarosz 2008 on it.
pub fn aware_and_unaware<W: World>(
    world: &W,
    x: VecOf<W>,
    out: Outgoing<VecOf<W>>,
    ps: &ProbeSettings,
    aw: &AwareSettings,
    seed: u64,
    progress: &Progress,
) -> Result<SharedLightField<W::S>, Cancelled> {
    let light_field = capture(world, x, out, ps, seed, 0, progress)?;
    let t = Instant::now();
    let aware = derivatives::aware(&light_field, &proxy::build(&light_field, aw.rule), aw);
    let aware_seconds = t.elapsed().as_secs_f64();
    // Every element, for the app to draw (not part of the method's cost).
    let elements = proxy::elements(&light_field, aw.rule);
    let t = Instant::now();
    let unaware = derivatives::unaware(&light_field);
    let unaware_seconds = t.elapsed().as_secs_f64();
    Ok(SharedLightField {
        light_field,
        elements,
        aware,
        unaware,
        aware_seconds,
        unaware_seconds,
    })
}

/// The luminance arriving at the light field's point along each of its rays, as
/// the probe inspectors draw it: (from the surface the ray hits, from the medium
/// along it, Σ T·L_s·Δt over its samples).
pub fn incoming_luminance<W: World>(world: &W, lf: &LightField<W::S>) -> Vec<(f64, f64)> {
    let t = |dir, d| world.transmittance(lf.x, dir, d);
    lf.rays
        .iter()
        .map(|r| {
            let surface = r.hit.map_or(0.0, |h| luminance(h.radiance * t(r.dir, r.length)));
            let medium = (r.samples.iter().enumerate())
                .map(|(i, s)| luminance(*s * t(r.dir, lf.sample_depth(r, i))) * lf.sample_thickness(r, i))
                .sum();
            (surface, medium)
        })
        .collect()
}

/// One method at `x`, with its cost: aware or unaware on a light field of their
/// own (capture included in the time), or the finite-difference reference.
#[allow(clippy::too_many_arguments)] // each setting block is its own type
pub fn derivatives_at<W: World>(
    world: &W,
    x: VecOf<W>,
    out: Outgoing<VecOf<W>>,
    method: Method,
    ps: &ProbeSettings,
    rs: &ReferenceSettings,
    aw: &AwareSettings,
    seed: u64,
    progress: &Progress,
) -> Result<Derivatives<W::S>, Cancelled> {
    if method == Method::Reference {
        return Ok(derivatives::reference_at(world, x, out, rs, &ps.settings, seed));
    }
    let start = Instant::now();
    let lf = capture(world, x, out, ps, seed, 0, progress)?;
    let aware = method == Method::Aware;
    let parts = if aware {
        derivatives::aware(&lf, &proxy::build(&lf, aw.rule), aw)
    } else {
        derivatives::unaware(&lf)
    };
    Ok(Derivatives {
        method,
        at: x,
        parts,
        has_hessian: aware,
        rays: lf.cost_rays,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Batch `b` (1, 2, …) of the finite-difference reference at `x`: `rs.spp`
/// samples per stencil point on the batch's own streams.
pub fn reference_batch<W: World>(
    world: &W,
    x: VecOf<W>,
    out: Outgoing<VecOf<W>>,
    rs: &ReferenceSettings,
    settings: &Settings,
    seed: u64,
    b: u64,
) -> Derivatives<W::S> {
    derivatives::reference_at(world, x, out, rs, settings, reference_batch_seed(seed, b))
}

/// The mean of the batches' derivatives (zero for none).
pub fn mean_parts<S: Dim>(batches: &[PartDerivs<S>]) -> PartDerivs<S> {
    PartDerivs::mean(batches)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::space::D2;
    use crate::flatland::scene::Scene;
    use glam::DVec2;

    /// Ours and Jarosz 2008 on the shared light field are what each computes on a
    /// light field of its own with the same seed; the reference batches average.
    #[test]
    fn shared_light_field_matches_each_method_alone() {
        let scene = Scene::default_scene();
        let x = DVec2::new(0.1, 0.2);
        let out = Outgoing::Direction(DVec2::X);
        let ps = ProbeSettings {
            rays: 64,
            steps: 4,
            ..ProbeSettings::default_for::<D2>()
        };
        let (aw, rs, p) = (
            AwareSettings::default(),
            ReferenceSettings {
                spp: 8,
                relative_step: 1e-2,
            },
            Progress::new(),
        );
        let shared = aware_and_unaware(&scene, x, out, &ps, &aw, 5, &p).unwrap();
        let alone = |m| derivatives_at(&scene, x, out, m, &ps, &rs, &aw, 5, &p).unwrap();
        let (a, u) = (alone(Method::Aware), alone(Method::Unaware));
        assert_eq!((a.parts, a.has_hessian), (shared.aware, true));
        assert_eq!((u.parts, u.has_hessian), (shared.unaware, false));
        assert_eq!(shared.elements, proxy::elements(&shared.light_field, aw.rule));
        let r = [1, 2].map(|b| reference_batch(&scene, x, out, &rs, &ps.settings, 5, b).parts);
        assert_ne!(r[0], r[1], "independent batches");
        let m = mean_parts(&r);
        assert_eq!(m.single, (r[0].single + r[1].single).scale(0.5));
        assert_eq!(mean_parts::<D2>(&[]), PartDerivs::default());
    }
}
