//! The viscously spreading ring (paper, Section 3.1; Lüst 1952, Pringle 1981): a thin gas
//! ring of mass M at radius R0 around a point mass, with constant kinematic viscosity ν, in
//! 2D. Particles are placed quietly on concentric rings (radial spacing R0/n, azimuthal
//! spacing about the same, alternate rings staggered) with masses that give the exact
//! Σ(R, τ0) of the Lüst solution, moving with the Keplerian velocity corrected for the
//! pressure gradient and with the exact viscous inflow velocity.
//!
//! The error is the L1 norm of the azimuthally averaged Σ against the exact Σ(R, τ),
//! relative to ∫Σ dR.

use std::collections::BTreeMap;

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

use crate::analysis::annulus_stats;
use crate::analysis::ring::SpreadingRing;
use crate::boundary::BoundaryKind;
use crate::config::{Config, RingParams};
use crate::particles::Particles;
use crate::physics::eos::Eos;
use crate::problems::{InitialState, make_box, smoothing_length};

/// What `summary.json` records of a ring run, so that it can be checked from its own output.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RingRecord {
    pub mass: f64,
    pub r0: f64,
    pub nu: f64,
    pub tau_start: f64,
    pub tau_end: f64,
    pub gm: f64,
    /// Radial spacing of the initial rings (the width of the averaging bins).
    pub spacing: f64,
}

impl RingRecord {
    /// Refuses a record the exact solution and the averaging cannot use (an edited or
    /// foreign `summary.json`), naming the entry: every figure positive and finite,
    /// τ_end > τ_start, annuli between 10⁻⁶ R0 and R0 wide, and Σ in units of M/(π R0²)
    /// representable.
    pub fn check(&self) -> Result<()> {
        for (name, v) in [
            ("mass", self.mass),
            ("r0", self.r0),
            ("nu", self.nu),
            ("tau_start", self.tau_start),
            ("gm", self.gm),
            ("spacing", self.spacing),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                bail!(
                    "`ring.{name}` must be a positive finite number, got {}",
                    show(v)
                );
            }
        }
        if !(self.tau_end > self.tau_start && self.tau_end.is_finite()) {
            bail!(
                "`ring.tau_end` must be finite and above `ring.tau_start` = {}, got {}",
                show(self.tau_start),
                show(self.tau_end)
            );
        }
        if !(self.spacing <= self.r0 && self.spacing >= 1e-6 * self.r0) {
            bail!(
                "`ring.spacing` = {} must lie between 1e-6 and 1 times `ring.r0` = {} (the \
                 width of the averaging annuli)",
                show(self.spacing),
                show(self.r0)
            );
        }
        let scale = std::f64::consts::PI * self.r0 * self.r0 / self.mass;
        let rate = 12.0 * self.nu / (self.r0 * self.r0);
        if !(scale.is_normal() && rate.is_normal()) {
            bail!(
                "`ring.r0` = {}, `ring.mass` = {} and `ring.nu` = {}: π R0²/M or 12 ν/R0² \
                 is out of range",
                show(self.r0),
                show(self.mass),
                show(self.nu)
            );
        }
        Ok(())
    }
}

/// A number as a message shows it: plainly, or with an exponent where it is huge or tiny.
fn show(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e6).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

fn params(cfg: &Config) -> RingParams {
    cfg.ring.clone().unwrap_or_default()
}

/// The exact solution and the figures of this run.
pub fn record(cfg: &Config) -> Result<RingRecord> {
    let r = params(cfg);
    let nu = match (cfg.viscosity.nu, cfg.viscosity.alpha) {
        (Some(nu), None) if nu > 0.0 => nu,
        _ => bail!("key `viscosity.nu`: the ring's exact solution needs a constant ν > 0"),
    };
    let gm = match &cfg.gravity {
        Some(g) => g.gm,
        None => bail!("key `gravity.gm`: the ring orbits a central mass; give [gravity] gm"),
    };
    Ok(RingRecord {
        mass: r.mass,
        r0: r.r0,
        nu,
        tau_start: r.tau_start,
        tau_end: r.tau_end,
        gm,
        spacing: r.r0 / cfg.particles.n.unwrap_or(1) as f64,
    })
}

