//! Experiments: the protocols by which the methods are compared, written once and
//! used by the command line and the app alike. They run the methods of `flatland`
//! (2D fields) and `volume` (3D images); they draw nothing and parse no options.
//!
//! - [`exact2d`]: exact single scattering in flatland (visibility intervals +
//!   Gauss–Legendre) and its derivatives, to judge estimators by.
//! - [`exact3d`]: the same in 3D (emitter polygons minus the occluders' central
//!   projections, collapsed Gauss–Legendre on the pieces).
//! - [`seeds`]: the seeds of an experiment's parts (reference, path tracing,
//!   gradient points) from the one seed the user gives.
//! - [`stored`]: the on-disk reference store (key, full-precision images);
//!   [`reference2d`] and [`reference3d`]: converged references read from it or
//!   rendered into it.
//! - [`field_runs`]: the 2D comparison protocol (equal record count, then a timed
//!   fresh run; path tracing at a sample count).
//! - [`runs3d`]: the 3D comparison runs (a cache method at a record count, path
//!   tracing at a sample count or a time budget); [`speedup`]: the speed-up of ours
//!   over Jarosz 2008 at equal error; [`targets`]: each method's time to 3%, 1% and
//!   0.3% relative RMSE (the reference's noise removed) and the ratios to ours.
//! - [`record_cost`]: what one record costs and how far it is from a converged
//!   record, per probe variant (`volcache bench records`).
//! - [`light_field_derivs`]: a point's derivatives by every method (aware and
//!   unaware on one shared light field, the reference in batches);
//!   [`gradients`]: the gradient study over a grid and a line;
//!   [`gradient_summary`]: its errors against the reference.

pub mod exact2d;
pub mod exact3d;
pub mod field_runs;
pub mod gradient_summary;
pub mod gradients;
pub mod light_field_derivs;
pub mod moments3d;
pub mod record_cost;
pub mod reference2d;
pub mod reference3d;
pub mod runs3d;
pub mod seeds;
pub mod speedup;
pub mod stored;
pub mod targets;
