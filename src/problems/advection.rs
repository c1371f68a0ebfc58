//! Advection of a smooth pulse around a periodic box (1, 2 or 3 dimensions): a cubic lattice
//! of `particles.n` per axis, masses m_i = ρ(x_i) Δx^D, uniform velocity, and internal
//! energies chosen after the first density sum so that the pressure is exactly uniform.
//! After one period the density should return to the initial profile; the L1 error measures
//! how far it does not. Reference spacing for `particles.h_factor`: the lattice spacing.

use std::collections::BTreeMap;

use anyhow::{Result, bail};

use crate::analysis::advection::Pulse;
use crate::analysis::l1_norm;
use crate::boundary::{BoundaryKind, SimBox};
use crate::config::{AdvectionParams, Config};
use crate::particles::Particles;
use crate::problems::{InitialState, lattice, make_box, smoothing_length};

fn pulse(a: &AdvectionParams) -> Pulse {
    Pulse {
        rho0: a.rho0,
        amplitude: a.amplitude,
        width: a.width,
        velocity: a.velocity,
        length: a.length,
    }
}

pub fn setup<const D: usize>(cfg: &Config) -> Result<InitialState<D>> {
    let a = cfg.advection.clone().unwrap_or_default();
    if !(a.rho0 > 0.0 && a.p0 > 0.0) {
        bail!("key `advection.rho0` / `advection.p0`: must be > 0");
    }
    if !(a.amplitude > -1.0) {
        bail!("key `advection.amplitude`: must be > −1 (positive density)");
    }
    if !(a.width > 0.0 && a.length > 0.0) {
        bail!("key `advection.width` / `advection.length`: must be > 0");
    }
    let n = cfg.particles.n.unwrap_or(0);
    let dx = a.length / n as f64;
    let shape = pulse(&a);
    let mut p = Particles::new();
    for x in lattice::cuboid([0.0; D], [dx; D], [n; D])? {
        let m = shape.density(x, 0.0) * dx.powi(D as i32);
        let id = p.len() as u64;
        p.push(
            id,
            x,
            [a.velocity; D],
            m,
            cfg.eos.internal_energy(a.rho0, a.p0),
        );
    }
    let bx = make_box(cfg, [0.0; D], [a.length; D], [BoundaryKind::Periodic; D]);
    Ok(InitialState {
        pressure_equilibrium: Some(a.p0),
        ..InitialState::new(p, bx, smoothing_length(cfg, dx))
    })
}

/// L1 norm of ρ against the exact advected profile.
pub fn errors<const D: usize>(
    cfg: &Config,
    p: &Particles<D>,
    _bx: &SimBox<D>,
    t: f64,
) -> Result<BTreeMap<String, f64>> {
    let shape = pulse(&cfg.advection.clone().unwrap_or_default());
    let l1 = l1_norm(p, |i| p.rho[i] - shape.density(p.position(i), t));
    Ok(BTreeMap::from([("l1_density".to_string(), l1)]))
}