pub fn exact(rec: &RingRecord) -> SpreadingRing {
    SpreadingRing {
        mass: rec.mass,
        r0: rec.r0,
        nu: rec.nu,
    }
}

/// τ at simulation time t (the run starts at τ_start).
pub fn tau_at(rec: &RingRecord, t: f64) -> f64 {
    rec.tau_start + 12.0 * rec.nu * t / (rec.r0 * rec.r0)
}

pub fn setup<const D: usize>(cfg: &Config) -> Result<InitialState<D>> {
    if D != 2 {
        bail!("key `problem.dimension`: the spreading ring is a 2D problem");
    }
    let rp = params(cfg);
    if !(rp.mass > 0.0 && rp.r0 > 0.0) {
        bail!("keys `ring.mass` and `ring.r0` must be > 0");
    }
    if !(rp.tau_start > 0.0 && rp.tau_end > rp.tau_start) {
        bail!("keys `ring.tau_start`, `ring.tau_end`: need 0 < tau_start < tau_end");
    }
    if !(rp.cutoff > 0.0 && rp.cutoff < 1.0) {
        bail!("key `ring.cutoff`: must lie in (0, 1)");
    }
    let rec = record(cfg)?;
    let sol = exact(&rec);
    let g = cfg.gravity.expect("checked by record");
    let n = cfg.particles.n.unwrap_or(0);
    let dr = rp.r0 / n as f64;
    let tau0 = rp.tau_start;
    let sigma = |r: f64| sol.sigma(r, tau0);
    let peak = (0..4000)
        .map(|k| sigma(k as f64 * 3.0 * rp.r0 / 4000.0))
        .fold(0.0, f64::max);
    // Ring radii r0 + k dr, outwards and inwards while Σ stays above the cut-off.
    let mut radii = Vec::new();
    for dir in [1i64, -1] {
        let mut k: i64 = if dir > 0 { 0 } else { -1 };
        loop {
            let r = rp.r0 + k as f64 * dr;
            if r <= 0.5 * dr || sigma(r) < rp.cutoff * peak {
                break;
            }
            radii.push((k, r));
            k += dir;
        }
    }
    radii.sort_by(|a, b| a.1.total_cmp(&b.1));
    if let Some(acc) = g.accretion_radius
        && radii.first().is_some_and(|&(_, r)| r <= acc)
    {
        bail!(
            "key `gravity.accretion_radius`: {acc} reaches into the ring (innermost particles at R = {:.4}); make it smaller",
            radii[0].1
        );
    }
    let cs2 = |r: f64| -> f64 {
        let (_, c) = cfg.eos.pressure_sound_speed(1.0, 0.0, r);
        c * c
    };
    let eps = 1e-5 * rp.r0;
    let mut p = Particles::new();
    for &(k, r) in &radii {
        let count = ((std::f64::consts::TAU * r / dr).round() as usize).max(1);
        let m = sigma(r) * std::f64::consts::TAU * r * dr / count as f64;
        // v_φ² = GM R²/(R² + ε²)^(3/2) + (R/Σ) dP/dR with P = c_s² Σ.
        let pres = |x: f64| cs2(x) * sigma(x);
        let dpdr = (pres(r + eps) - pres(r - eps)) / (2.0 * eps);
        let s2 = g.softening * g.softening;
        let vphi2 = g.gm * r * r / (r * r + s2).powf(1.5) + r / sigma(r) * dpdr;
        let vphi = vphi2.max(0.0).sqrt();
        // Exact viscous inflow: v_R = −3/(Σ √R) ∂(ν Σ √R)/∂R.
        let f = |x: f64| sigma(x) * x.sqrt();
        let vr = -3.0 * rec.nu / (sigma(r) * r.sqrt()) * (f(r + eps) - f(r - eps)) / (2.0 * eps);
        let offset = if k.rem_euclid(2) == 1 { 0.5 } else { 0.0 };
        for j in 0..count {
            let phi = std::f64::consts::TAU * (j as f64 + offset) / count as f64;
            let (s, c) = phi.sin_cos();
            let pos: [f64; D] = std::array::from_fn(|d| if d == 0 { r * c } else { r * s });
            let vel: [f64; D] = std::array::from_fn(|d| {
                if d == 0 {
                    vr * c - vphi * s
                } else {
                    vr * s + vphi * c
                }
            });
            let id = p.len() as u64;
            p.push(id, pos, vel, m, cfg.eos.internal_energy(1.0, 0.0));
        }
    }
    if !matches!(
        cfg.eos,
        Eos::Isothermal { .. } | Eos::LocallyIsothermal { .. } | Eos::Cold {}
    ) {
        bail!("key `eos.kind`: the ring uses an isothermal, locally_isothermal or cold gas");
    }
    let extent = 4.0 * rp.r0;
    let bx = make_box(cfg, [-extent; D], [extent; D], [BoundaryKind::Open; D]);
    for d in 0..D {
        let lo = radii.last().map_or(0.0, |r| r.1);
        if bx.kinds[d] != BoundaryKind::Open && (bx.min[d] > -lo || bx.max[d] < lo) {
            bail!("key `domain`: the ring (out to R = {lo:.3}) does not fit the box");
        }
    }
    let t_end = (rp.tau_end - tau0) * rp.r0 * rp.r0 / (12.0 * rec.nu);
    let output_times = rp
        .output_tau
        .iter()
        .filter(|&&tau| tau > tau0 && tau <= rp.tau_end)
        .map(|&tau| (tau - tau0) * rp.r0 * rp.r0 / (12.0 * rec.nu))
        .collect();
    Ok(InitialState {
        particles: p,
        bx,
        h: smoothing_length(cfg, dr),
        pressure_equilibrium: None,
        t_end: Some(t_end),
        output_times,
        injector: None,
    })
}

