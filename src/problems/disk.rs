//! A Keplerian accretion disk in equilibrium around a point mass, in 2D or 3D: locally
//! isothermal, Σ ∝ R^(−p) with a zero-torque inner taper and a steep outer cut-off, and (in
//! 3D) the vertically isothermal profile ρ ∝ exp(−z²/2H²), H = c_s/Ω. Particles sit on
//! concentric rings (and, in 3D, layers in z) of spacing (r_out − r_in)/n with masses that
//! give the profile; velocities balance gravity, pressure and rotation exactly for the
//! analytic profile. With ν = α c_s H the disk should only spread on the viscous time
//! R²/ν: the figures measure how far it departs from its start instead.

use std::collections::BTreeMap;

use anyhow::{Result, bail};

use crate::boundary::BoundaryKind;
use crate::config::{Config, DiskParams};
use crate::particles::Particles;
use crate::physics::eos::Eos;
use crate::problems::{InitialState, make_box, smoothing_length};

fn params(cfg: &Config) -> DiskParams {
    cfg.disk.clone().unwrap_or_default()
}

/// Unnormalised Σ(R).
fn shape(d: &DiskParams, r: f64) -> f64 {
    if r <= d.r_in {
        return 0.0;
    }
    r.powf(-d.p) * (1.0 - (d.r_in / r).sqrt()) * (-(r / d.r_out).powi(4)).exp()
}

fn spacing(cfg: &Config) -> f64 {
    let d = params(cfg);
    (d.r_out - d.r_in) / cfg.particles.n.unwrap_or(1) as f64
}

pub fn setup<const D: usize>(cfg: &Config) -> Result<InitialState<D>> {
    if D < 2 {
        bail!("key `problem.dimension`: a disk needs 2 or 3 dimensions");
    }
    let dp = params(cfg);
    if !(dp.mass > 0.0 && dp.r_in > 0.0 && dp.r_out > dp.r_in && dp.orbits > 0.0) {
        bail!("keys `disk.mass`, `disk.r_in` > 0, `disk.r_out` > `disk.r_in`, `disk.orbits` > 0");
    }
    if !(dp.cutoff > 0.0 && dp.cutoff < 1.0 && dp.layers_h > 0.0) {
        bail!("keys `disk.cutoff` in (0, 1) and `disk.layers_h` > 0");
    }
    let Some(g) = cfg.gravity else {
        bail!("key `gravity.gm`: a disk orbits a central mass; give [gravity] gm");
    };
    if matches!(cfg.eos, Eos::Ideal { .. }) {
        bail!(
            "key `eos.kind`: the disk set-up is isothermal (locally_isothermal, isothermal or cold)"
        );
    }
    let dr = spacing(cfg);
    // Radial extent where Σ is above the cut-off; normalisation to the disk mass.
    let rmax = 4.0 * dp.r_out;
    let samples = 20_000;
    let peak = (1..samples)
        .map(|k| shape(&dp, k as f64 * rmax / samples as f64))
        .fold(0.0, f64::max);
    let mut radii = Vec::new();
    let mut r = dp.r_in + 0.5 * dr;
    while r < rmax {
        if shape(&dp, r) >= dp.cutoff * peak {
            radii.push(r);
        }
        r += dr;
    }
    let norm: f64 = radii
        .iter()
        .map(|&r| shape(&dp, r) * std::f64::consts::TAU * r * dr)
        .sum();
    let sigma = |r: f64| dp.mass * shape(&dp, r) / norm;
    if let Some(acc) = g.accretion_radius
        && radii.first().is_some_and(|&r| r <= acc)
    {
        bail!(
            "key `gravity.accretion_radius`: {acc} reaches into the disk (inner particles at R = {:.3})",
            radii[0]
        );
    }
    let cs = |r: f64| cfg.eos.pressure_sound_speed(1.0, 0.0, r).1;
    let omega = |r: f64| (g.gm / (r * r * r)).sqrt();
    let scale_height = |r: f64| cs(r) / omega(r);
    // Midplane-referenced density and pressure: ρ(R, z) = Σ/(√(2π) H) exp(−z²/2H²) in 3D;
    // Σ itself in 2D.
    let rho = |r: f64, z: f64| -> f64 {
        if D == 2 {
            sigma(r)
        } else {
            let h = scale_height(r);
            sigma(r) / ((std::f64::consts::TAU).sqrt() * h) * (-z * z / (2.0 * h * h)).exp()
        }
    };
    let pressure = |r: f64, z: f64| cs(r).powi(2) * rho(r, z);
    let eps = 1e-5 * dp.r_in;
    let mut p = Particles::new();
    for (k, &r) in radii.iter().enumerate() {
        let count = ((std::f64::consts::TAU * r / dr).round() as usize).max(1);
        let offset = if k % 2 == 1 { 0.5 } else { 0.0 };
        let layers: Vec<(f64, f64)> = if D == 2 {
            vec![(0.0, 1.0)]
        } else {
            let h = scale_height(r);
            let nz = ((dp.layers_h * h / dr).ceil() as i64).max(1);
            let zs: Vec<f64> = (-nz..nz).map(|j| (j as f64 + 0.5) * dr).collect();
            let w: Vec<f64> = zs.iter().map(|z| (-z * z / (2.0 * h * h)).exp()).collect();
            let wsum: f64 = w.iter().sum();
            zs.into_iter().zip(w).map(|(z, w)| (z, w / wsum)).collect()
        };
        for &(z, wz) in &layers {
            let m = sigma(r) * std::f64::consts::TAU * r * dr / count as f64 * wz;
            // v_φ² = R g_R + (R/ρ) ∂P/∂R at fixed z.
            let g_r = g.gm * r / (r * r + z * z + g.softening * g.softening).powf(1.5);
            let dpdr = (pressure(r + eps, z) - pressure(r - eps, z)) / (2.0 * eps);
            let vphi = (r * g_r + r / rho(r, z) * dpdr).max(0.0).sqrt();
            for j in 0..count {
                let phi = std::f64::consts::TAU * (j as f64 + offset) / count as f64;
                let (s, c) = phi.sin_cos();
                let pos: [f64; D] = std::array::from_fn(|d| match d {
                    0 => r * c,
                    1 => r * s,
                    _ => z,
                });
                let vel: [f64; D] = std::array::from_fn(|d| match d {
                    0 => -vphi * s,
                    1 => vphi * c,
                    _ => 0.0,
                });
                let id = p.len() as u64;
                p.push(id, pos, vel, m, cfg.eos.internal_energy(1.0, 0.0));
            }
        }
    }
    let extent = 2.0 * rmax;
    let bx = make_box(cfg, [-extent; D], [extent; D], [BoundaryKind::Open; D]);
    let period = std::f64::consts::TAU / omega(dp.r_in);
    Ok(InitialState {
        particles: p,
        bx,
        h: smoothing_length(cfg, dr),
        pressure_equilibrium: None,
        t_end: Some(dp.orbits * period),
        output_times: Vec::new(),
    })
}

