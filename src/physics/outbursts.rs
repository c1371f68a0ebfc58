//! The dwarf-nova disk instability (Osaki 1989's thermal–tidal model; paper, Section 4):
//! disk gas lives on one of two branches of the thermal-equilibrium S-curve, cold (neutral
//! hydrogen, low viscosity) or hot (ionised, high viscosity), and jumps between them at the
//! surface densities where a branch ends (Cannizzo, Shafter & Wheeler 1988):
//!
//!   cold → hot where Σ > Σ_max(R),  hot → cold where Σ < Σ_min(R),
//!   Σ_max,min(R) = Σ_max,min(r0) · (R / r0)^s,  s = 1.05 (Cannizzo et al.),
//!
//! which is the parametrisation Truss et al. (2000, MNRAS 319, 467) used for SPH. Between the
//! thresholds a particle keeps its branch (the hysteresis of the S-curve).
//!
//! The branch is carried by the internal energy u alone (no extra particle state): the gas is
//! an ideal gas whose u relaxes on the thermal time β/Ω_K towards the branch's target
//! u_c or u_h (sound speeds `cs_cold`, `cs_hot`, u = c_s² / (γ(γ − 1)) as in `cooling`);
//! a particle is hot while u lies above the mid-point (u_c + u_h)/2. The relaxation replaces
//! the energy equation's compression and dissipation terms: on either branch heating and
//! cooling balance (that is what an S-curve branch is), and the dissipated energy leaves as
//! light — `lightcurve.csv` records it. The shear viscosity follows the branch smoothly,
//!
//!   ν = α(c_s) c_s² / Ω_K (Eqs. 8–10 with ν = α c_s H),
//!   α(c_s) = α_c + (α_h − α_c) · clamp((c_s² − c_c²) / (c_h² − c_c²), 0, 1),
//!
//! so a heating front switches on α_h over a thermal time and a cooling front switches it
//! off.
//!
//! Between the thresholds the S-curve has a third, unstable branch (Cannizzo et al. 1988;
//! Lasota 2001, Fig. 3), which `unstable_branch = true` makes literal, straight in u
//! between the ends of the stable branches:
//!
//!   u_mid(Σ) = u_c + (u_h − u_c) (Σ_max − Σ) / (Σ_max − Σ_min),
//!
//! and gas above u_mid heads for the hot branch, below it for the cold one. A heating
//! transition begun where Σ passed Σ_max then runs on when Σ falls back a little (u_mid
//! lies just above u_c there): the thermal runaway. Without it (the default) the branch
//! flips at the mid-point of the targets, and gas whose noisy SPH Σ wanders about Σ_max
//! keeps turning back half-heated.
//!
//! The relaxation acts on each particle alone: nothing carries heat between neighbours, so
//! gas between the thresholds keeps its branch particle by particle, and an annulus can
//! stay a salt-and-pepper mixture of hot and cold gas at the same Σ where a real disk has
//! one state and fronts between states (Menou, Hameury & Stehle 1999: fronts move by the
//! radial transport of heat and mass). `transport = true` keeps the energy equation's
//! compression work and the artificial conductivity's heat exchange between neighbours
//! (Price 2008; `artificial_viscosity.conductivity`, with the pressure signal) beside the
//! relaxation, which then replaces only the dissipation:
//!
//!   du_i/dt = −(u_i − u_branch) Ω_K/β + (du_i/dt)_work + (du_i/dt)_conduction,
//!
//! so that a hot particle among cold neighbours loses its heat to them and a mixed annulus
//! settles on one branch. Σ is the particle's density in 2D (the density of a 2D SPH disk is its surface
//! density) and √(2π) ρ H in 3D (H = c_s/Ω_K, the midplane estimate).

use serde::{Deserialize, Serialize};

use crate::particles::Particles;
use crate::physics::eos::{Eos, cylindrical_radius};
use crate::physics::gravity::PointMass;

