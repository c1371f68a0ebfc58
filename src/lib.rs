//! sphdisk: Smoothed Particle Hydrodynamics for accretion disks, after Speith, Schnetter,
//! Kunze & Riffert, "Distributed implementation of SPH for simulations of accretion disks".
//!
//! See `ARCHITECTURE.md` for the data flow of one step and which module owns what.

pub mod analysis;
pub mod bench;
pub mod boundary;
pub mod config;
pub mod domain;
pub mod grid;
pub mod integrate;
pub mod io;
pub mod kernel;
pub mod lanes;
pub mod limits;
pub mod memory;
pub mod particles;
pub mod physics;
pub mod problems;
pub mod render;
pub mod reports;
pub mod rng;
pub mod signals;
pub mod simulation;
pub mod sweep;
