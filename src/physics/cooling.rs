//! Simple cooling for disks with an energy equation (the "β cooling" of disk simulations,
//! e.g. Gammie 2001): the specific internal energy relaxes towards that of a set sound-speed
//! profile on a time β/Ω_K(R) about the central mass,
//!
//!   (du/dt)_cool = −(u − u₀(R)) Ω_K(R) / β,   u₀ = c_s(R)² / (γ (γ − 1)),
//!   c_s(R) = cs0 (R / r0)^(−q),  Ω_K = √(GM / R³),
//!
//! so that a disk keeps its temperature where nothing heats it, while shock heating (the
//! bright spot, where the stream strikes the rim) and viscous heating show as gas hotter than
//! u₀ for about a cooling time. With `heats = false` the term only cools,
//!
//!   (du/dt)_cool = −max(0, u − u₀(R)) Ω_K(R) / β,
//!
//! as radiative cooling does: gas that expanded below u₀ — the stream, cooling adiabatically
//! from L1 — keeps its lower temperature until a shock or the viscosity heats it, so a stream
//! cooler than the disk (the donor's ~3000 K against the disk's 10⁴ K) reaches the rim cool.
//! The term is added to du/dt after the sweep, as the external gravity is; the energy
//! criterion of the time step covers it.

use serde::{Deserialize, Serialize};

use crate::particles::Particles;
use crate::physics::eos::{Eos, cylindrical_radius};
use crate::physics::gravity::PointMass;

/// `[cooling]` of a problem file (needs `eos.kind = "ideal"` and a central mass).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cooling {
    /// Cooling time in units of the local 1/Ω_K.
    pub beta: f64,
    /// Sound speed of the target profile at `r0`.
    pub cs0: f64,
    /// Reference radius of the profile (default 1).
    #[serde(default = "one")]
    pub r0: f64,
    /// Power-law index: c_s ∝ R^(−q) (default 0, an isothermal target).
    #[serde(default)]
    pub q: f64,
    /// Whether the relaxation also heats gas cooler than u₀ (default true); false: it only
    /// cools, as radiation does.
    #[serde(default = "yes")]
    pub heats: bool,
}

fn one() -> f64 {
    1.0
}

fn yes() -> bool {
    true
}

impl Cooling {
    /// One line naming the offending key, or Ok.
    /// `central_gm`: G M of the central mass (the accretor's in a binary), if there is one.
    pub fn validate(&self, eos: &Eos, central_gm: Option<f64>) -> Result<(), String> {
        if !(self.beta > 0.0 && self.beta <= 1e6) {
            return Err(format!(
                "key `cooling.beta`: must be > 0 and ≤ 1e6 (orbits' worth of 1/Ω), got {}",
                self.beta
            ));
        }
        if !(self.cs0 > 0.0 && self.cs0.is_finite()) {
            return Err(format!(
                "key `cooling.cs0`: must be > 0, got {}",
                crate::limits::show(self.cs0)
            ));
        }
        if !(self.r0 > 0.0 && self.r0.is_finite()) {
            return Err(format!("key `cooling.r0`: must be > 0, got {}", self.r0));
        }
        if !(self.q.abs() <= 3.0) {
            return Err(format!(
                "key `cooling.q`: must lie in [−3, 3], got {}",
                self.q
            ));
        }
        if !matches!(eos, Eos::Ideal { .. }) {
            return Err(
                "table `[cooling]`: cooling acts on the internal energy; it needs eos.kind = \"ideal\""
                    .into(),
            );
        }
        let Some(gm) = central_gm else {
            return Err(
                "table `[cooling]`: the cooling time β/Ω_K needs a central mass ([gravity] or [binary])"
                    .into(),
            );
        };
        // A target sound speed as fast as the orbit at r0 is no disk's (cs0 = 1e300 made the
        // first step's internal energy NaN, and the message blamed the time step).
        let orbital = (gm / self.r0).sqrt();
        if !(self.cs0 < orbital) {
            return Err(format!(
                "key `cooling.cs0`: must be below the orbital speed at cooling.r0, √(GM/r0) = \
                 {orbital:.4}, got {}",
                crate::limits::show(self.cs0)
            ));
        }
        Ok(())
    }

    /// The target specific internal energy at cylindrical radius `r` for adiabatic index
    /// `gamma`.
    pub fn target_u(&self, gamma: f64, r: f64) -> f64 {
        let cs = self.cs0 * (r.max(1e-12 * self.r0) / self.r0).powf(-self.q);
        cs * cs / (gamma * (gamma - 1.0))
    }