/// `[outbursts]` of a problem file: the two branches and the thresholds between them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Outbursts {
    /// Shakura–Sunyaev α on the cold branch (quiescence; 0.01–0.03 in the literature).
    pub alpha_cold: f64,
    /// α on the hot branch (outburst; 0.1–0.2).
    pub alpha_hot: f64,
    /// Sound speed of the cold branch (code units; also give the stream this c_s).
    pub cs_cold: f64,
    /// Sound speed of the hot branch.
    pub cs_hot: f64,
    /// Σ_max at `r0`: above it cold gas turns hot.
    pub sigma_max: f64,
    /// Σ_min at `r0`: below it hot gas turns cold.
    pub sigma_min: f64,
    /// Radius at which the thresholds are given (default 1 a).
    #[serde(default = "one")]
    pub r0: f64,
    /// The thresholds scale as R^slope (default 1.05, Cannizzo et al. 1988).
    #[serde(default = "default_slope")]
    pub slope: f64,
    /// Thermal time in units of 1/Ω_K (default 1).
    #[serde(default = "one")]
    pub beta: f64,
    /// Whether gas between the thresholds follows the S-curve's unstable middle branch
    /// (default false: the branch flips at the mid-point of the targets). With it a
    /// transition, once begun, runs away to the other branch (module doc).
    #[serde(default)]
    pub unstable_branch: bool,
    /// Whether the energy equation's compression work and conduction between neighbours
    /// act beside the relaxation (default false: the relaxation replaces all of du/dt;
    /// module doc).
    #[serde(default)]
    pub transport: bool,
}

fn one() -> f64 {
    1.0
}
fn default_slope() -> f64 {
    1.05
}

/// The branch a particle is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Branch {
    Cold,
    Hot,
}

