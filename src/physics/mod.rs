//! The physics of one SPH scheme, written once for 1, 2 and 3 dimensions: the equation of
//! state, the artificial viscosity for shocks, and the fixed set of pair functions the sweep
//! calls (`hydro`). Physical viscosity and gravity join here.

pub mod artificial_viscosity;
pub mod eos;
pub mod hydro;
