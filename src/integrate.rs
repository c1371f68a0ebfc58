//! Time integration: kick–drift–kick leapfrog (second order, time-reversible for
//! velocity-independent forces) with a global step from the Courant, force and energy
//! conditions.
//!
//! One step of length Δt:
//! 1. kick:  v ← v + a Δt/2,  u ← u + (du/dt) Δt/2;
//! 2. drift: x ← x + v Δt (then wrap or reflect at the box);
//! 3. predict v and u at the end of the step (v + a Δt/2) for the velocity-dependent terms;
//! 4. evaluate: one sweep gives the new a and du/dt, plus external gravity;
//! 5. kick:  v ← v_half + a Δt/2, u ← u_half + (du/dt) Δt/2;
//! 6. with the artificial-viscosity switch, each particle's α over Δt (`physics::av_switch`).

use rayon::prelude::*;

use crate::boundary::SimBox;
use crate::particles::Particles;
use crate::physics::av_switch::{AvSwitch, SwitchKind};
use crate::physics::eos::cylindrical_radius;
use crate::physics::pressure_energy::{rescaled_pressure, sound_speed};
use crate::sweep::{Physics, SweepStats, Window, evaluate};

/// Step-limiter factors.
#[derive(Clone, Copy, Debug)]
pub struct StepControl {
    pub courant: f64,
    pub force: f64,
    pub energy: f64,
    /// Δt ≤ viscous · h² / ν (explicit diffusion limit).
    pub viscous: f64,
}

impl Default for StepControl {
    /// The problem file's defaults: Courant 0.3, force 0.25, energy 0.3, viscous 0.4.
    fn default() -> Self {
        Self {
            courant: 0.3,
            force: 0.25,
            energy: 0.3,
            viscous: 0.4,
        }
    }
}

/// The right-hand sides: one sweep (hydrodynamics and viscosity), then the external
/// gravity of the central mass added to the accelerations.
pub fn rhs<const D: usize>(
    p: &mut Particles<D>,
    bx: &SimBox<D>,
    phys: &Physics<D>,
    window: Window,
) -> SweepStats {
    let stats = evaluate(p, bx, phys, window);
    add_external(p, phys);
    stats
}

/// What acts on each particle from outside the sweep: the external gravity, and cooling or
/// the disk instability's relaxation of u to its branch.
pub fn add_external<const D: usize>(p: &mut Particles<D>, phys: &Physics<D>) {
    add_gravity(p, phys);
    if let (Some(c), Some(g)) = (&phys.cooling, &phys.gravity) {
        c.add_to(p, &phys.eos, g);
    }
    if let (Some(o), Some(g)) = (&phys.outbursts, &phys.gravity) {
        o.set_rates(p, &phys.eos, g);
    }
}

/// The external gravity at `x`: the central point mass's, if there is one, and a binary
/// donor's.
#[inline]
pub fn external_acceleration<const D: usize>(phys: &Physics<D>, x: &[f64; D]) -> [f64; D] {
    let mut a = phys.gravity.map_or([0.0; D], |g| g.acceleration(x));
    if let Some(b) = &phys.binary {
        let a2 = b.donor_acceleration(x);
        for d in 0..D {
            a[d] += a2[d];
        }
    }
    a
}

/// Adds the external gravity ([`external_acceleration`]) to every particle's acceleration.
pub fn add_gravity<const D: usize>(p: &mut Particles<D>, phys: &Physics<D>) {
    if phys.gravity.is_none() && phys.binary.is_none() {
        return;
    }
    let a: Vec<[f64; D]> = (0..p.len())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|i| external_acceleration(phys, &p.position(i)))
        .collect();
    for d in 0..D {
        p.acc[d]
            .par_iter_mut()
            .zip(a.par_iter())
            .with_min_len(GRAIN)
            .for_each(|(acc, a)| *acc += a[d]);
    }
}

/// Particles per task in the integrator's parallel loops.
const GRAIN: usize = 4096;

/// v ← v_half + a Δt/2 and, if the energy is evolved, u ← u_half + (du/dt) Δt/2.
fn half_kick<const D: usize>(
    p: &mut Particles<D>,
    v_half: &[Vec<f64>; D],
    u_half: &[f64],
    half: f64,
    evolve_u: bool,
) {
    let kick = |x: &mut [f64], half_step: &[f64], rate: &[f64]| {
        x.par_iter_mut()
            .zip(half_step.par_iter().zip(rate.par_iter()))
            .with_min_len(GRAIN)
            .for_each(|(x, (&h, &r))| *x = h + half * r);
    };
    for d in 0..D {
        kick(&mut p.vel[d], &v_half[d], &p.acc[d]);
    }
    if evolve_u {
        kick(&mut p.u, u_half, &p.du);
    }
}

/// The largest stable global step: min over particles of C_cour h / v_sig, C_force √(h/|a|),
/// C_energy u / |du/dt| where the internal energy falls, and C_visc h² / ν.
pub fn time_step<const D: usize>(
    p: &Particles<D>,
    h: f64,
    ctl: &StepControl,
    evolve_u: bool,
) -> f64 {
    // The minimum is exact in any order: the same step on any number of threads.
    (0..p.len())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|i| particle_time_step(p, i, h, ctl, evolve_u))
        .reduce(|| f64::INFINITY, f64::min)
}