impl Outbursts {
    /// One line naming the offending key, or Ok.
    pub fn validate(
        &self,
        eos: &Eos,
        has_central_mass: bool,
        dimension: usize,
    ) -> Result<(), String> {
        for (k, v) in [
            ("alpha_cold", self.alpha_cold),
            ("alpha_hot", self.alpha_hot),
        ] {
            if !(v > 0.0 && v <= 1.0) {
                return Err(format!("key `outbursts.{k}`: must be > 0 and ≤ 1, got {v}"));
            }
        }
        if self.alpha_cold > self.alpha_hot {
            return Err(format!(
                "key `outbursts.alpha_cold`: must not exceed alpha_hot = {}, got {}",
                self.alpha_hot, self.alpha_cold
            ));
        }
        for (k, v) in [("cs_cold", self.cs_cold), ("cs_hot", self.cs_hot)] {
            if !(v > 0.0 && v < 1.0) {
                return Err(format!(
                    "key `outbursts.{k}`: must be > 0 and < 1 (the orbital speed), got {v}"
                ));
            }
        }
        if self.cs_cold >= self.cs_hot {
            return Err(format!(
                "key `outbursts.cs_cold`: must be below cs_hot = {}, got {}",
                self.cs_hot, self.cs_cold
            ));
        }
        for (k, v) in [("sigma_max", self.sigma_max), ("sigma_min", self.sigma_min)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("key `outbursts.{k}`: must be > 0, got {v}"));
            }
        }
        if self.sigma_min >= self.sigma_max {
            return Err(format!(
                "key `outbursts.sigma_min`: must be below sigma_max = {} (the S-curve's hysteresis), got {}",
                self.sigma_max, self.sigma_min
            ));
        }
        if !(self.r0 > 0.0 && self.r0.is_finite()) {
            return Err(format!("key `outbursts.r0`: must be > 0, got {}", self.r0));
        }
        if !(self.slope.abs() <= 3.0) {
            return Err(format!(
                "key `outbursts.slope`: must lie in [−3, 3], got {}",
                self.slope
            ));
        }
        if !(self.beta > 0.0 && self.beta <= 1e6) {
            return Err(format!(
                "key `outbursts.beta`: must be > 0 and ≤ 1e6, got {}",
                self.beta
            ));
        }
        if !matches!(eos, Eos::Ideal { .. }) {
            return Err(
                "table `[outbursts]`: the branch lives in the internal energy; it needs eos.kind = \"ideal\""
                    .into(),
            );
        }
        if !has_central_mass {
            return Err(
                "table `[outbursts]`: ν = α c_s H and the thermal time need a central mass ([binary] or [gravity])"
                    .into(),
            );
        }
        if dimension < 2 {
            return Err("table `[outbursts]`: a disk needs problem.dimension = 2 or 3".into());
        }
        Ok(())
    }

    /// Target internal energy of a branch for adiabatic index `gamma`.
    pub fn branch_u(&self, gamma: f64, branch: Branch) -> f64 {
        let cs = match branch {
            Branch::Cold => self.cs_cold,
            Branch::Hot => self.cs_hot,
        };
        cs * cs / (gamma * (gamma - 1.0))
    }

    /// The branch of gas with internal energy `u`: hot above the mid-point of the targets.
    pub fn branch(&self, gamma: f64, u: f64) -> Branch {
        let mid = 0.5 * (self.branch_u(gamma, Branch::Cold) + self.branch_u(gamma, Branch::Hot));
        if u > mid { Branch::Hot } else { Branch::Cold }
    }

    /// (Σ_min, Σ_max) at cylindrical radius `r`.
    pub fn thresholds(&self, r: f64) -> (f64, f64) {
        let s = (r.max(1e-12 * self.r0) / self.r0).powf(self.slope);
        (self.sigma_min * s, self.sigma_max * s)
    }

    /// The branch gas on `branch` with surface density `sigma` at radius `r` heads for.
    pub fn next_branch(&self, branch: Branch, sigma: f64, r: f64) -> Branch {
        let (lo, hi) = self.thresholds(r);
        match branch {
            Branch::Cold if sigma > hi => Branch::Hot,
            Branch::Hot if sigma < lo => Branch::Cold,
            b => b,
        }
    }

    /// α for a particle with sound speed `cs` (interpolated in c_s² between the branches).
    #[inline]
    pub fn alpha(&self, cs: f64) -> f64 {
        let (c2, h2) = (self.cs_cold * self.cs_cold, self.cs_hot * self.cs_hot);
        let x = ((cs * cs - c2) / (h2 - c2)).clamp(0.0, 1.0);
        self.alpha_cold + (self.alpha_hot - self.alpha_cold) * x
    }

    /// ν = α(c_s) c_s² / Ω_K at distance `r` from a central mass `gm`.
    #[inline]
    pub fn nu(&self, cs: f64, r: f64, gm: f64) -> f64 {
        let omega = (gm / (r * r * r).max(f64::MIN_POSITIVE)).sqrt();
        self.alpha(cs) * cs * cs / omega
    }

    /// Surface density from a particle's density `rho`, sound speed `cs`, at radius `r`
    /// about `gm`, in `dimension` dimensions.
    pub fn surface_density(rho: f64, cs: f64, r: f64, gm: f64, dimension: usize) -> f64 {
        if dimension == 2 {
            return rho;
        }
        let omega = (gm / (r * r * r).max(f64::MIN_POSITIVE)).sqrt();
        (std::f64::consts::TAU).sqrt() * rho * cs / omega
    }

    /// The branch gas with internal energy `u` and surface density `sigma` at radius `r`
    /// heads for: past a threshold the other branch; between them its own (the mid-point
    /// rule) or the side of the unstable middle branch u_mid(Σ) it lies on.
    pub fn target(&self, gamma: f64, u: f64, sigma: f64, r: f64) -> Branch {
        if !self.unstable_branch {
            return self.next_branch(self.branch(gamma, u), sigma, r);
        }
        let (lo, hi) = self.thresholds(r);
        if sigma > hi {
            return Branch::Hot;
        }
        if sigma < lo {
            return Branch::Cold;
        }
        let (uc, uh) = (
            self.branch_u(gamma, Branch::Cold),
            self.branch_u(gamma, Branch::Hot),
        );
        let u_mid = uc + (uh - uc) * (hi - sigma) / (hi - lo);
        if u > u_mid { Branch::Hot } else { Branch::Cold }
    }

    /// du/dt of a particle: relaxation towards the branch it heads for ([`Self::target`]).
    #[inline]
    pub fn rate(&self, gamma: f64, g: &PointMass, u: f64, sigma: f64, r: f64) -> f64 {
        let r = r.max(f64::MIN_POSITIVE);
        let omega = (g.gm / (r * r * r)).sqrt();
        let target = self.target(gamma, u, sigma, r);
        -(u - self.branch_u(gamma, target)) * omega / self.beta
    }

    /// Replaces every particle's du/dt by the relaxation towards its branch (after the
    /// sweep, which set ρ, c_s, du/dt and the dissipation); with `transport` the sweep's
    /// du/dt less its dissipation (the compression work and the conduction) stays.
    pub fn set_rates<const D: usize>(&self, p: &mut Particles<D>, eos: &Eos, g: &PointMass) {
        let Eos::Ideal { gamma } = *eos else { return };
        for i in 0..p.len() {
            let r = cylindrical_radius(&p.position(i));
            let sigma = Self::surface_density(p.rho[i], p.cs[i], r, g.gm, D);
            let kept = if self.transport {
                p.du[i] - p.diss[i]
            } else {
                0.0
            };
            p.du[i] = self.rate(gamma, g, p.u[i], sigma, r) + kept;
        }
    }

    /// (mass on the hot branch, total mass) of `p`, for the run's monitor.
    pub fn hot_mass<const D: usize>(&self, p: &Particles<D>, eos: &Eos) -> (f64, f64) {
        let Eos::Ideal { gamma } = *eos else {
            return (0.0, 0.0);
        };
        let mut hot = 0.0;
        let mut all = 0.0;
        for i in 0..p.len() {
            all += p.mass[i];
            if self.branch(gamma, p.u[i]) == Branch::Hot {
                hot += p.mass[i];
            }
        }
        (hot, all)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> Outbursts {
        Outbursts {
            alpha_cold: 0.02,
            alpha_hot: 0.2,
            cs_cold: 0.025,
            cs_hot: 0.05,
            sigma_max: 2.0,
            sigma_min: 1.0,
            r0: 0.5,
            slope: 1.05,
            beta: 2.0,
            unstable_branch: false,
            transport: false,
        }
    }

    const GAMMA: f64 = 5.0 / 3.0;

    #[test]
    fn the_s_curve_has_hysteresis() {
        let m = model();
        let r = 0.5;
        // Between the thresholds each branch keeps itself.
        assert_eq!(m.next_branch(Branch::Cold, 1.5, r), Branch::Cold);
        assert_eq!(m.next_branch(Branch::Hot, 1.5, r), Branch::Hot);
        // Past them it jumps.
        assert_eq!(m.next_branch(Branch::Cold, 2.01, r), Branch::Hot);
        assert_eq!(m.next_branch(Branch::Hot, 0.99, r), Branch::Cold);
        // The thresholds scale as R^1.05: at 2 r0 Σ_max is 2^1.05 · 2 = 4.14.
        let (lo, hi) = m.thresholds(1.0);
        assert!((hi - 2.0 * 2f64.powf(1.05)).abs() < 1e-12 && (lo - 2f64.powf(1.05)).abs() < 1e-12);
        assert_eq!(m.next_branch(Branch::Cold, 4.0, 1.0), Branch::Cold);
        assert_eq!(m.next_branch(Branch::Cold, 4.2, 1.0), Branch::Hot);
    }

    #[test]
    fn transport_keeps_the_work_and_conduction_beside_the_relaxation() {
        // One particle at R = 0.5 with the sweep's du/dt = 5 of which 3 is dissipation:
        // without transport du/dt is the relaxation alone, with it the relaxation + 2.
        let g = PointMass {
            gm: 1.0,
            softening: 0.0,
            accretion_radius: None,
        };
        let eos = Eos::Ideal { gamma: GAMMA };
        let mut m = model();
        let u = 0.5 * (m.branch_u(GAMMA, Branch::Cold) + m.branch_u(GAMMA, Branch::Hot));
        let mut p = Particles::<2>::new();
        p.push(0, [0.5, 0.0], [0.0, 0.0], 1.0, u);
        p.rho[0] = 1.5;
        let relax = m.rate(GAMMA, &g, u, 1.5, 0.5);
        assert!(relax != 0.0);
        for (transport, kept) in [(false, 0.0), (true, 2.0)] {
            m.transport = transport;
            (p.du[0], p.diss[0]) = (5.0, 3.0);
            m.set_rates(&mut p, &eos, &g);
            assert!(
                (p.du[0] - (relax + kept)).abs() < 1e-12,
                "{transport}: {}",
                p.du[0]
            );
        }
    }

    #[test]
    fn u_relaxes_to_the_branch_on_beta_over_omega() {
        let m = model();
        let g = PointMass {
            gm: 1.0,
            softening: 0.0,
            accretion_radius: None,
        };
        let (uc, uh) = (
            m.branch_u(GAMMA, Branch::Cold),
            m.branch_u(GAMMA, Branch::Hot),
        );
        assert!((uh / uc - 4.0).abs() < 1e-12);
        let r: f64 = 0.25; // Ω = 8
        // Cold gas below Σ_max stays at u_c; above it heads for u_h at (u_h − u_c) Ω / β.
        let (_, hi) = m.thresholds(r);
        assert_eq!(m.rate(GAMMA, &g, uc, 0.99 * hi, r), 0.0);
        let heating = m.rate(GAMMA, &g, uc, 1.01 * hi, r);
        assert!((heating - (uh - uc) * 8.0 / 2.0).abs() < 1e-15);
        // Hot gas above Σ_min stays hot, even with Σ below Σ_max.
        assert_eq!(m.rate(GAMMA, &g, uh, 0.99 * hi, r), 0.0);
        assert!(m.rate(GAMMA, &g, uh, 0.5 * m.thresholds(r).0, r) < 0.0);
        // The branch flips at the mid-point of the targets.
        assert_eq!(m.branch(GAMMA, 0.49 * (uc + uh)), Branch::Cold);
        assert_eq!(m.branch(GAMMA, 0.51 * (uc + uh)), Branch::Hot);
    }

    #[test]
    fn on_the_unstable_branch_a_begun_transition_runs_away() {
        let mut m = model();
        let r = 0.5;
        let (lo, hi) = m.thresholds(r);
        let (uc, uh) = (
            m.branch_u(GAMMA, Branch::Cold),
            m.branch_u(GAMMA, Branch::Hot),
        );
        // Gas 15% of the way from u_c to u_h, heated while Σ was past Σ_max, with Σ back
        // at 0.95 Σ_max = 1.9: u_mid lies (2 − 1.9) / (2 − 1) = 10% of the way.
        let u = uc + 0.15 * (uh - uc);
        let sigma = 0.95 * hi;
        let u_mid = uc + (uh - uc) * (hi - sigma) / (hi - lo);
        assert!(u > u_mid);
        // The mid-point rule turns it back to cold; the unstable branch carries it on.
        assert_eq!(m.target(GAMMA, u, sigma, r), Branch::Cold);
        m.unstable_branch = true;
        assert_eq!(m.target(GAMMA, u, sigma, r), Branch::Hot);
        // A cooling transition likewise: 90% of the way up with Σ just above Σ_min.
        let u = uc + 0.9 * (uh - uc);
        assert_eq!(m.target(GAMMA, u, 1.05 * lo, r), Branch::Cold);
        // The stable branches keep themselves between the thresholds, and the
        // thresholds still force the jump.
        let mid_sigma = 0.5 * (lo + hi);
        assert_eq!(m.target(GAMMA, uc, mid_sigma, r), Branch::Cold);
        assert_eq!(m.target(GAMMA, uh, mid_sigma, r), Branch::Hot);
        assert_eq!(m.target(GAMMA, uc, 1.001 * hi, r), Branch::Hot);
        assert_eq!(m.target(GAMMA, uh, 0.999 * lo, r), Branch::Cold);
    }

    #[test]
    fn alpha_follows_the_branch() {
        let m = model();
        assert_eq!(m.alpha(0.025), 0.02);
        assert_eq!(m.alpha(0.01), 0.02);
        assert_eq!(m.alpha(0.05), 0.2);
        assert_eq!(m.alpha(0.08), 0.2);
        // Half-way in c_s² is half-way in α.
        let mid = ((0.025f64.powi(2) + 0.05f64.powi(2)) / 2.0).sqrt();
        assert!((m.alpha(mid) - 0.11).abs() < 1e-15);
        // ν = α c_s² / Ω: hot over cold is (0.2/0.02)·4 = 40 at one radius.
        assert!((m.nu(0.05, 0.3, 1.0) / m.nu(0.025, 0.3, 1.0) - 40.0).abs() < 1e-12);
    }

    #[test]
    fn validation_names_the_key() {
        let eos = Eos::Ideal { gamma: GAMMA };
        assert!(model().validate(&eos, true, 2).is_ok());
        let mut m = model();
        m.sigma_min = 3.0;
        assert!(
            m.validate(&eos, true, 2)
                .unwrap_err()
                .contains("outbursts.sigma_min")
        );
        let mut m = model();
        m.cs_cold = 0.06;
        assert!(
            m.validate(&eos, true, 2)
                .unwrap_err()
                .contains("outbursts.cs_cold")
        );
        let mut m = model();
        m.alpha_hot = f64::NAN;
        assert!(
            m.validate(&eos, true, 2)
                .unwrap_err()
                .contains("outbursts.alpha_hot")
        );
        assert!(
            model()
                .validate(&Eos::Isothermal { cs: 0.05 }, true, 2)
                .unwrap_err()
                .contains("ideal")
        );
        assert!(model().validate(&eos, false, 2).is_err());
        assert!(model().validate(&eos, true, 1).is_err());
    }
}
