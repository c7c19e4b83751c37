//! An irradiance meter: a flat virtual sensor — a segment in 2D, a parallelogram in
//! 3D — and the estimate of the mean irradiance over its front side,
//! E = (1/|A|) ∫_A ∫ L_i(y, ω) max(0, n·ω) dω dy (W m⁻¹ in 2D, W m⁻² in 3D).
//! E·|A| is the power crossing the sensor towards its back (the reflected power of
//! the half-space problem, `benchmarks.md`). pbrt-v4's and Mitsuba's irradiance
//! meters estimate the same integral the same way: a uniform point on the shape,
//! then a cosine-weighted direction (here the path tracer's Lambertian lobe, with
//! NEE and MIS, [`path::sample_query`]).
//!
//! The sensor is virtual: it neither occludes nor reflects. Its front side follows
//! the scene formats: left of a→b (2D segments), along u × v (3D quads).

use super::path::{Accumulator, Estimate, Query, Settings, sample_query};
use super::world::World;
use crate::core::rng::Sampler;
use crate::core::space::{D2, D3, Space};
use crate::limits;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// A flat sensor origin + s·u (+ t·v in 3D), s, t ∈ [0, 1], measuring light that
/// arrives at its front side (unit normal `normal`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensor<S: Space> {
    pub origin: S::Vec,
    pub u: S::Vec,
    /// The second edge (3D); none for a segment.
    pub v: Option<S::Vec>,
    pub normal: S::Vec,
    /// Length (2D) or area (3D).
    pub measure: f64,
}

/// What is wrong with a sensor's geometry (the caller names the option or field).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SensorError {
    #[error(
        "{what} is {len:e} long, less than {:e} of the scene size ({min:e})",
        limits::MIN_SEPARATION
    )]
    TooSmall { what: &'static str, len: f64, min: f64 },
    #[error("the edges u and v are parallel (the sine of their angle is {sine:e}, below 1e-6): the quad has no area")]
    Parallel { sine: f64 },
    #[error("a coordinate is not finite or lies beyond ±{:e}", limits::MAX_COORD)]
    OutOfRange,
}

fn in_range(c: &[f64]) -> Result<(), SensorError> {
    match c.iter().all(|v| v.is_finite() && v.abs() <= limits::MAX_COORD) {
        true => Ok(()),
        false => Err(SensorError::OutOfRange),
    }
}

/// Edges shorter than this fraction of the scene are refused, as segments of the
/// scene are (README "Ranges").
fn long_enough(what: &'static str, len: f64, scale: f64) -> Result<(), SensorError> {
    let min = limits::MIN_SEPARATION * scale;
    match len >= min && len > 0.0 {
        true => Ok(()),
        false => Err(SensorError::TooSmall { what, len, min }),
    }
}

impl Sensor<D2> {
    /// The segment a→b of a scene of size `scale`; its front is to the left of a→b.
    pub fn segment(a: DVec2, b: DVec2, scale: f64) -> Result<Self, SensorError> {
        in_range(&[a.x, a.y, b.x, b.y])?;
        let u = b - a;
        long_enough("the segment a→b", u.length(), scale)?;
        Ok(Sensor {
            origin: a,
            u,
            v: None,
            normal: u.perp().normalize(),
            measure: u.length(),
        })
    }
}

impl Sensor<D3> {
    /// The parallelogram origin + s·u + t·v of a scene of size `scale`; its front
    /// is along u × v.
    pub fn parallelogram(origin: DVec3, u: DVec3, v: DVec3, scale: f64) -> Result<Self, SensorError> {
        in_range(&[origin.to_array(), u.to_array(), v.to_array()].concat())?;
        long_enough("edge u", u.length(), scale)?;
        long_enough("edge v", v.length(), scale)?;
        // Scaled before the cross product so that 10¹² × 10¹² cannot overflow.
        let (uh, vh) = (u / u.length(), v / v.length());
        let n = uh.cross(vh);
        let sine = n.length();
        if sine < 1e-6 {
            return Err(SensorError::Parallel { sine });
        }
        Ok(Sensor {
            origin,
            u,
            v: Some(v),
            normal: n / sine,
            measure: u.length() * v.length() * sine,
        })
    }
}

impl<S: Space> Sensor<S> {
    /// A uniform point on the sensor (one number per edge).
    pub fn sample_point(&self, s: &mut Sampler) -> S::Vec {
        let mut p = self.origin + self.u * s.next_f64();
        if let Some(v) = self.v {
            p += v * s.next_f64();
        }
        p
    }
}

/// Samples per parallel block: blocks are summed in their order, so the estimate
/// is the same bit for bit whatever the thread count.
const BLOCK: u32 = 1024;

/// Mean irradiance over the sensor's front side, per part, with its standard
/// error: `spp` samples, sample k drawing from the stream (seed, item, k) — a
/// uniform point on the sensor, then one sample of the cosine-weighted integral
/// there (NEE to every light, one Lambertian path, MIS).
pub fn estimate_irradiance<W: World>(
    world: &W,
    sensor: &Sensor<W::S>,
    settings: &Settings,
    spp: u32,
    seed: u64,
    item: u64,
) -> Estimate {
    let q = Query::Irradiance { normal: sensor.normal };
    let blocks: Vec<Accumulator> = (0..spp.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let (mut acc, mut rays) = (Accumulator::default(), 0);
            for k in b * BLOCK..((b + 1) * BLOCK).min(spp) {
                let mut s = Sampler::new2(seed, item, k as u64);
                let y = sensor.sample_point(&mut s);
                acc.push(&sample_query(world, y, &q, settings, &mut s, &mut rays));
            }
            acc.add_rays(rays);
            acc
        })
        .collect();
    let mut total = Accumulator::default();
    for b in &blocks {
        total.merge(b);
    }
    total.estimate()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_front_is_left_of_a_to_b() {
        let s = Sensor::segment(DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0), 1.0).unwrap();
        assert_eq!((s.normal, s.measure), (DVec2::Y, 2.0));
    }

    #[test]
    fn parallelogram_front_is_along_u_cross_v() {
        let s = Sensor::parallelogram(DVec3::ZERO, DVec3::X * 2.0, DVec3::new(1.0, 3.0, 0.0), 1.0).unwrap();
        assert!((s.normal - DVec3::Z).length() < 1e-15);
        assert!((s.measure - 6.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_sensors_are_refused() {
        let p = DVec2::new(0.5, 0.5);
        assert!(matches!(Sensor::segment(p, p, 1.0), Err(SensorError::TooSmall { .. })));
        let e = Sensor::parallelogram(DVec3::ZERO, DVec3::X, DVec3::X * 3.0, 1.0);
        assert!(matches!(e, Err(SensorError::Parallel { .. })));
        let e = Sensor::parallelogram(DVec3::ZERO, DVec3::X, DVec3::Y * 1e-12, 1.0);
        assert!(matches!(e, Err(SensorError::TooSmall { what: "edge v", .. })));
        let far = DVec2::new(f64::NAN, 0.0);
        assert_eq!(Sensor::segment(far, p, 1.0), Err(SensorError::OutOfRange));
    }

    #[test]
    fn points_are_uniform_on_the_sensor() {
        let s = Sensor::parallelogram(DVec3::ONE, DVec3::X, DVec3::Y * 2.0, 1.0).unwrap();
        let n = 20_000;
        let mean = (0..n).fold(DVec3::ZERO, |m, k| m + s.sample_point(&mut Sampler::new(1, k))) / n as f64;
        assert!((mean - DVec3::new(1.5, 2.0, 1.0)).length() < 0.02, "{mean}");
    }
}