/// Particle `i`'s limit on the step ([`time_step`]).
#[inline]
fn particle_time_step<const D: usize>(
    p: &Particles<D>,
    i: usize,
    h: f64,
    ctl: &StepControl,
    evolve_u: bool,
) -> f64 {
    let mut dt = f64::INFINITY;
    if p.vsig[i] > 0.0 {
        dt = dt.min(ctl.courant * h / p.vsig[i]);
    }
    let a2: f64 = (0..D).map(|d| p.acc[d][i] * p.acc[d][i]).sum();
    if a2 > 0.0 {
        dt = dt.min(ctl.force * (h / a2.sqrt()).sqrt());
    }
    if evolve_u && p.du[i] < 0.0 && p.u[i] > 0.0 {
        dt = dt.min(ctl.energy * p.u[i] / -p.du[i]);
    }
    if p.nu[i] > 0.0 {
        dt = dt.min(ctl.viscous * h * h / p.nu[i]);
    }
    dt
}

/// Advances the particles by one KDK step of length `dt`. Expects `acc` and `du` from the
/// previous evaluation; leaves them (and ρ, p, c_s, v_sig) from the new one.
pub fn kdk_step<const D: usize>(
    p: &mut Particles<D>,
    bx: &SimBox<D>,
    phys: &Physics<D>,
    window: Window,
    dt: f64,
) -> SweepStats {
    kdk_step_with(p, bx, phys, dt, |p| rhs(p, bx, phys, window))
}

/// [`kdk_step`] with the right-hand sides from `rhs` (e.g. a distributed evaluation).
pub fn kdk_step_with<const D: usize>(
    p: &mut Particles<D>,
    bx: &SimBox<D>,
    phys: &Physics<D>,
    dt: f64,
    rhs: impl FnOnce(&mut Particles<D>) -> SweepStats,
) -> SweepStats {
    let evolve_u = phys.eos.evolves_energy();
    let half = 0.5 * dt;
    // In a binary's turning frame the kicks act on the inertial velocity (module doc of
    // `physics::binary`): corotating → inertial here, back at the end of the step.
    if let Some(b) = &phys.binary {
        b.add_frame_velocity(&p.pos, &mut p.vel, 1.0);
    }
    let half_step = |x: &[f64], rate: &[f64]| -> Vec<f64> {
        x.par_iter()
            .zip(rate.par_iter())
            .with_min_len(GRAIN)
            .map(|(&x, &r)| x + half * r)
            .collect()
    };
    let mut v_half: [Vec<f64>; D] = std::array::from_fn(|d| half_step(&p.vel[d], &p.acc[d]));
    for d in 0..D {
        p.pos[d]
            .par_iter_mut()
            .zip(v_half[d].par_iter())
            .with_min_len(GRAIN)
            .for_each(|(x, &v)| *x += v * dt);
    }
    let u_half: Vec<f64> = if evolve_u {
        half_step(&p.u, &p.du)
    } else {
        p.u.clone()
    };
    if let Some(b) = &phys.binary {
        // The straight drift was inertial: the frame turns on by Ω Δt under it.
        b.turn(&mut p.pos, &mut [&mut v_half, &mut p.acc], dt);
    }
    // Reflection flips the half-step velocity too: apply the walls to it.
    bx.enforce(&mut p.pos, &mut v_half);
    // Predict with the old accelerations, evaluate, correct with the new ones.
    half_kick(p, &v_half, &u_half, half, evolve_u);
    let switch = phys.av.switch();
    // Cullen & Dehnen's trigger needs ∇·v before the evaluation too.
    let div_old = match switch {
        Some(sw) if sw.kind == SwitchKind::CullenDehnen => AvSwitch::divergence(p),
        _ => Vec::new(),
    };
    // The pressure–energy p̄ was smoothed from the predicted u; kept consistent with the
    // corrected one below.
    let pe_gamma = phys.pressure_energy_gamma();
    let u_eval = if pe_gamma.is_some() {
        p.u.clone()
    } else {
        Vec::new()
    };
    let stats = rhs(p);
    half_kick(p, &v_half, &u_half, half, evolve_u);
    if let Some(sw) = switch {
        // α_i over the step, with this evaluation's ∇·v (physics::av_switch).
        sw.advance_all(p, &div_old, phys.kernel.h(), dt);
    }
    if let Some(b) = &phys.binary {
        b.add_frame_velocity(&p.pos, &mut p.vel, -1.0);
    }
    if evolve_u {
        // Pressure and sound speed from the corrected energy (density is unchanged).
        let (pos, rho, u) = (&p.pos, &p.rho, &p.u);
        p.p.par_iter_mut()
            .zip(p.cs.par_iter_mut())
            .enumerate()
            .with_min_len(GRAIN)
            .for_each(|(i, (p_i, cs_i))| {
                (*p_i, *cs_i) = match pe_gamma {
                    Some(gamma) => {
                        let pr = rescaled_pressure(*p_i, u_eval[i], u[i]);
                        (pr, sound_speed(gamma, pr, rho[i]))
                    }
                    None => {
                        let radius = if phys.eos.needs_radius() {
                            cylindrical_radius::<D>(&std::array::from_fn(|d| pos[d][i]))
                        } else {
                            0.0
                        };
                        phys.eos.pressure_sound_speed(rho[i], u[i], radius)
                    }
                };
            });
    }
    stats
}
