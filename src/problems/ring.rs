//! The viscously spreading ring (paper, Section 3.1; Lüst 1952, Pringle 1981): a thin gas
//! ring of mass M at radius R0 around a point mass, with constant kinematic viscosity ν, in
//! 2D. Particles are placed quietly on concentric rings (radial spacing R0/n, azimuthal
//! spacing about the same, alternate rings staggered) with masses that give the exact
//! Σ(R, τ0) of the Lüst solution, moving with the Keplerian velocity corrected for the
//! pressure gradient and with the exact viscous inflow velocity. `ring.radial_jitter`
//! spreads each particle's radius across its ring's spacing (each particle's mass and
//! velocities then taken at its own radius).
//!
//! The error is the L1 norm of the azimuthally averaged Σ against the exact Σ(R, τ),
//! relative to ∫Σ dR; beside it, the share of the ring's annuli of 0.01 R0 that hold no
//! particle ([`ring_empty_annuli`]).

use std::collections::BTreeMap;

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

use crate::analysis::annulus_stats;
use crate::analysis::ring::SpreadingRing;
use crate::boundary::BoundaryKind;
use crate::config::{Config, RingParams};
use crate::limits::show;
use crate::particles::Particles;
use crate::physics::eos::Eos;
use crate::problems::{InitialState, make_box, ring_count, smoothing_length};
use crate::rng::Rng;

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

fn params(cfg: &Config) -> RingParams {
    cfg.ring.clone().unwrap_or_default()
}

