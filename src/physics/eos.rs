//! Equations of state: pressure and sound speed from density and specific internal energy.

use serde::{Deserialize, Serialize};

/// An equation of state. `Ideal` evolves the internal energy; `Isothermal` ignores it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Eos {
    /// p = (γ − 1) ρ u, c = √(γ p / ρ).
    Ideal { gamma: f64 },
    /// p = c_s² ρ, c = c_s.
    Isothermal { cs: f64 },
}

impl Eos {
    /// (pressure, sound speed) at density `rho` and specific internal energy `u`.
    #[inline]
    pub fn pressure_sound_speed(&self, rho: f64, u: f64) -> (f64, f64) {
        match *self {
            Eos::Ideal { gamma } => {
                let p = (gamma - 1.0) * rho * u;
                (p, (gamma * (gamma - 1.0) * u.max(0.0)).sqrt())
            }
            Eos::Isothermal { cs } => (cs * cs * rho, cs),
        }
    }

    /// Specific internal energy that gives pressure `p` at density `rho`.
    pub fn internal_energy(&self, rho: f64, p: f64) -> f64 {
        match *self {
            Eos::Ideal { gamma } => p / ((gamma - 1.0) * rho),
            Eos::Isothermal { cs } => cs * cs,
        }
    }

    /// Whether the energy equation is integrated (and total energy is a conserved figure).
    pub fn evolves_energy(&self) -> bool {
        matches!(self, Eos::Ideal { .. })
    }

    pub fn validate(&self) -> Result<(), String> {
        match *self {
            Eos::Ideal { gamma } if !(gamma > 1.0 && gamma.is_finite()) => {
                Err(format!("eos.gamma must be > 1, got {gamma}"))
            }
            Eos::Isothermal { cs } if !(cs > 0.0 && cs.is_finite()) => {
                Err(format!("eos.cs must be > 0, got {cs}"))
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ideal_gas_round_trips_pressure() {
        let eos = Eos::Ideal { gamma: 1.4 };
        let u = eos.internal_energy(0.125, 0.1);
        let (p, c) = eos.pressure_sound_speed(0.125, u);
        assert!((p - 0.1).abs() < 1e-15);
        assert!((c - (1.4f64 * 0.1 / 0.125).sqrt()).abs() < 1e-14);
    }

    #[test]
    fn isothermal_ignores_internal_energy() {
        let eos = Eos::Isothermal { cs: 0.5 };
        assert_eq!(eos.pressure_sound_speed(2.0, 123.0), (0.5, 0.5));
        assert!(!eos.evolves_energy());
        assert!(Eos::Isothermal { cs: -1.0 }.validate().is_err());
        assert!(Eos::Ideal { gamma: 1.0 }.validate().is_err());
    }
}