/// L1 norm of the azimuthally averaged Σ against the exact Σ at time t, relative to ∫Σ dR:
/// ∫|⟨Σ⟩ − Σ_exact| dR / ∫Σ_exact dR by the trapezoidal rule over the occupied annuli (one
/// ring spacing wide, at the particles' mean radius). The particles keep to rings as they
/// spread, so some annuli are empty; they are skipped, not counted as Σ = 0.
pub fn ring_l1<const D: usize>(rec: &RingRecord, p: &Particles<D>, t: f64) -> f64 {
    let sol = exact(rec);
    let tau = tau_at(rec, t);
    let bins: Vec<(f64, f64, f64)> = annulus_stats(p, rec.spacing)
        .into_iter()
        .filter(|b| b.count > 0)
        .map(|b| {
            let ex = sol.sigma(b.r, tau);
            (b.r, (b.mean - ex).abs(), ex)
        })
        .collect();
    let (mut num, mut den) = (0.0, 0.0);
    for w in bins.windows(2) {
        let dr = w[1].0 - w[0].0;
        num += 0.5 * (w[0].1 + w[1].1) * dr;
        den += 0.5 * (w[0].2 + w[1].2) * dr;
    }
    num / den
}

pub fn errors<const D: usize>(
    cfg: &Config,
    p: &Particles<D>,
    t: f64,
) -> Result<BTreeMap<String, f64>> {
    let rec = record(cfg)?;
    let mut e = BTreeMap::new();
    e.insert("ring_l1".to_string(), ring_l1(&rec, p, t));
    e.insert("ring_tau".to_string(), tau_at(&rec, t));
    Ok(e)
}