/// The exact solution and the figures of this run.
pub fn record(cfg: &Config) -> Result<RingRecord> {
    let r = params(cfg);
    crate::limits::check_scale("ring.mass", r.mass).map_err(anyhow::Error::msg)?;
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
    if !(0.0..=1.0).contains(&rp.radial_jitter) {
        bail!(
            "key `ring.radial_jitter`: must lie in [0, 1] (a fraction of the ring spacing), got {}",
            rp.radial_jitter
        );
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
    if !(peak > 0.0 && peak.is_finite()) {
        bail!(
            "keys `ring.r0` and `ring.mass`: the ring's surface density at tau_start is {} at \
             its peak (r0 = {}, mass = {}), not a positive number",
            show(peak),
            show(rp.r0),
            show(rp.mass)
        );
    }
    // The ring at r0 alone holds 2π n particles: a run that cannot hold them is refused
    // before the radii are walked (up to 4 n of them).
    let budget = crate::limits::particle_budget::<D>()?;
    let at_r0 = std::f64::consts::TAU * n as f64;
    if !(at_r0 <= budget) {
        bail!(
            "key `particles.n`: {n} rings per r0 put {at_r0:.3e} particles on the ring at r0 \
             alone, more than the {budget:.3e} a run here can hold"
        );
    }
    // Ring radii r0 + k dr, outwards and inwards while Σ stays above the cut-off, and
    // inside the box (4 r0).
    let mut radii = Vec::new();
    for dir in [1i64, -1] {
        let mut k: i64 = if dir > 0 { 0 } else { -1 };
        loop {
            let r = rp.r0 + k as f64 * dr;
            if r <= 0.5 * dr || r >= 4.0 * rp.r0 || !(sigma(r) >= rp.cutoff * peak) {
                break;
            }
            radii.push((k, r));
            k += dir;
        }
    }
    radii.sort_by(|a, b| a.1.total_cmp(&b.1));
    // The particles, counted before any is made.
    let total: f64 = radii.iter().map(|&(_, r)| ring_count(r, dr) as f64).sum();
    crate::limits::check_particle_count::<D>(
        total,
        "key `particles.n`",
        &format!("the ring's {} rings", radii.len()),
        "particles.n",
    )?;
    // The innermost particle: its ring less half the jitter's width.
    let innermost = radii.first().map(|&(_, r)| r - 0.5 * rp.radial_jitter * dr);
    if let Some(acc) = g.accretion_radius
        && innermost.is_some_and(|r| r <= acc)
    {
        bail!(
            "key `gravity.accretion_radius`: {acc} reaches into the ring (innermost particles at R = {:.4}); make it smaller",
            innermost.unwrap_or(0.0)
        );
    }
    let cs2 = |r: f64| -> f64 {
        let (_, c) = cfg.eos.pressure_sound_speed(1.0, 0.0, r);
        c * c
    };
    let eps = 1e-5 * rp.r0;
    let s2 = g.softening * g.softening;
    // v_φ² = GM R²/(R² + ε²)^(3/2) + (R/Σ) dP/dR with P = c_s² Σ, and the exact viscous
    // inflow v_R = −3/(Σ √R) ∂(ν Σ √R)/∂R.
    let velocity = |r: f64| -> (f64, f64) {
        let pres = |x: f64| cs2(x) * sigma(x);
        let dpdr = (pres(r + eps) - pres(r - eps)) / (2.0 * eps);
        let vphi2 = g.gm * r * r / (r * r + s2).powf(1.5) + r / sigma(r) * dpdr;
        let f = |x: f64| sigma(x) * x.sqrt();
        let vr = -3.0 * rec.nu / (sigma(r) * r.sqrt()) * (f(r + eps) - f(r - eps)) / (2.0 * eps);
        (vphi2.max(0.0).sqrt(), vr)
    };
    let mut rng = Rng::new(cfg.particles.seed);
    let mut p = Particles::new();
    for &(k, r_ring) in &radii {
        let count = ring_count(r_ring, dr);
        let offset = if k.rem_euclid(2) == 1 { 0.5 } else { 0.0 };
        for j in 0..count {
            // Each particle carries the annulus Σ(R) 2πR Δr / count at its own radius, so
            // that a jittered ring still samples Σ where its particles lie.
            let r = if rp.radial_jitter > 0.0 {
                r_ring + rp.radial_jitter * dr * (rng.uniform() - 0.5)
            } else {
                r_ring
            };
            let m = sigma(r) * std::f64::consts::TAU * r * dr / count as f64;
            let (vphi, vr) = velocity(r);
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
        let lo = radii
            .last()
            .map_or(0.0, |r| r.1 + 0.5 * rp.radial_jitter * dr);
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

/// Width of the annuli of [`ring_empty_annuli`], in units of R0.
pub const EMPTY_ANNULUS_WIDTH: f64 = 0.01;

/// Most annuli [`ring_empty_annuli`] examines: out to 10⁴ R0 (τ ≈ 10⁶).
const MAX_EMPTY_ANNULI: usize = 1_000_000;

/// Share of the ring left without particles at time t: of the annuli of width
/// [`EMPTY_ANNULUS_WIDTH`] R0 (from R = 0) whose exact Σ at their centre exceeds 10% of the
/// exact peak, the fraction that hold no particle. Particles kept on rings spaced more than
/// one annulus apart leave the annuli between them empty (about half at a spacing of
/// 0.02 R0); a continuous distribution leaves none. The peak is the largest Σ on the annuli's
/// centres (within 0.2% of the true one for τ ≥ 0.016, where the ring's width √(τ/2) R0
/// spans ≥ 9 annuli).
pub fn ring_empty_annuli<const D: usize>(rec: &RingRecord, p: &Particles<D>, t: f64) -> f64 {
    let sol = exact(rec);
    let tau = tau_at(rec, t);
    let width = EMPTY_ANNULUS_WIDTH * rec.r0;
    // Out to R0 (2 + 10 √τ), more than 14 widths √(τ/2) R0 of the ring beyond R0, and at
    // most MAX_EMPTY_ANNULI annuli (a snapshot of an edited run at a huge τ).
    let reach = rec.r0 * (2.0 + 10.0 * tau.sqrt());
    let nb = ((reach / width).ceil() as usize).min(MAX_EMPTY_ANNULI);
    let exact_sigma: Vec<f64> = (0..nb)
        .map(|k| sol.sigma((k as f64 + 0.5) * width, tau))
        .collect();
    let peak = exact_sigma.iter().copied().fold(0.0, f64::max);
    let mut occupied = vec![false; nb];
    for i in 0..p.len() {
        let r = (0..D.min(2))
            .map(|d| p.pos[d][i].powi(2))
            .sum::<f64>()
            .sqrt();
        let b = (r / width).floor();
        if b < nb as f64 {
            occupied[b as usize] = true;
        }
    }
    let (mut inside, mut empty) = (0usize, 0usize);
    for (s, occ) in exact_sigma.iter().zip(&occupied) {
        if *s > 0.1 * peak {
            inside += 1;
            if !occ {
                empty += 1;
            }
        }
    }
    empty as f64 / inside.max(1) as f64
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
    e.insert(
        "ring_empty_annuli".to_string(),
        ring_empty_annuli(&rec, p, t),
    );
    Ok(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_record() -> RingRecord {
        RingRecord {
            mass: 1.0,
            r0: 1.0,
            nu: 1e-3,
            tau_start: 0.016,
            tau_end: 0.128,
            gm: 1.0,
            spacing: 0.02,
        }
    }

    /// Eight particles on each ring R = first + k spacing below `end`.
    fn rings(p: &mut Particles<2>, first: f64, spacing: f64, end: f64) {
        let mut k = 0;
        while first + k as f64 * spacing < end {
            let r = first + k as f64 * spacing;
            for j in 0..8 {
                let (s, c) = (std::f64::consts::TAU * j as f64 / 8.0).sin_cos();
                p.push(p.len() as u64, [r * c, r * s], [0.0; 2], 1.0, 0.0);
            }
            k += 1;
        }
    }

    #[test]
    fn rings_two_annuli_apart_leave_half_the_annuli_empty() {
        let rec = unit_record();
        // t = 4 is τ = 0.064, where the exact Σ exceeds 10% of its peak in the 78 annuli
        // from R = 0.58 to 1.36 (the edge annuli at 10.07% and 11.0% of the peak, their
        // outer neighbours at 8.9% and 9.8%: far from the threshold).
        let t = 4.0;
        assert!((tau_at(&rec, t) - 0.064).abs() < 1e-15);
        let count = |empty: usize| empty as f64 / 78.0;
        // Rings 0.02 R0 apart, at the centres of the even annuli: the 39 odd ones of the
        // 78 are empty.
        let mut p = Particles::new();
        rings(&mut p, 0.005, 0.02, 2.5);
        assert_eq!(ring_empty_annuli(&rec, &p, t), count(39));
        // 0.005 R0 apart, two rings in every annulus: none is empty.
        let mut p = Particles::new();
        rings(&mut p, 0.0025, 0.005, 2.5);
        assert_eq!(ring_empty_annuli(&rec, &p, t), 0.0);
        // 0.02 R0 apart inside R = 0.8, 0.005 R0 outside: the odd annuli from 0.59 to
        // 0.79 are empty, 11 of the 78.
        let mut p = Particles::new();
        rings(&mut p, 0.005, 0.02, 0.8);
        rings(&mut p, 0.8025, 0.005, 2.5);
        assert_eq!(ring_empty_annuli(&rec, &p, t), count(11));
        // No particle where the ring is: all are empty.
        let mut p = Particles::new();
        rings(&mut p, 2.0025, 0.005, 2.5);
        assert_eq!(ring_empty_annuli(&rec, &p, t), 1.0);
    }

    fn load(sets: &[&str]) -> Config {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/ring.toml");
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        Config::load(&path, &sets).expect("ring.toml loads")
    }

    /// Rings R0/35 apart (2.86 annuli: one ring in seven on an annulus's edge, in either
    /// annulus by round-off) leave 60–65% of the annuli empty from the start; jittered
    /// across their spacing they leave none (each annulus then expects ~70 particles from
    /// each ring that covers it).
    #[test]
    fn radial_jitter_fills_the_annuli_between_the_rings() {
        let on_rings = load(&["particles.n=35"]);
        let jittered = load(&["particles.n=35", "ring.radial_jitter=1"]);
        let rec = record(&on_rings).unwrap();
        let a = setup::<2>(&on_rings).unwrap().particles;
        let b = setup::<2>(&jittered).unwrap().particles;
        assert_eq!(a.len(), b.len());
        let empty_a = ring_empty_annuli(&rec, &a, 0.0);
        let empty_b = ring_empty_annuli(&rec, &b, 0.0);
        assert!(empty_a > 0.55 && empty_a < 0.7, "on rings: {empty_a}");
        assert_eq!(empty_b, 0.0);
        // Each particle's mass follows Σ at its own radius. Over a Gaussian ring the
        // uniform jitter leaves the expected total unchanged to second order in Δr/σ
        // (the curvature term averages to zero); what remains is sampling noise, a few
        // 1e-4 for ~5 000 particles whose masses vary by tens of percent across a
        // spacing. 1% would be a mass assigned at the wrong radius.
        let (ma, mb): (f64, f64) = (a.mass.iter().sum(), b.mass.iter().sum());
        eprintln!(
            "on rings: {empty_a} empty, {} particles, mass {ma}; jittered: {mb}",
            a.len()
        );
        assert!((mb / ma - 1.0).abs() < 1e-2, "{ma} {mb}");
        // Particles keep within half a spacing of their rings.
        let ra = |p: &Particles<2>, i: usize| p.pos[0][i].hypot(p.pos[1][i]);
        let far = (0..a.len())
            .map(|i| (ra(&a, i) - ra(&b, i)).abs())
            .fold(0.0, f64::max);
        assert!(far <= 0.5 * rec.spacing && far > 0.4 * rec.spacing, "{far}");
        for bad in ["-0.1", "1.5", "nan"] {
            let sets = vec![format!("ring.radial_jitter={bad}")];
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/ring.toml");
            let e = Config::load(&path, &sets)
                .and_then(|c| setup::<2>(&c).map(|_| ()))
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            assert!(e.contains("ring.radial_jitter"), "{bad}: {e}");
        }
    }
}
