//! sphdisk: Smoothed Particle Hydrodynamics for accretion disks, after Speith, Schnetter,
//! Kunze & Riffert, "Distributed implementation of SPH for simulations of accretion disks".
//!
//! See `ARCHITECTURE.md` for the data flow of one step and which module owns what.

pub mod boundary;
pub mod grid;
pub mod kernel;
pub mod particles;
pub mod physics;
pub mod rng;
pub mod sweep;