    /// (du/dt)_cool of gas with internal energy `u` at radius `r` about a central mass.
    #[inline]
    pub fn rate(&self, gamma: f64, g: &PointMass, u: f64, r: f64) -> f64 {
        let r = r.max(f64::MIN_POSITIVE);
        let omega = (g.gm / (r * r * r)).sqrt();
        let excess = u - self.target_u(gamma, r);
        let excess = if self.heats { excess } else { excess.max(0.0) };
        -excess * omega / self.beta
    }

    /// Adds the cooling term to every particle's du/dt.
    pub fn add_to<const D: usize>(&self, p: &mut Particles<D>, eos: &Eos, g: &PointMass) {
        let Eos::Ideal { gamma } = *eos else { return };
        for i in 0..p.len() {
            let r = cylindrical_radius(&p.position(i));
            p.du[i] += self.rate(gamma, g, p.u[i], r);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relaxes_towards_the_profile_on_beta_over_omega() {
        let c = Cooling {
            beta: 2.0,
            cs0: 0.05,
            r0: 1.0,
            q: 0.5,
            heats: true,
        };
        let g = PointMass {
            gm: 1.0,
            softening: 0.0,
            accretion_radius: None,
        };
        let gamma = 5.0 / 3.0;
        let r = 0.25;
        let u0 = c.target_u(gamma, r);
        // c_s(0.25) = 0.05 · 0.25^(−0.5) = 0.1.
        assert!((u0 - 0.01 / (gamma * (gamma - 1.0))).abs() < 1e-15);
        assert_eq!(c.rate(gamma, &g, u0, r), 0.0);
        // Ω(0.25) = 8: twice the target cools at (u − u0) · 8 / 2.
        assert!((c.rate(gamma, &g, 2.0 * u0, r) + 4.0 * u0).abs() < 1e-15);
        assert!(c.rate(gamma, &g, 0.5 * u0, r) > 0.0);
    }

    /// Cooling only: gas hotter than u₀ cools exactly as with two-sided relaxation, gas
    /// cooler than u₀ (the stream after its adiabatic expansion) is left alone.
    #[test]
    fn cooling_only_leaves_cooler_gas_alone() {
        let both = Cooling {
            beta: 2.0,
            cs0: 0.05,
            r0: 1.0,
            q: 0.5,
            heats: true,
        };
        let only = Cooling {
            heats: false,
            ..both
        };
        let g = PointMass {
            gm: 1.0,
            softening: 0.0,
            accretion_radius: None,
        };
        let gamma = 5.0 / 3.0;
        for r in [0.1, 0.25, 0.7] {
            let u0 = both.target_u(gamma, r);
            for f in [1.01, 2.0, 300.0] {
                assert_eq!(
                    only.rate(gamma, &g, f * u0, r),
                    both.rate(gamma, &g, f * u0, r)
                );
            }
            for f in [0.0, 0.1, 0.99] {
                assert!(both.rate(gamma, &g, f * u0, r) > 0.0);
                assert_eq!(only.rate(gamma, &g, f * u0, r), 0.0);
            }
            assert_eq!(only.rate(gamma, &g, u0, r), 0.0);
        }
    }

    #[test]
    fn needs_an_energy_equation_and_a_central_mass() {
        let c = Cooling {
            beta: 1.0,
            cs0: 0.05,
            r0: 1.0,
            q: 0.0,
            heats: true,
        };
        let ideal = Eos::Ideal { gamma: 1.4 };
        assert!(c.validate(&ideal, Some(1.0)).is_ok());
        assert!(
            c.validate(&Eos::Isothermal { cs: 0.1 }, Some(1.0))
                .unwrap_err()
                .contains("ideal")
        );
        assert!(
            c.validate(&ideal, None)
                .unwrap_err()
                .contains("central mass")
        );
        let bad = Cooling { beta: 0.0, ..c };
        assert!(
            bad.validate(&ideal, Some(1.0))
                .unwrap_err()
                .contains("cooling.beta")
        );
        // The orbital speed at r0 bounds the target: √(GM/r0) = 0.5 here.
        let hot = Cooling {
            cs0: 0.6,
            r0: 4.0,
            ..c
        };
        assert!(
            hot.validate(&ideal, Some(1.0))
                .unwrap_err()
                .contains("cooling.cs0")
        );
        assert!(
            Cooling { cs0: 0.4, ..hot }
                .validate(&ideal, Some(1.0))
                .is_ok()
        );
    }
}