/// How far the disk left its initial equilibrium: the relative shifts of the radii that
/// enclose 10%, 50% and 90% of the mass (robust to the rings' epicyclic wobble), the
/// relative change of the mass-weighted rms thickness (3D), and the mass-weighted rms
/// radial velocity in units of the sound speed at r_in.
pub fn errors<const D: usize>(cfg: &Config, p: &Particles<D>) -> Result<BTreeMap<String, f64>> {
    let start = setup::<D>(cfg)?.particles;
    let dp = params(cfg);
    let quantiles = |q: &Particles<D>| -> [f64; 3] {
        let mut rm: Vec<(f64, f64)> = (0..q.len())
            .map(|i| (q.pos[0][i].hypot(q.pos[1][i]), q.mass[i]))
            .collect();
        rm.sort_by(|a, b| a.0.total_cmp(&b.0));
        let total: f64 = rm.iter().map(|x| x.1).sum();
        let mut out = [0.0; 3];
        let mut acc = 0.0;
        let mut k = 0;
        for (r, m) in rm {
            acc += m;
            while k < 3 && acc >= [0.1, 0.5, 0.9][k] * total {
                out[k] = r;
                k += 1;
            }
        }
        out
    };
    let (q0, q1) = (quantiles(&start), quantiles(p));
    let mut e = BTreeMap::new();
    for (k, name) in ["disk_r10_change", "disk_r50_change", "disk_r90_change"]
        .iter()
        .enumerate()
    {
        e.insert(name.to_string(), (q1[k] - q0[k]) / q0[k]);
    }
    if D == 3 {
        let thickness = |q: &Particles<D>| {
            let mt: f64 = q.mass.iter().sum();
            ((0..q.len())
                .map(|i| q.mass[i] * q.pos[2][i].powi(2))
                .sum::<f64>()
                / mt)
                .sqrt()
        };
        let (h0, h1) = (thickness(&start), thickness(p));
        e.insert("disk_thickness_rms".to_string(), h1);
        e.insert("disk_thickness_change".to_string(), (h1 - h0).abs() / h0);
    }
    let cs_in = cfg
        .eos
        .pressure_sound_speed(1.0, 0.0, dp.r_in)
        .1
        .max(f64::MIN_POSITIVE);
    let mt: f64 = p.mass.iter().sum();
    let vr2: f64 = (0..p.len())
        .map(|i| {
            let (x, y) = (p.pos[0][i], p.pos[1][i]);
            let r = x.hypot(y);
            let vr = (x * p.vel[0][i] + y * p.vel[1][i]) / r;
            p.mass[i] * vr * vr
        })
        .sum();
    e.insert("disk_vr_rms_over_cs".to_string(), (vr2 / mt).sqrt() / cs_in);
    Ok(e)
}
