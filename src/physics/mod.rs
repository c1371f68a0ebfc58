//! The physics of one SPH scheme, written once for 1, 2 and 3 dimensions: the equation of
//! state, artificial viscosity for shocks, physical viscosity (Eqs. 8–10), external gravity,
//! the choice of formulation (`pressure_energy`), and the fixed set of pair functions the sweep calls (`hydro`).

pub mod artificial_viscosity;
pub mod av_switch;
pub mod binary;
pub mod cooling;
pub mod eos;
pub mod gravity;
pub mod hydro;
pub mod l1_stream;
pub mod mass_transfer;
pub mod outbursts;
pub mod pressure_energy;
pub mod viscosity;
